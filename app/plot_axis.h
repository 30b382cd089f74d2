/* rtsim plot's axes and labels: the unit a column's name states, numbers as a
 * reader of a figure wants them (44M, 512 KiB, 25 cycles; never 4.4e+07), and
 * axis ranges with their ticks computed here rather than left to gnuplot, so
 * panels can share one range and every tick label is ours. Pure functions. */
#ifndef RTSIM_APP_PLOT_AXIS_H
#define RTSIM_APP_PLOT_AXIS_H

#include <stdbool.h>
#include <stddef.h>

/* A column's unit ("bytes", "cycles", "fraction", ...), or "" (a count or a
 * label): the one rtsim run's tables state for it (run_output_unit_of), else
 * the one its name states. docs/sweeps.md (Plotting) has the rules. */
const char *plot_unit_of(const char *name);

/* A tick label of v on an axis of unit `unit`: bytes as "512 KiB" when an
 * exact binary multiple, else "44 MB"; any other unit with SI prefixes
 * ("44M", "2.5k", "0.25"). Always fits in 32 bytes. */
void plot_fmt_tick(double v, const char *unit, char *out, size_t cap);

/* A cell's value with its column's unit, for legends and captions: a number
 * as plot_fmt_tick, then the unit when it is not bytes or a fraction
 * ("25 cycles", "1.4 GHz"); text as it is. */
void plot_fmt_value(const char *cell, const char *unit, char *out, size_t cap);

/* An axis label of a column's name (or a --y pattern such as dram_*_bytes)
 * and its unit, in words: the name's parts between '_' and '.' as words,
 * the acronyms in capitals, the '*' of a pattern left out, and the unit in
 * parentheses unless the words already end with it: dram_bytes_per_cycle
 * "DRAM bytes per cycle", l2.size "L2 size (bytes)", work_s "work
 * (seconds)", dram_*_bytes "DRAM bytes". A name with a space is a label
 * already and stays as it is. */
void plot_axis_label(const char *name, const char *unit, char *out, size_t cap);

#define PLOT_TICKS_MAX 64

/* An axis: its range [lo, hi] and where its ticks go. */
struct plot_axis {
  double lo, hi;
  bool log;
  double ticks[PLOT_TICKS_MAX];
  unsigned nticks;
};

/* A range over [min, max] (min <= max) with round ticks: on a log scale of
 * base `base` (min > 0) from the power at or below min to the one at or
 * above max; else on multiples of 1, 2, 2.5 or 5 x 10^k, about 5 intervals.
 * fraction: a unit of fraction, drawn on [0, 1] when the values fit in it;
 * zero: the range includes 0 (bars start there). */
void plot_axis_nice(struct plot_axis *a, double min, double max, bool log, int base, bool fraction,
                    bool zero);

/* A range just around the values v[0..n-1] (sorted, distinct, n >= 1) with a
 * tick at each, when they are few and far enough apart to be read (a sweep's
 * axis: 4, 16, 64 cores); false when they are not (use plot_axis_nice). */
bool plot_axis_at_values(struct plot_axis *a, const double *v, unsigned n, bool log);

#endif
