#!/bin/sh
# The latency-hiding table of README.md: for each policy, threads per core and
# DRAM latency, core utilization at each rays-per-thread value, and the fewest
# rays per thread that reach 0.9 (">8": none of the swept values); then the
# work issued per geometry line fetched from DRAM. COLUMN (default
# dram.latency) is the memory axis; for the banked sweep, clock_ghz, with the
# mean DRAM read latency in core cycles of its points beside it.
#   usage: sh results/latency-hiding/summary.sh TABLE.csv [COLUMN]
set -eu
awk -v col="${2:-dram.latency}" '
# Split a CSV line into f[1..n] (quoted cells may hold commas).
function csv(line, f,   n, i, ch, cell, q) {
  n = 0; cell = ""; q = 0
  for (i = 1; i <= length(line); i++) {
    ch = substr(line, i, 1)
    if (q) { if (ch == "\"") { if (substr(line, i + 1, 1) == "\"") { cell = cell ch; i++ } else q = 0 } else cell = cell ch }
    else if (ch == "\"") q = 1
    else if (ch == ",") { f[++n] = cell; cell = "" }
    else cell = cell ch
  }
  f[++n] = cell
  return n
}
NR == 1 { nc = csv($0, h); for (i = 1; i <= nc; i++) c[h[i]] = i; next }
{
  csv($0, f)
  k = f[c["policy"]] "|" f[c["threads_per_core"]] "|" f[c[col]]
  ls[f[c[col]]] += f[c["dram_read_latency_mean"]]; ln[f[c[col]]]++
  u[k "|" f[c["rays_per_thread"]]] = f[c["core_utilization"]]
  if (!(k in seen)) { seen[k] = 1; keys[++n] = k }
  pol = f[c["policy"]]
  gs[pol] += f[c["issue_slots_per_geometry_miss"]]; gn[pol]++
  bs[pol] += f[c["issue_slots_per_blocking_load"]]
}
END {
  split("1 2 3 4 6 8", R, " ")
  print "| policy | threads/core | " (col == "dram.latency" ? "DRAM latency" : col " (DRAM read, cycles)") " | R=1 | R=2 | R=3 | R=4 | R=6 | R=8 | fewest R for 0.9 |"
  print "|---|---|---|---|---|---|---|---|---|---|"
  for (i = 1; i <= n; i++) {
    k = keys[i]; split(k, p, "|"); best = ">8"
    line = "| " p[1] " | " p[2] " | " p[3] (col == "dram.latency" ? "" : sprintf(" (%.0f)", ls[p[3]] / ln[p[3]]))
    for (j = 1; j <= 6; j++) {
      v = u[k "|" R[j]]; line = line " | " (v == "" ? "-" : sprintf("%.2f", v))
      if (best == ">8" && v != "" && v + 0 >= 0.9) best = R[j]
    }
    print line " | " best " |"
  }
  print ""
  print "| policy | issue slots per geometry line from DRAM (mean over points) | issue slots per load that left the L1 |"
  print "|---|---|---|"
  for (pol in gn) printf "| %s | %.0f | %.1f |\n", pol, gs[pol] / gn[pol], bs[pol] / gn[pol]
}' "$1"
