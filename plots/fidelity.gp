# Numerical damping and period error against nu = h*omega from a fidelity.csv written by
# stiffbench fidelity (columns: 1 integrator, 2 nu, 3 amplification, 4 damping_ratio,
# 5 period_error, 6 frequency_error, 7 source). Two panels (stiffbench passes the same methods
# as panel 1 and panel 2): the damping ratio -ln(A)/theta and |period error| nu/theta - 1, both
# log-log; lines are the analytic curves, points the measured ones (harmonic_oscillator runs).
# Values below 1e-13 in magnitude (no damping: symplectic methods, round-off) are not drawn.
#
#   gnuplot -e "csvfile='DIR/fidelity.csv'; outfile='DIR/fidelity.png'; npanels='2'; \
#               pmethods1='rk4 backward_euler'; pmethods2='rk4 backward_euler'; \
#               ptitle1='damping ratio'; ptitle2='|period error|'; ttl='title'; plotdir='plots'" \
#           plots/fidelity.gp
panelw = 640
panelh = 520
load plotdir."/common.gp"
set logscale xy
set format x "10^{%L}"
set format y "10^{%L}"
set xlabel "nu = h omega"
set key outside bottom center horizontal
eval panel_begin
do for [K=1:np] {
  m = methods(K)
  n = words(m)
  col = (K == 1) ? 4 : 5
  set title ptitle(K) noenhanced
  set ylabel ptitle(K) noenhanced
  stats csvfile every ::1 using (abs(column(col)) > 1e-13 ? $2 : NaN) nooutput
  valid = exists("STATS_records") ? STATS_records : 0
  undefine STATS_*
  if (valid == 0) { eval empty_panel_on }
  plot for [j=1:n] csvfile every ::1 \
         using ((strcol(1) eq word(m, j) && strcol(7) eq "analytic") ? $2 : NaN):(abs(column(col)) > 1e-13 ? abs(column(col)) : NaN) \
         with lines lt j title word(m, j), \
       for [j=1:n] csvfile every ::1 \
         using ((strcol(1) eq word(m, j) && strcol(7) eq "measured") ? $2 : NaN):(abs(column(col)) > 1e-13 ? abs(column(col)) : NaN) \
         with points lt j notitle
  eval empty_panel_off
}
unset multiplot
