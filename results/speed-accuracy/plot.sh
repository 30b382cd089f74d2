#!/bin/sh
# Error against speed-up: one point per rung (against banked, 128x128, each
# scene and policy) and per sampled run (recursive, 256x256, seed 1), from
# summary.sh's plot data. Left: cycles; right: DRAM bytes. Absolute errors in
# percent (log scale, errors below 0.01% drawn at 0.01%); speed-up over the
# banked full run's host time (log scale).
#   usage: sh results/speed-accuracy/plot.sh PLOT.dat OUT.png
set -eu
dat=$1 out=$2
printf '%s\n' "set terminal pngcairo size 1200,520 noenhanced" "set output '$out.tmp'" \
  "set multiplot layout 1,2 title 'Speed against accuracy on the default machine (banked full run = 1x, 0% error): rungs at 128x128, every policy; samples at 256x256, recursive'" \
  "set logscale xy" "set grid" "set xrange [0.5:200]" "set yrange [0.01:300]" \
  "set xlabel 'speed-up over the banked full run (host time)'" "set key bottom right" \
  "R = 'analytic fixed channel sample-0.2 sample-0.1 sample-0.05'" \
  "e(x) = abs(x) < 0.01 ? 0.01 : abs(x)" \
  "set ylabel '|error of cycles| (%)'" \
  "plot for [i=1:words(R)] '$dat' using (strcol(1) eq word(R,i) ? \$3 : NaN):(e(\$4)) with points pt (i+5) ps 1.5 title word(R,i)" \
  "set ylabel '|error of DRAM bytes| (%)'" \
  "plot for [i=1:words(R)] '$dat' using (strcol(1) eq word(R,i) ? \$3 : NaN):(e(\$5)) with points pt (i+5) ps 1.5 title word(R,i)" \
  "unset multiplot" | gnuplot
mv "$out.tmp" "$out"
