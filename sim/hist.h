/* Log-linear histograms of cycle counts (load latency, queue delay): exact
 * for small values, a fixed relative width beyond, so that quantiles cost a
 * fixed array whatever the range. */
#ifndef RTSIM_SIM_HIST_H
#define RTSIM_SIM_HIST_H

#include <stdint.h>
#include <stdio.h>

/* Exact below 64; above, 8 buckets an octave (each at most 12.5% wide). */
#define HIST_EXACT 64u
#define HIST_BUCKETS (HIST_EXACT + 58u * 8u)

struct hist {
  uint64_t count, sum, max;
  uint64_t bucket[HIST_BUCKETS];
};

void hist_add(struct hist *h, uint64_t v);
/* Bucket i covers [lo, hi] (inclusive). */
void hist_bucket_range(unsigned i, uint64_t *lo, uint64_t *hi);
/* The upper edge of the bucket holding the q-quantile (0 < q <= 1) of the
 * values: exact below 64, at most 12.5% above the true quantile beyond. 0 when
 * empty. */
uint64_t hist_quantile(const struct hist *h, double q);
double hist_mean(const struct hist *h);
/* JSON array of the non-empty buckets: [{"lo":L,"hi":H,"count":N},...]. */
void hist_write_json(const struct hist *h, FILE *f);

#endif
