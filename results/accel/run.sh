#!/bin/sh
# results/accel: the k-d tree, the BVH2 and the compressed BVH8 under the four
# policies. Three parts, one run at a time, into W (default build/accel):
#   1. the paper's traffic grid (rtsim traffic: 3 scenes x 4 ray
#      configurations x 13 cache sizes x 4 policies) for each structure, at
#      the paper's resolutions divided by DIV (default 4: 256x256, diffuse
#      128x128), into traffic-STRUCTURE.csv;
#   2. the contention study's memory-bound points
#      (configs/sweeps/accel-contention.yaml, 72 timed runs) into
#      contention.csv;
#   3. latency hiding (configs/sweeps/accel-latency.yaml, 36 timed runs) into
#      latency.csv;
# then tables.md. From the repository top, after sh .ci/setup:
#   sh results/accel/run.sh [W]
set -eu
W=${1:-build/accel} DIV=${DIV:-4} R=results/accel
for a in kd bvh2 bvh8; do
  ACCEL=$a POLICY=all sh results/traffic/run.sh "$W/traffic-$a" "$DIV" 1
  cp "$W/traffic-$a/all.csv" "$R/traffic-$a.csv"
done
for s in contention latency; do
  build/rtsim sweep "configs/sweeps/accel-$s.yaml" -o "$W/$s" -j 1
  build/rtsim merge "$W/$s" -o "$R/$s.csv"
done
sh "$R/tables.sh" "$R" > "$R/tables.md.tmp" && mv "$R/tables.md.tmp" "$R/tables.md"
