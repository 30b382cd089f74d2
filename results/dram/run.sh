#!/bin/sh
# results/dram: the DRAM's levels of detail on rtsim's own traffic.
#  1. levels.csv: fixed, channel and banked on the default machine, every scene
#     and policy (configs/sweeps/dram-levels.yaml).
#  2. dramsim3.csv: the banked DDR4-2400 level against DRAMsim3 on the same
#     request streams (each run's --dram-trace, replayed open loop by both).
#     DRAMsim3's side needs a DRAMsim3 build with results/dram/dramsim3_replay.cc
#     (README here): DRAMSIM3=its binary DRAMSIM3_INI=its DDR4_8Gb_x8_2400.ini.
#     Without them only rtsim's columns are filled.
# From the repository top, after sh .ci/setup:
#   [DRAMSIM3=... DRAMSIM3_INI=...] sh results/dram/run.sh
set -eu
out=build/dram
# A fresh directory: a sweep resumes, and points from an older build would stay.
rm -rf "$out"
mkdir -p "$out"
build/rtsim sweep configs/sweeps/dram-levels.yaml -o "$out/levels"
build/rtsim merge "$out/levels" -o results/dram/levels.csv

csvget() { awk -F, -v k="$2" 'NR == 1 { for (i = 1; i <= NF; i++) if ($i == k) c = i } NR == 2 { print $c }' "$1"; }
kvget() { awk -F= -v k="$2" '$1 == k { print $2 }' "$1"; }

table=results/dram/dramsim3.csv
echo "scene,policy,requests,writes,rtsim_read_latency_mean,dramsim3_read_latency_mean,rtsim_read_latency_p50,dramsim3_read_latency_p50,rtsim_read_latency_p95,dramsim3_read_latency_p95,rtsim_read_latency_p99,dramsim3_read_latency_p99,rtsim_gb_per_s,dramsim3_gb_per_s,rtsim_row_hit_rate,dramsim3_row_hit_rate" > "$table.tmp"
for scene in sphereflake grove room; do
  for policy in recursive dynamic; do
    t="$out/$scene-$policy"
    build/rtsim run configs/default.yaml "scenes/$scene.yaml" --width 96 --height 96 \
      --rays primary,shadow,diffuse --policy "$policy" --dram-trace "$t.trace" -o "$t" > /dev/null
    build/rtsim dram-replay configs/default.yaml "$t.trace" > "$t.rtsim.csv"
    d3_mean= d3_p50= d3_p95= d3_p99= d3_gbs= d3_hit=
    if [ -n "${DRAMSIM3:-}" ]; then
      awk '!/^#/ && NF { print $1, $2, $3 }' "$t.trace" > "$t.dramsim3.trace"
      # DRAMsim3's controller can deadlock (a write drain that a queued read of
      # the same line blocks, with that read never moved): bound its run at
      # twice the stream's span and leave its columns empty if it stalls.
      limit=$(awk 'END { print 2 * $3 + 1000000 }' "$t.dramsim3.trace")
      "$DRAMSIM3" "$DRAMSIM3_INI" "$t.dramsim3.trace" --out-dir "$t.dramsim3" \
        --cycles-limit "$limit" > "$t.dramsim3.txt" || true
      d3="$t.dramsim3.txt"
      if [ "$(kvget "$d3" finished)" = 1 ]; then
        d3_mean=$(kvget "$d3" read_latency_mean) d3_p50=$(kvget "$d3" read_latency_p50)
        d3_p95=$(kvget "$d3" read_latency_p95) d3_p99=$(kvget "$d3" read_latency_p99)
        d3_gbs=$(awk -v b="$(kvget "$d3" bandwidth_bytes_per_cycle)" 'BEGIN { printf "%.3f", b * 1.2 }')
        d3_hit=$(kvget "$d3" row_hit_rate)
      fi
    fi
    r="$t.rtsim.csv"
    printf '%s,%s,%s,%s,%.2f,%s,%.0f,%s,%.1f,%s,%.1f,%s,%.3f,%s,%.4f,%s\n' "$scene" "$policy" \
      "$(csvget "$r" requests)" "$(csvget "$r" writes)" \
      "$(csvget "$r" read_latency_mean_dram_cycles)" "$d3_mean" \
      "$(csvget "$r" read_latency_p50_dram_cycles)" "$d3_p50" \
      "$(csvget "$r" read_latency_p95_dram_cycles)" "$d3_p95" \
      "$(csvget "$r" read_latency_p99_dram_cycles)" "$d3_p99" \
      "$(csvget "$r" gb_per_s)" "$d3_gbs" "$(csvget "$r" dram_row_hit_rate)" "$d3_hit" >> "$table.tmp"
  done
done
mv "$table.tmp" "$table"

# 3. saturated.csv: the first 400,000 requests of two streams offered one a DRAM
#    cycle (at clock_ghz 1.2 the core and DRAM cycles are one), faster than one
#    channel serves: the bandwidth each controller sustains.
sat=results/dram/saturated.csv
echo "stream,rtsim_bytes_per_cycle,dramsim3_bytes_per_cycle,rtsim_row_hit_rate,dramsim3_row_hit_rate" > "$sat.tmp"
for s in grove-recursive sphereflake-dynamic; do
  awk '!/^#/ && NF { n++; if (n <= 400000) print $1, $2, n }' "$out/$s.trace" > "$out/$s.saturated.trace"
  build/rtsim dram-replay configs/default.yaml "$out/$s.saturated.trace" --set clock_ghz=1.2 > "$out/$s.saturated.csv"
  d3_bpc= d3_hit=
  if [ -n "${DRAMSIM3:-}" ]; then
    "$DRAMSIM3" "$DRAMSIM3_INI" "$out/$s.saturated.trace" --out-dir "$out/$s.saturated.dramsim3" \
      --cycles-limit 20000000 > "$out/$s.saturated.dramsim3.txt" || true
    if [ "$(kvget "$out/$s.saturated.dramsim3.txt" finished)" = 1 ]; then
      d3_bpc=$(kvget "$out/$s.saturated.dramsim3.txt" bandwidth_bytes_per_cycle)
      d3_hit=$(kvget "$out/$s.saturated.dramsim3.txt" row_hit_rate)
    fi
  fi
  r="$out/$s.saturated.csv"
  printf '%s,%.3f,%s,%.4f,%s\n' "$s" "$(csvget "$r" bytes_per_cycle)" "$d3_bpc" \
    "$(csvget "$r" dram_row_hit_rate)" "$d3_hit" >> "$sat.tmp"
done
mv "$sat.tmp" "$sat"
