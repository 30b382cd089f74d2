#!/bin/sh
# results/dram: the DRAM's levels of detail on rtsim's own traffic.
#  1. levels.csv: fixed, channel and banked on the default machine, every scene
#     and policy (configs/sweeps/dram-levels.yaml).
#  2. dramsim3.csv: the banked DDR4-2400 level against DRAMsim3 on the same
#     request streams (each run's --dram-trace cut to DRAMsim3's trace format,
#     address, op and arrival in DRAM cycles, replayed open loop by both as
#     DRAMsim3's trace reader does: each request offered from its DRAM cycle on,
#     at most one a cycle, in trace order; rtsim at clock_ghz 1.2, so its core
#     and DRAM cycles are one).
#     DRAMsim3's side needs a DRAMsim3 build with results/dram/dramsim3_replay.cc
#     (README here): DRAMSIM3=its binary DRAMSIM3_INI=its DDR4_8Gb_x8_2400.ini.
#     Without them only rtsim's columns are filled.
#  3. saturated.csv: three streams offered faster than a channel serves.
#  4. energy.csv: the DRAM's energy of the replays of 2 and 3 by component,
#     rtsim's and DRAMsim3's, in joules.
#  rtsim replays each stream of 2 and 3 twice: with the presets' idle write
#  drain (dram.idle_drain_cycles 1000) and without it (0, as DRAMsim3); each
#  table has a row for each (column idle_drain_cycles), DRAMsim3's columns the
#  same on both.
#  5. energy-estimate.csv: a DRAM energy estimate from a cheaper rung's counts
#     against the banked level's (from levels.csv).
# From the repository top, after sh .ci/setup:
#   [DRAMSIM3=... DRAMSIM3_INI=...] sh results/dram/run.sh
set -eu
# Check the DDR4 preset's table of sources (configs/dram/README.md, its rows
# whose source is an ini key) against the DRAMsim3 ini this run replays with.
if [ -n "${DRAMSIM3_INI:-}" ]; then
  awk -F'|' '
    FNR == NR {
      if ($0 ~ /^[ \t]*[A-Za-z_0-9]+[ \t]*=/) {
        k = $0; sub(/[ \t]*=.*/, "", k); gsub(/[ \t]/, "", k)
        v = $0; sub(/^[^=]*=[ \t]*/, "", v); sub(/[ \t;].*$/, "", v); ini[k] = v
      }
      next
    }
    /^<!-- preset: / { on = ($0 ~ /preset: ddr4-2400\.yaml /); next }
    on && /^\|/ && $4 ~ /ini `/ {
      k = $4; sub(/.*ini `/, "", k); sub(/`.*/, "", k)
      v = $5; gsub(/[ `]/, "", v); n++
      if (!(k in ini) || ini[k] != v) { printf "configs/dram/README.md: ini %s is %s in the table, %s in %s\n", k, v, (k in ini) ? ini[k] : "absent", ARGV[1]; bad++ }
    }
    END { if (bad || !n) { if (!n) print "configs/dram/README.md: no ini rows for ddr4-2400.yaml"; exit 1 } }
  ' "$DRAMSIM3_INI" configs/dram/README.md
fi
out=build/dram
# A fresh directory: a sweep resumes, and points from an older build would stay.
rm -rf "$out"
mkdir -p "$out"
build/rtsim sweep configs/sweeps/dram-levels.yaml -o "$out/levels"
build/rtsim merge "$out/levels" -o results/dram/levels.csv

csvget() { awk -F, -v k="$2" 'NR == 1 { for (i = 1; i <= NF; i++) if ($i == k) c = i } NR == 2 { print $c }' "$1"; }
kvget() { awk -F= -v k="$2" '$1 == k { print $2 }' "$1"; }
# Read latencies of a replay from its three-column trace ($1) and per-request
# file ($2, '#' header then one line a request in trace order): mean, p50, p95,
# p99 of done - arrival, exact (the ceil(p/100 n)-th smallest, as the DRAMsim3
# driver ranks them; rtsim's CSV gives quantiles as histogram bucket bounds).
readlat() {
  tail -n +2 "$2" | paste -d' ' "$1" - | awk '$2 == "READ" { print $7 - $5 }' | sort -n |
    awk 'function at(p,  r, c) { r = p / 100.0 * NR; c = int(r); if (c < r) c++; if (c < 1) c = 1; return v[c] }
         { v[NR] = $1; s += $1 } END { printf "%.3f %d %d %d\n", s / NR, at(50), at(95), at(99) }'
}

# 4. energy.csv (filled as 2 and 3 run): the DRAM's energy of each replay by
#    component, rtsim's (its dram_energy_*_j) and DRAMsim3's (its
#    simple_stats sums, in V x mA x DRAM cycles though it names them pJ,
#    times tCK = 1 / 1.2 GHz, in joules; the ini's tCK 0.83 is that rounded).
energy=results/dram/energy.csv
ecomp="activate read write refresh active_standby precharge_standby total"
{
  printf 'stream,idle_drain_cycles,requests,writes'
  for c in $ecomp; do printf ',rtsim_%s_j,dramsim3_%s_j' "$c" "$c"; done
  printf '\n'
} > "$energy.tmp"
# A replay's energy row: stream name, rtsim's CSV, DRAMsim3's output (may be
# missing or unfinished: its columns empty), rtsim's dram.idle_drain_cycles.
energy_row() {
  printf '%s,%s,%s,%s' "$1" "$4" "$(csvget "$2" requests)" "$(csvget "$2" writes)"
  fin=; [ -f "$3" ] && fin=$(kvget "$3" finished)
  for c in $ecomp; do
    case $c in
      activate) k=act_energy ;; read) k=read_energy ;; write) k=write_energy ;;
      refresh) k=ref_energy ;; active_standby) k=act_stb_energy ;;
      precharge_standby) k=pre_stb_energy ;; total) k=total_energy ;;
    esac
    rk=dram_energy_${c}_j; [ "$c" = total ] && rk=dram_energy_j
    d3=
    [ "$fin" = 1 ] && d3=$(awk -v v="$(kvget "$3" "dramsim3.$k")" 'BEGIN { printf "%.9g", v / 1.2 * 1e-12 }')
    printf ',%s,%s' "$(csvget "$2" "$rk")" "$d3"
  done
  printf '\n'
}

table=results/dram/dramsim3.csv
echo "scene,policy,idle_drain_cycles,requests,writes,rtsim_read_latency_mean,dramsim3_read_latency_mean,rtsim_read_latency_p50,dramsim3_read_latency_p50,rtsim_read_latency_p95,dramsim3_read_latency_p95,rtsim_read_latency_p99,dramsim3_read_latency_p99,rtsim_gb_per_s,dramsim3_gb_per_s,rtsim_row_hit_rate,dramsim3_row_hit_rate" > "$table.tmp"
for scene in sphereflake grove room; do
  for policy in recursive dynamic; do
    t="$out/$scene-$policy"
    build/rtsim run configs/default.yaml "scenes/$scene.yaml" --width 96 --height 96 \
      --rays primary,shadow,diffuse --policy "$policy" --dram-trace "$t.trace" -o "$t" > /dev/null
    # Both replay the same three-column trace (DRAMsim3's format).
    awk '!/^#/ && NF { print $1, $2, $3 }' "$t.trace" > "$t.dramsim3.trace"
    d3_mean= d3_p50= d3_p95= d3_p99= d3_gbs= d3_hit=
    if [ -n "${DRAMSIM3:-}" ]; then
      # DRAMsim3's controller can deadlock (a write drain that a queued read of
      # the same line blocks, with that read never moved): bound its run at
      # twice the stream's span and leave its columns empty if it stalls.
      limit=$(awk 'END { print 2 * $3 + 1000000 }' "$t.dramsim3.trace")
      "$DRAMSIM3" "$DRAMSIM3_INI" "$t.dramsim3.trace" --out-dir "$t.dramsim3" \
        --cycles-limit "$limit" > "$t.dramsim3.txt" || true
      d3="$t.dramsim3.txt"
      if [ "$(kvget "$d3" finished)" = 1 ]; then
        d3_mean=$(kvget "$d3" read_latency_mean) d3_p50=$(kvget "$d3" read_latency_p50)
        d3_p95=$(kvget "$d3" read_latency_p95) d3_p99=$(kvget "$d3" read_latency_p99)
        d3_gbs=$(awk -v b="$(kvget "$d3" bandwidth_bytes_per_cycle)" 'BEGIN { printf "%.3f", b * 1.2 }')
        d3_hit=$(kvget "$d3" row_hit_rate)
      fi
    fi
    for drain in 1000 0; do
      r="$t.rtsim-$drain.csv"
      build/rtsim dram-replay configs/default.yaml "$t.dramsim3.trace" --set clock_ghz=1.2 \
        --set dram.idle_drain_cycles=$drain --per-request "$t.rtsim-$drain.per" > "$r"
      set -- $(readlat "$t.dramsim3.trace" "$t.rtsim-$drain.per")
      printf '%s,%s,%s,%s,%s,%s,%s,%s,%s,%s,%s,%s,%s,%.3f,%s,%.4f,%s\n' "$scene" "$policy" "$drain" \
        "$(csvget "$r" requests)" "$(csvget "$r" writes)" "$1" "$d3_mean" "$2" "$d3_p50" \
        "$3" "$d3_p95" "$4" "$d3_p99" \
        "$(csvget "$r" gb_per_s)" "$d3_gbs" "$(csvget "$r" dram_row_hit_rate)" "$d3_hit" >> "$table.tmp"
      energy_row "$scene-$policy" "$r" "$t.dramsim3.txt" "$drain" >> "$energy.tmp"
    done
  done
done
mv "$table.tmp" "$table"

# 3. saturated.csv: the first 400,000 requests of three streams (one of them
#    write-heavy: room's dynamic, 45% writes) offered one a DRAM cycle (at
#    clock_ghz 1.2 the core and DRAM cycles are one), faster than one channel
#    serves: the bandwidth each controller sustains, and the read latencies
#    (DRAM cycles, from the request's arrival; from its taking, the mean).
sat=results/dram/saturated.csv
echo "stream,idle_drain_cycles,requests,writes,rtsim_bytes_per_cycle,dramsim3_bytes_per_cycle,rtsim_row_hit_rate,dramsim3_row_hit_rate,rtsim_read_latency_mean,dramsim3_read_latency_mean,rtsim_read_latency_p95,dramsim3_read_latency_p95,rtsim_read_latency_p99,dramsim3_read_latency_p99,rtsim_read_latency_taken_mean,dramsim3_read_latency_taken_mean" > "$sat.tmp"
for s in grove-recursive sphereflake-dynamic room-dynamic; do
  awk '!/^#/ && NF { n++; if (n <= 400000) print $1, $2, n }' "$out/$s.trace" > "$out/$s.saturated.trace"
  d3_bpc= d3_hit= d3_mean= d3_p95= d3_p99= d3_taken=
  if [ -n "${DRAMSIM3:-}" ]; then
    d3="$out/$s.saturated.dramsim3.txt"
    "$DRAMSIM3" "$DRAMSIM3_INI" "$out/$s.saturated.trace" --out-dir "$out/$s.saturated.dramsim3" \
      --cycles-limit 20000000 > "$d3" || true
    if [ "$(kvget "$d3" finished)" = 1 ]; then
      d3_bpc=$(kvget "$d3" bandwidth_bytes_per_cycle) d3_hit=$(kvget "$d3" row_hit_rate)
      d3_mean=$(kvget "$d3" read_latency_mean) d3_p95=$(kvget "$d3" read_latency_p95)
      d3_p99=$(kvget "$d3" read_latency_p99) d3_taken=$(kvget "$d3" read_latency_from_accept_mean)
    fi
  fi
  for drain in 1000 0; do
    r="$out/$s.saturated-$drain.csv"
    build/rtsim dram-replay configs/default.yaml "$out/$s.saturated.trace" --set clock_ghz=1.2 \
      --set dram.idle_drain_cycles=$drain --per-request "$out/$s.saturated-$drain.per" > "$r"
    set -- $(readlat "$out/$s.saturated.trace" "$out/$s.saturated-$drain.per")
    printf '%s,%s,%s,%s,%.3f,%s,%.4f,%s,%s,%s,%s,%s,%s,%s,%.2f,%s\n' "$s" "$drain" \
      "$(csvget "$r" requests)" "$(csvget "$r" writes)" \
      "$(csvget "$r" bytes_per_cycle)" "$d3_bpc" "$(csvget "$r" dram_row_hit_rate)" "$d3_hit" \
      "$1" "$d3_mean" "$3" "$d3_p95" "$4" "$d3_p99" "$(csvget "$r" read_latency_taken_mean)" "$d3_taken" >> "$sat.tmp"
    energy_row "$s-saturated" "$r" "$out/$s.saturated.dramsim3.txt" "$drain" >> "$energy.tmp"
  done
done
mv "$sat.tmp" "$sat"
mv "$energy.tmp" "$energy"

# 5. energy-estimate.csv: the DRAM energy a cheaper rung could estimate from
#    its own counts (levels.csv: dram_reads, dram_writes, cycles) with
#    DRAMsim3's increments, against the banked run's dram_energy_j for the same
#    scene and policy: every request a burst, a row hit rate of 0.5 assumed (an
#    ACT for every other request), a refresh every tREFI / ranks DRAM cycles,
#    every rank-cycle in active standby. The banked rows apply it to the banked
#    run's own counts: the formula's error alone.
# (A quoted field's commas, as in the first column's point name, become ';'.)
awk '{ o = ""; q = 0
       for (i = 1; i <= length($0); i++) { ch = substr($0, i, 1); if (ch == "\"") q = !q; else if (ch == "," && q) ch = ";"; o = o ch }
       print o }' results/dram/levels.csv |
awk -F, -v h=0.5 '
  NR == 1 { for (i = 1; i <= NF; i++) c[$i] = i; next }
  { n++; for (k in c) v[n, k] = $c[k] }
  function f(r, k) { return v[r, k] + 0 }
  END {
    print "scene,policy,fidelity,cycles,dram_reads,dram_writes,estimate_j,banked_j,error"
    for (r = 1; r <= n; r++)
      if (v[r, "fidelity"] == "banked") bk[v[r, "scene"], v[r, "policy"]] = f(r, "dram_energy_j")
    for (r = 1; r <= n; r++) {
      mhz = f(r, "dram.clock_mhz"); ranks = f(r, "dram.ranks"); chs = f(r, "dram.channels")
      j = f(r, "dram.VDD") * (f(r, "dram.bus_bytes") * 8 / f(r, "dram.device_width")) * (1000 / mhz) * 1e-12
      b = f(r, "dram.burst_length") / 2; i3 = f(r, "dram.IDD3N")
      rd = f(r, "dram_reads"); wr = f(r, "dram_writes")
      t = f(r, "cycles") * mhz / (f(r, "clock_ghz") * 1000)
      act = j * (f(r, "dram.IDD0") * f(r, "dram.tRC") - i3 * f(r, "dram.tRAS") - f(r, "dram.IDD2N") * f(r, "dram.tRP"))
      e = rd * j * (f(r, "dram.IDD4R") - i3) * b + wr * j * (f(r, "dram.IDD4W") - i3) * b
      e += (rd + wr) * (1 - h) * act
      e += int(t / int(f(r, "dram.tREFI") / ranks)) * chs * j * (f(r, "dram.IDD5AB") - i3) * f(r, "dram.tRFC")
      e += ranks * chs * t * j * i3
      ref = bk[v[r, "scene"], v[r, "policy"]]
      printf "%s,%s,%s,%d,%d,%d,%.6g,%.6g,%.4f\n", v[r, "scene"], v[r, "policy"], v[r, "fidelity"],
        f(r, "cycles"), rd, wr, e, ref, (e - ref) / ref
    }
  }' > results/dram/energy-estimate.csv.tmp
mv results/dram/energy-estimate.csv.tmp results/dram/energy-estimate.csv
