/* rtsim bench --timed MACHINE.yaml --policies LIST: the host cost of whole
 * `rtsim run` processes, one policy against another on the same machine and
 * image (the dynamic policy's target: within 2x the recursive policy's host
 * time, events and memory on a machine of mostly idle contexts). Each run is
 * a fresh process of this program, as a user runs it, so its first touches
 * of memory, its scene load and its output files are all counted. */
#ifndef RTSIM_APP_BENCH_POLICIES_H
#define RTSIM_APP_BENCH_POLICIES_H

#include <stdbool.h>
#include <stdint.h>

#include "renderer/policy/policy.h"

#define BENCH_POLICIES_MAX 8

/* An OPTS_PARSE destination: policy names separated by commas, at least two,
 * each once. */
struct bench_policy_list {
  enum policy_kind k[BENCH_POLICIES_MAX];
  unsigned n;
};
bool bench_parse_policies(const char *text, void *dst);
#define BENCH_POLICIES_EXPECT                                                                      \
  "two or more of recursive, packet, dynamic, treelet, separated by commas"

/* An OPTS_PARSE destination for --levels: rungs of the fidelity ladder
 * (analytic, fixed, channel, banked) or native (rtsim render of the same
 * image: the renderer alone), at least two, each once. */
struct bench_level_list {
  char name[BENCH_POLICIES_MAX][12];
  unsigned n;
};
bool bench_parse_levels(const char *text, void *dst);
#define BENCH_LEVELS_EXPECT                                                                        \
  "two or more of native, analytic, fixed, channel, banked, separated by commas"

struct app_sets;

/* For each scene: `rounds` rounds, each running every policy of l in turn
 * (l NULL: every level of lv, with policy `policy`); prints the CSV rows (one
 * per scene and policy or level) on stdout. sets: --set assignments for
 * every run; width, height 0: the scene's. Returns the exit code: 0,
 * APP_EXIT_USAGE for a config refused before any run, or a failed run's own
 * (its stderr shown). */
int bench_policies(const char *machine, const struct app_sets *sets,
                   const struct bench_policy_list *l, const struct bench_level_list *lv,
                   enum policy_kind policy, uint32_t mask, uint64_t width, uint64_t height,
                   uint64_t rounds, int argc, char **argv, int first_scene);

#endif
