#!/bin/sh
# The summary table of results/traffic/README.md: per scene and ray
# configuration, dynamic's geometry and total traffic over recursive's at 4 KB,
# 16 KB, 512 KB and 4 MB, and dynamic's total over packet's at 512 KB beside the
# paper's.   usage: sh results/traffic/summary.sh ALL.csv PAPER.csv
set -eu
awk -F, '
NR == FNR { if (FNR > 1 && $3 == 524288) paper[$1 "|" $2] = $10 / $9; next }
FNR == 1 { for (i = 1; i <= NF; i++) c[$i] = i; next }
{
  sc = $c["scene"]; sub(/-small$/, "", sc); r = $c["rays"]
  cfg = r == "primary" ? "primary" : r == "primary+shadow" ? "shadow" : r == "primary+shadow+specular" ? "specular" : r == "primary+shadow+diffuse" ? "diffuse" : r
  k = sc "|" cfg; cb = $c["cache_bytes"]; p = $c["policy"]
  g[k "|" cb "|" p] = $c["geometry_mb"]; t[k "|" cb "|" p] = $c["total_mb"]
  if (!(k in seen)) { seen[k] = 1; order[++n] = k }
}
function ratio(a, b) { return b > 0 ? sprintf("%.2f", a / b) : "-" }
END {
  print "| scene, rays | dyn/rec geometry at 4K / 16K / 512K / 4M | dyn/rec total at 4K / 16K / 512K / 4M | dyn/pkt total at 512K (paper) |"
  print "|---|---|---|---|"
  split("4096 16384 524288 4194304", S, " ")
  for (i = 1; i <= n; i++) {
    k = order[i]; split(k, kk, "|")
    line = "| " kk[1] ", " kk[2] " |"
    for (j = 1; j <= 4; j++) line = line " " ratio(g[k "|" S[j] "|dynamic"], g[k "|" S[j] "|recursive"]) (j < 4 ? " /" : " |")
    for (j = 1; j <= 4; j++) line = line " " ratio(t[k "|" S[j] "|dynamic"], t[k "|" S[j] "|recursive"]) (j < 4 ? " /" : " |")
    line = line " " ratio(t[k "|524288|dynamic"], t[k "|524288|packet"]) " (" ((k in paper) ? sprintf("%.2f", paper[k]) : "n/a") ") |"
    print line
  }
}' "$2" "$1"
