#!/bin/sh
# The memory-bound points of issue 36's study: configs/sweeps/memory-bound.yaml
# (64 cores, a 512 KiB or a 4 MiB L2, grove and sphereflake, primary + shadow +
# diffuse, the four policies, 512x512 and 1024x1024, every rung), one point at
# a time, then memory-bound.csv: one row a complete point. The sweep resumes:
# rerun the same command to go on after a stop. From the repository top, after
# sh .ci/setup:
#   sh results/speed-accuracy/memory-bound.sh [SWEEPDIR]
# With only a SWEEPDIR whose points are done, skip the runs: COLLECT_ONLY=1.
set -eu
cd "$(dirname "$0")/../.."
W=${1:-build/speed-accuracy/memory-bound}
[ "${COLLECT_ONLY:-0}" = 1 ] || build/rtsim sweep configs/sweeps/memory-bound.yaml -o "$W" -j 1
out=results/speed-accuracy/memory-bound.csv
echo "scene,policy,width,l2_size,fidelity,cycles,dram_bytes,dram_utilization,core_utilization,energy_j,wall_s,rung_dram_utilization,rung_bandwidth_bound" > "$out.tmp"
for d in "$W"/*/; do
  [ -f "$d/stats.csv" ] || continue
  wall=$(grep -o '"wall_s": [0-9.e+-]*' "$d/stats.json" | sed 's/.*: //')
  # A quoted field (rays) holds commas: one placeholder keeps the columns.
  awk -F, -v wall="$wall" '
    { gsub(/"[^"]*"/, "q"); $0 = $0 }
    NR == 1 { for (i = 1; i <= NF; i++) c[$i] = i; next }
    function f(k) { return c[k] ? $c[k] : "" }
    { printf "%s,%s,%s,%s,%s,%s,%.0f,%s,%s,%s,%.1f,%s,%s\n", $c["scene"], $c["policy"], $c["width"],
        $c["l2.size"], $c["fidelity"], $c["cycles"], $c["dram_read_bytes"] + $c["dram_write_bytes"],
        f("dram_utilization"), $c["core_utilization"], $c["energy_j"], wall,
        f("rung_dram_utilization"), f("rung_bandwidth_bound") }' "$d/stats.csv"
done | sort -t, -k3,3n -k1,1 -k4,4 -k2,2 -k5,5 >> "$out.tmp"
mv "$out.tmp" "$out"
