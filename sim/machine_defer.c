/* L2-hit answers a core keeps instead of queuing events (machine_state.h).
 *
 * An answer stands for an event with key (at, seq), seq taken when the L2 hit
 * (engine_reserve): the line filled into the core's L1, the ray's wait ended,
 * its thread taking it or queuing it, and a kick of the core's issue. Kept by
 * the core, it is done at the first call that could see it, with `at` as its
 * cycle: every event and kept answer before its key has been done by then, and
 * none after, so it finds what its event would have found and does the same.
 * All but the kick: a kick that schedules an issue event needs the engine at
 * `at`. So an answer is kept only while its kick would do nothing: while its
 * core has an issue event due when its port frees (it issues back to back:
 * kick leaves such an event alone), with a key after the answer's. That holds
 * until the issue event itself, which does the answers before it first; one
 * due after the core's next issue is kept until that issue, after which the
 * core turns into events what it keeps that no longer meets the rule
 * (defer_settle). On a busy core nearly every hit is kept.
 *
 * What it saves: an event a hit (a third of a default run's), and its host
 * cache misses. What it costs: a check where a core's L1 or threads are
 * read, and `events` counts fewer events (docs/stats.md). */
#include "sim/machine_state.h"

#include <string.h>

/* The core's issue event comes when its port frees: kick leaves it alone. */
static inline bool back_to_back(const struct mcore *k) {
  return k->ev && k->ev_at == k->port_free;
}

static void keep(struct mcore *k, const struct mdefer *d) {
  if (k->dn == k->dcap) {
    if (k->dh) {
      memmove(k->dq, k->dq + k->dh, (k->dn - k->dh) * sizeof *k->dq);
      k->dn -= k->dh;
      k->dh = 0;
    } else {
      k->dcap = k->dcap ? 2 * k->dcap : 16;
      k->dq = xrealloc(k->dq, k->dcap * sizeof *k->dq);
    }
  }
  /* In key order; a new answer's key is nearly always the last. */
  uint32_t i = k->dn++;
  for (; i > k->dh && engine_key_before(d->at, d->seq, k->dq[i - 1].at, k->dq[i - 1].seq); i--)
    k->dq[i] = k->dq[i - 1];
  k->dq[i] = *d;
}

void defer_hit(void *waiter, uint64_t line, uint64_t at) {
  struct mctx *c = waiter;
  struct machine *m = c->m;
  struct mcore *k = &m->core[c->info.core];
  const uint64_t seq = engine_reserve(m->eng);
  if (back_to_back(k) || (k->ev && engine_key_before(k->ev_at, k->ev_seq, at, seq))) {
    const struct mdefer d = {at, seq, line, (uint32_t)(c - m->ctx)};
    keep(k, &d);
  } else {
    engine_at_reserved(m->eng, at, seq, m->line_ready, c, line);
  }
}

void defer_until(struct machine *m, struct mcore *k, uint64_t at, uint64_t seq) {
  while (k->dh != k->dn && engine_key_before(k->dq[k->dh].at, k->dq[k->dh].seq, at, seq)) {
    const struct mdefer d = k->dq[k->dh++];
    /* What makes it exact: the kick it ends with does nothing. */
    CHECK(back_to_back(k));
    machine_line_back(m, &m->ctx[d.ctx], d.line, d.at);
  }
  if (k->dh == k->dn) k->dh = k->dn = 0;
}

void defer_until_all(struct machine *m, uint64_t at, uint64_t seq) {
  for (uint32_t i = 0; i < m->p.cores; i++)
    if (m->core[i].dh != m->core[i].dn) defer_until(m, &m->core[i], at, seq);
}

void defer_settle(struct machine *m, struct mcore *k) {
  if (k->dh == k->dn || back_to_back(k)) return;
  /* Those before its next issue (all, with none due) become events. */
  while (k->dh != k->dn &&
         (!k->ev || engine_key_before(k->dq[k->dh].at, k->dq[k->dh].seq, k->ev_at, k->ev_seq))) {
    const struct mdefer d = k->dq[k->dh++];
    engine_at_reserved(m->eng, d.at, d.seq, m->line_ready, &m->ctx[d.ctx], d.line);
  }
  if (k->dh == k->dn) k->dh = k->dn = 0;
}
