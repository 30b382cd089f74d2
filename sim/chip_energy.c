/* The chip's energy model: the 65 nm SRAM table, what each counted event
 * pays, leakage over the run's time, and the stats the run writes of it. */
#include "sim/chip_energy.h"

#include <math.h>
#include <stddef.h>

#include "sim/stats.h"

/* A 64-byte read at 65 nm by SRAM capacity: the figures SimTRaX and Arches
 * take from CACTI (Kopta et al., Memory Considerations for Low Energy Ray
 * Tracing, CGF 2015). */
static const struct { double lg2_bytes, nj; } SRAM_READ[] = {{13, 0.119}, {19, 0.58}, {22, 1.6}};
#define SRAM_POINTS (sizeof SRAM_READ / sizeof SRAM_READ[0])

double chip_energy_sram_read_nj(uint64_t size_bytes) {
  if (!size_bytes) return 0.0;
  const double x = log2((double)size_bytes);
  /* Below the first point the table says nothing: scale with the size. */
  if (x <= SRAM_READ[0].lg2_bytes) return SRAM_READ[0].nj * ldexp((double)size_bytes, -13);
  unsigned i = 1;
  while (i + 1 < SRAM_POINTS && x > SRAM_READ[i].lg2_bytes) i++;
  const double x0 = SRAM_READ[i - 1].lg2_bytes, x1 = SRAM_READ[i].lg2_bytes;
  const double e0 = SRAM_READ[i - 1].nj, e1 = SRAM_READ[i].nj;
  if (x == x1) return e1;
  return e0 + (e1 - e0) * (x - x0) / (x1 - x0);
}

static struct chip_energy_sram resolve_sram(struct chip_energy_sram s, uint64_t size_bytes) {
  const double read = chip_energy_sram_read_nj(size_bytes);
  if (s.read_nj < 0) s.read_nj = read;
  if (s.write_nj < 0) s.write_nj = read;
  if (s.fill_nj < 0) s.fill_nj = read;
  if (s.tag_nj < 0) s.tag_nj = read / 10;
  return s;
}

struct chip_energy_params chip_energy_resolve(const struct chip_energy_params *p,
                                              uint64_t l1_size_bytes, uint64_t l2_size_bytes) {
  struct chip_energy_params r = *p;
  r.l1 = resolve_sram(p->l1, l1_size_bytes);
  r.l2 = resolve_sram(p->l2, l2_size_bytes);
  return r;
}

static uint64_t sub0(uint64_t a, uint64_t b) { return a > b ? a - b : 0; }

#define NJ 1e-9 /* joules a nanojoule */
#define MW 1e-3 /* watts a milliwatt */

void chip_energy_compute(const struct chip_energy_params *p, const struct chip_energy_counts *c,
                         struct chip_energy *out) {
  *out = (struct chip_energy){0};
  /* An L1 hit reads; a miss probes and later fills; a store writes through
   * (charged whether the line was there or not: the L1 does not count it). */
  if (c->l1_size_bytes) {
    const uint64_t misses = sub0(c->l1_accesses, c->l1_hits);
    out->l1_dynamic_j =
        ((double)c->l1_hits * p->l1.read_nj + (double)misses * (p->l1.tag_nj + p->l1.fill_nj) +
         (double)c->stores * p->l1.write_nj) *
        NJ;
  }
  /* L2: each store writes; the other accesses that did not miss read (load
   * hits, merges); a miss probes and fills; a write-back reads its victim. */
  const uint64_t writes = c->stores < c->l2_accesses ? c->stores : c->l2_accesses;
  const uint64_t reads = sub0(sub0(c->l2_accesses, c->l2_misses), writes);
  out->l2_dynamic_j = ((double)reads * p->l2.read_nj + (double)writes * p->l2.write_nj +
                       (double)c->l2_misses * (p->l2.tag_nj + p->l2.fill_nj) +
                       (double)c->l2_writeback_lines * p->l2.read_nj) *
                      NJ;
  const uint64_t computes = sub0(c->issue_slots, c->loads + c->stores);
  out->cores_dynamic_j =
      ((double)computes * p->compute_nj + (double)c->loads * p->load_nj +
       (double)c->stores * p->store_nj + (double)c->ray_switches * p->ray_switch_nj) *
      NJ;
  const double kib_w = p->sram_leakage_mw_per_kib * MW / 1024.0; /* W a byte */
  out->l1_leakage_j = (double)c->cores * (double)c->l1_size_bytes * kib_w * c->seconds;
  out->l2_leakage_j = (double)c->l2_size_bytes * kib_w * c->seconds;
  out->cores_leakage_j = (double)c->cores * p->core_leakage_mw * MW * c->seconds;
}

double chip_energy_total_j(const struct chip_energy *e) {
  return e->l1_dynamic_j + e->l2_dynamic_j + e->cores_dynamic_j + e->l1_leakage_j +
         e->l2_leakage_j + e->cores_leakage_j;
}

/* ---- the stats (docs/stats.md) ---- */

#define R(st) ((const struct chip_energy_report *)(st))
static double ce_total_j(const void *st) {
  return chip_energy_total_j(&R(st)->chip) + (R(st)->has_dram ? R(st)->dram_j : 0.0);
}
static double ce_chip_j(const void *st, const struct stats_env *env) {
  (void)env;
  return chip_energy_total_j(&R(st)->chip);
}
static double ce_energy_j(const void *st, const struct stats_env *env) {
  (void)env;
  return ce_total_j(st);
}
/* A run renders one frame. */
static double ce_mj_per_frame(const void *st, const struct stats_env *env) {
  (void)env;
  return ce_total_j(st) * 1e3;
}
static double ce_power_w(const void *st, const struct stats_env *env) {
  (void)env;
  return stats_ratio(ce_total_j(st), R(st)->seconds);
}
static double ce_rays_per_joule(const void *st, const struct stats_env *env) {
  (void)env;
  return stats_ratio((double)R(st)->rays, ce_total_j(st));
}
#undef R

/* One of the six parts: field chip.f, named chip_energy_f, in joules. */
#define CE_PART(f, ds) STATS_DOUBLE(struct chip_energy_report, chip.f, "chip_energy_" #f, "J", ds)
static const struct stats_desc chip_energy_desc[] = {
    CE_PART(l1_dynamic_j, "the L1s' accesses: hits read, misses probe and fill, stores write"),
    CE_PART(l2_dynamic_j, "the L2's accesses: reads, writes, misses (probe and fill), write-backs"),
    CE_PART(cores_dynamic_j,
            "the cores' issue slots by kind (compute, load, store) and ray switches"),
    CE_PART(l1_leakage_j, "the L1s' leakage over the run"),
    CE_PART(l2_leakage_j, "the L2's leakage over the run"),
    CE_PART(cores_leakage_j, "the cores' leakage over the run, their L1s apart"),
    STATS_FN_F64(ce_chip_j, "chip_energy_j", "J", "the chip's energy: the six above"),
    STATS_FN_F64(ce_energy_j, "energy_j", "J",
                 "chip_energy_j + dram_energy_j where the DRAM level reports it; else the "
                 "chip's alone"),
    STATS_FN_F64(ce_mj_per_frame, "energy_mj_per_frame", "mJ",
                 "energy_j of the run's one frame, in millijoules"),
    STATS_FN_F64(ce_power_w, "power_w", "W", "energy_j / seconds"),
    STATS_FN_F64(ce_rays_per_joule, "rays_per_joule", "per joule", "rays_traced / energy_j"),
};
#undef CE_PART
const struct stats_descs chip_energy_stats_descs = {
    "energy", chip_energy_desc, STATS_COUNT(chip_energy_desc), 0, NULL, 0};
