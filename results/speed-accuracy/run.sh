#!/bin/sh
# results/speed-accuracy: every rung of the fidelity ladder and sampling,
# against the banked rung's full run; host time and error. From the
# repository top, after sh .ci/setup:
#   sh results/speed-accuracy/run.sh
# Three sweeps into build/speed-accuracy (the first two one point at a time,
# since their host times are results; the coverage sweep's host times are not
# used), then points.csv and coverage.csv (one
# row a point), table.md (summary.sh) and error-vs-speedup.png (plot.sh).
set -eu
out=build/speed-accuracy res=results/speed-accuracy
# A fresh directory: a sweep resumes, and points from an older build would stay.
rm -rf "$out"
mkdir -p "$out"
build/rtsim sweep configs/sweeps/speed-accuracy.yaml -o "$out/ladder" -j 1
build/rtsim sweep configs/sweeps/sampling.yaml -o "$out/sampling" -j 1
build/rtsim sweep configs/sweeps/sampling-coverage.yaml -o "$out/coverage"
sh "$res/collect.sh" "$out/ladder" "$out/sampling" > "$res/points.csv"
sh "$res/collect.sh" "$out/coverage" > "$res/coverage.csv"
sh "$res/summary.sh" "$res/points.csv" "$res/coverage.csv" "$out/plot.dat" > "$res/table.md"
sh "$res/plot.sh" "$out/plot.dat" "$res/error-vs-speedup.png"
