#!/bin/sh
# How the traffic moves with the k-d tree: the same grid run on the tree with
# whole bounds (PBRT's, the paper's) and with clipped (perfect) splits. Per
# scene and ray configuration, at 16 KB and 512 KB: recursive's total DRAM
# traffic in MB, dynamic's and packet's total over recursive's, and dynamic's
# over packet's; every cell is whole -> clipped.
#   usage: sh results/traffic/compare_trees.sh WHOLE_ALL.csv CLIPPED_ALL.csv
set -eu
awk -F, '
FNR == 1 { f++; delete c; for (i = 1; i <= NF; i++) c[$i] = i; next }
{
  sc = $c["scene"]; r = $c["rays"]
  cfg = r == "primary" ? "primary" : r == "primary+shadow" ? "shadow" : r == "primary+shadow+specular" ? "specular" : r == "primary+shadow+diffuse" ? "diffuse" : r
  k = sc "|" cfg
  t[f "|" k "|" $c["cache_bytes"] "|" $c["policy"]] = $c["total_mb"]
  if (f == 1 && !(k in seen)) { seen[k] = 1; order[++n] = k }
}
function r2(a, b) { return b > 0 ? sprintf("%.2f", a / b) : "-" }
function cell(x, y) { return " " x " -> " y " |" }
END {
  print "| scene, rays | recursive MB 16K | recursive MB 512K | dyn/rec 16K | dyn/rec 512K | pkt/rec 16K | pkt/rec 512K | dyn/pkt 512K |"
  print "|---|---|---|---|---|---|---|---|"
  for (i = 1; i <= n; i++) {
    k = order[i]; split(k, kk, "|")
    line = "| " kk[1] ", " kk[2] " |"
    for (j = 1; j <= 2; j++) {
      s = j == 1 ? 16384 : 524288
      line = line cell(sprintf("%.1f", t[1 "|" k "|" s "|recursive"]), sprintf("%.1f", t[2 "|" k "|" s "|recursive"]))
    }
    split("dynamic packet", P, " ")
    for (m = 1; m <= 2; m++)
      for (j = 1; j <= 2; j++) {
        s = j == 1 ? 16384 : 524288
        line = line cell(r2(t[1 "|" k "|" s "|" P[m]], t[1 "|" k "|" s "|recursive"]), r2(t[2 "|" k "|" s "|" P[m]], t[2 "|" k "|" s "|recursive"]))
      }
    line = line cell(r2(t[1 "|" k "|524288|dynamic"], t[1 "|" k "|524288|packet"]), r2(t[2 "|" k "|524288|dynamic"], t[2 "|" k "|524288|packet"]))
    print line
  }
}' "$1" "$2"
