#!/bin/sh
# Sampling at the DRAM-bound point: grove 256x256, primary + shadow + diffuse,
# recursive, configs/default.yaml with 64 cores and a 512 KiB L2, the full
# banked run against sample.fraction 0.2 (8 units, the fewest allowed) at
# seeds 1-8. Writes dram-bound.csv (one row a run). From the repository top,
# after sh .ci/setup:  sh results/speed-accuracy/dram-bound.sh [WORKDIR]
set -eu
cd "$(dirname "$0")/../.."
W=${1:-build/dram-bound}
mkdir -p "$W"
run() { build/rtsim run configs/default.yaml scenes/grove.yaml --width 256 --height 256 \
  --rays primary,shadow,diffuse --set cores=64 --set l2.size=512KiB "$@" > /dev/null; }
run -o "$W/full"
for s in 1 2 3 4 5 6 7 8; do run -o "$W/s$s" --set sample.fraction=0.2 --set sample.seed=$s; done
num() { grep -o "\"$2\": [-0-9.e+]*" "$1/stats.json" | head -1 | sed 's/.*: //'; }
out=results/speed-accuracy/dram-bound.csv
echo "run,seed,wall_s,cycles,cycles_lo,cycles_hi,dram_bytes,dram_bytes_lo,dram_bytes_hi" > "$out"
echo "full,,$(num "$W/full" wall_s),$(num "$W/full" cycles),,,$(num "$W/full" dram_bytes),," >> "$out"
for s in 1 2 3 4 5 6 7 8; do
  d="$W/s$s"
  echo "sampled,$s,$(num "$d" wall_s),$(num "$d" cycles),$(num "$d" cycles_ci95_low),$(num "$d" cycles_ci95_high),$(num "$d" dram_bytes),$(num "$d" dram_bytes_ci95_low),$(num "$d" dram_bytes_ci95_high)" >> "$out"
done
