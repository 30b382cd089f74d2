/* libFuzzer target: machine configs (sim/machine_cfg.c through sim/cfg.c).
 * The input is a YAML file in configs/ of the scratch folder, so an include
 * of a DRAM preset (dram/ddr4-2400.yaml) resolves as in the repository. Any
 * bytes must give a config that passes machine_cfg_check, or one error on one
 * line; every accepted config's values must print and read back the same. */
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>

#include "sim/err.h"
#include "sim/machine_cfg.h"
#include "tests/fuzz/fuzz_util.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
  const char *path = fuzz_file("configs/fuzz.yaml", data, size);
  static struct machine_cfg c;
  struct err e;
  memset(&e, 0, sizeof e);
  machine_cfg_defaults(&c);
  if (!machine_cfg_load(&c, path, &e) || !machine_cfg_check(&c, &e)) {
    fuzz_check_err(&e);
    return 0;
  }
  CHECK(!e.set);
  fuzz_check_machine(&c);
  return 0;
}
