/* libFuzzer target: --set KEY=VALUE overrides (machine_cfg_set). The input is
 * a list of assignments separated by NUL bytes (a command line's arguments
 * cannot hold one; they can hold a newline), applied in order over the
 * default machine as `rtsim run --set A --set B` does (app_machine_load);
 * then the relations between keys are checked. Every refusal is one line;
 * every accepted config's values must print and read back the same. */
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "sim/err.h"
#include "sim/machine_cfg.h"
#include "tests/fuzz/fuzz_util.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
  char *text = malloc(size + 1);
  CHECK(text != NULL);
  if (size) memcpy(text, data, size);
  text[size] = '\0';
  static struct machine_cfg c;
  struct err e;
  memset(&e, 0, sizeof e);
  machine_cfg_defaults(&c);
  bool ok = true;
  for (size_t at = 0; ok && at < size; at += strlen(text + at) + 1)
    ok = machine_cfg_set(&c, text + at, &e);
  if (ok) ok = machine_cfg_check(&c, &e);
  free(text);
  if (!ok) {
    fuzz_check_err(&e);
    return 0;
  }
  CHECK(!e.set);
  fuzz_check_machine(&c);
  return 0;
}
