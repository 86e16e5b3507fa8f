# Stability limits from a stability.csv written by `stiffbench stability`; one panel per
# integrator family.
#   sweep = 1: h_max against the swept parameter on log-log axes, measured points joined by a
#              solid line, the linear-theory prediction as a dashed line of the same colour
#              (parallel lines: the method's limit scales as theory says); triangles with an
#              upward arrow for methods stable up to the largest step tried (a lower bound of
#              their limit), squares for solver_limit rows (the
#              largest step that ran before Newton or the linear solver failed). Rows of one
#              integrator must be
#              consecutive in the CSV (stiffbench writes them grouped).
#   sweep = 0: one column per integrator, measured h_max as a filled circle and the prediction
#              as an open circle (they coincide when theory predicts the limit); a triangle with
#              an upward arrow for methods stable up to the largest step tried (a lower bound of
#              their limit), a cross at the bottom
#              for methods with no stable step (unstable_for_all_h), a square for solver_limit
#              (the largest step that ran before Newton or the linear solver failed).
# Columns: 1 model, 2 integrator, 3 param, 4 value, 5 h_max_measured, 6 h_max_predicted,
# 7 ratio, 8 status (then limit_kind and the solver counters, unused here).
sw = exists("sweep") ? int(sweep) : 0
if (!exists("xlab")) xlab = "parameter"
load plotdir."/common.gp"
set logscale y
set format y "10^{%L}"
set ylabel "largest stable step h_{max}"
set key outside right top
# Finite positive number in column c, else NaN (empty cells, "inf").
okval(c) = (strcol(c) ne "" && strcol(c) ne "inf" && column(c) > 0) ? column(c) : NaN
# The upward arrow of a stable_up_to row: from h_max_measured to 3 times it (log axis).
upval(c) = strcol(8) eq "stable_up_to" ? 2 * okval(c) : NaN
eval panel_begin
do for [K=1:np] {
  m = methods(K)
  n = words(m)
  set title ptitle(K) noenhanced
  stats csvfile every ::1 using (inlist(strcol(2), m) ? okval(5) : NaN) nooutput
  valid = exists("STATS_records") ? STATS_records : 0
  undefine STATS_*
  stats csvfile every ::1 using (inlist(strcol(2), m) ? okval(6) : NaN) nooutput
  valid = valid + (exists("STATS_records") ? STATS_records : 0)
  undefine STATS_*
  if (sw) {
    set logscale x
    set format x "10^{%L}"
    set xlabel xlab noenhanced
    if (valid == 0) { eval empty_panel_on }
    set offsets graph 0.05, graph 0.05, graph 0.05, graph 0.05
    plot for [j=1:n] csvfile every ::1 using (strcol(2) eq word(m, j) ? abs($4) : NaN):(strcol(8) eq "ok" ? okval(5) : NaN) \
           with linespoints lt j title word(m, j), \
         for [j=1:n] csvfile every ::1 using (strcol(2) eq word(m, j) ? abs($4) : NaN):(okval(6)) \
           with lines lt j dt 2 lw 1 notitle, \
         for [j=1:n] csvfile every ::1 using (strcol(2) eq word(m, j) && strcol(8) eq "stable_up_to" ? abs($4) : NaN):(okval(5)) \
           with points lt j pt 9 ps 1.6 notitle, \
         for [j=1:n] csvfile every ::1 using (strcol(2) eq word(m, j) ? abs($4) : NaN):(okval(5)):(0):(upval(5)) \
           with vectors lt j head filled size screen 0.008,20 notitle, \
         for [j=1:n] csvfile every ::1 using (strcol(2) eq word(m, j) && strcol(8) eq "solver_limit" ? abs($4) : NaN):(okval(5)) \
           with points lt j pt 5 ps 1.4 notitle, \
         NaN with lines lc "black" dt 2 lw 1 title "predicted", \
         NaN with points lc "black" pt 9 title "stable up to (largest step tried; limit above)", \
         NaN with points lc "black" pt 5 title "solver limit (Newton/linear solver failed above)"
    set offsets 0, 0, 0, 0
    eval empty_panel_off
  } else {
    unset logscale x
    set format x "%g"
    set xlabel ""
    set xrange [0.5:n + 0.5]
    set xtics () rotate by -30 noenhanced
    set offsets 0, 0, graph 0.15, graph 0.15
    do for [j=1:n] { set xtics add (word(m, j) j) }
    ybot = 1e-3
    stats csvfile every ::1 using (inlist(strcol(2), m) ? okval(5) : NaN) nooutput
    if (exists("STATS_min")) { ybot = STATS_min / 2 }
    undefine STATS_*
    stats csvfile every ::1 using (inlist(strcol(2), m) ? okval(6) : NaN) nooutput
    if (exists("STATS_min")) { ybot = (STATS_min / 2 < ybot) ? STATS_min / 2 : ybot }
    undefine STATS_*
    if (valid == 0) { set yrange [1e-3:1]; set label 99 'no finite limits' at graph 0.5, 0.5 center }
    # Unstable for every h: a cross on the bottom axis.
    plot for [j=1:n] csvfile every ::1 using (strcol(2) eq word(m, j) && strcol(8) eq "ok" ? j : NaN):(okval(5)) \
           with points lt j pt 7 ps 1.4 notitle, \
         for [j=1:n] csvfile every ::1 using (strcol(2) eq word(m, j) && strcol(8) eq "stable_up_to" ? j : NaN):(okval(5)) \
           with points lt j pt 9 ps 1.6 notitle, \
         for [j=1:n] csvfile every ::1 using (strcol(2) eq word(m, j) ? j : NaN):(okval(5)):(0):(upval(5)) \
           with vectors lt j head filled size screen 0.008,20 notitle, \
         for [j=1:n] csvfile every ::1 using (strcol(2) eq word(m, j) && strcol(8) eq "solver_limit" ? j : NaN):(okval(5)) \
           with points lt j pt 5 ps 1.4 notitle, \
         for [j=1:n] csvfile every ::1 using (strcol(2) eq word(m, j) ? j : NaN):(okval(6)) \
           with points lt j pt 6 ps 2.2 notitle, \
         for [j=1:n] csvfile every ::1 using (strcol(2) eq word(m, j) && strcol(8) eq "unstable_for_all_h" ? j : NaN):(ybot) \
           with points lt j pt 2 ps 2 notitle, \
         NaN with points lc "black" pt 7 title "measured", \
         NaN with points lc "black" pt 6 ps 2 title "predicted", \
         NaN with points lc "black" pt 9 title "stable up to (largest step tried; limit above)", \
         NaN with points lc "black" pt 5 title "solver limit (solver failed above)", \
         NaN with points lc "black" pt 2 title "unstable for all h"
    set autoscale xy
    set offsets 0, 0, 0, 0
    unset label 99
    set xtics autofreq norotate
  }
}
unset multiplot
