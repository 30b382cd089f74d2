/* YAML to a positioned tree (libyaml's document API), and typed getters. */
#include "sim/cfg.h"

#include <errno.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <yaml.h>

#include "sim/err.h"

/* Aliases may make the node graph deep or cyclic; no sane config nests this far. */
#define CFG_MAX_DEPTH 64

static char *dup_str(const char *s) {
  size_t n = strlen(s) + 1;
  char *p = xmalloc(n);
  memcpy(p, s, n);
  return p;
}

static void node_free(struct cfg_node *n) {
  for (uint32_t i = 0; i < n->count; i++) node_free(&n->items[i]);
  free(n->items);
  free(n->text);
  free(n->key);
  memset(n, 0, sizeof *n);
}

void cfg_free(struct cfg_doc *d) {
  if (d) node_free(&d->root);
}

static bool convert(const struct cfg_doc *d, yaml_document_t *doc, yaml_node_t *yn,
                    struct cfg_node *out, int depth, struct err *e) {
  out->line = (int)yn->start_mark.line + 1;
  out->col = (int)yn->start_mark.column + 1;
  if (depth > CFG_MAX_DEPTH)
    return err_set(e, d->file, out->line, out->col, "nesting deeper than %d levels",
                   CFG_MAX_DEPTH);
  switch (yn->type) {
  case YAML_SCALAR_NODE:
    out->kind = CFG_SCALAR;
    out->text = dup_str((const char *)yn->data.scalar.value);
    return true;
  case YAML_SEQUENCE_NODE: {
    out->kind = CFG_SEQ;
    yaml_node_item_t *b = yn->data.sequence.items.start, *t = yn->data.sequence.items.top;
    out->count = (uint32_t)(t - b);
    out->items = xcalloc(out->count, sizeof *out->items);
    for (uint32_t i = 0; i < out->count; i++)
      if (!convert(d, doc, yaml_document_get_node(doc, b[i]), &out->items[i], depth + 1, e))
        return false;
    return true;
  }
  case YAML_MAPPING_NODE: {
    out->kind = CFG_MAP;
    yaml_node_pair_t *b = yn->data.mapping.pairs.start, *t = yn->data.mapping.pairs.top;
    out->count = (uint32_t)(t - b);
    out->items = xcalloc(out->count, sizeof *out->items);
    for (uint32_t i = 0; i < out->count; i++) {
      yaml_node_t *k = yaml_document_get_node(doc, b[i].key);
      int kl = (int)k->start_mark.line + 1, kc = (int)k->start_mark.column + 1;
      if (k->type != YAML_SCALAR_NODE)
        return err_set(e, d->file, kl, kc, "a key must be a plain word, not a list or map");
      const char *key = (const char *)k->data.scalar.value;
      for (uint32_t j = 0; j < i; j++)
        if (strcmp(out->items[j].key, key) == 0)
          return err_set(e, d->file, kl, kc, "duplicate key '%s' (first at line %d)", key,
                         out->items[j].key_line);
      struct cfg_node *v = &out->items[i];
      v->key = dup_str(key);
      v->key_line = kl;
      v->key_col = kc;
      if (!convert(d, doc, yaml_document_get_node(doc, b[i].value), v, depth + 1, e))
        return false;
    }
    return true;
  }
  default:
    return err_set(e, d->file, out->line, out->col, "empty YAML node");
  }
}

static bool load(struct cfg_doc *d, yaml_parser_t *p, struct err *e) {
  yaml_document_t doc;
  bool ok = false;
  if (!yaml_parser_load(p, &doc)) {
    const char *what = p->problem ? p->problem : "malformed YAML";
    yaml_mark_t m = p->problem_mark;
    if (p->context)
      err_set(e, d->file, (int)m.line + 1, (int)m.column + 1, "YAML syntax: %s %s", what,
              p->context);
    else
      err_set(e, d->file, (int)m.line + 1, (int)m.column + 1, "YAML syntax: %s", what);
    return false;
  }
  yaml_node_t *root = yaml_document_get_root_node(&doc);
  if (!root)
    err_set(e, d->file, 0, 0, "empty file (expected a YAML map)");
  else
    ok = convert(d, &doc, root, &d->root, 0, e);
  yaml_document_delete(&doc);
  if (!ok) node_free(&d->root);
  return ok;
}

bool cfg_load_file(struct cfg_doc *d, const char *path, struct err *e) {
  memset(d, 0, sizeof *d);
  snprintf(d->file, sizeof d->file, "%s", path);
  FILE *f = fopen(path, "rb");
  if (!f) return err_set(e, path, 0, 0, "cannot open: %s", strerror(errno));
  yaml_parser_t p;
  CHECK(yaml_parser_initialize(&p));
  yaml_parser_set_input_file(&p, f);
  bool ok = load(d, &p, e);
  yaml_parser_delete(&p);
  fclose(f);
  return ok;
}

bool cfg_load_text(struct cfg_doc *d, const char *name, const char *text, struct err *e) {
  memset(d, 0, sizeof *d);
  snprintf(d->file, sizeof d->file, "%s", name);
  yaml_parser_t p;
  CHECK(yaml_parser_initialize(&p));
  yaml_parser_set_input_string(&p, (const unsigned char *)text, strlen(text));
  bool ok = load(d, &p, e);
  yaml_parser_delete(&p);
  return ok;
}

struct cfg_node *cfg_get(struct cfg_node *m, const char *key) {
  if (!m || m->kind != CFG_MAP) return NULL;
  for (uint32_t i = 0; i < m->count; i++)
    if (strcmp(m->items[i].key, key) == 0) {
      m->items[i].used = true;
      return &m->items[i];
    }
  return NULL;
}

bool cfg_fail(const struct cfg_doc *d, const struct cfg_node *n, const char *path, struct err *e,
              const char *fmt, ...) {
  char msg[ERR_MSG_MAX];
  va_list ap;
  va_start(ap, fmt);
  vsnprintf(msg, sizeof msg, fmt, ap);
  va_end(ap);
  if (path && path[0])
    return err_set(e, d->file, n ? n->line : 0, n ? n->col : 0, "%s: %s", path, msg);
  return err_set(e, d->file, n ? n->line : 0, n ? n->col : 0, "%s", msg);
}

static const char *kind_name(const struct cfg_node *n) {
  return n->kind == CFG_MAP ? "a map" : n->kind == CFG_SEQ ? "a list" : "a scalar";
}

bool cfg_expect_map(const struct cfg_doc *d, const struct cfg_node *n, const char *path,
                    struct err *e) {
  if (n->kind == CFG_MAP) return true;
  return cfg_fail(d, n, path, e, "wrong type (got %s, expected a map of key: value)",
                  kind_name(n));
}

bool cfg_expect_seq(const struct cfg_doc *d, const struct cfg_node *n, const char *path,
                    struct err *e) {
  if (n->kind == CFG_SEQ) return true;
  return cfg_fail(d, n, path, e, "wrong type (got %s, expected a list)", kind_name(n));
}

static bool expect_scalar(const struct cfg_doc *d, const struct cfg_node *n, const char *path,
                          const char *want, struct err *e) {
  if (n->kind == CFG_SCALAR) return true;
  return cfg_fail(d, n, path, e, "wrong type (got %s, expected %s)", kind_name(n), want);
}

bool cfg_f64(const struct cfg_doc *d, const struct cfg_node *n, const char *path, double lo,
             double hi, double *out, struct err *e) {
  if (!expect_scalar(d, n, path, "a number", e)) return false;
  char *end = NULL;
  errno = 0;
  double v = strtod(n->text, &end);
  if (end == n->text || *end != '\0' || errno == ERANGE || !isfinite(v))
    return cfg_fail(d, n, path, e, "not a number (got '%s', expected a number)", n->text);
  if (v < lo || v > hi)
    return cfg_fail(d, n, path, e, "out of range (got %s, expected %g to %g)", n->text, lo, hi);
  *out = v;
  return true;
}

bool cfg_u64(const struct cfg_doc *d, const struct cfg_node *n, const char *path, uint64_t lo,
             uint64_t hi, uint64_t *out, struct err *e) {
  if (!expect_scalar(d, n, path, "a whole number", e)) return false;
  const char *s = n->text;
  char *end = NULL;
  errno = 0;
  unsigned long long v = (s[0] >= '0' && s[0] <= '9') ? strtoull(s, &end, 0) : 0;
  if (!end || end == s || *end != '\0' || errno == ERANGE)
    return cfg_fail(d, n, path, e, "not a whole number (got '%s', expected %llu to %llu)", s,
                    (unsigned long long)lo, (unsigned long long)hi);
  if (v < lo || v > hi)
    return cfg_fail(d, n, path, e, "out of range (got %s, expected %llu to %llu)", s,
                    (unsigned long long)lo, (unsigned long long)hi);
  *out = v;
  return true;
}

bool cfg_bool(const struct cfg_doc *d, const struct cfg_node *n, const char *path, bool *out,
              struct err *e) {
  if (!expect_scalar(d, n, path, "true or false", e)) return false;
  if (strcmp(n->text, "true") == 0) *out = true;
  else if (strcmp(n->text, "false") == 0) *out = false;
  else return cfg_fail(d, n, path, e, "not a boolean (got '%s', expected true or false)", n->text);
  return true;
}

bool cfg_str(const struct cfg_doc *d, const struct cfg_node *n, const char *path, char *out,
             unsigned cap, struct err *e) {
  if (!expect_scalar(d, n, path, "a string", e)) return false;
  size_t len = strlen(n->text);
  if (len == 0) return cfg_fail(d, n, path, e, "empty string");
  if (len >= cap)
    return cfg_fail(d, n, path, e, "too long (got %zu characters, expected at most %u)", len,
                    cap - 1);
  memcpy(out, n->text, len + 1);
  return true;
}

bool cfg_f64_list(const struct cfg_doc *d, const struct cfg_node *n, const char *path,
                  unsigned count, double lo, double hi, double *out, struct err *e) {
  if (n->kind != CFG_SEQ || n->count != count) {
    if (n->kind == CFG_SEQ)
      return cfg_fail(d, n, path, e, "wrong length (got %u numbers, expected %u)", n->count,
                      count);
    return cfg_fail(d, n, path, e, "wrong type (got %s, expected a list of %u numbers)",
                    kind_name(n), count);
  }
  for (unsigned i = 0; i < count; i++) {
    char sub[256];
    snprintf(sub, sizeof sub, "%s[%u]", path, i);
    if (!cfg_f64(d, &n->items[i], sub, lo, hi, &out[i], e)) return false;
  }
  return true;
}

bool cfg_enum(const struct cfg_doc *d, const struct cfg_node *n, const char *path,
              const char *const *choices, int *out, struct err *e) {
  if (!expect_scalar(d, n, path, "a word", e)) return false;
  char list[512] = "";
  for (int i = 0; choices[i]; i++) {
    if (strcmp(n->text, choices[i]) == 0) {
      *out = i;
      return true;
    }
    size_t l = strlen(list);
    snprintf(list + l, sizeof list - l, "%s%s", i ? ", " : "", choices[i]);
  }
  return cfg_fail(d, n, path, e, "unknown value (got '%s', expected one of: %s)", n->text, list);
}

bool cfg_check_keys(const struct cfg_doc *d, const struct cfg_node *m, const char *path,
                    const char *expected, struct err *e) {
  for (uint32_t i = 0; i < m->count; i++) {
    const struct cfg_node *v = &m->items[i];
    if (v->used) continue;
    char where[256];
    if (path && path[0])
      snprintf(where, sizeof where, "%s.%s", path, v->key);
    else
      snprintf(where, sizeof where, "%s", v->key);
    return err_set(e, d->file, v->key_line, v->key_col,
                   "%s: unknown key '%s' (expected one of: %s)", where, v->key, expected);
  }
  return true;
}
