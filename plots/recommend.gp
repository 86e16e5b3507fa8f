# Recommend plot from a recommend.csv written by `stiffbench recommend`: error_rel (y, log)
# against the median wall time (x, log), one series of points per integrator, the rows on the
# Pareto front by wall time circled (on_pareto_wall = 1) and the requested tolerance as a
# horizontal line. Reads only the CSV.
#
#   gnuplot -e "csvfile='DIR/recommend.csv'; outfile='DIR/recommend.png'; npanels='1'; \
#               pmethods1='cvode_bdf radau5'; ptitle1='all methods'; ttl='title'; \
#               log10_rtol='-8'; plotdir='plots'" plots/recommend.gp
#
# Columns: 2 integrator, 7 error_rel, 9 wall_s, 11 on_pareto_wall. Rows that did not end ok
# (empty error_rel) are left out.
panelh = 560
panelw = 900
load plotdir."/common.gp"
set logscale xy
set format x "10^{%L}"
set format y "10^{%L}"
set key outside right top
set xlabel "wall time [s] (median)"
set ylabel "error_rel = max-norm error / max(1, max|y_ref|)" noenhanced
rlim = 10**real(log10_rtol)
set arrow 1 from graph 0, first rlim to graph 1, first rlim nohead lc rgb "#444444" dt 2 lw 1.5
set label 1 sprintf("rtol %.3g", rlim) at graph 0.02, first rlim offset 0, 0.7 textcolor rgb "#444444"
eval panel_begin
do for [K=1:np] {
  m = methods(K)
  n = words(m)
  set title ptitle(K) noenhanced
  plot csvfile every ::1 using (column(11) == 1 && column(7) > 0 ? column(9) : NaN):(column(7) > 0 ? column(7) : NaN) \
         with points pt 6 ps 2.5 lc rgb "black" lw 1.5 title "on the Pareto front (wall time)", \
       for [j=1:n] csvfile every ::1 using (strcol(2) eq word(m, j) && column(7) > 0 ? column(9) : NaN):(column(7) > 0 ? column(7) : NaN) \
         with points lt j title word(m, j)
}
unset multiplot
