#!/bin/sh
# Primary-ray throughput at 1024x1024 beside Embree 3, for both k-d trees and
# both BVHs: each scene as committed (whole bounds, PBRT's tree), with
# kd_tree.splits: clipped, and with accel: bvh2 and accel: bvh8.
# A benchmark (host seconds), not a test; run it on a quiet machine.
#   usage: sh results/bench_primary.sh > results/bench_primary.csv   (from the
#   repository top). Needs Debian's libembree-dev; builds build-embree/ itself.
set -eu
apt-get install -y libembree-dev > /dev/null 2>&1 || true
cmake -S . -B build-embree -DRTSIM_EMBREE=ON > /dev/null
cmake --build build-embree -j2 > /dev/null
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
set --
for s in sphereflake grove room; do
  { cat "scenes/$s.yaml"; echo 'kd_tree: {splits: clipped}'; } > "$tmp/$s.yaml"
  { cat "scenes/$s.yaml"; echo 'accel: bvh2'; } > "$tmp/$s-bvh2.yaml"
  { cat "scenes/$s.yaml"; echo 'accel: bvh8'; } > "$tmp/$s-bvh8.yaml"
  set -- "$@" "scenes/$s.yaml" "$tmp/$s.yaml" "$tmp/$s-bvh2.yaml" "$tmp/$s-bvh8.yaml"
done
build-embree/rtsim bench --embree --repeat 3 "$@"
