#!/bin/sh
# The table of stretch.csv (README, "A sampled image through a functional
# model of the L2"): one block a point (scene, size, L2, fraction), one row a
# figure: the sampled runs' errors against the point's full run (lowest,
# highest, mean, mean absolute), the median interval half-width and how many
# intervals hold the full run's value; the runs' median CPU seconds and the
# speed-up over FULL_CPU (the full run's CPU seconds, given per scene and
# size as SCENE-SIZE-L2=SECONDS arguments; none: left out).
#   sh results/speed-accuracy/stretch-table.sh results/speed-accuracy/stretch.csv [P=S ...]
set -eu
CSV=$1
shift
awk -F, -v cpus="$*" '
BEGIN { n = split(cpus, a, " "); for (i = 1; i <= n; i++) { split(a[i], kv, "="); full_cpu[kv[1]] = kv[2] } }
function pct(x) { return sprintf("%+.1f%%", 100 * x) }
NR == 1 { for (i = 1; i <= NF; i++) col[$i] = i; next }
$5 == "full" { key = $1 "," $2 "," $3; full[key, "cycles"] = $col["cycles"]
  full[key, "dram_bytes"] = $col["dram_bytes"]; full[key, "issue_slots"] = $col["issue_slots"]
  full[key, "rays_traced"] = $col["rays_traced"]; next }
$5 == "sampled" {
  p = $1 "," $2 "," $3 "," $4
  if (!(p in seen)) { seen[p] = 1; order[++np] = p }
  r = ++runs[p]; cpu[p, r] = $col["cpu_s"] + 0
  key = $1 "," $2 "," $3
  for (k = 1; k <= 4; k++) {
    f = k == 1 ? "cycles" : k == 2 ? "dram_bytes" : k == 3 ? "issue_slots" : "rays_traced"
    v = full[key, f]; e = ($col[f] - v) / v
    err[p, f, r] = e; half[p, f, r] = ($col[f "_hi"] - $col[f "_lo"]) / 2 / v
    hold[p, f] += ($col[f "_lo"] <= v && v <= $col[f "_hi"])
  }
}
function median(arr, p, f, n,   i, j, t, x) {
  for (i = 1; i <= n; i++) x[i] = f == "" ? arr[p, i] : arr[p, f, i]
  for (i = 2; i <= n; i++) for (j = i; j > 1 && x[j - 1] > x[j]; j--) { t = x[j]; x[j] = x[j - 1]; x[j - 1] = t }
  return n % 2 ? x[(n + 1) / 2] : (x[n / 2] + x[n / 2 + 1]) / 2
}
END {
  print "| point | runs | CPU s (median) | speed-up | figure | error | mean | mean abs. | interval half-width (median) | intervals holding |"
  print "|---|---|---|---|---|---|---|---|---|---|"
  for (i = 1; i <= np; i++) {
    p = order[i]; n = runs[p]; split(p, q, ","); c = median(cpu, p, "", n)
    fc = full_cpu[q[1] "-" q[2] "-" q[3]]
    su = fc ? sprintf("%.0fx", fc / c) : "-"
    for (k = 1; k <= 4; k++) {
      f = k == 1 ? "cycles" : k == 2 ? "dram_bytes" : k == 3 ? "issue_slots" : "rays_traced"
      lo = 1e9; hi = -1e9; s = 0; sa = 0
      for (r = 1; r <= n; r++) { e = err[p, f, r]; if (e < lo) lo = e; if (e > hi) hi = e; s += e; sa += e < 0 ? -e : e }
      h = median(half, p, f, n)
      head = k == 1 ? sprintf("%s %s, %s L2, %s | %d | %.1f | %s", q[1], q[2], q[3], q[4], n, c, su) : " | | |"
      printf "| %s | %s | %s to %s | %s | %.1f%% | %.1f%% | %d of %d |\n", head, f, pct(lo), pct(hi), pct(s / n), 100 * sa / n, 100 * h, hold[p, f], n
    }
  }
}' "$CSV"
