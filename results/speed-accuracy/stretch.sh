#!/bin/sh
# Sampling with a sampled image and the pre-pass's functional L2 model at
# the memory-bound point (docs/fidelity-and-sampling.md "Sampling"): SCENE
# at SIZE x SIZE, primary + shadow + diffuse, recursive, configs/default.yaml
# with 64 cores and an L2 of L2 (512KiB or 4MiB; 512 ray contexts),
# sample.image sampled at sample.fraction FRACTION, seeds 1-SEEDS, against
# the full banked run of the same point in FULLDIR (made there first if
# absent: FULLDIR/stats.json).
# Appends one row a run to stretch.csv: the point, the seed, the CPU
# seconds (user + system, /usr/bin/time), then each figure with its 95%
# interval (the full run's row: no interval); CSV (environment) writes
# elsewhere, FIRST starts at another seed than 1. From the repository top,
# after sh .ci/setup:
#   sh results/speed-accuracy/stretch.sh WORKDIR FULLDIR SCENE SIZE FRACTION SEEDS L2 [--set ...]
# The committed table (two at a time by hand: one scene each):
#   stretch.sh build/st build/st/grove-512-full grove 512 0.05 5 512KiB
#   stretch.sh build/st build/st/sphereflake-512-full sphereflake 512 0.05 5 512KiB
#   stretch.sh build/st build/st/grove-512-4m-full grove 512 0.05 5 4MiB
#   stretch.sh build/st build/st/sphereflake-512-4m-full sphereflake 512 0.05 5 4MiB
# (the 512x512 references are the memory-bound grid's banked runs: copy them to
# FULLDIR to reuse them).
set -eu
cd "$(dirname "$0")/../.."
W=$1 FULL=$2 SC=$3 SIZE=$4 FRACTION=$5 SEEDS=$6 L2=$7
shift 7
mkdir -p "$W"
CSV=${CSV:-results/speed-accuracy/stretch.csv}
F="cycles dram_bytes issue_slots rays_traced"
run() {
  d=$1
  shift
  /usr/bin/time -f "%U %S" -o "$d.cpu" build/rtsim run configs/default.yaml "scenes/$SC.yaml" \
    --width "$SIZE" --height "$SIZE" --rays primary,shadow,diffuse --set cores=64 \
    --set l2.size="$L2" "$@" -o "$d" > /dev/null 2>&1
}
num() { grep -o "\"$2\": [-0-9.e+]*" "$1/stats.json" | head -1 | sed 's/.*: //'; }
cpu() { awk '{ printf "%.1f", $1 + $2 }' "$1.cpu" 2> /dev/null || printf ""; }
if [ ! -f "$CSV" ]; then
  printf "scene,size,l2,fraction,run,seed,cpu_s" > "$CSV"
  for x in $F; do printf ",%s,%s_lo,%s_hi" "$x" "$x" "$x" >> "$CSV"; done
  printf ",options\n" >> "$CSV"
fi
[ -f "$FULL/stats.json" ] || run "$FULL"
if ! grep -q "^$SC,$SIZE,$L2,1,full," "$CSV"; then
  printf "%s,%s,%s,1,full,,%s" "$SC" "$SIZE" "$L2" "$(cpu "$FULL")" >> "$CSV"
  for x in $F; do printf ",%s,," "$(num "$FULL" "$x")" >> "$CSV"; done
  printf ",\n" >> "$CSV"
fi
for s in $(seq "${FIRST:-1}" "$SEEDS"); do
  d="$W/$SC-$SIZE-$L2-$FRACTION-s$s"
  run "$d" --set sample.fraction="$FRACTION" --set sample.image=sampled --set sample.seed="$s" "$@"
  printf "%s,%s,%s,%s,sampled,%s,%s" "$SC" "$SIZE" "$L2" "$FRACTION" "$s" "$(cpu "$d")" >> "$CSV"
  for x in $F; do
    printf ",%s,%s,%s" "$(num "$d" "$x")" "$(num "$d" "${x}_ci95_low")" \
      "$(num "$d" "${x}_ci95_high")" >> "$CSV"
  done
  printf ",%s\n" "$*" >> "$CSV"
done
