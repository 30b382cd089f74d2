/* One table of keys drives reading, --set, checking and writing. */
#include "sim/machine_cfg.h"

#include <math.h>
#include <stddef.h>
#include <stdlib.h>
#include <string.h>

#include "sim/cfg.h"
#include "sim/dram_banked.h"
#include "sim/err.h"
#include "sim/scalar.h"
#include "sim/stats.h"

enum kind { K_U32, K_U64, K_F64, K_SIZE, K_WAYS, K_ENUM, K_MAPPING };

struct key {
  const char *name; /* "section.key" or "key" */
  enum kind kind;
  double lo, hi;
  size_t off;
  const char *const *names; /* K_ENUM: the values' names (a uint32_t index), hi + 1 of them */
};

#define OFF(f) offsetof(struct machine_params, f), NULL
static const char *const PAGE_NAMES[] = {"open", "close"};
static const char *const FIDELITY_NAMES[MACHINE_FIDELITY_COUNT] = {"analytic", "fixed", "channel",
                                                                   "banked"};
static const char *const QUEUE_NAMES[] = {"shared", "per_bank", "per_rank"}; /* enum dram_banked_queues */
static const char *const SHARING_NAMES[] = {"partition", "chip"}; /* renderer/policy.h */
static const struct key KEYS[MACHINE_CFG_KEYS] = {
    {"clock_ghz", K_F64, 1e-3, 1e3, OFF(clock_ghz)},
    {"cores", K_U32, 1, 4096, OFF(cores)},
    {"threads_per_core", K_U32, 1, 256, OFF(threads_per_core)},
    {"rays_per_thread", K_U32, 1, 256, OFF(rays_per_thread)},
    {"l1.size", K_SIZE, 0, 1ull << 30, OFF(l1_size_bytes)},
    {"l1.ways", K_WAYS, 1, 1u << 24, OFF(l1_ways)},
    {"l1.latency", K_U32, 0, 1e6, OFF(l1_latency_cycles)},
    {"l2.size", K_SIZE, 1, 1ull << 34, OFF(l2_size_bytes)},
    {"l2.ways", K_WAYS, 1, 1u << 28, OFF(l2_ways)},
    {"l2.latency", K_U32, 0, 1e6, OFF(l2_latency_cycles)},
    {"l2.banks", K_U32, 1, 4096, OFF(l2_banks)},
    {"l2.mshrs", K_U32, 1, 1u << 20, OFF(l2_mshrs)},
    {"l2.write_buffer", K_U32, 1, 1u << 20, OFF(l2_write_buffer)},
    /* Where dram.model stood (its successor), so columns keep their order. */
    {"fidelity", K_ENUM, 0, MACHINE_FIDELITY_COUNT - 1, offsetof(struct machine_params, fidelity),
     FIDELITY_NAMES},
    {"dram.latency", K_U64, 0, 1e9, OFF(dram_latency_cycles)},
    {"dram.bytes_per_cycle", K_F64, 1e-6, 1e6, OFF(dram_bytes_per_cycle)},
    {"dram.queue_depth", K_U32, 1, 1u << 20, OFF(dram_queue_depth)},
    {"dram.clock_mhz", K_U32, 1, 16000, OFF(dram_clock_mhz)},
#define BK(f) offsetof(struct machine_params, dram_banked.f), NULL
    {"dram.channels", K_U32, 1, 64, BK(channels)},
    {"dram.ranks", K_U32, 1, 16, BK(ranks)},
    {"dram.bank_groups", K_U32, 1, 16, BK(bank_groups)},
    {"dram.banks_per_group", K_U32, 1, 64, BK(banks_per_group)},
    {"dram.rows", K_U32, 1, 1u << 24, BK(rows)},
    {"dram.columns", K_U32, 1, 1u << 20, BK(columns)},
    {"dram.bus_bytes", K_U32, 1, 64, BK(bus_bytes)},
    {"dram.burst_length", K_U32, 1, 64, BK(burst_length)},
    {"dram.mapping", K_MAPPING, 0, 0, BK(mapping)},
    {"dram.page_policy", K_ENUM, 0, 1, offsetof(struct machine_params, dram_banked.page),
     PAGE_NAMES},
    {"dram.read_queue", K_U32, 1, 4096, BK(read_queue)},
    {"dram.write_queue", K_U32, 1, 4096, BK(write_queue)},
    {"dram.write_high", K_U32, 1, 4096, BK(write_high)},
    {"dram.write_low", K_U32, 0, 4096, BK(write_low)},
    {"dram.controller_cycles", K_U32, 0, 1000, BK(controller_cycles)},
    {"dram.queue_structure", K_ENUM, 0, 2, offsetof(struct machine_params, dram_banked.queue_structure),
     QUEUE_NAMES},
    {"dram.command_queue", K_U32, 1, 4096, BK(command_queue)},
    {"dram.tCL", K_U32, 1, 1000, BK(tCL)},
    {"dram.tCWL", K_U32, 1, 1000, BK(tCWL)},
    {"dram.tRCD", K_U32, 1, 1000, BK(tRCD)},
    {"dram.tRP", K_U32, 1, 1000, BK(tRP)},
    {"dram.tRAS", K_U32, 1, 1000, BK(tRAS)},
    {"dram.tRC", K_U32, 1, 2000, BK(tRC)},
    {"dram.tCCD_S", K_U32, 1, 1000, BK(tCCD_S)},
    {"dram.tCCD_L", K_U32, 1, 1000, BK(tCCD_L)},
    {"dram.tRRD_S", K_U32, 1, 1000, BK(tRRD_S)},
    {"dram.tRRD_L", K_U32, 1, 1000, BK(tRRD_L)},
    {"dram.tFAW", K_U32, 1, 10000, BK(tFAW)},
    {"dram.tWR", K_U32, 1, 1000, BK(tWR)},
    {"dram.tWTR_S", K_U32, 1, 1000, BK(tWTR_S)},
    {"dram.tWTR_L", K_U32, 1, 1000, BK(tWTR_L)},
    {"dram.tRTW", K_U32, 1, 1000, BK(tRTW)},
    {"dram.tRTP", K_U32, 1, 1000, BK(tRTP)},
    {"dram.tREFI", K_U32, 0, 1u << 20, BK(tREFI)},
    {"dram.tRFC", K_U32, 1, 100000, BK(tRFC)},
#undef BK
    {"costs.node", K_U32, 0, 1e6, OFF(cost_node_cycles)},
    {"costs.triangle", K_U32, 0, 1e6, OFF(cost_triangle_cycles)},
    {"costs.shade", K_U32, 0, 1e6, OFF(cost_shade_cycles)},
    {"costs.ray_switch", K_U32, 0, 1e6, OFF(cost_ray_switch_cycles)},
    {"timeline.window", K_U64, 1, 1e12, OFF(timeline_window_cycles)},
    {"dynamic.sharing", K_ENUM, 0, 1, offsetof(struct machine_params, dyn_sharing), SHARING_NAMES},
    {"sample.fraction", K_F64, 1e-6, 1, OFF(sample_fraction)},
    {"sample.units", K_U32, 0, 1u << 20, OFF(sample_units)},
    {"sample.warming", K_F64, 0, 1e6, OFF(sample_warming)},
    {"sample.seed", K_U64, 0, 1e15, OFF(sample_seed)},
};

static const char *const SECTIONS[] = {"l1", "l2", "dram", "costs", "timeline", "dynamic", "sample"};
#define NSECTIONS (sizeof SECTIONS / sizeof SECTIONS[0])

const char *machine_cfg_key(unsigned i) { return i < MACHINE_CFG_KEYS ? KEYS[i].name : NULL; }

void machine_cfg_key_list(char *buf, size_t cap) {
  size_t n = 0;
  buf[0] = '\0';
  for (unsigned i = 0; i < MACHINE_CFG_KEYS && n < cap; i++)
    n += (size_t)snprintf(buf + n, cap - n, "%s%s", i ? ", " : "", KEYS[i].name);
}

void machine_cfg_defaults(struct machine_cfg *c) {
  memset(c, 0, sizeof *c);
  struct machine_params *p = &c->p;
  /* configs/default.yaml documents each figure and its source. */
  p->clock_ghz = 1.4;
  p->cores = 16;
  p->threads_per_core = 4;
  p->rays_per_thread = 2;
  p->l1_size_bytes = 8u << 10;
  p->l1_ways = 4;
  p->l1_latency_cycles = 3;
  p->l2_size_bytes = 4u << 20;
  p->l2_ways = 16;
  p->l2_latency_cycles = 20;
  p->l2_banks = 8;
  p->l2_mshrs = 64;
  p->l2_write_buffer = 16;
  p->fidelity = MACHINE_FIDELITY_BANKED;
  /* fidelity channel, fixed or analytic: fitted to the banked DDR4-2400 channel
   * (configs/default.yaml says how). */
  p->dram_latency_cycles = 50;
  p->dram_bytes_per_cycle = 13;
  p->dram_queue_depth = 16;
  p->dram_clock_mhz = 1200;
  /* fidelity banked: one DDR4-2400 channel (configs/dram/ddr4-2400.yaml
   * gives each figure's source). */
  struct dram_banked_params *b = &p->dram_banked;
  b->channels = 1;
  b->ranks = 2;
  b->bank_groups = 4;
  b->banks_per_group = 4;
  b->rows = 65536;
  b->columns = 1024;
  b->bus_bytes = 8;
  b->burst_length = 8;
  snprintf(b->mapping, sizeof b->mapping, "rochrababgco");
  b->page = DRAM_BANKED_OPEN_PAGE;
  b->read_queue = 16;
  b->write_queue = 16;
  b->write_high = 16;
  b->write_low = 8;
  b->controller_cycles = 2;
  b->queue_structure = DRAM_BANKED_PER_BANK;
  b->command_queue = 8;
  b->tCL = 17;
  b->tCWL = 12;
  b->tRCD = 17;
  b->tRP = 17;
  b->tRAS = 39;
  b->tRC = 56;
  b->tCCD_S = 4;
  b->tCCD_L = 6;
  b->tRRD_S = 4;
  b->tRRD_L = 6;
  b->tFAW = 26;
  b->tWR = 18;
  b->tWTR_S = 3;
  b->tWTR_L = 9;
  b->tRTW = 10;
  b->tRTP = 9;
  b->tREFI = 9360;
  b->tRFC = 420;
  p->cost_node_cycles = 7;
  p->cost_triangle_cycles = 20;
  p->cost_shade_cycles = 50;
  p->cost_ray_switch_cycles = 2;
  p->timeline_window_cycles = 10000;
  p->dyn_sharing = 1; /* chip: results/contention/scheduling */
  p->sample_fraction = 1;
  p->sample_units = 0;
  p->sample_warming = 4;
  p->sample_seed = 1;
}

/* "512KiB", "4MiB", "1GiB", "64B" or a plain number of bytes: the number
 * under scalar.h's rule (so 010KiB is refused, as 010 is for a count). */
static enum scalar_why parse_size(const char *s, uint64_t *out) {
  enum scalar_why w = scalar_text(s);
  if (w != SCALAR_OK) return w;
  size_t digits = strspn(s, "0123456789");
  const char *unit = s + digits;
  unsigned shift = 0;
  if (*unit == '\0' || strcmp(unit, "B") == 0) shift = 0;
  else if (strcmp(unit, "KiB") == 0) shift = 10;
  else if (strcmp(unit, "MiB") == 0) shift = 20;
  else if (strcmp(unit, "GiB") == 0) shift = 30;
  else return SCALAR_SYNTAX;
  uint64_t v = 0;
  w = scalar_u64_n(s, digits, &v);
  if (w == SCALAR_EMPTY) return SCALAR_SYNTAX; /* a unit alone */
  if (w != SCALAR_OK) return w;
  if (shift && v > (UINT64_MAX >> shift)) return SCALAR_OVERFLOW;
  *out = v << shift;
  return SCALAR_OK;
}

/* Read node n (a scalar) as key k into p. */
static bool read_value(const struct cfg_doc *d, const struct cfg_node *n, const struct key *k,
                       struct machine_params *p, struct err *e) {
  char *dst = (char *)p + k->off;
  switch (k->kind) {
  case K_F64: {
    double v;
    if (!cfg_f64(d, n, k->name, k->lo, k->hi, &v, e)) return false;
    memcpy(dst, &v, sizeof v);
    return true;
  }
  case K_U32:
  case K_U64: {
    uint64_t v;
    if (!cfg_u64(d, n, k->name, (uint64_t)k->lo, (uint64_t)k->hi, &v, e)) return false;
    if (k->kind == K_U32) {
      uint32_t v32 = (uint32_t)v;
      memcpy(dst, &v32, sizeof v32);
    } else {
      memcpy(dst, &v, sizeof v);
    }
    return true;
  }
  case K_SIZE: {
    uint64_t v = 0;
    enum scalar_why w = n->kind == CFG_SCALAR ? parse_size(n->text, &v) : SCALAR_SYNTAX;
    if (w == SCALAR_OVERFLOW)
      return cfg_fail(d, n, k->name, e, "out of range (got %s, expected %.0f to %.0f bytes)",
                      n->text, k->lo, k->hi);
    if (w != SCALAR_OK)
      return cfg_fail(d, n, k->name, e,
                      "not a size%s%s (got '%s', expected bytes such as 4096, 512KiB, 4MiB or "
                      "1GiB)",
                      w == SCALAR_SYNTAX ? "" : ": ", scalar_why_text(w),
                      n->kind == CFG_SCALAR ? n->text : "a list or map");
    if ((double)v < k->lo || (double)v > k->hi)
      return cfg_fail(d, n, k->name, e, "out of range (got %s, expected %.0f to %.0f bytes)",
                      n->text, k->lo, k->hi);
    memcpy(dst, &v, sizeof v);
    return true;
  }
  case K_ENUM: {
    char list[256] = "";
    for (unsigned i = 0; i <= (unsigned)k->hi; i++) {
      if (n->kind == CFG_SCALAR && strcmp(n->text, k->names[i]) == 0) {
        uint32_t v = i;
        memcpy(dst, &v, sizeof v);
        return true;
      }
      snprintf(list + strlen(list), sizeof list - strlen(list), "%s%s", i ? ", " : "", k->names[i]);
    }
    return cfg_fail(d, n, k->name, e, "unknown value (got '%s', expected one of: %s)",
                    n->kind == CFG_SCALAR ? n->text : "a list or map", list);
  }
  case K_MAPPING: {
    if (n->kind != CFG_SCALAR || !dram_banked_mapping_ok(n->text))
      return cfg_fail(d, n, k->name, e,
                      "not an address mapping (got '%s', expected six two-letter fields, each of "
                      "ro ch ra bg ba co once, most significant first, e.g. rochrababgco)",
                      n->kind == CFG_SCALAR ? n->text : "a list or map");
    snprintf(dst, sizeof p->dram_banked.mapping, "%s", n->text);
    return true;
  }
  case K_WAYS: {
    uint32_t v = 0;
    if (n->kind == CFG_SCALAR && strcmp(n->text, "full") == 0) {
      memcpy(dst, &v, sizeof v);
      return true;
    }
    uint64_t w;
    enum scalar_why why = n->kind == CFG_SCALAR ? scalar_u64(n->text, &w) : SCALAR_SYNTAX;
    if (why != SCALAR_OK && why != SCALAR_OVERFLOW)
      return cfg_fail(d, n, k->name, e,
                      "not a number of ways%s%s (got '%s', expected 1 to %.0f or full)",
                      why == SCALAR_SYNTAX ? "" : ": ", scalar_why_text(why),
                      n->kind == CFG_SCALAR ? n->text : "a list or map", k->hi);
    if (!cfg_u64(d, n, k->name, (uint64_t)k->lo, (uint64_t)k->hi, &w, e)) return false;
    v = (uint32_t)w;
    memcpy(dst, &v, sizeof v);
    return true;
  }
  }
  return false;
}

static void set_origin(struct machine_cfg *c, unsigned i, const char *file, int line, int col,
                       bool included) {
  snprintf(c->at[i].file, sizeof c->at[i].file, "%s", file);
  c->at[i].line = line;
  c->at[i].col = col;
  c->at[i].included = included;
  c->at[i].seq = ++c->seq;
}

/* The rungs whose DRAM reads key `name` (a mask of 1 << enum machine_fidelity).
 * The analytic rung reads the channel's latency and bandwidth for its bounds.
 * NOTE: only dram keys are held to this: a rung that ignores another key
 * (analytic and l2.mshrs, say) does not refuse it. */
static unsigned key_models(const char *name) {
  const unsigned all = (1u << MACHINE_FIDELITY_COUNT) - 1;
  if (strncmp(name, "dram.", 5)) return all;
  name += 5;
  if (!strcmp(name, "clock_mhz")) return all;
  if (!strcmp(name, "latency"))
    return 1u << MACHINE_FIDELITY_ANALYTIC | 1u << MACHINE_FIDELITY_FIXED |
           1u << MACHINE_FIDELITY_CHANNEL;
  if (!strcmp(name, "bytes_per_cycle"))
    return 1u << MACHINE_FIDELITY_ANALYTIC | 1u << MACHINE_FIDELITY_CHANNEL;
  if (!strcmp(name, "queue_depth")) return 1u << MACHINE_FIDELITY_CHANNEL;
  return 1u << MACHINE_FIDELITY_BANKED;
}

const char *machine_cfg_renamed(const char *name) {
  if (!strcmp(name, "dram.model"))
    return "renamed to fidelity, a top-level key (fidelity: analytic, fixed, channel or "
           "banked; README: Fidelity ladder)";
  return NULL;
}

#define INCLUDE_DEPTH 8

static bool load(struct machine_cfg *c, const char *path, unsigned depth, struct err *e);

/* include: FILE or [FILE, ...], each relative to the including file's folder,
 * read before the including file's own keys (which override them). */
static bool load_includes(struct machine_cfg *c, struct cfg_doc *d, const char *path,
                          unsigned depth, struct err *e) {
  struct cfg_node *inc = cfg_get(&d->root, "include");
  if (!inc) return true;
  uint32_t n = inc->kind == CFG_SEQ ? inc->count : 1;
  if (inc->kind == CFG_MAP)
    return cfg_fail(d, inc, "include", e, "expected a file name or a list of them");
  if (depth >= INCLUDE_DEPTH)
    return cfg_fail(d, inc, "include", e, "included files nest deeper than %d (a cycle?)",
                    INCLUDE_DEPTH);
  const char *slash = strrchr(path, '/');
  int dir = slash ? (int)(slash - path) + 1 : 0;
  for (uint32_t i = 0; i < n; i++) {
    struct cfg_node *f = inc->kind == CFG_SEQ ? &inc->items[i] : inc;
    if (f->kind != CFG_SCALAR) return cfg_fail(d, f, "include", e, "expected a file name");
    enum scalar_why w = scalar_text(f->text);
    if (w != SCALAR_OK)
      return cfg_fail(d, f, "include", e, "%s (got '%s', expected a file name)",
                      scalar_why_text(w), f->text);
    char sub[1024];
    if (f->text[0] == '/') snprintf(sub, sizeof sub, "%s", f->text);
    else if ((size_t)snprintf(sub, sizeof sub, "%.*s%s", dir, path, f->text) >= sizeof sub)
      return cfg_fail(d, f, "include", e, "the path is too long");
    struct err sube;
    memset(&sube, 0, sizeof sube);
    if (!load(c, sub, depth + 1, &sube)) {
      /* Say where the include was written, then what is wrong inside. */
      char msg[ERR_MSG_MAX];
      err_format(&sube, msg, sizeof msg);
      return cfg_fail(d, f, "include", e, "%s", msg);
    }
  }
  return true;
}

static bool load(struct machine_cfg *c, const char *path, unsigned depth, struct err *e) {
  struct cfg_doc d;
  memset(&d, 0, sizeof d);
  bool ok = cfg_load_file(&d, path, e) && cfg_expect_map(&d, &d.root, "(top level)", e);
  /* Ask for the top-level keys in the order an unknown key's message lists
   * them: plain keys, sections, include. */
  for (unsigned i = 0; ok && i < MACHINE_CFG_KEYS; i++)
    if (!strchr(KEYS[i].name, '.')) cfg_get(&d.root, KEYS[i].name);
  for (unsigned s = 0; ok && s < NSECTIONS; s++) cfg_get(&d.root, SECTIONS[s]);
  if (ok) cfg_get(&d.root, "include");
  for (unsigned s = 0; ok && s < NSECTIONS; s++) {
    struct cfg_node *sec = cfg_get(&d.root, SECTIONS[s]);
    if (sec && !cfg_expect_map(&d, sec, SECTIONS[s], e)) ok = false;
  }
  if (ok) ok = load_includes(c, &d, path, depth, e);
  struct cfg_node *dm = cfg_get(&d.root, "dram");
  if (ok && dm && (dm = cfg_peek(dm, "model")))
    ok = err_set(e, d.file, dm->key_line, dm->key_col, "dram.model: %s",
                 machine_cfg_renamed("dram.model"));
  for (unsigned i = 0; ok && i < MACHINE_CFG_KEYS; i++) {
    const char *name = KEYS[i].name, *dot = strchr(name, '.');
    struct cfg_node *n;
    if (dot) {
      char sec[32];
      snprintf(sec, sizeof sec, "%.*s", (int)(dot - name), name);
      struct cfg_node *m = cfg_get(&d.root, sec);
      n = m ? cfg_get(m, dot + 1) : NULL;
    } else {
      n = cfg_get(&d.root, name);
    }
    if (!n) continue;
    if (!read_value(&d, n, &KEYS[i], &c->p, e)) ok = false;
    else set_origin(c, i, path, n->line, n->col, depth > 0);
  }
  for (unsigned s = 0; ok && s < NSECTIONS; s++) {
    struct cfg_node *sec = cfg_get(&d.root, SECTIONS[s]);
    if (sec && !cfg_check_keys(&d, sec, SECTIONS[s], e)) ok = false;
  }
  if (ok) ok = cfg_check_keys(&d, &d.root, "", e);
  cfg_free(&d);
  return ok;
}

bool machine_cfg_load(struct machine_cfg *c, const char *path, struct err *e) {
  return load(c, path, 0, e);
}

int machine_cfg_find(const char *name) {
  for (unsigned i = 0; i < MACHINE_CFG_KEYS; i++)
    if (!strcmp(KEYS[i].name, name)) return (int)i;
  return -1;
}

bool machine_cfg_set_at(struct machine_cfg *c, unsigned i, const char *value, const char *file,
                        int line, int col, struct err *e) {
  CHECK_LT(i, MACHINE_CFG_KEYS);
  /* The value goes through the same typed reader as a file's. */
  struct cfg_doc d;
  memset(&d, 0, sizeof d);
  snprintf(d.file, sizeof d.file, "%s", file);
  struct cfg_node n;
  memset(&n, 0, sizeof n);
  n.kind = CFG_SCALAR;
  n.text = (char *)value;
  n.line = line;
  n.col = col;
  if (!read_value(&d, &n, &KEYS[i], &c->p, e)) return false;
  set_origin(c, i, file, line, col, false);
  return true;
}

bool machine_cfg_set(struct machine_cfg *c, const char *assignment, struct err *e) {
  char where[300];
  snprintf(where, sizeof where, "--set %s", assignment);
  const char *eq = strchr(assignment, '=');
  if (!eq)
  {
    char keys[2048];
    machine_cfg_key_list(keys, sizeof keys);
    return err_set(e, where, 0, 0, "expected KEY=VALUE (keys: %s)", keys);
  }
  char key[64];
  snprintf(key, sizeof key, "%.*s", (int)(eq - assignment), assignment);
  int i = (size_t)(eq - assignment) < sizeof key ? machine_cfg_find(key) : -1;
  if (i < 0 && machine_cfg_renamed(key))
    return err_set(e, where, 0, 0, "%s: %s", key, machine_cfg_renamed(key));
  if (i < 0) {
    char keys[2048];
    machine_cfg_key_list(keys, sizeof keys);
    return err_set(e, where, 0, 0, "unknown key '%.*s' (expected one of: %s)",
                   (int)(eq - assignment), assignment, keys);
  }
  return machine_cfg_set_at(c, (unsigned)i, eq + 1, where, 0, 0, e);
}

static unsigned key_index(const char *name) {
  int i = machine_cfg_find(name);
  CHECK_GE(i, 0);
  return (unsigned)i;
}

/* An error at key `name`, where its value came from. */
static bool fail_at(const struct machine_cfg *c, const char *name, struct err *e, const char *msg,
                    const char *got) {
  const struct machine_cfg_origin *o = &c->at[key_index(name)];
  return err_set(e, o->file[0] ? o->file : NULL, o->line, o->col, "%s: %s (got %s)%s", name, msg,
                 got, o->file[0] ? "" : " [the default]");
}

static bool check_cache(const struct machine_cfg *c, const char *lvl, uint64_t size, uint32_t ways,
                        struct err *e) {
  char sk[16], wk[16], got[64];
  snprintf(sk, sizeof sk, "%s.size", lvl);
  snprintf(wk, sizeof wk, "%s.ways", lvl);
  snprintf(got, sizeof got, "%llu bytes", (unsigned long long)size);
  if (size < 64) return fail_at(c, sk, e, "smaller than one 64-byte line", got);
  if (size % 64) return fail_at(c, sk, e, "not a whole number of 64-byte lines", got);
  uint64_t lines = size / 64;
  snprintf(got, sizeof got, "%u ways for %llu lines", ways, (unsigned long long)lines);
  if (ways && ways > lines) return fail_at(c, wk, e, "more ways than the cache has lines", got);
  if (ways && lines % ways) return fail_at(c, wk, e, "the ways must divide the number of lines", got);
  return true;
}

bool machine_cfg_check(const struct machine_cfg *c, struct err *e) {
  const struct machine_params *p = &c->p;
  if (p->l1_size_bytes && !check_cache(c, "l1", p->l1_size_bytes, p->l1_ways, e)) return false;
  if (!check_cache(c, "l2", p->l2_size_bytes, p->l2_ways, e)) return false;
  uint64_t n = (uint64_t)p->cores * p->threads_per_core * p->rays_per_thread;
  if (n > (1u << 20)) {
    char got[64];
    snprintf(got, sizeof got, "%llu ray contexts", (unsigned long long)n);
    return fail_at(c, "rays_per_thread", e,
                   "cores x threads_per_core x rays_per_thread must be at most 1048576", got);
  }
  /* A key written for another DRAM level, after the rung was chosen, would
   * silently do nothing: refuse it. (Choosing the rung last, as --set
   * fidelity=fixed on a channel config does, sets the others aside; a
   * preset's keys are a whole level.) */
  const unsigned model_seq = c->at[key_index("fidelity")].seq;
  for (unsigned i = 0; i < MACHINE_CFG_KEYS; i++) {
    const struct machine_cfg_origin *o = &c->at[i];
    if (!o->file[0] || o->included || o->seq < model_seq ||
        (key_models(KEYS[i].name) >> p->fidelity & 1u))
      continue;
    char v[64], msg[160];
    machine_cfg_value(c, i, v, sizeof v);
    snprintf(msg, sizeof msg, "not read by fidelity %s (set fidelity to a rung that uses it)",
             FIDELITY_NAMES[p->fidelity]);
    return fail_at(c, KEYS[i].name, e, msg, v);
  }
  const char *why = machine_params_problem(p);
  if (!why) return true;
  /* A problem that names its key ("dram.tRC: ...") points where it was set. */
  const char *colon = strchr(why, ':');
  char key[64];
  if (colon && (size_t)(colon - why) < sizeof key) {
    snprintf(key, sizeof key, "%.*s", (int)(colon - why), why);
    int i = machine_cfg_find(key);
    if (i >= 0) {
      char v[64];
      machine_cfg_value(c, (unsigned)i, v, sizeof v);
      return fail_at(c, key, e, colon + 2, v);
    }
  }
  return err_set(e, NULL, 0, 0, "machine config: %s", why);
}

void machine_cfg_value(const struct machine_cfg *c, unsigned i, char *buf, unsigned cap) {
  const struct key *k = &KEYS[i];
  const char *src = (const char *)&c->p + k->off;
  switch (k->kind) {
  case K_F64: {
    double v;
    memcpy(&v, src, sizeof v);
    snprintf(buf, cap, "%.17g", v);
    /* The shortest text that reads back the same. */
    for (int prec = 1; prec <= 17; prec++) {
      snprintf(buf, cap, "%.*g", prec, v);
      if (strtod(buf, NULL) == v) break;
    }
    break;
  }
  case K_ENUM: {
    uint32_t v;
    memcpy(&v, src, sizeof v);
    snprintf(buf, cap, "%s", k->names[v]);
    break;
  }
  case K_MAPPING: snprintf(buf, cap, "%s", src); break;
  case K_U32:
  case K_WAYS: {
    uint32_t v;
    memcpy(&v, src, sizeof v);
    if (k->kind == K_WAYS && v == 0) snprintf(buf, cap, "full");
    else snprintf(buf, cap, "%u", v);
    break;
  }
  case K_U64:
  case K_SIZE: {
    uint64_t v;
    memcpy(&v, src, sizeof v);
    snprintf(buf, cap, "%llu", (unsigned long long)v);
    break;
  }
  }
}

void machine_cfg_write_json(const struct machine_cfg *c, FILE *f, const char *indent) {
  for (unsigned i = 0; i < MACHINE_CFG_KEYS; i++) {
    char v[64];
    machine_cfg_value(c, i, v, sizeof v);
    fprintf(f, "%s%s", i ? ",\n" : "", indent);
    stats_write_json_str(f, KEYS[i].name);
    fputs(": ", f);
    if (KEYS[i].kind == K_ENUM || KEYS[i].kind == K_MAPPING || !strcmp(v, "full"))
      stats_write_json_str(f, v);
    else fputs(v, f);
  }
}

void machine_cfg_to_stats(const struct machine_cfg *c, struct stats_table *t) {
  for (unsigned i = 0; i < MACHINE_CFG_KEYS; i++) {
    char v[64];
    machine_cfg_value(c, i, v, sizeof v);
    stats_str(t, KEYS[i].name, v);
  }
}
