# Charts of the accuracy/cost sweep (tools/accuracy_cost.sh runs this).
#   gnuplot -e "dir='DATA'; out='DIR'" tools/accuracy_cost.gp
# DATA holds the driver's <scene>_<series>.dat (columns: CPU ms per simulated second, end
# tension error against the finest reference [N], time-only error [N], segments, step [ms]),
# <scene>_<series>_front.dat (that series' Pareto front) and <scene>_front.dat (the scene's).
set terminal pngcairo size 1400,740 font ",10"
set datafile missing "nan"
set logscale xy
set format x "10^{%L}"
set format y "10^{%L}"
set grid
set key top right box opaque
file(s) = sprintf("%s/%s.dat", dir, s)
has_file(s) = system(sprintf("test -s %s/%s.dat && echo 1 || echo 0", dir, s)) + 0

# Series: colour, point type, title.
series = "explicit implicit implicit2 rk4 bdf2 mujoco_explicit mujoco_implicit mujoco_implicit2 mujoco_rk4 mujoco_bdf2 composite_rope"
colour(i) = word("#1f77b4 #d62728 #2ca02c #ff7f0e #8c564b #1f77b4 #d62728 #2ca02c #ff7f0e #8c564b #9467bd", i)
ptype(i) = word("7 5 9 11 3 6 4 8 10 1 13", i) + 0
title(i) = (i <= 5 ? word(series, i) : (i <= 10 ? word(series, i - 5) . " through MuJoCo (mocap)" : "MuJoCo composite rope"))

set output sprintf("%s/accuracy_cost_line.png", out)
set multiplot layout 1,2 title "Fixed line: 100 m, EA 1e6 N, fairlead x = 80 + 2 sin(2{/Symbol p}t/10), 60 s; RMS fairlead tension error over t = 10-60 s"
set xlabel "CPU time per simulated second [ms] (one core)"
set ylabel "end tension error [N]"
set yrange [0.004:1e3]
set bmargin 11
# Keys below the panels: inside, any corner covers runs (the bottom left held the Pareto front).
set key at graph 0.5, graph -0.13 center top horizontal maxcols 3 box
stats file("line_mean") using 1 nooutput
meanT = STATS_min
set title sprintf("all segment counts (10-320) against 640 segments converged; mean tension %.0f N", meanT)
set label 1 "1%" at graph 0.01, first 0.01 * meanT left offset 0,0.6 front
set arrow 1 from graph 0, first 0.01 * meanT to graph 1, first 0.01 * meanT nohead dt 3 lc rgb "#888888"
set label 2 "0.1%" at graph 0.01, first 0.001 * meanT left offset 0,0.6 front
set arrow 2 from graph 0, first 0.001 * meanT to graph 1, first 0.001 * meanT nohead dt 3 lc rgb "#888888"
plot for [i=1:11] (has_file("line_".word(series, i)) ? file("line_".word(series, i)) : NaN) \
       using 1:2 with points pt ptype(i) ps 1.1 lc rgb colour(i) title title(i), \
     for [i=1:5] file("line_".word(series, i)."_front") using 1:2 with lines lw 2 \
       lc rgb colour(i) notitle, \
     file("line_composite_rope") using 1:2 with lines lw 1 dt 2 lc rgb colour(11) notitle, \
     file("line_front") using 1:2 with steps lw 3 lc rgb "black" dt 1 title "Pareto front"
unset label 1
unset arrow 1
unset label 2
unset arrow 2
set title "80 segments: time error only (against 80 segments converged in time)"
set ylabel "end tension error, time discretisation only [N]"
set yrange [1e-4:1e3]
set key at graph 0.5, graph -0.13 center top horizontal maxcols 3 box
set object 1 rect from graph 0, first 1e-9 to first 6, first 0.02 fc rgb "#2ca02c" fs transparent solid 0.12 noborder
set object 2 rect from graph 0, first 1e-9 to first 3, first 6 fc rgb "#1f77b4" fs transparent solid 0.08 noborder
set label 3 "target: 0.02 N in 6 ms" at first 6, first 0.02 right offset -0.5,-0.8 front
set label 4 "target: 6 N in 3 ms" at first 3, first 6 right offset -0.5,-0.8 front
plot for [i=1:10] (has_file("line_".word(series, i)) ? file("line_".word(series, i)) : NaN) \
       using 1:($4 == 80 ? $3 : NaN) with linespoints pt ptype(i) ps 1.1 lc rgb colour(i) \
       title title(i)
unset object 1
unset object 2
unset label 3
unset label 4
unset multiplot
unset bmargin
set key default
set key top right box opaque

set terminal pngcairo size 1400,1000 font ",10"
set output sprintf("%s/accuracy_cost_scenes.png", out)
set multiplot layout 2,2 title "Other reference scenes: end tension error against the finest reference (catenary: Irvine's closed form) vs CPU time; lines: each integrator's Pareto front, black: overall"
set ylabel "end tension error [N]"
set xlabel "CPU time per simulated second [ms]"
set autoscale y
do for [sc in "catenary swing snap slack"] {
  set title sc eq "catenary" ? "static catenary, 100 m, settled after 40 s" : \
            sc eq "swing" ? "swing: dry 10 m chain released straight at 30° from hanging, 5 s" : \
            sc eq "snap" ? "snap: 20 m line jerked from 0.9 L to 1.005 L in 0.5 s, 3 s" : \
            "slack: 40 m ROV tether, EI 0.5, current 0.3 m/s, end circling, 20 s"
  plot for [i=1:5] file(sc."_".word(series, i)) using 1:2 with points pt ptype(i) \
         lc rgb colour(i) title word(series, i), \
       for [i=1:5] file(sc."_".word(series, i)."_front") using 1:2 with lines lw 2 \
         lc rgb colour(i) notitle, \
       file(sc."_front") using 1:2 with steps lw 3 lc rgb "black" title "Pareto front"
}
unset multiplot
