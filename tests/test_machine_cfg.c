/* Machine configs: the shipped files load, default.yaml states the built-in
 * defaults, --set goes through the same checks, and every bad value is one
 * message naming file:line:col. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "sim/dram.h"
#include "sim/err.h"
#include "sim/machine_cfg.h"
#include "testing.h"

static void load_err(const char *file, char *out, unsigned cap) {
  char path[1024];
  snprintf(path, sizeof path, "%s/configs/%s", RTSIM_TEST_DATA, file);
  struct machine_cfg c;
  machine_cfg_defaults(&c);
  struct err e;
  memset(&e, 0, sizeof e);
  out[0] = '\0';
  if (machine_cfg_load(&c, path, &e)) machine_cfg_check(&c, &e);
  if (e.set) err_format(&e, out, cap);
}

static void set_err(const char *assignment, char *out, unsigned cap) {
  struct machine_cfg c;
  machine_cfg_defaults(&c);
  struct err e;
  memset(&e, 0, sizeof e);
  out[0] = '\0';
  if (machine_cfg_set(&c, assignment, &e)) machine_cfg_check(&c, &e);
  if (e.set) err_format(&e, out, cap);
}

/* docs/config-keys.md's key table is what `rtsim run --help-keys` prints from
 * the table of keys: a key added, renamed or redocumented without the manual
 * fails here (regenerate the lines between the markers with that command). */
static void test_readme_table(void) {
  char *readme = testing_slurp(RTSIM_SOURCE_DIR, "docs/config-keys.md", NULL);
  EXPECT(readme != NULL);
  if (!readme) return;
  const char *begin = strstr(readme, "--help-keys`, one row a key");
  const char *end = strstr(readme, "<!-- end of rtsim run --help-keys -->");
  begin = begin ? strstr(begin, "-->\n") : NULL;
  EXPECTF(begin && end && begin < end, "docs/config-keys.md has no marked key table%s", "");
  FILE *f = tmpfile();
  CHECK(f);
  machine_cfg_write_keys(f);
  long n = ftell(f);
  rewind(f);
  char *want = calloc((size_t)n + 1, 1);
  CHECK(want && fread(want, 1, (size_t)n, f) == (size_t)n);
  fclose(f);
  if (begin && end && begin < end) {
    begin += 4;
    const size_t have = (size_t)(end - begin);
    size_t same = 0;
    while (same < have && same < (size_t)n && begin[same] == want[same]) same++;
    EXPECTF(have == (size_t)n && same == have,
            "docs/config-keys.md's key table differs from rtsim run --help-keys at byte %zu: "
            "docs '%.60s', "
            "table '%.60s'",
            same, begin + same, want + same);
  }
  free(want);
  free(readme);
}

/* Parameters built in code (tests, bench) meet each key's range in the key
 * table itself, not in a copy of it: machine_params_problem (for the sample.*
 * keys, machine_cfg_sample_range_problem) names the key. */
static void test_params_ranges(void) {
  struct machine_cfg c;
  machine_cfg_defaults(&c);
  char buf[MACHINE_PROBLEM_MAX];
  EXPECT(machine_params_problem(&c.p, buf, sizeof buf) == NULL);
  EXPECT(machine_cfg_sample_range_problem(&c.sample, buf, sizeof buf) == NULL);
  static const struct {
    const char *key, *want;
  } cases[] = {
      {"cores", "cores: must be 1 to 4096"},
      {"clock_ghz", "clock_ghz: must be 0.001 to 1000 GHz"},
      {"l2.banks", "l2.banks: must be 1 to 4096"},
      {"l2.mshrs", "l2.mshrs: must be 1 to 2^20"},
      {"l2.ways", "l2.ways: must be 1 to 2^28 or full"},
      {"fidelity", "fidelity: expected one of: analytic, fixed, channel, banked"},
      {"dram.channels", "dram.channels: must be 1 to 64"},
      {"dram.banks_per_group", "dram.banks_per_group: must be 1 to 64"},
      {"dram.page_policy", "dram.page_policy: expected one of: open, close"},
      {"dram.queue_structure", "dram.queue_structure: expected one of: shared, per_bank, per_rank"},
      {"dram.command_queue", "dram.command_queue: must be 1 to 4096 entries"},
      {"dram.read_queue", "dram.read_queue: must be 1 to 4096 entries"},
      {"dram.clock_mhz", "dram.clock_mhz: must be 1 to 16000 MHz"},
      {"dram.tCL", "dram.tCL: must be 1 to 1000 DRAM cycles"},
      {"dram.tFAW", "dram.tFAW: must be 1 to 10000 DRAM cycles"},
      {"dram.bytes_per_cycle", "dram.bytes_per_cycle: must be 1e-06 to 10^6 bytes/cycle"},
      {"dram.latency", "dram.latency: must be 0 to 10^9 cycles"},
      {"dram.idle_drain_cycles", "dram.idle_drain_cycles: must be 0 to 10^7 DRAM cycles"},
      {"timeline.window", "timeline.window: must be 1 to 10^12 cycles"},
      {"sample.fraction", "sample.fraction: must be 1e-06 to 1"},
      {"sample.image", "sample.image: expected one of: sampled, whole"},
  };
  for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
    struct machine_cfg b;
    machine_cfg_defaults(&b);
    /* Out of range on whichever side the key has room: above its top, or 0
     * (or, for a double, NaN) below a bottom of 1. */
    const char *k = cases[i].key;
    if (!strcmp(k, "cores")) b.p.cores = 4097;
    else if (!strcmp(k, "clock_ghz")) b.p.clock_ghz = 0.0 / 0.0;
    else if (!strcmp(k, "l2.banks")) b.p.l2_banks = 0;
    else if (!strcmp(k, "l2.mshrs")) b.p.l2_mshrs = (1u << 20) + 1;
    else if (!strcmp(k, "l2.ways")) b.p.l2_ways = (1u << 28) + 1;
    else if (!strcmp(k, "fidelity")) b.p.fidelity = MACHINE_FIDELITY_COUNT;
    else if (!strcmp(k, "dram.channels")) b.p.dram_banked.channels = 128;
    else if (!strcmp(k, "dram.banks_per_group")) b.p.dram_banked.banks_per_group = 128;
    else if (!strcmp(k, "dram.page_policy")) b.p.dram_banked.page = (enum dram_banked_page)7;
    else if (!strcmp(k, "dram.queue_structure"))
      b.p.dram_banked.queue_structure = (enum dram_banked_queues)7;
    else if (!strcmp(k, "dram.command_queue")) b.p.dram_banked.command_queue = 4097;
    else if (!strcmp(k, "dram.read_queue")) b.p.dram_banked.read_queue = 0;
    else if (!strcmp(k, "dram.clock_mhz")) b.p.dram_clock_mhz = 0;
    else if (!strcmp(k, "dram.tCL")) b.p.dram_banked.tCL = 0;
    else if (!strcmp(k, "dram.tFAW")) b.p.dram_banked.tFAW = 1u << 21;
    else if (!strcmp(k, "dram.bytes_per_cycle")) b.p.dram_bytes_per_cycle = 0;
    else if (!strcmp(k, "dram.latency")) b.p.dram_latency_cycles = 1ull << 40;
    else if (!strcmp(k, "dram.idle_drain_cycles")) b.p.dram_banked.idle_drain_cycles = 10000001;
    else if (!strcmp(k, "timeline.window")) b.p.timeline_window_cycles = 0;
    else if (!strcmp(k, "sample.fraction")) b.sample.fraction = 1.5;
    else if (!strcmp(k, "sample.image")) b.sample.whole_image = 2;
    /* The sample.* keys are the run's, not the machine's: their own check. */
    const bool sample = !strncmp(k, "sample.", 7);
    const char *why = sample ? machine_cfg_sample_range_problem(&b.sample, buf, sizeof buf)
                             : machine_params_problem(&b.p, buf, sizeof buf);
    EXPECTF(why && !strcmp(why, cases[i].want), "%s: got '%s', want '%s'", k, why ? why : "NULL",
            cases[i].want);
  }
}

int main(void) {
  test_readme_table();
  test_params_ranges();
  static const struct {
    const char *file, *want;
  } bad[] = {
      {"bad_unknown_key.yaml",
       "bad_unknown_key.yaml:3:3: error: l2.sise: unknown key 'sise' (did you mean 'size'?)"},
      {"bad_top_key.yaml",
       "bad_top_key.yaml:1:1: error: core: unknown key 'core' (did you mean 'cores'?)"},
      {"bad_size_unit.yaml", "bad_size_unit.yaml:2:9: error: l2.size: not a size (got '4MB'"},
      {"bad_cores_zero.yaml",
       "bad_cores_zero.yaml:2:8: error: cores: out of range (got 0, expected 1 to 4096)"},
      {"bad_bandwidth_zero.yaml",
       "bad_bandwidth_zero.yaml:3:20: error: dram.bytes_per_cycle: out of range"},
      {"bad_l2_below_line.yaml",
       "bad_l2_below_line.yaml:2:9: error: l2.size: smaller than one 64-byte line (got 32 bytes)"},
      {"bad_ways_divide.yaml",
       "bad_ways_divide.yaml:3:9: error: l2.ways: the ways must divide the number of lines (got 3 ways for 64 lines)"},
      {"bad_section_type.yaml", "bad_section_type.yaml:1:5: error: l1: wrong type"},
      {"bad_ways_word.yaml",
       "bad_ways_word.yaml:2:9: error: l2.ways: not a number of ways (got 'all'"},
      {"bad_fraction.yaml",
       "bad_fraction.yaml:1:18: error: rays_per_thread: not a whole number (got '2.5'"},
      {"missing.yaml", "missing.yaml"},
      {"bad_mapping.yaml",
       "bad_mapping.yaml:3:12: error: dram.mapping: not an address mapping (got 'rochrabagco'"},
      {"bad_page.yaml",
       "bad_page.yaml:2:16: error: dram.page_policy: unknown value (got 'half', expected one of: open, close)"},
      {"bad_model.yaml",
       "bad_model.yaml:2:11: error: fidelity: unknown value (got 'ddr5', expected one of: analytic, fixed, channel, banked)"},
      {"bad_renamed_model.yaml",
       "bad_renamed_model.yaml:2:3: error: dram.model: renamed to fidelity, a top-level key"},
      {"bad_queue_structure.yaml",
       "bad_queue_structure.yaml:2:20: error: dram.queue_structure: unknown value (got 'per_channel', expected one of: shared, per_bank, per_rank)"},
      {"bad_dyn_sharing.yaml",
       "bad_dyn_sharing.yaml:2:12: error: dynamic.sharing: unknown value (got 'both', expected one of: partition, chip)"},
      {"bad_trc.yaml", "bad_trc.yaml:3:8: error: dram.tRC: must be at least tRAS (got 20)"},
      {"bad_include_missing.yaml", "bad_include_missing.yaml:1:10: error: include: "},
      {"bad_include_cycle.yaml", "error: include: included files nest deeper than 8"},
      {"bad_include_inner.yaml", "bad_include_inner.yaml:2:25: error: include: "},
      {"bad_include_map.yaml",
       "bad_include_map.yaml:2:3: error: include: expected a file name or a list of them"},
      /* #17: a NUL escape cut the value ("4\0xyz" read as 4); counts read 010
       * as octal 8 while sizes read it as 10; whitespace was skipped. */
      {"bad_nul.yaml",
       "bad_nul.yaml:2:8: error: a NUL character (\\0) in a value (got '4\\0...', expected text without one)"},
      {"bad_count_leading_zero.yaml",
       "bad_count_leading_zero.yaml:2:8: error: cores: not a whole number: a leading zero, ambiguous between octal and decimal (got '010', expected 1 to 4096)"},
      {"bad_size_leading_zero.yaml",
       "bad_size_leading_zero.yaml:2:9: error: l2.size: not a size: a leading zero, ambiguous between octal and decimal (got '010KiB'"},
      {"bad_number_space.yaml",
       "bad_number_space.yaml:1:12: error: clock_ghz: not a number: whitespace before or after it (got '\\n1.5', expected a decimal number)"},
  };
  char buf[2048];
  for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
    load_err(bad[i].file, buf, sizeof buf);
    EXPECTF(strstr(buf, bad[i].want) != NULL, "%s: got '%s'", bad[i].file, buf);
  }

  static const struct {
    const char *set, *want;
  } sets[] = {
      {"cores=0", "--set cores=0: error: cores: out of range (got 0, expected 1 to 4096)"},
      {"energy.l2_read=abc", "--set energy.l2_read=abc: error: energy.l2_read: not a number "
                             "(got 'abc', expected a decimal number)"},
      {"energy.l2_read=-5",
       "--set energy.l2_read=-5: error: energy.l2_read: out of range (got -5, expected -1 to "
       "1e+06)"},
      {"dram.IDD4R=1", "--set dram.IDD4R=1: error: dram.IDD4R: must be at least IDD3N (got 1)"},
      {"dram.VDD=0", "--set dram.VDD=0: error: dram.VDD: out of range (got 0, expected 0.1 to 10)"},
      {"l2.size=32", "--set l2.size=32: error: l2.size: smaller than one 64-byte line"},
      {"dram.bytes_per_cycle=0",
       "--set dram.bytes_per_cycle=0: error: dram.bytes_per_cycle: out of range"},
      {"l2.sise=1", "--set l2.sise=1: error: unknown key 'l2.sise' (did you mean 'l2.size'?)"},
      {"l2.szie=1", "unknown key 'l2.szie' (did you mean 'l2.size'?)"},
      {"size=1", "unknown key 'size' (did you mean 'l1.size' or 'l2.size'?)"},
      {"frobnicate=1",
       "unknown key 'frobnicate' (no key is near it; 'rtsim run --help-keys' lists all"},
      {"cores", "expected KEY=VALUE"},
      {"l2.ways=full", ""},
      {"l2.size=1MiB", ""},
      {"dram.bytes_per_cycle=0.01",
       "--set dram.bytes_per_cycle=0.01: error: dram.bytes_per_cycle: not read by fidelity banked (set fidelity to a rung that uses it) (got 0.01)"},
      {"l1.size=0", ""},
      {"l2.ways=7",
       "--set l2.ways=7: error: l2.ways: the ways must divide the number of lines (got 7 ways for 65536 lines)"},
      {"l2.size=4000", "l2.size: not a whole number of 64-byte lines (got 4000 bytes)"},
      {"dram.tRC=10", "--set dram.tRC=10: error: dram.tRC: must be at least tRAS (got 10)"},
      {"dram.mapping=coco", "--set dram.mapping=coco: error: dram.mapping: not an address mapping"},
      {"dram.page_policy=close", ""},
      {"fidelity=banked", ""},
      {"fidelity=analytic", ""},
      {"fidelity=lazy",
       "--set fidelity=lazy: error: fidelity: unknown value (got 'lazy', expected one of: analytic, fixed, channel, banked)"},
      {"dram.model=banked",
       "--set dram.model=banked: error: dram.model: renamed to fidelity, a top-level key"},
      {"dram.queue_structure=shared", ""},
      {"dram.command_queue=0",
       "--set dram.command_queue=0: error: dram.command_queue: out of range (got 0, expected 1 to 4096)"},
      {"dram.controller_cycles=0",
       "--set dram.controller_cycles=0: error: dram.controller_cycles: must be at least 1 with queue_structure per_bank or per_rank"},
      /* Strict values (sim/scalar.h), one rule for counts and sizes. */
      {"cores=10", ""},
      {"cores=010",
       "--set cores=010: error: cores: not a whole number: a leading zero, ambiguous between octal and decimal (got '010', expected 1 to 4096)"},
      {"cores=0x10",
       "--set cores=0x10: error: cores: not a whole number (got '0x10', expected 1 to 4096)"},
      {"cores=+4", "cores: not a whole number (got '+4'"},
      {"cores= 4",
       "--set cores= 4: error: cores: not a whole number: whitespace before or after it (got ' 4'"},
      {"cores=4 ", "cores: not a whole number: whitespace before or after it (got '4 '"},
      {"cores=", "--set cores=: error: cores: not a whole number: empty (got ''"},
      {"cores=99999999999999999999",
       "cores: out of range (got 99999999999999999999, expected 1 to 4096)"},
      {"sample.seed=007", "sample.seed: not a whole number: a leading zero"},
      {"l2.size=1024KiB", ""},
      {"l2.size=010KiB",
       "--set l2.size=010KiB: error: l2.size: not a size: a leading zero, ambiguous between octal and decimal (got '010KiB'"},
      {"l2.size=01024", "l2.size: not a size: a leading zero"},
      {"l1.size=00", "l1.size: not a size: a leading zero"},
      {"l2.size= 1MiB", "l2.size: not a size: whitespace before or after it (got ' 1MiB'"},
      {"l2.size=1MiB ", "l2.size: not a size: whitespace before or after it"},
      {"l2.size=1 MiB", "l2.size: not a size (got '1 MiB'"},
      {"l2.size=KiB", "l2.size: not a size (got 'KiB'"},
      {"l2.size=18446744073709551615KiB", "l2.size: out of range (got 18446744073709551615KiB"},
      {"l2.ways=08",
       "--set l2.ways=08: error: l2.ways: not a number of ways: a leading zero, ambiguous between octal and decimal (got '08', expected 1 to 268435456 or full)"},
      {"l2.ways= full",
       "l2.ways: not a number of ways: whitespace before or after it (got ' full'"},
      {"clock_ghz= 2",
       "--set clock_ghz= 2: error: clock_ghz: not a number: whitespace before or after it (got ' 2', expected a decimal number)"},
      {"clock_ghz=\n1.5",
       "--set clock_ghz=\\n1.5: error: clock_ghz: not a number: whitespace before or after it (got '\\n1.5'"},
      {"clock_ghz=01.5", "clock_ghz: not a number: a leading zero"},
      {"clock_ghz=0.5", ""},
      {"clock_ghz=inf", "clock_ghz: not a number (got 'inf'"},
      {"dram.mapping=rochrababgco ",
       "--set dram.mapping=rochrababgco : error: dram.mapping: not an address mapping"},
      {"fidelity= banked", "fidelity: unknown value (got ' banked'"},
  };
  for (size_t i = 0; i < sizeof sets / sizeof sets[0]; i++) {
    set_err(sets[i].set, buf, sizeof buf);
    if (!sets[i].want[0]) EXPECTF(buf[0] == '\0', "%s: unexpected '%s'", sets[i].set, buf);
    else EXPECTF(strstr(buf, sets[i].want) != NULL, "%s: got '%s'", sets[i].set, buf);
  }

  /* The shipped configs load; default.yaml is the built-in default. */
  const char *shipped[] = {"default.yaml", "paper-2007.yaml", "tiny.yaml"};
  for (int i = 0; i < 3; i++) {
    char path[1024];
    snprintf(path, sizeof path, "%s/configs/%s", RTSIM_SOURCE_DIR, shipped[i]);
    struct machine_cfg c;
    machine_cfg_defaults(&c);
    struct err e;
    memset(&e, 0, sizeof e);
    EXPECTF(machine_cfg_load(&c, path, &e) && machine_cfg_check(&c, &e), "%s: %s", shipped[i],
            e.msg);
    if (i == 0) {
      struct machine_cfg d;
      machine_cfg_defaults(&d);
      for (unsigned k = 0; k < machine_cfg_count(); k++) {
        char a[64], b[64];
        machine_cfg_value(&c, k, a, sizeof a);
        machine_cfg_value(&d, k, b, sizeof b);
        EXPECTF(!strcmp(a, b), "default.yaml %s = %s, built-in %s", machine_cfg_key(k), a, b);
      }
    }
  }
  /* An error inside an included file names that file too. */
  load_err("bad_include_inner.yaml", buf, sizeof buf);
  EXPECTF(strstr(buf, "bad_cores_zero.yaml:2:8: error: cores: out of range") != NULL, "got '%s'",
          buf);

  /* Presets: include reads the fragment first, the file's own keys win. */
  {
    char path[1024];
    snprintf(path, sizeof path, "%s/configs/dram/ddr4-2400-2ch.yaml", RTSIM_SOURCE_DIR);
    struct machine_cfg p2;
    machine_cfg_defaults(&p2);
    struct err pe;
    memset(&pe, 0, sizeof pe);
    EXPECTF(machine_cfg_load(&p2, path, &pe) && machine_cfg_check(&p2, &pe), "%s", pe.msg);
    EXPECT(p2.p.fidelity == MACHINE_FIDELITY_BANKED && p2.p.dram_banked.channels == 2 &&
           p2.p.dram_banked.tCL == 17 && !strcmp(p2.p.dram_banked.mapping, "rorababgchco"));
    const char *presets[] = {"ddr4-2400.yaml", "hbm2.yaml"};
    for (int i = 0; i < 2; i++) {
      snprintf(path, sizeof path, "%s/configs/dram/%s", RTSIM_SOURCE_DIR, presets[i]);
      machine_cfg_defaults(&p2);
      memset(&pe, 0, sizeof pe);
      EXPECTF(machine_cfg_load(&p2, path, &pe) && machine_cfg_check(&p2, &pe), "%s: %s", presets[i],
              pe.msg);
    }
  }

  /* The analytic rung reads the channel's latency and bandwidth for its
   * bounds, nothing else of the DRAM: a dram key for another rung, set after
   * fidelity, is refused where it was written. */
  {
    static const struct {
      const char *second, *want;
    } after[] = {
        {"dram.latency=100", ""},
        {"dram.bytes_per_cycle=4", ""},
        {"dram.queue_depth=4",
         "--set dram.queue_depth=4: error: dram.queue_depth: not read by fidelity analytic"},
        {"dram.tRC=60", "--set dram.tRC=60: error: dram.tRC: not read by fidelity analytic"},
    };
    for (size_t i = 0; i < sizeof after / sizeof after[0]; i++) {
      struct machine_cfg a;
      machine_cfg_defaults(&a);
      struct err ae;
      memset(&ae, 0, sizeof ae);
      bool ok = machine_cfg_set(&a, "fidelity=analytic", &ae) &&
                machine_cfg_set(&a, after[i].second, &ae) && machine_cfg_check(&a, &ae);
      buf[0] = '\0';
      if (!ok) err_format(&ae, buf, sizeof buf);
      if (!after[i].want[0])
        EXPECTF(ok, "%s after fidelity=analytic: got '%s'", after[i].second, buf);
      else
        EXPECTF(!ok && strstr(buf, after[i].want), "%s after fidelity=analytic: got '%s'",
                after[i].second, buf);
    }
  }

  /* A --set after the file wins, and is reported as the value. */
  struct machine_cfg c;
  machine_cfg_defaults(&c);
  struct err e;
  memset(&e, 0, sizeof e);
  EXPECT(machine_cfg_set(&c, "l2.size=512KiB", &e) && c.p.l2_size_bytes == 512u * 1024u);
  EXPECT(machine_cfg_set(&c, "clock_ghz=2.5", &e) && c.p.clock_ghz == 2.5);
  char v[64];
  machine_cfg_value(&c, 0, v, sizeof v);
  EXPECT(!strcmp(v, "2.5"));

  /* A value set with its position (a sweep file's axis value) is reported
   * there, both when it is read and when a relation check fails later. */
  EXPECT(machine_cfg_find("l2.ways") >= 0 && machine_cfg_find("l2.way") == -1);
  unsigned ways = (unsigned)machine_cfg_find("l2.ways");
  machine_cfg_defaults(&c);
  memset(&e, 0, sizeof e);
  EXPECT(!machine_cfg_set_at(&c, ways, "many", "s.yaml", 4, 12, &e));
  err_format(&e, buf, sizeof buf);
  EXPECTF(strstr(buf, "s.yaml:4:12: error: l2.ways: not a number of ways (got 'many'"), "got '%s'",
          buf);
  memset(&e, 0, sizeof e);
  EXPECT(machine_cfg_set_at(&c, ways, "7", "s.yaml", 5, 3, &e) && !machine_cfg_check(&c, &e));
  err_format(&e, buf, sizeof buf);
  EXPECTF(strstr(buf, "s.yaml:5:3: error: l2.ways: the ways must divide"), "got '%s'", buf);
  return testing_done("test_machine_cfg");
}
