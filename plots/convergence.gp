# Error against step size on log-log axes from a convergence.csv or local_error.csv written by
# stiffbench; one panel per integrator family, one line per integrator. The dashed line of the
# same colour has the method's expected slope (order, or order + 1 for the local error) through
# its finest point above the floors (status not `floor`): where the measured line runs parallel
# to it, the method is in its asymptotic range.
#
#   gnuplot -e "csvfile='DIR/convergence.csv'; outfile='DIR/convergence.png'; npanels='1'; \
#               pmethods1='euler rk4'; ptitle1='explicit'; ttl='title'; ycolumn='6'; \
#               slope_offset='0'; plotdir='plots'" plots/convergence.gp
#
# Columns: 2 integrator, 3 order, 4 h; ycolumn 6 (error, convergence.csv) or 5 (local_error,
# local_error.csv); slope_offset 1 for the local error.
ycol = exists("ycolumn") ? int(ycolumn) : 6
soff = exists("slope_offset") ? int(slope_offset) : 0
# The status column (12 in convergence.csv, 7 in local_error.csv): rows at a floor do not anchor
# the expected-slope line.
scol = exists("statuscolumn") ? int(statuscolumn) : (ycol == 6 ? 12 : 7)
if (!exists("ylab")) ylab = "error (max-norm)"
load plotdir."/common.gp"
set logscale xy
set format x "10^{%L}"
set format y "10^{%L}"
set xlabel "step size h"
set ylabel ylab noenhanced
set key outside right top
eval panel_begin
do for [K=1:np] {
  m = methods(K)
  n = words(m)
  array H0[n > 0 ? n : 1]
  array E0[n > 0 ? n : 1]
  array P[n > 0 ? n : 1]
  do for [j=1:n] {
    H0[j] = NaN; E0[j] = NaN; P[j] = 0
    stats csvfile every ::1 using (strcol(2) eq word(m, j) && column(ycol) > 0 && strcol(scol) ne "floor" ? $4 : NaN) nooutput
    if (exists("STATS_min")) { H0[j] = STATS_min }
    undefine STATS_*
    stats csvfile every ::1 using (strcol(2) eq word(m, j) && $4 == H0[j] ? column(ycol) : NaN) nooutput
    if (exists("STATS_min")) { E0[j] = STATS_min }
    undefine STATS_*
    stats csvfile every ::1 using (strcol(2) eq word(m, j) ? $3 : NaN) nooutput
    if (exists("STATS_max")) { P[j] = STATS_max + soff }
    undefine STATS_*
  }
  set title ptitle(K) noenhanced
  stats csvfile every ::1 using (inlist(strcol(2), m) && column(ycol) > 0 ? $4 : NaN) nooutput
  valid = exists("STATS_records") ? STATS_records : 0
  undefine STATS_*
  if (valid == 0) { eval empty_panel_on }
  plot for [j=1:n] csvfile every ::1 using (strcol(2) eq word(m, j) ? $4 : NaN):(column(ycol) > 0 ? column(ycol) : NaN) \
         with linespoints lt j title word(m, j), \
       for [j=1:n] csvfile every ::1 using (strcol(2) eq word(m, j) ? $4 : NaN):(E0[j] * ($4 / H0[j])**P[j]) \
         with lines lt j dt 2 lw 1 notitle
  eval empty_panel_off
}
unset multiplot
