/* YAML to a positioned tree, and typed getters. Loading takes two passes: the
 * first reads libyaml's events into a pool where an alias only refers to its
 * anchor's node, whose expanded size and height are known by then, so an alias
 * that would pass a limit of cfg.h is refused at the alias, before anything
 * grows; the second copies the pool into the tree, expanding aliases. NOTE:
 * libyaml's document API finds anchors by linear search: quadratic time. */
#include "sim/cfg.h"

#include <errno.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <yaml.h>

#include "sim/err.h"
#include "sim/near.h"
#include "sim/scalar.h"

#define PN_ALIAS 3 /* pool node kind besides enum cfg_kind */
#define PN_NONE UINT32_MAX
_Static_assert(CFG_SCALAR < PN_ALIAS && CFG_MAP < PN_ALIAS && CFG_SEQ < PN_ALIAS,
               "PN_ALIAS must differ from every enum cfg_kind");

/* A node as written in the file. Pool index 0 is unused: 0 means "none". */
struct pnode {
  uint64_t size;              /* nodes of the expanded subtree, itself included */
  uint32_t first, last, next; /* children in order, then the next sibling */
  uint32_t count;             /* children (a map: keys and values alternate) */
  uint32_t target;            /* PN_ALIAS: the anchored node (never an alias) */
  uint32_t text;              /* scalar: offset of its text in the string arena */
  uint32_t anchor;            /* offset of its anchor's name, or PN_NONE */
  int line, col;              /* 1-based */
  uint32_t height;            /* levels of the expanded subtree (a scalar: 1) */
  uint8_t kind;               /* enum cfg_kind or PN_ALIAS */
  bool open;                  /* a list or map whose end has not come */
};

struct loader {
  struct cfg_doc *d;
  struct err *e;
  struct pnode *pool;
  uint32_t npool, cap, root;
  char *str; /* arena of scalar texts and anchor names, NUL-terminated */
  size_t str_len, str_cap;
  uint32_t stack[CFG_MAX_DEPTH + 1]; /* open lists and maps, outermost first */
  unsigned depth;
  uint32_t *anchors; /* open-addressing table of anchored pool nodes, 0 = empty */
  uint32_t anchor_mask, anchor_count;
  uint64_t nodes, alias_nodes; /* after expansion; of which through aliases */
};

static uint32_t str_add(struct loader *L, const char *s, size_t len) {
  /* Bounded by the file size (each scalar and anchor is stored once). */
  CHECK_LT(L->str_len + len + 1, PN_NONE);
  if (L->str_len + len + 1 > L->str_cap) {
    while (L->str_len + len + 1 > L->str_cap) L->str_cap = L->str_cap ? 2 * L->str_cap : 4096;
    L->str = xrealloc(L->str, L->str_cap);
  }
  uint32_t at = (uint32_t)L->str_len;
  memcpy(L->str + at, s, len);
  L->str[at + len] = '\0';
  L->str_len += len + 1;
  return at;
}

static uint64_t name_hash(const char *s) {
  uint64_t h = 0xcbf29ce484222325ull; /* FNV-1a */
  for (; *s; s++) h = (h ^ (unsigned char)*s) * 0x100000001b3ull;
  return h;
}

/* The slot of anchor `name`: where it is, or the empty slot it would go in. */
static uint32_t *anchor_slot(struct loader *L, const char *name) {
  for (uint64_t h = name_hash(name);; h++) {
    uint32_t *t = &L->anchors[h & L->anchor_mask];
    if (*t == 0 || strcmp(L->str + L->pool[*t].anchor, name) == 0) return t;
  }
}

/* Anchor pool node i (its name already stored); a later anchor of the same
 * name replaces the earlier one, as YAML says. */
static void anchor_add(struct loader *L, uint32_t i) {
  if (2 * (L->anchor_count + 1) > L->anchor_mask + 1) {
    uint32_t *old = L->anchors, old_size = L->anchors ? L->anchor_mask + 1 : 0;
    uint32_t size = old_size ? 2 * old_size : 64;
    L->anchors = xcalloc(size, sizeof *L->anchors);
    L->anchor_mask = size - 1;
    for (uint32_t k = 0; k < old_size; k++)
      if (old[k]) *anchor_slot(L, L->str + L->pool[old[k]].anchor) = old[k];
    free(old);
  }
  uint32_t *t = anchor_slot(L, L->str + L->pool[i].anchor);
  if (*t == 0) L->anchor_count++;
  *t = i;
}

static uint64_t sat_add(uint64_t a, uint64_t b) { return a + b < a ? UINT64_MAX : a + b; }

/* Node `child` is complete: it counts in its parent's size and height. */
static void child_done(struct loader *L, uint32_t child) {
  if (L->depth == 0) return;
  struct pnode *c = &L->pool[child], *p = &L->pool[L->stack[L->depth - 1]];
  p->size = sat_add(p->size, c->size);
  if (c->height + 1 > p->height) p->height = c->height + 1;
}

/* Is the next child of the innermost open node a map key? */
static bool at_key(const struct loader *L) {
  if (L->depth == 0) return false;
  const struct pnode *p = &L->pool[L->stack[L->depth - 1]];
  return p->kind == CFG_MAP && p->count % 2 == 0;
}

/* Append a node to the pool as the next child of the innermost open node (or
 * as the root); 0 when a limit is passed (error set). */
static uint32_t node_add(struct loader *L, uint8_t kind, yaml_mark_t m, const yaml_char_t *anchor) {
  int line = (int)m.line + 1, col = (int)m.column + 1;
  if (L->depth > CFG_MAX_DEPTH) {
    err_set(L->e, L->d->file, line, col, "nesting deeper than %u levels", CFG_MAX_DEPTH);
    return 0;
  }
  if (kind != PN_ALIAS && ++L->nodes > CFG_MAX_NODES) {
    err_set(L->e, L->d->file, line, col,
            "too many YAML nodes (got more than %u, expected at most %u)", CFG_MAX_NODES,
            CFG_MAX_NODES);
    return 0;
  }
  if (L->npool == L->cap) {
    L->cap = L->cap ? 2 * L->cap : 256;
    L->pool = xrealloc(L->pool, (unsigned long long)L->cap * sizeof *L->pool);
  }
  uint32_t i = L->npool++;
  struct pnode *n = &L->pool[i];
  memset(n, 0, sizeof *n);
  n->kind = kind;
  n->line = line;
  n->col = col;
  n->size = 1;
  n->height = 1;
  n->anchor = PN_NONE;
  n->text = PN_NONE;
  if (L->depth > 0) {
    struct pnode *p = &L->pool[L->stack[L->depth - 1]];
    if (p->last) L->pool[p->last].next = i;
    else p->first = i;
    p->last = i;
    p->count++;
  } else if (!L->root) {
    L->root = i;
  }
  if (anchor) {
    L->pool[i].anchor = str_add(L, (const char *)anchor, strlen((const char *)anchor));
    anchor_add(L, i);
  }
  return i;
}

static bool on_alias(struct loader *L, const yaml_event_t *ev) {
  const char *name = (const char *)ev->data.alias.anchor;
  int line = (int)ev->start_mark.line + 1, col = (int)ev->start_mark.column + 1;
  uint32_t t = L->anchors ? *anchor_slot(L, name) : 0;
  if (t == 0)
    return err_set(L->e, L->d->file, line, col,
                   "alias '*%.64s' refers to no anchor defined before it", name);
  const struct pnode *tn = &L->pool[t];
  if (tn->open)
    return err_set(L->e, L->d->file, line, col, "alias '*%.64s' refers to a node that contains it",
                   name);
  if (at_key(L) && tn->kind != CFG_SCALAR)
    return err_set(L->e, L->d->file, line, col, "a key must be a plain word, not a list or map");
  if (L->depth + tn->height - 1 > CFG_MAX_DEPTH)
    return err_set(L->e, L->d->file, line, col, "alias '*%.64s': nesting deeper than %u levels",
                   name, CFG_MAX_DEPTH);
  uint64_t size = tn->size;
  L->alias_nodes = sat_add(L->alias_nodes, size);
  L->nodes = sat_add(L->nodes, size);
  if (L->alias_nodes > CFG_MAX_ALIAS_NODES)
    return err_set(L->e, L->d->file, line, col,
                   "alias '*%.64s': too many YAML nodes reached through aliases (got %llu, "
                   "expected at most %u)",
                   name, (unsigned long long)L->alias_nodes, CFG_MAX_ALIAS_NODES);
  if (L->nodes > CFG_MAX_NODES)
    return err_set(L->e, L->d->file, line, col,
                   "alias '*%.64s': too many YAML nodes (got %llu, expected at most %u)", name,
                   (unsigned long long)L->nodes, CFG_MAX_NODES);
  uint32_t i = node_add(L, PN_ALIAS, ev->start_mark, NULL);
  struct pnode *n = &L->pool[i];
  n->target = t;
  n->size = L->pool[t].size;
  n->height = L->pool[t].height;
  child_done(L, i);
  return true;
}

/* One parser event; *done when the first document (or the stream) ends. */
static bool on_event(struct loader *L, const yaml_event_t *ev, bool *done) {
  int line = (int)ev->start_mark.line + 1, col = (int)ev->start_mark.column + 1;
  switch (ev->type) {
  case YAML_STREAM_END_EVENT:
  case YAML_DOCUMENT_END_EVENT: *done = true; return true;
  case YAML_SCALAR_EVENT: {
    size_t len = ev->data.scalar.length;
    const char *text = (const char *)ev->data.scalar.value;
    if (len > CFG_MAX_SCALAR_BYTES)
      return err_set(L->e, L->d->file, line, col,
                     "scalar too long (got %zu bytes, expected at most %u)", len,
                     CFG_MAX_SCALAR_BYTES);
    /* A "\0" escape (or \x00, \u0000) would cut the text short: "4\0xyz"
     * would read as 4. */
    if (memchr(text, '\0', len))
      return err_set(L->e, L->d->file, line, col,
                     "a NUL character (\\0) in a %s (got '%s\\0...', expected text without one)",
                     at_key(L) ? "key" : "value", text);
    enum scalar_why w = at_key(L) ? scalar_text(text) : SCALAR_OK;
    if (w != SCALAR_OK)
      return err_set(L->e, L->d->file, line, col,
                     "key: %s (got '%s', expected a key without whitespace around it or control "
                     "characters)",
                     scalar_why_text(w), text);
    uint32_t i = node_add(L, CFG_SCALAR, ev->start_mark, ev->data.scalar.anchor);
    if (!i) return false;
    L->pool[i].text = str_add(L, text, len);
    child_done(L, i);
    return true;
  }
  case YAML_SEQUENCE_START_EVENT:
  case YAML_MAPPING_START_EVENT: {
    if (at_key(L))
      return err_set(L->e, L->d->file, line, col, "a key must be a plain word, not a list or map");
    bool seq = ev->type == YAML_SEQUENCE_START_EVENT;
    const yaml_char_t *anchor =
        seq ? ev->data.sequence_start.anchor : ev->data.mapping_start.anchor;
    uint32_t i = node_add(L, seq ? CFG_SEQ : CFG_MAP, ev->start_mark, anchor);
    if (!i) return false;
    L->pool[i].open = true;
    L->stack[L->depth++] = i;
    return true;
  }
  case YAML_SEQUENCE_END_EVENT:
  case YAML_MAPPING_END_EVENT: {
    CHECK_GT(L->depth, 0);
    uint32_t i = L->stack[--L->depth];
    L->pool[i].open = false;
    child_done(L, i);
    return true;
  }
  case YAML_ALIAS_EVENT: return on_alias(L, ev);
  default: /* stream and document starts */ return true;
  }
}

struct key_ref {
  const char *key;
  uint32_t i;
};

static int key_ref_cmp(const void *a, const void *b) {
  const struct key_ref *x = a, *y = b;
  int c = strcmp(x->key, y->key);
  return c ? c : (x->i > y->i) - (x->i < y->i);
}

/* The first key of map m (in file order) that repeats an earlier one, found by
 * sorting (a map may have tens of thousands of keys). */
static bool check_duplicates(const struct cfg_doc *d, const struct cfg_node *m, struct err *e) {
  if (m->count < 2) return true;
  struct key_ref *r = xmalloc((unsigned long long)m->count * sizeof *r);
  for (uint32_t i = 0; i < m->count; i++) r[i] = (struct key_ref){m->items[i].key, i};
  qsort(r, m->count, sizeof *r, key_ref_cmp);
  uint32_t dup = UINT32_MAX, first = 0, group = 0;
  for (uint32_t k = 1; k < m->count; k++) {
    if (strcmp(r[k].key, r[k - 1].key) != 0) {
      group = k;
      continue;
    }
    if (r[k].i < dup) {
      dup = r[k].i;
      first = r[group].i;
    }
  }
  free(r);
  if (dup == UINT32_MAX) return true;
  const struct cfg_node *v = &m->items[dup];
  return err_set(e, d->file, v->key_line, v->key_col, "duplicate key '%s' (first at line %d)",
                 v->key, m->items[first].key_line);
}

/* Copy pool node i into out, aliases expanded (copies keep the positions of
 * the anchored original). Depth is bounded by the first pass. */
static bool build(const struct loader *L, uint32_t i, struct cfg_node *out, struct err *e) {
  const struct pnode *n = &L->pool[i];
  if (n->kind == PN_ALIAS) n = &L->pool[n->target];
  out->line = n->line;
  out->col = n->col;
  out->kind = (enum cfg_kind)n->kind;
  if (n->kind == CFG_SCALAR) {
    out->text = L->d->strings + n->text;
    return true;
  }
  bool map = n->kind == CFG_MAP;
  out->count = map ? n->count / 2 : n->count;
  out->items = xcalloc(out->count ? out->count : 1, sizeof *out->items);
  uint32_t c = n->first;
  for (uint32_t k = 0; k < out->count; k++) {
    struct cfg_node *v = &out->items[k];
    if (map) {
      /* A key keeps where it is written, even an alias: it locates the entry. */
      const struct pnode *kw = &L->pool[c];
      const struct pnode *key = kw->kind == PN_ALIAS ? &L->pool[kw->target] : kw;
      CHECK_EQ(key->kind, CFG_SCALAR); /* the first pass refused other keys */
      v->key = L->d->strings + key->text;
      v->key_line = kw->line;
      v->key_col = kw->col;
      c = L->pool[c].next;
    }
    if (!build(L, c, v, e)) return false;
    c = L->pool[c].next;
  }
  return !map || check_duplicates(L->d, out, e);
}

static void node_free(struct cfg_node *n) {
  for (uint32_t i = 0; i < n->count; i++) node_free(&n->items[i]);
  free(n->items);
  free(n->asked);
  memset(n, 0, sizeof *n);
}

void cfg_free(struct cfg_doc *d) {
  if (!d) return;
  node_free(&d->root);
  free(d->strings);
  d->strings = NULL;
}

/* Position of byte `at` of text (1-based line and column, in bytes). */
static void text_position(const char *text, size_t at, int *line, int *col) {
  *line = 1;
  *col = 1;
  for (size_t i = 0; i < at; i++) {
    if (text[i] == '\n') {
      ++*line;
      *col = 1;
    } else {
      ++*col;
    }
  }
}

/* Parse len bytes of text (len <= CFG_MAX_FILE_BYTES) into d. */
static bool load(struct cfg_doc *d, const char *text, size_t len, struct err *e) {
  struct loader L;
  memset(&L, 0, sizeof L);
  L.d = d;
  L.e = e;
  L.npool = 1; /* index 0 means none */
  L.cap = 256;
  L.pool = xcalloc(L.cap, sizeof *L.pool);
  yaml_parser_t p;
  CHECK(yaml_parser_initialize(&p));
  yaml_parser_set_input_string(&p, (const unsigned char *)text, len);
  bool ok = true, done = false;
  while (ok && !done) {
    yaml_event_t ev;
    if (!yaml_parser_parse(&p, &ev)) {
      const char *what = p.problem ? p.problem : "malformed YAML";
      int line = (int)p.problem_mark.line + 1, col = (int)p.problem_mark.column + 1;
      if (p.error == YAML_READER_ERROR) {
        /* A byte libyaml cannot read (a raw NUL, a bad UTF-8 sequence): it
         * gives the byte's offset, not a mark. */
        if (p.problem_offset <= len) text_position(text, p.problem_offset, &line, &col);
        err_set(e, d->file, line, col, "YAML syntax: %s (byte 0x%02x)", what,
                (unsigned)p.problem_value & 0xffu);
      } else if (p.context) {
        err_set(e, d->file, line, col, "YAML syntax: %s %s", what, p.context);
      } else {
        err_set(e, d->file, line, col, "YAML syntax: %s", what);
      }
      ok = false;
      break;
    }
    ok = on_event(&L, &ev, &done);
    yaml_event_delete(&ev);
  }
  yaml_parser_delete(&p);
  if (ok && !L.root) ok = err_set(e, d->file, 0, 0, "empty file (expected a YAML map)");
  if (ok) {
    d->strings = L.str;
    L.str = NULL;
    ok = build(&L, L.root, &d->root, e);
  }
  free(L.pool);
  free(L.str);
  free(L.anchors);
  if (!ok) cfg_free(d);
  return ok;
}

/* Refuse text over the size limit, at its first byte past the limit. */
static bool size_ok(const struct cfg_doc *d, const char *text, size_t len, struct err *e) {
  if (len <= CFG_MAX_FILE_BYTES) return true;
  int line, col;
  text_position(text, CFG_MAX_FILE_BYTES, &line, &col);
  return err_set(e, d->file, line, col,
                 "file too large (got more than %u bytes, expected at most %u)", CFG_MAX_FILE_BYTES,
                 CFG_MAX_FILE_BYTES);
}

bool cfg_load_file(struct cfg_doc *d, const char *path, struct err *e) {
  memset(d, 0, sizeof *d);
  snprintf(d->file, sizeof d->file, "%s", path);
  const char *why;
  FILE *f = err_fopen_regular(path, &why); /* a pipe or device is refused unopened */
  if (!f) return err_set(e, path, 0, 0, "cannot open: %s", why);
  /* Read at most one byte past the limit: a file that grows as it is read
   * is refused like a large file. The buffer grows as the file does: a
   * megabyte for every small file costs an mmap and a munmap each time under
   * the sanitizers, which is most of a fuzzer's time (tests/fuzz). */
  const size_t limit = CFG_MAX_FILE_BYTES + 1;
  size_t cap = 4096, n = 0;
  char *buf = xmalloc(cap + 1);
  while ((n += fread(buf + n, 1, cap - n, f)) == cap && cap < limit) {
    cap = cap * 2 < limit ? cap * 2 : limit;
    buf = xrealloc(buf, cap + 1);
  }
  bool ok;
  if (ferror(f)) ok = err_set(e, path, 0, 0, "cannot read: %s", strerror(errno));
  else ok = size_ok(d, buf, n, e) && load(d, buf, n, e);
  fclose(f);
  free(buf);
  return ok;
}

bool cfg_load_text(struct cfg_doc *d, const char *name, const char *text, struct err *e) {
  memset(d, 0, sizeof *d);
  snprintf(d->file, sizeof d->file, "%s", name);
  size_t len = strlen(text);
  return size_ok(d, text, len, e) && load(d, text, len, e);
}

/* Record in map m that its reader asks for key (once). */
static void ask(struct cfg_node *m, const char *key) {
  const size_t klen = strlen(key);
  for (const char *p = m->asked; p && *p;) {
    const char *end = strchr(p, ',');
    size_t len = end ? (size_t)(end - p) : strlen(p);
    if (len == klen && !memcmp(p, key, klen)) return;
    p = end ? end + 2 : p + len;
  }
  const size_t sep = m->asked_len ? 2 : 0;
  m->asked = xrealloc(m->asked, m->asked_len + sep + klen + 1);
  memcpy(m->asked + m->asked_len, ", ", sep);
  memcpy(m->asked + m->asked_len + sep, key, klen + 1);
  m->asked_len += (uint32_t)(sep + klen);
}

struct cfg_node *cfg_peek(struct cfg_node *m, const char *key) {
  if (!m || m->kind != CFG_MAP) return NULL;
  for (uint32_t i = 0; i < m->count; i++)
    if (strcmp(m->items[i].key, key) == 0) return &m->items[i];
  return NULL;
}

struct cfg_node *cfg_get(struct cfg_node *m, const char *key) {
  if (!m || m->kind != CFG_MAP) return NULL;
  ask(m, key);
  struct cfg_node *n = cfg_peek(m, key);
  if (n) n->used = true;
  return n;
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
  return cfg_fail(d, n, path, e, "wrong type (got %s, expected a map of key: value)", kind_name(n));
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
  double v = 0;
  enum scalar_why w = scalar_f64(n->text, &v);
  if (w != SCALAR_OK)
    return cfg_fail(d, n, path, e, "not a number%s%s (got '%s', expected a decimal number)",
                    w == SCALAR_SYNTAX ? "" : ": ", scalar_why_text(w), n->text);
  if (v < lo || v > hi)
    return cfg_fail(d, n, path, e, "out of range (got %s, expected %g to %g)", n->text, lo, hi);
  *out = v;
  return true;
}

bool cfg_u64(const struct cfg_doc *d, const struct cfg_node *n, const char *path, uint64_t lo,
             uint64_t hi, uint64_t *out, struct err *e) {
  if (!expect_scalar(d, n, path, "a whole number", e)) return false;
  const char *s = n->text;
  uint64_t v = 0;
  enum scalar_why w = scalar_u64(s, &v);
  if (w == SCALAR_OVERFLOW || (w == SCALAR_OK && (v < lo || v > hi)))
    return cfg_fail(d, n, path, e, "out of range (got %s, expected %llu to %llu)", s,
                    (unsigned long long)lo, (unsigned long long)hi);
  if (w != SCALAR_OK)
    return cfg_fail(d, n, path, e, "not a whole number%s%s (got '%s', expected %llu to %llu)",
                    w == SCALAR_SYNTAX ? "" : ": ", scalar_why_text(w), s, (unsigned long long)lo,
                    (unsigned long long)hi);
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
  enum scalar_why w = scalar_text(n->text);
  if (w != SCALAR_OK)
    return cfg_fail(d, n, path, e,
                    "%s (got '%s', expected text without whitespace around it or control "
                    "characters)",
                    scalar_why_text(w), n->text);
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
      return cfg_fail(d, n, path, e, "wrong length (got %u numbers, expected %u)", n->count, count);
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
                    struct err *e) {
  const char *expected = m->asked ? m->asked : "(none)";
  for (uint32_t i = 0; i < m->count; i++) {
    const struct cfg_node *v = &m->items[i];
    if (v->used) continue;
    char where[256];
    if (path && path[0]) snprintf(where, sizeof where, "%s.%s", path, v->key);
    else snprintf(where, sizeof where, "%s", v->key);
    char near[256];
    if (near_words(v->key, expected, near, sizeof near))
      return err_set(e, d->file, v->key_line, v->key_col, "%s: unknown key '%s' (did you mean %s?)",
                     where, v->key, near);
    return err_set(e, d->file, v->key_line, v->key_col,
                   "%s: unknown key '%s' (expected one of: %s)", where, v->key, expected);
  }
  return true;
}
