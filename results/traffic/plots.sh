#!/bin/sh
# The paper's Figures 5-7 as plots: for each scene, one panel per ray
# configuration; DRAM-to-L2 traffic of the packet and dynamic policies against
# cache size, relative to the recursive policy's total at the same size (as the
# paper's Figures 3-4), split into its geometry part (triangles, k-d nodes and
# leaf lists) and the rest (rays, queues, framebuffer). Lines: ours; open
# marks: the paper's (paper.csv). Writes fig-SCENE.png and fig-SCENE.svg.
#   usage: sh results/traffic/plots.sh ALL.csv PAPER.csv OUTDIR
set -eu
all=$1 paper=$2 out=$3
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
# One data file per scene and ray configuration, columns: cache_kb,
# ours (packet geometry, packet rest, dynamic geometry, dynamic rest),
# paper's (the same four; empty where the paper has no number).
awk -F, -v dir="$tmp" '
NR == FNR {
  if (FNR == 1) next
  k = $1 "|" $2 "|" $3
  pg[k] = $6 / $8; pr[k] = ($9 - $6) / $8; dg[k] = $7 / $8; dr[k] = ($10 - $7) / $8
  next
}
FNR == 1 { for (i = 1; i <= NF; i++) c[$i] = i; next }
{
  sc = $c["scene"]; sub(/-small$/, "", sc); r = $c["rays"]
  cfg = r == "primary" ? "primary" : r == "primary+shadow" ? "shadow" : r == "primary+shadow+specular" ? "specular" : r == "primary+shadow+diffuse" ? "diffuse" : r
  k = sc "|" cfg "|" $c["cache_bytes"]
  g[k "|" $c["policy"]] = $c["geometry_mb"]; t[k "|" $c["policy"]] = $c["total_mb"]
  if (!(k in seen)) { seen[k] = 1; keys[++n] = k }
}
function v(x) { return x == "" ? "?" : sprintf("%.4g", x) }
END {
  for (i = 1; i <= n; i++) {
    k = keys[i]; split(k, p, "|"); f = dir "/" p[1] "-" p[2] ".dat"
    rt = t[k "|recursive"]
    printf "%d %.6g %.6g %.6g %.6g %s %s %s %s\n", p[3] / 1024,
      g[k "|packet"] / rt, (t[k "|packet"] - g[k "|packet"]) / rt,
      g[k "|dynamic"] / rt, (t[k "|dynamic"] - g[k "|dynamic"]) / rt,
      (k in pg) ? v(pg[k]) : "?", (k in pr) ? v(pr[k]) : "?",
      (k in dg) ? v(dg[k]) : "?", (k in dr) ? v(dr[k]) : "?" > f
  }
}' "$paper" "$all"
mkdir -p "$out"
for scene in room grove sphereflake; do
  for term in png svg; do
    if [ $term = png ]; then setterm="set terminal pngcairo size 1400,900 noenhanced font ',10'"
    else setterm="set terminal svg size 1400,900 noenhanced font 'sans,10'"; fi
    {
      echo "$setterm"
      echo "set output '$out/fig-$scene.$term.tmp'"
      echo "set datafile missing '?'"
      echo "set multiplot layout 2,2 title 'DRAM-to-L2 traffic relative to the recursive policy: $scene (lines: ours; marks: the paper, Figures 5-7)'"
      echo "set logscale x 2; set logscale y; set grid"
      echo "set xlabel 'L2 size (KB)'; set ylabel 'traffic / recursive total traffic'"
      echo "set xrange [1:4096]; set yrange [0.001:20]; set key top right font ',8'"
      for cfg in primary shadow specular diffuse; do
        f="$tmp/$scene-$cfg.dat"
        echo "set title '$cfg rays'"
        if [ -s "$f" ]; then
          echo "plot '$f' u 1:2 w lp lc rgb '#1f77b4' pt 7 ps 0.6 lw 2 t 'packet geometry', \
'' u 1:3 w lp lc rgb '#1f77b4' dt 2 pt 7 ps 0.6 t 'packet rays+other', \
'' u 1:4 w lp lc rgb '#d62728' pt 7 ps 0.6 lw 2 t 'dynamic geometry', \
'' u 1:5 w lp lc rgb '#d62728' dt 2 pt 7 ps 0.6 t 'dynamic rays+other', \
'' u 1:6 w p lc rgb '#1f77b4' pt 6 ps 1.2 t 'paper: packet geometry', \
'' u 1:7 w p lc rgb '#1f77b4' pt 4 ps 1.2 t 'paper: packet rays+other', \
'' u 1:8 w p lc rgb '#d62728' pt 6 ps 1.2 t 'paper: dynamic geometry', \
'' u 1:9 w p lc rgb '#d62728' pt 4 ps 1.2 t 'paper: dynamic rays+other'"
        else
          echo "set label 1 'no data' at graph 0.5,0.5 center; plot 2 notitle; unset label 1"
        fi
      done
      echo "unset multiplot"
    } | gnuplot
    mv "$out/fig-$scene.$term.tmp" "$out/fig-$scene.$term"
  done
done
