#!/bin/sh
# DRAM traffic per cycle over a run, the policies on shared axes: for each
# scene, the timeline.csv of each policy's point of the contention sweep at
# the given cores and L2 size. Bytes per cycle of a window are its read and
# write bytes over its length; x is the window's middle, in million cycles.
#   usage: sh results/traffic-per-cycle/plot.sh SWEEPDIR CORES L2SIZE OUTDIR SCENE...
set -eu
dir=$1 cores=$2 l2=$3 out=$4
shift 4
mkdir -p "$out"
for scene in "$@"; do
  for term in png svg; do
    if [ $term = png ]; then t="set terminal pngcairo size 1000,520 noenhanced"; else t="set terminal svg size 1000,520 noenhanced"; fi
    plot=""
    for p in recursive packet dynamic; do
      f="$dir/policy=$p,scene=$scene,cores=$cores,l2.size=$l2/timeline.csv"
      [ -f "$f" ] || continue
      [ -n "$plot" ] && plot="$plot, "
      plot="$plot'$f' using (((\$1+\$2/2))/1e6):((\$3+\$4)/\$2) with steps lw 2 title '$p'"
    done
    [ -n "$plot" ] || { echo "plot.sh: no timeline for $scene in $dir" >&2; exit 2; }
    printf '%s\n' "$t" "set output '$out/$scene.$term.tmp'" "set datafile separator ','" \
      "set title 'DRAM traffic per cycle: $scene, $cores cores, L2 $l2 (default machine: DDR4-2400, 13.7 bytes/cycle peak)'" \
      "set xlabel 'simulated time (million cycles)'" "set ylabel 'DRAM bytes per cycle (read + write)'" \
      "set grid" "set key top right" "set yrange [0:14]" "plot $plot" | gnuplot
    mv "$out/$scene.$term.tmp" "$out/$scene.$term"
  done
done
