/* The one render setup of the commands (app.h: struct app_render). */
#include "app/app.h"

#include <string.h>

#include "renderer/trace.h"

void app_render_init(struct app_render *r, const struct app_world *w, uint32_t mask, uint64_t seed,
                     uint32_t width, uint32_t height) {
  memset(r, 0, sizeof *r);
  r->sc.scene = &w->scene;
  r->sc.ray_mask = mask;
  r->sc.seed = seed;
  struct policy_setup *s = &r->setup;
  s->scene = &w->scene;
  s->kd = &w->kd;
  trace_layout_default(&s->layout);
  s->sc = &r->sc;
  fb_init(&r->fb, width, height, s->layout.fb_base);
  s->fb = &r->fb;
}

void app_render_fini(struct app_render *r) { fb_fini(&r->fb); }
