/* Log-linear histograms of cycle counts (hist.h). */
#include "sim/hist.h"

#include <math.h>
#include <stdbool.h>

static unsigned bucket_of(uint64_t v) {
  if (v < HIST_EXACT) return (unsigned)v;
  unsigned e = 63u - (unsigned)__builtin_clzll(v); /* >= HIST_EXACT_BITS */
  unsigned sub = (unsigned)(v >> (e - HIST_SUB_BITS)) & ((1u << HIST_SUB_BITS) - 1u);
  return HIST_EXACT + (e - HIST_EXACT_BITS) * (1u << HIST_SUB_BITS) + sub;
}

void hist_bucket_range(unsigned i, uint64_t *lo, uint64_t *hi) {
  if (i < HIST_EXACT) {
    *lo = *hi = i;
    return;
  }
  unsigned e = (i - HIST_EXACT) / (1u << HIST_SUB_BITS) + HIST_EXACT_BITS;
  unsigned sub = (i - HIST_EXACT) % (1u << HIST_SUB_BITS);
  uint64_t w = 1ull << (e - HIST_SUB_BITS);
  *lo = (1ull << e) + sub * w;
  *hi = *lo + (w - 1);
}

void hist_add(struct hist *h, uint64_t v) {
  h->count++;
  h->sum += v;
  if (v > h->max) h->max = v;
  h->bucket[bucket_of(v)]++;
}

uint64_t hist_quantile(const struct hist *h, double q) {
  if (h->count == 0) return 0;
  uint64_t need = (uint64_t)ceil(q * (double)h->count);
  if (need < 1) need = 1;
  uint64_t seen = 0;
  for (unsigned i = 0; i < HIST_BUCKETS; i++) {
    seen += h->bucket[i];
    if (seen >= need) {
      uint64_t lo, hi;
      hist_bucket_range(i, &lo, &hi);
      return hi < h->max ? hi : h->max;
    }
  }
  return h->max;
}

double hist_mean(const struct hist *h) {
  return h->count ? (double)h->sum / (double)h->count : 0.0;
}

void hist_write_json(const struct hist *h, FILE *f) {
  fputc('[', f);
  bool first = true;
  for (unsigned i = 0; i < HIST_BUCKETS; i++) {
    if (!h->bucket[i]) continue;
    uint64_t lo, hi;
    hist_bucket_range(i, &lo, &hi);
    fprintf(f, "%s{\"lo\": %llu, \"hi\": %llu, \"count\": %llu}", first ? "" : ", ",
            (unsigned long long)lo, (unsigned long long)hi, (unsigned long long)h->bucket[i]);
    first = false;
  }
  fputc(']', f);
}
