/* rtsim bench: primary-ray throughput per scene (a benchmark, not a test). */
#include <getopt.h>
#include <stdio.h>
#include <string.h>

#include "app/app.h"
#include "renderer/framebuffer.h"
#include "renderer/policy.h"
#include "renderer/shade.h"
#include "renderer/trace.h"

static const char HELP[] =
    "usage: rtsim bench [options] SCENE.yaml...\n"
    "\n"
    "For each scene: load, build the k-d tree, and render primary rays only (native\n"
    "backend, single thread) several times; report the best time. Prints CSV on\n"
    "stdout: scene,triangles,kd_nodes,kd_build_s,width,height,rays,best_s,rays_per_s.\n"
    "\n"
    "options:\n"
    "  --width W --height H   image size (default: each scene's)\n"
    "  --repeat N             renders per scene, best kept (default 3)\n"
    "  -h, --help             this text\n";

int cmd_bench(int argc, char **argv) {
  static const struct option opts[] = {{"width", required_argument, 0, 'W'},
                                       {"height", required_argument, 0, 'H'},
                                       {"repeat", required_argument, 0, 'n'},
                                       {"help", no_argument, 0, 'h'},
                                       {0, 0, 0, 0}};
  uint64_t width = 0, height = 0, repeat = 3;
  int c;
  opterr = 0;
  optind = 1;
  while ((c = getopt_long(argc, argv, ":h", opts, NULL)) != -1) {
    switch (c) {
    case 'W': if (!app_parse_u64("bench", "--width", optarg, 1, 16384, &width)) return 2; break;
    case 'H': if (!app_parse_u64("bench", "--height", optarg, 1, 16384, &height)) return 2; break;
    case 'n': if (!app_parse_u64("bench", "--repeat", optarg, 1, 1000, &repeat)) return 2; break;
    case 'h': fputs(HELP, stdout); return 0;
    case ':': return app_usage_error("bench", "option %s needs a value", argv[optind - 1]);
    default: return app_usage_error("bench", "unknown option '%s'", argv[optind - 1]);
    }
  }
  if (optind >= argc) return app_usage_error("bench", "missing SCENE.yaml");
  printf("scene,triangles,kd_nodes,kd_build_s,width,height,rays,best_s,rays_per_s\n");
  for (int i = optind; i < argc; i++) {
    struct app_world w;
    if (!app_world_load(&w, argv[i])) return 2;
    uint32_t W = width ? (uint32_t)width : w.scene.width;
    uint32_t H = height ? (uint32_t)height : w.scene.height;
    struct trace_layout layout;
    trace_layout_default(&layout);
    struct shade_ctx sc = {&w.scene, RAY_MASK(RAY_PRIMARY), w.scene.seed};
    double best = 0;
    uint64_t rays = 0;
    for (uint64_t k = 0; k < repeat; k++) {
      struct tracer tr;
      tracer_init(&tr, &w.scene, &w.kd, mem_port_native(), &layout);
      struct framebuffer fb;
      fb_init(&fb, W, H, 0);
      struct render_stats st;
      memset(&st, 0, sizeof st);
      double t0 = app_now();
      struct policy_env env = {&tr, &sc, &fb, &st, NULL, NULL};
      struct policy_params pp;
      policy_params_default(&pp);
      policy_run(POLICY_RECURSIVE, &env, &pp);
      double s = app_now() - t0;
      fb_fini(&fb);
      rays = st.rays[RAY_PRIMARY];
      if (k == 0 || s < best) best = s;
    }
    printf("%s,%u,%u,%.3f,%u,%u,%llu,%.4f,%.0f\n", w.scene.name[0] ? w.scene.name : argv[i],
           w.scene.tri_count, w.kd.stats.nodes, w.build_s, W, H, (unsigned long long)rays, best,
           best > 0 ? (double)rays / best : 0.0);
    fflush(stdout);
    app_world_fini(&w);
  }
  return 0;
}
