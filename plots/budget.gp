# Pareto plot of a budget.csv written by `stiffbench budget`: the error of each configuration
# (y, log) against its wall time per frame (x, log), one series of points per integrator, the
# frame budget as a vertical line. Reads only the CSV.
#
#   gnuplot -e "csvfile='DIR/budget.csv'; outfile='DIR/budget.png'; npanels='1'; \
#               pmethods1='xpbd backward_euler'; ptitle1='all methods'; ttl='title'; \
#               xcol='7'; ycol='13'; ylab='strain'; budget_ms='16.67'; plotdir='plots'" plots/budget.gp
#
# Columns: 2 integrator, xcol ms_per_frame_median, ycol the error (strain_max, or
# constraint_residual for a model without springs). Rows without a finite time or a positive
# error (unstable, failed) are left out.
panelh = 560
panelw = 820
load plotdir."/common.gp"
set logscale xy
set format x "10^{%L}"
set format y "10^{%L}"
set key outside right top
set xlabel "wall time per frame [ms] (median)"
set ylabel ylab noenhanced
bx = real(budget_ms)
set arrow 1 from bx, graph 0 to bx, graph 1 nohead lc rgb "#444444" dt 2 lw 1.5
set label 1 sprintf("frame budget %.3g ms", bx) at bx, graph 0.97 right offset -0.5, 0 textcolor rgb "#444444"
xc = int(xcol)
yc = int(ycol)
eval panel_begin
do for [K=1:np] {
  m = methods(K)
  n = words(m)
  stats csvfile every ::1 using (inlist(strcol(2), m) && column(xc) > 0 && column(yc) > 0 ? column(yc) : NaN) nooutput
  valid = exists("STATS_records") ? STATS_records : 0
  undefine STATS_*
  if (valid == 0) { eval empty_panel_on }
  set title ptitle(K) noenhanced
  plot for [j=1:n] csvfile every ::1 using (strcol(2) eq word(m, j) && column(yc) > 0 ? column(xc) : NaN):(column(yc) > 0 ? column(yc) : NaN) \
       with points lt j title word(m, j)
  eval empty_panel_off
}
unset multiplot
