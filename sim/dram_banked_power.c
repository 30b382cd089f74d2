/* The banked level's energy (sim/dram_banked.h, struct dram_banked_energy):
 * DRAMsim3's model from the commands each rank issued and the cycles it had a
 * bank open, in joules. Holds: every figure is a count the level keeps times a
 * constant of the parameters, so the energy costs the hot path a few integer
 * increments; a rank's cycles split into active and precharged standby, which
 * add up to the level's DRAM cycles. The file's name sorts it among the
 * level's cold files (see the NOTE in sim/dram_banked_state.h). */
#include "sim/dram_banked_state.h"

#include "sim/err.h"

/* A rank's (or a sum of ranks') counts. */
struct counts {
  uint64_t acts, reads, writes, refs, active_cycles, cycles;
};

void dram_banked_costs_of(const struct dram_banked_params *p, struct dram_banked_costs *out) {
  /* mA x V x ns is pJ: a DRAM cycle is 1000 / clock_mhz ns. */
  const double devices = (double)(p->bus_bytes * 8 / p->device_width);
  const double j = p->VDD * devices * (1000.0 / p->clock_mhz) * 1e-12;
  const double burst = (double)(p->burst_length / 2);
  struct dram_banked_costs k;
  k.act = j * (p->IDD0 * p->tRC - (p->IDD3N * p->tRAS + p->IDD2N * p->tRP));
  k.read = j * (p->IDD4R - p->IDD3N) * burst;
  k.write = j * (p->IDD4W - p->IDD3N) * burst;
  k.ref = j * (p->IDD5AB - p->IDD3N) * p->tRFC;
  k.act_stb = j * p->IDD3N;
  k.pre_stb = j * p->IDD2N;
  *out = k;
}

static void add_rank(struct counts *n, const struct dram_banked_rank *rk, uint64_t cycles) {
  n->acts += rk->acts;
  n->reads += rk->reads;
  n->writes += rk->writes;
  n->refs += rk->refs;
  n->active_cycles += rk->active_cycles;
  n->cycles += cycles;
}

static void energy(const struct dram_banked_params *p, const struct counts *n,
                   struct dram_banked_energy *out) {
  struct dram_banked_costs k;
  dram_banked_costs_of(p, &k);
  out->activate_j = (double)n->acts * k.act;
  out->read_j = (double)n->reads * k.read;
  out->write_j = (double)n->writes * k.write;
  out->refresh_j = (double)n->refs * k.ref;
  out->active_standby_j = (double)n->active_cycles * k.act_stb;
  out->precharge_standby_j = (double)(n->cycles - n->active_cycles) * k.pre_stb;
  out->total_j = out->activate_j + out->read_j + out->write_j + out->refresh_j +
                 out->active_standby_j + out->precharge_standby_j;
}

void dram_banked_power_finish(struct dram_banked *d, int64_t end) {
  d->st.rank_active_cycles = 0;
  for (uint32_t i = 0; i < d->p.channels; i++)
    for (uint32_t k = 0; k < d->p.ranks; k++) {
      struct dram_banked_rank *rk = &d->ch[i].ranks[k];
      if (rk->open) {
        rk->active_cycles += (uint64_t)(end - rk->active_since);
        rk->active_since = end;
      }
      d->st.rank_active_cycles += rk->active_cycles;
    }
  d->st.rank_cycles = (uint64_t)end * d->p.ranks * d->p.channels;
}

void dram_banked_energy_of(const struct dram_banked *d, int channel, int rank,
                           struct dram_banked_energy *out) {
  CHECK(channel < (int64_t)d->p.channels && rank < (int64_t)d->p.ranks);
  struct counts n = {0};
  for (uint32_t i = 0; i < d->p.channels; i++)
    for (uint32_t k = 0; k < d->p.ranks; k++)
      if ((channel < 0 || (uint32_t)channel == i) && (rank < 0 || (uint32_t)rank == k))
        add_rank(&n, &d->ch[i].ranks[k], d->finished_dram_cycles);
  energy(&d->p, &n, out);
}

/* Before finish: the commands counted, and each rank's cycles to DRAM cycle x
 * (t's, or the cursor if that is later: its counts reach there), those since
 * an open rank's ACT active. After: the total the stats report. */
double dram_banked_energy_so_far(const void *self, uint64_t t) {
  const struct dram_banked *d = self;
  struct dram_banked_energy e;
  if (d->finished) {
    dram_banked_energy_total(d, &d->st, &e);
    return e.total_j;
  }
  int64_t x = (int64_t)dram_clock_from_core(d->clk, t);
  if (x < d->cursor) x = d->cursor;
  struct counts n = {0};
  for (uint32_t i = 0; i < d->p.channels; i++)
    for (uint32_t k = 0; k < d->p.ranks; k++) {
      const struct dram_banked_rank *rk = &d->ch[i].ranks[k];
      add_rank(&n, rk, (uint64_t)x);
      if (rk->open && x > rk->active_since) n.active_cycles += (uint64_t)(x - rk->active_since);
    }
  energy(&d->p, &n, &e);
  return e.total_j;
}

void dram_banked_energy_total(const struct dram_banked *d, const struct dram_banked_stats *s,
                              struct dram_banked_energy *out) {
  const struct counts n = {s->activates,          s->reads,      s->writes, s->refreshes,
                           s->rank_active_cycles, s->rank_cycles};
  energy(&d->p, &n, out);
}
