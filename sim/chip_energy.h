/* The chip's energy (docs/machine.md "Chip energy"): dynamic energy of each
 * L1 and L2 access and of each core issue slot by kind, and leakage of the
 * SRAMs and cores over the run, in joules, from the run's counters. The SRAM
 * figures default to a table of published 65 nm figures keyed by capacity;
 * every figure is an energy.* key a config may override. Knows nothing of
 * rays: the run hands its ray count and the DRAM's energy in. */
#ifndef RTSIM_SIM_CHIP_ENERGY_H
#define RTSIM_SIM_CHIP_ENERGY_H

#include <stdbool.h>
#include <stdint.h>

/* What an SRAM's access costs, nJ; its leakage, mW. A negative figure: the
 * table's for the cache's size (chip_energy_resolve). */
struct chip_energy_sram {
  double read_nj;  /* a 64-byte read that hits, tag probe included */
  double write_nj; /* a store's write, tag probe included */
  double fill_nj;  /* a line written in after a miss */
  double tag_nj;   /* a tag probe that missed */
};

struct chip_energy_params {
  struct chip_energy_sram l1, l2;
  double sram_leakage_mw_per_kib;       /* leakage of every KiB of L1 and L2 */
  double compute_nj, load_nj, store_nj; /* a core's issue slot by kind (the cache apart) */
  double ray_switch_nj;                 /* a thread switching rays */
  double core_leakage_mw;               /* a core's, its L1 apart */
};

/* The table's read energy of a 64-byte line from an SRAM of size_bytes, nJ:
 * the published 65 nm points (8 KiB 0.119, 512 KiB 0.58, 4 MiB 1.6),
 * interpolated linearly in log(size) and log(energy) between them and beyond
 * the ends along the nearest segment; 0 for size 0. */
double chip_energy_sram_read_nj(uint64_t size_bytes);

/* p with each negative SRAM figure replaced by the table's for its size: read
 * as chip_energy_sram_read_nj, write and fill as a read, a tag probe a tenth
 * of one (docs/machine.md gives the sources). */
struct chip_energy_params chip_energy_resolve(const struct chip_energy_params *p,
                                              uint64_t l1_size_bytes, uint64_t l2_size_bytes);

/* The run's counters the model reads. */
struct chip_energy_counts {
  uint32_t cores;
  uint64_t l1_size_bytes, l2_size_bytes; /* l1 0: no L1 */
  double seconds;                        /* the run's simulated time */
  uint64_t issue_slots, loads, stores, ray_switches;
  uint64_t l1_accesses, l1_hits;                       /* load lines that looked in an L1 */
  uint64_t l2_accesses, l2_misses, l2_writeback_lines; /* misses: lines fetched */
};

/* The chip's energy by component and class, J. */
struct chip_energy {
  double l1_dynamic_j, l2_dynamic_j, cores_dynamic_j;
  double l1_leakage_j, l2_leakage_j, cores_leakage_j;
};

/* The energy of a run with counts c under resolved figures p (docs/machine.md
 * lists what each access pays). */
void chip_energy_compute(const struct chip_energy_params *p, const struct chip_energy_counts *c,
                         struct chip_energy *out);
double chip_energy_total_j(const struct chip_energy *e);

/* A run's energy as the stats write it: the chip's, the DRAM's when the run's
 * DRAM level reports one, and the rays traced. */
struct chip_energy_report {
  struct chip_energy chip;
  bool has_dram;
  double dram_j;
  double seconds;
  uint64_t rays;
};
struct stats_descs;
extern const struct stats_descs chip_energy_stats_descs;

#endif
