# One SPH particle frame as a scatter plot coloured by pressure (fluid particles) with the
# boundary particles in grey, from a frame_NNNN.csv written by `stiffbench solve --frames`.
# Reads only the CSV (columns x,y,z,density,pressure,velocity_x,velocity_y,velocity_z,fluid).
#
#   gnuplot -e "csvfile='DIR/frame_0020.csv'; outfile='frame.png'; ttl='t = 0.25 s'" \
#           plots/sph_frame.gp
#
# 2D scenes are drawn in the x-y plane (3D scenes: their projection on it), equal axis scales.
if (!exists("ttl")) ttl = ""
if (exists("term") && term eq "svg") {
  set terminal svg size 1000,560 enhanced font "Helvetica,11" background rgb "white"
} else {
  set terminal pngcairo size 1000,560 enhanced font ",10"
}
set output outfile
set datafile separator ","
set size ratio -1
set xlabel "x (m)"
set ylabel "y (m)"
set cblabel "pressure (Pa)"
set palette defined (0 "#2b2d85", 0.35 "#2c7fb8", 0.65 "#7fcdbb", 0.85 "#fdae61", 1 "#d7191c")
set title ttl noenhanced
# Colour range: 0 to mean + 3 standard deviations of the fluid pressure (an impact's few
# peak particles would otherwise wash out the bulk's hydrostatic gradient).
stats csvfile every ::1 using (column(9) > 0.5 ? column(5) : NaN) nooutput
set cbrange [0:STATS_mean + 3 * STATS_stddev]
unset key
set grid
plot csvfile every ::1 using (column(9) < 0.5 ? $1 : NaN):2 with points pt 7 ps 0.35 lc rgb "#9a9a9a", \
     csvfile every ::1 using (column(9) > 0.5 ? $1 : NaN):2:5 with points pt 7 ps 0.45 lc palette
