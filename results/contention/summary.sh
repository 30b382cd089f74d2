#!/bin/sh
# The contention study's table (results/contention/README.md, "The numbers")
# from the merged sweep (table.csv): one row per scene, policy and cores, the
# 4 MiB L2's figures with the 1 MiB L2's in brackets where they differ as
# printed (latency and MSHR merges: 4 MiB only). Geometry is triangles and
# k-d nodes fetched from DRAM, in MiB.
#   usage: sh results/contention/summary.sh TABLE.csv
set -eu
awk -f "$(dirname "$0")/scheduling/unquote.awk" "$1" | awk -F, '
NR == 1 { for (i = 1; i <= NF; i++) c[$i] = i; next }
{
  key = $c["scene"] "|" $c["policy"] "|" $c["cores"]
  if (!(key in seen)) { seen[key] = 1; order[++n] = key; rank[key] = srank($c["scene"]) * 1e7 + prank($c["policy"]) * 1e6 + $c["cores"] }
  big = ($c["l2.size"] == 4194304); if (!big && $c["l2.size"] != 1048576) next
  k = key "|" (big ? "4" : "1")
  cyc[k] = sprintf("%.3g", $c["cycles"] / 1e6); rps[k] = sprintf("%.3g", $c["rays_per_second"] / 1e6)
  cu[k] = sprintf("%.2f", $c["core_utilization"]); bus[k] = sprintf("%.2f", $c["dram_bus_utilization"])
  rh[k] = sprintf("%.2f", $c["dram_row_hit_rate"]); mr[k] = sprintf("%.2f", $c["l2_miss_rate"])
  geo[k] = sprintf("%.1f", ($c["fetch_geometry_bytes"] + $c["fetch_node_bytes"]) / 1048576)
  lat[k] = sprintf("%.0f / %.0f", $c["dram_read_latency_mean"], $c["dram_read_latency_p95"])
  m = $c["l2_mshr_merges"]; mg[k] = m >= 1000 ? sprintf("%.1fK", m / 1000) : m
}
# Rows in the order of the README: sphereflake, grove, room; recursive, packet,
# dynamic; cores ascending.
function srank(x) { return x == "sphereflake" ? 1 : x == "grove" ? 2 : x == "room" ? 3 : 4 }
function prank(x) { return x == "recursive" ? 1 : x == "packet" ? 2 : x == "dynamic" ? 3 : 4 }
function both(a, key) {
  return (a[key "|4"] == a[key "|1"]) ? a[key "|4"] : a[key "|4"] " (" a[key "|1"] ")"
}
END {
  for (i = 2; i <= n; i++)
    for (j = i; j > 1 && rank[order[j]] < rank[order[j - 1]]; j--) {
      t = order[j]; order[j] = order[j - 1]; order[j - 1] = t
    }
  print "| scene | policy | cores | Mcycles | rays/s (M) | core util. | DRAM bus util. | DRAM read latency mean / p95 | row hit rate | L2 miss rate | MSHR merges | geometry MB |"
  print "|---|---|---|---|---|---|---|---|---|---|---|---|"
  for (i = 1; i <= n; i++) {
    split(order[i], kk, "|")
    printf "| %s | %s | %s | %s | %s | %s | %s | %s | %s | %s | %s | %s |\n", kk[1], kk[2], kk[3], \
      both(cyc, order[i]), both(rps, order[i]), both(cu, order[i]), both(bus, order[i]), \
      lat[order[i] "|4"], both(rh, order[i]), both(mr, order[i]), mg[order[i] "|4"], both(geo, order[i])
  }
}'
