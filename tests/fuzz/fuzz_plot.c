/* libFuzzer target: rtsim plot's table reading (app/csv.c) and everything it
 * does with the table before gnuplot (app/plot_figure.c: columns, --where,
 * distinct lines and panels, numbers, log scales, rows that collide). The
 * input's first line is plot's options, separated by spaces; only --x, --y,
 * --lines, --panels, --where, --logx, --logy, --mark-x, --bars, --stack,
 * --own-y and --yrange are passed on (with their values), and -o names a
 * file in a folder that does not exist, so a table that passes every check
 * stops there (exit 1) and gnuplot never runs.
 * The rest of the input is the table. Any bytes must give exit 1 or 2 (one
 * message); never a crash or a hang. */
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>

#include "app/app.h"
#include "sim/err.h"
#include "tests/fuzz/fuzz_util.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

#define FUZZ_PLOT_ARGS 64

/* Options passed on, and whether each takes a value. */
static const struct {
  const char *name;
  bool value;
} OPTIONS[] = {{"--x", true},     {"--y", true},      {"--lines", true},  {"--panels", true},
               {"--where", true}, {"--logx", false},  {"--logy", false},  {"--mark-x", true},
               {"--bars", false}, {"--stack", false}, {"--own-y", false}, {"--yrange", true}};

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
  /* argv's strings stay valid between runs: getopt keeps a pointer into them. */
  static char line[1024], table[1024], out[1024], cmd[] = "plot", dash_o[] = "-o";
  const uint8_t *nl = memchr(data, '\n', size);
  size_t head = nl ? (size_t)(nl - data) : size;
  size_t keep = head < sizeof line - 1 ? head : sizeof line - 1;
  memcpy(line, data, keep);
  line[keep] = '\0';
  size_t rest = nl ? size - head - 1 : 0;
  snprintf(table, sizeof table, "%s", fuzz_file("table.csv", nl ? nl + 1 : data, rest));
  snprintf(out, sizeof out, "%s/no-such-folder/plot.png", fuzz_dir());

  char *argv[FUZZ_PLOT_ARGS + 5];
  int argc = 0;
  argv[argc++] = cmd;
  char *tok[FUZZ_PLOT_ARGS];
  unsigned ntok = 0;
  for (char *t = strtok(line, " "); t && ntok < FUZZ_PLOT_ARGS; t = strtok(NULL, " "))
    tok[ntok++] = t;
  for (unsigned i = 0; i < ntok; i++)
    for (unsigned k = 0; k < sizeof OPTIONS / sizeof OPTIONS[0]; k++) {
      if (strcmp(tok[i], OPTIONS[k].name)) continue;
      if (OPTIONS[k].value && i + 1 == ntok) break;
      argv[argc++] = tok[i];
      if (OPTIONS[k].value) argv[argc++] = tok[++i];
      break;
    }
  argv[argc++] = dash_o;
  argv[argc++] = out;
  argv[argc++] = table;
  argv[argc] = NULL;
  int rc = cmd_plot(argc, argv);
  CHECK(rc == 1 || rc == 2);
  return 0;
}
