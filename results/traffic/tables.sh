#!/bin/sh
# Markdown tables of our traffic (all.csv from run.sh) beside the paper's
# (paper.csv), one table per scene and ray configuration, as the paper's
# Figures 5-7: per cache size, the fraction of potentially visible geometry that
# fits, geometry and total MB per policy, and total relative to recursive.
#   usage: sh results/traffic/tables.sh ALL.csv PAPER.csv
set -eu
awk -F, '
NR == FNR {  # paper.csv
  if (FNR > 1) { k = $1 "|" $2 "|" $3; pg[k] = $5 " / " $6 " / " $7; pt[k] = $8 " / " $9 " / " $10; prt[k] = $15 " / " $16; pv[$1 "|" $2] = $17 " (" $18 " MB)" }
  next
}
FNR == 1 { for (i = 1; i <= NF; i++) col[$i] = i; next }
{
  sc = $col["scene"]; sub(/-small$/, "", sc)
  cfg = $col["rays"]
  if (cfg == "primary") c = "primary"; else if (cfg == "primary+shadow") c = "shadow";
  else if (cfg == "primary+shadow+specular") c = "specular"; else if (cfg == "primary+shadow+diffuse") c = "diffuse"; else c = cfg
  key = sc "|" c
  if (!(key in seen)) { seen[key] = 1; order[++n] = key; res[key] = $col["width"] "x" $col["height"] }
  cb = $col["cache_bytes"]; p = $col["policy"]
  sizes[key "|" cb] = 1; if (!(cb in sizeseen)) { sizeseen[cb] = 1; sz[++ns] = cb }
  g[key "|" cb "|" p] = $col["geometry_mb"]; t[key "|" cb "|" p] = $col["total_mb"]
  rt[key "|" cb "|" p] = $col["rel_total"]; f[key "|" cb "|" p] = $col["frac_pot_vis"]
  pvt[key "|" p] = $col["pot_vis_tris"]; pvb[key "|" p] = $col["pot_vis_bytes"]
}
END {
  for (i = 1; i <= n; i++) {
    key = order[i]; split(key, kk, "|")
    printf "### %s, %s rays (%s)\n\n", kk[1], kk[2], res[key]
    printf "Potentially visible (recursive): %d triangles (%.2f MB); paper: %s.\n\n", pvt[key "|recursive"], pvb[key "|recursive"] / 1048576, (key in pv) ? pv[key] : "n/a"
    print "| cache | frac pot-vis | geometry MB rec / pkt / dyn | paper | total MB rec / pkt / dyn | paper | rel total pkt / dyn | paper |"
    print "|---|---|---|---|---|---|---|---|"
    for (j = 1; j <= ns; j++) {
      cb = sz[j]; b = key "|" cb; pk = kk[1] "|" kk[2] "|" cb
      printf "| %d K | %.3f | %.2f / %.2f / %.2f | %s | %.2f / %.2f / %.2f | %s | %.2f / %.2f | %s |\n", cb / 1024, f[b "|recursive"], \
        g[b "|recursive"], g[b "|packet"], g[b "|dynamic"], (pk in pg) ? pg[pk] : "", \
        t[b "|recursive"], t[b "|packet"], t[b "|dynamic"], (pk in pt) ? pt[pk] : "", \
        rt[b "|packet"], rt[b "|dynamic"], (pk in prt) ? prt[pk] : ""
    }
    print ""
  }
}' "$2" "$1"
