#!/bin/sh
# Host time and peak host memory of rtsim's three paths against the work:
# native (rtsim render, recursive policy), functional (rtsim traffic, recursive
# policy, all 13 cache sizes, one host thread) and timed (rtsim run on
# configs/default.yaml, recursive policy). Axes: the sphereflake's detail 2..5
# (128x128, primary rays), the image 128..1024 (sphereflake, primary rays), and for
# the timed path alone the cores 1..1024 and the L2 16 KiB..16 GiB in bytes (grove,
# 128x128, primary and shadow rays). One process a measurement, one at a time.
# work_s is the wall seconds the program reports for its work, without loading
# the scene and building its tree (render's render_s, traffic's runs_s, run's
# stats.json wall_s); host_s (user + system seconds), wall_s and peak_mb (peak
# resident MiB) are the whole process's, read by GNU time (Debian package time).
# Each measurement runs REPEAT times (default 3); the run with the least work_s
# is kept.
#   usage: sh results/cost-growth/run.sh [OUT]   (from the repository top;
#   RTSIM names the binary, default build/rtsim). Writes OUT/table.csv (default
#   results/cost-growth) and the plots of work_s against each axis,
#   OUT/{image,detail,cores,l2}.png.
set -eu
RTSIM=${RTSIM:-build/rtsim}
OUT=${1:-results/cost-growth}
REPEAT=${REPEAT:-3}
case $REPEAT in
'' | *[!0-9]* | 0*) echo "run.sh: REPEAT: got '$REPEAT', expected a whole number from 1" >&2; exit 2 ;;
esac
TIME=/usr/bin/time
[ -x "$TIME" ] || { echo "run.sh: needs GNU time ($TIME; Debian package time)" >&2; exit 2; }
mkdir -p "$OUT"
TMP=$(mktemp -d)
trap 'rm -rf "$TMP"' EXIT INT TERM
# One row: axis path scene detail size rays cores l2_bytes (the last two for
# the timed path; empty otherwise).
row() {
  axis=$1 path=$2 scene=$3 detail=$4 size=$5 rays=$6 cores=$7 l2=$8
  case $path in
  native) set -- "$RTSIM" render "$scene" -o "$TMP/x.exr" ;;
  functional) set -- "$RTSIM" traffic "$scene" --policy recursive --threads 1 -o "$TMP/x.csv" ;;
  timed)
    set -- "$RTSIM" run configs/default.yaml "$scene" --set cores="$cores" --set l2.size="$l2" \
      -o "$TMP/run"
    ;;
  esac
  best=
  for _ in $(seq "$REPEAT"); do
    if ! "$TIME" -f "%U %S %e %M" -o "$TMP/t" "$@" --width "$size" --height "$size" --rays "$(echo "$rays" | tr + ,)" \
      > "$TMP/out" 2> "$TMP/err"; then
      cat "$TMP/err" >&2
      exit 1
    fi
    case $path in
    native) work=$(sed -n 's/^render_s: \([0-9.]*\).*/\1/p' "$TMP/out") ;;
    functional) work=$(sed -n 's/^runs_s: \([0-9.]*\).*/\1/p' "$TMP/out") ;;
    timed) work=$(sed -n 's/^ *"wall_s": \([0-9.]*\).*/\1/p' "$TMP/run/stats.json") ;;
    esac
    name=$(basename "$scene" .yaml)
    line=$(awk -v pre="$axis,$path,${name%%-*},$detail,$size,$rays,$cores,$l2" -v w="$work" \
      '{ printf "%s,%.3f,%.2f,%.2f,%.1f\n", pre, w, $1 + $2, $3, $4 / 1024 }' "$TMP/t")
    # The run with the least work_s stands for the measurement (the host's noise
    # only ever adds time); its host, wall and memory figures go with it.
    if [ -z "$best" ] || awk -v a="$work" -v b="$best_work" 'BEGIN { exit !(a < b) }'; then
      best=$line best_work=$work
    fi
  done
  echo "$best"
  echo "  $axis: $path $name ${size}x$size $rays ${cores:+cores $cores l2 $l2}" >&2
}
{
  echo "axis,path,scene,detail,width,rays,cores,l2_bytes,work_s,host_s,wall_s,peak_mb"
  # The default machine's cores and L2 (configs/default.yaml) for the timed path.
  C=16 L=4194304
  for d in 2 3 4 5; do
    s=scenes/sphereflake.yaml
    if [ "$d" != 4 ]; then
      s=$TMP/sphereflake-$d.yaml
      sed "s/^\( *detail:\) 4 /\1 $d /" scenes/sphereflake.yaml > "$s"
    fi
    row detail native "$s" "$d" 128 primary "" ""
    row detail functional "$s" "$d" 128 primary "" ""
    row detail timed "$s" "$d" 128 primary $C $L
  done
  for n in 128 256 512 1024; do
    row image native scenes/sphereflake.yaml 4 "$n" primary "" ""
    row image functional scenes/sphereflake.yaml 4 "$n" primary "" ""
    row image timed scenes/sphereflake.yaml 4 "$n" primary $C $L
  done
  for c in 1 4 16 64 256 1024; do row cores timed scenes/grove.yaml "" 128 primary+shadow "$c" $L; done
  for l in 16384 262144 4194304 67108864 1073741824 17179869184; do
    row l2 timed scenes/grove.yaml "" 128 primary+shadow $C "$l"
  done
} > "$TMP/table.csv"
mv "$TMP/table.csv" "$OUT/table.csv"
T=$OUT/table.csv
"$RTSIM" plot "$T" --where axis=image --x width --y work_s --lines path --logx --logy -o "$OUT/image.png"
"$RTSIM" plot "$T" --where axis=detail --x detail --y work_s --lines path --logy -o "$OUT/detail.png"
"$RTSIM" plot "$T" --where axis=cores --x cores --y work_s --logx -o "$OUT/cores.png"
"$RTSIM" plot "$T" --where axis=l2 --x l2_bytes --y work_s --logx -o "$OUT/l2.png"
echo "wrote $T and image.png, detail.png, cores.png, l2.png" >&2
