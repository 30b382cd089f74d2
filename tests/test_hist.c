/* Histograms against brute force: quantiles of random values compared with
 * the sorted values themselves (exact below HIST_EXACT, at most one bucket's
 * width above), and every value in the bucket whose range holds it. */
#include <stdlib.h>
#include <string.h>

#include "sim/hist.h"
#include "testing.h"

static int cmp_u64(const void *a, const void *b) {
  uint64_t x = *(const uint64_t *)a, y = *(const uint64_t *)b;
  return x < y ? -1 : x > y;
}

static void test_quantiles(uint64_t range, uint64_t seed) {
  enum { N = 20000 };
  static uint64_t v[N];
  static struct hist h;
  memset(&h, 0, sizeof h);
  uint64_t s = seed;
  for (unsigned i = 0; i < N; i++) {
    s = s * 6364136223846793005ull + 1442695040888963407ull;
    v[i] = (s >> 17) % range;
    hist_add(&h, v[i]);
  }
  qsort(v, N, sizeof v[0], cmp_u64);
  const double qs[] = {0.01, 0.5, 0.9, 0.95, 0.99, 1.0};
  for (unsigned i = 0; i < sizeof qs / sizeof qs[0]; i++) {
    uint64_t want = v[(unsigned)(qs[i] * N + 0.999999) - 1];
    uint64_t got = hist_quantile(&h, qs[i]);
    if (want < HIST_EXACT)
      EXPECTF(got == want, "range %llu q %.2f: %llu, exact %llu", (unsigned long long)range, qs[i],
              (unsigned long long)got, (unsigned long long)want);
    else
      EXPECTF(got >= want && (double)got <= (double)want * 1.016 + 1,
              "range %llu q %.2f: %llu, exact %llu", (unsigned long long)range, qs[i],
              (unsigned long long)got, (unsigned long long)want);
  }
  EXPECT(h.max == v[N - 1] && h.count == N);
}

static void test_buckets(void) {
  const uint64_t vals[] = {0,    1,    63,   64,   1023,      1024,       1025,
                           1039, 1040, 4095, 4096, 123456789, 1ull << 40, UINT64_MAX};
  for (unsigned i = 0; i < sizeof vals / sizeof vals[0]; i++) {
    struct hist *h = calloc(1, sizeof *h);
    hist_add(h, vals[i]);
    unsigned b = 0;
    while (b < HIST_BUCKETS && !h->bucket[b]) b++;
    EXPECTF(b < HIST_BUCKETS, "%llu: no bucket", (unsigned long long)vals[i]);
    if (b < HIST_BUCKETS) {
      uint64_t lo, hi;
      hist_bucket_range(b, &lo, &hi);
      EXPECTF(lo <= vals[i] && vals[i] <= hi, "%llu in [%llu, %llu]", (unsigned long long)vals[i],
              (unsigned long long)lo, (unsigned long long)hi);
      if (vals[i] < HIST_EXACT) EXPECT(lo == hi);
    }
    free(h);
  }
}

int main(void) {
  test_buckets();
  test_quantiles(500, 1);
  test_quantiles(3000, 2);
  test_quantiles(1000000, 3);
  return testing_done("test_hist");
}
