/* rtsim: entry point. Hands the command line to the subcommand, whose exit
 * code it returns (the shared helpers are in app.c). */
#include "app/app.h"

#include <stdio.h>
#include <string.h>

#include "sim/near.h"

/* Every command: its name, its entry, its lines in the usage text. The
 * unknown-command message and the manual page take the names from here too. */
static const struct app_command COMMANDS[] = {
    {"render", cmd_render,
     "  render SCENE.yaml -o IMAGE.exr   ray trace a scene to an OpenEXR image\n"},
    {"export", cmd_export,
     "  export SCENE.yaml -o SCENE.ply   write the scene's triangles (face i = primitive i)\n"},
    {"hits", cmd_hits,
     "  hits SCENE.yaml                  nearest hits for rays read as CSV on stdin\n"},
    {"traffic", cmd_traffic,
     "  traffic SCENE.yaml --rays R -o T.csv  DRAM-to-L2 traffic of the scheduling\n"
     "                                   policies for every cache size, 1 KB to 4 MB\n"},
    {"trace", cmd_trace,
     "  trace SCENE.yaml --din FILE ...  the access stream as a Dinero IV din trace\n"},
    {"run", cmd_run,
     "  run MACHINE.yaml SCENE.yaml -o DIR  render on the timed many-core machine:\n"
     "                                   cycles, utilization, L2 and DRAM statistics\n"},
    {"sweep", cmd_sweep,
     "  sweep SWEEP.yaml -o DIR          run a sweep file's points (machine configs x\n"
     "                                   workloads) in parallel, resumable; or print\n"
     "                                   them as jobs for GNU parallel or Slurm\n"},
    {"merge", cmd_merge,
     "  merge DIR -o TABLE.csv           a sweep's complete points as one tidy table\n"},
    {"plot", cmd_plot,
     "  plot TABLE.csv --x K --y M -o F  figures of a merged table (PNG, PDF or SVG)\n"},
    {"bench", cmd_bench,
     "  bench SCENE.yaml...              primary-ray throughput (rays/s) per scene\n"},
    {"dram-replay", cmd_dram_replay,
     "  dram-replay MACHINE.yaml TRACE   replay a trace of DRAM requests (rtsim's,\n"
     "                                   DRAMsim3's or Ramulator's) on the DRAM alone\n"},
};
#define NCOMMANDS (sizeof COMMANDS / sizeof COMMANDS[0])

/* The program's usage: the commands, an example, where to read more (also
 * the manual page's description). */
static void usage_text(char *buf, size_t cap) {
  size_t n = (size_t)snprintf(buf, cap, "usage: rtsim COMMAND [options]\n\ncommands:\n");
  for (size_t i = 0; i < NCOMMANDS && n < cap; i++)
    n += (size_t)snprintf(buf + n, cap - n, "%s", COMMANDS[i].usage);
  if (n < cap)
    snprintf(buf + n, cap - n,
             "\nexample (a timed run on the default machine, its summary on stdout):\n"
             "  rtsim run configs/default.yaml scenes/small/room.yaml --width 32 --height 32 \\\n"
             "      -o build/run-room\n"
             "\nRun 'rtsim COMMAND --help' for a command's options and an example,\n"
             "'rtsim COMMAND --help-full' for its reference; 'man rtsim' has them all.\n");
}

static void usage(FILE *f) {
  char text[4096];
  usage_text(text, sizeof text);
  fputs(text, f);
}

int main(int argc, char **argv) {
  if (argc < 2) {
    usage(stderr);
    return APP_EXIT_USAGE;
  }
  const char *cmd = argv[1];
  if (!strcmp(cmd, "--help") || !strcmp(cmd, "-h") || !strcmp(cmd, "help")) {
    usage(stdout);
    return 0;
  }
  if (!strcmp(cmd, "--man")) {
    char text[4096];
    usage_text(text, sizeof text);
    return app_man(stdout, text, COMMANDS, NCOMMANDS);
  }
  char names[256] = "";
  for (size_t i = 0; i < NCOMMANDS; i++) {
    if (!strcmp(cmd, COMMANDS[i].name)) return COMMANDS[i].run(argc - 1, argv + 1);
    snprintf(names + strlen(names), sizeof names - strlen(names), "%s%s", i ? ", " : "",
             COMMANDS[i].name);
  }
  char near[128];
  if (near_words(cmd, names, near, sizeof near))
    fprintf(stderr, "rtsim: error: unknown command '%s' (did you mean %s?)\n", cmd, near);
  else fprintf(stderr, "rtsim: error: unknown command '%s' (expected one of: %s)\n", cmd, names);
  return APP_EXIT_USAGE;
}
