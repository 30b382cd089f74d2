#!/bin/sh
# The scheduling study's figures: for each L2 size, cycles, DRAM bytes and the
# threads' waiting share against cores, one line a scheme (the policy, and for
# dynamic and treelet the sharing mode), one panel a scene; and the DRAM bytes
# by data class at 16 cores as stacked bars.
#   usage: sh results/contention/scheduling/plot.sh TABLE.csv OUTDIR
set -eu
RTSIM=${RTSIM:-build/rtsim}
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
# rtsim plot draws one line per value of one column: add a scheme column.
awk -f "$(dirname "$0")/unquote.awk" "$1" | awk -F, -v OFS=, '
NR == 1 { for (i = 1; i <= NF; i++) c[$i] = i; print $0, "scheme"; next }
{ s = $c["policy"]; if (s == "dynamic" || s == "treelet") s = s "-" $c["dynamic.sharing"]; print $0, s }' \
  > "$tmp/t.csv"
# The paper's order of the policies, then the newer schemes.
ORDER=recursive,packet,dynamic-chip,dynamic-partition,treelet-chip,treelet-partition
for l2 in 524288 4194304; do
  "$RTSIM" plot "$tmp/t.csv" --x cores --y cycles --lines scheme --order $ORDER --panels scene --where l2.size=$l2 --logx --logy -o "$2/cycles-l2-$l2.png"
  "$RTSIM" plot "$tmp/t.csv" --x cores --y dram_bytes --lines scheme --order $ORDER --panels scene --where l2.size=$l2 --logx --logy -o "$2/dram_bytes-l2-$l2.png"
  "$RTSIM" plot "$tmp/t.csv" --x cores --y thread_wait_fraction --lines scheme --order $ORDER --panels scene --where l2.size=$l2 --logx -o "$2/thread_wait_fraction-l2-$l2.png"
done
# The paper's Figures 3-4 as bars: DRAM bytes by data class, a group per
# scheme, a bar per L2 size, at 16 cores.
"$RTSIM" plot "$tmp/t.csv" --x scheme --y fetch_geometry_bytes,fetch_node_bytes,fetch_ray_bytes,fetch_queue_bytes,fetch_other_bytes \
  --stack --lines l2.size --order $ORDER --panels scene --where cores=16 -o "$2/bytes-by-class-cores-16.png"
