/* libFuzzer target: rtsim dram-replay's trace reader (sim/dram_trace_read.c)
 * and the replay it drives, on configs/default.yaml's DRAM. The input's first
 * line is options, separated by spaces: each word fidelity=..., clock_ghz=...
 * or dram.<key>=... is passed as --set, and the word per-request adds
 * --per-request (a file in the scratch folder); other words are dropped. The
 * rest of the input is the trace. Any bytes must give exit 0 (one CSV row)
 * or 2 (one message); never a crash, a failed check or a hang. */
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>

#include "app/app.h"
#include "sim/err.h"
#include "tests/fuzz/fuzz_util.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

#define FUZZ_REPLAY_SETS 16

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
  /* argv's strings stay valid between runs: the option parser may keep
   * pointers into them. */
  static char line[1024], trace[1024], machine[1024], per[1024],
      cmd[] = "dram-replay", set[] = "--set", per_opt[] = "--per-request";
  const uint8_t *nl = memchr(data, '\n', size);
  size_t head = nl ? (size_t)(nl - data) : size;
  size_t keep = head < sizeof line - 1 ? head : sizeof line - 1;
  memcpy(line, data, keep);
  line[keep] = '\0';
  size_t rest = nl ? size - head - 1 : 0;
  snprintf(trace, sizeof trace, "%s", fuzz_file("trace.txt", nl ? nl + 1 : data, rest));
  snprintf(machine, sizeof machine, "%s/configs/default.yaml", fuzz_dir());
  snprintf(per, sizeof per, "%s/per-request.txt", fuzz_dir());

  char *argv[2 * FUZZ_REPLAY_SETS + 8];
  int argc = 0;
  argv[argc++] = cmd;
  unsigned sets = 0;
  for (char *t = strtok(line, " "); t; t = strtok(NULL, " ")) {
    if (!strcmp(t, "per-request")) {
      argv[argc++] = per_opt;
      argv[argc++] = per;
    } else if (sets < FUZZ_REPLAY_SETS &&
               (!strncmp(t, "fidelity=", 9) || !strncmp(t, "clock_ghz=", 10) ||
                !strncmp(t, "dram.", 5))) {
      argv[argc++] = set;
      argv[argc++] = t;
      sets++;
    }
    if (argc > 2 * FUZZ_REPLAY_SETS + 2) break;
  }
  argv[argc++] = machine;
  argv[argc++] = trace;
  argv[argc] = NULL;
  int rc = cmd_dram_replay(argc, argv);
  CHECK(rc == 0 || rc == 2);
  return 0;
}
