/* The banked level's parameter rules: what a key's range in the key table
 * (machine_cfg) cannot say, powers of two and the relations between keys, and
 * the bounds the level's arithmetic holds within. Holds: a params struct that
 * passes dram_banked_params_problem builds a level (dram_banked_create CHECKs
 * both), and each message names the key to change. */
#include "sim/dram_banked_state.h"

#include <stddef.h>

static bool pow2(uint64_t x) { return x && !(x & (x - 1)); }

const char *dram_banked_params_problem(const struct dram_banked_params *p) {
  /* Each key's range is its row in the key table (machine_params_problem);
   * here, what a range cannot say: powers of two, and rules between keys.
   * The messages state the ranges too, so a bad value reads the same from a
   * config or from code that fills the parameters itself. */
  if (!pow2(p->channels)) return "dram.channels: must be a power of two from 1 to 64";
  if (!pow2(p->ranks)) return "dram.ranks: must be a power of two from 1 to 16";
  if (!pow2(p->bank_groups)) return "dram.bank_groups: must be a power of two from 1 to 16";
  if (!pow2(p->banks_per_group)) return "dram.banks_per_group: must be a power of two from 1 to 64";
  if (!pow2(p->rows)) return "dram.rows: must be a power of two up to 2^24";
  if (p->burst_length < 2 || !pow2(p->burst_length))
    return "dram.burst_length: must be a power of two from 2 to 64";
  if (!pow2(p->columns) || p->columns < p->burst_length)
    return "dram.columns: must be a power of two from burst_length to 2^20";
  /* 32: the widest bus a burst of two beats leaves for a 64-byte line. */
  if (!pow2(p->bus_bytes) || p->bus_bytes > SIM_LINE_BYTES / 2)
    return "dram.bus_bytes: must be a power of two up to 32";
  if (p->bus_bytes * p->burst_length != SIM_LINE_BYTES)
    return "dram.bus_bytes: bus_bytes x burst_length must be 64 (one line per burst)";
  if (!dram_banked_mapping_ok(p->mapping))
    return "dram.mapping: expected six two-letter fields, each of ro ch ra bg ba co once";
  /* The fields must fit above the 6 offset bits of a 64-bit address. */
  if (dram_banked_map_bits(p) > 64 - SIM_LINE_LG2)
    return "dram.rows: the address fields need more than 64 bits";
  if (p->write_high > p->write_queue) return "dram.write_high: must be 1 to write_queue";
  if (p->write_low >= p->write_high) return "dram.write_low: must be below write_high";
  if (p->queue_structure != DRAM_BANKED_SHARED && p->controller_cycles < 1)
    return "dram.controller_cycles: must be at least 1 with queue_structure per_bank or per_rank "
           "(a request reaches its command queue at the end of a cycle)";
  if (p->tRC < p->tRAS) return "dram.tRC: must be at least tRAS";
  if (p->tCCD_L < p->tCCD_S) return "dram.tCCD_L: must be at least tCCD_S";
  if (p->tRRD_L < p->tRRD_S) return "dram.tRRD_L: must be at least tRRD_S";
  if (p->tWTR_L < p->tWTR_S) return "dram.tWTR_L: must be at least tWTR_S";
  if (p->tREFI && p->tREFI / p->ranks <= p->tRFC)
    return "dram.tREFI: tREFI / ranks must exceed tRFC (or tREFI 0: no refresh)";
  if (!pow2(p->device_width) || p->device_width > p->bus_bytes * 8)
    return "dram.device_width: must be a power of two up to bus_bytes x 8";
  /* No energy of a command below its standby's (DRAMsim3's increments). */
  if (p->IDD0 * p->tRC < p->IDD3N * p->tRAS + p->IDD2N * p->tRP)
    return "dram.IDD0: IDD0 x tRC must be at least IDD3N x tRAS + IDD2N x tRP (an activate's "
           "energy is not negative)";
  if (p->IDD4R < p->IDD3N) return "dram.IDD4R: must be at least IDD3N";
  if (p->IDD4W < p->IDD3N) return "dram.IDD4W: must be at least IDD3N";
  if (p->IDD5AB < p->IDD3N) return "dram.IDD5AB: must be at least IDD3N";
  return NULL;
}

/* NOTE: the level's arithmetic holds for timings up to 2^20 DRAM cycles and
 * clocks up to 2^24 kHz; the key table's ranges lie well inside. CHECKed at
 * creation, so a table widened past them fails loudly, not in a wrong cycle. */
bool dram_banked_params_within_model(const struct dram_banked_params *p) {
  const uint32_t t[] = {p->tCL,    p->tCWL,   p->tRCD,   p->tRP,    p->tRAS,  p->tRC,
                        p->tCCD_S, p->tCCD_L, p->tRRD_S, p->tRRD_L, p->tFAW,  p->tWR,
                        p->tWTR_S, p->tWTR_L, p->tRTW,   p->tRTP,   p->tREFI, p->tRFC};
  for (unsigned i = 0; i < sizeof t / sizeof t[0]; i++)
    if (t[i] > (1u << 20)) return false;
  return p->clock_mhz >= 1 && p->clock_mhz <= (1u << 24) / 1000;
}
