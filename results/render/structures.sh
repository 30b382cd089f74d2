#!/bin/sh
# The three structures on the three scenes: what each build makes and costs,
# and what a render through it costs (512x512, every ray type, the recursive
# policy), one row a scene and structure, into results/render/structures.csv.
# From the repository top, after sh .ci/setup (about 2 min of CPU, one run at
# a time; GNU time measures the CPU seconds and the peak):
#   sh results/render/structures.sh
# cpu_s is the whole command's user CPU time (loading, build and render);
# peak_rss_mb is rtsim's own report, data_mb what the run must hold (scene,
# structure with its leaf lists, rays held at once). node_bytes: 8 a k-d
# node, 64 a BVH2 node, 80 a BVH8 node.
set -eu
out=results/render/structures.csv tmp=build/structures
mkdir -p "$tmp"
echo "scene,accel,nodes,node_bytes,leaves,depth_max,build_s,node_visits,triangle_tests,rays,cpu_s,data_mb,peak_rss_mb" > "$out.tmp"
for s in sphereflake grove room; do
  for a in kd bvh2 bvh8; do
    /usr/bin/time -f "%U" -o "$tmp/time" build/rtsim render "scenes/$s.yaml" --accel "$a" \
      --width 512 --height 512 -o "$tmp/image.exr" > "$tmp/summary.txt"
    awk -v s="$s" -v a="$a" -v cpu="$(tail -n 1 "$tmp/time")" '
      { i = index($0, ": "); if (i) v[substr($0, 1, i - 1)] = substr($0, i + 2) }
      END {
        if (a == "kd") {
          split(v["kd_leaves"], l, " ")
          n = v["kd_nodes"]; nb = 8 * n; lv = l[1]; d = v["kd_depth_max"]
          b = v["kd_build_s"]; vis = v["kd_node_visits"]
        } else {
          split(v["bvh_nodes"], x, " "); n = x[1]; nb = substr(x[2], 2)
          lv = v["bvh_leaves"]; d = v["bvh_depth_max"]; b = v["bvh_build_s"]
          vis = v["bvh_node_visits"]
        }
        split(v["data_mb"], dm, " "); split(v["peak_rss_mb"], pk, " ")
        printf "%s,%s,%s,%s,%s,%s,%s,%s,%s,%s,%s,%s,%s\n", s, a, n, nb, lv, d, b, vis,
          v["triangle_tests"], v["rays_total"], cpu, dm[1], pk[1]
      }' "$tmp/summary.txt" >> "$out.tmp"
  done
done
mv "$out.tmp" "$out"
