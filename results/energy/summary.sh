#!/bin/sh
# The energy study's tables (README.md) from its three merged sweeps: on the
# contention and scheduling points, each policy's millijoules a frame and their
# parts, and at each point the policy that moves the fewest DRAM bytes against
# the one that spends the fewest joules; on the latency-hiding points,
# millijoules a frame by rays a thread, and what each doubling of the threads
# saves, with the leakage a thread could add before the doubling stops paying.
# Markdown on stdout; one row a point of the three sweeps in SUMMARY.csv.
#   usage: sh results/energy/summary.sh CONTENTION.csv SCHEDULING.csv LATENCY-HIDING.csv SUMMARY.csv
set -eu
here=$(dirname "$0")
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
sh "$here/derive.sh" "$1" > "$tmp/contention.csv"
sh "$here/derive.sh" "$2" > "$tmp/scheduling.csv"
sh "$here/derive.sh" "$3" > "$tmp/latency-hiding.csv"

# One row a point, both sweeps: the figures the tables print, unrounded.
awk -F, -v OFS=, '
FNR == 1 {
  delete c; for (i = 1; i <= NF; i++) c[$i] = i
  study = FILENAME; sub(/.*\//, "", study); sub(/\.csv$/, "", study)
  if (NR == 1) print "study", "scene", "policy", "l2.size", "cores", "clock_ghz", "threads_per_core",
    "rays_per_thread", "energy_mj_per_frame", "chip_dynamic_mj", "chip_leakage_mj", "dram_traffic_mj",
    "dram_background_mj", "dram_share", "rays_per_joule", "power_w", "dram_bytes", "cycles",
    "seconds", "core_utilization"
  next
}
{
  print study, $c["scene"], $c["policy"], $c["l2.size"], $c["cores"], $c["clock_ghz"],
    $c["threads_per_core"], $c["rays_per_thread"], $c["energy_mj_per_frame"], $c["chip_dynamic"],
    $c["chip_leakage"], $c["dram_traffic"], $c["dram_background"], $c["dram_share"],
    $c["rays_per_joule"], $c["power_w"], $c["dram_bytes"], $c["cycles"], $c["seconds"],
    $c["core_utilization"]
}' "$tmp/contention.csv" "$tmp/scheduling.csv" "$tmp/latency-hiding.csv" > "$4"

# A sweep over scenes, L2 sizes and cores: a row a point and policy, then the
# point's fewest bytes against its fewest joules.
#   usage: by_point TABLE.csv TITLE WHAT
by_point() {
awk -F, -v title="$2" -v what="$3" '
NR == 1 { for (i = 1; i <= NF; i++) c[$i] = i; next }
function prank(x) { return x == "recursive" ? 1 : x == "packet" ? 2 : x == "dynamic" ? 3 : 4 }
function srank(x) { return x == "sphereflake" ? 1 : x == "grove" ? 2 : 3 }
function size(b) { return b >= 1048576 ? b / 1048576 " MiB" : b / 1024 " KiB" }
{
  pt = $c["scene"] "|" $c["l2.size"] "|" $c["cores"]; k = pt "|" $c["policy"]
  if (!(pt in seen)) { seen[pt] = 1; pts[++np] = pt; prk[pt] = srank($c["scene"]) * 1e9 + $c["l2.size"] / 1048576 * 1e3 + $c["cores"] }
  pol[pt, prank($c["policy"])] = $c["policy"]
  e[k] = $c["energy_mj_per_frame"]; b[k] = $c["dram_bytes"]; tr[k] = $c["dram_traffic"]
  row[k] = sprintf("%.1f | %.1f / %.1f | %.1f / %.1f | %.2f | %.2f | %.1f | %.2f", e[k],
    $c["chip_dynamic"], $c["chip_leakage"], $c["dram_traffic"], $c["dram_background"],
    $c["dram_share"], $c["rays_per_joule"] / 1e6, b[k] / 1048576, $c["cycles"] / 1e6)
}
# The factor on every policy'"'"'s DRAM traffic energy (activates and bursts)
# that would make the point'"'"'s fewest-bytes policy f the cheapest: against each
# cheaper policy p, 1 + (E_f - E_p) / (T_p - T_f); "never" when a cheaper
# policy'"'"'s traffic energy is no higher than f'"'"'s.
function tie(pt, f,   r, k, m, x) {
  m = 1
  for (r = 1; r <= 4; r++) { k = pt "|" pol[pt, r]
    if (k == f || e[k] >= e[f]) continue
    if (tr[k] <= tr[f]) return "never"
    x = 1 + (e[f] - e[k]) / (tr[k] - tr[f]); if (x > m) m = x }
  return sprintf("%.1f", m)
}
END {
  for (i = 2; i <= np; i++)
    for (j = i; j > 1 && prk[pts[j]] < prk[pts[j - 1]]; j--) { t = pts[j]; pts[j] = pts[j - 1]; pts[j - 1] = t }
  print "### " title ": millijoules a frame by policy"
  print ""
  print what
  print "**Bold**: the fewest millijoules at the point; *italic* policy: the fewest DRAM bytes."
  print ""
  print "| scene | L2 | cores | policy | mJ/frame | chip dynamic / leakage (mJ) | DRAM traffic / background (mJ) | DRAM share | M rays/J | DRAM MiB | Mcycles |"
  print "|---|---|---|---|---|---|---|---|---|---|---|"
  for (i = 1; i <= np; i++) {
    pt = pts[i]; split(pt, q, "|"); be = bb = ""
    for (r = 1; r <= 4; r++) { k = pt "|" pol[pt, r]
      if (be == "" || e[k] < e[be]) be = k
      if (bb == "" || b[k] < b[bb]) bb = k }
    win[pt] = be; few[pt] = bb
    for (r = 1; r <= 4; r++) {
      k = pt "|" pol[pt, r]; split(row[k], f, " \\| ")
      p = (k == bb) ? "*" pol[pt, r] "*" : pol[pt, r]
      m = (k == be) ? "**" f[1] "**" : f[1]
      printf "| %s | %s | %s | %s | %s | %s | %s | %s | %s | %s | %s |\n", q[1], size(q[2]), q[3], p, m, f[2], f[3], f[4], f[5], f[6], f[7]
    }
  }
  print ""
  print "### " title ": does the policy with the fewest DRAM bytes spend the fewest joules?"
  print ""
  print "*DRAM traffic x to tie*: the factor on the DRAM'"'"'s traffic energy (activates and bursts) that"
  print "would make the fewest-bytes policy the cheapest."
  print ""
  print "| scene | L2 | cores | fewest bytes (MiB, mJ) | fewest joules (MiB, mJ) | the first'"'"'s energy over the least | DRAM traffic x to tie |"
  print "|---|---|---|---|---|---|---|"
  for (i = 1; i <= np; i++) {
    pt = pts[i]; split(pt, q, "|"); bb = few[pt]; be = win[pt]; split(bb, x, "|"); split(be, y, "|")
    same += (bb == be)
    printf "| %s | %s | %s | %s (%.1f, %.1f) | %s (%.1f, %.1f) | %s | %s |\n", q[1], size(q[2]), q[3],
      x[4], b[bb] / 1048576, e[bb], y[4], b[be] / 1048576, e[be],
      bb == be ? "same policy" : sprintf("+%.0f%%", (e[bb] / e[be] - 1) * 100), bb == be ? "-" : tie(pt, bb)
  }
  printf "\nThe same policy at %d of %d points.\n\n", same, np
}' "$1"
}
by_point "$tmp/contention.csv" "Contention points" \
  "The default machine (banked DDR4-2400), 256x256, primary and shadow rays."
by_point "$tmp/scheduling.csv" "Scheduling points" \
  "The default machine (banked DDR4-2400), grove 128x128, primary, shadow and diffuse rays."

# The latency-hiding points: millijoules a frame by rays a thread, then what
# doubling the threads saves at two rays a thread (the paper's figure) and at
# the policy and clock's cheapest rays a thread.
awk -F, '
NR == 1 { for (i = 1; i <= NF; i++) c[$i] = i; next }
{
  g = $c["policy"] "|" $c["clock_ghz"]; k = g "|" $c["threads_per_core"] "|" $c["rays_per_thread"]
  if (!(g in gs)) { gs[g] = 1; grp[++ng] = g }
  e[k] = $c["energy_mj_per_frame"]; s[k] = $c["seconds"]; cy[k] = $c["cycles"]; u[k] = $c["core_utilization"]
  cd[k] = $c["chip_dynamic"]; cl[k] = $c["chip_leakage"]; dt[k] = $c["dram_traffic"]; db[k] = $c["dram_background"]
  sh[k] = $c["dram_share"]; cores = $c["cores"]
  rd[$c["clock_ghz"]] += $c["dram_read_latency_mean"]; rn[$c["clock_ghz"]]++
}
# The leakage in mW a hardware thread may add before 2T threads a core spend
# more than T: (E_T - E_2T) / (cores (2T s_2T - T s_T)).
function breakeven(a, b, t,   d) {
  d = cores * (2 * t * s[b] - t * s[a])
  if (e[a] <= e[b]) return "none"
  if (d <= 0) return "any"
  return sprintf("%.2f", (e[a] - e[b]) * 1e-3 / d * 1e3)
}
function prank(x) { return x == "recursive" ? 1 : x == "packet" ? 2 : x == "dynamic" ? 3 : 4 }
END {
  # The policies in the paper'"'"'s order, then treelet; clocks ascending.
  for (i = 1; i <= ng; i++) { split(grp[i], q, "|"); gr[grp[i]] = prank(q[1]) * 1e3 + q[2] }
  for (i = 2; i <= ng; i++)
    for (j = i; j > 1 && gr[grp[j]] < gr[grp[j - 1]]; j--) { t = grp[j]; grp[j] = grp[j - 1]; grp[j - 1] = t }
  split("1 2 3 4 6 8", R, " "); split("1 2 4 8", T, " ")
  print "### Latency-hiding points: millijoules a frame by rays a thread"
  print ""
  print "The 2-core machine of configs/latency-hiding.yaml on banked DDR4-2400, grove 128x128,"
  print "primary and shadow rays; the clock and, in brackets, the mean DRAM read in core cycles."
  print ""
  print "| policy | clock GHz (DRAM read, cycles) | threads/core | R=1 | R=2 | R=3 | R=4 | R=6 | R=8 | cheapest R |"
  print "|---|---|---|---|---|---|---|---|---|---|"
  for (i = 1; i <= ng; i++) {
    g = grp[i]; split(g, q, "|")
    for (t = 1; t <= 4; t++) {
      line = sprintf("| %s | %s (%.0f) | %s", q[1], q[2], rd[q[2]] / rn[q[2]], T[t]); best = ""
      for (r = 1; r <= 6; r++) { k = g "|" T[t] "|" R[r]; line = line sprintf(" | %.2f", e[k])
        if (best == "" || e[k] < e[g "|" T[t] "|" best]) best = R[r] }
      print line " | " best " |"
    }
  }
  print ""
  print "### What the threads cost: R = 2 rays a thread"
  print ""
  print "Chip leakage is each core'"'"'s 10 mW and each KiB of SRAM'"'"'s 0.1 mW, whatever the threads;"
  print "*break-even*: the leakage (mW) a hardware thread could add, every thread alike, before"
  print "this row'"'"'s thread count spends more than the row above'"'"'s (\"none\": it already does)."
  print ""
  print "| policy | clock GHz | threads/core | Mcycles | core util. | mJ/frame | chip dynamic / leakage (mJ) | DRAM traffic / background (mJ) | DRAM share | break-even mW a thread |"
  print "|---|---|---|---|---|---|---|---|---|---|"
  for (i = 1; i <= ng; i++) {
    g = grp[i]; split(g, q, "|")
    for (t = 1; t <= 4; t++) {
      k = g "|" T[t] "|2"
      be = t == 1 ? "-" : breakeven(g "|" T[t - 1] "|2", k, T[t - 1])
      printf "| %s | %s | %s | %.2f | %.2f | %.2f | %.2f / %.2f | %.2f / %.2f | %.2f | %s |\n", q[1], q[2], T[t],
        cy[k] / 1e6, u[k], e[k], cd[k], cl[k], dt[k], db[k], sh[k], be
    }
  }
}' "$tmp/latency-hiding.csv"
