/* Mesh import and PLY export. Oracles: hand-written meshes (OBJ quad, ASCII
 * PLY tetrahedron, glTF with node transforms and instancing) whose placed
 * vertices are computed here; an exported PLY re-read by assimp itself must
 * give face i = primitive i bit for bit; every broken fixture fails with the
 * mesh path in the error and leaves the scene as it was. */
#include "renderer/scene/meshio.h"

#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include <assimp/cimport.h>
#include <assimp/postprocess.h>
#include <assimp/scene.h>

#include "renderer/scene.h"
#include "sim/err.h"
#include "testing.h"

static void tmp_path(char *buf, size_t n, const char *name) {
  snprintf(buf, n, "%s/%s", RTSIM_TMP, name);
}

static bool write_file(const char *path, const void *data, size_t n) {
  FILE *f = fopen(path, "wb");
  if (!f) return false;
  bool ok = fwrite(data, 1, n, f) == n;
  return fclose(f) == 0 && ok;
}

static bool write_text(const char *path, const char *text) {
  return write_file(path, text, strlen(text));
}

static bool v3_same(vec3 a, vec3 b) { return memcmp(&a, &b, sizeof a) == 0; }

static bool v3_near(vec3 a, vec3 b, float tol) {
  return fabsf(a.x - b.x) <= tol && fabsf(a.y - b.y) <= tol && fabsf(a.z - b.z) <= tol;
}

static vec3 placed(vec3 p, const struct meshio_xform *xf) {
  return v3_add(v3_scale(p, xf->scale), xf->translate);
}

static float tri_area(const struct scene_tri *t) {
  return 0.5f * v3_len(v3_cross(v3_sub(t->v[1], t->v[0]), v3_sub(t->v[2], t->v[0])));
}

/* A scene that already holds geometry, so "unchanged" is a real check. */
static void scene_with_two(struct scene *s) {
  scene_init(s);
  scene_add_tri(s, v3(0, 0, 0), v3(1, 0, 0), v3(0, 1, 0), NULL, 0);
  scene_add_tri(s, v3(0, 0, 1), v3(1, 0, 1), v3(0, 1, 1), NULL, 1);
}

static void test_obj_quad(void) {
  /* One quad (with a tilted normal from the file), a line and a point. */
  char path[1024];
  tmp_path(path, sizeof path, "quad.obj");
  EXPECT(write_text(path, "# quad\n"
                          "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\n"
                          "vn 0 0.6 0.8\n"
                          "f 1//1 2//1 3//1 4//1\n"
                          "l 1 3\n"
                          "p 2\n"));
  struct scene s;
  scene_with_two(&s);
  struct meshio_xform xf = {2.0f, {10.0f, 20.0f, 30.0f}};
  struct err e = {0};
  EXPECTF(meshio_import(&s, path, &xf, 7, UINT32_MAX, &e), "%s", e.msg);
  EXPECTF(s.tri_count == 4, "tri_count %u", s.tri_count);
  const vec3 corners[4] = {v3(0, 0, 0), v3(1, 0, 0), v3(1, 1, 0), v3(0, 1, 0)};
  bool seen[4] = {false, false, false, false};
  float area = 0;
  for (uint32_t i = 2; i < s.tri_count; i++) {
    const struct scene_tri *t = &s.tris[i];
    EXPECT(t->material == 7);
    area += tri_area(t);
    for (int k = 0; k < 3; k++) {
      int hit = -1;
      for (int c = 0; c < 4; c++)
        if (v3_same(t->v[k], placed(corners[c], &xf))) hit = c;
      EXPECTF(hit >= 0, "tri %u vertex %d (%g %g %g) is not a placed corner", i, k, t->v[k].x,
              t->v[k].y, t->v[k].z);
      if (hit >= 0) seen[hit] = true;
      EXPECTF(v3_near(t->n[k], v3(0, 0.6f, 0.8f), 1e-6f), "normal %g %g %g", t->n[k].x, t->n[k].y,
              t->n[k].z);
    }
  }
  EXPECT(seen[0] && seen[1] && seen[2] && seen[3]);
  EXPECTF(fabsf(area - 4.0f) < 1e-5f, "area %g", area); /* unit quad scaled by 2 */
  scene_fini(&s);

  /* Without normals in the file: flat normals (+Z for this winding). */
  tmp_path(path, sizeof path, "quad_flat.obj");
  EXPECT(write_text(path, "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3 4\n"));
  scene_init(&s);
  struct meshio_xform id = {1.0f, {0, 0, 0}};
  EXPECTF(meshio_import(&s, path, &id, 0, UINT32_MAX, &e), "%s", e.msg);
  EXPECT(s.tri_count == 2);
  for (uint32_t i = 0; i < s.tri_count; i++)
    for (int k = 0; k < 3; k++) EXPECT(v3_same(s.tris[i].n[k], v3(0, 0, 1)));
  scene_fini(&s);
}

static void test_ply_ascii(void) {
  char path[1024];
  tmp_path(path, sizeof path, "tetra_ascii.ply");
  EXPECT(write_text(path, "ply\nformat ascii 1.0\ncomment tetrahedron\n"
                          "element vertex 4\nproperty float x\nproperty float y\n"
                          "property float z\nelement face 4\n"
                          "property list uchar int vertex_indices\nend_header\n"
                          "0 0 0\n1 0 0\n0 1 0\n0 0 1\n"
                          "3 0 2 1\n3 0 1 3\n3 0 3 2\n3 1 2 3\n"));
  static const int faces[4][3] = {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}};
  const vec3 verts[4] = {v3(0, 0, 0), v3(1, 0, 0), v3(0, 1, 0), v3(0, 0, 1)};
  struct scene s;
  scene_init(&s);
  struct meshio_xform xf = {0.5f, {1.0f, -2.0f, 3.0f}};
  struct err e = {0};
  EXPECTF(meshio_import(&s, path, &xf, 3, UINT32_MAX, &e), "%s", e.msg);
  EXPECTF(s.tri_count == 4, "tri_count %u", s.tri_count);
  for (uint32_t i = 0; i < 4 && i < s.tri_count; i++) {
    EXPECT(s.tris[i].material == 3);
    for (int k = 0; k < 3; k++)
      EXPECTF(v3_same(s.tris[i].v[k], placed(verts[faces[i][k]], &xf)), "face %u vertex %d", i, k);
  }
  /* Flat normals point out of the tetrahedron: face 0 lies in z = 0. */
  if (s.tri_count >= 1) EXPECT(v3_near(s.tris[0].n[0], v3(0, 0, -1), 1e-6f));
  scene_fini(&s);
}

static void base64(const unsigned char *in, size_t n, char *out) {
  static const char tab[] = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  size_t o = 0;
  for (size_t i = 0; i < n; i += 3) {
    uint32_t v = (uint32_t)in[i] << 16;
    if (i + 1 < n) v |= (uint32_t)in[i + 1] << 8;
    if (i + 2 < n) v |= in[i + 2];
    out[o++] = tab[(v >> 18) & 63];
    out[o++] = tab[(v >> 12) & 63];
    out[o++] = i + 1 < n ? tab[(v >> 6) & 63] : '=';
    out[o++] = i + 2 < n ? tab[v & 63] : '=';
  }
  out[o] = '\0';
}

static void put_f32(unsigned char *p, float f) {
  uint32_t u;
  memcpy(&u, &f, 4);
  for (int k = 0; k < 4; k++) p[k] = (unsigned char)(u >> (8 * k));
}

/* glTF 2.0, buffer embedded as base64: one triangle mesh used by two nodes,
 * one translated and scaled, one translated; the two instances must both
 * arrive with their node transform applied. */
static void test_gltf(void) {
  unsigned char buf[80] = {0};
  const float pos[9] = {0, 0, 0, 1, 0, 0, 0, 1, 0};
  const float nrm[9] = {0, 0, 1, 0, 0, 1, 0, 0, 1};
  for (int i = 0; i < 9; i++) put_f32(buf + 4 * i, pos[i]);
  for (int i = 0; i < 9; i++) put_f32(buf + 36 + 4 * i, nrm[i]);
  const uint16_t idx[3] = {0, 1, 2};
  for (int i = 0; i < 3; i++) {
    buf[72 + 2 * i] = (unsigned char)(idx[i] & 0xff);
    buf[73 + 2 * i] = (unsigned char)(idx[i] >> 8);
  }
  char b64[128];
  base64(buf, sizeof buf, b64);
  char json[4096];
  snprintf(
      json, sizeof json,
      "{\"asset\":{\"version\":\"2.0\"},\"scene\":0,\"scenes\":[{\"nodes\":[0,1]}],\n"
      "\"nodes\":[{\"mesh\":0,\"translation\":[5,0,0],\"scale\":[2,2,2]},\n"
      "          {\"mesh\":0,\"translation\":[0,0,-3]}],\n"
      "\"meshes\":[{\"primitives\":[{\"attributes\":{\"POSITION\":0,\"NORMAL\":1},"
      "\"indices\":2}]}],\n"
      "\"buffers\":[{\"byteLength\":80,\"uri\":\"data:application/octet-stream;base64,%s\"}],\n"
      "\"bufferViews\":[{\"buffer\":0,\"byteOffset\":0,\"byteLength\":36},\n"
      "  {\"buffer\":0,\"byteOffset\":36,\"byteLength\":36},\n"
      "  {\"buffer\":0,\"byteOffset\":72,\"byteLength\":6}],\n"
      "\"accessors\":[{\"bufferView\":0,\"componentType\":5126,\"count\":3,\"type\":\"VEC3\","
      "\"min\":[0,0,0],\"max\":[1,1,0]},\n"
      "  {\"bufferView\":1,\"componentType\":5126,\"count\":3,\"type\":\"VEC3\"},\n"
      "  {\"bufferView\":2,\"componentType\":5123,\"count\":3,\"type\":\"SCALAR\"}]}\n",
      b64);
  char path[1024];
  tmp_path(path, sizeof path, "instanced.gltf");
  EXPECT(write_text(path, json));

  struct scene s;
  scene_init(&s);
  struct meshio_xform xf = {3.0f, {1.0f, 1.0f, 1.0f}};
  struct err e = {0};
  bool ok = meshio_import(&s, path, &xf, 2, UINT32_MAX, &e);
  EXPECTF(ok, "glTF import failed: %s", e.msg);
  EXPECTF(s.tri_count == 2, "tri_count %u", s.tri_count);
  /* Node 0: p * 2 + (5,0,0); node 1: p + (0,0,-3); then the placement. */
  bool got0 = false, got1 = false;
  for (uint32_t i = 0; i < s.tri_count; i++) {
    const struct scene_tri *t = &s.tris[i];
    EXPECT(t->material == 2);
    bool is0 = true, is1 = true;
    for (int k = 0; k < 3; k++) {
      vec3 p = v3(pos[3 * k], pos[3 * k + 1], pos[3 * k + 2]);
      is0 = is0 && v3_same(t->v[k], placed(v3_add(v3_scale(p, 2), v3(5, 0, 0)), &xf));
      is1 = is1 && v3_same(t->v[k], placed(v3_add(p, v3(0, 0, -3)), &xf));
      EXPECTF(v3_near(t->n[k], v3(0, 0, 1), 1e-6f), "normal %g %g %g", t->n[k].x, t->n[k].y,
              t->n[k].z);
    }
    got0 = got0 || is0;
    got1 = got1 || is1;
  }
  EXPECT(got0 && got1);
  scene_fini(&s);
}

/* Awkward but finite coordinates: thirds, tiny, huge, negative zero. */
static float odd_value(uint64_t *st) {
  *st = *st * 6364136223846793005ull + 1442695040888963407ull;
  uint32_t r = (uint32_t)(*st >> 33);
  switch (r % 5) {
  case 0: return (float)r / 3.0f;
  case 1: return -1e-7f * (float)(r % 1000);
  case 2: return 1e6f / (float)(1 + r % 97);
  case 3: return -0.0f;
  default: return (float)(r % 2001) / 1000.0f - 1.0f;
  }
}

/* NOTE: a vector's values one a statement, z first (the cases were tuned
 * with gcc, which took v3's three arguments last first; clang takes them
 * first first, and C leaves it open). */
static vec3 odd_v3(uint64_t *st) {
  float z = odd_value(st);
  float y = odd_value(st);
  float x = odd_value(st);
  return v3(x, y, z);
}

static void test_export_round_trip(void) {
  struct scene s;
  scene_init(&s);
  uint64_t st = 42;
  for (int i = 0; i < 300; i++) {
    vec3 a = odd_v3(&st), b = odd_v3(&st), c = odd_v3(&st);
    scene_add_tri(&s, a, b, c, NULL, (uint32_t)(i % 3));
  }
  /* Shared vertices and a degenerate triangle must survive as they are. */
  scene_add_tri(&s, s.tris[0].v[1], s.tris[0].v[0], s.tris[5].v[2], NULL, 0);
  scene_add_tri(&s, v3(1, 1, 1), v3(1, 1, 1), v3(2, 2, 2), NULL, 0);

  char path[1024];
  tmp_path(path, sizeof path, "export.ply");
  struct err e = {0};
  EXPECTF(meshio_export_ply(&s, path, &e), "%s", e.msg);
  EXPECT(testing_temps_of(path) == 0);

  FILE *f = fopen(path, "rb");
  char head[64] = {0};
  if (f) {
    EXPECT(fread(head, 1, 36, f) == 36);
    fclose(f);
  }
  EXPECT(strncmp(head, "ply\nformat binary_little_endian 1.0\n", 36) == 0);

  /* assimp as the independent reader, without vertex joining. */
  const struct aiScene *as = aiImportFile(path, aiProcess_ValidateDataStructure);
  EXPECTF(as != NULL, "assimp: %s", aiGetErrorString());
  if (as) {
    EXPECT(as->mNumMeshes == 1);
    const struct aiMesh *m = as->mNumMeshes ? as->mMeshes[0] : NULL;
    EXPECT(m && m->mNumFaces == s.tri_count && m->mNumVertices == 3 * s.tri_count);
    uint32_t bad = 0;
    for (uint32_t i = 0; m && i < m->mNumFaces && i < s.tri_count; i++) {
      const struct aiFace *fc = &m->mFaces[i];
      if (fc->mNumIndices != 3) {
        bad++;
        continue;
      }
      for (int k = 0; k < 3; k++) {
        const struct aiVector3D *p = &m->mVertices[fc->mIndices[k]];
        if (!v3_same(v3(p->x, p->y, p->z), s.tris[i].v[k])) bad++;
      }
    }
    EXPECTF(bad == 0, "%u vertices differ", bad);
    aiReleaseImport(as);
  }

  /* And through our own importer: same triangles, same order. Compared by
   * value: placement computes p * 1 + 0, which turns -0 into +0. */
  struct scene r;
  scene_init(&r);
  struct meshio_xform id = {1.0f, {0, 0, 0}};
  EXPECTF(meshio_import(&r, path, &id, 9, UINT32_MAX, &e), "%s", e.msg);
  EXPECT(r.tri_count == s.tri_count);
  uint32_t bad = 0;
  for (uint32_t i = 0; i < r.tri_count && i < s.tri_count; i++)
    for (int k = 0; k < 3; k++)
      if (!v3_near(r.tris[i].v[k], s.tris[i].v[k], 0.0f) || r.tris[i].material != 9) bad++;
  EXPECTF(bad == 0, "%u vertices differ after meshio_import", bad);
  scene_fini(&r);

  /* Same scene, same bytes. */
  char path2[1024];
  tmp_path(path2, sizeof path2, "export_again.ply");
  EXPECT(meshio_export_ply(&s, path2, &e));
  FILE *f1 = fopen(path, "rb"), *f2 = fopen(path2, "rb");
  bool same = f1 && f2;
  while (same) {
    int c1 = fgetc(f1), c2 = fgetc(f2);
    if (c1 != c2) same = false;
    if (c1 == EOF || c2 == EOF) break;
  }
  if (f1) fclose(f1);
  if (f2) fclose(f2);
  EXPECT(same);
  remove(path2);

  /* Into a directory that does not exist: clean failure, nothing left. */
  tmp_path(path, sizeof path, "no_such_dir/export.ply");
  memset(&e, 0, sizeof e);
  EXPECT(!meshio_export_ply(&s, path, &e));
  EXPECT(e.set && strcmp(e.file, path) == 0);
  EXPECT(access(path, F_OK) != 0);
  scene_fini(&s);
}

static void expect_import_fails(const char *path) {
  struct scene s;
  scene_with_two(&s);
  uint64_t h = scene_hash(&s);
  struct meshio_xform id = {1.0f, {0, 0, 0}};
  struct err e = {0};
  bool ok = meshio_import(&s, path, &id, 0, UINT32_MAX, &e);
  EXPECTF(!ok, "%s imported", path);
  EXPECTF(e.set && strcmp(e.file, path) == 0, "%s: err.file = '%s'", path, e.file);
  EXPECTF(strncmp(e.msg, "cannot import mesh: ", 20) == 0 && strlen(e.msg) > 20, "%s: msg '%s'",
          path, e.msg);
  EXPECTF(s.tri_count == 2 && scene_hash(&s) == h, "%s: scene changed", path);
  printf("  %s: %s\n", strrchr(path, '/') ? strrchr(path, '/') + 1 : path, e.msg);
  scene_fini(&s);
}

static void test_broken(void) {
  static const char *const fixtures[] = {
      "obj_bad_index.obj",     "obj_empty.obj",           "obj_garbage.obj",
      "obj_lines_only.obj",    "obj_overflow.obj",        "ply_truncated_binary.ply",
      "ply_no_end_header.ply", "ply_truncated_ascii.ply",
  };
  char path[1024];
  printf("broken meshes:\n");
  for (size_t i = 0; i < sizeof fixtures / sizeof fixtures[0]; i++) {
    snprintf(path, sizeof path, "%s/meshes/%s", RTSIM_TEST_DATA, fixtures[i]);
    EXPECTF(access(path, R_OK) == 0, "fixture %s missing", path);
    expect_import_fails(path);
  }
  tmp_path(path, sizeof path, "no_such_mesh.obj");
  remove(path);
  expect_import_fails(path);
}

static void test_box(void) {
  const char *path = "/usr/share/assimp/models/OBJ/box.obj";
  if (access(path, R_OK) != 0) {
    printf("note: %s not installed (assimp-testmodels); box case skipped\n", path);
    return;
  }
  struct scene s;
  scene_init(&s);
  struct meshio_xform id = {1.0f, {0, 0, 0}};
  struct err e = {0};
  EXPECTF(meshio_import(&s, path, &id, 0, UINT32_MAX, &e), "%s", e.msg);
  EXPECTF(s.tri_count == 12, "box has %u triangles", s.tri_count);
  vec3 lo, hi;
  scene_bounds(&s, &lo, &hi);
  EXPECT(v3_same(lo, v3(-0.5f, -0.5f, -0.5f)) && v3_same(hi, v3(0.5f, 0.5f, 0.5f)));
  float area = 0;
  for (uint32_t i = 0; i < s.tri_count; i++) area += tri_area(&s.tris[i]);
  EXPECTF(fabsf(area - 6.0f) < 1e-5f, "box area %g", area);
  scene_fini(&s);
}

int main(void) {
  test_obj_quad();
  test_ply_ascii();
  test_gltf();
  test_export_round_trip();
  test_broken();
  test_box();
  return testing_done("test_meshio");
}
