#!/bin/sh
# The cost maps of results/cost-maps: grove at 128x128 on configs/default.yaml,
# all ray types, for the three paper policies; two channels each, on one colour
# scale per channel. Run from the top of the repository after building.
set -e
out=results/cost-maps
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
echo "policy,cycles,issue_slots,load_latency_cycles_sum,fetch_geometry_bytes,fetch_node_bytes,fetch_ray_bytes,l2_writeback_bytes" > "$tmp/totals.csv"
for p in recursive packet dynamic; do
  build/rtsim run configs/default.yaml scenes/grove.yaml --width 128 --height 128 --policy $p \
    -o "$tmp/$p" --cost-preview $out/$p-geometry.png \
    --cost-channel cost.dram_read_bytes.geometry --cost-max 40000 > /dev/null
  build/rtsim run configs/default.yaml scenes/grove.yaml --width 128 --height 128 --policy $p \
    -o "$tmp/$p" --cost-preview $out/$p-wait.png \
    --cost-channel cost.load_wait_cycles --cost-max 500000 > /dev/null
  j="$tmp/$p/stats.json"
  v() { sed -n "s/^  \"$1\": \([0-9]*\),\{0,1\}$/\1/p" "$j"; }
  echo "$p,$(v cycles),$(v issue_slots),$(v load_latency_cycles_sum),$(v fetch_geometry_bytes),$(v fetch_node_bytes),$(v fetch_ray_bytes),$(v l2_writeback_bytes)" >> "$tmp/totals.csv"
done
# Whole or not at all: the table appears once every run is in.
mv "$tmp/totals.csv" $out/totals.csv
