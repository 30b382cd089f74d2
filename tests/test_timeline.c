/* The timeline against brute force: random points and spans, in time order and
 * out of it, over runs long enough to coarsen the windows several times; each
 * row must hold the exact sum of what fell in its window (integer amounts, so
 * the doubles add exactly), at whatever window the timeline ended with. And
 * timeline_spread (a DRAM transfer over the cycles it holds the channel)
 * against hand-computed windows. */
#include <stdlib.h>
#include <string.h>

#include "sim/timeline.h"
#include "testing.h"

enum { COLS = 3 };

static uint64_t next(uint64_t *s) {
  *s = *s * 6364136223846793005ull + 1442695040888963407ull;
  return *s >> 17;
}

static void run(uint64_t window, uint64_t horizon, unsigned adds, bool ordered, uint64_t seed) {
  struct timeline tl;
  timeline_init(&tl, COLS, window);
  /* Brute force: the amount each cycle got, by column. */
  double *cyc = calloc(horizon * COLS, sizeof *cyc);
  uint64_t s = seed, t = 0, end = 0;
  for (unsigned i = 0; i < adds; i++) {
    const unsigned col = (unsigned)(next(&s) % COLS);
    if (ordered) t += next(&s) % (2 * horizon / adds + 1);
    else t = next(&s) % horizon;
    if (t >= horizon) t = horizon - 1;
    if (next(&s) % 2) {
      const double a = (double)(next(&s) % 100);
      timeline_point(&tl, col, t, a);
      cyc[t * COLS + col] += a;
      if (t + 1 > end) end = t + 1;
    } else {
      uint64_t b = t + next(&s) % (5 * window);
      if (b > horizon) b = horizon;
      const double per = (double)(1 + next(&s) % 3);
      timeline_span(&tl, col, t, b, per);
      for (uint64_t x = t; x < b; x++) cyc[x * COLS + col] += per;
      if (b > end) end = b;
    }
  }
  timeline_cover(&tl, end);
  const uint64_t w = tl.window;
  EXPECTF(tl.rows == (end + w - 1) / w, "window %llu: %llu rows for %llu cycles",
          (unsigned long long)w, (unsigned long long)tl.rows, (unsigned long long)end);
  EXPECT(tl.rows <= TIMELINE_MAX_ROWS);
  unsigned bad = 0;
  for (uint64_t r = 0; r < tl.rows; r++)
    for (unsigned c = 0; c < COLS; c++) {
      double want = 0;
      for (uint64_t x = r * w; x < (r + 1) * w && x < horizon; x++) want += cyc[x * COLS + c];
      bad += timeline_row(&tl, r)[c] != want;
    }
  EXPECTF(bad == 0, "window %llu -> %llu, %s: %u cells differ from brute force",
          (unsigned long long)window, (unsigned long long)w, ordered ? "ordered" : "random", bad);
  free(cyc);
  timeline_fini(&tl);
}

/* timeline_spread, by hand: a DRAM line of 64 bytes whose transfer takes
 * 256 cycles (0.25 bytes a cycle) against windows of 200 cycles. */
static void test_spread(void) {
  struct timeline tl;
  timeline_init(&tl, 1, 200);
  /* [300, 556): 100 cycles in window 1, 156 in window 2 -> 25 and 39. */
  timeline_spread(&tl, 0, 300, 556, 64);
  EXPECT(tl.rows == 3 && timeline_row(&tl, 1)[0] == 25 && timeline_row(&tl, 2)[0] == 39);
  /* Fractions: [999.5, 1000.5) halves across the edge of windows 4 and 5. */
  timeline_spread(&tl, 0, 999.5, 1000.5, 64);
  EXPECT(timeline_row(&tl, 4)[0] == 32 && timeline_row(&tl, 5)[0] == 32);
  /* Over three windows: [1250, 1750) of 100 -> 150, 200 and 150 cycles of
   * 500: 30, 40, 30. */
  timeline_spread(&tl, 0, 1250, 1750, 100);
  EXPECT(timeline_row(&tl, 6)[0] == 30 && timeline_row(&tl, 7)[0] == 40 &&
         timeline_row(&tl, 8)[0] == 30);
  /* Ending on an edge leaves the next window empty; an empty span counts at
   * its cycle. */
  timeline_spread(&tl, 0, 1800, 2000, 8);
  timeline_spread(&tl, 0, 2100.75, 2100.75, 3);
  EXPECT(timeline_row(&tl, 9)[0] == 8 && tl.rows == 11 && timeline_row(&tl, 10)[0] == 3);
  timeline_fini(&tl);

  /* Back to back, as a saturated channel moves them (100 lines, 25,600
   * cycles, 128 windows): every window holds its capacity, 200 x 0.25 = 50
   * bytes, no more and no less. */
  timeline_init(&tl, 1, 200);
  for (unsigned k = 0; k < 100; k++) timeline_spread(&tl, 0, 256.0 * k, 256.0 * (k + 1), 64);
  double sum = 0;
  unsigned off = 0;
  for (uint64_t r = 0; r < tl.rows; r++) {
    const double v = timeline_row(&tl, r)[0];
    sum += v;
    off += v > 50 + 1e-9 || v < 50 - 1e-9;
  }
  EXPECTF(tl.rows == 128 && off == 0, "%llu rows, %u not 50 bytes", (unsigned long long)tl.rows,
          off);
  EXPECTF(sum > 6400 - 1e-6 && sum < 6400 + 1e-6, "sum %.9f", sum);
  timeline_fini(&tl);

  /* Coarsening while spreading: 8192 over [0, 8192) at windows of 1 leaves
   * 4096 windows of 2 cycles, 2 each. */
  timeline_init(&tl, 1, 1);
  timeline_spread(&tl, 0, 0, 8192, 8192);
  unsigned bad = 0;
  for (uint64_t r = 0; r < tl.rows; r++) bad += timeline_row(&tl, r)[0] != 2;
  EXPECTF(tl.window == 2 && tl.rows == 4096 && bad == 0, "window %llu, %llu rows, %u bad",
          (unsigned long long)tl.window, (unsigned long long)tl.rows, bad);
  timeline_fini(&tl);
}

int main(void) {
  test_spread();
  /* Within the first window, no coarsening; then 2, 4 and 16 times coarser. */
  run(1000, 900, 2000, true, 1);
  run(7, 7 * 4000, 20000, true, 2);
  run(3, 3 * 4096 * 4, 30000, true, 3);
  run(5, 5 * 4096 * 16, 30000, false, 4);
  run(1, 4096 * 3 + 1, 30000, false, 5);
  return testing_done("test_timeline");
}
