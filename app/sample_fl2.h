/* Sampling's functional model of the shared L2 (docs/fidelity-and-sampling.md
 * "Sampling"): the DRAM bytes a stretch of consecutive work items causes when
 * the machine's ray contexts run them together. Items are recorded one at a
 * time (their line accesses, in order), then replayed interleaved as the
 * machine interleaves them: every ray context holds one item and takes the
 * next item of the stretch when its own ends, and the contexts issue one
 * access each in turn (round robin, a cheap stand-in for the timed machine's
 * pace, which follows each ray's misses): a context's turn runs its
 * accesses up to its first load that misses its L1 (where a ray waits). An access goes through its
 * core's L1 (the machine's: write-through, no allocation on a store) and the shared L2 (write-back,
 * write-allocate, a whole-line store allocated without a fetch, LRU); a miss that fetches a line
 * costs 64 bytes, a dirty victim 64 more, both charged to the item that made the access. No time,
 * no MSHRs, no pending lines. A batch (a contiguous run of recorded items) starts from the
 * caches the batch before left (the first from empty ones); the items before its counted ones
 * are its warming. Kept, not emptied: a 4 MiB L2 that starts a batch empty charged a stretch's
 * items 1-5% more than a model of the whole image did, however long the warming (3,072 items
 * were 3% over on sphereflake at 512 ray contexts), and with the last batch's lines, 1%. */
#ifndef RTSIM_APP_SAMPLE_FL2_H
#define RTSIM_APP_SAMPLE_FL2_H

#include <stdbool.h>
#include <stdint.h>

struct machine_params;
struct sfl2;

/* The caches and contexts of machine p (cores x threads_per_core x
 * rays_per_thread contexts; context c on core c / (threads x rays)),
 * modelling the lines with line % sets_every == residue only (a power of
 * two; 1: all) and charging each of their bytes sets_every times. The L1's
 * and the L2's set index are the line's low bits, so the modelled lines fill
 * whole sets of both and their hits and misses are exactly those of the full
 * model: set sampling (Kessler et al., 1994), at 1 / sets_every of the cost. */
struct sfl2 *sfl2_create(const struct machine_params *p, uint32_t sets_every, uint32_t residue);
void sfl2_destroy(struct sfl2 *x); /* NULL ok */

/* Begin recording the next item of the batch; its DRAM bytes are added to
 * *out when it is replayed (out NULL: a warming item, counted nowhere). */
void sfl2_item(struct sfl2 *x, double *out);
/* Record one access of the current item (bytes at addr; a store marks lines
 * dirty; a store covering a whole line allocates it without a fetch). */
void sfl2_access(struct sfl2 *x, uint64_t addr, uint32_t size, bool store);
/* How sfl2_pump ends. SFL2_MORE: replay what can run now (every context
 * that needs an item has one), the rest later. SFL2_DRAIN: run the batch to
 * its end, contexts going idle as the recorded items run out (as a timed
 * unit drains); the caches stay for the next batch. SFL2_REFILL: the
 * same, but a context that finds no item takes a filler (the batch's
 * recorded items again, counted nowhere) while a counted item runs: its
 * last counted items share the L2 with as many others as in a full run,
 * however long they run. */
enum sfl2_end { SFL2_MORE, SFL2_DRAIN, SFL2_REFILL };
void sfl2_pump(struct sfl2 *x, enum sfl2_end end);

/* Accesses replayed so far (lines), for the cost. */
uint64_t sfl2_replayed(const struct sfl2 *x);

#endif
