#!/bin/sh
# The study's tables (markdown on stdout) from the merged sweeps and the
# traffic grids of results/accel/run.sh:
#   sh results/accel/tables.sh results/accel > results/accel/tables.md
set -eu
R=${1:-results/accel}

# One merged table's columns by name, the quoted point names made one field.
cols() {
  awk -F, -v want="$2" '
    { gsub(/"[^"]*"/, "q"); $0 = $0 }
    NR == 1 { for (i = 1; i <= NF; i++) c[$i] = i; n = split(want, w, " "); next }
    { s = ""; for (i = 1; i <= n; i++) s = s (i > 1 ? "," : "") $c[w[i]]; print s }' "$1"
}

# One table a machine of the sweep (cores, L2 bytes), in the sweep's order.
contention_table() {
  echo "## The memory-bound point: $1 cores, $(($2 / 1024)) KiB L2 (128x128, primary + shadow + diffuse)"
  echo
  echo "Each policy against recursive on the same structure (x recursive's), and each"
  echo "structure's figures. DRAM MB: read and written; geometry: triangles and nodes."
  echo
  echo "| scene | policy | structure | Mcycles | x recursive | DRAM MB | geometry MB | x recursive | core util. | DRAM util. | Mrays/s | mJ a frame |"
  echo "|---|---|---|---|---|---|---|---|---|---|---|---|"
  cols "$R/contention.csv" "scene policy accel cycles dram_bytes fetch_geometry_bytes fetch_node_bytes core_utilization dram_utilization rays_per_second energy_mj_per_frame cores l2.size" |
    awk -F, -v cores="$1" -v l2="$2" '
      $12 != cores || $13 != l2 { next }
      { k = $1 SUBSEP $3; if ($2 == "recursive") { rc[k] = $4; rg[k] = $6 + $7 }
        row[++nr] = $0 }
      END {
        n = split("grove sphereflake", S, " "); m = split("recursive packet dynamic treelet", P, " ")
        split("kd bvh2 bvh8", A, " ")
        for (s = 1; s <= n; s++) for (p = 1; p <= m; p++) for (a = 1; a <= 3; a++)
          for (i = 1; i <= nr; i++) {
            split(row[i], f, ",")
            if (f[1] != S[s] || f[2] != P[p] || f[3] != A[a]) continue
            k = f[1] SUBSEP f[3]; g = f[6] + f[7]
            printf "| %s | %s | %s | %.1f | %.2f | %.0f | %.0f | %.2f | %.2f | %.2f | %.1f | %.2f |\n",
              f[1], f[2], f[3], f[4] / 1e6, f[4] / rc[k], f[5] / 1e6, g / 1e6, g / rg[k], f[8],
              f[9], f[10] / 1e6, f[11]
          }
      }'
  echo
}
contention_table 64 524288
contention_table 16 524288
contention_table 64 4194304

echo "## Latency hiding (grove 128x128, primary + shadow, recursive, 2 cores)"
echo
echo "Core utilization by rays a thread (1, 2, 4)."
echo
echo "| threads a core | DRAM latency | structure | 1 ray | 2 rays | 4 rays | issue slots (M) |"
echo "|---|---|---|---|---|---|---|"
cols "$R/latency.csv" "threads_per_core dram.latency accel rays_per_thread core_utilization issue_slots" |
  awk -F, '
    { k = $1 SUBSEP $2 SUBSEP $3; u[k, $4] = $5; slots[k] = $6 }
    END {
      split("1 4", T, " "); split("200 800", L, " "); split("kd bvh2 bvh8", A, " ")
      for (t = 1; t <= 2; t++) for (l = 1; l <= 2; l++) for (a = 1; a <= 3; a++) {
        k = T[t] SUBSEP L[l] SUBSEP A[a]
        printf "| %s | %s | %s | %.3f | %.3f | %.3f | %.1f |\n", T[t], L[l], A[a], u[k, 1],
          u[k, 2], u[k, 4], slots[k] / 1e6
      }
    }'

echo
echo "## Traffic (rtsim traffic): DRAM-to-L2 MB, and x recursive's on the same structure"
echo
echo "At three cache sizes; the rays are the paper's configurations (shadow: primary and"
echo "shadow; specular and diffuse: with shadows); geometry is triangles and nodes, total"
echo "adds rays, queues and write-backs."
echo
echo "| scene | rays | cache | structure | recursive total | packet | dynamic | treelet | recursive geometry | packet | dynamic | treelet |"
echo "|---|---|---|---|---|---|---|---|---|---|---|---|"
for a in kd bvh2 bvh8; do
  awk -F, -v a="$a" 'NR == 1 { for (i = 1; i <= NF; i++) c[$i] = i; next }
    { print $c["scene"] "," $c["rays"] "," $c["cache_bytes"] "," a "," $c["policy"] "," \
        $c["total_mb"] "," $c["geometry_mb"] }' "$R/traffic-$a.csv"
done | awk -F, '
  { k = $1 SUBSEP $2 SUBSEP $3 SUBSEP $4; t[k, $5] = $6; g[k, $5] = $7 }
  END {
    split("room grove sphereflake", S, " "); split("primary primary+shadow primary+shadow+specular primary+shadow+diffuse", C, " ")
    split("primary shadow specular diffuse", CN, " ")
    split("65536 524288 4194304", Z, " "); split("kd bvh2 bvh8", A, " ")
    split("packet dynamic treelet", P, " ")
    for (s = 1; s <= 3; s++) for (c = 1; c <= 4; c++) for (z = 1; z <= 3; z++)
      for (a = 1; a <= 3; a++) {
        k = S[s] SUBSEP C[c] SUBSEP Z[z] SUBSEP A[a]
        if (!((k, "recursive") in t)) continue
        line = sprintf("| %s | %s | %d KiB | %s | %.1f", S[s], CN[c], Z[z] / 1024, A[a], t[k, "recursive"])
        for (p = 1; p <= 3; p++) line = line sprintf(" | %.2f", t[k, P[p]] / t[k, "recursive"])
        line = line sprintf(" | %.1f", g[k, "recursive"])
        for (p = 1; p <= 3; p++) line = line sprintf(" | %.2f", g[k, P[p]] / g[k, "recursive"])
        print line " |"
      }
  }'
