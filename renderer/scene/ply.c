/* Strict PLY reader. The header is parsed into element and property tables,
 * every declared count is checked against the bytes that follow the header
 * before anything is allocated, then the data is read in one forward pass.
 * Face lists are fanned while they stream (only the first and previous index
 * are kept), so no face is buffered; the triangle array grows by doubling and
 * is bounded by the data actually read. Worst case (int8 coordinates and
 * indices) that is under 30 bytes of memory per file byte: the file (up to 2x
 * while read), 4x for positions, 4x for normals, under 24x for triangles. No
 * recursion, no whitespace skipping between end_header and the data. */
#include "renderer/scene/ply.h"

#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "sim/err.h"

enum ply_type {
  PLY_INT8,
  PLY_UINT8,
  PLY_INT16,
  PLY_UINT16,
  PLY_INT32,
  PLY_UINT32,
  PLY_FLOAT32,
  PLY_FLOAT64,
  PLY_TYPE_COUNT
};

static const struct {
  const char *name, *alias;
  unsigned size;
  bool is_float;
  int64_t lo, hi; /* range of the integer types */
} ply_types[PLY_TYPE_COUNT] = {
    {"char", "int8", 1, false, INT8_MIN, INT8_MAX},
    {"uchar", "uint8", 1, false, 0, UINT8_MAX},
    {"short", "int16", 2, false, INT16_MIN, INT16_MAX},
    {"ushort", "uint16", 2, false, 0, UINT16_MAX},
    {"int", "int32", 4, false, INT32_MIN, INT32_MAX},
    {"uint", "uint32", 4, false, 0, UINT32_MAX},
    {"float", "float32", 4, true, 0, 0},
    {"double", "float64", 8, true, 0, 0},
};

enum { PLY_NAME_MAX = 64, PLY_WORDS_MAX = 8, PLY_TOKEN_MAX = 64 };

/* What a property feeds, if anything. */
enum ply_role {
  PLY_ROLE_NONE,
  PLY_ROLE_X,
  PLY_ROLE_Y,
  PLY_ROLE_Z,
  PLY_ROLE_NX,
  PLY_ROLE_NY,
  PLY_ROLE_NZ,
  PLY_ROLE_INDICES
};

struct ply_prop {
  char name[PLY_NAME_MAX];
  bool is_list;
  enum ply_type type, count_type; /* count_type only for lists */
  enum ply_role role;
};

struct ply_elem {
  char name[PLY_NAME_MAX];
  uint64_t count;
  int line;
  struct ply_prop *props;
  size_t nprops, cap;
};

enum ply_format { PLY_FMT_NONE, PLY_FMT_ASCII, PLY_FMT_LE, PLY_FMT_BE };

struct ply_value {
  bool is_int;
  int64_t i;
  double f;
};

/* Everything one parse needs; lives on ply_read_memory's stack. */
struct ply_reader {
  const unsigned char *buf;
  size_t len, pos;
  uint64_t file_len; /* bytes in the whole file: len, or more when buf is its header */
  uint64_t slack;    /* data bytes past every element's fewest (ply_check_counts) */
  const char *name;
  struct err *e;
  enum ply_format fmt;
  int line;          /* ASCII data: current 1-based line */
  size_t line_start; /* offset of that line's first byte */
  struct ply_elem *elems;
  size_t nelems, cap;
  struct ply_elem *vertex, *face;
  size_t tri_cap;
};

static bool ply_same_word(const char *a, const char *b) { return strcmp(a, b) == 0; }

static int ply_type_of(const char *word) {
  for (int t = 0; t < PLY_TYPE_COUNT; t++)
    if (ply_same_word(word, ply_types[t].name) || ply_same_word(word, ply_types[t].alias)) return t;
  return -1;
}

static bool ply_unknown_type(struct ply_reader *r, int line, const char *word) {
  return err_set(r->e, r->name, line, 0,
                 "PLY header: unknown type '%s' (expected one of: char, "
                 "uchar, short, ushort, int, uint, float, double, int8, uint8, int16, uint16, "
                 "int32, uint32, float32, float64)",
                 word);
}

/* Split a header line (NUL-terminated, no line break) at spaces and tabs. */
static int ply_split(char *line, char *words[PLY_WORDS_MAX]) {
  int n = 0;
  for (char *p = line; *p;) {
    while (*p == ' ' || *p == '\t') p++;
    if (!*p) break;
    if (n == PLY_WORDS_MAX) return n + 1;
    words[n++] = p;
    while (*p && *p != ' ' && *p != '\t') p++;
    if (*p) *p++ = '\0';
  }
  return n;
}

/* A whole decimal number for an element count, at most 2^63. */
static bool ply_parse_count(const char *s, uint64_t *out) {
  uint64_t v = 0;
  if (!*s) return false;
  for (; *s; s++) {
    if (*s < '0' || *s > '9') return false;
    if (v > (UINT64_MAX / 2 - 9) / 10) return false;
    v = v * 10 + (uint64_t)(*s - '0');
  }
  *out = v;
  return true;
}

static bool ply_add_elem(struct ply_reader *r, int line, const char *name, const char *count) {
  for (size_t i = 0; i < r->nelems; i++)
    if (ply_same_word(r->elems[i].name, name))
      return err_set(r->e, r->name, line, 0,
                     "PLY header: element '%s' declared twice (first at "
                     "line %d)",
                     name, r->elems[i].line);
  if (strlen(name) >= PLY_NAME_MAX)
    return err_set(r->e, r->name, line, 0,
                   "PLY header: element name too long (got %zu bytes, "
                   "expected at most %d)",
                   strlen(name), PLY_NAME_MAX - 1);
  uint64_t n;
  if (!ply_parse_count(count, &n))
    return err_set(r->e, r->name, line, 0,
                   "PLY header: element '%s': count is not a whole "
                   "number (got '%s')",
                   name, count);
  if (r->nelems == r->cap) {
    r->cap = r->cap ? 2 * r->cap : 4;
    r->elems = xrealloc(r->elems, r->cap * sizeof *r->elems);
  }
  struct ply_elem *el = &r->elems[r->nelems++];
  memset(el, 0, sizeof *el);
  memcpy(el->name, name, strlen(name) + 1);
  el->count = n;
  el->line = line;
  return true;
}

static bool ply_add_prop(struct ply_reader *r, int line, char **w, int nw) {
  if (r->nelems == 0)
    return err_set(r->e, r->name, line, 0, "PLY header: property before any element");
  struct ply_elem *el = &r->elems[r->nelems - 1];
  struct ply_prop p;
  memset(&p, 0, sizeof p);
  const char *name;
  if (nw >= 2 && ply_same_word(w[1], "list")) {
    if (nw != 5)
      return err_set(r->e, r->name, line, 0,
                     "PLY header: expected 'property list COUNT_TYPE "
                     "ITEM_TYPE NAME' (got %d words)",
                     nw);
    int ct = ply_type_of(w[2]), it = ply_type_of(w[3]);
    if (ct < 0) return ply_unknown_type(r, line, w[2]);
    if (it < 0) return ply_unknown_type(r, line, w[3]);
    if (ply_types[ct].is_float)
      return err_set(r->e, r->name, line, 0,
                     "PLY header: property '%s': list count type must be "
                     "an integer type (got '%s')",
                     w[4], w[2]);
    p.is_list = true;
    p.count_type = (enum ply_type)ct;
    p.type = (enum ply_type)it;
    name = w[4];
  } else {
    if (nw != 3)
      return err_set(r->e, r->name, line, 0,
                     "PLY header: expected 'property TYPE NAME' (got %d "
                     "words)",
                     nw);
    int t = ply_type_of(w[1]);
    if (t < 0) return ply_unknown_type(r, line, w[1]);
    p.type = (enum ply_type)t;
    name = w[2];
  }
  if (strlen(name) >= PLY_NAME_MAX)
    return err_set(r->e, r->name, line, 0,
                   "PLY header: property name too long (got %zu bytes, "
                   "expected at most %d)",
                   strlen(name), PLY_NAME_MAX - 1);
  for (size_t i = 0; i < el->nprops; i++)
    if (ply_same_word(el->props[i].name, name))
      return err_set(r->e, r->name, line, 0,
                     "PLY header: element '%s': property '%s' declared "
                     "twice",
                     el->name, name);
  memcpy(p.name, name, strlen(name) + 1);
  if (el->nprops == el->cap) {
    el->cap = el->cap ? 2 * el->cap : 4;
    el->props = xrealloc(el->props, el->cap * sizeof *el->props);
  }
  el->props[el->nprops++] = p;
  return true;
}

/* Give the vertex and face properties their roles and check they have the
 * shape rtsim needs. */
static bool ply_assign_roles(struct ply_reader *r) {
  static const struct {
    const char *name;
    enum ply_role role;
  } vroles[] = {{"x", PLY_ROLE_X},   {"y", PLY_ROLE_Y},   {"z", PLY_ROLE_Z},
                {"nx", PLY_ROLE_NX}, {"ny", PLY_ROLE_NY}, {"nz", PLY_ROLE_NZ}};
  for (size_t i = 0; i < r->nelems; i++) {
    if (ply_same_word(r->elems[i].name, "vertex")) r->vertex = &r->elems[i];
    if (ply_same_word(r->elems[i].name, "face")) r->face = &r->elems[i];
  }
  if (!r->vertex) return err_set(r->e, r->name, 0, 0, "PLY header: no 'vertex' element");
  if (!r->face)
    return err_set(r->e, r->name, 0, 0,
                   "PLY header: no 'face' element (rtsim imports "
                   "triangles, not point clouds)");
  struct ply_elem *v = r->vertex, *f = r->face;
  if (v->count > UINT32_MAX || f->count > UINT32_MAX)
    return err_set(r->e, r->name, v->count > UINT32_MAX ? v->line : f->line, 0,
                   "PLY header: element '%s': too many instances (got %llu, expected at most "
                   "%u)",
                   v->count > UINT32_MAX ? "vertex" : "face",
                   (unsigned long long)(v->count > UINT32_MAX ? v->count : f->count), UINT32_MAX);
  int have_n = 0;
  bool have[3] = {false, false, false};
  for (size_t i = 0; i < v->nprops; i++)
    for (size_t k = 0; k < sizeof vroles / sizeof vroles[0]; k++)
      if (ply_same_word(v->props[i].name, vroles[k].name)) {
        if (v->props[i].is_list)
          return err_set(r->e, r->name, v->line, 0,
                         "PLY header: vertex property '%s' is a list "
                         "(expected a scalar)",
                         v->props[i].name);
        v->props[i].role = vroles[k].role;
        if (k < 3) have[k] = true;
        else have_n++;
      }
  for (int k = 0; k < 3; k++)
    if (!have[k])
      return err_set(r->e, r->name, v->line, 0,
                     "PLY header: element 'vertex' has no property "
                     "'%s'",
                     vroles[k].name);
  /* Normals only when all three are there: a partial set is ignored. */
  if (have_n != 3)
    for (size_t i = 0; i < v->nprops; i++)
      if (v->props[i].role >= PLY_ROLE_NX) v->props[i].role = PLY_ROLE_NONE;
  struct ply_prop *idx = NULL;
  for (size_t i = 0; i < f->nprops; i++)
    if (ply_same_word(f->props[i].name, "vertex_indices") ||
        ply_same_word(f->props[i].name, "vertex_index")) {
      if (idx)
        return err_set(r->e, r->name, f->line, 0,
                       "PLY header: element 'face' has both "
                       "'vertex_indices' and 'vertex_index'");
      idx = &f->props[i];
    }
  if (!idx)
    return err_set(r->e, r->name, f->line, 0,
                   "PLY header: element 'face' has no property "
                   "'vertex_indices' (or 'vertex_index')");
  if (!idx->is_list || ply_types[idx->type].is_float)
    return err_set(r->e, r->name, f->line, 0,
                   "PLY header: face property '%s' must be a list of "
                   "an integer type",
                   idx->name);
  idx->role = PLY_ROLE_INDICES;
  return true;
}

/* The fewest bytes one instance of el can take in the data. */
static uint64_t ply_min_bytes(const struct ply_reader *r, const struct ply_elem *el) {
  uint64_t n = 0;
  for (size_t i = 0; i < el->nprops; i++) {
    const struct ply_prop *p = &el->props[i];
    bool idx = p->role == PLY_ROLE_INDICES;              /* at least 3 items */
    if (r->fmt == PLY_FMT_ASCII) n += 2 * (idx ? 4 : 1); /* a digit and a separator per value */
    else if (p->is_list)
      n += ply_types[p->count_type].size + (idx ? 3 * ply_types[p->type].size : 0);
    else n += ply_types[p->type].size;
  }
  return n;
}

/* Refuse counts the data cannot hold, before anything is allocated. */
static bool ply_check_counts(struct ply_reader *r) {
  uint64_t budget = r->file_len - r->pos;
  if (r->fmt == PLY_FMT_ASCII) budget++; /* the last line may lack its line break */
  for (size_t i = 0; i < r->nelems; i++) {
    const struct ply_elem *el = &r->elems[i];
    if (el->count == 0) continue;
    if (el->nprops == 0)
      return err_set(r->e, r->name, el->line, 0,
                     "PLY header: element '%s' has %llu instances "
                     "but no properties",
                     el->name, (unsigned long long)el->count);
    uint64_t min = ply_min_bytes(r, el);
    if (el->count > budget / min)
      return err_set(r->e, r->name, el->line, 0,
                     "PLY header: element '%s': %llu instances of "
                     "at least %llu bytes each cannot fit in the %llu bytes after the header",
                     el->name, (unsigned long long)el->count, (unsigned long long)min,
                     (unsigned long long)(r->file_len - r->pos));
    budget -= el->count * min;
  }
  r->slack = budget;
  return true;
}

/* Whether the n bytes at p begin with the word w (then a blank or the end). */
static bool ply_starts_word(const unsigned char *p, size_t n, const char *w) {
  size_t k = strlen(w);
  return n >= k && memcmp(p, w, k) == 0 && (n == k || p[k] == ' ' || p[k] == '\t');
}

static bool ply_parse_header(struct ply_reader *r) {
  const unsigned char *b = r->buf;
  size_t n = r->len;
  if (!(n >= 4 && memcmp(b, "ply\n", 4) == 0) && !(n >= 5 && memcmp(b, "ply\r\n", 5) == 0)) {
    char got[24];
    size_t k = 0;
    for (size_t i = 0; i < n && i < 8 && k + 5 < sizeof got; i++) {
      if (b[i] >= 0x20 && b[i] < 0x7f && b[i] != '\'') got[k++] = (char)b[i];
      else k += (size_t)snprintf(got + k, sizeof got - k, "\\x%02x", b[i]);
    }
    got[k] = '\0';
    return err_set(r->e, r->name, 1, 0, "not a PLY file: the first line must be 'ply' (got '%s')",
                   got);
  }
  char line[1024];
  int lineno = 0;
  size_t pos = 0;
  bool ended = false;
  while (!ended) {
    lineno++;
    const unsigned char *nl = memchr(b + pos, '\n', n - pos);
    if (!nl)
      return err_set(r->e, r->name, lineno, 0,
                     "PLY header: not terminated (no end_header line "
                     "before the end of the file; truncated?)");
    size_t end = (size_t)(nl - b), ll = end - pos;
    if (ll > 0 && b[end - 1] == '\r') ll--;
    for (size_t i = 0; i < ll; i++)
      if ((b[pos + i] < 0x20 && b[pos + i] != '\t') || b[pos + i] == 0x7f)
        return err_set(r->e, r->name, lineno, (int)i + 1, "PLY header: byte 0x%02x is not text",
                       b[pos + i]);
    if (ll >= sizeof line) {
      /* Comments may be long; nothing else needs to be. */
      bool remark =
          ply_starts_word(b + pos, ll, "comment") || ply_starts_word(b + pos, ll, "obj_info");
      if (!remark || lineno == 1)
        return err_set(r->e, r->name, lineno, 0,
                       "PLY header: line too long (got %zu bytes, "
                       "expected at most %zu)",
                       ll, sizeof line - 1);
      pos = end + 1;
      continue;
    }
    memcpy(line, b + pos, ll);
    line[ll] = '\0';
    pos = end + 1;
    if (lineno == 1) continue; /* "ply", checked above */
    char *w[PLY_WORDS_MAX];
    int nw = ply_split(line, w);
    if (nw == 0) return err_set(r->e, r->name, lineno, 0, "PLY header: empty line");
    if (ply_same_word(w[0], "comment") || ply_same_word(w[0], "obj_info")) continue;
    if (nw > PLY_WORDS_MAX)
      return err_set(r->e, r->name, lineno, 0, "PLY header: too many words on a '%s' line", w[0]);
    if (ply_same_word(w[0], "format")) {
      if (r->fmt != PLY_FMT_NONE)
        return err_set(r->e, r->name, lineno, 0, "PLY header: second format line");
      if (r->nelems)
        return err_set(r->e, r->name, lineno, 0, "PLY header: format line after an element");
      if (nw != 3)
        return err_set(r->e, r->name, lineno, 0,
                       "PLY header: expected 'format FORMAT 1.0' (got "
                       "%d words)",
                       nw);
      if (ply_same_word(w[1], "ascii")) r->fmt = PLY_FMT_ASCII;
      else if (ply_same_word(w[1], "binary_little_endian")) r->fmt = PLY_FMT_LE;
      else if (ply_same_word(w[1], "binary_big_endian")) r->fmt = PLY_FMT_BE;
      else
        return err_set(r->e, r->name, lineno, 0,
                       "PLY header: unknown format '%s' (expected "
                       "ascii, binary_little_endian or binary_big_endian)",
                       w[1]);
      if (!ply_same_word(w[2], "1.0"))
        return err_set(r->e, r->name, lineno, 0,
                       "PLY header: unsupported version '%s' "
                       "(expected 1.0)",
                       w[2]);
    } else if (ply_same_word(w[0], "element")) {
      if (r->fmt == PLY_FMT_NONE)
        return err_set(r->e, r->name, lineno, 0, "PLY header: element before the format line");
      if (nw != 3)
        return err_set(r->e, r->name, lineno, 0,
                       "PLY header: expected 'element NAME COUNT' "
                       "(got %d words)",
                       nw);
      if (!ply_add_elem(r, lineno, w[1], w[2])) return false;
    } else if (ply_same_word(w[0], "property")) {
      if (!ply_add_prop(r, lineno, w, nw)) return false;
    } else if (ply_same_word(w[0], "end_header")) {
      if (nw != 1)
        return err_set(r->e, r->name, lineno, 0, "PLY header: unexpected text after end_header");
      ended = true;
    } else {
      return err_set(r->e, r->name, lineno, 0,
                     "PLY header: unknown keyword '%s' (expected one "
                     "of: format, element, property, comment, obj_info, end_header)",
                     w[0]);
    }
  }
  if (r->fmt == PLY_FMT_NONE)
    return err_set(r->e, r->name, lineno, 0, "PLY header: no format line");
  r->pos = pos; /* exactly the byte after end_header's line break */
  r->line = lineno + 1;
  r->line_start = pos;
  return ply_assign_roles(r) && ply_check_counts(r);
}

/* Where a value sits, for messages: "element 'vertex' 12 property 'x'". */
struct ply_where {
  const struct ply_elem *el;
  uint64_t index;
  const struct ply_prop *prop;
};

static bool ply_data_error(struct ply_reader *r, size_t at, const struct ply_where *w,
                           const char *what) {
  if (r->fmt == PLY_FMT_ASCII)
    return err_set(r->e, r->name, r->line, (int)(at - r->line_start) + 1,
                   "PLY data: element '%s' %llu, property '%s': %s", w->el->name,
                   (unsigned long long)w->index, w->prop->name, what);
  return err_set(r->e, r->name, 0, 0, "byte %zu: PLY data: element '%s' %llu, property '%s': %s",
                 at, w->el->name, (unsigned long long)w->index, w->prop->name, what);
}

static uint64_t ply_load_uint(const unsigned char *p, unsigned size, bool big) {
  uint64_t v = 0;
  for (unsigned k = 0; k < size; k++) v |= (uint64_t)p[big ? size - 1 - k : k] << (8 * k);
  return v;
}

static bool ply_read_binary(struct ply_reader *r, enum ply_type t, const struct ply_where *w,
                            struct ply_value *v, size_t *at) {
  unsigned size = ply_types[t].size;
  *at = r->pos;
  if (r->len - r->pos < size) {
    char what[96];
    snprintf(what, sizeof what, "truncated (needs %u bytes, the file ends after %zu)", size,
             r->len - r->pos);
    return ply_data_error(r, r->pos, w, what);
  }
  uint64_t u = ply_load_uint(r->buf + r->pos, size, r->fmt == PLY_FMT_BE);
  r->pos += size;
  v->is_int = !ply_types[t].is_float;
  switch (t) {
  case PLY_INT8: v->i = (int8_t)(uint8_t)u; break;
  case PLY_INT16: v->i = (int16_t)(uint16_t)u; break;
  case PLY_INT32: v->i = (int32_t)(uint32_t)u; break;
  case PLY_FLOAT32: {
    uint32_t u32 = (uint32_t)u;
    float f;
    memcpy(&f, &u32, sizeof f);
    v->f = f;
    break;
  }
  case PLY_FLOAT64: memcpy(&v->f, &u, sizeof v->f); break;
  default: v->i = (int64_t)u; break; /* the unsigned types */
  }
  return true;
}

static bool ply_is_blank(unsigned char c) { return c == ' ' || c == '\t'; }

/* Skip whitespace and line breaks before an ASCII instance, counting lines. */
static void ply_skip_lines(struct ply_reader *r) {
  while (r->pos < r->len &&
         (ply_is_blank(r->buf[r->pos]) || r->buf[r->pos] == '\r' || r->buf[r->pos] == '\n')) {
    if (r->buf[r->pos] == '\n') {
      r->line++;
      r->line_start = r->pos + 1;
    }
    r->pos++;
  }
}

/* One ASCII value on the current line: an integer for the integer types (in
 * the type's range), a number strtod takes whole for the float types. */
static bool ply_read_ascii(struct ply_reader *r, enum ply_type t, const struct ply_where *w,
                           struct ply_value *v, size_t *at) {
  while (r->pos < r->len && ply_is_blank(r->buf[r->pos])) r->pos++;
  size_t s = r->pos;
  while (r->pos < r->len && !ply_is_blank(r->buf[r->pos]) && r->buf[r->pos] != '\r' &&
         r->buf[r->pos] != '\n')
    r->pos++;
  *at = s;
  size_t n = r->pos - s;
  if (n == 0) return ply_data_error(r, s, w, "missing value (the line ends)");
  char tok[PLY_TOKEN_MAX + 1];
  if (n > PLY_TOKEN_MAX) return ply_data_error(r, s, w, "value too long (over 64 bytes)");
  memcpy(tok, r->buf + s, n);
  tok[n] = '\0';
  for (size_t i = 0; i < n; i++)
    if (tok[i] < 0x21 || tok[i] > 0x7e) tok[i] = '?'; /* keep the message one printable line */
  char what[160];
  if (!ply_types[t].is_float) {
    const char *p = tok;
    bool neg = *p == '-';
    if (*p == '-' || *p == '+') p++;
    uint64_t u = 0;
    bool ok = *p != '\0';
    for (; ok && *p; p++) {
      if (*p < '0' || *p > '9' || u > UINT32_MAX) ok = false;
      else u = u * 10 + (uint64_t)(*p - '0');
    }
    int64_t i = neg ? -(int64_t)u : (int64_t)u;
    if (!ok || i < ply_types[t].lo || i > ply_types[t].hi) {
      snprintf(what, sizeof what,
               "not a whole number of type %s (got '%s', expected %lld to "
               "%lld)",
               ply_types[t].name, tok, (long long)ply_types[t].lo, (long long)ply_types[t].hi);
      return ply_data_error(r, s, w, what);
    }
    v->is_int = true;
    v->i = i;
    return true;
  }
  char *end = NULL;
  double d = strtod(tok, &end);
  if (end != tok + n) {
    snprintf(what, sizeof what, "not a number (got '%s')", tok);
    return ply_data_error(r, s, w, what);
  }
  v->is_int = false;
  v->f = t == PLY_FLOAT32 ? (double)(float)d : d;
  return true;
}

static bool ply_read_value(struct ply_reader *r, enum ply_type t, const struct ply_where *w,
                           struct ply_value *v, size_t *at) {
  return r->fmt == PLY_FMT_ASCII ? ply_read_ascii(r, t, w, v, at) : ply_read_binary(r, t, w, v, at);
}

/* After an ASCII instance: only blanks, then a line break or the end. */
static bool ply_end_line(struct ply_reader *r, const struct ply_elem *el, uint64_t index) {
  while (r->pos < r->len && ply_is_blank(r->buf[r->pos])) r->pos++;
  if (r->pos < r->len && r->buf[r->pos] == '\r') r->pos++;
  if (r->pos == r->len || r->buf[r->pos] == '\n') return true;
  return err_set(r->e, r->name, r->line, (int)(r->pos - r->line_start) + 1,
                 "PLY data: element '%s' %llu: unexpected text after its %zu properties "
                 "(expected the end of the line)",
                 el->name, (unsigned long long)index, el->nprops);
}

static void ply_push_tri(struct ply_reader *r, struct ply_mesh *m, uint32_t a, uint32_t b,
                         uint32_t c) {
  if (m->tri_count == r->tri_cap) {
    r->tri_cap = r->tri_cap ? 2 * r->tri_cap : 1024;
    m->tri = xrealloc(m->tri, r->tri_cap * 3 * sizeof *m->tri);
  }
  uint32_t *t = m->tri + 3 * (size_t)m->tri_count++;
  t[0] = a;
  t[1] = b;
  t[2] = c;
}

/* A list: its count, then its items; the face's index list is fanned. */
static bool ply_read_list(struct ply_reader *r, struct ply_mesh *m, const struct ply_where *w) {
  const struct ply_prop *p = w->prop;
  struct ply_value v;
  size_t at;
  if (!ply_read_value(r, p->count_type, w, &v, &at)) return false;
  if (v.i < 0) return ply_data_error(r, at, w, "negative list length");
  uint64_t count = (uint64_t)v.i;
  char what[160];
  if (p->role != PLY_ROLE_INDICES) {
    if (r->fmt != PLY_FMT_ASCII) {
      uint64_t need = count * ply_types[p->type].size;
      if (need > r->len - r->pos) {
        snprintf(what, sizeof what,
                 "truncated list (%llu items need %llu bytes, the file ends "
                 "after %zu)",
                 (unsigned long long)count, (unsigned long long)need, r->len - r->pos);
        return ply_data_error(r, r->pos, w, what);
      }
      r->pos += need;
      return true;
    }
    for (uint64_t k = 0; k < count; k++)
      if (!ply_read_value(r, p->type, w, &v, &at)) return false;
    return true;
  }
  if (count < 3) {
    snprintf(what, sizeof what, "a face needs at least 3 vertices (got %llu)",
             (unsigned long long)count);
    return ply_data_error(r, at, w, what);
  }
  uint32_t first = 0, prev = 0;
  for (uint64_t k = 0; k < count; k++) {
    if (!ply_read_value(r, p->type, w, &v, &at)) return false;
    if (v.i < 0 || (uint64_t)v.i >= m->vertex_count) {
      snprintf(what, sizeof what,
               "vertex index out of range (got %lld, the file has %u "
               "vertices)",
               (long long)v.i, m->vertex_count);
      return ply_data_error(r, at, w, what);
    }
    uint32_t cur = (uint32_t)v.i;
    if (k == 0) first = cur;
    if (k >= 2) {
      if (m->tri_count == UINT32_MAX)
        return ply_data_error(r, at, w, "too many triangles (over 4294967295)");
      ply_push_tri(r, m, first, prev, cur);
    }
    prev = cur;
  }
  return true;
}

static bool ply_read_data(struct ply_reader *r, struct ply_mesh *m) {
  m->vertex_count = (uint32_t)r->vertex->count;
  m->pos = xmalloc((uint64_t)m->vertex_count * 3 * sizeof *m->pos + 1);
  bool normals = false;
  for (size_t i = 0; i < r->vertex->nprops; i++) normals |= r->vertex->props[i].role == PLY_ROLE_NX;
  if (normals) m->normal = xmalloc((uint64_t)m->vertex_count * 3 * sizeof *m->normal + 1);
  for (size_t ei = 0; ei < r->nelems; ei++) {
    const struct ply_elem *el = &r->elems[ei];
    for (uint64_t idx = 0; idx < el->count; idx++) {
      if (r->fmt == PLY_FMT_ASCII) ply_skip_lines(r);
      for (size_t pi = 0; pi < el->nprops; pi++) {
        const struct ply_prop *p = &el->props[pi];
        struct ply_where w = {el, idx, p};
        if (p->is_list) {
          if (!ply_read_list(r, m, &w)) return false;
          continue;
        }
        struct ply_value v;
        size_t at;
        if (!ply_read_value(r, p->type, &w, &v, &at)) return false;
        if (p->role == PLY_ROLE_NONE) continue;
        float f = v.is_int ? (float)v.i : (float)v.f;
        int k = (int)p->role - (int)PLY_ROLE_X;
        if (k < 3) {
          if (!isfinite(f)) {
            char what[96];
            snprintf(what, sizeof what, "coordinate is not a finite float (got %g)",
                     v.is_int ? (double)v.i : v.f);
            return ply_data_error(r, at, &w, what);
          }
          m->pos[3 * idx + (uint64_t)k] = f;
        } else {
          m->normal[3 * idx + (uint64_t)(k - 3)] = f;
        }
      }
      if (r->fmt == PLY_FMT_ASCII && !ply_end_line(r, el, idx)) return false;
    }
  }
  if (r->fmt == PLY_FMT_ASCII) {
    ply_skip_lines(r);
    if (r->pos != r->len)
      return err_set(r->e, r->name, r->line, (int)(r->pos - r->line_start) + 1,
                     "PLY data: unexpected text after the last element");
  } else if (r->pos != r->len) {
    return err_set(r->e, r->name, 0, 0,
                   "byte %zu: PLY data: %zu bytes of trailing data after "
                   "the last element",
                   r->pos, r->len - r->pos);
  }
  return true;
}

bool ply_read_memory(const unsigned char *buf, size_t len, const char *name, struct ply_mesh *m,
                     struct err *e) {
  memset(m, 0, sizeof *m);
  struct ply_reader r;
  memset(&r, 0, sizeof r);
  r.buf = buf;
  r.len = len;
  r.file_len = len;
  r.name = name;
  r.e = e;
  bool ok = ply_parse_header(&r) && ply_read_data(&r, m);
  for (size_t i = 0; i < r.nelems; i++) free(r.elems[i].props);
  free(r.elems);
  if (!ok) ply_mesh_fini(m);
  return ok;
}

bool ply_read_file(const char *path, struct ply_mesh *m, struct err *e) {
  memset(m, 0, sizeof *m);
  const char *why;
  FILE *f = err_fopen_regular(path, &why);
  if (!f) return err_set(e, path, 0, 0, "cannot open: %s", why);
  /* Grow by doubling as bytes arrive: the buffer is at most twice the file. */
  size_t cap = 65536, len = 0, got;
  unsigned char *buf = xmalloc(cap);
  while ((got = fread(buf + len, 1, cap - len, f)) > 0) {
    len += got;
    if (len == cap) buf = xrealloc(buf, cap *= 2);
  }
  bool ok;
  if (ferror(f)) ok = err_set(e, path, 0, 0, "cannot read: %s", strerror(errno));
  else ok = ply_read_memory(buf, len, path, m, e);
  fclose(f);
  free(buf);
  return ok;
}

enum { PLY_HEADER_SCAN_MAX = 64 << 20 };

/* Whether the n bytes at b hold a whole header: a line whose only word is
 * end_header (what ply_parse_header ends at), ended by its line break. */
static bool ply_header_complete(const unsigned char *b, size_t n) {
  for (size_t pos = 0; pos < n;) {
    const unsigned char *nl = memchr(b + pos, '\n', n - pos);
    if (!nl) return false;
    size_t end = (size_t)(nl - b), i = pos;
    while (i < end && (b[i] == ' ' || b[i] == '\t')) i++;
    if (end - i >= 10 && memcmp(b + i, "end_header", 10) == 0) {
      i += 10;
      while (i < end && (b[i] == ' ' || b[i] == '\t' || b[i] == '\r')) i++;
      if (i == end) return true;
    }
    pos = end + 1;
  }
  return false;
}

bool ply_read_header_file(const char *path, struct ply_counts *c, struct err *e) {
  memset(c, 0, sizeof *c);
  const char *why;
  FILE *f = err_fopen_regular(path, &why);
  if (!f) return err_set(e, path, 0, 0, "cannot open: %s", why);
  /* Read until the header is whole: headers are short, but comments may be
   * long, so up to PLY_HEADER_SCAN_MAX bytes. */
  size_t cap = 4096, len = 0, got;
  unsigned char *buf = xmalloc(cap);
  bool whole = false;
  while (!(whole = ply_header_complete(buf, len)) && len < PLY_HEADER_SCAN_MAX &&
         (got = fread(buf + len, 1, cap - len, f)) > 0) {
    len += got;
    if (len == cap) buf = xrealloc(buf, cap *= 2);
  }
  bool ok = !ferror(f);
  if (!ok) err_set(e, path, 0, 0, "cannot read: %s", strerror(errno));
  else if (!whole && len >= PLY_HEADER_SCAN_MAX)
    ok = err_set(e, path, 0, 0, "PLY header: no end_header line in the first %d MiB",
                 PLY_HEADER_SCAN_MAX >> 20);
  /* The file's size bounds what its data can hold. */
  uint64_t file_len = UINT64_MAX;
  if (ok && fseek(f, 0, SEEK_END) == 0) {
    long end = ftell(f);
    if (end >= 0 && (uint64_t)end >= len) file_len = (uint64_t)end;
  }
  fclose(f);
  struct ply_reader r;
  memset(&r, 0, sizeof r);
  r.buf = buf;
  r.len = len;
  r.file_len = file_len;
  r.name = path;
  r.e = e;
  ok = ok && ply_parse_header(&r);
  if (ok) {
    const struct ply_prop *idx = NULL;
    for (size_t i = 0; i < r.face->nprops; i++)
      if (r.face->props[i].role == PLY_ROLE_INDICES) idx = &r.face->props[i];
    c->vertices = r.vertex->count;
    c->faces = r.face->count;
    /* Each index past a face's third adds a triangle and takes at least one
     * item's bytes (two characters in ASCII) of the slack. */
    uint64_t item = r.fmt == PLY_FMT_ASCII ? 2 : ply_types[idx->type].size;
    c->tri_max = file_len == UINT64_MAX ? UINT64_MAX : c->faces + r.slack / item;
  }
  for (size_t i = 0; i < r.nelems; i++) free(r.elems[i].props);
  free(r.elems);
  free(buf);
  return ok;
}

bool ply_claims(const char *path) {
  size_t n = strlen(path);
  if (n >= 4 && path[n - 4] == '.' && (path[n - 3] | 0x20) == 'p' && (path[n - 2] | 0x20) == 'l' &&
      (path[n - 1] | 0x20) == 'y')
    return true;
  const char *why;
  FILE *f = err_fopen_regular(path, &why);
  if (!f) return false;
  char head[3];
  bool ply = fread(head, 1, 3, f) == 3 && (head[0] | 0x20) == 'p' && (head[1] | 0x20) == 'l' &&
             (head[2] | 0x20) == 'y';
  fclose(f);
  return ply;
}

void ply_mesh_fini(struct ply_mesh *m) {
  if (!m) return;
  free(m->pos);
  free(m->normal);
  free(m->tri);
  memset(m, 0, sizeof *m);
}
