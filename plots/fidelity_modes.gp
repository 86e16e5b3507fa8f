# Per-mode damping and period error from a modes.csv written by stiffbench fidelity --model
# (columns: 1 integrator, 2 h, 3 mode, 4 omega, 5 nu, 6/7 amplification measured/predicted,
# 8/9 damping ratio measured/predicted, 10/11 period error measured/predicted, ...). Two panels
# (damping ratio, |period error|) against nu = h*omega_k, log-log: open circles the analytic
# value at each mode's nu, filled points the measured one; one colour per integrator.
#
#   gnuplot -e "csvfile='DIR/modes.csv'; outfile='DIR/modes.png'; npanels='2'; \
#               pmethods1='backward_euler bdf2'; pmethods2='backward_euler bdf2'; \
#               ptitle1='damping ratio'; ptitle2='|period error|'; ttl='title'; plotdir='plots'" \
#           plots/fidelity_modes.gp
panelw = 640
panelh = 520
load plotdir."/common.gp"
set logscale xy
set format x "10^{%L}"
set format y "10^{%L}"
set xlabel "nu = h omega_k"
set key outside bottom center horizontal
eval panel_begin
do for [K=1:np] {
  m = methods(K)
  n = words(m)
  cm = (K == 1) ? 8 : 10
  set title ptitle(K) noenhanced
  set ylabel ptitle(K) noenhanced
  stats csvfile every ::1 using (abs(column(cm)) > 0 ? $5 : NaN) nooutput
  valid = exists("STATS_records") ? STATS_records : 0
  undefine STATS_*
  if (valid == 0) { eval empty_panel_on }
  plot for [j=1:n] csvfile every ::1 \
         using ((strcol(1) eq word(m, j)) ? $5 : NaN):(abs(column(cm + 1)) > 0 ? abs(column(cm + 1)) : NaN) \
         with points lt j pt 6 ps 1.6 title word(m, j)." predicted", \
       for [j=1:n] csvfile every ::1 \
         using ((strcol(1) eq word(m, j)) ? $5 : NaN):(abs(column(cm)) > 0 ? abs(column(cm)) : NaN) \
         with points lt j pt 7 ps 0.8 title word(m, j)." measured"
  eval empty_panel_off
}
unset multiplot
