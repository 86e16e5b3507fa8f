# Relative invariant (energy) error against time from an energy.csv written by stiffbench
# energy; one panel per integrator family, one line per integrator, log y. The y value of each
# sampled row is max_rel_error_since_last, the largest error over the steps since the previous
# row, so no peak between two samples (a pericentre passage) is lost. On these axes (linear t,
# log error) a bounded error stays in a horizontal band (symplectic methods) while a linear drift
# keeps rising like log t.
#
#   gnuplot -e "csvfile='DIR/energy.csv'; outfile='DIR/energy.png'; npanels='1'; \
#               pmethods1='euler rk4'; ptitle1='explicit'; ttl='title'; plotdir='plots'" \
#           plots/energy.gp
#
# Columns: 1 model, 2 integrator, 3 h, 4 t, 5 energy, 6 rel_error, 7 max_rel_error_since_last.
if (!exists("ylab")) ylab = "relative energy error (max since previous sample)"
load plotdir."/common.gp"
set logscale y
set format y "10^{%L}"
set xlabel "t"
set ylabel ylab noenhanced
set key outside right top
eval panel_begin
do for [K=1:np] {
  m = methods(K)
  n = words(m)
  set title ptitle(K) noenhanced
  stats csvfile every ::1 using (inlist(strcol(2), m) && $7 > 0 ? $4 : NaN) nooutput
  valid = exists("STATS_records") ? STATS_records : 0
  undefine STATS_*
  # About ten markers per line (the rows per integrator follow --samples).
  pint = (n > 0) ? int(valid / n / 10) : 1
  pint = (pint < 1) ? 1 : pint
  set autoscale xfix
  if (valid == 0) { eval empty_panel_on }
  plot for [j=1:n] csvfile every ::1 using (strcol(2) eq word(m, j) ? $4 : NaN):($7 > 0 ? $7 : NaN) \
         with linespoints lt j pi pint title word(m, j)
  eval empty_panel_off
}
unset multiplot
