/* rtsim plot's units, number formats and axis ranges (see plot_axis.h). */
#include "app/plot_axis.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

#include "app/csv.h"
#include "app/run_output.h"

/* The unit a column's name states, for names no table holds (a sweep's
 * point columns, a bench's). */
static const char *unit_by_name(const char *name) {
  size_t n = strlen(name);
#define ENDS(s) (n >= strlen(s) && !strcmp(name + n - strlen(s), s))
#define STARTS(s) (!strncmp(name, s, strlen(s)))
#define IS(s) (!strcmp(name, s))
  if (ENDS("_bytes_per_cycle") || IS("dram.bytes_per_cycle")) return "bytes per cycle";
  if (ENDS("_per_cycle")) return "per cycle";
  if (ENDS("_bytes") || IS("l1.size") || IS("l2.size")) return "bytes";
  if (ENDS("_per_second")) return "per second";
  /* The banked DRAM's timings count its own clock, not the core's (docs/config-keys.md's
   * key table): dram.tCL, dram.tRCD, ... */
  if (STARTS("dram.t") && n > 6 && name[6] >= 'A' && name[6] <= 'Z') return "DRAM cycles";
  if (IS("cycles") || ENDS("_cycles") || ENDS(".latency") || STARTS("costs.") ||
      IS("timeline.window") || ENDS("_wait_mean") || STARTS("load_latency_") ||
      (STARTS("dram_") && strstr(name, "_latency_")))
    return "cycles";
  if (ENDS("_fraction") || ENDS("utilization") || ENDS("_rate")) return "fraction";
  if (IS("seconds") || ENDS("_s")) return "seconds";
  if (IS("clock_ghz")) return "GHz";
  if (IS("dram.clock_mhz")) return "MHz";
  if (ENDS("_mb")) return "MiB";
  if (IS("l2.write_buffer")) return "lines";
  if (IS("dram.queue_depth") || IS("dram.read_queue") || IS("dram.write_queue") ||
      IS("dram.write_high") || IS("dram.write_low") || IS("dram.command_queue"))
    return "entries";
  if (IS("width") || IS("height")) return "pixels";
  return "";
#undef ENDS
#undef STARTS
#undef IS
}

const char *plot_unit_of(const char *name) {
  const char *u = run_output_unit_of(name);
  if (!u) return unit_by_name(name);
  /* A count, or a 0/1 flag, has no unit to write on an axis; a rate of bytes
   * reads one way on every figure whichever way its table spells it. */
  if (!strcmp(u, "count") || !strcmp(u, "flag")) return "";
  if (!strcmp(u, "bytes a cycle") || !strcmp(u, "bytes/cycle")) return "bytes per cycle";
  return u;
}

void plot_fmt_tick(double v, const char *unit, char *out, size_t cap) {
  static const char *const BIG[] = {"", "k", "M", "G", "T", "P", "E"};
  static const char *const SMALL[] = {"", "m", "µ", "n", "p"};
  static const char *const BIN[] = {"KiB", "MiB", "GiB", "TiB", "PiB", "EiB"};
  const bool bytes = !strcmp(unit, "bytes");
  const char *sign = v < 0 ? "-" : "";
  double a = fabs(v);
  if (a == 0) {
    snprintf(out, cap, "0");
    return;
  }
  if (bytes && a >= 1024) {
    /* Sizes are set in KiB and MiB (l2.size: 4MiB): say them so when the
     * value is one to two decimals of its binary unit (512 KiB, 1.5 MiB);
     * others (2e9) read better in decimal units. */
    int k = (int)floor(log(a) / log(1024)) - 1;
    if (k < 0) k = 0;
    if (k > 5) k = 5;
    double s = a / pow(1024, k + 1);
    if (s * 100 == floor(s * 100)) {
      snprintf(out, cap, "%s%g %s", sign, s, BIN[k]);
      return;
    }
  }
  int k = 0;
  /* A whole number under 10,000 that the prefix would turn into a long
   * fraction (1024 pixels, 2048 cores) reads better in full than as 1.024k;
   * round ones (2.5k, 2k) keep the prefix. */
  if (!bytes && a < 10000 && a == floor(a) && fmod(a, 100) != 0) {
    snprintf(out, cap, "%s%.0f", sign, a);
    return;
  }
  if (a >= 1000) {
    k = (int)floor(log10(a) / 3);
    if (k > 6) k = 6;
    a /= pow(1000, k);
    /* 999.96e3 reads 1000k at %.4g: move to the next prefix. */
    if (a >= 999.95 && k < 6) a /= 1000, k++;
    if (bytes) snprintf(out, cap, "%s%.4g %sB", sign, a, BIG[k]);
    else snprintf(out, cap, "%s%.4g%s", sign, a, BIG[k]);
    return;
  }
  if (a < 1e-3 && !bytes) {
    k = (int)floor(log10(a) / 3);
    if (k < -4) k = -4;
    a /= pow(1000, k);
    snprintf(out, cap, "%s%.4g%s", sign, a, SMALL[-k]);
    return;
  }
  snprintf(out, cap, "%s%.4g%s", sign, a, bytes ? " B" : "");
}

void plot_fmt_value(const char *cell, const char *unit, char *out, size_t cap) {
  double v;
  if (!csv_number(cell, &v)) {
    snprintf(out, cap, "%s", cell);
    return;
  }
  char num[64];
  plot_fmt_tick(v, unit, num, sizeof num);
  if (!unit[0] || !strcmp(unit, "bytes") || !strcmp(unit, "fraction"))
    snprintf(out, cap, "%s", num);
  else snprintf(out, cap, "%s %s", num, unit);
}

/* A word of a column's name as a figure writes it. */
static const char *word_of(const char *w) {
  static const char *const CAPS[][2] = {{"dram", "DRAM"}, {"l1", "L1"},       {"l2", "L2"},
                                        {"mshr", "MSHR"}, {"mshrs", "MSHRs"}, {"rss", "RSS"},
                                        {"kd", "k-d"},    {"ci95", "95% CI"}, {"exr", "EXR"}};
  for (size_t i = 0; i < sizeof CAPS / sizeof CAPS[0]; i++)
    if (!strcmp(w, CAPS[i][0])) return CAPS[i][1];
  return w;
}

void plot_axis_label(const char *name, const char *unit, char *out, size_t cap) {
  if (strchr(name, ' ')) {
    if (!unit[0] || strstr(name, unit)) snprintf(out, cap, "%s", name);
    else snprintf(out, cap, "%s (%s)", name, unit);
    return;
  }
  char words[1024] = "", buf[1024];
  snprintf(buf, sizeof buf, "%s", name);
  size_t len = 0;
  char *save = NULL;
  for (char *w = strtok_r(buf, "_.", &save); w; w = strtok_r(NULL, "_.", &save)) {
    if (!strcmp(w, "*")) continue;
    len += (size_t)snprintf(words + len, len < sizeof words ? sizeof words - len : 0, "%s%s",
                            len ? " " : "", word_of(w));
  }
  if (len >= sizeof words) len = sizeof words - 1;
  /* A unit the last word abbreviates (work_s, peak_rss_mb) is said once. */
  const char *last = strrchr(words, ' ');
  last = last ? last + 1 : words;
  if (last != words && ((!strcmp(unit, "seconds") && !strcmp(last, "s")) ||
                        (!strcmp(unit, "MiB") && !strcmp(last, "mb"))))
    words[last - words - 1] = '\0', len = strlen(words);
  const size_t ul = strlen(unit);
  if (!len) snprintf(out, cap, "%s", unit[0] ? unit : name);
  else if (!ul || (len >= ul && !strcmp(words + len - ul, unit) &&
                   (len == ul || words[len - ul - 1] == ' ')))
    snprintf(out, cap, "%s", words);
  else snprintf(out, cap, "%s (%s)", words, unit);
}

/* 1, 2, 2.5 or 5 x 10^k at or above raw (> 0). */
static double nice_step(double raw) {
  double mag = pow(10, floor(log10(raw))), f = raw / mag;
  return (f <= 1 ? 1 : f <= 2 ? 2 : f <= 2.5 ? 2.5 : f <= 5 ? 5 : 10) * mag;
}

static void add_tick(struct plot_axis *a, double v) {
  if (a->nticks < PLOT_TICKS_MAX) a->ticks[a->nticks++] = v;
}

void plot_axis_nice(struct plot_axis *a, double min, double max, bool log, int base, bool fraction,
                    bool zero) {
  a->log = log;
  a->nticks = 0;
  if (log) {
    const double lb = log10((double)base);
    int e0 = (int)floor(log10(min) / lb + 1e-9), e1 = (int)ceil(log10(max) / lb - 1e-9);
    if (fraction && e1 < 0) e1 = 0;
    if (e0 == e1) e0--, e1++;
    a->lo = pow(base, e0);
    a->hi = pow(base, e1);
    /* At most 9 powers get a tick: 2^0 to 2^30 would crowd the axis. */
    int stride = (e1 - e0) / 8 + 1;
    for (int e = e0; e <= e1; e += stride) add_tick(a, pow(base, e));
    if (base == 10 && e1 - e0 <= 2)
      for (int e = e0; e < e1; e++) add_tick(a, 2 * pow(10, e)), add_tick(a, 5 * pow(10, e));
    return;
  }
  if (fraction && min >= 0 && max <= 1) {
    a->lo = 0;
    a->hi = 1;
    for (int k = 0; k <= 5; k++) add_tick(a, k * 0.2);
    return;
  }
  if (zero) {
    if (min > 0) min = 0;
    if (max < 0) max = 0;
  }
  if (max == min) {
    double d = min == 0 ? 1 : fabs(min) * 0.1;
    min -= d;
    max += d;
  }
  double step = nice_step((max - min) / 5);
  double k0 = floor(min / step + 1e-9), k1 = ceil(max / step - 1e-9);
  a->lo = k0 * step;
  a->hi = k1 * step;
  for (double k = k0; k <= k1 + 0.5; k++) {
    double t = k * step;
    add_tick(a, fabs(t) < step * 1e-9 ? 0 : t);
  }
}

bool plot_axis_at_values(struct plot_axis *a, const double *v, unsigned n, bool log) {
  if (n == 0 || n > 12) return false;
  a->log = log;
  a->nticks = 0;
#define T(x) (log ? log10(x) : (x))
  double t0 = T(v[0]), t1 = T(v[n - 1]), span = t1 - t0;
  if (span == 0) {
    /* One value: a range around it. */
    if (log) a->lo = v[0] / 2, a->hi = v[0] * 2;
    else {
      double d = v[0] == 0 ? 1 : fabs(v[0]) * 0.5;
      a->lo = v[0] - d, a->hi = v[0] + d;
    }
    add_tick(a, v[0]);
    return true;
  }
  /* Labels closer than 6% of the axis run into each other. */
  for (unsigned i = 1; i < n; i++)
    if (T(v[i]) - T(v[i - 1]) < span * 0.06) return false;
#undef T
  double pad = span * 0.05;
  if (log) a->lo = v[0] / pow(10, pad), a->hi = v[n - 1] * pow(10, pad);
  else a->lo = v[0] - pad, a->hi = v[n - 1] + pad;
  for (unsigned i = 0; i < n; i++) add_tick(a, v[i]);
  return true;
}
