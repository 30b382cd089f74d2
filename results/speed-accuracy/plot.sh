#!/bin/sh
# Error against speed-up, drawn by `rtsim plot --points` (a scatter): one
# point per rung (against banked, 128x128, each scene and policy) and per
# sampled run (recursive, 256x256, seed 1), from summary.sh's plot data. Left
# panel: cycles; right: DRAM bytes. Absolute errors in percent (log scale,
# errors below 0.01% drawn at 0.01%); speed-up over the banked full run's host
# time (log scale). The banked run itself (1x, 0% error) is not a point.
# rtsim plot names no machine or image size for a table of its own making:
# the README says them (the default machine; rungs 128x128, samples 256x256).
#   usage: sh results/speed-accuracy/plot.sh PLOT.dat OUT.png|OUT.svg
set -eu
dat=$1 out=$2
rtsim=${RTSIM:-build/rtsim}
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
# PLOT.dat: rung, scene-policy, speed-up, error of cycles, error of DRAM bytes
# (percent, signed; empty where unknown). One tidy row per point and quantity.
awk '
function e(x) { x = x < 0 ? -x : x; return x < 0.01 ? 0.01 : x }
BEGIN { print "fidelity,metric,speed-up over banked (host time),|error| (%)" }
NF >= 4 && $4 != "" { printf "%s,cycles,%s,%.6g\n", $1, $3, e($4) }
NF >= 5 && $5 != "" { printf "%s,dram_bytes,%s,%.6g\n", $1, $3, e($5) }
' "$dat" > "$tmp/tidy.csv"
"$rtsim" plot "$tmp/tidy.csv" --x "speed-up over banked (host time)" --y "|error| (%)" \
  --lines fidelity --panels metric --points --logx --logy --yrange 0.005:200 -o "$out"
