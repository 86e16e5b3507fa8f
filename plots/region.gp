# Linear stability regions from a region.csv written by stiffbench (columns: 1 integrator,
# 2 re, 3 im): the boundary |R(z)| = 1 of each method in the complex plane z = h*lambda, one
# panel per integrator family, one colour per method, equal scales on both axes, the real and
# imaginary axes drawn. A row `name,nan,nan` separates two polylines of one method (gnuplot lifts
# the pen at a NaN point). Each panel shows the range of its methods' boundary points with a 5%
# margin, and always the origin. Methods with the same stability function have the same
# boundary: stiffbench passes plwK / pdtK (line width and dash type per method of panel K) so
# that a coinciding later curve is drawn thinner and dashed on top of the earlier one.
#
#   gnuplot -e "csvfile='DIR/region.csv'; outfile='DIR/region.png'; npanels='1'; \
#               pmethods1='rk4 heun'; ptitle1='explicit'; ttl='title'; plotdir='plots'" \
#           plots/region.gp
panelw = 620
panelh = 560
load plotdir."/common.gp"
set size ratio -1
set xzeroaxis lt -1 lw 1
set yzeroaxis lt -1 lw 1
set xlabel "Re z  (z = h {/Symbol l})"
set ylabel "Im z"
set key outside right top
# Line width and dash type of the j-th method of panel K: plwK / pdtK (space-separated, set by
# stiffbench: a curve coinciding with an earlier one is thinner and dashed); default solid, 2.5.
lwidth(K, j) = exists("plw".K) ? real(word(value("plw".K), j)) : 2.5
dash(K, j) = exists("pdt".K) ? int(word(value("pdt".K), j)) : 1
eval panel_begin
do for [K=1:np] {
  m = methods(K)
  n = words(m)
  # stats honours the ranges set for the previous panel: reset them first.
  set autoscale xy
  stats csvfile every ::1 using (inlist(strcol(1), m) ? $2 : NaN):3 nooutput
  x0 = STATS_min_x < 0 ? STATS_min_x : 0
  x1 = STATS_max_x > 0 ? STATS_max_x : 0
  y0 = STATS_min_y < 0 ? STATS_min_y : 0
  y1 = STATS_max_y > 0 ? STATS_max_y : 0
  undefine STATS_*
  span = (x1 - x0 > y1 - y0) ? x1 - x0 : y1 - y0
  span = span > 0 ? span : 1
  x0 = x0 - 0.05 * span; x1 = x1 + 0.05 * span
  y0 = y0 - 0.05 * span; y1 = y1 + 0.05 * span
  # Widen the narrower side (about its centre) to a width/height ratio in [0.8, 1.6], so that a
  # tall or flat set of boundaries does not leave a sliver of a panel at equal scales.
  if (x1 - x0 < 0.8 * (y1 - y0)) { c = 0.5 * (x0 + x1); w = 0.4 * (y1 - y0); x0 = c - w; x1 = c + w }
  if (y1 - y0 < (x1 - x0) / 1.6) { c = 0.5 * (y0 + y1); w = (x1 - x0) / 3.2; y0 = c - w; y1 = c + w }
  set xrange [x0 : x1]
  set yrange [y0 : y1]
  set title ptitle(K) noenhanced
  plot for [j=1:n] csvfile every ::1 using (strcol(1) eq word(m, j) ? $2 : NaN):3 \
         with lines lt j lw lwidth(K, j) dt dash(K, j) \
         title word(m, j)
}
unset multiplot
