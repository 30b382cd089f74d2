/* rtsim: entry point. Hands the command line to the subcommand, whose exit
 * code it returns (the shared helpers are in app.c). */
#include "app/app.h"

#include <stdio.h>
#include <string.h>

static const char USAGE[] =
    "usage: rtsim COMMAND [options]\n"
    "\n"
    "commands:\n"
    "  render SCENE.yaml -o IMAGE.exr   ray trace a scene to an OpenEXR image\n"
    "  export SCENE.yaml -o SCENE.ply   write the scene's triangles (face i = primitive i)\n"
    "  hits SCENE.yaml                  nearest hits for rays read as CSV on stdin\n"
    "  traffic SCENE.yaml --rays R -o T.csv  DRAM-to-L2 traffic of the scheduling\n"
    "                                   policies for every cache size, 1 KB to 4 MB\n"
    "  trace SCENE.yaml --din FILE ...  the access stream as a Dinero IV din trace\n"
    "  run MACHINE.yaml SCENE.yaml -o DIR  render on the timed many-core machine:\n"
    "                                   cycles, utilization, L2 and DRAM statistics\n"
    "  sweep SWEEP.yaml -o DIR          run a sweep file's points (machine configs x\n"
    "                                   workloads) in parallel, resumable; or print\n"
    "                                   them as jobs for GNU parallel or Slurm\n"
    "  merge DIR -o TABLE.csv           a sweep's complete points as one tidy table\n"
    "  plot TABLE.csv --x K --y M -o F  line plots of a merged table (PNG or SVG)\n"
    "  bench SCENE.yaml...              primary-ray throughput (rays/s) per scene\n"
    "  dram-replay MACHINE.yaml TRACE   replay a trace of DRAM requests (rtsim's,\n"
    "                                   DRAMsim3's or Ramulator's) on the DRAM alone\n"
    "\n"
    "Run 'rtsim COMMAND --help' for a command's options.\n";

int main(int argc, char **argv) {
  if (argc < 2) {
    fputs(USAGE, stderr);
    return APP_EXIT_USAGE;
  }
  const char *cmd = argv[1];
  if (!strcmp(cmd, "--help") || !strcmp(cmd, "-h") || !strcmp(cmd, "help")) {
    fputs(USAGE, stdout);
    return 0;
  }
  if (!strcmp(cmd, "render")) return cmd_render(argc - 1, argv + 1);
  if (!strcmp(cmd, "export")) return cmd_export(argc - 1, argv + 1);
  if (!strcmp(cmd, "hits")) return cmd_hits(argc - 1, argv + 1);
  if (!strcmp(cmd, "bench")) return cmd_bench(argc - 1, argv + 1);
  if (!strcmp(cmd, "traffic")) return cmd_traffic(argc - 1, argv + 1);
  if (!strcmp(cmd, "trace")) return cmd_trace(argc - 1, argv + 1);
  if (!strcmp(cmd, "run")) return cmd_run(argc - 1, argv + 1);
  if (!strcmp(cmd, "sweep")) return cmd_sweep(argc - 1, argv + 1);
  if (!strcmp(cmd, "merge")) return cmd_merge(argc - 1, argv + 1);
  if (!strcmp(cmd, "plot")) return cmd_plot(argc - 1, argv + 1);
  if (!strcmp(cmd, "dram-replay")) return cmd_dram_replay(argc - 1, argv + 1);
  fprintf(stderr, "rtsim: error: unknown command '%s' (expected one of: render, export, hits, traffic, trace, run, sweep, merge, plot, bench, dram-replay)\n",
          cmd);
  return APP_EXIT_USAGE;
}
