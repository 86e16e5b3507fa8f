# Error against step size on log-log axes, one line per integrator, from a convergence.csv or
# local_error.csv written by stiffbench. Reads only the CSV (measurement and drawing are
# separate steps).
#
#   gnuplot -e "csvfile='DIR/convergence.csv'; outfile='DIR/convergence.png'; \
#               methods='euler rk4'; ttl='title'; ycolumn='6'; ylab='error'" plots/convergence.gp
#
# ycolumn: 6 for convergence.csv (error), 5 for local_error.csv (local_error). Column 4 is h.
ycol = exists("ycolumn") ? int(ycolumn) : 6
if (!exists("ylab")) ylab = "error (max-norm)"
if (!exists("ttl")) ttl = ""
set terminal pngcairo size 900,650 enhanced font ",10"
set output outfile
set datafile separator ","
set logscale xy
set format x "10^{%L}"
set format y "10^{%L}"
set xlabel "step size h"
set ylabel ylab noenhanced
set title ttl noenhanced
set key outside right top noenhanced
set grid
plot for [m in methods] csvfile every ::1 using (strcol(2) eq m ? $4 : NaN):(column(ycol) > 0 ? column(ycol) : NaN) \
     with linespoints title m
