#!/bin/sh
# How wrong is each cheaper rung (analytic, fixed, channel) against banked,
# by regime? Every rung on grove and sphereflake (primary, shadow and diffuse
# rays, 128x128), every policy, on three machines from compute-bound to
# DRAM-bound; then rung-points.csv (one row a run at a cheaper rung: where it
# falls, by its own figures, and its error against the banked run of the same
# point) and rung-errors.csv (one row a regime: the errors of its points, by
# rung, policy, analytic's bound and bands of DRAM and core utilization),
# which the build compiles into rtsim (app/rung_error.h). From the repository
# top, after sh .ci/setup (about 11 min of CPU, one run at a time):
#   sh results/speed-accuracy/rung-errors.sh [--keep]
# --keep: keep the runs a stopped earlier call completed (their stats.json
# exists) instead of starting afresh. --fold: run nothing, keep the 128x128
# rows of the committed rung-points.csv and fold memory-bound.csv in again
# (after memory-bound.sh gained points). RTSIM: the program (default
# build/rtsim). Then rebuild rtsim to compile the table.
set -eu
out=build/rung-errors res=results/speed-accuracy rtsim=${RTSIM:-build/rtsim}
case ${1:-} in --keep | --fold) ;; *) rm -rf "$out" ;; esac
mkdir -p "$out"

# The machines: the default (the recursive policy compute-bound), 32 cores
# on a 1 MiB L2 (issue 36's machine: near the DRAM's peak already), and a
# DRAM-bound one (64 cores on a 512 KiB L2).
regime_sets() {
  case $1 in
  compute) echo "" ;;
  middle) echo "--set cores=32 --set l2.size=1MiB" ;;
  dram) echo "--set cores=64 --set l2.size=512KiB" ;;
  esac
}
# The bands rung-errors.csv groups the points by (low ends; the last band
# has no end). DRAM utilization is the run's own bytes a cycle over the banked
# DRAM's peak, so above 1 only the fixed rung (no bandwidth limit) goes.
DRAM_EDGES="0 0.5 0.8 1"
CORE_EDGES="0 0.5 0.9"

# One number member of a stats.json (empty when absent).
num() { sed -n "s/^  \"$2\": \([^,]*\),*\$/\1/p" "$1/stats.json"; }

[ "${1:-}" = --fold ] || for regime in compute middle dram; do
  for scene in grove sphereflake; do
    for policy in recursive packet dynamic treelet; do
      for rung in banked channel fixed analytic; do
        d="$out/$regime-$scene-$policy-$rung"
        [ -f "$d/stats.json" ] && continue
        # Every cheaper run warns (its error is what this measures): stderr
        # is shown only when a run fails.
        # shellcheck disable=SC2046 # the sets are words
        if ! nice "$rtsim" run configs/default.yaml "scenes/$scene.yaml" -o "$d" --width 128 \
          --height 128 --rays primary,shadow,diffuse --policy "$policy" \
          --set "fidelity=$rung" $(regime_sets "$regime") > /dev/null 2> "$out/stderr.txt"; then
          cat "$out/stderr.txt" >&2
          exit 1
        fi
      done
    done
  done
done

points="$res/rung-points.csv"
if [ "${1:-}" = --fold ]; then
  grep -v "^memory-bound-" "$points" > "$points.tmp" && mv "$points.tmp" "$points"
else
  echo "regime,scene,policy,rung,bound,rung_dram_utilization,core_utilization,cycles,dram_bytes,banked_cycles,banked_dram_bytes,banked_dram_utilization,banked_core_utilization,cycles_error,dram_bytes_error" > "$points"
  for regime in compute middle dram; do
    for scene in grove sphereflake; do
      for policy in recursive packet dynamic treelet; do
        b="$out/$regime-$scene-$policy-banked"
        bc=$(num "$b" cycles) bb=$(num "$b" dram_bytes)
        bu=$(num "$b" dram_utilization) bk=$(num "$b" core_utilization)
        for rung in analytic fixed channel; do
          d="$out/$regime-$scene-$policy-$rung"
          bound=-
          case $(num "$d" rung_bandwidth_bound) in 1) bound=bandwidth ;; 0) bound=latency ;; esac
          c=$(num "$d" cycles) u=$(num "$d" rung_dram_utilization) k=$(num "$d" core_utilization)
          y=$(($(num "$d" dram_read_bytes) + $(num "$d" dram_write_bytes)))
          awk -v f="$regime,$scene,$policy,$rung,$bound,$u,$k,$c,$y,$bc,$bb,$bu,$bk" \
            -v c="$c" -v y="$y" -v bc="$bc" -v bb="$bb" \
            'BEGIN { printf "%s,%.6f,%.6f\n", f, (c - bc) / bc, (y - bb) / bb }' >> "$points"
        done
      done
    done
  done
fi

# The memory-bound grid's points (memory-bound.csv: 64 cores, a 512 KiB or a
# 4 MiB L2, 512x512 and up) join them, each cheaper run against the banked run
# of its point, so a run near the DRAM's peak quotes what was measured there.
awk -F, '
NR == 1 { for (i = 1; i <= NF; i++) c[$i] = i; next }
{ k = $c["scene"] SUBSEP $c["policy"] SUBSEP $c["width"] SUBSEP $c["l2_size"] }
$c["fidelity"] == "banked" { bc[k] = $c["cycles"]; bb[k] = $c["dram_bytes"]
  bu[k] = $c["dram_utilization"]; bk[k] = $c["core_utilization"]; next }
{ row[++n] = $0; key[n] = k }
END {
  for (i = 1; i <= n; i++) {
    if (!(key[i] in bc)) continue
    split(row[i], f, ",")
    bound = f[c["rung_bandwidth_bound"]] == 1 ? "bandwidth" : \
      f[c["rung_bandwidth_bound"]] == "0" ? "latency" : "-"
    k = key[i]
    printf "memory-bound-%s-%s,%s,%s,%s,%s,%s,%s,%s,%s,%s,%s,%s,%s,%.6f,%.6f\n",
      f[c["width"]], f[c["l2_size"]], f[c["scene"]], f[c["policy"]], f[c["fidelity"]], bound,
      f[c["rung_dram_utilization"]], f[c["core_utilization"]], f[c["cycles"]],
      f[c["dram_bytes"]], bc[k], bb[k], bu[k], bk[k], (f[c["cycles"]] - bc[k]) / bc[k],
      (f[c["dram_bytes"]] - bb[k]) / bb[k]
  }
}' "$res/memory-bound.csv" >> "$points"

# One row a regime: rung x policy x bound x DRAM band x core band, in the
# order of the loops above; errors' smallest and largest.
awk -F, -v de="$DRAM_EDGES" -v ce="$CORE_EDGES" '
function band(x, e, n,   i) { for (i = n; i > 1; i--) if (x >= e[i]) return i; return 1 }
function hi(e, n, i) { return i < n ? e[i + 1] : "inf" }
NR == 1 { nd = split(de, D, " "); nc = split(ce, C, " "); next }
{
  k = $4 SUBSEP $3 SUBSEP $5 SUBSEP band($6, D, nd) SUBSEP band($7, C, nc)
  if (!(k in n)) { n[k] = 0; c0[k] = c1[k] = $14; y0[k] = y1[k] = $15 }
  n[k]++
  if ($14 < c0[k]) c0[k] = $14; if ($14 > c1[k]) c1[k] = $14
  if ($15 < y0[k]) y0[k] = $15; if ($15 > y1[k]) y1[k] = $15
}
END {
  print "rung,policy,bound,dram_utilization_low,dram_utilization_high,core_utilization_low,core_utilization_high,points,cycles_error_min,cycles_error_max,dram_bytes_error_min,dram_bytes_error_max"
  split("analytic fixed channel", R, " "); split("recursive packet dynamic treelet", P, " ")
  split("latency bandwidth -", B, " ")
  for (r = 1; r <= 3; r++) for (p = 1; p <= 4; p++) for (b = 1; b <= 3; b++)
    for (i = 1; i <= nd; i++) for (j = 1; j <= nc; j++) {
      k = R[r] SUBSEP P[p] SUBSEP B[b] SUBSEP i SUBSEP j
      if (k in n)
        printf "%s,%s,%s,%s,%s,%s,%s,%d,%s,%s,%s,%s\n", R[r], P[p], B[b], D[i], hi(D, nd, i),
          C[j], hi(C, nc, j), n[k], c0[k], c1[k], y0[k], y1[k]
    }
}' "$points" > "$res/rung-errors.csv"

# The figure a reader picks a rung by: each cheaper run's cycles error
# against the banked run of its point, over that banked run's DRAM
# utilization, one panel a policy, one marker a rung.
awk -F, 'NR == 1 { print "rung,policy,DRAM utilization (banked run),cycles error against banked (%)"; next }
{ printf "%s,%s,%s,%.4g\n", $4, $3, $12, $14 * 100 }' "$points" > "$out/rung-plot.csv"
"$rtsim" plot "$out/rung-plot.csv" --x "DRAM utilization (banked run)" \
  --y "cycles error against banked (%)" --lines rung --panels policy --points \
  --order channel,fixed,analytic -o "$res/rung-errors.png"
