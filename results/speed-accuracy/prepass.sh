#!/bin/sh
# Sampling with a sampled image and the pre-pass's ratio estimator at the
# DRAM-bound point: SCENES at SIZE x SIZE, primary + shadow + diffuse,
# recursive, configs/default.yaml with 64 cores and a 512 KiB L2 (512 ray
# contexts), the full banked run against sample.fraction FRACTION with
# sample.image sampled at seeds 1-SEEDS, two runs at a time. Writes
# prepass-SIZE.csv (one row a run: host seconds, then each figure with its
# 95% interval). From the repository top, after sh .ci/setup:
#   sh results/speed-accuracy/prepass.sh WORKDIR SEEDS SIZE FRACTION "SCENES" [collect]
# (collect: only write the CSV from the runs already in WORKDIR, named
# SCENE-full and SCENE-sSEED). The committed tables:
#   prepass.sh build/pp 10 256 0.2 "grove sphereflake"
#   prepass.sh build/pp512 10 512 0.05 grove
set -eu
cd "$(dirname "$0")/../.."
W=$1 SEEDS=$2 SIZE=$3 FRACTION=$4 SCENES=$5
mkdir -p "$W"
run() {
  sc=$1
  shift
  build/rtsim run configs/default.yaml "scenes/$sc.yaml" --width "$SIZE" --height "$SIZE" \
    --rays primary,shadow,diffuse --set cores=64 --set l2.size=512KiB "$@" > /dev/null 2>&1
}
if [ "${6:-run}" != collect ]; then
  for sc in $SCENES; do run "$sc" -o "$W/$sc-full"; done
  for s in $(seq 1 "$SEEDS"); do
    for sc in $SCENES; do
      run "$sc" -o "$W/$sc-s$s" --set sample.fraction="$FRACTION" --set sample.image=sampled \
        --set sample.seed="$s" &
    done
    wait
  done
fi
num() { grep -o "\"$2\": [-0-9.e+]*" "$1/stats.json" | head -1 | sed 's/.*: //'; }
f="cycles dram_bytes issue_slots rays_traced"
{
  printf "scene,size,fraction,run,seed,wall_s"
  for x in $f; do printf ",%s,%s_lo,%s_hi" "$x" "$x" "$x"; done
  printf "\n"
  for sc in $SCENES; do
    d="$W/$sc-full"
    printf "%s,%s,1,full,,%s" "$sc" "$SIZE" "$(num "$d" wall_s)"
    for x in $f; do printf ",%s,," "$(num "$d" "$x")"; done
    printf "\n"
    for s in $(seq 1 "$SEEDS"); do
      d="$W/$sc-s$s"
      printf "%s,%s,%s,sampled,%s,%s" "$sc" "$SIZE" "$FRACTION" "$s" "$(num "$d" wall_s)"
      for x in $f; do
        printf ",%s,%s,%s" "$(num "$d" "$x")" "$(num "$d" "${x}_ci95_low")" \
          "$(num "$d" "${x}_ci95_high")"
      done
      printf "\n"
    done
  done
} > "results/speed-accuracy/prepass-$SIZE.csv"
