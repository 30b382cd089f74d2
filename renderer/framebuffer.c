/* Fixed-point framebuffer: order-independent sums. */
#include "renderer/framebuffer.h"

#include <math.h>
#include <stdlib.h>

#include "renderer/image.h"
#include "renderer/trace.h"
#include "sim/err.h"

#define FB_ONE 4294967296.0 /* 2^32: fixed-point unit */

void fb_init(struct framebuffer *fb, uint32_t width, uint32_t height, uint64_t base_addr) {
  uint64_t n = (uint64_t)width * height;
  fb->width = width;
  fb->height = height;
  fb->acc = xcalloc(3 * n, sizeof *fb->acc);
  fb->cost_nodes = xcalloc(n, sizeof *fb->cost_nodes);
  fb->cost_tris = xcalloc(n, sizeof *fb->cost_tris);
  fb->base_addr = base_addr;
}

void fb_fini(struct framebuffer *fb) {
  if (!fb) return;
  free(fb->acc);
  free(fb->cost_nodes);
  free(fb->cost_tris);
  fb->acc = NULL;
  fb->cost_nodes = fb->cost_tris = NULL;
}

static int64_t to_fixed(float v) {
  /* NOTE: clamp so that a runaway value cannot overflow the sum: 2^20 is far
   * above any radiance this renderer produces. */
  double x = (double)v;
  if (!(x > 0.0)) return 0;
  if (x > 1048576.0) x = 1048576.0;
  return (int64_t)llrint(x * FB_ONE);
}

void fb_add(struct framebuffer *fb, uint32_t pixel, vec3 c, const struct mem_port *mem) {
  uint64_t addr = fb->base_addr + (uint64_t)pixel * FB_PIXEL_BYTES;
  mem_load(mem, addr, FB_PIXEL_BYTES, TRACE_CLASS_OTHER);
  int64_t *a = &fb->acc[3 * (uint64_t)pixel];
  a[0] += to_fixed(c.x);
  a[1] += to_fixed(c.y);
  a[2] += to_fixed(c.z);
  mem_store(mem, addr, FB_PIXEL_BYTES, TRACE_CLASS_OTHER);
}

void fb_to_image(const struct framebuffer *fb, struct image *im) {
  static const char *const names[] = {"R", "G", "B", "cost.nodes", "cost.tris"};
  image_init(im, fb->width, fb->height, 5, names);
  uint64_t n = (uint64_t)fb->width * fb->height;
  for (uint64_t i = 0; i < n; i++) {
    for (int c = 0; c < 3; c++) im->planes[c][i] = (float)((double)fb->acc[3 * i + c] / FB_ONE);
    im->planes[3][i] = (float)fb->cost_nodes[i];
    im->planes[4][i] = (float)fb->cost_tris[i];
  }
}
