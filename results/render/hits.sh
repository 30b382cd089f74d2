#!/bin/sh
# Do the k-d tree, the BVH2, the BVH8 and Embree find the same nearest
# triangle? rtsim bench --hits --embree on the three scenes at 512x512: the
# primary rays, the shadow and diffuse rays their hits spawn, and 262,144
# random rays through each scene's box; a row a scene, ray set and structure
# into results/render/hits.csv (columns: rtsim bench --help-full). Needs
# Debian's libembree-dev; builds build-embree/ itself (as
# results/bench_primary.sh). No timing: any host gives the same file.
#   sh results/render/hits.sh        (from the repository top; ~10 min CPU)
set -eu
cmake -S . -B build-embree -DRTSIM_EMBREE=ON > /dev/null
cmake --build build-embree -j2 --target rtsim > /dev/null
out=results/render/hits.csv
build-embree/rtsim bench --hits --embree --width 512 --height 512 scenes/sphereflake.yaml \
  scenes/grove.yaml scenes/room.yaml > "$out.tmp"
mv "$out.tmp" "$out"
