#!/bin/sh
# The speed-accuracy tables (markdown on stdout) and the plot's data (PLOT):
# every rung and every sampled point against the banked rung's full run of
# the same scene, policy and size. Speed-up: the banked full run's wall_s over
# the point's. Errors: (point - banked) / banked, in percent.
#   usage: sh results/speed-accuracy/summary.sh POINTS.csv COVERAGE.csv PLOT.dat
set -eu
awk -F, -v cov="$2" -v plot="$3" '
function err(a, b) { return (a == "" || b == "" || b + 0 == 0) ? "" : 100 * (a - b) / b }
function pct(x) { return x == "" ? "-" : sprintf("%+.1f%%", x) }
function key(t, i) { return t[i, c["scene"]] "|" t[i, c["policy"]] "|" t[i, c["width"]] }
function isfull(t, i) { return t[i, c["sample_fraction"]] == "" || t[i, c["sample_fraction"]] + 0 >= 1 }
FNR == 1 { for (i = 1; i <= NF; i++) c[$i] = i; next }
FILENAME != cov {
  n++; for (i = 1; i <= NF; i++) P[n, i] = $i
  if ($c["fidelity"] == "banked" && isfull(P, n)) ref[key(P, n)] = n
  next
}
{ m++; for (i = 1; i <= NF; i++) C[m, i] = $i }
END {
  nq = split("cycles dram_bytes core_utilization load_latency_mean", Q, " ")
  split("sphereflake grove room", S, " "); split("recursive packet dynamic", PO, " ")
  split("banked channel fixed analytic", R, " ")
  printf "" > plot
  print "### The ladder (128x128, every rung against banked)\n"
  print "| scene | policy | rung | speed-up | cycles | DRAM bytes | core utilization | load latency |"
  print "|---|---|---|---|---|---|---|---|"
  for (s = 1; s <= 3; s++) for (p = 1; p <= 3; p++) for (r = 1; r <= 4; r++) for (i = 1; i <= n; i++) {
    if (P[i, c["scene"]] != S[s] || P[i, c["policy"]] != PO[p] || P[i, c["fidelity"]] != R[r] || !isfull(P, i)) continue
    if (!(key(P, i) in ref) || P[i, c["width"]] != 128) continue
    b = ref[key(P, i)]
    if (i == b) {
      printf "| %s | %s | **banked** | 1 (%.1f s) | %.2f M | %.1f MB | %.3f | %.1f cycles |\n", S[s], PO[p], P[b, c["wall_s"]], P[b, c["cycles"]] / 1e6, P[b, c["dram_bytes"]] / 1e6, P[b, c["core_utilization"]], P[b, c["load_latency_mean"]]
      continue
    }
    sp = P[b, c["wall_s"]] / P[i, c["wall_s"]]
    line = sprintf("| %s | %s | %s | %.1fx", S[s], PO[p], R[r], sp)
    for (j = 1; j <= nq; j++) line = line " | " pct(err(P[i, c[Q[j]]], P[b, c[Q[j]]]))
    print line " |"
    printf "%s %s-%s %.4g %s %s\n", R[r], S[s], PO[p], sp, err(P[i, c["cycles"]], P[b, c["cycles"]]), err(P[i, c["dram_bytes"]], P[b, c["dram_bytes"]]) >> plot
  }
  print "\n### Sampling (recursive, 256x256, banked, seed 1)\n"
  print "| scene | sample.fraction | detailed | units | speed-up | cycles [95% interval] | DRAM bytes [interval] | core utilization [interval] | load latency [interval] |"
  print "|---|---|---|---|---|---|---|---|---|"
  for (s = 1; s <= 3; s++) for (i = 1; i <= n; i++) {
    if (P[i, c["scene"]] != S[s] || isfull(P, i) || !(key(P, i) in ref)) continue
    b = ref[key(P, i)]
    sp = P[b, c["wall_s"]] / P[i, c["wall_s"]]
    line = sprintf("| %s | %s | %.3f | %d | %.1fx", S[s], P[i, c["sample_fraction"]], P[i, c["sample_detailed_fraction"]], P[i, c["sample_units"]], sp)
    for (j = 1; j <= nq; j++) {
      x = P[b, c[Q[j]]]
      line = line sprintf(" | %s [%s, %s]", pct(err(P[i, c[Q[j]]], x)), pct(err(P[i, c[Q[j] "_lo"]], x)), pct(err(P[i, c[Q[j] "_hi"]], x)))
    }
    print line " |"
    printf "sample-%s %s-recursive %.4g %s %s\n", P[i, c["sample_fraction"]], S[s], sp, err(P[i, c["cycles"]], P[b, c["cycles"]]), err(P[i, c["dram_bytes"]], P[b, c["dram_bytes"]]) >> plot
  }
  print "\n### Coverage of the 95% intervals (recursive, 256x256, banked, 20 seeds)\n"
  print "| scene | sample.fraction | runs | cycles inside | DRAM bytes inside | core utilization inside | load latency inside | cycles error: mean, largest |"
  print "|---|---|---|---|---|---|---|---|"
  nf = split("0.1 0.05", F, " ")
  for (s = 1; s <= 3; s++) for (f = 1; f <= nf; f++) {
    runs = 0; for (j = 1; j <= nq; j++) in_[j] = 0; se = 0; mx = 0
    for (i = 1; i <= m; i++) {
      if (C[i, c["scene"]] != S[s] || C[i, c["sample_fraction"]] != F[f] || !(key(C, i) in ref)) continue
      b = ref[key(C, i)]; runs++
      for (j = 1; j <= nq; j++) {
        x = P[b, c[Q[j]]]
        if (C[i, c[Q[j] "_lo"]] + 0 <= x + 0 && x + 0 <= C[i, c[Q[j] "_hi"]] + 0) in_[j]++
      }
      e = err(C[i, c["cycles"]], P[b, c["cycles"]]); if (e < 0) e = -e; se += e; if (e > mx) mx = e
    }
    if (!runs) continue
    line = sprintf("| %s | %s | %d", S[s], F[f], runs)
    for (j = 1; j <= nq; j++) { line = line sprintf(" | %d%%", 100 * in_[j] / runs); tot[j] += in_[j] }
    print line sprintf(" | %.2f%%, %.2f%% |", se / runs, mx)
    totruns += runs
  }
  if (totruns) {
    line = sprintf("| all | | %d", totruns)
    for (j = 1; j <= nq; j++) line = line sprintf(" | %.0f%%", 100 * tot[j] / totruns)
    print line " | |"
  }
}' "$1" "$2"
