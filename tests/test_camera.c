/* renderer/camera: the view frame is scale-free. An up vector (or a view
 * direction) of any finite nonzero size gives the frame of its direction, bit
 * for bit, so up: [0, 0, 1e-30] is the unit up's camera; an up that is zero or
 * parallel to the view, as far as floats can tell, is refused. */
#include "renderer/camera.h"

#include <math.h>
#include <string.h>

#include "renderer/scene.h"
#include "testing.h"

static struct scene_camera cam(vec3 from, vec3 at, vec3 up) {
  struct scene_camera c;
  memset(&c, 0, sizeof c);
  c.from = from;
  c.at = at;
  c.up = up;
  c.fov_deg = 60;
  return c;
}

static bool same_frame(const struct camera_frame *a, const struct camera_frame *b) {
  return !memcmp(&a->forward, &b->forward, sizeof a->forward) &&
         !memcmp(&a->right, &b->right, sizeof a->right) && !memcmp(&a->up, &b->up, sizeof a->up);
}

static bool finite3(vec3 v) { return isfinite(v.x) && isfinite(v.y) && isfinite(v.z); }

int main(void) {
  static const char *const names[] = {"OK", "NO_VIEW", "BAD_UP"};
  static const struct {
    const char *what;
    vec3 from, at, up;
    enum camera_fault want;
  } cases[] = {
      {"room", {0.7f, 0.6f, 1.6f}, {5.5f, 4.6f, 0.9f}, {0, 0, 1}, CAMERA_OK},
      {"tiny up (#17)", {0, -5, 0}, {0, 0, 0}, {0, 0, 1e-30f}, CAMERA_OK},
      {"subnormal up", {0, -5, 0}, {0, 0, 0}, {0, 0, 1e-45f}, CAMERA_OK},
      {"huge up", {0, -5, 0}, {0, 0, 0}, {0, 0, 3e38f}, CAMERA_OK},
      {"tiny view", {0, 0, 0}, {0, 1e-30f, 0}, {0, 0, 1}, CAMERA_OK},
      {"huge view", {0, -1e30f, 0}, {0, 1e30f, 0}, {0, 0, 1}, CAMERA_OK},
      /* Looking almost straight down: exact products, a valid frame. */
      {"top-down", {0, 0, 10}, {0, 1e-24f, 0}, {0, 0, 1}, CAMERA_OK},
      {"tilted up", {0, 0, 0}, {1, 2, 3}, {1, 2, 3.1f}, CAMERA_OK},
      {"no view", {1, 1, 1}, {1, 1, 1}, {0, 0, 1}, CAMERA_NO_VIEW},
      {"zero up", {0, -5, 0}, {0, 0, 0}, {0, 0, 0}, CAMERA_BAD_UP},
      {"tiny parallel up (#17)", {0, 0, -5}, {0, 0, 0}, {0, 0, 1e-30f}, CAMERA_BAD_UP},
      {"parallel up", {0, 0, -5}, {0, 0, 0}, {0, 0, 1}, CAMERA_BAD_UP},
      {"antiparallel up", {0, 0, -5}, {0, 0, 0}, {0, 0, -7}, CAMERA_BAD_UP},
      /* Parallel in decimal, not in floats: the cross product is rounding. */
      {"parallel, rounded", {0, 0, 0}, {1, 2, 3}, {2, 4, 6}, CAMERA_BAD_UP},
      {"parallel, rounded, tiny",
       {0, 0, 0},
       {0.1f, 0.2f, 0.3f},
       {1e-31f, 2e-31f, 3e-31f},
       CAMERA_BAD_UP},
  };
  for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
    struct scene_camera c = cam(cases[i].from, cases[i].at, cases[i].up);
    enum camera_fault got = camera_check(&c);
    EXPECTF(got == cases[i].want, "%s: got %s, want %s", cases[i].what, names[got],
            names[cases[i].want]);
    if (got != CAMERA_OK) continue;
    struct camera_frame f;
    camera_frame_init(&f, &c, 64, 48);
    EXPECTF(finite3(f.forward) && finite3(f.right) && finite3(f.up), "%s: a frame not finite",
            cases[i].what);
    EXPECTF(fabsf(v3_len(f.forward) - 1) < 1e-6f, "%s: |forward| = %g", cases[i].what,
            (double)v3_len(f.forward));
    EXPECTF(fabsf(v3_dot(f.forward, f.right)) < 1e-6f && fabsf(v3_dot(f.forward, f.up)) < 1e-6f,
            "%s: the frame is not orthogonal", cases[i].what);
  }

  /* The frame depends on up's direction only: the same bits at every scale. */
  struct scene_camera unit = cam(v3(0.7f, 0.6f, 1.6f), v3(5.5f, 4.6f, 0.9f), v3(0.1f, 0.2f, 1));
  struct camera_frame ref;
  camera_frame_init(&ref, &unit, 64, 48);
  static const float scales[] = {1e-30f, 0x1p-100f, 1e-20f, 1e-4f, 0.1f, 3, 0x1p60f, 1e20f, 1e30f};
  for (size_t i = 0; i < sizeof scales / sizeof scales[0]; i++) {
    struct scene_camera c = unit;
    c.up = v3_scale(unit.up, scales[i]);
    struct camera_frame f;
    EXPECT(camera_check(&c) == CAMERA_OK);
    camera_frame_init(&f, &c, 64, 48);
    /* A power of two scales exactly (while up stays a normal float); other
     * scales round up's components, so the frame may move in its last bits,
     * never more. */
    int ex;
    if (frexpf(scales[i], &ex) == 0.5f)
      EXPECTF(same_frame(&f, &ref), "up x %g: another frame", (double)scales[i]);
    float k = fabsf(f.right.x - ref.right.x) + fabsf(f.right.y - ref.right.y) +
              fabsf(f.right.z - ref.right.z);
    EXPECTF(k < 1e-5f, "up x %g: right moved by %g", (double)scales[i], (double)k);
  }
  /* And the issue's own: up [0, 0, 1e-30] is up [0, 0, 1], bit for bit. */
  struct scene_camera a = cam(v3(0, -5, 1), v3(0, 0, 0), v3(0, 0, 1));
  struct scene_camera b = cam(v3(0, -5, 1), v3(0, 0, 0), v3(0, 0, 1e-30f));
  struct camera_frame fa, fb;
  camera_frame_init(&fa, &a, 64, 48);
  camera_frame_init(&fb, &b, 64, 48);
  EXPECT(same_frame(&fa, &fb));
  return testing_done("test_camera");
}
