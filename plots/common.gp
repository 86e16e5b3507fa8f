# Shared set-up of every stiffbench plot script: terminal, palette, panel layout.
# stiffbench (experiments/output/plotting.cpp) defines these gnuplot strings before running a script:
#   outfile  output file;  term  'png' or 'svg';  plotdir  this folder;  ttl  the title
#   csvfile  the CSV read (scripts read only stiffbench's CSV files)
#   npanels  number of panels; ptitleK / pmethodsK (K = 1..npanels): a family's title and its
#            space-separated integrator names
# A script sets `panelw`/`panelh` (pixels per panel) before `load plotdir.'/common.gp'`, then
# calls `eval panel_begin` once and loops `do for [K=1:np] { ... }` using methods(K), ptitle(K).
if (!exists("ttl")) ttl = ""
if (!exists("term")) term = "png"
if (!exists("panelw")) panelw = 700
if (!exists("panelh")) panelh = 520
np = exists("npanels") ? int(npanels) : 1
pcols = (np >= 2) ? 2 : 1
prows = int((np + pcols - 1) / pcols)
if (term eq "svg") {
  set terminal svg size pcols*panelw, prows*panelh + 40 enhanced font "Helvetica,11" background rgb "white"
} else {
  set terminal pngcairo size pcols*panelw, prows*panelh + 40 enhanced font ",10"
}
set output outfile
set datafile separator ","
set grid
set key noenhanced
# Twelve colour/marker pairs: inside one panel (at most twelve methods) none repeats.
array palette[12] = ["#1f77b4", "#d62728", "#2ca02c", "#ff7f0e", "#9467bd", "#8c564b", \
                     "#e377c2", "#17becf", "#7f7f7f", "#bcbd22", "#000000", "#0000aa"]
array markers[12] = [7, 5, 9, 11, 13, 15, 1, 2, 3, 4, 6, 8]
do for [i=1:12] { set linetype i lc rgb palette[i] lw 1.5 pt markers[i] ps 0.9 }
set linetype cycle 12
methods(K) = exists("pmethods".K) ? value("pmethods".K) : ""
ptitle(K) = exists("ptitle".K) ? value("ptitle".K) : ""
panel_begin = "set multiplot layout prows,pcols title ttl noenhanced"
# inlist(name, list): name is one of the space-separated words of list.
inlist(s, l) = strstrt(" ".l." ", " ".s." ") > 0
# A panel whose methods have no finite point (every run unstable) must not use autoscale: gnuplot
# stops with "all points undefined". Scripts count the valid points with `stats` and, when
# there are none, fix the ranges and say so in the panel:
#   eval empty_panel_on   ...plot...   eval empty_panel_off
empty_panel_on = "set xrange [1e-3:1]; set yrange [1e-3:1]; set label 99 'no finite values (every run unstable or empty)' at graph 0.5, 0.5 center"
empty_panel_off = "set autoscale xy; unset label 99"
