#!/bin/sh
# results/energy: joules a frame by policy on the contention study's points,
# on the scheduling study's case (grove, diffuse rays) cut to 128x128, and on
# the latency-hiding study's banked points; the tables (table.md, summary.csv)
# and the figures. From the repository top, after sh .ci/setup:
#   sh results/energy/run.sh
# Three sweeps into build/energy, one point at a time (the study's budget is
# about half an hour of one host core), then the merged tables, table.md and
# the PNGs in results/energy.
set -eu
out=build/energy res=results/energy
# A fresh directory: a sweep resumes, and points from an older build would stay.
rm -rf "$out"
mkdir -p "$out"
for s in contention scheduling latency-hiding; do
  build/rtsim sweep configs/sweeps/energy-$s.yaml -o "$out/$s" -j 1
  build/rtsim merge "$out/$s" -o "$res/$s.csv"
done
sh "$res/summary.sh" "$res/contention.csv" "$res/scheduling.csv" "$res/latency-hiding.csv" \
  "$res/summary.csv" > "$res/table.md"
sh "$res/plot.sh" "$res/contention.csv" "$res/scheduling.csv" "$res/latency-hiding.csv" "$res"
