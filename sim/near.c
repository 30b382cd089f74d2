/* Nearest words by optimal string alignment distance (near.h). Names are
 * short (keys, commands, options), so a full table of at most 64 x 64 cells
 * on the stack does; longer words count as far. */
#include "sim/near.h"

#include <stdio.h>
#include <string.h>

/* Names and words longer than this are never near. */
#define NEAR_LEN_MAX 63u
#define NEAR_FAR 255u
#define NEAR_SHOWN 3u

static unsigned min3(unsigned a, unsigned b, unsigned c) {
  unsigned m = a < b ? a : b;
  return m < c ? m : c;
}

/* The distance between a[0..la) and b[0..lb), both at most NEAR_LEN_MAX. */
static unsigned osa(const char *a, size_t la, const char *b, size_t lb) {
  unsigned d[NEAR_LEN_MAX + 1][NEAR_LEN_MAX + 1];
  for (size_t i = 0; i <= la; i++) d[i][0] = (unsigned)i;
  for (size_t j = 0; j <= lb; j++) d[0][j] = (unsigned)j;
  for (size_t i = 1; i <= la; i++)
    for (size_t j = 1; j <= lb; j++) {
      const unsigned change = a[i - 1] != b[j - 1];
      d[i][j] = min3(d[i - 1][j] + 1, d[i][j - 1] + 1, d[i - 1][j - 1] + change);
      if (i > 1 && j > 1 && a[i - 1] == b[j - 2] && a[i - 2] == b[j - 1] &&
          d[i - 2][j - 2] + 1 < d[i][j])
        d[i][j] = d[i - 2][j - 2] + 1;
    }
  return d[la][lb];
}

static unsigned distance_n(const char *a, size_t la, const char *b, size_t lb) {
  if (la > NEAR_LEN_MAX || lb > NEAR_LEN_MAX) return NEAR_FAR;
  return osa(a, la, b, lb);
}

unsigned near_distance(const char *a, const char *b) {
  return distance_n(a, strlen(a), b, strlen(b));
}

/* How near name[0..n) is to word: its distance, 1 when word is its last
 * dotted part, NEAR_FAR when too far. */
static unsigned nearness(const char *word, const char *name, size_t n) {
  const size_t lw = strlen(word);
  const unsigned most = lw / 3 > 1 ? (unsigned)(lw / 3) : 1;
  const unsigned d = distance_n(word, lw, name, n);
  if (d <= most) return d;
  const char *dot = memchr(name, '.', n);
  for (const char *p = dot; p; p = memchr(p + 1, '.', n - (size_t)(p + 1 - name))) dot = p;
  if (dot && (size_t)(name + n - dot - 1) == lw && !memcmp(dot + 1, word, lw)) return 1;
  return NEAR_FAR;
}

unsigned near_words(const char *word, const char *list, char *buf, size_t cap) {
  /* First the nearest distance, then the names at it. */
  unsigned best = NEAR_FAR;
  for (const char *p = list; *p;) {
    const size_t n = strcspn(p, ",");
    const unsigned d = nearness(word, p, n);
    if (d < best) best = d;
    p += n;
    while (*p == ',' || *p == ' ') p++;
  }
  if (cap) buf[0] = '\0';
  if (best == NEAR_FAR) return 0;
  const char *shown[NEAR_SHOWN];
  size_t len[NEAR_SHOWN];
  unsigned k = 0;
  for (const char *p = list; *p && k < NEAR_SHOWN;) {
    const size_t n = strcspn(p, ",");
    if (nearness(word, p, n) == best) shown[k] = p, len[k++] = n;
    p += n;
    while (*p == ',' || *p == ' ') p++;
  }
  size_t used = 0;
  for (unsigned i = 0; i < k && used < cap; i++) {
    const char *sep = i == 0 ? "" : ", ";
    if (i > 0 && i + 1 == k) sep = " or ";
    used += (size_t)snprintf(buf + used, cap - used, "%s'%.*s'", sep, (int)len[i], shown[i]);
  }
  return k;
}
