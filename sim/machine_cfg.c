/* One table of keys, a row each, drives the defaults, reading, --set, the key
 * lists of messages, checking, writing and the key table of docs/config-keys.md. */
#include "sim/machine_cfg.h"

#include <math.h>
#include <stddef.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "sim/cache.h"
#include "sim/cfg.h"
#include "sim/dram_banked.h"
#include "sim/err.h"
#include "sim/near.h"
#include "sim/scalar.h"
#include "sim/stats.h"

enum kind { K_U32, K_U64, K_F64, K_SIZE, K_WAYS, K_ENUM, K_MAPPING };

/* The fidelity rungs that read a key (a mask of 1 << enum machine_fidelity);
 * a key written for another rung after fidelity was chosen is refused. */
#define R_A (1u << MACHINE_FIDELITY_ANALYTIC)
#define R_F (1u << MACHINE_FIDELITY_FIXED)
#define R_C (1u << MACHINE_FIDELITY_CHANNEL)
#define R_B (1u << MACHINE_FIDELITY_BANKED)
#define R_ALL (R_A | R_F | R_C | R_B)

struct key {
  const char *name; /* "section.key" or "key" */
  enum kind kind;
  double lo, hi;            /* K_ENUM: 0 and the last value's index */
  const char *def;          /* the default, as a config writes it */
  const char *unit;         /* of the value ("" for a count or a name) */
  unsigned rungs;           /* R_*: the fidelity rungs that read it */
  size_t off;               /* where it goes in struct machine_cfg (p, work or sample) */
  const char *const *names; /* K_ENUM: the values' names (a uint32_t index), hi + 1 of them */
  const char *doc;          /* one line: what it is (docs/config-keys.md's key table) */
};

static const char *const PAGE_NAMES[] = {"open", "close"};
static const char *const FIDELITY_NAMES[MACHINE_FIDELITY_COUNT] = {"analytic", "fixed", "channel",
                                                                   "banked"};
static const char *const QUEUE_NAMES[] = {"shared", "per_bank",
                                          "per_rank"};            /* enum dram_banked_queues */
static const char *const SHARING_NAMES[] = {"partition", "chip"}; /* renderer/policy/policy.h */
static const char *const IMAGE_NAMES[] = {"sampled", "whole"};    /* sample.image */

/* Every machine key, one row each: name, kind, range, default, unit, rungs,
 * where it goes, (names of an enum's values,) what it is. The order is that of
 * the stats columns and of stats.json's config: add a key at the end of its
 * section. configs/default.yaml (or the DRAM preset it includes) states each
 * default again with its source; a test holds the two equal. */
#define P(f) offsetof(struct machine_cfg, p.f), NULL
#define B(f) offsetof(struct machine_cfg, p.dram_banked.f), NULL
#define E(f, names) offsetof(struct machine_cfg, p.f), names
#define W(f) offsetof(struct machine_cfg, work.f), NULL
#define WE(f, names) offsetof(struct machine_cfg, work.f), names
#define S(f) offsetof(struct machine_cfg, sample.f), NULL
#define SE(f, names) offsetof(struct machine_cfg, sample.f), names
#define EN(f) offsetof(struct machine_cfg, p.energy.f), NULL
#define R_T (R_F | R_C | R_B)
static const struct key KEYS[] = {
    {"clock_ghz", K_F64, 1e-3, 1e3, "1.4", "GHz", R_ALL, P(clock_ghz),
     "the core clock; converts cycles to seconds (rays_per_second)"},
    {"cores", K_U32, 1, 4096, "16", "", R_ALL, P(cores),
     "cores, each with an issue port and a private L1"},
    {"threads_per_core", K_U32, 1, 256, "4", "", R_ALL, P(threads_per_core),
     "hardware threads a core, sharing its issue port round robin"},
    {"rays_per_thread", K_U32, 1, 256, "2", "", R_ALL, P(rays_per_thread),
     "ray contexts a thread, which switches to another when one waits on memory"},
    {"l1.size", K_SIZE, 0, 1ull << 30, "8KiB", "bytes", R_ALL, P(l1_size_bytes),
     "each core's private L1 (0: none)"},
    {"l1.ways", K_WAYS, 1, 1u << 24, "4", "", R_ALL, P(l1_ways),
     "the L1's associativity (full: fully associative)"},
    {"l1.latency", K_U32, 0, 1e6, "3", "cycles", R_ALL, P(l1_latency_cycles),
     "an L1 hit's load-use latency"},
    {"l2.size", K_SIZE, 1, 1ull << 34, "4MiB", "bytes", R_ALL, P(l2_size_bytes),
     "the shared L2 (tags allocated as lines arrive)"},
    {"l2.ways", K_WAYS, 1, 1u << 28, "16", "", R_ALL, P(l2_ways),
     "the L2's associativity (full: fully associative)"},
    {"l2.latency", K_U32, 0, 1e6, "20", "cycles", R_ALL, P(l2_latency_cycles),
     "an L2 hit's latency"},
    {"l2.banks", K_U32, 1, 4096, "8", "", R_ALL, P(l2_banks),
     "line-interleaved L2 banks, one access a cycle each"},
    {"l2.mshrs", K_U32, 1, 1u << 20, "64", "", R_ALL, P(l2_mshrs),
     "L2 misses outstanding at once; a fixed number, not scaled with cores or threads (64: one a "
     "hardware thread of the default 16 x 4)"},
    {"l2.write_buffer", K_U32, 1, 1u << 20, "16", "lines", R_ALL, P(l2_write_buffer),
     "dirty victims waiting for the DRAM"},
    /* Here, among the DRAM keys, so stats.csv keeps its column order. */
    {"fidelity", K_ENUM, 0, MACHINE_FIDELITY_COUNT - 1, "banked", "", R_ALL,
     E(fidelity, FIDELITY_NAMES),
     "the rung of the fidelity ladder: an estimate, or the timed machine with the DRAM at that detail"},
    {"dram.latency", K_U64, 0, 1e9, "50", "cycles", R_A | R_F | R_C, P(dram_latency_cycles),
     "a DRAM read's latency with an idle queue"},
    {"dram.bytes_per_cycle", K_F64, 1e-6, 1e6, "13", "bytes/cycle", R_A | R_C,
     P(dram_bytes_per_cycle), "what the channel sustains"},
    {"dram.queue_depth", K_U32, 1, 1u << 20, "16", "entries", R_C, P(dram_queue_depth),
     "the channel's request queue"},
    {"dram.clock_mhz", K_U32, 1, 16000, "1200", "MHz", R_ALL, P(dram_clock_mhz),
     "the DRAM's own clock: the banked level's timing, the DRAM-cycle column of --dram-trace"},
    {"dram.channels", K_U32, 1, 64, "1", "", R_B, B(channels),
     "independent channels (a power of two)"},
    {"dram.ranks", K_U32, 1, 16, "2", "", R_B, B(ranks), "ranks a channel (a power of two)"},
    {"dram.bank_groups", K_U32, 1, 16, "4", "", R_B, B(bank_groups),
     "bank groups a rank (a power of two)"},
    {"dram.banks_per_group", K_U32, 1, 64, "4", "", R_B, B(banks_per_group),
     "banks a bank group (a power of two)"},
    {"dram.rows", K_U32, 1, 1u << 24, "65536", "", R_B, B(rows), "rows a bank (a power of two)"},
    {"dram.columns", K_U32, 1, 1u << 20, "1024", "", R_B, B(columns),
     "device columns a row (a power of two)"},
    {"dram.bus_bytes", K_U32, 1, 64, "8", "bytes", R_B, B(bus_bytes),
     "a channel's data bus; bus_bytes x burst_length = 64"},
    {"dram.burst_length", K_U32, 1, 64, "8", "", R_B, B(burst_length),
     "beats a burst (even; a burst takes half as many DRAM cycles)"},
    {"dram.mapping", K_MAPPING, 0, 0, "rochrababgco", "", R_B, B(mapping),
     "address bits to ro(w) ch(annel) ra(nk) b(ank)g(roup) ba(nk) co(lumn), most significant first"},
    {"dram.page_policy", K_ENUM, 0, 1, "open", "", R_B, E(dram_banked.page, PAGE_NAMES),
     "open: a row stays open after its access; close: precharged at once"},
    {"dram.read_queue", K_U32, 1, 4096, "32", "entries", R_B, B(read_queue),
     "read transactions a channel holds"},
    {"dram.write_queue", K_U32, 1, 4096, "32", "entries", R_B, B(write_queue),
     "write transactions a channel holds"},
    {"dram.write_high", K_U32, 1, 4096, "32", "entries", R_B, B(write_high),
     "writes that start a write drain"},
    {"dram.write_low", K_U32, 0, 4096, "8", "entries", R_B, B(write_low),
     "writes a drain stops at"},
    {"dram.controller_cycles", K_U32, 0, 1000, "2", "DRAM cycles", R_B, B(controller_cycles),
     "from taking a request to its first command (at least 1 with command queues)"},
    {"dram.queue_structure", K_ENUM, 0, 2, "per_bank", "", R_B,
     E(dram_banked.queue_structure, QUEUE_NAMES),
     "transaction queues feeding a command queue per bank or per rank, or one FR-FCFS queue a channel"},
    {"dram.command_queue", K_U32, 1, 4096, "8", "entries", R_B, B(command_queue),
     "a command queue (per_bank, per_rank)"},
    {"dram.tCL", K_U32, 1, 1000, "17", "DRAM cycles", R_B, B(tCL), "read command to data"},
    {"dram.tCWL", K_U32, 1, 1000, "12", "DRAM cycles", R_B, B(tCWL), "write command to data"},
    {"dram.tRCD", K_U32, 1, 1000, "17", "DRAM cycles", R_B, B(tRCD), "activate to read or write"},
    {"dram.tRP", K_U32, 1, 1000, "17", "DRAM cycles", R_B, B(tRP), "precharge to activate"},
    {"dram.tRAS", K_U32, 1, 1000, "39", "DRAM cycles", R_B, B(tRAS), "activate to precharge"},
    {"dram.tRC", K_U32, 1, 2000, "56", "DRAM cycles", R_B, B(tRC),
     "activate to activate, one bank (at least tRAS)"},
    {"dram.tCCD_S", K_U32, 1, 1000, "4", "DRAM cycles", R_B, B(tCCD_S),
     "column to column, other bank group"},
    {"dram.tCCD_L", K_U32, 1, 1000, "6", "DRAM cycles", R_B, B(tCCD_L),
     "column to column, same bank group"},
    {"dram.tRRD_S", K_U32, 1, 1000, "4", "DRAM cycles", R_B, B(tRRD_S),
     "activate to activate, other bank group"},
    {"dram.tRRD_L", K_U32, 1, 1000, "6", "DRAM cycles", R_B, B(tRRD_L),
     "activate to activate, same bank group"},
    {"dram.tFAW", K_U32, 1, 10000, "26", "DRAM cycles", R_B, B(tFAW),
     "window of four activates, one rank"},
    {"dram.tWR", K_U32, 1, 1000, "18", "DRAM cycles", R_B, B(tWR),
     "write recovery: write data to precharge"},
    {"dram.tWTR_S", K_U32, 1, 1000, "3", "DRAM cycles", R_B, B(tWTR_S),
     "write data to read, other bank group"},
    {"dram.tWTR_L", K_U32, 1, 1000, "9", "DRAM cycles", R_B, B(tWTR_L),
     "write data to read, same bank group"},
    {"dram.tRTW", K_U32, 1, 1000, "10", "DRAM cycles", R_B, B(tRTW), "read to write"},
    {"dram.tRTP", K_U32, 1, 1000, "9", "DRAM cycles", R_B, B(tRTP), "read to precharge"},
    {"dram.tREFI", K_U32, 0, 1u << 20, "9360", "DRAM cycles", R_B, B(tREFI),
     "refresh interval (0: no refresh)"},
    {"dram.tRFC", K_U32, 1, 100000, "420", "DRAM cycles", R_B, B(tRFC), "refresh to activate"},
    {"dram.device_width", K_U32, 1, 512, "8", "bits", R_B, B(device_width),
     "a DRAM device's data width; a rank is bus_bytes x 8 / device_width devices (energy)"},
    {"dram.VDD", K_F64, 0.1, 10, "1.2", "V", R_B, B(VDD),
     "the devices' supply voltage (energy), at least 0.1 V"},
    {"dram.IDD0", K_F64, 0, 1e5, "48", "mA", R_B, B(IDD0),
     "a device's current, one bank activated and precharged every tRC"},
    {"dram.IDD2N", K_F64, 0, 1e5, "34", "mA", R_B, B(IDD2N),
     "a device's current, all banks precharged (standby)"},
    {"dram.IDD3N", K_F64, 0, 1e5, "43", "mA", R_B, B(IDD3N),
     "a device's current, a bank active (standby)"},
    {"dram.IDD4R", K_F64, 0, 1e5, "135", "mA", R_B, B(IDD4R), "a device's current, burst reads"},
    {"dram.IDD4W", K_F64, 0, 1e5, "123", "mA", R_B, B(IDD4W), "a device's current, burst writes"},
    {"dram.IDD5AB", K_F64, 0, 1e5, "250", "mA", R_B, B(IDD5AB),
     "a device's current, all-bank refresh (over tRFC)"},
    {"dram.idle_drain_cycles", K_U32, 0, 1e7, "0", "DRAM cycles", R_B, B(idle_drain_cycles),
     "per_bank, per_rank: idle time (no arrival, no request command, no read queued) after which "
     "buffered writes drain (0: never, as DRAMsim3; those left at the end are never written)"},
    {"costs.node", K_U32, 0, 1e6, "7", "cycles", R_ALL, W(cost_node_cycles),
     "compute a k-d traversal step"},
    {"costs.triangle", K_U32, 0, 1e6, "20", "cycles", R_ALL, W(cost_triangle_cycles),
     "compute a ray/triangle test"},
    {"costs.shade", K_U32, 0, 1e6, "50", "cycles", R_ALL, W(cost_shade_cycles),
     "compute shading a hit (spawning its rays included)"},
    {"costs.ray_switch", K_U32, 0, 1e6, "2", "cycles", R_ALL, P(cost_ray_switch_cycles),
     "a thread switching to another ray's registers"},
    {"timeline.window", K_U64, 1, 1e12, "10000", "cycles", R_ALL, P(timeline_window_cycles),
     "a timeline.csv row (windows double past 4096 rows)"},
    {"dynamic.sharing", K_ENUM, 0, 1, "chip", "", R_ALL, WE(dyn_sharing, SHARING_NAMES),
     "the dynamic and treelet policies' queue points: one a core (g_max divided) or chip-wide"},
    {"sample.fraction", K_F64, 1e-6, 1, "1", "", R_ALL, S(fraction),
     "share of work items simulated in detail, warm-up included (1: no sampling)"},
    {"sample.units", K_U32, 0, 1u << 20, "0", "", R_ALL, S(units),
     "strata of the work list, one detailed unit each (0: as many as fit, at most 40)"},
    {"sample.warming", K_F64, 0, 1e6, "4", "", R_ALL, S(warming),
     "items warmed without time before a unit, a multiple of its detailed items"},
    {"sample.image", K_ENUM, 0, 1, "whole", "", R_ALL, SE(whole_image, IMAGE_NAMES),
     "whole: every item is traced (rays and issue slots exact); sampled: only the units and "
     "the items warmed before them (the rest of the image black, rays and issue slots "
     "estimated)"},
    {"sample.prepass", K_U32, 0, 1u << 20, "8", "", R_ALL, S(prepass),
     "with sample.image sampled: the pre-pass counts one item in this many outside the units, "
     "in stretches, through a functional model of the L2 (no time), for the ratio estimator's "
     "auxiliary totals (0: none, an expansion by items)"},
    {"sample.stretch", K_U32, 0, 1u << 24, "0", "items", R_ALL, S(stretch),
     "the pre-pass's stretches of consecutive items (0: as many as the ray contexts)"},
    {"sample.stretch_warming", K_F64, 0, 1e3, "2", "", R_ALL, S(stretch_warming),
     "items the pre-pass's L2 model runs before each stretch and unit window, a multiple of the "
     "ray contexts"},
    {"sample.seed", K_U64, 0, 1e15, "1", "", R_ALL, S(seed),
     "where each middle unit falls in its stratum"},
    {"energy.l1_read", K_F64, -1, 1e6, "-1", "nJ", R_T, EN(l1.read_nj),
     "an L1 load hit, 64 bytes read (negative: the 65 nm table's for l1.size)"},
    {"energy.l1_write", K_F64, -1, 1e6, "-1", "nJ", R_T, EN(l1.write_nj),
     "an L1 store write (negative: as a read)"},
    {"energy.l1_fill", K_F64, -1, 1e6, "-1", "nJ", R_T, EN(l1.fill_nj),
     "an L1 line filled after a miss (negative: as a read)"},
    {"energy.l1_tag", K_F64, -1, 1e6, "-1", "nJ", R_T, EN(l1.tag_nj),
     "an L1 tag probe that missed (negative: a tenth of a read)"},
    {"energy.l2_read", K_F64, -1, 1e6, "-1", "nJ", R_T, EN(l2.read_nj),
     "an L2 read, 64 bytes: a hit or a write-back's victim (negative: the 65 nm table's for "
     "l2.size)"},
    {"energy.l2_write", K_F64, -1, 1e6, "-1", "nJ", R_T, EN(l2.write_nj),
     "an L2 store write (negative: as a read)"},
    {"energy.l2_fill", K_F64, -1, 1e6, "-1", "nJ", R_T, EN(l2.fill_nj),
     "an L2 line filled from the DRAM (negative: as a read)"},
    {"energy.l2_tag", K_F64, -1, 1e6, "-1", "nJ", R_T, EN(l2.tag_nj),
     "an L2 tag probe that missed (negative: a tenth of a read)"},
    {"energy.sram_leakage", K_F64, 0, 1e6, "0.1", "mW/KiB", R_T, EN(sram_leakage_mw_per_kib),
     "leakage of each KiB of the L1s and the L2"},
    {"energy.compute", K_F64, 0, 1e6, "0.07", "nJ", R_T, EN(compute_nj),
     "a core's compute issue slot"},
    {"energy.load", K_F64, 0, 1e6, "0.07", "nJ", R_T, EN(load_nj),
     "a core's load issue slot (its cache accesses apart)"},
    {"energy.store", K_F64, 0, 1e6, "0.07", "nJ", R_T, EN(store_nj),
     "a core's store issue slot (its cache accesses apart)"},
    {"energy.ray_switch", K_F64, 0, 1e6, "0.07", "nJ", R_T, EN(ray_switch_nj),
     "a thread switching to another ray's registers"},
    {"energy.core_leakage", K_F64, 0, 1e6, "10", "mW", R_T, EN(core_leakage_mw),
     "a core's leakage, its L1 apart"},
};
#undef P
#undef B
#undef E
#undef W
#undef WE
#undef S
#undef SE
#undef EN
#undef R_T
#define NKEYS (unsigned)(sizeof KEYS / sizeof KEYS[0])
_Static_assert(sizeof KEYS / sizeof KEYS[0] <= MACHINE_CFG_KEYS_MAX, "raise MACHINE_CFG_KEYS_MAX");

/* Key i's section ("l2") into sec; false for a top-level key. */
static bool section_of(unsigned i, char sec[32]) {
  const char *dot = strchr(KEYS[i].name, '.');
  if (dot) snprintf(sec, 32, "%.*s", (int)(dot - KEYS[i].name), KEYS[i].name);
  return dot != NULL;
}

/* Does key i open its section (the sections in the table's order)? */
static bool opens_section(unsigned i, char sec[32]) {
  char other[32];
  if (!section_of(i, sec)) return false;
  for (unsigned j = 0; j < i; j++)
    if (section_of(j, other) && !strcmp(other, sec)) return false;
  return true;
}

unsigned machine_cfg_count(void) { return NKEYS; }

const char *machine_cfg_key(unsigned i) { return i < NKEYS ? KEYS[i].name : NULL; }

const char *machine_cfg_unit(unsigned i) { return i < NKEYS ? KEYS[i].unit : NULL; }

void machine_cfg_key_list(char *buf, size_t cap) {
  size_t n = 0;
  buf[0] = '\0';
  for (unsigned i = 0; i < NKEYS && n < cap; i++)
    n += (size_t)snprintf(buf + n, cap - n, "%s%s", i ? ", " : "", KEYS[i].name);
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
                       struct machine_cfg *c, struct err *e) {
  char *dst = (char *)c + k->off;
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
    snprintf(dst, sizeof c->p.dram_banked.mapping, "%s", n->text);
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

void machine_cfg_defaults(struct machine_cfg *c) {
  memset(c, 0, sizeof *c);
  /* Each default goes through the reader a config's value does. */
  struct cfg_doc d;
  memset(&d, 0, sizeof d);
  for (unsigned i = 0; i < NKEYS; i++) {
    struct cfg_node n;
    memset(&n, 0, sizeof n);
    n.kind = CFG_SCALAR;
    n.text = (char *)KEYS[i].def;
    struct err e;
    memset(&e, 0, sizeof e);
    CHECK(read_value(&d, &n, &KEYS[i], c, &e));
  }
}

static void set_origin(struct machine_cfg *c, unsigned i, const char *file, int line, int col,
                       bool included) {
  snprintf(c->at[i].file, sizeof c->at[i].file, "%s", file);
  c->at[i].line = line;
  c->at[i].col = col;
  c->at[i].included = included;
  c->at[i].seq = ++c->seq;
}

const char *machine_cfg_renamed(const char *name) {
  if (!strcmp(name, "dram.model"))
    return "renamed to fidelity, a top-level key (fidelity: analytic, fixed, channel or "
           "banked; docs/fidelity-and-sampling.md, Fidelity ladder)";
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
      return cfg_fail(d, f, "include", e, "%s (got '%s', expected a file name)", scalar_why_text(w),
                      f->text);
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
  char sec[32];
  for (unsigned i = 0; ok && i < NKEYS; i++)
    if (!section_of(i, sec)) cfg_get(&d.root, KEYS[i].name);
  for (unsigned i = 0; ok && i < NKEYS; i++)
    if (opens_section(i, sec)) cfg_get(&d.root, sec);
  if (ok) cfg_get(&d.root, "include");
  for (unsigned i = 0; ok && i < NKEYS; i++) {
    struct cfg_node *m = opens_section(i, sec) ? cfg_get(&d.root, sec) : NULL;
    if (m && !cfg_expect_map(&d, m, sec, e)) ok = false;
  }
  if (ok) ok = load_includes(c, &d, path, depth, e);
  struct cfg_node *dm = cfg_get(&d.root, "dram");
  if (ok && dm && (dm = cfg_peek(dm, "model")))
    ok = err_set(e, d.file, dm->key_line, dm->key_col, "dram.model: %s",
                 machine_cfg_renamed("dram.model"));
  for (unsigned i = 0; ok && i < NKEYS; i++) {
    struct cfg_node *n;
    if (section_of(i, sec)) {
      struct cfg_node *m = cfg_get(&d.root, sec);
      n = m ? cfg_get(m, KEYS[i].name + strlen(sec) + 1) : NULL;
    } else {
      n = cfg_get(&d.root, KEYS[i].name);
    }
    if (!n) continue;
    if (!read_value(&d, n, &KEYS[i], c, e)) ok = false;
    else set_origin(c, i, path, n->line, n->col, depth > 0);
  }
  for (unsigned i = 0; ok && i < NKEYS; i++) {
    struct cfg_node *m = opens_section(i, sec) ? cfg_get(&d.root, sec) : NULL;
    if (m && !cfg_check_keys(&d, m, sec, e)) ok = false;
  }
  if (ok) ok = cfg_check_keys(&d, &d.root, "", e);
  cfg_free(&d);
  return ok;
}

bool machine_cfg_load(struct machine_cfg *c, const char *path, struct err *e) {
  return load(c, path, 0, e);
}

int machine_cfg_find(const char *name) {
  for (unsigned i = 0; i < NKEYS; i++)
    if (!strcmp(KEYS[i].name, name)) return (int)i;
  return -1;
}

bool machine_cfg_set_at(struct machine_cfg *c, unsigned i, const char *value, const char *file,
                        int line, int col, struct err *e) {
  CHECK_LT(i, NKEYS);
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
  if (!read_value(&d, &n, &KEYS[i], c, e)) return false;
  set_origin(c, i, file, line, col, false);
  return true;
}

bool machine_cfg_set(struct machine_cfg *c, const char *assignment, struct err *e) {
  char where[300];
  snprintf(where, sizeof where, "--set %s", assignment);
  const char *eq = strchr(assignment, '=');
  if (!eq)
    return err_set(e, where, 0, 0,
                   "expected KEY=VALUE, e.g. l2.size=1MiB ('rtsim run --help-keys' lists the %u "
                   "keys)",
                   NKEYS);
  char key[64];
  snprintf(key, sizeof key, "%.*s", (int)(eq - assignment), assignment);
  int i = (size_t)(eq - assignment) < sizeof key ? machine_cfg_find(key) : -1;
  if (i < 0 && machine_cfg_renamed(key))
    return err_set(e, where, 0, 0, "%s: %s", key, machine_cfg_renamed(key));
  if (i < 0) {
    char keys[2048], near[256];
    machine_cfg_key_list(keys, sizeof keys);
    if (near_words(key, keys, near, sizeof near))
      return err_set(e, where, 0, 0, "unknown key '%.*s' (did you mean %s?)",
                     (int)(eq - assignment), assignment, near);
    return err_set(e, where, 0, 0,
                   "unknown key '%.*s' (no key is near it; 'rtsim run --help-keys' lists all %u)",
                   (int)(eq - assignment), assignment, NKEYS);
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
  char sk[16], wk[16], got[64], msg[64];
  snprintf(sk, sizeof sk, "%s.size", lvl);
  snprintf(wk, sizeof wk, "%s.ways", lvl);
  const struct cache_params cp = {size, ways, SIM_LINE_LG2, false};
  const unsigned line = 1u << SIM_LINE_LG2;
  const unsigned long long lines = size >> SIM_LINE_LG2;
  snprintf(got, sizeof got, "%llu bytes", (unsigned long long)size);
  switch (cache_geometry(&cp)) {
  case CACHE_GEOMETRY_OK: return true;
  case CACHE_GEOMETRY_SMALL:
    snprintf(msg, sizeof msg, "smaller than one %u-byte line", line);
    break;
  case CACHE_GEOMETRY_PARTIAL:
    snprintf(msg, sizeof msg, "not a whole number of %u-byte lines", line);
    break;
  case CACHE_GEOMETRY_LINES:
    snprintf(msg, sizeof msg, "more than %llu lines", (unsigned long long)CACHE_MAX_LINES);
    break;
  case CACHE_GEOMETRY_WAYS_OVER:
  case CACHE_GEOMETRY_WAYS_SPLIT:
    snprintf(got, sizeof got, "%u ways for %llu lines", ways, lines);
    return fail_at(c, wk, e,
                   cache_geometry(&cp) == CACHE_GEOMETRY_WAYS_OVER
                       ? "more ways than the cache has lines"
                       : "the ways must divide the number of lines",
                   got);
  case CACHE_GEOMETRY_LINE: CHECK(!"the machine's line size is a cache's"); break;
  }
  return fail_at(c, sk, e, msg, got);
}

bool machine_cfg_check(const struct machine_cfg *c, struct err *e) {
  const struct machine_params *p = &c->p;
  if (p->l1_size_bytes && !check_cache(c, "l1", p->l1_size_bytes, p->l1_ways, e)) return false;
  if (!check_cache(c, "l2", p->l2_size_bytes, p->l2_ways, e)) return false;
  uint64_t n = (uint64_t)p->cores * p->threads_per_core * p->rays_per_thread;
  if (n > MACHINE_MAX_CONTEXTS) {
    char got[64], msg[96];
    snprintf(got, sizeof got, "%llu ray contexts", (unsigned long long)n);
    snprintf(msg, sizeof msg, "cores x threads_per_core x rays_per_thread must be at most %u",
             MACHINE_MAX_CONTEXTS);
    return fail_at(c, "rays_per_thread", e, msg, got);
  }
  /* A key written for another DRAM level, after the rung was chosen, would
   * silently do nothing: refuse it. (Choosing the rung last, as --set
   * fidelity=fixed on a channel config does, sets the others aside; a
   * preset's keys are a whole level.) */
  const unsigned model_seq = c->at[key_index("fidelity")].seq;
  for (unsigned i = 0; i < NKEYS; i++) {
    const struct machine_cfg_origin *o = &c->at[i];
    if (!o->file[0] || o->included || o->seq < model_seq || (KEYS[i].rungs >> p->fidelity & 1u))
      continue;
    char v[64], msg[160];
    machine_cfg_value(c, i, v, sizeof v);
    snprintf(msg, sizeof msg, "not read by fidelity %s (set fidelity to a rung that uses it)",
             FIDELITY_NAMES[p->fidelity]);
    return fail_at(c, KEYS[i].name, e, msg, v);
  }
  char whybuf[MACHINE_PROBLEM_MAX];
  const char *why = machine_params_problem(p, whybuf, sizeof whybuf);
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

/* The fewest significant digits a K_F64 key's value is written with: 1, but
 * 6 for a datasheet's volts and milliamperes, so 250 mA reads "250", not
 * "2.5e+02". */
static int f64_digits(const struct key *k) {
  return !strcmp(k->unit, "mA") || !strcmp(k->unit, "V") ? 6 : 1;
}

void machine_cfg_value(const struct machine_cfg *c, unsigned i, char *buf, unsigned cap) {
  const struct key *k = &KEYS[i];
  const char *src = (const char *)c + k->off;
  switch (k->kind) {
  case K_F64: {
    double v;
    memcpy(&v, src, sizeof v);
    stats_f64_text(v, f64_digits(k), buf, cap);
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
  for (unsigned i = 0; i < NKEYS; i++) {
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

const char *machine_cfg_fidelity_name(uint32_t f) {
  CHECK_LT(f, MACHINE_FIDELITY_COUNT);
  return FIDELITY_NAMES[f];
}

void machine_cfg_to_stats(const struct machine_cfg *c, struct stats_table *t) {
  for (unsigned i = 0; i < NKEYS; i++) {
    char v[64];
    machine_cfg_value(c, i, v, sizeof v);
    stats_str(t, KEYS[i].name, v);
  }
}

/* A bound of a key's range as a person writes it: 4096, 2^20, 10^9, 1GiB, 0.001. */
static void bound_text(double v, bool bytes, char *buf, size_t cap) {
  static const char *const UNITS[] = {"KiB", "MiB", "GiB"};
  const bool whole = v == floor(v) && v >= 0 && v < 0x1p63;
  const uint64_t u = whole ? (uint64_t)v : 0;
  if (bytes && u >= 1024) {
    for (int k = 2; k >= 0; k--)
      if (u % (1ull << (10 * (k + 1))) == 0) {
        snprintf(buf, cap, "%lluGiB", (unsigned long long)(u >> (10 * (k + 1))));
        memcpy(strchr(buf, 'G'), UNITS[k], 3);
        return;
      }
  }
  if (whole && u >= 65536 && !(u & (u - 1))) {
    int lg = 0;
    while ((1ull << lg) < u) lg++;
    snprintf(buf, cap, "2^%d", lg);
  } else if (whole) {
    int lg = 0;
    uint64_t t = u;
    while (u >= 1000000 && t % 10 == 0) t /= 10, lg++;
    if (u >= 1000000 && t == 1) snprintf(buf, cap, "10^%d", lg);
    else snprintf(buf, cap, "%llu", (unsigned long long)u);
  } else {
    stats_f64_text(v, 1, buf, cap);
  }
}

/* NULL if every key whose value lies in struct machine_cfg's member at
 * [at, at + size), given at `base`, is within its row's range, else why not
 * in buf. */
static const char *range_problem(const void *base, size_t at, size_t size, char *buf, size_t cap) {
  for (unsigned i = 0; i < NKEYS; i++) {
    const struct key *k = &KEYS[i];
    /* Other members' keys are checked with their own member; a mapping's
     * shape is the DRAM's rule. */
    if (k->off < at || k->off >= at + size || k->kind == K_MAPPING) continue;
    const char *src = (const char *)base + (k->off - at);
    double v;
    uint32_t v32;
    uint64_t v64;
    switch (k->kind) {
    case K_F64: memcpy(&v, src, sizeof v); break;
    case K_U64:
    case K_SIZE:
      memcpy(&v64, src, sizeof v64);
      v = (double)v64;
      break;
    default:
      memcpy(&v32, src, sizeof v32);
      v = k->kind == K_WAYS && v32 == 0 ? k->lo : (double)v32; /* 0: full */
    }
    if (v >= k->lo && v <= k->hi) continue; /* NaN is neither */
    if (k->kind == K_ENUM) {
      size_t n = (size_t)snprintf(buf, cap, "%s: expected one of: ", k->name);
      for (unsigned j = 0; j <= (unsigned)k->hi && n < cap; j++)
        n += (size_t)snprintf(buf + n, cap - n, "%s%s", j ? ", " : "", k->names[j]);
      return buf;
    }
    char lo[32], hi[32];
    bound_text(k->lo, k->kind == K_SIZE, lo, sizeof lo);
    bound_text(k->hi, k->kind == K_SIZE, hi, sizeof hi);
    const bool unit = k->unit[0] && k->kind != K_SIZE; /* a size's bounds carry theirs */
    snprintf(buf, cap, "%s: must be %s to %s%s%s%s", k->name, lo, hi, unit ? " " : "",
             unit ? k->unit : "", k->kind == K_WAYS ? " or full" : "");
    return buf;
  }
  return NULL;
}

const char *machine_cfg_range_problem(const struct machine_params *p, char *buf, size_t cap) {
  return range_problem(p, offsetof(struct machine_cfg, p), sizeof *p, buf, cap);
}

const char *machine_cfg_sample_range_problem(const struct machine_cfg_sample *s, char *buf,
                                             size_t cap) {
  return range_problem(s, offsetof(struct machine_cfg, sample), sizeof *s, buf, cap);
}

void machine_cfg_write_keys(FILE *f) {
  fputs("| key | default | range | unit | fidelity rungs | what it is |\n", f);
  fputs("|---|---|---|---|---|---|\n", f);
  for (unsigned i = 0; i < NKEYS; i++) {
    const struct key *k = &KEYS[i];
    char range[256] = "", lo[32], hi[32], rungs[64] = "";
    switch (k->kind) {
    case K_ENUM:
      for (unsigned v = 0; v <= (unsigned)k->hi; v++)
        snprintf(range + strlen(range), sizeof range - strlen(range), "%s`%s`", v ? ", " : "",
                 k->names[v]);
      break;
    case K_MAPPING: snprintf(range, sizeof range, "`ro ch ra bg ba co`, each once"); break;
    default:
      bound_text(k->lo, k->kind == K_SIZE, lo, sizeof lo);
      bound_text(k->hi, k->kind == K_SIZE, hi, sizeof hi);
      snprintf(range, sizeof range, "%s to %s%s", lo, hi, k->kind == K_WAYS ? ", `full`" : "");
    }
    for (unsigned r = 0; k->rungs != R_ALL && r < MACHINE_FIDELITY_COUNT; r++)
      if (k->rungs >> r & 1u)
        snprintf(rungs + strlen(rungs), sizeof rungs - strlen(rungs), "%s%s", rungs[0] ? ", " : "",
                 FIDELITY_NAMES[r]);
    fprintf(f, "| `%s` | `%s` | %s | %s | %s | %s |\n", k->name, k->def, range, k->unit,
            k->rungs == R_ALL ? "all" : rungs, k->doc);
  }
}
