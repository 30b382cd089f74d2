/* The scratch folder and the generator stand-ins (fuzz_util.h). */
#define _XOPEN_SOURCE 700 /* nftw, realpath, symlink, mkdtemp */
#include "tests/fuzz/fuzz_util.h"

#include <dirent.h>
#include <ftw.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "renderer/scene.h"
#include "renderer/scene/gen.h"
#include "renderer/scene/meshio.h"
#include "sim/err.h"
#include "sim/machine.h"
#include "sim/machine_cfg.h"

static char dir[512];

static int remove_one(const char *path, const struct stat *st, int flag, struct FTW *ftw) {
  (void)st, (void)flag, (void)ftw;
  remove(path);
  return 0;
}

static void remove_dir(void) {
  if (dir[0]) nftw(dir, remove_one, 16, FTW_DEPTH | FTW_PHYS);
}

/* Folders made real in the scratch folder (parents first), each holding a
 * link to every entry of the repository's folder of the same name that is
 * not itself in this list; the inputs are written into them. */
static const char *const MIRRORED[] = {"",
                                       "configs",
                                       "configs/sweeps",
                                       "tests",
                                       "tests/data",
                                       "tests/data/configs",
                                       "tests/data/scenes",
                                       "tests/data/sweeps",
                                       NULL};

static void link_entries(const char *rel) {
  char src[1024], dst[1024];
  snprintf(src, sizeof src, "%s/%s", RTSIM_SOURCE_DIR, rel);
  DIR *d = opendir(src);
  CHECK(d != NULL);
  for (struct dirent *de; (de = readdir(d));) {
    if (!strcmp(de->d_name, ".") || !strcmp(de->d_name, "..")) continue;
    snprintf(dst, sizeof dst, "%s/%s%s%s", dir, rel, rel[0] ? "/" : "", de->d_name);
    if (access(dst, F_OK) == 0) continue; /* a mirrored folder */
    snprintf(src, sizeof src, "%s/%s%s%s", RTSIM_SOURCE_DIR, rel, rel[0] ? "/" : "", de->d_name);
    CHECK(symlink(src, dst) == 0);
  }
  closedir(d);
}

const char *fuzz_dir(void) {
  if (dir[0]) return dir;
  /* In memory where there is a tmpfs: every run writes its input. */
  const char *tmp = getenv("TMPDIR");
  if (!tmp || !tmp[0]) tmp = access("/dev/shm", W_OK) == 0 ? "/dev/shm" : P_tmpdir;
  snprintf(dir, sizeof dir, "%s/rtsim-fuzz-XXXXXX", tmp);
  CHECK(mkdtemp(dir) != NULL);
  atexit(remove_dir);
  char path[1024];
  for (unsigned i = 1; MIRRORED[i]; i++) {
    snprintf(path, sizeof path, "%s/%s", dir, MIRRORED[i]);
    CHECK(mkdir(path, 0755) == 0);
  }
  for (unsigned i = 0; MIRRORED[i]; i++) link_entries(MIRRORED[i]);
  return dir;
}

const char *fuzz_file(const char *rel, const uint8_t *data, size_t size) {
  static char path[1024];
  snprintf(path, sizeof path, "%s/%s", fuzz_dir(), rel);
  FILE *f = fopen(path, "wb");
  CHECK(f != NULL);
  CHECK(size == 0 || fwrite(data, 1, size, f) == size);
  CHECK(fclose(f) == 0);
  return path;
}

void fuzz_check_err(const struct err *e) {
  CHECK(e->set);
  CHECK(e->msg[0] != '\0');
  CHECK(strchr(e->msg, '\n') == NULL);
  CHECK(strchr(e->file, '\n') == NULL);
}

void fuzz_check_machine(const struct machine_cfg *c) {
  static struct machine_cfg again;
  again = *c;
  struct err e;
  memset(&e, 0, sizeof e);
  char text[256], back[256];
  for (unsigned i = 0; i < machine_cfg_count(); i++) {
    machine_cfg_value(c, i, text, sizeof text);
    CHECK(text[0] != '\0');
    CHECK(machine_cfg_set_at(&again, i, text, "round trip", 0, 0, &e));
    machine_cfg_value(&again, i, back, sizeof back);
    CHECK(strcmp(text, back) == 0);
  }
  CHECK(memcmp(&again.p, &c->p, sizeof c->p) == 0);
  static FILE *sink;
  if (!sink) CHECK((sink = fopen("/dev/null", "w")) != NULL);
  machine_cfg_write_json(c, sink, "  ");
}

/* ---- generator and mesh stand-ins (linked with --wrap) ------------------------ */

/* Detail up to which grove and room stay within FUZZ_GEN_TRIANGLES (measured:
 * grove gives 4,613 triangles up to detail 0.03, room 3,674 at 0.03; both
 * grow about linearly above). */
#define FUZZ_GROVE_DETAIL 0.03
#define FUZZ_ROOM_DETAIL 0.03

void __real_gen_sphereflake(struct scene *s, uint32_t levels, uint32_t tess);
void __real_gen_grove(struct scene *s, double detail, uint64_t seed);
void __real_gen_room(struct scene *s, double detail, uint64_t seed);
bool __real_meshio_import(struct scene *s, const char *path, const struct meshio_xform *xf,
                          uint32_t material, uint64_t max_tris, struct err *e);
uint64_t __real_gen_sphereflake_tri_count(uint32_t levels, uint32_t tess);
uint64_t __real_gen_grove_tri_count(double detail);
uint64_t __real_gen_room_tri_count(double detail);
void __wrap_gen_sphereflake(struct scene *s, uint32_t levels, uint32_t tess);
void __wrap_gen_grove(struct scene *s, double detail, uint64_t seed);
void __wrap_gen_room(struct scene *s, double detail, uint64_t seed);
uint64_t __wrap_gen_sphereflake_tri_count(uint32_t levels, uint32_t tess);
uint64_t __wrap_gen_grove_tri_count(double detail);
uint64_t __wrap_gen_room_tri_count(double detail);
bool __wrap_meshio_import(struct scene *s, const char *path, const struct meshio_xform *xf,
                          uint32_t material, uint64_t max_tris, struct err *e);

/* One triangle in place of a large generator's or mesh's. */
static void stand_in(struct scene *s, uint32_t material) {
  scene_add_tri(s, v3(0, 0, 0), v3(1, 0, 0), v3(0, 1, 0), NULL, material);
}

/* The scene reader counts a generator's triangles before it builds them and
 * checks the count after: the counts follow the stand-ins. */
uint64_t __wrap_gen_sphereflake_tri_count(uint32_t levels, uint32_t tess) {
  uint64_t n = __real_gen_sphereflake_tri_count(levels, tess);
  return n <= FUZZ_GEN_TRIANGLES ? n : 1;
}

uint64_t __wrap_gen_grove_tri_count(double detail) {
  return detail <= FUZZ_GROVE_DETAIL ? __real_gen_grove_tri_count(detail) : 1;
}

uint64_t __wrap_gen_room_tri_count(double detail) {
  return detail <= FUZZ_ROOM_DETAIL ? __real_gen_room_tri_count(detail) : 1;
}

void __wrap_gen_sphereflake(struct scene *s, uint32_t levels, uint32_t tess) {
  if (__real_gen_sphereflake_tri_count(levels, tess) <= FUZZ_GEN_TRIANGLES)
    __real_gen_sphereflake(s, levels, tess);
  else stand_in(s, scene_material_or_default(s, "flake", v3(1, 1, 1), 1, 0));
}

void __wrap_gen_grove(struct scene *s, double detail, uint64_t seed) {
  if (detail <= FUZZ_GROVE_DETAIL) __real_gen_grove(s, detail, seed);
  else stand_in(s, scene_material_or_default(s, "bark", v3(1, 1, 1), 1, 0));
}

void __wrap_gen_room(struct scene *s, double detail, uint64_t seed) {
  if (detail <= FUZZ_ROOM_DETAIL) __real_gen_room(s, detail, seed);
  else stand_in(s, scene_material_or_default(s, "wall", v3(1, 1, 1), 1, 0));
}

/* Meshes are read for real only from the repository's tests/data (small
 * files; the PLY reader has a target of its own) or when there is no such
 * file: a fuzz input never makes the importer open a device, a pipe or a
 * large file elsewhere. */
bool __wrap_meshio_import(struct scene *s, const char *path, const struct meshio_xform *xf,
                          uint32_t material, uint64_t max_tris, struct err *e) {
  static char data[1024];
  if (!data[0]) CHECK(realpath(RTSIM_SOURCE_DIR "/tests/data", data) != NULL);
  char *real = realpath(path, NULL);
  if (!real) return __real_meshio_import(s, path, xf, material, max_tris, e); /* no such file */
  struct stat st;
  bool ours = !strncmp(real, data, strlen(data)) && real[strlen(data)] == '/' &&
              stat(real, &st) == 0 && S_ISREG(st.st_mode) && st.st_size <= 65536;
  free(real);
  if (ours) return __real_meshio_import(s, path, xf, material, max_tris, e);
  stand_in(s, material);
  return true;
}
