# Work-precision diagram from a work_precision.csv written by stiffbench: error at t_end (x, log)
# against f evaluations (left column) and wall time (right column), one row of panels per
# integrator family, one line per integrator. Reads only the CSV.
#
#   gnuplot -e "csvfile='DIR/work_precision.csv'; outfile='DIR/work_precision.png'; \
#               npanels='1'; pmethods1='cvode_bdf sdirk3'; ptitle1='implicit'; ttl='title'; \
#               plotdir='plots'" plots/work_precision.gp
#
# Columns: 2 integrator, 4 error, 5 f_evals, 9 wall_s (the median over the repeats), 19
# wall_s_ci_low, 20 wall_s_ci_high (its bootstrap 95% interval, drawn as error bars on the wall
# time; a CSV written before these columns existed is drawn without them). Rows without f
# evaluations (stable_fluids composes the model's operators and never evaluates f) are left out
# of the f-evaluation panel. flagcol: the column `flag` (stiffbench passes it; 0 for a CSV
# without it): rows flagged reference_floor (error within 10x of the reference's estimated
# error) are drawn as hollow rings, not joined to the method's line.
panelh = 460
load plotdir."/common.gp"
FC = exists("flagcol") ? int(flagcol) : 0
isfloor(dummy) = (FC > 0) ? (strcol(FC) eq "reference_floor") : 0
stats csvfile every ::1 using (isfloor(0) ? 1 : NaN) nooutput
nfloor = exists("STATS_records") ? STATS_records : 0
undefine STATS_*
floortitle = "hollow: reference floor"
# Two panels (f evaluations, wall time) per family: override the layout of common.gp.
if (term eq "svg") {
  set terminal svg size 1400, np*panelh + 40 enhanced font "Helvetica,11" background rgb "white"
} else {
  set terminal pngcairo size 1400, np*panelh + 40 enhanced font ",10"
}
set output outfile
set logscale xy
set format x "10^{%L}"
set format y "10^{%L}"
set key outside right top
set multiplot layout np,2 title ttl noenhanced
do for [K=1:np] {
  m = methods(K)
  n = words(m)
  stats csvfile every ::1 using (inlist(strcol(2), m) && column(4) > 0 ? $4 : NaN) nooutput
  valid = exists("STATS_records") ? STATS_records : 0
  undefine STATS_*
  stats csvfile every ::1 using (inlist(strcol(2), m) && column(4) > 0 && column(5) > 0 ? $4 : NaN) nooutput
  fvalid = exists("STATS_records") ? STATS_records : 0
  undefine STATS_*
  if (fvalid == 0) { eval empty_panel_on }
  if (fvalid == 0 && valid > 0) { set label 99 "no f evaluations (see the wall-time panel)" at graph 0.5, 0.5 center }
  set xlabel "error at t_{end} (max-norm)"
  set ylabel "f evaluations"
  set title ptitle(K)." - f evaluations" noenhanced
  plot for [j=1:n] csvfile every ::1 using (strcol(2) eq word(m, j) && column(4) > 0 && column(5) > 0 && !isfloor(0) ? $4 : NaN):5 \
       with linespoints lt j title word(m, j), \
       for [j=1:n] csvfile every ::1 using (strcol(2) eq word(m, j) && column(4) > 0 && column(5) > 0 && isfloor(0) ? $4 : NaN):5 \
       with points lt j pt 6 ps 1.6 notitle, \
       keyentry with points pt 6 ps 1.6 lc rgb "black" title (nfloor > 0 ? floortitle : "")
  eval empty_panel_off
  if (valid == 0) { eval empty_panel_on }
  stats csvfile every ::1 using (inlist(strcol(2), m) && column(4) > 0 && column(20) > 0 ? $20 : NaN) nooutput
  spread = exists("STATS_records") ? STATS_records : 0
  undefine STATS_*
  set title ptitle(K)." - wall time" noenhanced
  if (spread > 0) {
    set ylabel "wall time [s] (median, bootstrap 95% interval)"
    plot for [j=1:n] csvfile every ::1 using (strcol(2) eq word(m, j) && column(4) > 0 && !isfloor(0) ? $4 : NaN):9:19:20 \
         with yerrorlines lt j title word(m, j), \
         for [j=1:n] csvfile every ::1 using (strcol(2) eq word(m, j) && column(4) > 0 && isfloor(0) ? $4 : NaN):9 \
         with points lt j pt 6 ps 1.6 notitle, \
         keyentry with points pt 6 ps 1.6 lc rgb "black" title (nfloor > 0 ? floortitle : "")
  } else {
    set ylabel "wall time [s]"
    plot for [j=1:n] csvfile every ::1 using (strcol(2) eq word(m, j) && column(4) > 0 && !isfloor(0) ? $4 : NaN):9 \
         with linespoints lt j title word(m, j), \
         for [j=1:n] csvfile every ::1 using (strcol(2) eq word(m, j) && column(4) > 0 && isfloor(0) ? $4 : NaN):9 \
         with points lt j pt 6 ps 1.6 notitle, \
         keyentry with points pt 6 ps 1.6 lc rgb "black" title (nfloor > 0 ? floortitle : "")
  }
  eval empty_panel_off
}
unset multiplot
