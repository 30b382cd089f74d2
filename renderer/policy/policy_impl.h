/* What the policy dispatcher (policy.c) shares with the policy modules
 * (policy_recursive.c, policy_packet.c, policy_dynamic.c, policy_treelet.c):
 * the job's fields, each module's table of operations, and the work-list
 * helpers every module uses the same way. Private to renderer/. */
#ifndef RTSIM_RENDERER_POLICY_POLICY_IMPL_H
#define RTSIM_RENDERER_POLICY_POLICY_IMPL_H

#include <stdbool.h>
#include <stdint.h>

#include "renderer/camera.h"
#include "renderer/policy/policy.h"

struct ray;

/* One policy's operations (a constant table in its module). */
struct policy_module {
  /* Bytes of one worker's ray region (policy_ray_region_bytes). */
  uint64_t region_bytes;
  /* Most workers a job may have; 0: as many as the ray regions allow. */
  uint32_t max_workers;
  /* Set the job's total and progress_every, and its shared state. */
  void (*create)(struct policy_job *job);
  void (*destroy)(struct policy_job *job); /* frees the shared state */
  /* policy_job_step: claim, then do one work item. */
  bool (*step)(struct policy_job *job, struct policy_worker *w);
  void (*scratch_free)(void *scratch); /* a worker's scratch; NULL ok */
  /* Optional: add what the job as a whole counted to st, at the end. */
  void (*finish)(struct policy_job *job, struct render_stats *st);
};

extern const struct policy_module policy_recursive_module, policy_packet_module,
    policy_dynamic_module, policy_treelet_module;

struct policy_job {
  const struct policy_module *mod;
  struct policy_setup setup;
  struct policy_params params;
  struct camera_frame cf; /* the scene's camera at the image size */
  uint32_t workers, cores;
  uint32_t live; /* workers initialised and not yet finished */
  /* The shared work list: items [next, total) are still to be claimed. */
  uint64_t total, next;
  uint64_t done;           /* items finished, for progress */
  uint64_t progress_every; /* report every this many items; 0: the module reports */
  struct render_stats st;  /* sums of the finished workers */
  struct trace_stats ts;
  void *shared; /* the module's shared state */
};

/* Claim up to n work items for the caller: returns how many (0: none left)
 * and the first in *first. Makes no access: call it before the item's first. */
uint64_t policy_job_claim(struct policy_job *job, uint64_t n, uint64_t *first);

/* Sampling (policy_setup.item): before item k's first access (it may wait
 * first); w's port may be swapped for the item, *own keeps w's own for
 * policy_item_end. POLICY_ITEM_DETAIL: the item goes through w's own port;
 * POLICY_ITEM_PORT: through another; POLICY_ITEM_SKIP: the caller skips it
 * (policy_item_end is not called, policy_job_done is). */
enum policy_item policy_item_begin(struct policy_job *job, struct policy_worker *w, uint64_t k,
                                   struct mem_port *own);
void policy_item_end(struct policy_job *job, struct policy_worker *w, uint64_t k,
                     const struct mem_port *own, bool detail);

/* n claimed items are done: reports progress every progress_every items and
 * at the last one. */
void policy_job_done(struct policy_job *job, uint64_t n);

/* Pixel (x, y)'s primary ray. Every policy reads it from the camera's ray
 * array in the memory image (one 64-byte load through w's port;
 * trace_layout.camera_base), as a ray-generation stage would have left it:
 * the same input traffic for all policies, and the 64 bytes per primary ray
 * the paper's baselines carry. */
void policy_primary(const struct policy_job *job, struct policy_worker *w, uint32_t x, uint32_t y,
                    struct ray *r);

#endif
