/* The functional backend: a struct mem_ops behind the memory door that splits
 * each access into the cache lines it touches and feeds every line to the
 * one-pass LRU stack analyser (all cache sizes at once) and, if given, to a din
 * trace writer. No time: compute announcements are ignored. */
#ifndef RTSIM_SIM_MEM_FUNCTIONAL_H
#define RTSIM_SIM_MEM_FUNCTIONAL_H

#include <stdbool.h>
#include <stdint.h>

#include "sim/lru_stack.h"
#include "sim/mem.h"

struct din_writer;

/* What the renderer asked for, by data class (requests, not lines). */
struct mem_functional_stats {
  uint64_t loads[MEM_CLASS_MAX], stores[MEM_CLASS_MAX]; /* requests */
  uint64_t bytes_loaded[MEM_CLASS_MAX], bytes_stored[MEM_CLASS_MAX];
  uint64_t line_accesses[MEM_CLASS_MAX]; /* lines touched, = analyser accesses */
};

struct mem_functional;

/* Create a backend with a fresh analyser of geometry p (must pass
 * lru_stack_params_problem; CHECKed). din is borrowed and may be NULL: the
 * caller closes it after the run; records go one per line of p->lg2_line.
 * analyser_thread: the analyser runs on a host thread of its own, beside the
 * caller's (results identical; mem_functional_stack waits for it). Worth it
 * only with a host core to spare (mem_functional_host_cpus). Caller destroys;
 * the port is then for one thread, the caller's. */
struct mem_functional *mem_functional_create(const struct lru_stack_params *p,
                                             struct din_writer *din, bool analyser_thread);
bool mem_functional_threaded(const struct mem_functional *b);

/* Host CPUs this process may run on (its affinity mask: a Slurm task or
 * taskset sees its own share), at least 1. */
unsigned mem_functional_host_cpus(void);
void mem_functional_destroy(struct mem_functional *b); /* NULL ok; does not touch din */

/* The port the renderer calls through; valid while b lives. */
struct mem_port mem_functional_port(struct mem_functional *b);

/* The analyser (borrowed), after the run: call lru_stack_finish and read
 * results. With an analyser thread, this waits until it has taken every line
 * so far; the caller may then read the analyser until its next access. Accesses that repeat the
 * last line without changing its state skip the analyser and are counted here; this call hands
 * those counts over, so call it again after any further access before reading results. */
struct lru_stack *mem_functional_stack(struct mem_functional *b);

const struct mem_functional_stats *mem_functional_get_stats(const struct mem_functional *b);

#endif
