#!/bin/sh
# The scheduling study's table (results/contention/README.md) from the merged
# sweep (table.csv): one row per scene, L2, cores and scheme (the policy, and
# for dynamic and treelet the sharing mode): Mcycles, speed against recursive
# at the same point, simulated rays per second, DRAM MiB read by class
# (geometry: triangles and k-d nodes; rays; queues) and written, the DRAM bus
# utilization, and where the threads' cycles went.
#   usage: sh results/contention/scheduling/summary.sh TABLE.csv
set -eu
awk -f "$(dirname "$0")/unquote.awk" "$1" | awk -F, '
NR == 1 { for (i = 1; i <= NF; i++) c[$i] = i; next }
{
  s = $c["policy"]; if (s == "dynamic" || s == "treelet") s = s " (" $c["dynamic.sharing"] ")"
  l2 = $c["l2.size"] / 1024; l2 = (l2 >= 1024) ? (l2 / 1024) " MiB" : l2 " KiB"
  key = $c["scene"] "|" l2 "|" $c["cores"]
  if (!(key in seen)) { seen[key] = 1; order[++n] = key }
  k = key "|" s; if (!(s in sseen)) { sseen[s] = 1; sch[++ns] = s }
  cyc[k] = $c["cycles"]; rps[k] = $c["rays_per_second"]
  geo[k] = ($c["fetch_geometry_bytes"] + $c["fetch_node_bytes"]) / 1048576
  ray[k] = $c["fetch_ray_bytes"] / 1048576; que[k] = $c["fetch_queue_bytes"] / 1048576
  wr[k] = $c["dram_write_bytes"] / 1048576; bus[k] = $c["dram_bus_utilization"]
  cu[k] = $c["core_utilization"]; tw[k] = $c["thread_wait_fraction"]
  tp[k] = $c["thread_parked_fraction"]; td[k] = $c["thread_done_fraction"]
}
END {
  print "| scene | L2 | cores | scheme | Mcycles | speed vs recursive | rays/s (M) | DRAM read MiB: geometry / rays / queues | DRAM written MiB | DRAM bus util. | core util. | thread wait / parked / done |"
  print "|---|---|---|---|---|---|---|---|---|---|---|---|"
  for (i = 1; i <= n; i++) {
    split(order[i], kk, "|")
    r = order[i] "|recursive"
    for (j = 1; j <= ns; j++) {
      k = order[i] "|" sch[j]; if (!(k in cyc)) continue
      printf "| %s | %s | %s | %s | %.1f | %s | %.1f | %.1f / %.1f / %.1f | %.1f | %.2f | %.2f | %.2f / %.2f / %.2f |\n", \
        kk[1], kk[2], kk[3], sch[j], cyc[k] / 1e6, (r in cyc) ? sprintf("%.2f", cyc[r] / cyc[k]) : "", rps[k] / 1e6, \
        geo[k], ray[k], que[k], wr[k], bus[k], cu[k], tw[k], tp[k], td[k]
    }
  }
}'
