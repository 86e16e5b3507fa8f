# Performance and data profiles from a profile.csv written by `stiffbench profile`: panel 1 the
# performance profile rho_m(alpha) against alpha (log2), panel 2 the data profile d_m(kappa)
# against the budget kappa in cost units (log10), one step line per method, for one target
# accuracy `tau` and one cost measure `cost` (both as written in the CSV). Reads only the CSV.
# The data panel's axis is linear when some cost is 0 (a log axis cannot show it).
#
#   gnuplot -e "csvfile='DIR/profile.csv'; outfile='DIR/profile_1e-06_wall.png'; npanels='2'; \
#               pmethods1='cvode_bdf radau5'; ptitle1='performance'; pmethods2='cvode_bdf radau5'; \
#               ptitle2='data'; tau='1e-06'; cost='wall'; ttl='title'; plotdir='plots'" plots/profile.gp
#
# Columns: 1 tau, 2 cost, 3 kind (performance | data), 4 method, 5 x, 6 fraction.
panelh = 520
panelw = 700
load plotdir."/common.gp"
set key bottom right
set yrange [-0.02:1.02]
set ylabel "fraction of problems solved"
sel(k, j) = strcol(1) eq tau && strcol(2) eq cost && strcol(3) eq k && strcol(4) eq word(m, j)
eval panel_begin
do for [K=1:np] {
  m = methods(K)
  n = words(m)
  k = (K == 1) ? "performance" : "data"
  set title ptitle(K) noenhanced
  if (K == 1) {
    set logscale x 2
    set xlabel "alpha (cost / cheapest method's cost)"
    set format x "%g"
  } else {
    # A zero cost (no linear solves at all) has no place on a log axis: then the axis is linear.
    stats csvfile every ::1 using (strcol(1) eq tau && strcol(2) eq cost && strcol(3) eq k && column(5) <= 0 ? 1 : NaN) nooutput
    nonpositive = exists("STATS_records") ? STATS_records : 0
    undefine STATS_*
    if (nonpositive == 0) { set logscale x 10; set format x "10^{%L}" } else { set format x "%g" }
    set xlabel sprintf("budget kappa (%s)", cost) noenhanced
  }
  plot for [j=1:n] csvfile every ::1 using (sel(k, j) ? column(5) : NaN):(sel(k, j) ? column(6) : NaN) \
         with steps lt j title word(m, j)
  unset logscale x
}
unset multiplot
