/* The banked DRAM level's parameter rules alone (sim/dram_banked_params.c):
 * each rule between keys refuses a bad value and names the key, and the
 * bounds within which the level's arithmetic holds. */
#include <string.h>

#include "sim/dram_banked_state.h"
#include "testing.h"

static struct dram_banked_params ddr4(void) { return testing_ddr4_params(); }

/* Each rule's message names its key (the rules a range cannot say; ranges
 * are the key table's: test_machine_cfg). */
static void test_problems(void) {
  struct dram_banked_params ok = ddr4();
  EXPECT(dram_banked_params_problem(&ok) == NULL);
  struct dram_banked_params p;
#define BAD(stmt, key)                                                                             \
  do {                                                                                             \
    p = ok;                                                                                        \
    stmt;                                                                                          \
    const char *m = dram_banked_params_problem(&p);                                                \
    EXPECTF(m && !strncmp(m, key ":", strlen(key ":")), "%s: got %s", #stmt, m ? m : "NULL");      \
  } while (0)
  BAD(p.channels = 3, "dram.channels");
  BAD(p.ranks = 0, "dram.ranks");
  BAD(p.bank_groups = 6, "dram.bank_groups");
  BAD(p.rows = 1000, "dram.rows");
  BAD(p.columns = 1000, "dram.columns");
  BAD(p.columns = 4, "dram.columns");
  BAD(p.bus_bytes = 16, "dram.bus_bytes");
  BAD((p.bus_bytes = 4, p.burst_length = 8), "dram.bus_bytes");
  BAD(p.burst_length = 6, "dram.burst_length");
  BAD(strcpy(p.mapping, "rochrababg"), "dram.mapping");
  BAD(strcpy(p.mapping, "rochrababgba"), "dram.mapping");
  BAD(strcpy(p.mapping, "rochrababgxx"), "dram.mapping");
  BAD((p.queue_structure = DRAM_BANKED_PER_BANK, p.command_queue = 8, p.controller_cycles = 0),
      "dram.controller_cycles");
  BAD(p.write_high = 40, "dram.write_high");
  BAD(p.write_low = 24, "dram.write_low");
  BAD(p.tRC = 20, "dram.tRC");
  BAD(p.tCCD_L = 2, "dram.tCCD_L");
  BAD(p.tRRD_L = 1, "dram.tRRD_L");
  BAD(p.tWTR_L = 1, "dram.tWTR_L");
  BAD((p.tREFI = 400, p.tRFC = 420), "dram.tREFI");
  /* 6 + ch 6 + ra 4 + bg 4 + ba 6 + ro 24 + co 17 = 67 bits. */
  BAD((p.channels = 64, p.ranks = 16, p.bank_groups = 16, p.banks_per_group = 64, p.rows = 1u << 24,
       p.columns = 1u << 20),
      "dram.rows");
#undef BAD
}

/* The arithmetic's bounds (CHECKed at creation): timings up to 2^20 DRAM
 * cycles, clocks from 1 to floor(2^24 / 1000) = 16777 MHz. */
static void test_within_model(void) {
  struct dram_banked_params p = ddr4();
  EXPECT(dram_banked_params_within_model(&p));
  p.tRFC = 1u << 20;
  EXPECT(dram_banked_params_within_model(&p));
  p.tRFC = (1u << 20) + 1;
  EXPECT(!dram_banked_params_within_model(&p));
  p = ddr4();
  p.clock_mhz = 16777;
  EXPECT(dram_banked_params_within_model(&p));
  p.clock_mhz = 16778;
  EXPECT(!dram_banked_params_within_model(&p));
  p.clock_mhz = 0;
  EXPECT(!dram_banked_params_within_model(&p));
}

int main(void) {
  test_problems();
  test_within_model();
  return testing_done("dram_banked_params");
}
