#!/bin/sh
# The energy study's figures (README.md), through rtsim plot: millijoules a
# frame against cores, a line a policy; the frame's energy by part (chip
# dynamic and leakage, DRAM traffic and background) as stacked bars, a group a
# policy and a bar a core count; energy against DRAM bytes, a point a run; on
# the scheduling points, the parts again, a panel an L2 size; on the
# latency-hiding points, millijoules a frame against rays a thread, a line a
# thread count, and the parts by policy and thread count at two rays a thread.
#   usage: sh results/energy/plot.sh CONTENTION.csv SCHEDULING.csv LATENCY-HIDING.csv OUTDIR
set -eu
RTSIM=${RTSIM:-build/rtsim}
here=$(dirname "$0")
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
# The parts' columns as the legend names them.
parts() {
  sh "$here/derive.sh" "$1" |
    sed '1s/chip_dynamic,chip_leakage,dram_traffic,dram_background/chip dynamic,chip leakage,DRAM traffic,DRAM background/'
}
parts "$1" > "$tmp/c.csv"
parts "$2" > "$tmp/s.csv"
parts "$3" > "$tmp/l.csv"
o=$4
PARTS="chip dynamic,chip leakage,DRAM traffic,DRAM background"
ORDER=recursive,packet,dynamic,treelet,sphereflake,grove,room
MJ="energy a frame (mJ)"
"$RTSIM" plot "$tmp/c.csv" --x cores --y energy_mj_per_frame --lines policy --dash l2.size --order $ORDER \
  --panels scene --logx --ylabel "$MJ" --title "Energy a frame against cores, by policy and L2 size" \
  -o "$o/mj-per-frame.png"
for l2 in 1048576 4194304; do
  "$RTSIM" plot "$tmp/c.csv" --x policy --y "$PARTS" --stack --lines cores --order $ORDER --panels scene \
    --where l2.size=$l2 --ylabel "$MJ" --title "Energy a frame by part, $((l2 / 1048576)) MiB L2 (bars: 4, 16, 64 cores)" \
    -o "$o/parts-l2-$l2.png"
done
"$RTSIM" plot "$tmp/c.csv" --x dram_bytes --y energy_mj_per_frame --points --lines policy --order $ORDER \
  --panels scene --ylabel "$MJ" --title "Energy a frame against DRAM bytes (a point: a core count and L2 size)" \
  -o "$o/mj-against-dram-bytes.png"
"$RTSIM" plot "$tmp/s.csv" --x policy --y "$PARTS" --stack --lines cores --order $ORDER --panels l2.size \
  --ylabel "$MJ" --title "Energy a frame by part, grove with diffuse rays (bars: 16 and 64 cores)" \
  -o "$o/scheduling-parts.png"
for ghz in 1.4 5.6; do
  "$RTSIM" plot "$tmp/l.csv" --x rays_per_thread --y energy_mj_per_frame --lines threads_per_core \
    --panels policy --order $ORDER --where clock_ghz=$ghz --mark-x 2 --mark-x 4 --ylabel "$MJ" \
    --title "Energy a frame against rays a thread, $ghz GHz" -o "$o/latency-hiding-mj-$ghz.png"
done
"$RTSIM" plot "$tmp/l.csv" --x policy --y "$PARTS" --stack --lines threads_per_core --panels clock_ghz \
  --order $ORDER --where rays_per_thread=2 --ylabel "$MJ" \
  --title "Energy a frame by part, 2 rays a thread (bars: 1, 2, 4, 8 threads a core)" \
  -o "$o/latency-hiding-parts.png"
