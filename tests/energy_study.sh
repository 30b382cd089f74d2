#!/bin/sh
# results/energy's scripts against oracles: on a real 4-point sweep (the four
# policies, the small room at banked), derive.sh's four parts add to each run's
# energy_mj_per_frame and dram_share is dram_energy_j / energy_j, and
# summary.sh marks the policies with the fewest joules and the fewest bytes that
# an independent pass finds; on the same table with hand-set energies, the
# fewest-bytes policy's excess, its traffic factor to tie and a thread's
# break-even leakage are the hand-computed ones; a table without an energy
# column is refused with its name.
#   usage: sh tests/energy_study.sh SOURCE_DIR RTSIM SCRATCH
set -eu
src=$1 rtsim=$2 dir=$3
res=$src/results/energy
rm -rf "$dir"
mkdir -p "$dir"
fail() { echo "energy_study: $*" >&2; exit 1; }

cat > "$dir/sweep.yaml" <<EOF
machine: $src/configs/tiny.yaml
workload:
  scene: $src/scenes/small/room.yaml
  rays: primary,shadow
  width: 16
  height: 16
set:
  fidelity: banked
axes:
  policy: [recursive, packet, dynamic, treelet]
EOF
"$rtsim" sweep "$dir/sweep.yaml" -o "$dir/points" -j 1 2>/dev/null
"$rtsim" merge "$dir/points" -o "$dir/m.csv" 2>/dev/null

# The parts add up, and the share is the DRAM's.
sh "$res/derive.sh" "$dir/m.csv" | awk -F, '
NR == 1 { for (i = 1; i <= NF; i++) c[$i] = i; next }
function off(a, b) { return (a > b ? a - b : b - a) > 1e-6 * (b > 0 ? b : 1) }
{
  n++
  s = $c["chip_dynamic"] + $c["chip_leakage"] + $c["dram_traffic"] + $c["dram_background"]
  if (off(s, $c["energy_mj_per_frame"])) { print $c["policy"] ": parts " s " mJ, total " $c["energy_mj_per_frame"]; bad = 1 }
  if (off($c["dram_share"] * $c["energy_j"], $c["dram_energy_j"])) { print $c["policy"] ": dram_share " $c["dram_share"]; bad = 1 }
  if ($c["dram_traffic"] <= 0 || $c["dram_background"] <= 0 || $c["chip_dynamic"] <= 0) { print $c["policy"] ": a part is 0"; bad = 1 }
}
END { if (n != 4) { print n " rows, expected 4"; bad = 1 } exit bad }' || fail "derive.sh's parts"

# The marks are the argmins.
want=$(awk -f "$src/results/contention/scheduling/unquote.awk" "$dir/m.csv" | awk -F, '
NR == 1 { for (i = 1; i <= NF; i++) c[$i] = i; next }
{ e = $c["energy_mj_per_frame"] + 0; b = $c["dram_bytes"] + 0
  if (ce == "" || e < ce) { ce = e; pe = $c["policy"] }
  if (cb == "" || b < cb) { cb = b; pb = $c["policy"] } }
END { print pe " " pb }')
sh "$res/summary.sh" "$dir/m.csv" "$dir/m.csv" "$dir/m.csv" "$dir/s.csv" > "$dir/t.md"
got=$(awk -F' [|] ' '/^### Contention points: millijoules/ { on = 1 } /^### Contention points: does/ { on = 0 }
  on && /^[|] room/ { if ($5 ~ /^[*][*]/) e = $4; if ($4 ~ /^[*]/) b = $4 }
  END { gsub(/[*]/, "", e); gsub(/[*]/, "", b); print e " " b }' "$dir/t.md")
[ "$got" = "$want" ] || fail "summary.sh marks '$got' (fewest joules, fewest bytes), expected '$want'"
[ "$(wc -l < "$dir/s.csv")" -eq 13 ] || fail "summary.csv: $(wc -l < "$dir/s.csv") lines, expected 13"

# Hand-set energies (mJ) all in two DRAM parts: traffic T as activates, the
# rest as active standby. recursive E 50 T 2, 10 bytes; packet 40, 6, 30 bytes;
# dynamic 60, 1, 20 bytes; treelet 46, 4, 40 bytes. Fewest bytes: recursive;
# fewest joules: packet; recursive's excess 50 / 40 - 1 = 25%; to tie packet
# 1 + 10 / 4 = 3.5, treelet 1 + 4 / 2 = 3: 3.5. As threads (2 cores, R 2):
# recursive 1 thread 50 mJ in 0.02 s, packet standing for 2 threads, 40 mJ in
# 0.012 s: (50 - 40) mJ / (2 (2 x 0.012 - 0.02) s) = 1250 mW a thread.
awk -f "$src/results/contention/scheduling/unquote.awk" "$dir/m.csv" | awk -F, -v OFS=, '
NR == 1 { for (i = 1; i <= NF; i++) c[$i] = i; print; next }
{
  p = $c["policy"]
  E = p == "recursive" ? 50 : p == "packet" ? 40 : p == "dynamic" ? 60 : 46
  T = p == "recursive" ? 2 : p == "packet" ? 6 : p == "dynamic" ? 1 : 4
  $c["dram_bytes"] = p == "recursive" ? 10 : p == "packet" ? 30 : p == "dynamic" ? 20 : 40
  split("l1_dynamic l2_dynamic cores_dynamic l1_leakage l2_leakage cores_leakage", k, " ")
  for (i = 1; i <= 6; i++) $c["chip_energy_" k[i] "_j"] = 0
  split("read write refresh precharge_standby", k, " ")
  for (i = 1; i <= 4; i++) $c["dram_energy_" k[i] "_j"] = 0
  $c["dram_energy_activate_j"] = T / 1e3; $c["dram_energy_active_standby_j"] = (E - T) / 1e3
  $c["dram_energy_j"] = $c["energy_j"] = E / 1e3; $c["energy_mj_per_frame"] = E
  $c["clock_ghz"] = 1.4; $c["cores"] = 2; $c["rays_per_thread"] = 2
  $c["threads_per_core"] = p == "packet" ? 2 : 1
  $c["seconds"] = p == "packet" ? 0.012 : 0.02
  print
}' > "$dir/hand.csv"
# The threads' table: recursive's row as one thread, packet's as two.
awk -F, -v OFS=, 'NR == 1 { for (i = 1; i <= NF; i++) c[$i] = i; print; next }
$c["policy"] == "packet" { $c["policy"] = "recursive" } $c["policy"] == "recursive"' \
  "$dir/hand.csv" > "$dir/threads.csv"
sh "$res/summary.sh" "$dir/hand.csv" "$dir/hand.csv" "$dir/threads.csv" "$dir/s2.csv" > "$dir/t2.md" 2>/dev/null || true
grep -q '^| room-small | 32 KiB | 2 | recursive (0.0, 50.0) | .* (0.0, 40.0) | +25% | 3.5 |$' "$dir/t2.md" ||
  fail "the hand-set point: expected recursive +25% over the least and 3.5 to tie; got: $(grep '^| room-small | 32 KiB | 2 | recursive (' "$dir/t2.md" | head -n 1)"
grep -q '^| recursive | 1.4 | 2 | .* | 1250.00 |$' "$dir/t2.md" ||
  fail "the hand-set threads: expected 1250.00 mW a thread; got: $(grep '^| recursive | 1.4 | 2 |' "$dir/t2.md")"

# A table without an energy column: refused, naming it.
awk -F, -v OFS=, 'NR == 1 { for (i = 1; i <= NF; i++) if ($i == "dram_energy_refresh_j") $i = "x" } { print }' \
  "$dir/m.csv" > "$dir/bad.csv"
if sh "$res/derive.sh" "$dir/bad.csv" > /dev/null 2> "$dir/err"; then fail "derive.sh took a table without dram_energy_refresh_j"; fi
grep -q 'no column dram_energy_refresh_j' "$dir/err" || fail "derive.sh's message: $(cat "$dir/err")"
echo "energy_study: ok"
