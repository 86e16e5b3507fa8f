# Work-precision diagram from a work_precision.csv written by stiffbench: error at t_end (x,
# log) against f evaluations (left) and wall time (right), one line per integrator. Reads only
# the CSV.
#
#   gnuplot -e "csvfile='DIR/work_precision.csv'; outfile='DIR/work_precision.png'; \
#               methods='cvode_bdf sdirk3'; ttl='title'" plots/work_precision.gp
#
# Columns: 2 integrator, 4 error, 5 f_evals, 9 wall_s.
if (!exists("ttl")) ttl = ""
set terminal pngcairo size 1400,600 enhanced font ",10"
set output outfile
set datafile separator ","
set logscale xy
set format x "10^{%L}"
set format y "10^{%L}"
set grid
set key outside right top noenhanced
set multiplot layout 1,2 title ttl noenhanced
set xlabel "error at t_{end} (max-norm)"
set ylabel "f evaluations"
plot for [m in methods] csvfile every ::1 using (strcol(2) eq m && column(4) > 0 ? $4 : NaN):5 \
     with linespoints title m
set ylabel "wall time [s] (minimum over repeats)"
plot for [m in methods] csvfile every ::1 using (strcol(2) eq m && column(4) > 0 ? $4 : NaN):9 \
     with linespoints title m
unset multiplot
