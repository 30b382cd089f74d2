/* Machine configs: YAML files (through cfg) and --set KEY=VALUE overrides into
 * struct machine_params, every key checked where it was written (file:line:col
 * or the --set that gave it). The key names are a stable interface: they are
 * the YAML keys, the --set names, and the config columns of stats files.
 * Every key has a default (configs/default.yaml states the same values and
 * where each comes from); a file or --set changes only what it names. */
#ifndef RTSIM_SIM_MACHINE_CFG_H
#define RTSIM_SIM_MACHINE_CFG_H

#include <stdbool.h>
#include <stddef.h>
#include <stdio.h>

#include "sim/machine.h"

struct err;
struct stats_table;

/* Room for the keys (the table in machine_cfg.c; a compile-time check). */
#define MACHINE_CFG_KEYS_MAX 96

/* Where each key's value came from, for errors found after reading. */
struct machine_cfg_origin {
  char file[320]; /* "" : the default */
  int line, col;
  bool included; /* set by a file another one included (a preset) */
  unsigned seq;  /* order of setting (0: the default) */
};

/* What a machine config says about the work run on the machine rather than
 * about the machine: the compute the renderer announces per step (its
 * kernel's costs on these cores) and how the dynamic and treelet policies
 * share queue points among the cores. Not in struct machine_params: the
 * machine never reads them; the program hands them to the renderer. */
struct machine_cfg_work {
  uint32_t cost_node_cycles, cost_triangle_cycles, cost_shade_cycles;
  uint32_t dyn_sharing; /* renderer/policy/policy.h: 0 partition, 1 chip */
};

/* How a timed run is sampled (docs/fidelity-and-sampling.md; app/sample.h): the share of
 * work items simulated in detail (1: all, no sampling), the strata (one
 * detailed unit each), the items warmed functionally before a unit as a
 * multiple of its detailed items, the seed of the units' places. Not in
 * struct machine_params: the machine never reads them; the run does. */
struct machine_cfg_sample {
  double fraction;
  uint32_t units;
  double warming;
  uint32_t whole_image;   /* 1: every item traced (sample.image: whole) */
  uint32_t prepass;       /* sampled image: the pre-pass counts one item in this many (0: none) */
  uint32_t stretch;       /* the pre-pass's stretches, items (0: the ray contexts) */
  double stretch_warming; /* items warmed before a stretch or unit window, x the ray contexts */
  uint64_t seed;
};

struct machine_cfg {
  struct machine_params p;
  struct machine_cfg_work work;
  struct machine_cfg_sample sample;
  struct machine_cfg_origin at[MACHINE_CFG_KEYS_MAX]; /* [0, machine_cfg_count()) */
  unsigned seq;                                       /* settings so far */
};

/* The default machine (configs/default.yaml). */
void machine_cfg_defaults(struct machine_cfg *c);
/* Read a YAML machine config over the values c holds. A top-level
 * `include: FILE` (or a list of files), relative to the file's folder, is read
 * first, so the file's own keys override it (presets: configs/dram/). On bad
 * input fills e (file:line:col) and returns false. */
bool machine_cfg_load(struct machine_cfg *c, const char *path, struct err *e);
/* Apply one "key=value" (the value as it would be written in YAML). */
bool machine_cfg_set(struct machine_cfg *c, const char *assignment, struct err *e);
/* A one-line hint for a key name rtsim no longer reads and what replaces it
 * (dram.model: fidelity), or NULL for any other name. */
const char *machine_cfg_renamed(const char *name);
/* Index of key `name` ("l2.size"), or -1 when there is no such key. */
int machine_cfg_find(const char *name);
/* Set key i from `value` (text as written in YAML), which was written at
 * file:line:col (0 when unknown): errors now, and relation errors found by
 * machine_cfg_check later, are reported there. Same checks as a file's. */
bool machine_cfg_set_at(struct machine_cfg *c, unsigned i, const char *value, const char *file,
                        int line, int col, struct err *e);
/* Check relations between keys (a cache that holds whole lines, ways that
 * divide them, ...), naming the key at fault where it was written. */
bool machine_cfg_check(const struct machine_cfg *c, struct err *e);

/* NULL if every key p holds is within its row's range (the check a config's
 * value gets as it is read, for parameters built in code), else "key: must
 * be LO to HI ..." in buf. Relations between keys are machine_params_problem's. */
const char *machine_cfg_range_problem(const struct machine_params *p, char *buf, size_t cap);
/* The same for the sample.* keys s holds (for sampling set in code). */
const char *machine_cfg_sample_range_problem(const struct machine_cfg_sample *s, char *buf,
                                             size_t cap);

/* How many keys there are; key i's name (dotted; NULL past the last), its
 * unit as the key table states it ("bytes", "DRAM cycles"; "" for a count or
 * a name; NULL past the last) and its value as text ("4194304", "full", "0.5"). */
unsigned machine_cfg_count(void);
const char *machine_cfg_key(unsigned i);
const char *machine_cfg_unit(unsigned i);
void machine_cfg_value(const struct machine_cfg *c, unsigned i, char *buf, unsigned cap);
/* "key, key, ...": every key, for messages (cut to cap). */
void machine_cfg_key_list(char *buf, size_t cap);
/* Every key as a JSON member `"key": value` (numbers, or "full"). */
void machine_cfg_write_json(const struct machine_cfg *c, FILE *f, const char *indent);
/* Every key as a row of a Markdown table: name, default, range, unit, the
 * fidelity rungs that read it, what it is (docs/config-keys.md's key table; rtsim run
 * --help-keys). */
void machine_cfg_write_keys(FILE *f);
/* Every key as a column of t (numbers as numbers, "full" as text). */
void machine_cfg_to_stats(const struct machine_cfg *c, struct stats_table *t);
/* A rung's name as the fidelity key takes it ("analytic", ...; f < MACHINE_FIDELITY_COUNT). */
const char *machine_cfg_fidelity_name(uint32_t f);

#endif
