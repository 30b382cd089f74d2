#!/bin/sh
# The paper's Figures 5-7 as plots, drawn by `rtsim plot`: for each scene, one
# panel per ray configuration (and its image size); DRAM-to-L2 traffic of the
# packet and dynamic policies against L2 size, relative to the recursive
# policy's total at the same size (as the paper's Figures 3-4), split into its
# geometry part (triangles, k-d nodes and leaf lists) and the rest (rays,
# queues, framebuffer). Ours from ALL.csv, the paper's from PAPER.csv (left
# out where the paper has no number). Writes fig-SCENE.png and fig-SCENE.svg.
#
# A colour a series (policy and part), solid for ours and dashed for the
# paper's (--dash source), so each pair reads as one colour; the title says
# what "relative to recursive" means.
#   usage: sh results/traffic/plots.sh ALL.csv PAPER.csv OUTDIR
set -eu
all=$1 paper=$2 out=$3
rtsim=${RTSIM:-build/rtsim}
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
# One tidy table: scene, rays (with the image size), l2.size in bytes, the
# data (ours or the paper's: policy and part) and its traffic over recursive's.
awk -F, '
BEGIN { print "scene,rays,l2.size,source,series,traffic relative to recursive total" }
NR == FNR {
  if (FNR == 1) next
  k = $1 "|" $2 "|" $3
  pk[k] = 1; pg[k] = $6 / $8; pr[k] = ($9 - $6) / $8; dg[k] = $7 / $8; dr[k] = ($10 - $7) / $8
  next
}
FNR == 1 { for (i = 1; i <= NF; i++) c[$i] = i; next }
{
  sc = $c["scene"]; sub(/-small$/, "", sc); r = $c["rays"]
  cfg = r == "primary" ? "primary" : r == "primary+shadow" ? "shadow" : r == "primary+shadow+specular" ? "specular" : r == "primary+shadow+diffuse" ? "diffuse" : r
  k = sc "|" cfg "|" $c["cache_bytes"]
  g[k "|" $c["policy"]] = $c["geometry_mb"]; t[k "|" $c["policy"]] = $c["total_mb"]
  label[k] = r " at " $c["width"] "x" $c["height"]
  if (!(k in seen)) { seen[k] = 1; keys[++n] = k }
}
function row(k, src, s, v) { split(k, p, "|"); printf "%s,%s,%d,%s,%s,%.6g\n", p[1], label[k], p[3], src, s, v }
END {
  for (i = 1; i <= n; i++) {
    k = keys[i]; rt = t[k "|recursive"]
    row(k, "ours", "packet geometry", g[k "|packet"] / rt)
    row(k, "ours", "packet rays+other", (t[k "|packet"] - g[k "|packet"]) / rt)
    row(k, "ours", "dynamic geometry", g[k "|dynamic"] / rt)
    row(k, "ours", "dynamic rays+other", (t[k "|dynamic"] - g[k "|dynamic"]) / rt)
    if (!(k in pk)) continue
    row(k, "paper", "packet geometry", pg[k]); row(k, "paper", "packet rays+other", pr[k])
    row(k, "paper", "dynamic geometry", dg[k]); row(k, "paper", "dynamic rays+other", dr[k])
  }
}' "$paper" "$all" > "$tmp/tidy.csv"
mkdir -p "$out"
for scene in room grove sphereflake; do
  for ext in png svg; do
    "$rtsim" plot "$tmp/tidy.csv" --x l2.size --y "traffic relative to recursive total" \
      --lines series --dash source --order ours,paper --panels rays --where scene=$scene --logx \
      --logy --title "DRAM-to-L2 traffic of packet and dynamic over recursive's total: $scene" \
      --ylabel "traffic / recursive's total" -o "$out/fig-$scene.$ext"
  done
done
