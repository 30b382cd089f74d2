/* EXR write/read: FLOAT round trips bit-exactly, HALF within half precision
 * (exactly for half-representable values), files written by hand through the
 * raw chunk API (uncompressed, offset data window, tiled) are read or refused
 * as expected, and every failure names the file and leaves no output behind. */
#include "renderer/image.h"

#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include <openexr.h>

#include "sim/err.h"
#include "testing.h"

struct test_rng {
  uint64_t s;
};

static uint64_t test_rng_next(struct test_rng *r) {
  r->s ^= r->s << 13;
  r->s ^= r->s >> 7;
  r->s ^= r->s << 17;
  return r->s;
}

/* Uniform in [0,1). */
static double test_rng_unit(struct test_rng *r) {
  return (double)(test_rng_next(r) >> 11) * (1.0 / 9007199254740992.0);
}

static void tmp_path(char *buf, size_t n, const char *name) {
  snprintf(buf, n, "%s/%s", RTSIM_TMP, name);
}

static bool file_exists(const char *path) { return access(path, F_OK) == 0; }

static long file_size(const char *path) {
  FILE *f = fopen(path, "rb");
  if (!f) return -1;
  fseek(f, 0, SEEK_END);
  long n = ftell(f);
  fclose(f);
  return n;
}

static bool files_equal(const char *a, const char *b) {
  FILE *fa = fopen(a, "rb"), *fb = fopen(b, "rb");
  bool eq = fa && fb;
  while (eq) {
    int ca = fgetc(fa), cb = fgetc(fb);
    if (ca != cb) eq = false;
    if (ca == EOF || cb == EOF) break;
  }
  if (fa) fclose(fa);
  if (fb) fclose(fb);
  return eq;
}

static bool bits_equal(float a, float b) { return memcmp(&a, &b, sizeof a) == 0; }

/* Values spanning sign, tiny (denormal), huge and ordinary magnitudes. */
static float wild_value(struct test_rng *r) {
  double u = test_rng_unit(r);
  double sign = (test_rng_next(r) & 1) ? -1.0 : 1.0;
  switch (test_rng_next(r) % 6) {
  case 0: return (float)(sign * u);
  case 1: return (float)(sign * u * 1e-30);
  case 2: return (float)(sign * u * 1e30);
  case 3: return (float)(sign * 1e-42 * (1 + u)); /* float denormal */
  case 4: return 0.0f;
  default: return (float)(sign * (u * 1000.0));
  }
}

static void test_float_round_trip(void) {
  static const char *const names[] = {"R", "G", "B", "cost.nodes", "A"};
  struct image im;
  image_init(&im, 37, 19, 5, names);
  struct test_rng r = {0x9e3779b97f4a7c15ull};
  for (uint32_t c = 0; c < im.channel_count; c++)
    for (uint32_t i = 0; i < im.width * im.height; i++) im.planes[c][i] = wild_value(&r);
  im.planes[0][0] = -0.0f;
  im.planes[1][0] = 3.4028235e38f;

  char path[1024], path2[1024];
  tmp_path(path, sizeof path, "image_float.exr");
  tmp_path(path2, sizeof path2, "image_float_again.exr");
  remove(path);
  struct err e = {0};
  EXPECTF(image_write_exr(&im, path, false, &e), "%s", e.msg);
  EXPECT(file_exists(path));
  EXPECT(testing_temps_of(path) == 0);

  /* Same image, same bytes: outputs must be reproducible run to run. */
  EXPECTF(image_write_exr(&im, path2, false, &e), "%s", e.msg);
  EXPECT(files_equal(path, path2));

  struct image back;
  EXPECTF(image_read_exr(&back, path, &e), "%s", e.msg);
  EXPECT(back.width == 37 && back.height == 19 && back.channel_count == 5);
  for (uint32_t c = 0; c < im.channel_count; c++) {
    int b = image_channel(&back, names[c]);
    EXPECTF(b >= 0, "channel %s missing", names[c]);
    if (b < 0) continue;
    uint32_t bad = 0;
    for (uint32_t i = 0; i < im.width * im.height; i++)
      if (!bits_equal(im.planes[c][i], back.planes[b][i])) bad++;
    EXPECTF(bad == 0, "channel %s: %u pixels differ", names[c], bad);
  }
  /* Sorted by name in the file, so "A" comes back first. */
  EXPECT(strcmp(back.names[0], "A") == 0);
  EXPECT(image_channel(&back, "nope") == -1);
  image_fini(&back);

  /* Overwriting an existing file replaces it. */
  im.planes[2][5] = 42.0f;
  EXPECTF(image_write_exr(&im, path, false, &e), "%s", e.msg);
  EXPECTF(image_read_exr(&back, path, &e), "%s", e.msg);
  EXPECT(back.planes[image_channel(&back, "B")][5] == 42.0f);
  image_fini(&back);
  image_fini(&im);
  remove(path2);
}

static void test_half_round_trip(void) {
  static const char *const names[] = {"R", "G", "B"};
  /* Exactly representable in binary16: normals, subnormals, the extremes. */
  static const float exact[] = {0.0f,         1.0f,      -1.0f,         0.5f,          -3.25f,
                                65504.0f,     -65504.0f, 6.1035156e-5f, 5.9604645e-8f, 1024.0f,
                                0.099975586f, 2047.0f,   -0.33325195f};
  const uint32_t n_exact = sizeof exact / sizeof exact[0];
  struct image im;
  image_init(&im, 23, 41, 3, names);
  struct test_rng r = {12345};
  const uint32_t n = im.width * im.height;
  for (uint32_t c = 0; c < 3; c++)
    for (uint32_t i = 0; i < n; i++) {
      /* Magnitudes within half's normal range, log-uniform. */
      double mag = pow(10.0, -4.0 + 8.6 * test_rng_unit(&r));
      im.planes[c][i] = (float)((test_rng_next(&r) & 1) ? -mag : mag);
    }
  for (uint32_t i = 0; i < n_exact; i++) im.planes[1][i] = exact[i];

  char path[1024];
  tmp_path(path, sizeof path, "image_half.exr");
  struct err e = {0};
  EXPECTF(image_write_exr(&im, path, true, &e), "%s", e.msg);
  struct image back;
  EXPECTF(image_read_exr(&back, path, &e), "%s", e.msg);
  EXPECT(back.width == im.width && back.height == im.height && back.channel_count == 3);
  double worst = 0;
  for (uint32_t c = 0; c < 3; c++) {
    int b = image_channel(&back, names[c]);
    EXPECT(b >= 0);
    if (b < 0) continue;
    for (uint32_t i = c == 1 ? n_exact : 0; i < n; i++) {
      double rel = fabs((double)back.planes[b][i] - im.planes[c][i]) / fabs(im.planes[c][i]);
      if (rel > worst) worst = rel;
    }
  }
  EXPECTF(worst <= 1e-3, "worst relative error %g", worst);
  int g = image_channel(&back, "G");
  for (uint32_t i = 0; g >= 0 && i < n_exact; i++)
    EXPECTF(bits_equal(back.planes[g][i], exact[i]), "%.9g came back as %.9g", exact[i],
            back.planes[g][i]);
  image_fini(&back);
  image_fini(&im);
}

/* A noisy gradient, as a render would be: to compare HALF and FLOAT sizes. */
static void test_sizes(void) {
  static const char *const names[] = {"R", "G", "B"};
  struct image im;
  image_init(&im, 512, 512, 3, names);
  struct test_rng r = {777};
  for (uint32_t y = 0; y < 512; y++)
    for (uint32_t x = 0; x < 512; x++)
      for (uint32_t c = 0; c < 3; c++)
        im.planes[c][y * 512 + x] = (float)((x + y * (c + 1)) / 1024.0 + 0.02 * test_rng_unit(&r));
  char ph[1024], pf[1024];
  tmp_path(ph, sizeof ph, "image_512_half.exr");
  tmp_path(pf, sizeof pf, "image_512_float.exr");
  struct err e = {0};
  EXPECT(image_write_exr(&im, ph, true, &e));
  EXPECT(image_write_exr(&im, pf, false, &e));
  long sh = file_size(ph), sf = file_size(pf);
  printf("512x512 RGB noisy gradient, ZIP: half %ld bytes, float %ld bytes (raw %d / %d)\n", sh, sf,
         512 * 512 * 3 * 2, 512 * 512 * 3 * 4);
  EXPECT(sh > 0 && sf > sh);
  image_fini(&im);
  remove(ph);
  remove(pf);
}

/* Write an EXR by hand with raw (uncompressed) chunks: a 3x2 image with data
 * window origin (5,-2), channels Z (float) and Y (half), given in unsorted
 * order. Packed scanline layout: per line, per channel in sorted order. */
static bool write_raw_scanline(const char *path) {
  exr_context_initializer_t init = EXR_DEFAULT_CONTEXT_INITIALIZER;
  exr_context_t ctx = NULL;
  int part = 0;
  exr_attr_box2i_t dw;
  dw.min.x = 5;
  dw.min.y = -2;
  dw.max.x = 7;
  dw.max.y = -1;
  exr_attr_v2f_t center;
  center.x = center.y = 0.0f;
  exr_result_t rv = exr_start_write(&ctx, path, EXR_WRITE_FILE_DIRECTLY, &init);
  if (rv == EXR_ERR_SUCCESS) rv = exr_add_part(ctx, NULL, EXR_STORAGE_SCANLINE, &part);
  if (rv == EXR_ERR_SUCCESS)
    rv = exr_initialize_required_attr(ctx, part, &dw, &dw, 1.0f, &center, 1.0f,
                                      EXR_LINEORDER_INCREASING_Y, EXR_COMPRESSION_NONE);
  if (rv == EXR_ERR_SUCCESS)
    rv = exr_add_channel(ctx, part, "Z", EXR_PIXEL_FLOAT, EXR_PERCEPTUALLY_LINEAR, 1, 1);
  if (rv == EXR_ERR_SUCCESS)
    rv = exr_add_channel(ctx, part, "Y", EXR_PIXEL_HALF, EXR_PERCEPTUALLY_LINEAR, 1, 1);
  if (rv == EXR_ERR_SUCCESS) rv = exr_write_header(ctx);
  for (int y = -2; rv == EXR_ERR_SUCCESS && y <= -1; y++) {
    /* Y: halves 1.0 (0x3c00), 2.0 (0x4000), -0.5 (0xb800) times line sign. */
    uint8_t buf[3 * 2 + 3 * 4];
    uint16_t hv[3] = {0x3c00, 0x4000, 0xb800};
    for (int x = 0; x < 3; x++) {
      uint16_t v = hv[x] ^ (y == -1 ? 0x8000 : 0);
      buf[2 * x] = (uint8_t)(v & 0xff);
      buf[2 * x + 1] = (uint8_t)(v >> 8);
      float z = (float)(10 * y + x) + 0.25f;
      uint32_t u;
      memcpy(&u, &z, 4);
      for (int k = 0; k < 4; k++) buf[6 + 4 * x + k] = (uint8_t)(u >> (8 * k));
    }
    rv = exr_write_scanline_chunk(ctx, part, y, buf, sizeof buf);
  }
  exr_result_t fin = exr_finish(&ctx);
  return rv == EXR_ERR_SUCCESS && fin == EXR_ERR_SUCCESS;
}

static bool write_raw_tiled(const char *path) {
  exr_context_initializer_t init = EXR_DEFAULT_CONTEXT_INITIALIZER;
  exr_context_t ctx = NULL;
  int part = 0;
  exr_result_t rv = exr_start_write(&ctx, path, EXR_WRITE_FILE_DIRECTLY, &init);
  if (rv == EXR_ERR_SUCCESS) rv = exr_add_part(ctx, NULL, EXR_STORAGE_TILED, &part);
  if (rv == EXR_ERR_SUCCESS)
    rv = exr_initialize_required_attr_simple(ctx, part, 4, 4, EXR_COMPRESSION_NONE);
  if (rv == EXR_ERR_SUCCESS)
    rv = exr_set_tile_descriptor(ctx, part, 4, 4, EXR_TILE_ONE_LEVEL, EXR_TILE_ROUND_DOWN);
  if (rv == EXR_ERR_SUCCESS)
    rv = exr_add_channel(ctx, part, "R", EXR_PIXEL_FLOAT, EXR_PERCEPTUALLY_LINEAR, 1, 1);
  if (rv == EXR_ERR_SUCCESS) rv = exr_write_header(ctx);
  float data[16] = {0};
  if (rv == EXR_ERR_SUCCESS) rv = exr_write_tile_chunk(ctx, part, 0, 0, 0, 0, data, sizeof data);
  exr_result_t fin = exr_finish(&ctx);
  return rv == EXR_ERR_SUCCESS && fin == EXR_ERR_SUCCESS;
}

static void test_foreign_files(void) {
  char path[1024];
  struct err e = {0};
  struct image im;

  tmp_path(path, sizeof path, "image_raw_scanline.exr");
  EXPECT(write_raw_scanline(path));
  EXPECTF(image_read_exr(&im, path, &e), "%s", e.msg);
  EXPECT(im.width == 3 && im.height == 2 && im.channel_count == 2);
  int z = image_channel(&im, "Z"), y = image_channel(&im, "Y");
  EXPECT(z >= 0 && y >= 0);
  if (z >= 0 && y >= 0 && im.width == 3 && im.height == 2) {
    static const float want_y[6] = {1.0f, 2.0f, -0.5f, -1.0f, -2.0f, 0.5f};
    for (int i = 0; i < 6; i++) {
      int row = i / 3, x = i % 3;
      float want_z = (float)(10 * (row - 2) + x) + 0.25f;
      EXPECTF(im.planes[z][i] == want_z, "Z[%d] = %g, want %g", i, im.planes[z][i], want_z);
      EXPECTF(im.planes[y][i] == want_y[i], "Y[%d] = %g, want %g", i, im.planes[y][i], want_y[i]);
    }
  }
  image_fini(&im);

  tmp_path(path, sizeof path, "image_tiled.exr");
  EXPECT(write_raw_tiled(path));
  memset(&e, 0, sizeof e);
  EXPECT(!image_read_exr(&im, path, &e));
  EXPECT(e.set && strcmp(e.file, path) == 0);
  EXPECTF(strstr(e.msg, "tiled") != NULL, "%s", e.msg);
  EXPECT(im.channel_count == 0 && im.planes[0] == NULL);
  image_fini(&im); /* safe after a failed read */
}

static void test_errors(void) {
  char path[1024];
  struct err e = {0};
  struct image im;

  tmp_path(path, sizeof path, "no_such_file.exr");
  remove(path);
  EXPECT(!image_read_exr(&im, path, &e));
  EXPECT(e.set);
  EXPECTF(strcmp(e.file, path) == 0, "file = '%s'", e.file);
  EXPECTF(e.msg[0] != '\0', "empty message");
  printf("missing file: %s\n", e.msg);

  tmp_path(path, sizeof path, "not_an_exr.exr");
  FILE *f = fopen(path, "w");
  EXPECT(f != NULL);
  if (f) {
    fputs("P3\n1 1\n255\n0 0 0\nthis is not an OpenEXR file at all\n", f);
    fclose(f);
  }
  memset(&e, 0, sizeof e);
  EXPECT(!image_read_exr(&im, path, &e));
  EXPECT(e.set && strcmp(e.file, path) == 0);
  printf("not an EXR: %s\n", e.msg);

  tmp_path(path, sizeof path, "empty.exr");
  f = fopen(path, "w");
  if (f) fclose(f);
  memset(&e, 0, sizeof e);
  EXPECT(!image_read_exr(&im, path, &e));
  EXPECT(e.set && strcmp(e.file, path) == 0);
  printf("empty file: %s\n", e.msg);

  /* A truncated EXR: a valid header whose pixel chunks are cut off. */
  static const char *const names[] = {"R"};
  struct image small;
  image_init(&small, 64, 64, 1, names);
  for (uint32_t i = 0; i < 64 * 64; i++) small.planes[0][i] = (float)i;
  char whole[1024];
  tmp_path(whole, sizeof whole, "whole.exr");
  tmp_path(path, sizeof path, "truncated.exr");
  memset(&e, 0, sizeof e);
  EXPECT(image_write_exr(&small, whole, false, &e));
  long n = file_size(whole);
  FILE *in = fopen(whole, "rb"), *out = fopen(path, "wb");
  if (in && out && n > 0) {
    for (long i = 0; i < n * 2 / 3; i++) fputc(fgetc(in), out);
  }
  if (in) fclose(in);
  if (out) fclose(out);
  memset(&e, 0, sizeof e);
  EXPECT(!image_read_exr(&im, path, &e));
  EXPECT(e.set && strcmp(e.file, path) == 0);
  printf("truncated: %s\n", e.msg);

  /* Writing into a directory that does not exist: clean failure, no file. */
  tmp_path(path, sizeof path, "no_such_dir/out.exr");
  memset(&e, 0, sizeof e);
  EXPECT(!image_write_exr(&small, path, true, &e));
  EXPECT(e.set && strcmp(e.file, path) == 0);
  EXPECT(!file_exists(path));
  printf("bad directory: %s\n", e.msg);
  image_fini(&small);
}

int main(void) {
  test_float_round_trip();
  test_half_round_trip();
  test_sizes();
  test_foreign_files();
  test_errors();
  return testing_done("test_image");
}
