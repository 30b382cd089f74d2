/* The strict PLY reader. Oracles: hand-built byte buffers whose values are
 * known here (floats compared bit for bit), both byte orders and ASCII, every
 * scalar type, fanned polygons; one malformed file per error with its message
 * and position; and end to end through the rtsim binary: an exported room read
 * back gives the same PLY bytes and the same hits, the 0.1-scaled room whose
 * first data byte is a line feed (the case assimp read shifted) reads back
 * exactly, and the shapes that crashed or hung assimp exit 2 with one line. */
#include "renderer/scene/ply.h"

#include <math.h>
#include <stdarg.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include "sim/err.h"
#include "testing.h"

/* A file under construction. */
struct bb {
  unsigned char d[16384];
  size_t n;
};

static const char *const type_name[8] = {"char", "uchar", "short", "ushort",
                                         "int",  "uint",  "float", "double"};
static const char *const type_alias[8] = {"int8",  "uint8",  "int16",   "uint16",
                                          "int32", "uint32", "float32", "float64"};
static const unsigned type_size[8] = {1, 1, 2, 2, 4, 4, 4, 8};

static void bb_str(struct bb *b, const char *s) {
  size_t n = strlen(s);
  CHECK(b->n + n <= sizeof b->d);
  memcpy(b->d + b->n, s, n);
  b->n += n;
}

static void bb_fmt(struct bb *b, const char *fmt, ...) __attribute__((format(printf, 2, 3)));
static void bb_fmt(struct bb *b, const char *fmt, ...) {
  char tmp[1024];
  va_list ap;
  va_start(ap, fmt);
  vsnprintf(tmp, sizeof tmp, fmt, ap);
  va_end(ap);
  bb_str(b, tmp);
}

static void bb_uint(struct bb *b, uint64_t v, unsigned size, bool big) {
  CHECK(b->n + size <= sizeof b->d);
  for (unsigned k = 0; k < size; k++)
    b->d[b->n + (big ? size - 1 - k : k)] = (unsigned char)(v >> (8 * k));
  b->n += size;
}

/* v stored as type t (0..7 in type_name order). */
static void bb_val(struct bb *b, int t, double v, bool big) {
  if (t == 6) {
    float f = (float)v;
    uint32_t u;
    memcpy(&u, &f, 4);
    bb_uint(b, u, 4, big);
  } else if (t == 7) {
    uint64_t u;
    memcpy(&u, &v, 8);
    bb_uint(b, u, 8, big);
  } else {
    bb_uint(b, (uint64_t)(int64_t)v, type_size[t], big);
  }
}

static void bb_f32bits(struct bb *b, uint32_t bits, bool big) { bb_uint(b, bits, 4, big); }

static uint32_t bits_of(float f) {
  uint32_t u;
  memcpy(&u, &f, 4);
  return u;
}

static void tmp_path(char *buf, size_t n, const char *name) {
  snprintf(buf, n, "%s/%s", RTSIM_TMP, name);
}

static bool write_bytes(const char *path, const void *data, size_t n) {
  FILE *f = fopen(path, "wb");
  if (!f) return false;
  bool ok = fwrite(data, 1, n, f) == n;
  return fclose(f) == 0 && ok;
}

/* Write b under `name` in the test's directory and read it back. */
static bool read_bb(const char *name, const struct bb *b, struct ply_mesh *m, struct err *e) {
  char path[1024];
  tmp_path(path, sizeof path, name);
  CHECK(write_bytes(path, b->d, b->n));
  memset(e, 0, sizeof *e);
  return ply_read_file(path, m, e);
}

static const char *fmt_name(bool big) { return big ? "binary_big_endian" : "binary_little_endian"; }

/* A binary file of one triangle whose first data byte is each of the bytes
 * assimp skipped, in both byte orders: read exactly, bit for bit. */
static void test_whitespace_first_byte(void) {
  static const unsigned char ws[4] = {0x0a, 0x0d, 0x09, 0x20};
  for (int big = 0; big < 2; big++)
    for (int i = 0; i < 4; i++) {
      /* The first byte in the file is the low byte (LE) or the high one (BE). */
      uint32_t x = big ? ((uint32_t)ws[i] << 24) | 0x123456u : 0x3f800000u | ws[i];
      const uint32_t rest[8] = {0x40000000u, 0xc0400000u, 0x3e99999au, 0x00000000u,
                                0x80000000u, 0x3f800000u, 0x41200000u, 0xbf000000u};
      struct bb b = {.n = 0};
      bb_fmt(&b,
             "ply\nformat %s 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
             "property float z\nelement face 1\nproperty list uchar int vertex_indices\n"
             "end_header\n",
             fmt_name(big));
      size_t first = b.n;
      bb_f32bits(&b, x, big);
      for (int k = 0; k < 8; k++) bb_f32bits(&b, rest[k], big);
      bb_uint(&b, 3, 1, big);
      for (int k = 0; k < 3; k++) bb_uint(&b, (uint64_t)(2 - k), 4, big);
      EXPECT(b.d[first] == ws[i]);
      struct ply_mesh m;
      struct err e;
      EXPECTF(read_bb("ws.ply", &b, &m, &e), "%s", e.msg);
      EXPECT(m.vertex_count == 3 && m.tri_count == 1 && m.normal == NULL);
      if (m.vertex_count == 3) {
        EXPECTF(bits_of(m.pos[0]) == x, "byte 0x%02x %s: x bits %08x", ws[i], fmt_name(big),
                bits_of(m.pos[0]));
        for (int k = 0; k < 8; k++) EXPECT(bits_of(m.pos[1 + k]) == rest[k]);
      }
      if (m.tri_count == 1) EXPECT(m.tri[0] == 2 && m.tri[1] == 1 && m.tri[2] == 0);
      ply_mesh_fini(&m);
    }
}

/* Every scalar type (by both its names) for x, y, z, in both byte orders. */
static void test_scalar_types(void) {
  for (int big = 0; big < 2; big++)
    for (int t = 0; t < 8; t++)
      for (int alias = 0; alias < 2; alias++) {
        const char *tn = alias ? type_alias[t] : type_name[t];
        bool is_signed = t == 0 || t == 2 || t == 4 || t >= 6;
        double vals[6] = {is_signed ? -5 : 5, 7, 100, 0, 1, is_signed ? -128 : 255};
        if (t >= 6) vals[0] = 0.1, vals[1] = -2.25, vals[2] = 1e-3;
        struct bb b = {.n = 0};
        bb_fmt(&b,
               "ply\nformat %s 1.0\ncomment types\nelement vertex 3\nproperty %s x\n"
               "property %s y\nproperty %s z\nelement face 1\n"
               "property list uchar uint vertex_indices\nend_header\n",
               fmt_name(big), tn, tn, tn);
        for (int k = 0; k < 6; k++) bb_val(&b, t, vals[k], big);
        bb_val(&b, t, 3, big); /* third vertex: (3, 3, 3) */
        bb_val(&b, t, 3, big);
        bb_val(&b, t, 3, big);
        bb_uint(&b, 3, 1, big);
        for (int k = 0; k < 3; k++) bb_uint(&b, (uint64_t)k, 4, big);
        struct ply_mesh m;
        struct err e;
        bool ok = read_bb("types.ply", &b, &m, &e);
        EXPECTF(ok, "%s %s: %s", tn, fmt_name(big), e.msg);
        for (int k = 0; ok && k < 6; k++)
          EXPECTF(bits_of(m.pos[k]) == bits_of((float)vals[k]), "%s %s value %d: got %g", tn,
                  fmt_name(big), k, (double)m.pos[k]);
        if (ok) EXPECT(m.pos[6] == 3.0f && m.pos[8] == 3.0f);
        ply_mesh_fini(&m);
      }
}

/* Every integer type as list count and as index, with a quad and a triangle. */
static void test_list_types(void) {
  static const int ints[6] = {0, 1, 2, 3, 4, 5};
  for (int big = 0; big < 2; big++)
    for (int ci = 0; ci < 6; ci++)
      for (int ii = 0; ii < 6; ii++) {
        int ct = ints[ci], it = ints[ii];
        struct bb b = {.n = 0};
        bb_fmt(&b,
               "ply\nformat %s 1.0\nelement vertex 4\nproperty double x\n"
               "property double y\nproperty double z\nelement face 2\n"
               "property list %s %s vertex_index\nend_header\n",
               fmt_name(big), type_name[ct], type_name[it]);
        const double q[4][3] = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}};
        for (int v = 0; v < 4; v++)
          for (int k = 0; k < 3; k++) bb_val(&b, 7, q[v][k], big);
        bb_val(&b, ct, 4, big);
        for (int k = 0; k < 4; k++) bb_val(&b, it, k, big);
        bb_val(&b, ct, 3, big);
        bb_val(&b, it, 3, big);
        bb_val(&b, it, 2, big);
        bb_val(&b, it, 1, big);
        struct ply_mesh m;
        struct err e;
        bool ok = read_bb("lists.ply", &b, &m, &e);
        EXPECTF(ok, "count %s index %s %s: %s", type_name[ct], type_name[it], fmt_name(big), e.msg);
        static const uint32_t want[9] = {0, 1, 2, 0, 2, 3, 3, 2, 1};
        EXPECT(!ok || m.tri_count == 3);
        if (ok && m.tri_count == 3) EXPECT(memcmp(m.tri, want, sizeof want) == 0);
        ply_mesh_fini(&m);
      }
}

/* ASCII with CRLF line breaks, blank and trailing whitespace, an extra vertex
 * property, normals, an extra element with a float list, a pentagon. */
static void test_ascii(void) {
  struct bb b = {.n = 0};
  bb_str(&b,
         "ply\r\nformat ascii 1.0\r\ncomment made by hand\r\nobj_info none\r\n"
         "element vertex 5\r\nproperty float32 x\r\nproperty float32 y\r\n"
         "property float32 z\r\nproperty uchar red\r\nproperty float nx\r\n"
         "property float ny\r\nproperty float nz\r\n"
         "element face 2\r\nproperty uchar flags\r\nproperty list uint8 int32 vertex_indices\r\n"
         "element edge 1\r\nproperty list uchar float weights\r\nend_header\r\n"
         "0 0 0 255 0 0 1\r\n1 0 0 0 0 0 1\r\n  1.5 1 0 7 0 0 2\r\n0.1 2 -0 1 0 0 1\r\n"
         "-1e-3 1 0 1 0 1 0\r\n"
         "9 5 0 1 2 3 4\r\n\r\n"
         "0 3 4 0 2\r\n"
         "3 0.5 -1 2e3   \r\n\r\n  \n");
  struct ply_mesh m;
  struct err e;
  bool ok = read_bb("ascii.ply", &b, &m, &e);
  EXPECTF(ok, "%s", e.msg);
  EXPECT(!ok || (m.vertex_count == 5 && m.tri_count == 4 && m.normal != NULL));
  if (ok && m.tri_count == 4 && m.normal) {
    static const uint32_t want[12] = {0, 1, 2, 0, 2, 3, 0, 3, 4, 4, 0, 2};
    EXPECT(memcmp(m.tri, want, sizeof want) == 0);
    EXPECT(bits_of(m.pos[9]) == bits_of(0.1f) && bits_of(m.pos[11]) == bits_of(-0.0f));
    EXPECT(bits_of(m.pos[12]) == bits_of(-1e-3f) && m.pos[6] == 1.5f);
    EXPECT(m.normal[2] == 1.0f && m.normal[8] == 2.0f && m.normal[13] == 1.0f);
  }
  ply_mesh_fini(&m);

  /* nx and ny without nz: no normals at all, not a half set. */
  b.n = 0;
  bb_str(&b, "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
             "property float z\nproperty float nx\nproperty float ny\nelement face 1\n"
             "property list uchar int vertex_indices\nend_header\n"
             "0 0 0 1 0\n1 0 0 1 0\n0 1 0 1 0\n3 0 1 2");
  ok = read_bb("ascii_half_normals.ply", &b, &m, &e);
  EXPECTF(ok, "%s", e.msg);
  EXPECT(!ok || (m.tri_count == 1 && m.normal == NULL));
  ply_mesh_fini(&m);
}

/* One malformed file: refused with `want` in the message at header line
 * `line` (0: none), and nothing left in the mesh. */
static void expect_refused(const char *label, const void *data, size_t n, const char *want,
                           int line) {
  char path[1024];
  tmp_path(path, sizeof path, "bad.ply");
  CHECK(write_bytes(path, data, n));
  struct ply_mesh m;
  struct err e = {0};
  bool ok = ply_read_file(path, &m, &e);
  EXPECTF(!ok, "%s: accepted", label);
  EXPECTF(e.set && strstr(e.msg, want) != NULL, "%s: got '%s', want '%s'", label, e.msg, want);
  EXPECTF(e.line == line, "%s: line %d, want %d (%s)", label, e.line, line, e.msg);
  EXPECTF(strcmp(e.file, path) == 0 && !strchr(e.msg, '\n'), "%s: file '%s'", label, e.file);
  EXPECT(m.pos == NULL && m.tri == NULL && m.normal == NULL && m.tri_count == 0);
  printf("  %-28s %d: %s\n", label, e.line, e.msg);
  ply_mesh_fini(&m);
}

#define HDR_V3(fmt)                                                                                \
  "ply\nformat " fmt " 1.0\nelement vertex 3\nproperty float x\n"                                  \
  "property float y\nproperty float z\nelement face 1\n"
#define IDX "property list uchar int vertex_indices\nend_header\n"

static void test_malformed_header(void) {
  static const struct {
    const char *label, *text, *want;
    int line;
  } cases[] = {
      {"empty file", "", "not a PLY file: the first line must be 'ply' (got '')", 1},
      {"wrong magic", "plx\nformat ascii 1.0\n", "not a PLY file", 1},
      {"garbled magic", "ply junk\nformat ascii 1.0\n", "(got 'ply junk')", 1},
      {"magic without newline", "ply", "not a PLY file", 1},
      {"unknown format", "ply\nformat binary_middle_endian 1.0\nend_header\n",
       "unknown format 'binary_middle_endian'", 2},
      {"unknown version", "ply\nformat ascii 2.0\nend_header\n", "unsupported version '2.0'", 2},
      {"unknown type", "ply\nformat ascii 1.0\nelement vertex 1\nproperty float128 x\n",
       "unknown type 'float128'", 4},
      {"unknown list type", "ply\nformat ascii 1.0\nelement face 1\nproperty list uchar int4 v\n",
       "unknown type 'int4'", 4},
      {"float list count", "ply\nformat ascii 1.0\nelement face 1\nproperty list float int v\n",
       "list count type must be an integer type", 4},
      {"unknown keyword", "ply\nformat ascii 1.0\nelemnt vertex 1\n", "unknown keyword 'elemnt'",
       3},
      {"property first", "ply\nformat ascii 1.0\nproperty float x\n", "property before any element",
       3},
      {"element before format", "ply\nelement vertex 1\n", "element before the format line", 2},
      {"no format", "ply\nend_header\n", "no format line", 2},
      {"count not a number", "ply\nformat ascii 1.0\nelement vertex -3\n",
       "count is not a whole number", 3},
      {"count with junk", "ply\nformat ascii 1.0\nelement vertex 3x\n",
       "count is not a whole number", 3},
      {"no end_header (37 bytes)", "ply\nformat binary_little_endian 1.0\ne", "not terminated", 3},
      {"binary in header", "ply\nformat ascii 1.0\ncomment \x01\n", "byte 0x01 is not text", 3},
      {"duplicate property",
       "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\n"
       "property float x\n",
       "property 'x' declared twice", 5},
      {"no vertex element", "ply\nformat ascii 1.0\nelement face 0\n" IDX, "no 'vertex' element",
       0},
      {"no face element",
       "ply\nformat ascii 1.0\nelement vertex 0\nproperty float x\n"
       "end_header\n",
       "no 'face' element", 0},
      {"no z",
       "ply\nformat ascii 1.0\nelement vertex 0\nproperty float x\nproperty float y\n"
       "element face 0\n" IDX,
       "element 'vertex' has no property 'z'", 3},
      {"no index list", HDR_V3("ascii") "property uchar flags\nend_header\n",
       "has no property 'vertex_indices'", 7},
      {"float indices", HDR_V3("ascii") "property list uchar float vertex_indices\nend_header\n",
       "must be a list of an integer type", 7},
      {"scalar indices", HDR_V3("ascii") "property int vertex_indices\nend_header\n",
       "must be a list of an integer type", 7},
      {"counts cannot fit", HDR_V3("binary_little_endian") IDX "\x01\x02",
       "element 'vertex': 3 instances of at least 12 bytes each cannot fit in the 2 bytes", 3},
      {"element without properties",
       "ply\nformat ascii 1.0\nelement blob 5\nelement vertex 0\nproperty float x\n"
       "property float y\nproperty float z\nelement face 0\n" IDX "1\n",
       "element 'blob' has 5 instances but no properties", 3},
  };
  /* A long comment is fine; a long line of anything else is not. */
  struct bb b = {.n = 0};
  bb_str(&b, "ply\nformat ascii 1.0\ncomment ");
  for (int i = 0; i < 3000; i++) bb_str(&b, "c");
  bb_str(&b, "\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
             "element face 1\n" IDX "0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n");
  struct ply_mesh m;
  struct err e;
  EXPECTF(read_bb("long_comment.ply", &b, &m, &e), "%s", e.msg);
  EXPECT(m.tri_count == 1);
  ply_mesh_fini(&m);
  b.n = 0;
  bb_str(&b, "ply\nformat ascii 1.0\nelement vertex 3");
  for (int i = 0; i < 3000; i++) bb_str(&b, " ");
  bb_str(&b, "\n");
  expect_refused("long line", b.d, b.n, "line too long (got 3016 bytes, expected at most 1023)", 3);
  printf("malformed headers:\n");
  for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++)
    expect_refused(cases[i].label, cases[i].text, strlen(cases[i].text), cases[i].want,
                   cases[i].line);
}

/* Binary data errors say "byte N"; ASCII ones carry line and column. */
static void test_malformed_data(void) {
  printf("malformed data:\n");
  struct bb b = {.n = 0};
  char want[128];

  /* Truncated inside the face list (the header's counts fit: 1 face of 13
   * bytes is promised, 10 arrive). */
  bb_str(&b, HDR_V3("binary_little_endian") IDX);
  size_t data = b.n;
  for (int k = 0; k < 9; k++) bb_val(&b, 6, k, false);
  bb_uint(&b, 3, 1, false);
  for (int k = 0; k < 3; k++) bb_uint(&b, (uint64_t)k, 4, false);
  struct bb ok_file = b; /* a correct file, for the trailing-data case */
  b.n -= 3;
  /* 3 * 12 + 13 = 49 bytes promised, 46 present: refused from the header... */
  expect_refused("truncated binary", b.d, b.n,
                 "element 'face': 1 instances of at least 13 bytes "
                 "each cannot fit",
                 7);
  /* ... so make the list longer than its minimum to reach the data reader. */
  b = ok_file;
  b.d[data + 36] = 4; /* a quad whose fourth index is missing */
  snprintf(want, sizeof want,
           "byte %zu: PLY data: element 'face' 0, property 'vertex_indices': "
           "truncated (needs 4 bytes, the file ends after 0)",
           data + 36 + 13);
  expect_refused("truncated binary list", b.d, b.n, want, 0);

  b = ok_file;
  bb_str(&b, "\n");
  snprintf(want, sizeof want, "byte %zu: PLY data: 1 bytes of trailing data", ok_file.n);
  expect_refused("trailing binary data", b.d, b.n, want, 0);

  b = ok_file;
  b.d[data + 36 + 5] = 3; /* second index: 3 of 3 vertices */
  snprintf(want, sizeof want,
           "byte %zu: PLY data: element 'face' 0, property 'vertex_indices': "
           "vertex index out of range (got 3, the file has 3 vertices)",
           data + 36 + 5);
  expect_refused("binary index out of range", b.d, b.n, want, 0);

  b = ok_file;
  memset(b.d + data + 36 + 9, 0xff, 4); /* third index: -1 */
  expect_refused("binary negative index", b.d, b.n, "vertex index out of range (got -1", 0);

  b = ok_file;
  b.d[data + 36] = 2; /* two indices, then 4 bytes nobody asked for */
  snprintf(want, sizeof want,
           "byte %zu: PLY data: element 'face' 0, property 'vertex_indices': "
           "a face needs at least 3 vertices (got 2)",
           data + 36);
  expect_refused("binary face of 2", b.d, b.n, want, 0);

  b = ok_file;
  memcpy(b.d + data + 4, "\x00\x00\xc0\x7f", 4); /* y of vertex 0: NaN */
  snprintf(want, sizeof want,
           "byte %zu: PLY data: element 'vertex' 0, property 'y': coordinate "
           "is not a finite float",
           data + 4);
  expect_refused("binary NaN", b.d, b.n, want, 0);

  b.n = 0; /* a double that overflows float */
  bb_str(&b, "ply\nformat binary_big_endian 1.0\nelement vertex 1\nproperty double x\n"
             "property double y\nproperty double z\nelement face 0\n" IDX);
  bb_val(&b, 7, 0, true);
  bb_val(&b, 7, 1e300, true);
  bb_val(&b, 7, 0, true);
  expect_refused("double overflows float", b.d, b.n,
                 "property 'y': coordinate is not a finite "
                 "float (got 1e+300)",
                 0);

  static const struct {
    const char *label, *data, *want;
    int line;
  } ascii[] = {
      {"ascii word", "0 0 0\n1 0 0\n0 1 abc\n3 0 1 2\n",
       "PLY data: element 'vertex' 2, property 'z': not a number (got 'abc')", 12},
      {"ascii trailing junk", "0 0 0\n1 0 0\n0 1 0x\n3 0 1 2\n", "not a number (got '0x')", 12},
      {"ascii extra value", "0 0 0\n1 0 0 5\n0 1 0\n3 0 1 2\n",
       "element 'vertex' 1: unexpected text after its 3 properties", 11},
      {"ascii missing value", "0 0 0\n1 0\n0 1 0\n3 0 1 2\n",
       "property 'z': missing value (the line ends)", 11},
      {"ascii short list", "0 0 0\n1 0 0\n0 1 0\n3 0 1\n", "missing value", 13},
      {"ascii index range", "0 0 0\n1 0 0\n0 1 0\n3 0 1 7\n",
       "vertex index out of range (got 7, the file has 3 vertices)", 13},
      {"ascii negative index", "0 0 0\n1 0 0\n0 1 0\n3 0 -1 2\n", "(got -1,", 13},
      {"ascii float index", "0 0 0\n1 0 0\n0 1 0\n3 0 1.0 2\n",
       "not a whole number of type int (got '1.0'", 13},
      {"ascii count range", "0 0 0\n1 0 0\n0 1 0\n300 0 1 2\n",
       "not a whole number of type uchar (got '300'", 13},
      {"ascii face of 2", "0 0 0\n1 0 0\n0 1 0\n2 0 1\n", "at least 3 vertices (got 2)", 13},
      {"ascii inf", "0 0 0\ninf 0 0\n0 1 0\n3 0 1 2\n", "coordinate is not a finite float", 11},
      {"ascii nan", "0 0 0\n1 nan 0\n0 1 0\n3 0 1 2\n", "coordinate is not a finite float", 11},
      {"ascii float overflow", "0 0 0\n1 0 1e39\n0 1 0\n3 0 1 2\n", "not a finite float", 11},
      {"ascii trailing element", "0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n3 0 1 2\n",
       "unexpected text after the last element", 14},
  };
  for (size_t i = 0; i < sizeof ascii / sizeof ascii[0]; i++) {
    b.n = 0;
    bb_str(&b, HDR_V3("ascii") IDX);
    bb_str(&b, ascii[i].data);
    bb_str(&b, "        \n"); /* trailing blanks, so the header's counts fit */
    expect_refused(ascii[i].label, b.d, b.n, ascii[i].want, ascii[i].line);
  }
}

/* A count of four billion in a small file: refused from the header alone,
 * before any allocation, in well under a second. */
static void test_absurd_count(void) {
  printf("absurd counts:\n");
  static const char *const texts[] = {
      "ply\nformat binary_little_endian 1.0\nelement vertex 4000000000\nproperty float x\n"
      "property float y\nproperty float z\nelement face 1\n" IDX "0123456789",
      "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
      "property float z\nelement face 4000000000\n" IDX "0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n",
      "ply\nformat binary_big_endian 1.0\nelement junk 999999999999999999\n"
      "property list uint char stuff\nelement vertex 0\nproperty char x\nproperty char y\n"
      "property char z\nelement face 0\n" IDX,
  };
  for (size_t i = 0; i < sizeof texts / sizeof texts[0]; i++) {
    clock_t t0 = clock();
    expect_refused("absurd count", texts[i], strlen(texts[i]), "cannot fit", 3 + 4 * (i == 1));
    double s = (double)(clock() - t0) / CLOCKS_PER_SEC;
    EXPECTF(s < 0.5, "absurd count %zu took %.3f s", i, s);
  }
}

/* ply_claims: by name or by the first three bytes. */
static void test_claims(void) {
  char path[1024];
  tmp_path(path, sizeof path, "claims.obj");
  CHECK(write_bytes(path, "PlY\n", 4));
  EXPECT(ply_claims(path));
  CHECK(write_bytes(path, "v 0 0 0\n", 8));
  EXPECT(!ply_claims(path));
  EXPECT(ply_claims("/no/such/dir/mesh.PLY"));
  EXPECT(!ply_claims("/no/such/dir/mesh.obj"));
}

/* ---- end to end through the rtsim binary ---- */

static long read_all(const char *path, unsigned char **out) {
  FILE *f = fopen(path, "rb");
  if (!f) return -1;
  fseek(f, 0, SEEK_END);
  long n = ftell(f);
  fseek(f, 0, SEEK_SET);
  *out = xmalloc((unsigned long long)n + 1);
  if (fread(*out, 1, (size_t)n, f) != (size_t)n) n = -1;
  fclose(f);
  return n;
}

static bool same_file(const char *a, const char *b) {
  unsigned char *da = NULL, *db = NULL;
  long na = read_all(a, &da), nb = read_all(b, &db);
  bool same = na >= 0 && na == nb && memcmp(da, db, (size_t)na) == 0;
  free(da);
  free(db);
  return same;
}

static void write_scene(const char *path, const char *mesh, const char *extra) {
  char text[1024];
  snprintf(text, sizeof text,
           "camera: {from: [0.7, 0.6, 1.6], at: [5.5, 4.6, 0.9], up: [0, 0, 1]}\n"
           "geometry:\n  - {mesh: %s%s}\n",
           mesh, extra);
  CHECK(write_bytes(path, text, strlen(text)));
}

static void test_cli_room(void) {
  char cmd[4096], out[65536];
  const char *room = RTSIM_TMP "/ply_room.ply", *scene = RTSIM_TMP "/ply_room_mesh.yaml",
             *again = RTSIM_TMP "/ply_room_again.ply";
  snprintf(cmd, sizeof cmd, "%s export %s/scenes/small/room.yaml -o %s", RTSIM_BINARY,
           RTSIM_SOURCE_DIR, room);
  EXPECTF(testing_run(cmd, out, sizeof out) == 0, "%s", out);
  write_scene(scene, "ply_room.ply", "");
  snprintf(cmd, sizeof cmd, "%s export %s -o %s", RTSIM_BINARY, scene, again);
  EXPECTF(testing_run(cmd, out, sizeof out) == 0, "%s", out);
  EXPECTF(strstr(out, "triangles: 5690\n") != NULL, "%s", out);
  EXPECTF(same_file(room, again), "re-export of the imported room differs from %s", room);

  /* The same hits, prim for prim, from the generator and from the PLY. */
  const char *rays = RTSIM_TMP "/ply_rays.csv";
  FILE *f = fopen(rays, "w");
  CHECK(f != NULL);
  fprintf(f, "id,ox,oy,oz,dx,dy,dz,tmin,tmax\n");
  for (int i = 0; i < 200; i++) {
    double a = 0.0314159 * i, b = 0.05 * (i % 17) - 0.4;
    fprintf(f, "%d,3.1,2.3,1.2,%.6f,%.6f,%.6f,0,inf\n", i, cos(a), sin(a), b);
  }
  fclose(f);
  char out2[65536];
  snprintf(cmd, sizeof cmd, "%s hits %s/scenes/small/room.yaml < %s", RTSIM_BINARY,
           RTSIM_SOURCE_DIR, rays);
  EXPECT(testing_run(cmd, out, sizeof out) == 0);
  snprintf(cmd, sizeof cmd, "%s hits %s < %s", RTSIM_BINARY, scene, rays);
  EXPECT(testing_run(cmd, out2, sizeof out2) == 0);
  EXPECTF(strcmp(out, out2) == 0, "hits differ");
  EXPECTF(strlen(out) > 2000, "hits output too short: %s", out);

  /* The room scaled by 0.1 (in double, rounded once to float): its first
   * data byte is 0x0a, so assimp read it shifted and refused it. */
  unsigned char *d = NULL;
  long n = read_all(room, &d);
  const char *end = n > 0 ? strstr((const char *)d, "end_header\n") : NULL;
  EXPECT(end != NULL);
  if (end) {
    size_t at = (size_t)(end - (const char *)d) + 11;
    unsigned long long nv = 3ull * 5690;
    for (size_t k = 0; k < 3 * nv; k++) {
      unsigned char *p = d + at + 4 * k;
      uint32_t u =
          (uint32_t)p[0] | (uint32_t)p[1] << 8 | (uint32_t)p[2] << 16 | (uint32_t)p[3] << 24;
      float x;
      memcpy(&x, &u, 4);
      x = (float)((double)x * 0.1);
      memcpy(&u, &x, 4);
      for (int j = 0; j < 4; j++) p[j] = (unsigned char)(u >> (8 * j));
    }
    EXPECTF(d[at] == 0x0a, "first data byte 0x%02x (the case needs a whitespace byte)", d[at]);
    const char *tenth = RTSIM_TMP "/ply_room_tenth.ply", *tscene = RTSIM_TMP "/ply_tenth.yaml",
               *tagain = RTSIM_TMP "/ply_room_tenth_again.ply";
    CHECK(write_bytes(tenth, d, (size_t)n));
    write_scene(tscene, "ply_room_tenth.ply", "");
    snprintf(cmd, sizeof cmd, "%s export %s -o %s", RTSIM_BINARY, tscene, tagain);
    EXPECTF(testing_run(cmd, out, sizeof out) == 0, "%s", out);
    EXPECTF(same_file(tenth, tagain), "the 0.1-scaled room does not read back exactly");
  }
  free(d);
}

static int count_lines(const char *s) {
  int n = 0;
  for (; *s; s++) n += *s == '\n';
  return n;
}

/* The shapes that crashed and hung assimp: exit 2, one line, in bounded time. */
static void test_cli_hostile(void) {
  struct bb crash = {.n = 0};
  bb_str(&crash, "ply\nformat binary_little_endian 1.0\nelement vertex 8\nproperty float x\n"
                 "property float y\nproperty float z\nelement face 1\n" IDX);
  while (crash.n < 177) bb_uint(&crash, 0x3f, 1, false);
  static const char looper[] = "ply\nformat binary_little_endian 1.0\ne";
  CHECK(crash.n == 177 && strlen(looper) == 37);
  static const struct {
    const char *name, *want;
  } cases[] = {
      {"ply_crash177.ply", "ply_crash177.ply:3: cannot import mesh: PLY header: element 'vertex': "
                           "8 instances of at least 12 bytes each cannot fit in the 8 bytes"},
      {"ply_loop37.ply", "ply_loop37.ply:3: cannot import mesh: PLY header: not terminated"},
  };
  char path[1024], scene[1024], cmd[4096], out[8192];
  for (int i = 0; i < 2; i++) {
    tmp_path(path, sizeof path, cases[i].name);
    CHECK(i == 0 ? write_bytes(path, crash.d, crash.n) : write_bytes(path, looper, 37));
    tmp_path(scene, sizeof scene, "ply_hostile.yaml");
    write_scene(scene, cases[i].name, ", scale: 2");
    const char *img = RTSIM_TMP "/ply_hostile.exr";
    unlink(img);
    snprintf(cmd, sizeof cmd, "timeout 60 %s render %s -o %s --width 8 --height 8", RTSIM_BINARY,
             scene, img);
    int rc = testing_run(cmd, out, sizeof out);
    EXPECTF(rc == 2, "%s: exit %d (124: timed out): %s", cases[i].name, rc, out);
    EXPECTF(strstr(out, cases[i].want) != NULL, "%s: got '%s', want '%s'", cases[i].name, out,
            cases[i].want);
    EXPECTF(strstr(out, "ply_hostile.yaml:3:") != NULL, "%s: no scene position: %s", cases[i].name,
            out);
    EXPECTF(count_lines(out) == 1, "%s: expected one line: %s", cases[i].name, out);
    EXPECTF(access(img, F_OK) != 0, "%s: image left behind", cases[i].name);
  }
}

int main(void) {
  test_whitespace_first_byte();
  test_scalar_types();
  test_list_types();
  test_ascii();
  test_malformed_header();
  test_malformed_data();
  test_absurd_count();
  test_claims();
  test_cli_room();
  test_cli_hostile();
  return testing_done("test_ply");
}
