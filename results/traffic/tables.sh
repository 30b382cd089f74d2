#!/bin/sh
# Markdown tables of our traffic (all.csv from run.sh) beside the paper's
# (paper.csv), one table per scene and ray configuration, as the paper's
# Figures 5-7: per cache size, the fraction of potentially visible geometry that
# fits, geometry and total MB per policy, and total relative to recursive.
# Further tables (the treelet policy's, from run.sh with POLICY=treelet) add
# their policy's column to every table.
#   usage: sh results/traffic/tables.sh ALL.csv PAPER.csv [MORE.csv...]
set -eu
all=$1 paper=$2
shift 2
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
  if (p == "treelet") tl = 1
}
END {
  for (i = 1; i <= n; i++) {
    key = order[i]; split(key, kk, "|")
    printf "### %s, %s rays (%s)\n\n", kk[1], kk[2], res[key]
    printf "Potentially visible (recursive): %d triangles (%.2f MB); paper: %s.\n\n", pvt[key "|recursive"], pvb[key "|recursive"] / 1048576, (key in pv) ? pv[key] : "n/a"
    if (tl) {
      print "| cache | frac pot-vis | geometry MB rec / pkt / dyn / tl | paper | total MB rec / pkt / dyn / tl | paper | rel total pkt / dyn / tl | paper |"
      print "|---|---|---|---|---|---|---|---|"
    } else {
      print "| cache | frac pot-vis | geometry MB rec / pkt / dyn | paper | total MB rec / pkt / dyn | paper | rel total pkt / dyn | paper |"
      print "|---|---|---|---|---|---|---|---|"
    }
    for (j = 1; j <= ns; j++) {
      cb = sz[j]; b = key "|" cb; pk = kk[1] "|" kk[2] "|" cb
      gt = tl ? sprintf(" / %.2f", g[b "|treelet"]) : ""
      tt = tl ? sprintf(" / %.2f", t[b "|treelet"]) : ""
      rtt = tl ? sprintf(" / %.2f", t[b "|treelet"] / t[b "|recursive"]) : ""
      printf "| %d K | %.3f | %.2f / %.2f / %.2f%s | %s | %.2f / %.2f / %.2f%s | %s | %.2f / %.2f%s | %s |\n", cb / 1024, f[b "|recursive"], \
        g[b "|recursive"], g[b "|packet"], g[b "|dynamic"], gt, (pk in pg) ? pg[pk] : "", \
        t[b "|recursive"], t[b "|packet"], t[b "|dynamic"], tt, (pk in pt) ? pt[pk] : "", \
        rt[b "|packet"], rt[b "|dynamic"], rtt, (pk in prt) ? prt[pk] : ""
    }
    print ""
  }
}' "$paper" "$all" "$@"
