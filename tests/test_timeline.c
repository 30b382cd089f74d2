/* The timeline against brute force: random points and spans, in time order and
 * out of it, over runs long enough to coarsen the windows several times; each
 * row must hold the exact sum of what fell in its window (integer amounts, so
 * the doubles add exactly), at whatever window the timeline ended with. */
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

int main(void) {
  /* Within the first window, no coarsening; then 2, 4 and 16 times coarser. */
  run(1000, 900, 2000, true, 1);
  run(7, 7 * 4000, 20000, true, 2);
  run(3, 3 * 4096 * 4, 30000, true, 3);
  run(5, 5 * 4096 * 16, 30000, false, 4);
  run(1, 4096 * 3 + 1, 30000, false, 5);
  return testing_done("test_timeline");
}
