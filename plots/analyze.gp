# Dissipation and dispersion from an analyze_dispersion.csv written by stiffbench (columns:
# 1 integrator, 2 nu, 3 amplification |R(i nu)|, 4 phase_error arg R(i nu) - nu): for each
# integrator family a row of two panels, |R(i nu)| (odd K) and |arg R(i nu) - nu| (even K)
# against nu on log axes, one colour per method. |R| = 1 is drawn as a dashed line: below it
# the method damps the oscillation, above it amplifies it.
#
#   gnuplot -e "csvfile='DIR/analyze_dispersion.csv'; outfile='DIR/analyze.png'; npanels='2'; \
#               pmethods1='rk4 dopri5'; ptitle1='explicit: |R(i nu)|'; \
#               pmethods2='rk4 dopri5'; ptitle2='explicit: |arg R(i nu) - nu|'; \
#               ttl='title'; plotdir='plots'" plots/analyze.gp
panelw = 620
panelh = 460
load plotdir."/common.gp"
set logscale xy
set format y "10^{%L}"
set xlabel "{/Symbol n}  (z = i {/Symbol n} = h{/Symbol l} on the imaginary axis)"
set key outside right top
eval panel_begin
do for [K=1:np] {
  m = methods(K)
  n = words(m)
  amplitude = (K % 2 == 1)
  set title ptitle(K) noenhanced
  if (amplitude) {
    set ylabel "|R(i{/Symbol n})|"
    plot for [j=1:n] csvfile every ::1 using (strcol(1) eq word(m, j) ? $2 : NaN):3 \
           with lines lt j lw 2 title word(m, j), \
         1 with lines lt -1 dt 2 lw 1 notitle
  } else {
    set ylabel "|arg R(i{/Symbol n}) - {/Symbol n}|"
    plot for [j=1:n] csvfile every ::1 using (strcol(1) eq word(m, j) ? $2 : NaN):(abs($4)) \
           with lines lt j lw 2 title word(m, j)
  }
}
unset multiplot
