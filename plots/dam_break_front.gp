# Dam break: surge front against time in the dimensionless form Z = front/a against
# T = t sqrt(2 g/a), from the observables.csv of `stiffbench solve --frames` on sph_dam_break_2d
# or _3d (its columns T and Z, found by name), with the Koshizuka & Oka (1996) experiment
# (docs/reference-values.md) overlaid.
#
#   gnuplot -e "csvfile='DIR/observables.csv'; outfile='front.png'; \
#               ttl='sph_dam_break_2d, symplectic_euler'" plots/dam_break_front.gp
if (!exists("ttl")) ttl = ""
if (exists("term") && term eq "svg") {
  set terminal svg size 800,560 enhanced font "Helvetica,11" background rgb "white"
} else {
  set terminal pngcairo size 800,560 enhanced font ",10"
}
set output outfile
set datafile separator ","
set datafile columnheaders
set xlabel "T = t (2g/a)^{1/2}"
set ylabel "Z = front / a"
set title ttl noenhanced
set key left top noenhanced
set grid
$ko << EOD
T,Z
0.000,1.000
0.381,1.111
0.769,1.252
1.153,1.505
1.537,1.892
1.935,2.241
2.323,2.615
2.719,3.003
3.096,3.624
EOD
plot csvfile using (column("T")):(column("Z")) \
       with lines lw 2 title "SPH (this run)", \
     $ko using 1:2 with points pt 7 ps 1.2 lc rgb "black" title "Koshizuka & Oka (1996)"
