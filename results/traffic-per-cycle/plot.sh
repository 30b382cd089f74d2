#!/bin/sh
# DRAM traffic per cycle over a run, the policies on shared axes, drawn by
# `rtsim plot`: for each scene, the timeline.csv of each policy's point of the
# contention sweep at the given cores and L2 size. Bytes per cycle of a window
# are its read and write bytes over its length; x is the window's middle, in
# cycles. The DRAM's columns come from the point's stats.csv, so rtsim plot
# draws the DRAM's peak (13.7 bytes a cycle on the default machine's
# DDR4-2400 channel) as a dashed line and names the DRAM in the caption with
# the scene, cores and L2 size.
#   usage: sh results/traffic-per-cycle/plot.sh SWEEPDIR CORES L2SIZE OUTDIR SCENE...
set -eu
dir=$1 cores=$2 l2=$3 out=$4
shift 4
rtsim=${RTSIM:-build/rtsim}
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
mkdir -p "$out"
for scene in "$@"; do
  # One tidy table a scene: policy, the window's middle and its bytes a cycle.
  echo "scene,cores,l2.size,policy,fidelity,clock_ghz,dram.channels,dram.bus_bytes,dram.clock_mhz,cycles,dram_bytes_per_cycle" > "$tmp/tidy.csv"
  found=0
  for p in recursive packet dynamic; do
    d="$dir/policy=$p,scene=$scene,cores=$cores,l2.size=$l2"
    [ -f "$d/timeline.csv" ] || continue
    found=1
    # The machine's DRAM, from the run's stats.csv (a header and one row;
    # quoted cells such as rays' "primary,shadow" unquoted first).
    m=$(awk -f "$(dirname "$0")/../contention/scheduling/unquote.awk" "$d/stats.csv" | awk -F, 'NR == 1 { for (i = 1; i <= NF; i++) k[$i] = i; next }
      { print $k["fidelity"] "," $k["clock_ghz"] "," $k["dram.channels"] "," $k["dram.bus_bytes"] "," $k["dram.clock_mhz"] }')
    awk -F, -v s="$scene" -v c="$cores" -v l="$l2" -v p="$p" -v m="$m" \
      'FNR == 1 { for (i = 1; i <= NF; i++) k[$i] = i; next }
       $k["cycles"] > 0 { printf "%s,%s,%s,%s,%s,%.17g,%.6g\n", s, c, l, p, m,
         $k["cycle"] + $k["cycles"] / 2, ($k["dram_read_bytes"] + $k["dram_write_bytes"]) / $k["cycles"] }' \
      "$d/timeline.csv" >> "$tmp/tidy.csv"
  done
  [ $found = 1 ] || { echo "plot.sh: no timeline for $scene in $dir" >&2; exit 2; }
  for ext in png svg; do
    "$rtsim" plot "$tmp/tidy.csv" --x cycles --y dram_bytes_per_cycle --lines policy \
      --title "DRAM traffic per cycle over a run: $scene" \
      --xlabel 'simulated time (cycles)' -o "$out/$scene.$ext"
  done
done
