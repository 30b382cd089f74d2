/* Mesh import (PLY through renderer/scene/ply.c, everything else through assimp's
 * C API) and PLY export of the scene's triangles. Import is two passes over
 * the loaded mesh: the first counts triangles and validates every vertex, the
 * second appends, so a bad file never leaves half a mesh in the scene. Export writes 3 unshared
 * vertices per face so face i is primitive i with its vertices in stored order, byte for byte. */
#include "renderer/scene/meshio.h"

#include <errno.h>
#include <math.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <assimp/cimport.h>
#include <assimp/postprocess.h>
#include <assimp/scene.h>

#include "renderer/scene.h"
#include "renderer/scene/ply.h"
#include "sim/err.h"
#include "sim/outfile.h"

/* Import in two stages. The file is read with validation only (indices in
 * range), then checked for what assimp's own post-processing would trip on,
 * then triangulated and flattened: PreTransformVertices bakes node transforms
 * into the vertices (instanced meshes are duplicated), so the meshes list is
 * all the geometry there is. SortByPType and JoinIdenticalVertices are left
 * out: faces are filtered by index count here and copied per triangle, so
 * they would only cost time and add code paths that can assert.
 * NOTE: Debian's assimp 5.2 keeps ai_assert on, and a mesh whose faces have
 * zero indices in a mesh flagged POLYGON makes TriangulateProcess abort() the
 * whole program (its PLY reader produced those from truncated files);
 * meshio_check_raw refuses such meshes first. */
#define MESHIO_READ_FLAGS (aiProcess_ValidateDataStructure)
#define MESHIO_POST_FLAGS (aiProcess_Triangulate | aiProcess_PreTransformVertices)

static vec3 meshio_place(const struct aiVector3D *p, const struct meshio_xform *xf) {
  return v3_add(v3_scale(v3(p->x, p->y, p->z), xf->scale), xf->translate);
}

static bool meshio_finite(vec3 v) { return isfinite(v.x) && isfinite(v.y) && isfinite(v.z); }

/* Unit shading normals from three stored ones, or false to use the flat one
 * (a zero or non-finite normal would poison shading). */
static bool meshio_unit_normals(const vec3 in[3], vec3 out[3]) {
  for (int k = 0; k < 3; k++) {
    float l = v3_len(in[k]);
    if (!(l > 0.0f) || !isfinite(l)) return false;
    out[k] = v3_scale(in[k], 1.0f / l);
  }
  return true;
}

/* Shading normals of one face from the file, or false to use the flat one. */
static bool meshio_face_normals(const struct aiMesh *m, const struct aiFace *f, vec3 out[3]) {
  if (!m->mNormals) return false;
  vec3 in[3];
  for (int k = 0; k < 3; k++) {
    const struct aiVector3D *n = &m->mNormals[f->mIndices[k]];
    in[k] = v3(n->x, n->y, n->z);
  }
  return meshio_unit_normals(in, out);
}

/* Refuse what the post-processing steps would assert on or misread: faces
 * without vertices, indices past the vertex array, and meshes flagged as
 * holding polygons that hold none. */
static bool meshio_check_raw(const struct aiScene *as, const char *path, struct err *e) {
  for (unsigned mi = 0; mi < as->mNumMeshes; mi++) {
    const struct aiMesh *m = as->mMeshes[mi];
    bool has_polygon = false;
    for (unsigned fi = 0; fi < m->mNumFaces; fi++) {
      const struct aiFace *f = &m->mFaces[fi];
      if (f->mNumIndices == 0)
        return err_set(e, path, 0, 0,
                       "cannot import mesh: mesh %u face %u has no vertices "
                       "(truncated file?)",
                       mi, fi);
      for (unsigned k = 0; k < f->mNumIndices; k++)
        if (f->mIndices[k] >= m->mNumVertices)
          return err_set(e, path, 0, 0,
                         "cannot import mesh: mesh %u face %u: vertex index %u "
                         "out of range (mesh has %u vertices)",
                         mi, fi, f->mIndices[k], m->mNumVertices);
      if (f->mNumIndices > 3) has_polygon = true;
    }
    if ((m->mPrimitiveTypes & aiPrimitiveType_POLYGON) && !has_polygon)
      return err_set(e, path, 0, 0,
                     "cannot import mesh: mesh %u is flagged as holding polygons "
                     "but has none (truncated or malformed file?)",
                     mi);
  }
  return true;
}

/* PLY goes through rtsim's own reader: assimp 5.2's crashes on some truncated
 * files, loops forever on a header without end_header, and skips whitespace
 * bytes after a binary end_header, shifting the data of about one binary PLY
 * in 64. The result matches what the assimp path gives for a correct file:
 * faces in file order, each fanned (a triangle as it is), normals from
 * nx/ny/nz when present. */
static bool meshio_import_ply(struct scene *s, const char *path, const struct meshio_xform *xf,
                              uint32_t material, uint64_t max_tris, struct err *e) {
  struct ply_mesh m;
  struct err pe = {0};
  if (!ply_read_file(path, &m, &pe))
    return err_set(e, pe.file, pe.line, pe.col, "cannot import mesh: %s", pe.msg);
  bool ok = false;
  if (m.tri_count == 0) {
    err_set(e, path, 0, 0,
            "cannot import mesh: file holds no triangles (its face element is "
            "empty)");
    goto done;
  }
  if (m.tri_count > max_tris || m.tri_count > UINT32_MAX - s->tri_count) {
    err_set(e, path, 0, 0,
            "cannot import mesh: too many triangles (got %u, the scene has room "
            "for %llu)",
            m.tri_count, (unsigned long long)max_tris);
    goto done;
  }
  /* Pass 1: every placed vertex of every triangle is finite. */
  for (uint32_t i = 0; i < m.tri_count; i++)
    for (int k = 0; k < 3; k++) {
      const float *p = m.pos + 3 * (size_t)m.tri[3 * (size_t)i + k];
      struct aiVector3D a = {p[0], p[1], p[2]};
      vec3 q = meshio_place(&a, xf);
      if (!meshio_finite(q)) {
        err_set(e, path, 0, 0,
                "cannot import mesh: triangle %u has a non-finite vertex after "
                "placement (got %g %g %g)",
                i, (double)q.x, (double)q.y, (double)q.z);
        goto done;
      }
    }
  /* Pass 2: append in file order. */
  for (uint32_t i = 0; i < m.tri_count; i++) {
    const uint32_t *t = m.tri + 3 * (size_t)i;
    vec3 v[3], n[3];
    for (int k = 0; k < 3; k++) {
      const float *p = m.pos + 3 * (size_t)t[k];
      struct aiVector3D a = {p[0], p[1], p[2]};
      v[k] = meshio_place(&a, xf);
    }
    bool has_n = false;
    if (m.normal) {
      vec3 in[3];
      for (int k = 0; k < 3; k++) {
        const float *q = m.normal + 3 * (size_t)t[k];
        in[k] = v3(q[0], q[1], q[2]);
      }
      has_n = meshio_unit_normals(in, n);
    }
    scene_add_tri(s, v[0], v[1], v[2], has_n ? n : NULL, material);
  }
  ok = true;
done:
  ply_mesh_fini(&m);
  return ok;
}

bool meshio_estimate(const char *path, uint64_t *least, uint64_t *most, struct err *e) {
  *least = 0;
  *most = UINT64_MAX;
  const char *irregular = err_not_regular(path);
  if (irregular) return err_set(e, path, 0, 0, "cannot import mesh: %s", irregular);
  if (!ply_claims(path)) return true;
  struct ply_counts c;
  struct err pe = {0};
  if (!ply_read_header_file(path, &c, &pe))
    return err_set(e, pe.file, pe.line, pe.col, "cannot import mesh: %s", pe.msg);
  *least = c.faces;
  *most = c.tri_max;
  return true;
}

/* assimp runs in a child process (meshio_import): a crash, an endless loop or
 * a runaway allocation in it becomes one error naming the file. The child
 * sends a head, then `count` triangles already placed, so the parent adds
 * exactly the floats the in-process import added. */
#define MESHIO_CHILD_CPU_S 60    /* CPU seconds (RLIMIT_CPU) */
#define MESHIO_CHILD_WALL_S 120  /* wall seconds (alarm), for a child stuck waiting */
#define MESHIO_CHILD_MEM_SHARE 4 /* it may map 1/4 of physical memory past the parent */

struct meshio_wire_head {
  uint32_t ok;
  uint32_t pad;
  uint64_t count;
  char msg[ERR_MSG_MAX];
};

struct meshio_wire_tri {
  float v[9], n[9];
  uint32_t has_n;
};

static bool meshio_write_all(int fd, const void *p, size_t n) {
  const char *b = p;
  while (n > 0) {
    ssize_t w = write(fd, b, n);
    if (w < 0 && errno == EINTR) continue;
    if (w <= 0) return false;
    b += w;
    n -= (size_t)w;
  }
  return true;
}

/* Bytes read, short only at the end of the stream or on an error. */
static size_t meshio_read_all(int fd, void *p, size_t n) {
  char *b = p;
  size_t got = 0;
  while (got < n) {
    ssize_t r = read(fd, b + got, n - got);
    if (r < 0 && errno == EINTR) continue;
    if (r <= 0) break;
    got += (size_t)r;
  }
  return got;
}

static void meshio_put_vec(float *out, vec3 v) {
  out[0] = v.x;
  out[1] = v.y;
  out[2] = v.z;
}

/* In the child: the in-process import of old, sending instead of adding. */
static bool meshio_assimp_send(const char *path, const struct meshio_xform *xf, int fd,
                               struct err *e) {
  const struct aiScene *as = aiImportFile(path, MESHIO_READ_FLAGS);
  if (!as) {
    const char *why = aiGetErrorString();
    return err_set(e, path, 0, 0, "cannot import mesh: %s",
                   why && why[0] ? why : "unknown assimp error");
  }
  bool ok = false;
  if (!meshio_check_raw(as, path, e)) goto done;
  /* On failure assimp has already released the scene; its error text belongs
   * to the deleted importer and is not reachable from the C API. */
  as = aiApplyPostProcessing(as, MESHIO_POST_FLAGS);
  if (!as)
    return err_set(e, path, 0, 0,
                   "cannot import mesh: assimp post-processing "
                   "(triangulation, node transforms) failed");

  /* Pass 1: count triangles and check every placed vertex is finite. */
  uint64_t count = 0;
  for (unsigned mi = 0; mi < as->mNumMeshes; mi++) {
    const struct aiMesh *m = as->mMeshes[mi];
    for (unsigned fi = 0; fi < m->mNumFaces; fi++) {
      const struct aiFace *f = &m->mFaces[fi];
      if (f->mNumIndices != 3) continue; /* points and lines */
      for (int k = 0; k < 3; k++) {
        /* Checked before post-processing; keep the read safe regardless. */
        if (f->mIndices[k] >= m->mNumVertices) {
          err_set(e, path, 0, 0,
                  "cannot import mesh: mesh %u face %u: vertex index %u out "
                  "of range (mesh has %u vertices)",
                  mi, fi, f->mIndices[k], m->mNumVertices);
          goto done;
        }
        vec3 p = meshio_place(&m->mVertices[f->mIndices[k]], xf);
        if (!meshio_finite(p)) {
          err_set(e, path, 0, 0,
                  "cannot import mesh: mesh %u face %u has a non-finite vertex "
                  "after placement (got %g %g %g)",
                  mi, fi, (double)p.x, (double)p.y, (double)p.z);
          goto done;
        }
      }
      count++;
    }
  }
  if (count == 0) {
    err_set(e, path, 0, 0, "cannot import mesh: file holds no triangles (%u meshes)",
            as->mNumMeshes);
    goto done;
  }

  /* Pass 2: send, in mesh then face order. */
  struct meshio_wire_head h;
  memset(&h, 0, sizeof h);
  h.ok = 1;
  h.count = count;
  if (!meshio_write_all(fd, &h, sizeof h)) goto done;
  enum { MESHIO_BATCH = 1024 };
  struct meshio_wire_tri *buf = xmalloc(MESHIO_BATCH * sizeof *buf);
  size_t used = 0;
  bool io_ok = true;
  for (unsigned mi = 0; io_ok && mi < as->mNumMeshes; mi++) {
    const struct aiMesh *m = as->mMeshes[mi];
    for (unsigned fi = 0; io_ok && fi < m->mNumFaces; fi++) {
      const struct aiFace *f = &m->mFaces[fi];
      if (f->mNumIndices != 3) continue;
      struct meshio_wire_tri *t = &buf[used++];
      memset(t, 0, sizeof *t);
      vec3 n[3];
      t->has_n = meshio_face_normals(m, f, n);
      for (int k = 0; k < 3; k++) {
        meshio_put_vec(t->v + 3 * k, meshio_place(&m->mVertices[f->mIndices[k]], xf));
        if (t->has_n) meshio_put_vec(t->n + 3 * k, n[k]);
      }
      if (used == MESHIO_BATCH) {
        io_ok = meshio_write_all(fd, buf, used * sizeof *buf);
        used = 0;
      }
    }
  }
  if (io_ok && used) io_ok = meshio_write_all(fd, buf, used * sizeof *buf);
  free(buf);
  ok = io_ok;

done:
  aiReleaseImport(as);
  return ok;
}

/* In the child: limits, the import, and its verdict on fd. Never returns. */
static _Noreturn void meshio_child(const char *path, const struct meshio_xform *xf, int fd) {
  struct rlimit cpu = {MESHIO_CHILD_CPU_S, MESHIO_CHILD_CPU_S};
  setrlimit(RLIMIT_CPU, &cpu);
  alarm(MESHIO_CHILD_WALL_S);
#ifndef __SANITIZE_ADDRESS__ /* ASan reserves terabytes of address space */
  /* The child starts as a copy of the parent (the scene so far included), so
   * the limit is what it maps now plus its share. */
  const long pages = sysconf(_SC_PHYS_PAGES), page = sysconf(_SC_PAGE_SIZE);
  unsigned long long mapped = 0;
  FILE *statm = fopen("/proc/self/statm", "r");
  if (statm && fscanf(statm, "%llu", &mapped) == 1 && pages > 0 && page > 0) {
    struct rlimit as = {0, 0};
    as.rlim_cur = as.rlim_max =
        (rlim_t)(mapped * (unsigned long long)page +
                 (unsigned long long)pages * (unsigned long long)page / MESHIO_CHILD_MEM_SHARE);
    setrlimit(RLIMIT_AS, &as);
  }
  if (statm) fclose(statm);
#endif
  struct err e;
  memset(&e, 0, sizeof e);
  if (!meshio_assimp_send(path, xf, fd, &e) && e.set) {
    struct meshio_wire_head h;
    memset(&h, 0, sizeof h);
    snprintf(h.msg, sizeof h.msg, "%s", e.msg);
    meshio_write_all(fd, &h, sizeof h);
  }
  _exit(0);
}

/* Why the child ended without a verdict, for the message. */
static void meshio_child_death(int status, char *out, size_t cap) {
  if (WIFSIGNALED(status)) {
    int sig = WTERMSIG(status);
    if (sig == SIGXCPU)
      snprintf(out, cap, "it passed its CPU-time limit of %d s", MESHIO_CHILD_CPU_S);
    else if (sig == SIGALRM)
      snprintf(out, cap, "it passed its time limit of %d s", MESHIO_CHILD_WALL_S);
    else
      snprintf(out, cap,
               "it crashed (signal %d, %s; or ran out of its memory limit of 1/%d of "
               "physical memory)",
               sig, strsignal(sig), MESHIO_CHILD_MEM_SHARE);
  } else {
    snprintf(out, cap, "it stopped (exit status %d; out of memory?)",
             WIFEXITED(status) ? WEXITSTATUS(status) : -1);
  }
}

bool meshio_import(struct scene *s, const char *path, const struct meshio_xform *xf,
                   uint32_t material, uint64_t max_tris, struct err *e) {
  /* assimp opens the file by name: a pipe or device is refused first (a pipe
   * would block it forever). */
  const char *irregular = err_not_regular(path);
  if (irregular) return err_set(e, path, 0, 0, "cannot import mesh: %s", irregular);
  if (ply_claims(path)) return meshio_import_ply(s, path, xf, material, max_tris, e);
  int fds[2];
  if (pipe(fds) != 0)
    return err_set(e, path, 0, 0, "cannot import mesh: pipe: %s", strerror(errno));
  fflush(NULL); /* nothing buffered is written twice */
  pid_t pid = fork();
  if (pid < 0) {
    close(fds[0]);
    close(fds[1]);
    return err_set(e, path, 0, 0, "cannot import mesh: fork: %s", strerror(errno));
  }
  if (pid == 0) {
    close(fds[0]);
    meshio_child(path, xf, fds[1]);
  }
  close(fds[1]);
  const uint32_t before = s->tri_count;
  bool ok = false, verdict = false;
  struct meshio_wire_head h;
  struct meshio_wire_tri *buf = NULL;
  if (meshio_read_all(fds[0], &h, sizeof h) != sizeof h) goto reap;
  verdict = true;
  h.msg[sizeof h.msg - 1] = '\0';
  if (!h.ok) {
    err_set(e, path, 0, 0, "%s", h.msg);
    goto reap;
  }
  if (h.count > max_tris || h.count > (uint64_t)UINT32_MAX - s->tri_count) {
    err_set(e, path, 0, 0,
            "cannot import mesh: too many triangles (got %llu, the scene has "
            "room for %llu)",
            (unsigned long long)h.count, (unsigned long long)max_tris);
    goto reap;
  }
  scene_reserve(s, s->tri_count + (uint32_t)h.count);
  enum { MESHIO_BATCH = 1024 };
  buf = xmalloc(MESHIO_BATCH * sizeof *buf);
  for (uint64_t i = 0; i < h.count;) {
    size_t n = h.count - i < MESHIO_BATCH ? (size_t)(h.count - i) : MESHIO_BATCH;
    if (meshio_read_all(fds[0], buf, n * sizeof *buf) != n * sizeof *buf) {
      verdict = false;
      goto reap;
    }
    for (size_t k = 0; k < n; k++) {
      const struct meshio_wire_tri *t = &buf[k];
      vec3 nn[3];
      for (int j = 0; j < 3; j++) nn[j] = v3(t->n[3 * j], t->n[3 * j + 1], t->n[3 * j + 2]);
      scene_add_tri(s, v3(t->v[0], t->v[1], t->v[2]), v3(t->v[3], t->v[4], t->v[5]),
                    v3(t->v[6], t->v[7], t->v[8]), t->has_n ? nn : NULL, material);
    }
    i += n;
  }
  ok = true;

reap:
  free(buf);
  /* The parent may stop reading early (a refusal); the child then ends on a
   * broken pipe, which is no news. */
  close(fds[0]);
  int status = 0;
  while (waitpid(pid, &status, 0) < 0 && errno == EINTR) {
  }
  if (!verdict) {
    char why[256];
    meshio_child_death(status, why, sizeof why);
    err_set(e, path, 0, 0,
            "cannot import mesh: the importer (assimp, in a child process) "
            "gave no answer: %s",
            why);
    ok = false;
  }
  if (!ok) s->tri_count = before; /* nothing of a failed mesh stays */
  return ok;
}

static void meshio_put_u32(unsigned char *p, uint32_t v) {
  for (int k = 0; k < 4; k++) p[k] = (unsigned char)(v >> (8 * k));
}

static void meshio_put_f32(unsigned char *p, float f) {
  uint32_t u;
  memcpy(&u, &f, sizeof u);
  meshio_put_u32(p, u);
}

bool meshio_export_ply(const struct scene *s, const char *path, struct err *e) {
  struct outfile out = {0};
  bool ok = false;
  unsigned char *buf = NULL;

  /* PLY vertex indices are signed 32-bit: 3n - 1 must fit. */
  uint64_t n = s->tri_count;
  if (3 * n > (uint64_t)INT32_MAX + 1) {
    err_set(e, path, 0, 0,
            "cannot write PLY: too many triangles for int indices (got %llu, "
            "max %lld)",
            (unsigned long long)n, ((long long)INT32_MAX + 1) / 3);
    goto done;
  }
  if (!outfile_open(&out, path, "PLY", e)) goto done;
  FILE *f = out.f;
  int hw = fprintf(f,
                   "ply\n"
                   "format binary_little_endian 1.0\n"
                   "comment rtsim export: face i = primitive i, vertices 3i..3i+2\n"
                   "element vertex %llu\n"
                   "property float x\n"
                   "property float y\n"
                   "property float z\n"
                   "element face %llu\n"
                   "property list uchar int vertex_indices\n"
                   "end_header\n",
                   (unsigned long long)(3 * n), (unsigned long long)n);
  bool io_ok = hw > 0;

  /* Vertex block then face block, written in batches to keep fwrite calls few. */
  enum { MESHIO_BATCH = 4096 };
  buf = xmalloc(MESHIO_BATCH * 36);
  for (uint64_t i = 0; io_ok && i < n;) {
    size_t used = 0;
    for (; i < n && used < MESHIO_BATCH * 36; i++)
      for (int k = 0; k < 3; k++, used += 12) {
        vec3 v = s->tris[i].v[k];
        meshio_put_f32(buf + used, v.x);
        meshio_put_f32(buf + used + 4, v.y);
        meshio_put_f32(buf + used + 8, v.z);
      }
    io_ok = fwrite(buf, 1, used, f) == used;
  }
  for (uint64_t i = 0; io_ok && i < n;) {
    size_t used = 0;
    for (; i < n && used < MESHIO_BATCH * 13; i++, used += 13) {
      buf[used] = 3;
      for (int k = 0; k < 3; k++) meshio_put_u32(buf + used + 1 + 4 * k, (uint32_t)(3 * i + k));
    }
    io_ok = fwrite(buf, 1, used, f) == used;
  }
  /* A failed write set the stream's error flag: the commit reports it. */
  ok = outfile_commit(&out, e);

done:
  outfile_abort(&out);
  free(buf);
  return ok;
}
