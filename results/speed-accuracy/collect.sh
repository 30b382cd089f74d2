#!/bin/sh
# One CSV row per complete point of the given sweep directories: what it ran
# (scene, policy, fidelity, sample fraction and seed), its host time (wall_s:
# the render pass, without the scene load and tree build) and the figures the
# speed-accuracy study compares, with their 95% intervals where the point was
# sampled (empty otherwise). DRAM bytes are read + written.
#   usage: sh results/speed-accuracy/collect.sh SWEEPDIR...
set -eu
echo "scene,policy,width,fidelity,sample_fraction,sample_seed,wall_s,cycles,cycles_lo,cycles_hi,dram_bytes,dram_bytes_lo,dram_bytes_hi,core_utilization,core_utilization_lo,core_utilization_hi,load_latency_mean,load_latency_mean_lo,load_latency_mean_hi,rays_traced,issue_slots,sample_detailed_fraction,sample_units"
for dir in "$@"; do
  for j in "$dir"/*/stats.json; do
    awk '
    match($0, /^ +"[^"]+": /) {
      k = substr($0, RSTART, RLENGTH); gsub(/^ +"|": $/, "", k)
      v = substr($0, RSTART + RLENGTH); sub(/,$/, "", v); gsub(/"/, "", v); m[k] = v
    }
    END {
      b = (m["dram_bytes"] != "") ? m["dram_bytes"] : m["dram_read_bytes"] + m["dram_write_bytes"]
      printf "%s,%s,%s,%s,%s,%s,%s", m["scene"], m["policy"], m["width"], m["fidelity"], m["sample.fraction"], m["sample.seed"], m["wall_s"]
      printf ",%s,%s,%s", m["cycles"], m["cycles_ci95_low"], m["cycles_ci95_high"]
      printf ",%s,%s,%s", b, m["dram_bytes_ci95_low"], m["dram_bytes_ci95_high"]
      printf ",%s,%s,%s", m["core_utilization"], m["core_utilization_ci95_low"], m["core_utilization_ci95_high"]
      printf ",%s,%s,%s", m["load_latency_mean"], m["load_latency_mean_ci95_low"], m["load_latency_mean_ci95_high"]
      printf ",%s,%s,%s,%s\n", m["rays_traced"], m["issue_slots"], m["sample_detailed_fraction"], m["sample_units_measured"]
    }' "$j"
  done
done
