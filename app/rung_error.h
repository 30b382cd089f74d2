/* How wrong a cheaper rung of the fidelity ladder may be (docs/fidelity-and-sampling.md,
 * "Fidelity ladder"): the errors each rung showed against banked, measured by regime
 * (results/speed-accuracy/rung-errors.csv, compiled in at build time), and the
 * lookup of a run's nearest regime by the figures that decide the error: its
 * DRAM utilization, its core utilization, its policy and, for analytic, the
 * bound its estimate took. A regime's bands are half-open [low, high). */
#ifndef RTSIM_APP_RUNG_ERROR_H
#define RTSIM_APP_RUNG_ERROR_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

/* One regime of the table: a rung and policy (and analytic's bound:
 * "latency" or "bandwidth"; "-" at a timed rung), the bands its points fell
 * in (high: INFINITY for the top band), how many points, and the smallest and
 * largest signed relative errors, (rung - banked) / banked, of cycles and DRAM
 * bytes. */
struct rung_error_row {
  const char *rung, *policy, *bound;
  double dram_low, dram_high, core_low, core_high;
  unsigned points;
  double cycles_min, cycles_max, dram_bytes_min, dram_bytes_max;
};

/* The committed table, rows in the CSV's order (generated from the CSV by
 * cmake/rung_errors.cmake). */
extern const struct rung_error_row rung_error_table[];
extern const unsigned rung_error_table_rows;
/* The CSV's path in the source tree, for messages and tests. */
#define RUNG_ERROR_TABLE_PATH "results/speed-accuracy/rung-errors.csv"

/* The cheaper rungs' DRAM energy estimate (dram_energy_j, estimated) against
 * the banked level's counted one, by rung and policy: its lowest and highest
 * signed relative error over the three scenes of RUNG_ENERGY_ERROR_PATH
 * (default machine, 96x96; results/dram/energy-estimate.sh), which the table
 * copies (tests/test_rung_error.c holds it to the CSV). */
struct rung_energy_error {
  const char *rung, *policy;
  unsigned points;
  double min, max;
};
extern const struct rung_energy_error rung_energy_error_table[];
extern const unsigned rung_energy_error_rows;
#define RUNG_ENERGY_ERROR_PATH "results/dram/energy-rungs.csv"

/* |error| above this in the matched regime warns. */
#define RUNG_ERROR_WARN 0.05

/* A run at a cheaper rung placed in the table. */
struct rung_error {
  const char *rung, *policy;
  int bandwidth_bound;     /* analytic: 1 its bandwidth bound, 0 its latency bound; else -1 */
  double dram_utilization; /* DRAM bytes a cycle / the peak of the config's banked DRAM */
  double core_utilization; /* issue slots / cores x cycles */
  const struct rung_error_row *row; /* the nearest regime; NULL: none of this rung and policy */
  bool inside;                      /* within both of row's bands */
  double distance; /* utilization outside row's bands, DRAM's plus the cores' (0 when inside) */
  bool warn;       /* outside every regime, or an error above RUNG_ERROR_WARN in row */
  const struct rung_energy_error *energy; /* its rung and policy's; NULL: not measured */
};

/* Place a run in rows[0..n) (rung_error_table in the program): among the rows
 * of its rung, policy and bound, one whose bands hold it, else the nearest by
 * distance (the first on a tie); and its energy error in
 * rung_energy_error_table by rung and policy. */
void rung_error_match_in(struct rung_error *r, const struct rung_error_row *rows, unsigned n,
                         const char *rung, const char *policy, int bandwidth_bound,
                         double dram_utilization, double core_utilization);

/* Place a whole run of config p at a cheaper rung in rung_error_table, from
 * its cycles, issue slots and DRAM bytes (read and written). */
struct machine_params;
void rung_error_match(struct rung_error *r, const struct machine_params *p, const char *policy,
                      int bandwidth_bound, uint64_t cycles, uint64_t issue_slots,
                      uint64_t dram_bytes);

/* If r->warn, the warning's one line (no newline) in buf; else "". */
void rung_error_warning(const struct rung_error *r, char *buf, size_t cap);

/* The stats a run at a cheaper rung writes (docs/stats.md, component
 * rung): where it falls, the regime it matched and the errors there; st: the
 * struct rung_error. */
struct stats_descs;
extern const struct stats_descs rung_error_stats_descs;

#endif
