/* Sweep files into points (sweep.h). Reading goes in one pass over the YAML
 * tree: the base machine, the workload, the fixed overrides, then each axis
 * value checked on its own where it is written; then the product is expanded
 * and every point's whole machine config checked; names must be unique; each
 * distinct scene is loaded once (to check it, and for its image size and the
 * cost estimate). */
#define _XOPEN_SOURCE 700 /* realpath */
#include "app/sweep.h"

#include <errno.h>
#include <limits.h>
#include <math.h>
#include <stdarg.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "app/app.h"
#include "app/sample.h"
#include "renderer/policy/policy.h"
#include "renderer/ray.h"
#include "renderer/scene.h"
#include "renderer/scene/scene_file.h"
#include "renderer/shade.h"
#include "sim/cfg.h"
#include "sim/derived.h"
#include "sim/err.h"
#include "sim/machine_cfg.h"
#include "sim/near.h"
#include "sim/scalar.h"

/* Workload keys; machine keys are machine_cfg's. */
enum wl { WL_SCENE, WL_POLICY, WL_RAYS, WL_WIDTH, WL_HEIGHT, WL_SEED, WL_ACCEL, WL_COUNT };
static const char *const WL_NAMES[WL_COUNT + 1] = {"scene",  "policy", "rays",  "width",
                                                   "height", "seed",   "accel", NULL};

/* One key's values (an axis, or one key of a zipped group). */
struct axis {
  const char *key;
  const char *section; /* "axes" or "zip" */
  int machine_key;     /* machine_cfg index, or -1 for a workload key */
  enum wl wl;
  struct cfg_node *node; /* the key's map entry (its list of values) */
  char **resolved;       /* scene axes: absolute paths (owned) */
};

/* A dimension of the product: one axis, or a zipped group of axes moving together. */
struct dim {
  unsigned first, naxes, count;
};

/* What a scene file gives a point: its size and what the estimate needs. */
struct scene_info {
  char *path; /* absolute (owned) */
  uint32_t width, height, tris, lights;
};

struct priv {
  struct cfg_doc doc;
  char dir[4096]; /* the sweep file's directory, absolute */
  struct axis *axes;
  unsigned naxes;
  struct dim *dims;
  unsigned ndims;
  /* The fixed workload (NULL = default) and machine overrides. */
  struct cfg_node *wl[WL_COUNT];
  char *scene_fixed; /* absolute (owned) */
  struct cfg_node *sets;
  struct machine_cfg base;    /* the base config with the fixed overrides */
  struct machine_cfg scratch; /* for checking axis values one at a time */
  char machine_path[4096];
  struct scene_info *scenes;
  unsigned nscenes;
};

static char *dup_str(const char *s) {
  size_t n = strlen(s) + 1;
  char *p = xmalloc(n);
  memcpy(p, s, n);
  return p;
}

/* path resolved against the sweep file's directory, made canonical: false
 * (error at n) when there is no such file. */
static bool resolve(const struct priv *pv, const struct cfg_node *n, const char *what, char **out,
                    struct err *e) {
  char joined[8192];
  if (n->text[0] == '/') snprintf(joined, sizeof joined, "%s", n->text);
  else snprintf(joined, sizeof joined, "%s/%s", pv->dir, n->text);
  char *real = realpath(joined, NULL);
  if (!real)
    return cfg_fail(&pv->doc, n, what, e,
                    "cannot open '%s' (%s; paths are relative to the sweep file)", n->text,
                    strerror(errno));
  if (strpbrk(real, "\n\r")) {
    free(real);
    return cfg_fail(&pv->doc, n, what, e, "a path with a line break cannot go into a job line");
  }
  *out = real;
  return true;
}

/* Check one workload value (scalar node n) for key k, where it is written. */
static bool check_workload(const struct priv *pv, enum wl k, const struct cfg_node *n,
                           struct err *e) {
  const struct cfg_doc *d = &pv->doc;
  const char *key = WL_NAMES[k];
  char text[4096];
  if (!cfg_str(d, n, key, text, sizeof text, e)) return false;
  switch (k) {
  case WL_SCENE: return true; /* resolved and loaded later */
  case WL_POLICY: {
    enum policy_kind p;
    char list[128];
    policy_list(list, sizeof list, ", ");
    if (!policy_parse(text, &p))
      return cfg_fail(d, n, key, e, "unknown policy (got '%s', expected one of: %s)", text, list);
    return true;
  }
  case WL_RAYS: {
    uint32_t mask;
    if (!shade_parse_rays(text, &mask))
      return cfg_fail(d, n, key, e,
                      "not a list of ray types (got '%s', expected a comma-separated list of "
                      "primary, shadow, specular, diffuse in one string)",
                      text);
    return true;
  }
  case WL_WIDTH:
  case WL_HEIGHT: {
    uint64_t v;
    return cfg_u64(d, n, key, 1, 16384, &v, e);
  }
  case WL_SEED: {
    uint64_t v;
    return cfg_u64(d, n, key, 0, UINT64_MAX, &v, e);
  }
  case WL_ACCEL: {
    int a; /* every policy traces every structure: only the name is checked */
    if (!app_parse_accel(text, &a))
      return cfg_fail(d, n, key, e, "unknown structure (got '%s', expected %s)", text,
                      APP_ACCEL_EXPECT);
    return true;
  }
  case WL_COUNT: break;
  }
  CHECK(!"bad workload key");
  return false;
}

/* A key that is neither a machine nor a workload key. */
static bool unknown_key(const struct priv *pv, const struct cfg_node *v, const char *section,
                        struct err *e, bool workload_too) {
  char keys[2048], wl[256] = "", near[256];
  machine_cfg_key_list(keys, sizeof keys);
  if (machine_cfg_renamed(v->key))
    return err_set(e, pv->doc.file, v->key_line, v->key_col, "%s.%s: %s", section, v->key,
                   machine_cfg_renamed(v->key));
  for (int k = 0; workload_too && k < WL_COUNT; k++)
    snprintf(wl + strlen(wl), sizeof wl - strlen(wl), "%s%s",
             k ? ", " : "; or a workload key: ", WL_NAMES[k]);
  /* The nearest of both kinds, else every name. */
  char all[2400];
  snprintf(all, sizeof all, "%s%s%s", keys, workload_too ? ", " : "",
           workload_too ? wl + strlen("; or a workload key: ") : "");
  if (near_words(v->key, all, near, sizeof near))
    return err_set(e, pv->doc.file, v->key_line, v->key_col,
                   "%s.%s: unknown key '%s' (did you mean %s?)", section, v->key, v->key, near);
  return err_set(e, pv->doc.file, v->key_line, v->key_col,
                 "%s.%s: unknown key '%s' (expected a machine config key: %s%s)", section, v->key,
                 v->key, keys, wl);
}

/* Where else key `key` was given, if anywhere (section name and line). */
static bool given_before(const struct priv *pv, const char *key, const char **where, int *line) {
  for (unsigned a = 0; a < pv->naxes; a++)
    if (!strcmp(pv->axes[a].key, key)) {
      *where = pv->axes[a].section;
      *line = pv->axes[a].node->key_line;
      return true;
    }
  for (unsigned k = 0; k < WL_COUNT; k++)
    if (pv->wl[k] && !strcmp(WL_NAMES[k], key)) {
      *where = "workload";
      *line = pv->wl[k]->key_line;
      return true;
    }
  for (uint32_t i = 0; pv->sets && i < pv->sets->count; i++)
    if (!strcmp(pv->sets->items[i].key, key)) {
      *where = "set";
      *line = pv->sets->items[i].key_line;
      return true;
    }
  return false;
}

struct by_text {
  const char *text;
  uint32_t i;
};

static int cmp_text(const void *a, const void *b) {
  const struct by_text *x = a, *y = b;
  int c = strcmp(x->text, y->text);
  return c ? c : (x->i > y->i) - (x->i < y->i);
}

/* The index of the first of n texts (in file order; NULL counts as no value)
 * that repeats an earlier one, and in *first that earlier one's; UINT32_MAX
 * when all differ. By sorting, n log n: an axis may hold a hundred thousand
 * values. */
static uint32_t first_repeat_of(const char *const *texts, uint32_t count, uint32_t *first) {
  struct by_text *r = xmalloc((count ? count : 1ull) * sizeof *r);
  uint32_t n = 0;
  for (uint32_t i = 0; i < count; i++)
    if (texts[i]) r[n++] = (struct by_text){texts[i], i};
  qsort(r, n, sizeof *r, cmp_text);
  uint32_t dup = UINT32_MAX, group = 0;
  *first = 0;
  for (uint32_t k = 1; k < n; k++) {
    if (strcmp(r[k].text, r[k - 1].text)) {
      group = k;
      continue;
    }
    if (r[k].i < dup) {
      dup = r[k].i;
      *first = r[group].i;
    }
  }
  free(r);
  return dup;
}

/* first_repeat_of over list v's values; non-scalar items (refused later,
 * where they stand) count as no value. */
static uint32_t first_repeat(const struct cfg_node *v, uint32_t *first) {
  const char **t = xmalloc((v->count ? v->count : 1ull) * sizeof *t);
  for (uint32_t i = 0; i < v->count; i++)
    t[i] = v->items[i].kind == CFG_SCALAR ? v->items[i].text : NULL;
  uint32_t dup = first_repeat_of(t, v->count, first);
  free(t);
  return dup;
}

/* In a zip group one key's values may repeat (policy: [dynamic, dynamic]
 * beside dynamic.sharing: [partition, chip]); what must differ are the
 * group's points, the rows of its values read across. Refused at the first
 * row that repeats an earlier one. The lists are checked and of one length. */
static bool check_zip_rows(const struct cfg_doc *d, const struct cfg_node *grp, const char *path,
                           struct err *e) {
  uint32_t rows = grp->items[0].count;
  char **t = xcalloc(rows, sizeof *t);
  for (uint32_t r = 0; r < rows; r++) {
    size_t len = 1;
    for (uint32_t k = 0; k < grp->count; k++) len += strlen(grp->items[k].items[r].text) + 1;
    t[r] = xmalloc(len);
    t[r][0] = '\0';
    for (uint32_t k = 0; k < grp->count; k++) {
      strcat(t[r], grp->items[k].items[r].text);
      strcat(t[r], "\x1f"); /* a separator no scalar holds */
    }
  }
  uint32_t first, dup = first_repeat_of((const char *const *)t, rows, &first);
  for (uint32_t r = 0; r < rows; r++) free(t[r]);
  free(t);
  if (dup == UINT32_MAX) return true;
  const struct cfg_node *at = &grp->items[0].items[dup];
  return err_set(e, d->file, at->line, at->col,
                 "%s: the values at index %u (one from each key) repeat those at index %u "
                 "(line %d)",
                 path, dup, first, grp->items[0].items[first].line);
}

/* In a flow list, YAML splits `[primary, shadow,specular]` at every comma:
 * three points, where the writer most likely meant two, the second with two
 * ray types. So two plain rays values with nothing but a comma between them
 * (the second starts one column after the first ends, on its line) are
 * refused: quoted, a value keeps its commas ("shadow,specular", one point),
 * and a space after the comma says two values were meant. A quoted value
 * starts at its quote, so its text is shorter than the span and never
 * matches; block lists (`- shadow,specular`) are one value already. The
 * values are checked ray lists, plain ASCII: a column is a byte. */
static bool check_rays_flow(const struct cfg_doc *d, const struct cfg_node *v, const char *path,
                            struct err *e) {
  for (uint32_t i = 0; i + 1 < v->count; i++) {
    const struct cfg_node *a = &v->items[i], *b = &v->items[i + 1];
    if (a->line != b->line || (size_t)b->col != (size_t)a->col + strlen(a->text) + 1) continue;
    char sub[160];
    snprintf(sub, sizeof sub, "%s[%u]", path, i);
    return cfg_fail(d, a, sub, e,
                    "'%s,%s' unquoted in a flow list is two values, so two points (quote it, "
                    "\"%s,%s\", for one point with both ray types; or put a space after the "
                    "comma for two)",
                    a->text, b->text, a->text, b->text);
  }
  return true;
}

/* Add map entry v (key: [values]) of section as an axis; check every value. */
static bool add_axis(struct priv *pv, struct cfg_node *v, const char *section, bool zipped,
                     struct err *e) {
  const struct cfg_doc *d = &pv->doc;
  char path[128];
  snprintf(path, sizeof path, "%s.%s", section, v->key);
  int mk = machine_cfg_find(v->key);
  int wk = -1;
  for (int k = 0; k < WL_COUNT; k++)
    if (!strcmp(WL_NAMES[k], v->key)) wk = k;
  if (mk < 0 && wk < 0) return unknown_key(pv, v, section, e, true);
  const char *where;
  int line;
  if (given_before(pv, v->key, &where, &line))
    return err_set(e, d->file, v->key_line, v->key_col,
                   "%s: '%s' is given twice (also in %s at line %d; a key moves in one axis or "
                   "group, or is fixed)",
                   path, v->key, where, line);
  if (!cfg_expect_seq(d, v, path, e)) return false;
  if (v->count == 0) return cfg_fail(d, v, path, e, "empty list (expected at least one value)");
  struct axis a = {v->key, strcmp(section, "axes") ? "zip" : "axes",
                   mk,     wk >= 0 ? (enum wl)wk : WL_COUNT,
                   v,      NULL};
  if (wk == WL_SCENE) a.resolved = xcalloc(v->count, sizeof *a.resolved);
  pv->axes = xrealloc(pv->axes, (pv->naxes + 1ull) * sizeof *pv->axes);
  pv->axes[pv->naxes++] = a;
  /* The first value that repeats an earlier one is refused where the old
   * one-by-one check refused it: after the values before it are checked. */
  uint32_t first = 0, dup = zipped ? UINT32_MAX : first_repeat(v, &first);
  /* One scratch config for every value: a value sets only its own key (and a
   * refused one ends the read), so the others' are never seen. */
  struct machine_cfg *scratch = &pv->scratch;
  *scratch = pv->base;
  for (uint32_t i = 0; i < v->count; i++) {
    struct cfg_node *n = &v->items[i];
    char sub[160];
    snprintf(sub, sizeof sub, "%s[%u]", path, i);
    if (n->kind != CFG_SCALAR)
      return cfg_fail(d, n, sub, e, "wrong type (got a %s, expected one value)",
                      n->kind == CFG_MAP ? "map" : "list");
    if (i == dup)
      return cfg_fail(d, n, sub, e, "'%s' is listed twice (first at line %d)", n->text,
                      v->items[first].line);
    if (mk >= 0) {
      if (!machine_cfg_set_at(scratch, (unsigned)mk, n->text, d->file, n->line, n->col, e))
        return false;
    } else if (!check_workload(pv, a.wl, n, e)) {
      return false;
    } else if (a.wl == WL_SCENE && !resolve(pv, n, sub, &a.resolved[i], e)) {
      return false;
    }
  }
  return a.wl != WL_RAYS || check_rays_flow(d, v, path, e);
}

static bool read_file(struct priv *pv, const char *path, struct err *e) {
  struct cfg_doc *d = &pv->doc;
  struct cfg_node *root = &d->root;
  if (!cfg_load_file(d, path, e) || !cfg_expect_map(d, root, "(top level)", e)) return false;
  char *abs = realpath(path, NULL);
  CHECK(abs); /* the file was just read */
  snprintf(pv->dir, sizeof pv->dir, "%s", abs);
  *strrchr(pv->dir, '/') = '\0';
  if (!pv->dir[0]) snprintf(pv->dir, sizeof pv->dir, "/");
  free(abs);

  /* The base machine, then the fixed overrides over it. */
  struct cfg_node *m = cfg_get(root, "machine");
  if (!m)
    return cfg_fail(d, root, "", e, "missing required key 'machine' (the base machine config)");
  char text[4096], *mpath = NULL;
  if (!cfg_str(d, m, "machine", text, sizeof text, e) || !resolve(pv, m, "machine", &mpath, e))
    return false;
  snprintf(pv->machine_path, sizeof pv->machine_path, "%s", mpath);
  free(mpath);
  machine_cfg_defaults(&pv->base);
  if (!machine_cfg_load(&pv->base, pv->machine_path, e)) return false;

  struct cfg_node *w = cfg_get(root, "workload");
  if (w) {
    if (!cfg_expect_map(d, w, "workload", e)) return false;
    for (int k = 0; k < WL_COUNT; k++) {
      struct cfg_node *n = cfg_get(w, WL_NAMES[k]);
      if (!n) continue;
      char path_k[64];
      snprintf(path_k, sizeof path_k, "workload.%s", WL_NAMES[k]);
      if (!check_workload(pv, (enum wl)k, n, e)) return false;
      if (k == WL_SCENE && !resolve(pv, n, path_k, &pv->scene_fixed, e)) return false;
      pv->wl[k] = n;
    }
    if (!cfg_check_keys(d, w, "workload", e)) return false;
  }

  struct cfg_node *sets = cfg_get(root, "set");
  if (sets) {
    if (!cfg_expect_map(d, sets, "set", e)) return false;
    for (uint32_t i = 0; i < sets->count; i++) {
      struct cfg_node *v = &sets->items[i];
      int mk = machine_cfg_find(v->key);
      if (mk < 0) return unknown_key(pv, v, "set", e, false);
      char path_k[128];
      snprintf(path_k, sizeof path_k, "set.%s", v->key);
      if (v->kind != CFG_SCALAR)
        return cfg_fail(d, v, path_k, e, "wrong type (got a %s, expected one value)",
                        v->kind == CFG_MAP ? "map" : "list");
      if (!machine_cfg_set_at(&pv->base, (unsigned)mk, v->text, d->file, v->line, v->col, e))
        return false;
    }
    pv->sets = sets;
  }

  /* Axes: each its own dimension, in file order; then zipped groups. */
  struct cfg_node *axes = cfg_get(root, "axes");
  if (axes) {
    if (!cfg_expect_map(d, axes, "axes", e)) return false;
    for (uint32_t i = 0; i < axes->count; i++) {
      if (!add_axis(pv, &axes->items[i], "axes", false, e)) return false;
      pv->dims = xrealloc(pv->dims, (pv->ndims + 1ull) * sizeof *pv->dims);
      pv->dims[pv->ndims++] = (struct dim){pv->naxes - 1, 1, axes->items[i].count};
    }
  }
  struct cfg_node *zip = cfg_get(root, "zip");
  if (zip) {
    if (!cfg_expect_seq(d, zip, "zip", e)) return false;
    for (uint32_t g = 0; g < zip->count; g++) {
      struct cfg_node *grp = &zip->items[g];
      char path_g[64];
      snprintf(path_g, sizeof path_g, "zip[%u]", g);
      if (!cfg_expect_map(d, grp, path_g, e)) return false;
      if (grp->count == 0)
        return cfg_fail(d, grp, path_g, e, "empty group (expected key: [values])");
      unsigned first = pv->naxes;
      for (uint32_t i = 0; i < grp->count; i++) {
        struct cfg_node *v = &grp->items[i];
        if (!add_axis(pv, v, path_g, true, e)) return false;
        if (v->count != grp->items[0].count)
          return cfg_fail(d, v, path_g, e,
                          "%s: %u values, but %s has %u (keys in a group move together)", v->key,
                          v->count, grp->items[0].key, grp->items[0].count);
      }
      if (!check_zip_rows(d, grp, path_g, e)) return false;
      pv->dims = xrealloc(pv->dims, (pv->ndims + 1ull) * sizeof *pv->dims);
      pv->dims[pv->ndims++] = (struct dim){first, grp->count, grp->items[0].count};
    }
  }
  if (!cfg_check_keys(d, root, "", e)) return false;
  bool scene_swept = false;
  for (unsigned a = 0; a < pv->naxes; a++) scene_swept |= pv->axes[a].wl == WL_SCENE;
  if (!pv->scene_fixed && !scene_swept)
    return cfg_fail(d, w ? w : root, w ? "workload" : "", e,
                    "missing the scene (give workload.scene, or scene as an axis)");
  return true;
}

/* Append to name at *len the value as a directory name can hold it: letters,
 * digits and . _ + - stay, a comma becomes +, anything else _. */
static void put_sanitised(char *name, size_t cap, size_t *len, const char *v) {
  for (const char *p = v; *p && *len + 1 < cap; p++) {
    char c = *p;
    bool keep = (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') ||
                c == '.' || c == '_' || c == '+' || c == '-';
    name[(*len)++] = keep ? c : c == ',' ? '+' : '_';
  }
  name[*len] = '\0';
}

/* A scene value's name part: its file name without the extension. */
static void scene_stem(const char *path, char *out, size_t cap) {
  const char *b = strrchr(path, '/');
  b = b ? b + 1 : path;
  snprintf(out, cap, "%s", b);
  char *dot = strrchr(out, '.');
  if (dot && dot != out && (!strcmp(dot, ".yaml") || !strcmp(dot, ".yml"))) *dot = '\0';
}

static uint64_t fnv1a(const char *s) {
  uint64_t h = 0xcbf29ce484222325ull;
  for (; *s; s++) h = (h ^ (unsigned char)*s) * 0x100000001b3ull;
  return h;
}

static void put_raw(char *name, size_t cap, size_t *len, const char *v) {
  for (const char *p = v; *p && *len + 1 < cap; p++) name[(*len)++] = *p;
  name[*len] = '\0';
}

/* The dimension axis a belongs to. */
static unsigned dim_of(const struct priv *pv, unsigned a) {
  for (unsigned d = 0; d < pv->ndims; d++)
    if (a >= pv->dims[d].first && a < pv->dims[d].first + pv->dims[d].naxes) return d;
  CHECK(!"axis outside every dimension");
  return 0;
}

/* The point's name from its choices: "key=value,..." or "base" when nothing
 * is swept; cut to SWEEP_NAME_MAX with a hash of the whole name. */
static void point_name(const struct priv *pv, const unsigned *choice, char *out) {
  char full[8192];
  size_t len = 0;
  full[0] = '\0';
  for (unsigned a = 0; a < pv->naxes; a++) {
    const struct axis *x = &pv->axes[a];
    const char *v = x->node->items[choice[dim_of(pv, a)]].text;
    char stem[512];
    if (x->wl == WL_SCENE) {
      scene_stem(v, stem, sizeof stem);
      v = stem;
    }
    if (len) put_raw(full, sizeof full, &len, ",");
    put_raw(full, sizeof full, &len, x->key);
    put_raw(full, sizeof full, &len, "=");
    put_sanitised(full, sizeof full, &len, v);
  }
  if (!len) snprintf(full, sizeof full, "base");
  const size_t n = strlen(full);
  if (n <= SWEEP_NAME_MAX) {
    /* (a copy, not snprintf: gcc -O0 cannot see that it fits) */
    memcpy(out, full, n + 1);
    return;
  }
  snprintf(out, SWEEP_NAME_MAX + 1, "%.*s~%016llx", SWEEP_NAME_MAX - 17, full,
           (unsigned long long)fnv1a(full));
}

struct by_name {
  const char *name;
  unsigned index;
};

static int cmp_name(const void *a, const void *b) {
  const struct by_name *x = a, *y = b;
  int c = strcmp(x->name, y->name);
  return c ? c : (x->index > y->index) - (x->index < y->index);
}

/* Two points must not share a directory: report the first pair that would,
 * at the value of the later one that makes them differ. */
static bool check_unique(const struct priv *pv, const struct sweep *s, const unsigned *choices,
                         struct err *e) {
  struct by_name *v = xmalloc((unsigned long long)s->npoints * sizeof *v);
  for (unsigned i = 0; i < s->npoints; i++) v[i] = (struct by_name){s->points[i].name, i};
  qsort(v, s->npoints, sizeof *v, cmp_name);
  bool ok = true;
  for (unsigned i = 1; ok && i < s->npoints; i++) {
    if (strcmp(v[i - 1].name, v[i].name)) continue;
    const unsigned *ca = &choices[(size_t)v[i - 1].index * pv->ndims];
    const unsigned *cb = &choices[(size_t)v[i].index * pv->ndims];
    unsigned a = 0;
    while (a < pv->naxes && ca[dim_of(pv, a)] == cb[dim_of(pv, a)]) a++;
    CHECK_LT(a, pv->naxes);
    const struct cfg_node *n = &pv->axes[a].node->items[cb[dim_of(pv, a)]];
    ok = cfg_fail(&pv->doc, n, pv->axes[a].key, e,
                  "two points would share the directory name '%s' (values that differ only in "
                  "characters a directory name cannot hold, or scenes with the same file name: "
                  "rename one)",
                  v[i].name);
  }
  free(v);
  return ok;
}

/* Rays a pixel traces, roughly: a primary ray, a shadow ray a light, a
 * mirror ray, and 9 diffuse rays with their own shadow rays. */
static double rays_per_pixel(uint32_t mask, uint32_t lights) {
  double shadow = (mask & RAY_MASK(RAY_SHADOW)) ? lights : 0;
  double r = 1 + shadow;
  if (mask & RAY_MASK(RAY_SPECULAR)) r += 1;
  if (mask & RAY_MASK(RAY_DIFFUSE)) r += 9 * (1 + shadow);
  return r;
}

/* Load each scene once: a bad scene is refused now, and a point takes its
 * default image size and the estimate's numbers from it. Scenes come from
 * workload.scene or from one axis (a key is given once); an axis's values are
 * distinct paths, since two values naming one file have one stem and so one
 * point name, refused before this (check_unique). So scene i is the axis's
 * value i, found by index: a long scene axis costs no search per point. */
static bool load_scenes(struct priv *pv, struct err *e) {
  unsigned axis = UINT_MAX;
  for (unsigned a = 0; a < pv->naxes; a++)
    if (pv->axes[a].wl == WL_SCENE) axis = a;
  const unsigned n = axis == UINT_MAX ? 1 : pv->axes[axis].node->count;
  pv->scenes = xcalloc(n, sizeof *pv->scenes);
  for (unsigned i = 0; i < n; i++) {
    const char *path = axis == UINT_MAX ? pv->scene_fixed : pv->axes[axis].resolved[i];
    struct scene sc;
    if (!scene_file_load(&sc, path, e)) return false;
    pv->scenes[pv->nscenes++] =
        (struct scene_info){dup_str(path), sc.width, sc.height, sc.tri_count, sc.light_count};
    scene_fini(&sc);
  }
  return true;
}

/* Argument vector under construction. */
struct args {
  char **v;
  unsigned n, cap;
};

static void arg(struct args *a, const char *fmt, ...) __attribute__((format(printf, 2, 3)));
static void arg(struct args *a, const char *fmt, ...) {
  if (a->n + 2 > a->cap) {
    a->cap = a->cap ? 2 * a->cap : 32;
    a->v = xrealloc(a->v, (unsigned long long)a->cap * sizeof *a->v);
  }
  char buf[8192];
  va_list ap;
  va_start(ap, fmt);
  vsnprintf(buf, sizeof buf, fmt, ap);
  va_end(ap);
  a->v[a->n++] = dup_str(buf);
  a->v[a->n] = NULL;
}

/* The workload value of key k for a point: its axis value, the fixed one, or NULL. */
static const char *workload_value(const struct priv *pv, const unsigned *choice, enum wl k,
                                  unsigned *axis) {
  for (unsigned a = 0; a < pv->naxes; a++)
    if (pv->axes[a].wl == k) {
      *axis = a;
      return pv->axes[a].node->items[choice[dim_of(pv, a)]].text;
    }
  *axis = UINT_MAX;
  return pv->wl[k] ? pv->wl[k]->text : NULL;
}

/* Point p's machine config check, its `rtsim run` arguments and its cost. */
static bool build_point(struct priv *pv, struct sweep_point *p, const unsigned *choice,
                        const char *out_dir, struct err *e) {
  struct machine_cfg c = pv->base;
  for (unsigned a = 0; a < pv->naxes; a++) {
    const struct axis *x = &pv->axes[a];
    if (x->machine_key < 0) continue;
    const struct cfg_node *n = &x->node->items[choice[dim_of(pv, a)]];
    CHECK(machine_cfg_set_at(&c, (unsigned)x->machine_key, n->text, pv->doc.file, n->line, n->col,
                             e)); /* each value was checked alone */
  }
  if (!machine_cfg_check(&c, e)) {
    size_t l = strlen(e->msg);
    snprintf(e->msg + l, sizeof e->msg - l, " [point %s]", p->name);
    if (!e->file[0]) snprintf(e->file, sizeof e->file, "%s", pv->doc.file);
    return false;
  }
  unsigned ax;
  const char *scene_text = workload_value(pv, choice, WL_SCENE, &ax);
  const unsigned si_index = ax == UINT_MAX ? 0 : choice[dim_of(pv, ax)];
  CHECK(scene_text && si_index < pv->nscenes);
  const struct scene_info *si = &pv->scenes[si_index];
  const char *scene = si->path;
  const char *policy = workload_value(pv, choice, WL_POLICY, &ax);
  const char *rays = workload_value(pv, choice, WL_RAYS, &ax);
  const char *width = workload_value(pv, choice, WL_WIDTH, &ax);
  const char *height = workload_value(pv, choice, WL_HEIGHT, &ax);
  const char *seed = workload_value(pv, choice, WL_SEED, &ax);
  const char *accel = workload_value(pv, choice, WL_ACCEL, &ax);
  uint32_t mask;
  CHECK(shade_parse_rays(rays ? rays : "primary,shadow,specular,diffuse", &mask));
  char rays_name[128];
  shade_rays_name(mask, rays_name, sizeof rays_name);
  /* Checked values: whole numbers in range (cfg_u64 read them already). */
  uint64_t w = si->width, h = si->height;
  CHECK(!width || scalar_u64(width, &w) == SCALAR_OK);
  CHECK(!height || scalar_u64(height, &h) == SCALAR_OK);
  /* Sampling's own limits need the point's policy and image size. */
  enum policy_kind pk;
  CHECK(policy_parse(policy ? policy : "recursive", &pk));
  char whybuf[512];
  const char *why =
      sample_problem(&c.sample, c.p.fidelity, pk, app_work_items(pk, (uint32_t)w, (uint32_t)h),
                     c.p.cores * c.p.threads_per_core * c.p.rays_per_thread, whybuf, sizeof whybuf);
  if (why) {
    const struct machine_cfg_origin *o = &c.at[machine_cfg_find("sample.fraction")];
    return err_set(e, o->file[0] ? o->file : pv->doc.file, o->line, o->col, "%s [point %s]", why,
                   p->name);
  }

  struct args a = {0};
  arg(&a, "run");
  arg(&a, "%s", pv->machine_path);
  arg(&a, "%s", scene);
  arg(&a, "-o");
  arg(&a, "%s/%s", out_dir, p->name);
  arg(&a, "--policy");
  arg(&a, "%s", policy ? policy : "recursive");
  arg(&a, "--rays");
  arg(&a, "%s", rays_name);
  arg(&a, "--width");
  arg(&a, "%llu", (unsigned long long)w);
  arg(&a, "--height");
  arg(&a, "%llu", (unsigned long long)h);
  if (seed) {
    uint64_t sv = 0;
    CHECK(scalar_u64(seed, &sv) == SCALAR_OK);
    arg(&a, "--seed");
    arg(&a, "%llu", (unsigned long long)sv);
  }
  if (accel) {
    arg(&a, "--accel");
    arg(&a, "%s", accel);
  }
  for (uint32_t i = 0; pv->sets && i < pv->sets->count; i++) {
    arg(&a, "--set");
    arg(&a, "%s=%s", pv->sets->items[i].key, pv->sets->items[i].text);
  }
  for (unsigned x = 0; x < pv->naxes; x++) {
    if (pv->axes[x].machine_key < 0) continue;
    arg(&a, "--set");
    arg(&a, "%s=%s", pv->axes[x].key, pv->axes[x].node->items[choice[dim_of(pv, x)]].text);
  }
  p->args = a.v;
  /* The expected host time, to start the longest points first: pixels x rays
   * a pixel traces x log2 of the triangles (a k-d tree descent) x a mild
   * growth with the ray contexts (their switches and working sets: on
   * tiny.yaml, 64 contexts took 1.5x the host time of 2 for the same image).
   * Latencies and cache sizes are left out: they move simulated cycles far
   * more than host seconds. A guess for ordering only. */
  const double contexts = (double)derived_contexts(&c.p);
  p->cost = (double)w * (double)h * rays_per_pixel(mask, si->lights) * log2(2.0 + si->tris) *
            (1.0 + log2(contexts) / 9.0);
  /* What a cluster job must request besides the simulation's own time, from
   * runs on the project's machine: loading a scene and building its tree took
   * 3.8 us a triangle (sphereflake, 797K triangles: 3.1 s), and the process
   * peaked at 22 MiB with a small scene plus 220 bytes a triangle. The
   * estimates round those up (a request too small kills the job): 1 s + 5 us
   * a triangle; 32 MiB + 256 bytes a triangle + 256 bytes a pixel (the image
   * and its channels) + 64 KiB a ray context (its coroutine stack, if all
   * touched). */
  p->setup_s = 1.0 + 5e-6 * si->tris;
  p->mem_mb = 32.0 + (256.0 * si->tris + 256.0 * (double)w * (double)h + 65536.0 * contexts) /
                         (1024.0 * 1024.0);
  return true;
}

bool sweep_load(struct sweep *s, const char *path, const char *out_dir, struct err *e) {
  return sweep_load_capped(s, path, out_dir, SWEEP_POINTS_DEFAULT, e);
}

bool sweep_load_capped(struct sweep *s, const char *path, const char *out_dir, unsigned max_points,
                       struct err *e) {
  memset(s, 0, sizeof *s);
  snprintf(s->file, sizeof s->file, "%s", path);
  struct priv *pv = xcalloc(1, sizeof *pv);
  s->priv = pv;
  CHECK(max_points >= 1 && max_points <= SWEEP_POINTS_MAX);
  if (!read_file(pv, path, e)) return false;

  /* The product's size, before anything is allocated for it: refused at the
   * dimension that takes it past the cap (the whole count is named, saturated
   * at 2^64 - 1, a count no sweep file can reach in 1 MiB anyway). */
  uint64_t total = 1;
  unsigned over = UINT_MAX;
  for (unsigned d = 0; d < pv->ndims; d++) {
    const uint64_t c = pv->dims[d].count;
    total = total > UINT64_MAX / c ? UINT64_MAX : total * c;
    if (total > max_points && over == UINT_MAX) over = d;
  }
  if (over != UINT_MAX) {
    const struct cfg_node *n = pv->axes[pv->dims[over].first].node;
    return err_set(e, pv->doc.file, n->key_line, n->key_col,
                   "%s: the sweep has %llu points (expected at most %u: fewer values, or raise "
                   "the cap with rtsim sweep --max-points N, up to %u)",
                   n->key, (unsigned long long)total, max_points, SWEEP_POINTS_MAX);
  }
  s->nkeys = pv->naxes;
  s->keys = xcalloc(pv->naxes, sizeof *s->keys);
  for (unsigned a = 0; a < pv->naxes; a++) s->keys[a] = pv->axes[a].key;
  s->npoints = (unsigned)total;
  s->points = xcalloc(total, sizeof *s->points);
  unsigned nd = pv->ndims ? pv->ndims : 1;
  unsigned *choices = xcalloc(total * nd, sizeof *choices);
  for (uint64_t i = 0; i < total; i++) {
    /* Mixed radix, the last dimension fastest. */
    unsigned *c = &choices[i * nd];
    uint64_t rest = i;
    for (unsigned d = pv->ndims; d-- > 0;) {
      c[d] = (unsigned)(rest % pv->dims[d].count);
      rest /= pv->dims[d].count;
    }
    struct sweep_point *p = &s->points[i];
    p->index = (unsigned)i;
    point_name(pv, c, p->name);
    p->values = xcalloc(pv->naxes ? pv->naxes : 1, sizeof *p->values);
    for (unsigned a = 0; a < pv->naxes; a++)
      p->values[a] = pv->axes[a].node->items[c[dim_of(pv, a)]].text;
  }
  bool ok = check_unique(pv, s, choices, e) && load_scenes(pv, e);
  for (unsigned i = 0; ok && i < s->npoints; i++)
    ok = build_point(pv, &s->points[i], &choices[(size_t)i * nd], out_dir, e);
  free(choices);
  if (!ok) { /* refused after the expansion: s is empty, as sweep.h promises */
    sweep_free(s);
    memset(s, 0, sizeof *s);
    snprintf(s->file, sizeof s->file, "%s", path);
  }
  return ok;
}

void sweep_free(struct sweep *s) {
  if (!s) return;
  for (unsigned i = 0; i < s->npoints; i++) {
    struct sweep_point *p = &s->points[i];
    for (char **a = p->args; a && *a; a++) free(*a);
    free(p->args);
    free(p->values);
  }
  free(s->points);
  free(s->keys);
  struct priv *pv = s->priv;
  if (pv) {
    for (unsigned a = 0; a < pv->naxes; a++) {
      for (uint32_t i = 0; pv->axes[a].resolved && i < pv->axes[a].node->count; i++)
        free(pv->axes[a].resolved[i]);
      free(pv->axes[a].resolved);
    }
    for (unsigned i = 0; i < pv->nscenes; i++) free(pv->scenes[i].path);
    free(pv->scenes);
    free(pv->axes);
    free(pv->dims);
    free(pv->scene_fixed);
    cfg_free(&pv->doc);
    free(pv);
  }
  memset(s, 0, sizeof *s);
}
