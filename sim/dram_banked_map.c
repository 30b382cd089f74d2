/* The banked level's address mapping (DRAMsim3's): above the 6 line-offset
 * bits, six fields from most to least significant in the order the mapping
 * string names them ("ro" "ch" "ra" "bg" "ba" "co"), each log2 of its count
 * wide; co is log2(columns / burst_length), one line per burst. Holds: every
 * field's shift and mask come from the string and the sizes alone, so two
 * levels of the same parameters decode alike. */
#include "sim/dram_banked_state.h"

#include <string.h>

static unsigned lg2(uint64_t x) {
  unsigned n = 0;
  while (x > 1) {
    x >>= 1;
    n++;
  }
  return n;
}

static const char *const FIELDS[6] = {"ro", "ch", "ra", "bg", "ba", "co"};

/* Index in FIELDS of the two letters at s, or -1. */
static int field_of(const char *s) {
  for (int i = 0; i < 6; i++)
    if (s[0] == FIELDS[i][0] && s[1] == FIELDS[i][1]) return i;
  return -1;
}

bool dram_banked_mapping_ok(const char *s) {
  if (!s || strlen(s) != 12) return false;
  unsigned seen = 0;
  for (int i = 0; i < 6; i++) {
    int f = field_of(s + 2 * i);
    if (f < 0 || (seen & (1u << f))) return false;
    seen |= 1u << f;
  }
  return true;
}

/* Each field's width, in FIELDS' order. */
static void widths(const struct dram_banked_params *p, unsigned width[6]) {
  width[0] = lg2(p->rows);
  width[1] = lg2(p->channels);
  width[2] = lg2(p->ranks);
  width[3] = lg2(p->bank_groups);
  width[4] = lg2(p->banks_per_group);
  width[5] = lg2(p->columns / p->burst_length);
}

unsigned dram_banked_map_bits(const struct dram_banked_params *p) {
  unsigned width[6];
  widths(p, width);
  return width[0] + width[1] + width[2] + width[3] + width[4] + width[5];
}

void dram_banked_map_init(struct dram_banked_map *m, const struct dram_banked_params *p) {
  /* Field widths, then positions from the least significant (the last). */
  unsigned width[6];
  widths(p, width);
  unsigned pos[6] = {0}, at = 0;
  for (int i = 5; i >= 0; i--) {
    int f = field_of(p->mapping + 2 * i);
    pos[f] = at;
    at += width[f];
  }
  m->sh_ro = pos[0], m->mk_ro = (1ull << width[0]) - 1;
  m->sh_ch = pos[1], m->mk_ch = (1ull << width[1]) - 1;
  m->sh_ra = pos[2], m->mk_ra = (1ull << width[2]) - 1;
  m->sh_bg = pos[3], m->mk_bg = (1ull << width[3]) - 1;
  m->sh_ba = pos[4], m->mk_ba = (1ull << width[4]) - 1;
  m->sh_co = pos[5], m->mk_co = (1ull << width[5]) - 1;
  m->burst_length = p->burst_length;
}

void dram_banked_map_decode(const struct dram_banked_map *m, uint64_t addr,
                            struct dram_banked_coord *out) {
  uint64_t a = addr >> SIM_LINE_LG2;
  out->channel = (uint32_t)((a >> m->sh_ch) & m->mk_ch);
  out->rank = (uint32_t)((a >> m->sh_ra) & m->mk_ra);
  out->bank_group = (uint32_t)((a >> m->sh_bg) & m->mk_bg);
  out->bank = (uint32_t)((a >> m->sh_ba) & m->mk_ba);
  out->row = (a >> m->sh_ro) & m->mk_ro;
  out->column = ((a >> m->sh_co) & m->mk_co) * m->burst_length;
}

void dram_banked_decode(const struct dram_banked *d, uint64_t addr, struct dram_banked_coord *out) {
  dram_banked_map_decode(&d->map, addr, out);
}
