#!/bin/sh
# The paper's traffic grid: 3 scenes x 4 ray configurations x 13 cache sizes x 3
# policies, at the paper's resolutions (1024x1024; 512x512 with diffuse rays)
# divided by DIV (default 1), one `rtsim traffic` process per scene and
# configuration, JOBS at a time (default: the number of cores). Writes
# OUT/SCENE-CONFIG.csv, OUT/all.csv and OUT/tables.md (our numbers beside the
# paper's, from results/traffic/paper.csv).
#   usage: sh results/traffic/run.sh [OUT [DIV [JOBS]]]   (from the repository top;
#   RTSIM names the binary (default build/rtsim), SCENES the scene folder
#   (default scenes; the tests use scenes/small), POLICY the policies (passed to
#   `rtsim traffic --policy`; default the paper's three), ACCEL the structure
#   (passed to --accel; default the scenes' own, the k-d tree))
set -eu
RTSIM=${RTSIM:-build/rtsim}
SCENES=${SCENES:-scenes}
OUT=${1:-results/traffic}
DIV=${2:-1}
JOBS=${3:-$(nproc)}
POLICY=${POLICY:-}
ACCEL=${ACCEL:-}
mkdir -p "$OUT"
# A run per core already keeps every core busy: the analyser's own thread
# (rtsim traffic --threads 2) would only add host CPU time then.
THREADS=1
[ "$JOBS" = 1 ] && THREADS=2
# Longest jobs first (diffuse, room before grove), so no core idles at the end.
for c in diffuse specular shadow primary; do
  for s in room grove sphereflake; do
    size=1024
    [ "$c" = diffuse ] && size=512
    echo "$s $c $((size / DIV))"
  done
done | RTSIM="$RTSIM" SCENES="$SCENES" POLICY="$POLICY" ACCEL="$ACCEL" THREADS="$THREADS" xargs -P "$JOBS" -L 1 sh -c \
  '"$RTSIM" traffic "$SCENES/$0.yaml" --rays "$1" --width "$2" --height "$2" ${POLICY:+--policy "$POLICY"} ${ACCEL:+--accel "$ACCEL"} --threads "$THREADS" -o "'"$OUT"'/$0-$1.csv" > /dev/null && echo "done: $0 $1 at $2x$2" >&2'
first=1
for s in room grove sphereflake; do
  for c in primary shadow specular diffuse; do
    if [ $first = 1 ]; then cat "$OUT/$s-$c.csv"; first=0; else tail -n +2 "$OUT/$s-$c.csv"; fi
  done
done > "$OUT/all.csv.tmp" && mv "$OUT/all.csv.tmp" "$OUT/all.csv"
case "$POLICY" in
'' | all)
  sh results/traffic/tables.sh "$OUT/all.csv" results/traffic/paper.csv > "$OUT/tables.md.tmp" && mv "$OUT/tables.md.tmp" "$OUT/tables.md"
  echo "wrote $OUT/all.csv and $OUT/tables.md" >&2 ;;
*)
  # Not the paper's three: the tables come with the full grid's, as a column.
  echo "wrote $OUT/all.csv (tables: sh results/traffic/tables.sh FULL/all.csv results/traffic/paper.csv $OUT/all.csv)" >&2 ;;
esac
