/* Log-linear histograms of cycle counts (load latency, queue delay): exact
 * for small values, a fixed relative width beyond, so that quantiles cost a
 * fixed array whatever the range. */
#ifndef RTSIM_SIM_HIST_H
#define RTSIM_SIM_HIST_H

#include <stdint.h>
#include <stdio.h>

/* Exact below 1024 cycles (DRAM and load latencies fall there: quantiles of
 * them are exact); above, 64 buckets an octave (each at most 1.6% wide). */
#define HIST_EXACT_BITS 10u
#define HIST_SUB_BITS 6u
#define HIST_EXACT (1u << HIST_EXACT_BITS)
#define HIST_BUCKETS (HIST_EXACT + (64u - HIST_EXACT_BITS) * (1u << HIST_SUB_BITS))

struct hist {
  uint64_t count, sum, max;
  uint64_t bucket[HIST_BUCKETS];
};

void hist_add(struct hist *h, uint64_t v);
/* Bucket i covers [lo, hi] (inclusive). */
void hist_bucket_range(unsigned i, uint64_t *lo, uint64_t *hi);
/* The upper edge of the bucket holding the q-quantile (0 < q <= 1) of the
 * values: exact below HIST_EXACT, at most 1.6% above the true quantile beyond.
 * 0 when empty. */
uint64_t hist_quantile(const struct hist *h, double q);
double hist_mean(const struct hist *h);
/* JSON array of the non-empty buckets: [{"lo":L,"hi":H,"count":N},...]. */
void hist_write_json(const struct hist *h, FILE *f);

#endif
