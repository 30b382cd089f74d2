#!/bin/sh
# results/dram: how far the cheaper rungs' DRAM energy estimate (fixed, channel
# and analytic report dram_energy_j estimated from their reads, writes and
# time, a row-hit rate of 0.5 assumed: sim/dram_energy_estimate.h) is from the
# banked level's counted dram_energy_j, on the points of dram-levels.yaml
# (three scenes, three policies, 96x96). Writes energy-rungs.csv: one row a
# run at a cheaper rung, its cycles and energy against the banked run of the
# same scene and policy. From the repository top, after sh .ci/setup (about
# 3 min of CPU, one run at a time):
#   sh results/dram/energy-estimate.sh
set -eu
out=build/dram-energy-estimate
# A fresh directory: a sweep resumes, and points from an older build would stay.
rm -rf "$out"
mkdir -p "$out"
build/rtsim sweep configs/sweeps/dram-energy-estimate.yaml -o "$out/runs" -j 1
build/rtsim merge "$out/runs" -o "$out/merged.csv"
# (A quoted field's commas, as in the first column's point name, become ';'.)
awk '{ o = ""; q = 0
       for (i = 1; i <= length($0); i++) { ch = substr($0, i, 1); if (ch == "\"") q = !q; else if (ch == "," && q) ch = ";"; o = o ch }
       print o }' "$out/merged.csv" |
awk -F, '
  NR == 1 { for (i = 1; i <= NF; i++) c[$i] = i; next }
  { n++; for (k in c) v[n, k] = $c[k] }
  function f(r, k) { return v[r, k] + 0 }
  END {
    print "scene,policy,rung,cycles,banked_cycles,cycles_error,dram_reads,dram_writes,banked_row_hit_rate,dram_energy_j,banked_dram_energy_j,energy_error"
    for (r = 1; r <= n; r++)
      if (v[r, "fidelity"] == "banked") bk[v[r, "scene"], v[r, "policy"]] = r
    split("fixed channel analytic", rungs, " ")
    for (g = 1; g <= 3; g++)
      for (r = 1; r <= n; r++) {
        if (v[r, "fidelity"] != rungs[g]) continue
        if (f(r, "dram_energy_estimated") != 1) { print "energy-estimate.sh: no estimate in a " rungs[g] " run" > "/dev/stderr"; exit 1 }
        b = bk[v[r, "scene"], v[r, "policy"]]
        printf "%s,%s,%s,%d,%d,%.4f,%d,%d,%.4f,%.6g,%.6g,%.4f\n", v[r, "scene"], v[r, "policy"], rungs[g],
          f(r, "cycles"), f(b, "cycles"), (f(r, "cycles") - f(b, "cycles")) / f(b, "cycles"),
          f(r, "dram_reads"), f(r, "dram_writes"), f(b, "dram_row_hit_rate"), f(r, "dram_energy_j"),
          f(b, "dram_energy_j"), (f(r, "dram_energy_j") - f(b, "dram_energy_j")) / f(b, "dram_energy_j")
      }
  }' > results/dram/energy-rungs.csv.tmp
mv results/dram/energy-rungs.csv.tmp results/dram/energy-rungs.csv
