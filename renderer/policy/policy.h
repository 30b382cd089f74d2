/* Ray scheduling policies (the paper's sections 2 and 3), each its own module
 * behind this one interface. A policy decides only the order in which rays are
 * traced and where they wait in memory; tracing and shading are the shared
 * kernels, so every policy produces the same hits and the same image, bit for
 * bit (the framebuffer sums in fixed point).
 *
 * A render is a job that many workers share: each worker is one simulated ray
 * context with its own memory port, tracer and counters, and takes work items
 * (pixels or tiles) from the job's shared work list until none is left. On the
 * timed machine a worker is a coroutine and any load, store or compute through
 * its port may suspend it while other workers of the same job run; on the
 * native and functional backends nothing suspends and one worker (policy_run)
 * renders the whole image. Rules that keep interleaved workers honest:
 * - a worker claims a work item from the shared list before its first memory
 *   access for that item (an access may let another worker claim meanwhile);
 * - a worker reads and writes shared host state only between two accesses,
 *   never across one (cooperative switching needs no locks then);
 * - each worker keeps its rays in its own region of the memory image (the
 *   dynamic policy's wait in the job's queues, each slot claimed before its
 *   accesses) and counts its own work (per-pixel costs are differences of its
 *   own counters);
 * - a worker with nothing to do until others make it some parks (mem_park)
 *   rather than spin, and whoever makes the work wakes it (mem_wake): the
 *   dynamic policy's workers share one batch.
 * With one worker (policy_run: rtsim render and traffic) nothing interleaves,
 * and a policy's accesses are those of its plain sequential loop. */
#ifndef RTSIM_RENDERER_POLICY_POLICY_H
#define RTSIM_RENDERER_POLICY_POLICY_H

#include <stdbool.h>
#include <stdint.h>

#include "renderer/render.h"
#include "renderer/trace.h"

struct scene;
struct kd_tree;
struct bvh;
struct shade_ctx;
struct framebuffer;

enum policy_kind {
  POLICY_RECURSIVE = 0,
  POLICY_PACKET = 1,
  POLICY_DYNAMIC = 2,
  POLICY_TREELET = 3, /* the dynamic policy's machinery, queues at treelets (treelet.h) */
  POLICY_COUNT = 4
};

/* How the dynamic policy's cores share its queue points (policy_params). */
enum policy_dyn_sharing { POLICY_DYN_PARTITION = 0, POLICY_DYN_CHIP = 1 };

/* What to do with a claimed work item (policy_setup.item). */
enum policy_item { POLICY_ITEM_DETAIL, POLICY_ITEM_PORT, POLICY_ITEM_HOLD, POLICY_ITEM_SKIP };

struct policy_params {
  uint32_t packet_dim;  /* packet: packets are packet_dim x packet_dim pixels (8) */
  uint64_t cache_bytes; /* dynamic: the cache size the schedule is made for */
  /* dynamic: what the cache holds besides geometry (section 2.2), each capped
   * by a share of cache_bytes: k-d nodes up to 1/dyn_node_share (4: the paper's
   * 1 MB of 4 MB), the queue table (8 bytes a queue point) up to
   * 1/dyn_table_share (16: 256 KB of 4 MB), a ray buffer of
   * dyn_ray_buffer_bytes up to 1/dyn_ray_share (16). What is left, divided
   * among the job's cores, is g_max, the geometry a queue point's subtree may
   * hold (qpoint.h). The rules for a machine of C cores x T threads x R ray
   * contexts a thread and an L2 of S bytes (policy_params_machine; the job's
   * `workers` = C x T x R, its `cores` = C):
   * - g_max = (S - nodes - table - ray buffer) / C. Every core holds its own
   *   queue point, and takes the next one as soon as its rays are handed out,
   *   so C queue points are drained at once and each needs its subtree's
   *   geometry resident in the shared L2 at the same time; the tree, the
   *   table and the ray buffer are shared. (A core that has just taken its
   *   next queue point still finishes up to T x R - 1 rays of the previous
   *   one: a short overlap the rule does not reserve for.)
   * - The rays active at once (the ray buffer) are one per ray context:
   *   C x T x R x 64 bytes (dyn_ray_buffer_bytes = 0). Queued rays wait in
   *   memory; a ray is brought into the cache when a context takes it and
   *   leaves with it, so the contexts hold exactly the rays in flight. This is
   *   the paper's "only enough rays to mask the latency": it argues that 2 to
   *   4 rays a thread hide a miss, and R is that number, chosen in the
   *   machine config. A leaf whose geometry exceeds g_max is processed in
   *   blocks of g_max; each context streams one ray at a time against a
   *   block (the group: the ray buffer over the workers).
   * The functional reproduction (one worker, policy_params_default) keeps a
   * 4096-byte buffer (64 rays) instead: see results/traffic. */
  uint32_t dyn_node_share, dyn_table_share, dyn_ray_share;
  uint64_t dyn_ray_buffer_bytes; /* 0: one 64-byte ray per worker */
  /* dynamic: primary rays admitted at a time, each batch traced through all
   * its generations before the next is admitted; this bounds the rays queued
   * at once (the paper's continuum between recursive and fully deferred
   * tracing). 0 (default): every primary ray at once, as the paper's section 2
   * reads. */
  uint64_t dyn_batch_rays;
  /* dynamic on several cores (enum policy_dyn_sharing): POLICY_DYN_PARTITION
   * (the rules above: each core drains its own queue point, g_max divided
   * among the cores) or POLICY_DYN_CHIP (the paper's section 3: "threads will
   * collaboratively process the rays at a single queue point"). In chip mode
   * queue points are made for the whole L2 (g_max not divided), and every core
   * works on the fullest queue point being drained; a core takes another queue
   * only while the queue points being drained have fewer rays left to hand out
   * than the contexts can take at once (workers x group): a few at once when
   * a queue holds too few rays to feed every context. One core: both the same. */
  uint32_t dyn_sharing;
};

void policy_params_default(struct policy_params *p);

/* The defaults, then what the dynamic policy is made for on a machine (the
 * rules above): cache_bytes = l2_bytes, one ray of buffer per worker. Plain
 * integers: the renderer does not know the machine. */
void policy_params_machine(struct policy_params *p, uint64_t l2_bytes);

struct qpoint_set;
struct qpoint_budget;

/* The dynamic policy's queue points for a job of `workers` workers on `cores`
 * cores (the rules above) on bvh if not NULL, else on kd: qpoint_plan's
 * selection (qs, caller finishes it with qpoint_fini) and budget (b), the
 * triangles of an oversized leaf's block (*block_tris, at least 1) and the
 * rays a worker streams against a block at once (*group, at least 1). */
void policy_dynamic_plan(const struct policy_params *p, uint32_t workers, uint32_t cores,
                         const struct kd_tree *kd, const struct bvh *bvh, uint32_t tri_bytes,
                         struct qpoint_set *qs, struct qpoint_budget *b, uint32_t *block_tris,
                         uint32_t *group);

/* What every worker of one render shares, read-only during the render except
 * for the framebuffer (contributions are sums, so their order does not
 * matter) and the tested set (bits are only ever set). Borrowed: everything
 * pointed to must outlive the job. */
struct policy_setup {
  const struct scene *scene;
  const struct kd_tree *kd;
  /* The BVH traced instead of kd (NULL: the k-d tree); every policy traces
   * either. */
  const struct bvh *bvh;
  struct trace_layout layout; /* simulated addresses of every region */
  const struct shade_ctx *sc;
  struct framebuffer *fb; /* its size is the image size */
  /* Optional bit set, one bit a triangle, set when any worker tests it against
   * a ray (the potentially visible geometry). NULL: not tracked. */
  uint64_t *tested;
  /* Called now and then with (work done, total), may be NULL: work items for
   * recursive and packet, rays terminated of rays spawned so far for dynamic. */
  render_progress_fn progress;
  void *progress_ctx;
  /* Sampling (optional; NULL: every item through the worker's own port).
   * Asked when a worker has claimed work item k and before its first access,
   * with the worker's core: POLICY_ITEM_DETAIL does the item through the
   * worker's port; POLICY_ITEM_PORT through *port instead (a backend that
   * takes no time and never suspends: it warms caches or only counts);
   * POLICY_ITEM_HOLD: the worker waits (mem_wait, 64 cycles, doubling up to
   * 4096) and asks again about the same item; POLICY_ITEM_SKIP: the item is
   * not traced at all (no access, no ray, its pixels left black). Items are
   * claimed in order, one a claim. item_done (may be
   * NULL) hears when a POLICY_ITEM_DETAIL item is finished. Recursive and packet only: the
   * dynamic policy claims a whole batch at once (policy_job_create CHECKs). */
  enum policy_item (*item)(void *ctx, uint64_t k, uint32_t core, struct mem_port *port);
  void (*item_done)(void *ctx, uint64_t k);
  void *item_ctx;
  /* Optional (NULL: not told): whom a worker's accesses are for, so that a
   * backend can charge their cost to pixels (docs/outputs.md "Cost in the picture").
   * Before its accesses for one ray the worker calls it with that ray's
   * pixel (n = 1); before work shared by several rays (a packet's traversal,
   * a queue point's table entry and geometry) with their pixels, one a ray
   * (n > 1; the array stays as it is until the worker's next call, which is
   * made, with n = 0 if need be, before it returns). Every access of a
   * render is announced so. */
  void (*attribute)(void *ctx, uint32_t worker, const uint32_t *pixels, uint32_t n);
  void *attribute_ctx;
  /* Optional (NULL: the dynamic policy counts them itself): qpoint_subtree_tris
   * of kd (with a BVH, qpoint_bvh_subtree_tris of it), for a caller that runs
   * the dynamic policy many times over one tree (rtsim traffic, once per cache
   * size) to count once. */
  const uint32_t *subtree_tris;
};

/* One render's shared work list and whatever the policy shares between its
 * workers (opaque). State that belongs to one core of the machine (the
 * dynamic policy's queue point) is kept in the job, indexed by the worker's
 * core. */
struct policy_job;

/* One worker: a simulated ray context. Caller-provided storage; set up by
 * policy_worker_init, released by policy_worker_fini. */
struct policy_worker {
  /* Its own tracer: its memory port, its trace_stats, and its layout, whose
   * ray_base is its own ray region: setup ray_base + id x
   * policy_ray_region_bytes (worker 0 keeps the setup's ray_base). */
  struct trace_ctx tr;
  struct render_stats st; /* its own counters */
  uint32_t id;            /* 0 .. workers-1: selects its ray region */
  uint32_t core, thread;  /* where it runs (plain integers; core < cores) */
  void *scratch;          /* the policy's, allocated on its first work item */
  /* Set by a step that parked w (mem_park: it has nothing to do until another
   * worker wakes it); policy_job_work returns then. */
  bool parked;
};

/* Create a render of policy k for up to `workers` workers on `cores` cores.
 * s and p are copied (what s points to is borrowed). CHECKs
 * policy_workers_supported(k, workers) and cores >= 1. Caller destroys. */
struct policy_job *policy_job_create(enum policy_kind k, const struct policy_setup *s,
                                     const struct policy_params *p, uint32_t workers,
                                     uint32_t cores);

/* Whether policy k can render with this many workers: recursive and packet
 * with any number whose ray regions fit the ray region of the layout; dynamic
 * with any (its rays wait in the shared queues). */
bool policy_workers_supported(enum policy_kind k, uint32_t workers);

/* Bytes of the memory image one worker's rays occupy (its ray stack or packet
 * buffers at their bound): worker i's region starts at ray_base + i x this.
 * 0 for dynamic, whose rays wait in the queues at queue_base. */
uint64_t policy_ray_region_bytes(enum policy_kind k);

/* Set up worker w of job: id < workers (each id once), core < cores; its
 * accesses go through port. Allocates nothing (scratch comes with its first
 * work item, so idle workers cost nothing). */
void policy_worker_init(struct policy_worker *w, struct policy_job *job, uint32_t id, uint32_t core,
                        uint32_t thread, struct mem_port port);

/* Take the next work item and do all of it: claim it from the job (before any
 * access), trace, shade, trace what it spawns. False, with no access made,
 * when no work was left. Recursive: one pixel, in Hilbert order, its ray tree
 * depth first; packet: one tile; dynamic: one batch of primary rays
 * (dyn_batch_rays, by default all) through all its generations, which all
 * workers take part in (it returns when the batch is done, or when it parks w
 * with nothing to do: w->parked). Any access through w's port may suspend w. */
bool policy_job_step(struct policy_job *job, struct policy_worker *w);

/* The worker loop: policy_job_step until no work is left (false), or until a
 * step parks w (true: the dynamic policy on the machine, sim/mem.h). A parked
 * worker's function returns; when it is woken the backend calls it again,
 * which calls policy_job_work again on the same w (not policy_worker_init:
 * w->parked tells it) and goes on where it stopped. */
bool policy_job_work(struct policy_job *job, struct policy_worker *w);

/* Release w's scratch and add its counters to the job. Every initialised
 * worker must be finished before policy_job_finish. */
void policy_worker_fini(struct policy_job *job, struct policy_worker *w);

/* After all work is done and all workers are finished: the counters summed
 * over the workers (st->ray_slots_max is the sum of their maxima, as each has
 * its own region). CHECKs that every work item was taken and rays spawned ==
 * rays terminated. ts may be NULL. */
void policy_job_finish(struct policy_job *job, struct render_stats *st, struct trace_stats *ts);

void policy_job_destroy(struct policy_job *job); /* NULL ok */

/* Work items of the render: pixels (recursive, dynamic) or tiles (packet). */
uint64_t policy_job_total(const struct policy_job *job);

/* Render the whole image with policy k and one worker (id 0, core 0, thread 0)
 * whose accesses go through port; st and ts (ts may be NULL) receive the
 * totals. Checks ray conservation at the end. */
void policy_run(enum policy_kind k, const struct policy_setup *s, const struct policy_params *p,
                struct mem_port port, struct render_stats *st, struct trace_stats *ts);

/* "recursive", "packet", "dynamic", "treelet". */
const char *policy_name(enum policy_kind k);
/* What policy k does, in one line for help texts ("?" for no policy). */
const char *policy_about(enum policy_kind k);
/* Parse a name; false if unknown. */
bool policy_parse(const char *name, enum policy_kind *k);
/* Every policy's name in order, ", "-separated, `last` before the last one
 * (", " or " or "): for messages (cut to cap). */
void policy_list(char *buf, size_t cap, const char *last);

/* The policies whose rays wait in queues (dynamic, treelet): they trace all
 * of a batch's rays at once, not a work item at a time. */
static inline bool policy_queues(enum policy_kind k) {
  return k == POLICY_DYNAMIC || k == POLICY_TREELET;
}

#endif
