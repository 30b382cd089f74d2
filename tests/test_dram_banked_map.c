/* The banked DRAM level's address mapping alone (sim/dram_banked_map.c):
 * hand-computed decodes of a few addresses for two mappings (DRAMsim3's
 * address-decoding tests), the bits the fields take, which mapping strings
 * are usable, and that a level decodes through the same map. */
#include <string.h>

#include "sim/dram_banked_state.h"
#include "sim/engine.h"
#include "testing.h"

static bool coord_is(const struct dram_banked_coord *c, uint32_t ch, uint32_t ra, uint32_t bg,
                     uint32_t ba, uint64_t row, uint64_t column) {
  return c->channel == ch && c->rank == ra && c->bank_group == bg && c->bank == ba &&
         c->row == row && c->column == column;
}

/* 2 channels, 2 ranks, 4 groups, 4 banks, 1024 rows, 1024 columns / BL 8 =
 * 128 bursts: widths ch 1, ra 1, bg 2, ba 2, ro 10, co 7, above 6 offset
 * bits: 23 bits of fields. */
static struct dram_banked_params small(const char *mapping) {
  struct dram_banked_params p = testing_ddr4_params();
  p.channels = 2;
  p.ranks = 2;
  p.rows = 1024;
  strcpy(p.mapping, mapping);
  return p;
}

static void test_decode(void) {
  struct dram_banked_map m;
  struct dram_banked_coord c;
  /* "rochrababgco": co 6..12, bg 13..14, ba 15..16, ra 17, ch 18, ro 19..28.
   * ro 0x2A5 (<< 19 = 0x15280000), ch 1 (0x40000), ra 0, ba 3 (0x18000),
   * bg 2 (0x4000), co 0x55 (<< 6 = 0x1540): 0x152DD540. */
  struct dram_banked_params p = small("rochrababgco");
  dram_banked_map_init(&m, &p);
  dram_banked_map_decode(&m, 0x152DD540ull, &c);
  EXPECT(coord_is(&c, 1, 0, 2, 3, 0x2A5, 0x55 * 8));
  dram_banked_map_decode(&m, 0x20000ull, &c); /* bit 17: rank 1 only */
  EXPECT(coord_is(&c, 0, 1, 0, 0, 0, 0));
  /* The line offset is not decoded: byte 63 of the first line is line 0. */
  dram_banked_map_decode(&m, 63, &c);
  EXPECT(coord_is(&c, 0, 0, 0, 0, 0, 0));
  /* Bits above the fields (29 and up) alias: the row wraps at 1024. */
  dram_banked_map_decode(&m, (1ull << 29) | 0x152DD540ull, &c);
  EXPECT(coord_is(&c, 1, 0, 2, 3, 0x2A5, 0x55 * 8));
  /* The last line of the space: every field at its most. */
  dram_banked_map_decode(&m, (1ull << 29) - 64, &c);
  EXPECT(coord_is(&c, 1, 1, 3, 3, 1023, 127 * 8));

  /* "chrobabgraco" (DRAMsim3's default): co 6..12, ra 13, bg 14..15, ba
   * 16..17, ro 18..27, ch 28. ch 1 (0x10000000), ro 0x155 (<< 18 =
   * 0x5540000), ba 2 (0x20000), bg 1 (0x4000), ra 1 (0x2000), co 0x7F
   * (0x1FC0): 0x15567FC0. */
  p = small("chrobabgraco");
  dram_banked_map_init(&m, &p);
  dram_banked_map_decode(&m, 0x15567FC0ull, &c);
  EXPECT(coord_is(&c, 1, 1, 1, 2, 0x155, 0x7F * 8));
  /* The same address under the first mapping reads other fields: line
   * 0x15567FC0 >> 6 = 0x5559FF, bits 0..6 co 0x7F, 7..8 bg 3, 9..10 ba 0,
   * 11 ra 1, 12 ch 1, 13..22 ro 0b1010101010 = 0x2AA. */
  p = small("rochrababgco");
  dram_banked_map_init(&m, &p);
  dram_banked_map_decode(&m, 0x15567FC0ull, &c);
  EXPECT(coord_is(&c, 1, 1, 3, 0, 0x2AA, 0x7F * 8));
}

/* HBM2's preset shape (8 channels, 32768 rows, 128 columns, 4-beat bursts:
 * 32 bursts a row, co 5 bits) and mapping "rorabgbachco": from the line
 * address's bit 0, co 0..4, ch 5..7, ba 8..9, bg 10..11, ra none (1 rank),
 * ro 12..26. Line 0x1234 = 0b1_0010_0011_0100: co 0b10100 = 0x14, ch 0b001,
 * ba 0b10, bg 0b00, ro 1. */
static void test_decode_hbm(void) {
  struct dram_banked_params p = testing_ddr4_params();
  p.channels = 8;
  p.rows = 32768;
  p.columns = 128;
  p.bus_bytes = 16;
  p.burst_length = 4;
  strcpy(p.mapping, "rorabgbachco");
  EXPECT(dram_banked_params_problem(&p) == NULL);
  struct dram_banked_map m;
  struct dram_banked_coord c;
  dram_banked_map_init(&m, &p);
  dram_banked_map_decode(&m, 0x1234ull << 6, &c);
  EXPECT(coord_is(&c, 1, 0, 0, 2, 1, 0x14 * 4));
  EXPECT(dram_banked_map_bits(&p) == 15 + 0 + 2 + 2 + 3 + 5);
}

static void test_bits_and_strings(void) {
  struct dram_banked_params p = small("rochrababgco");
  EXPECT(dram_banked_map_bits(&p) == 23);
  p = testing_ddr4_params(); /* 65536 rows, 16 banks, 128 bursts */
  EXPECT(dram_banked_map_bits(&p) == 16 + 0 + 0 + 2 + 2 + 7);
  EXPECT(dram_banked_mapping_ok("rochrababgco") && dram_banked_mapping_ok("chrobabgraco"));
  EXPECT(!dram_banked_mapping_ok("rochrababgc") && !dram_banked_mapping_ok("rorochrababg") &&
         !dram_banked_mapping_ok("rochrababgxx") && !dram_banked_mapping_ok(NULL));
}

static void no_done(void *ctx, uint64_t tag) {
  (void)ctx;
  (void)tag;
}

/* A level decodes with the map its parameters make. */
static void test_level_decodes(void) {
  struct dram_banked_params p = small("chrobabgraco");
  struct engine *e = engine_create();
  struct dram_client cl = {NULL, no_done, NULL, NULL};
  struct dram_banked *d = dram_banked_create(&p, 1200 * 1000, e, &cl);
  struct dram_banked_coord c;
  dram_banked_decode(d, 0x15567FC0ull, &c);
  EXPECT(coord_is(&c, 1, 1, 1, 2, 0x155, 0x7F * 8));
  dram_banked_destroy(d);
  engine_destroy(e);
}

int main(void) {
  test_decode();
  test_decode_hbm();
  test_bits_and_strings();
  test_level_decodes();
  return testing_done("dram_banked_map");
}
