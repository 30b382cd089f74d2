/* rtsim render: ray trace a scene to an OpenEXR image and print a summary. */
#include "app/app.h"

#include <stdio.h>
#include <string.h>
#include <sys/resource.h>
#include <unistd.h>

#include "app/opts.h"
#include "app/outguard.h"
#include "app/preview.h"
#include "renderer/framebuffer.h"
#include "renderer/image.h"
#include "renderer/policy/policy.h"
#include "renderer/shade.h"
#include "renderer/trace.h"
#include "sim/err.h"
#include "sim/outfile.h"

static const char HELP[] =
    "usage: rtsim render SCENE.yaml -o IMAGE.exr [options]\n"
    "\n"
    "Ray trace SCENE.yaml and write IMAGE.exr with channels R, G, B (linear radiance)\n"
    "and cost.nodes, cost.tris (node visits and triangle tests per pixel). The scene's\n"
    "accel key chooses the structure traced (kd, bvh2 or bvh8; docs/inputs.md).\n"
    "Prints a summary on stdout; progress on stderr when it is a terminal.\n"
    "\n"
    "example:\n"
    "  rtsim render scenes/small/sphereflake.yaml --width 128 --height 128 \\\n"
    "      -o build/sphereflake.exr --preview build/sphereflake.png\n"
    "\n"
    "options:\n"
    "  -o, --output FILE   image to write (required); it and the preview are written\n"
    "                      whole, both or neither (a failure or SIGINT leaves the\n"
    "                      earlier files as they were)\n"
    "  --width W           image width in pixels (default: the scene's)\n"
    "  --height H          image height in pixels (default: the scene's)\n"
    "  --rays LIST         ray types, comma-separated from primary,shadow,specular,diffuse\n"
    "                      (default: all; primary is always traced)\n"
    "  --policy P          ray scheduling (default recursive; all give the same image):\n"
    "                        {policies}\n"
    "  --seed S            seed of the diffuse sampling streams (default: the scene's seed)\n"
    "  --accel A           the structure traced: kd, bvh2 or bvh8 (default: the scene's\n"
    "                      accel key)\n"
    "  --half              store 16-bit floats (smaller file) instead of 32-bit\n"
    "  --preview PNG       also write an sRGB PNG preview (through gnuplot)\n"
    "  -h, --help          this text\n";

static void progress(void *ctx, uint64_t done, uint64_t total) {
  (void)ctx;
  fprintf(stderr, "\rrendering: %3d%%", (int)(100 * done / total));
  if (done == total) fputc('\n', stderr);
  fflush(stderr);
}

/* The BVH's summary lines, in place of the k-d tree's. */
static void print_bvh(const struct app_world *w) {
  const struct bvh_stats *b = &w->bvh.stats;
  printf("accel: %s\n", accel_names[w->scene.accel]);
  printf("bvh_build_s: %.3f\n", w->build_s);
  printf("bvh_nodes: %u (%llu bytes)\n", b->nodes, (unsigned long long)b->node_bytes);
  printf("bvh_leaves: %u\n", b->leaves);
  printf("bvh_depth_max: %u\n", b->max_depth);
  printf("bvh_leaf_prims_max: %u\n", b->max_leaf_prims);
  printf("bvh_leaf_prims_mean: %.2f\n",
         b->leaves ? (double)w->bvh.prim_count / (double)b->leaves : 0.0);
  printf("bvh_sah_cost: %.4f\n", b->sah_cost);
}

/* Print the scene and acceleration structure summary lines ("key: value")
 * on stdout. */
static void print_world(const struct app_world *w, const char *path) {
  const struct kd_stats *k = &w->kd.stats;
  printf("scene: %s (%s)\n", w->scene.name[0] ? w->scene.name : "unnamed", path);
  printf("triangles: %u\n", w->scene.tri_count);
  printf("load_s: %.3f\n", w->load_s);
  if (app_world_bvh(w)) {
    print_bvh(w);
    return;
  }
  printf("kd_build_s: %.3f\n", w->build_s);
  printf("kd_splits: %s\n", w->scene.kd_clip ? "clipped" : "whole");
  printf("kd_refs_per_triangle: %.2f\n",
         w->scene.tri_count ? (double)k->leaf_prim_refs / w->scene.tri_count : 0.0);
  printf("kd_nodes: %u\n", k->nodes);
  printf("kd_leaves: %u (empty %u)\n", k->leaves, k->empty_leaves);
  printf("kd_depth_max: %u\n", k->max_depth);
  printf("kd_leaf_prims_max: %u\n", k->max_leaf_prims);
  printf("kd_leaf_prims_mean: %.2f (non-empty leaves)\n",
         k->leaves > k->empty_leaves
             ? (double)k->leaf_prim_refs / (double)(k->leaves - k->empty_leaves)
             : 0.0);
}

int cmd_render(int argc, char **argv) {
  const char *out = NULL, *preview = NULL;
  uint32_t mask = RAY_MASK(RAY_TYPE_COUNT) - 1; /* every ray type */
  uint64_t width = 0, height = 0, seed = 0;
  bool have_seed = false, half = false;
  int accel = -1;
  enum policy_kind policy = POLICY_RECURSIVE;
  char policy_expect[160];
  app_policy_expect(policy_expect, sizeof policy_expect, "");
  const struct opts_spec spec[] = {
      OPTS_STR("output", 'o', &out),
      APP_RENDER_OPTS(&width, &height, &mask, &seed, &have_seed, &policy, policy_expect),
      APP_ACCEL_OPT(&accel),
      OPTS_FLAG("half", 0, &half),
      OPTS_STR("preview", 0, &preview),
      OPTS_END};
  struct opts_args args;
  char help[sizeof HELP + 1024];
  app_help(help, sizeof help, HELP);
  int rc = opts_parse("render", help, spec, argc, argv, &args);
  if (rc != OPTS_GO) return rc;
  const char *scene_path = opts_one_scene(&args);
  if (!scene_path) return APP_EXIT_USAGE;
  if (!out) return app_usage_error("render", "missing -o IMAGE.exr");
  const char *path = scene_path;

  struct app_world w;
  if (!app_world_load_as(&w, path, accel)) return 2;
  uint32_t W = width ? (uint32_t)width : w.scene.width;
  uint32_t H = height ? (uint32_t)height : w.scene.height;
  struct app_render ar;
  app_render_init(&ar, &w, mask, have_seed ? seed : w.scene.seed, W, H);
  ar.setup.progress = isatty(2) ? progress : NULL;
  struct render_stats st;
  struct trace_stats ts;
  double t0 = app_now();
  struct policy_params pp;
  policy_params_default(&pp);
  policy_run(policy, &ar.setup, &pp, mem_port_native(), &st, &ts);
  double secs = app_now() - t0;

  struct image im;
  const struct framebuffer *fb = &ar.fb;
  fb_to_image(fb, &im);
  /* Bytes of the image, for the memory line of the summary. */
  const double image_bytes = (double)W * H *
                             (3 * sizeof *fb->acc + sizeof *fb->cost_nodes + sizeof *fb->cost_tris +
                              im.channel_count * sizeof(float));
  struct err e;
  memset(&e, 0, sizeof e);
  /* The image and its preview both or neither: each drawn into a temporary,
   * renamed once both are whole; a signal meanwhile removes them. */
  struct outfile exr = {0}, png = {0};
  outguard_beside(out);
  if (preview) outguard_beside(preview);
  bool ok = outfile_open_named(&exr, out, "EXR", &e) && image_write_exr_to(&im, &exr, half, &e) &&
            (!preview || (outfile_open_named(&png, preview, "the preview", &e) &&
                          preview_write_png(&im, &png, &e) && outfile_commit(&png, &e))) &&
            outfile_commit(&exr, &e);
  outfile_abort(&exr);
  outfile_abort(&png);
  outguard_clear();
  image_fini(&im);
  const uint64_t seed_used = ar.sc.seed;
  app_render_fini(&ar);
  if (!ok) {
    app_world_fini(&w);
    return app_report(&e);
  }
  char names[64];
  shade_rays_name(mask, names, sizeof names);
  print_world(&w, path);
  printf("image: %ux%u\n", W, H);
  printf("policy: %s\n", policy_name(policy));
  printf("ray_types: %s\n", names);
  printf("seed: %llu\n", (unsigned long long)seed_used);
  static const char *const tn[] = {"primary", "shadow", "specular", "diffuse"};
  for (int t = 0; t < RAY_TYPE_COUNT; t++)
    printf("rays_%s: %llu\n", tn[t], (unsigned long long)st.rays[t]);
  uint64_t total = render_stats_total(&st);
  printf("rays_total: %llu\n", (unsigned long long)total);
  printf("ray_slots_max: %llu (%.1f MB of 64-byte rays held at once)\n",
         (unsigned long long)st.ray_slots_max, (double)st.ray_slots_max * 64 / 1048576.0);
  printf("%s_node_visits: %llu\n", app_world_bvh(&w) ? "bvh" : "kd",
         (unsigned long long)ts.node_visits);
  printf("triangle_tests: %llu\n", (unsigned long long)ts.tri_tests);
  /* Peak memory against what the run must hold: the scene, the tree and the
   * rays in flight (the target is at most twice that), and apart the image
   * (the framebuffer's sums and costs, and the output planes). */
  const double mb = 1048576.0;
  double scene_mb = (double)w.scene.tri_count * sizeof *w.scene.tris / mb;
  double tree_mb =
      ((double)w.kd.node_count * sizeof *w.kd.nodes +
       (double)w.kd.prim_ref_count * sizeof *w.kd.prims + (double)w.bvh.stats.node_bytes +
       (double)w.bvh.prim_count * sizeof *w.bvh.prims) /
      mb;
  double rays_mb = (double)st.ray_slots_max * sizeof(struct ray) / mb;
  double data_mb = scene_mb + tree_mb + rays_mb;
  double image_mb = image_bytes / mb;
  printf("data_mb: %.1f (scene %.1f + %s %.1f + rays %.1f)\n", data_mb, scene_mb,
         app_world_bvh(&w) ? "BVH" : "k-d tree", tree_mb, rays_mb);
  printf("image_mb: %.1f (framebuffer and output planes)\n", image_mb);
  struct rusage ru;
  if (getrusage(RUSAGE_SELF, &ru) == 0) {
    double peak = (double)ru.ru_maxrss / 1024.0;
    printf("peak_rss_mb: %.1f (%.2f x data_mb; %.2f x data_mb + image_mb)\n", peak, peak / data_mb,
           peak / (data_mb + image_mb));
  }
  printf("render_s: %.3f\n", secs);
  printf("rays_per_s: %.0f\n", secs > 0 ? (double)total / secs : 0.0);
  printf("output: %s\n", out);
  if (preview) printf("preview: %s\n", preview);
  app_world_fini(&w);
  return 0;
}
