#!/bin/sh
# The summary tables of results/traffic/README.md. First, per scene and ray
# configuration: dynamic's geometry and total traffic over recursive's at 4 KB,
# 16 KB, 512 KB and 4 MB, and dynamic's total over packet's at 512 KB; every
# cell is ours (the paper's). Second, at 512 KB: each policy's non-geometry
# traffic (total minus geometry: rays, queues, framebuffer) in MB, ours / the
# paper's.
#   usage: sh results/traffic/summary.sh ALL.csv PAPER.csv
set -eu
awk -F, '
NR == FNR {
  # paper.csv: scene,rays,cache_bytes,frac,geo rec/pkt/dyn,total rec/pkt/dyn,...
  if (FNR == 1) next
  k = $1 "|" $2 "|" $3
  pg[k] = $13; pt[k] = $16
  pd[k] = sprintf("%.2f", $10 / $9)
  pr[k "|recursive"] = $8 - $5; pr[k "|packet"] = $9 - $6; pr[k "|dynamic"] = $10 - $7
  next
}
FNR == 1 { for (i = 1; i <= NF; i++) c[$i] = i; next }
{
  sc = $c["scene"]; sub(/-small$/, "", sc); r = $c["rays"]
  cfg = r == "primary" ? "primary" : r == "primary+shadow" ? "shadow" : r == "primary+shadow+specular" ? "specular" : r == "primary+shadow+diffuse" ? "diffuse" : r
  k = sc "|" cfg; cb = $c["cache_bytes"]; p = $c["policy"]
  g[k "|" cb "|" p] = $c["geometry_mb"]; t[k "|" cb "|" p] = $c["total_mb"]
  if (!(k in seen)) { seen[k] = 1; order[++n] = k }
}
function ratio(a, b) { return b > 0 ? sprintf("%.2f", a / b) : "-" }
function paper(arr, key) { return (key in arr) ? arr[key] : "n/a" }
END {
  print "| scene, rays | geometry 4K | 16K | 512K | 4M | total 4K | 16K | 512K | 4M | dyn/pkt total 512K |"
  print "|---|---|---|---|---|---|---|---|---|---|"
  split("4096 16384 524288 4194304", S, " ")
  for (i = 1; i <= n; i++) {
    k = order[i]; split(k, kk, "|")
    line = "| " kk[1] ", " kk[2] " |"
    for (j = 1; j <= 4; j++)
      line = line " " ratio(g[k "|" S[j] "|dynamic"], g[k "|" S[j] "|recursive"]) " (" paper(pg, k "|" S[j]) ") |"
    for (j = 1; j <= 4; j++)
      line = line " " ratio(t[k "|" S[j] "|dynamic"], t[k "|" S[j] "|recursive"]) " (" paper(pt, k "|" S[j]) ") |"
    line = line " " ratio(t[k "|524288|dynamic"], t[k "|524288|packet"]) " (" paper(pd, k "|524288") ") |"
    print line
  }
  print ""
  print "| scene, rays | recursive | packet | dynamic |"
  print "|---|---|---|---|"
  split("recursive packet dynamic", P, " ")
  for (i = 1; i <= n; i++) {
    k = order[i]; split(k, kk, "|")
    line = "| " kk[1] ", " kk[2] " |"
    for (j = 1; j <= 3; j++) {
      q = k "|524288|" P[j]
      line = line sprintf(" %.0f / %s |", t[q] - g[q], ((k "|524288|" P[j]) in pr) ? sprintf("%.0f", pr[k "|524288|" P[j]]) : "n/a")
    }
    print line
  }
}' "$2" "$1"
