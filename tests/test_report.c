/* The reproduction's regeneration path at reduced size: results/traffic/run.sh
 * on the small scenes at 1/16 of the paper's resolutions writes all 12 scene x
 * ray-configuration tables, 3 policies x 13 cache sizes each, with recursive as
 * the relative baseline, and the markdown report beside the paper's numbers;
 * with POLICY=treelet the treelet policy's tables, which the report adds as a
 * fourth column. */
#include <stdio.h>
#include <string.h>

#include "testing.h"

static int count(const char *hay, const char *needle) {
  int n = 0;
  for (const char *p = strstr(hay, needle); p; p = strstr(p + 1, needle)) n++;
  return n;
}

int main(void) {
  static char out[1 << 20];
  char cmd[2048];
  snprintf(
      cmd, sizeof cmd,
      "cd %s && rm -rf %s/report && RTSIM=%s SCENES=scenes/small sh results/traffic/run.sh %s/report 16 2 "
      "2>/dev/null && cat %s/report/all.csv",
      RTSIM_SOURCE_DIR, RTSIM_TMP, RTSIM_BINARY, RTSIM_TMP, RTSIM_TMP);
  EXPECT(testing_run(cmd, out, sizeof out) == 0);
  EXPECT(count(out, "\n") == 1 + 12 * 3 * 13);
  EXPECT(count(out, ",recursive,") == 12 * 13);
  EXPECT(count(out, ",packet,") == 12 * 13);
  EXPECT(count(out, ",dynamic,") == 12 * 13);
  EXPECT(count(out, ",primary+shadow+diffuse,32,32,") == 3 * 3 * 13);
  EXPECT(count(out, ",primary+shadow+specular,64,64,") == 3 * 3 * 13);
  /* Relative columns of the baseline are exactly 1. */
  int base_ok = 1;
  for (const char *p = strstr(out, ",recursive,"); p; p = strstr(p + 1, ",recursive,")) {
    const char *eol = strchr(p, '\n');
    const char *rel = strstr(p, ",1.0000,1.0000,");
    if (!rel || (eol && rel > eol)) base_ok = 0;
  }
  EXPECT(base_ok);
  snprintf(cmd, sizeof cmd, "cat %s/report/tables.md", RTSIM_TMP);
  EXPECT(testing_run(cmd, out, sizeof out) == 0);
  EXPECT(count(out, "### ") == 12);
  EXPECT(count(out, "| 1 K |") == 12 && count(out, "| 4096 K |") == 12);
  EXPECT(strstr(out, "### grove, diffuse rays (32x32)") != NULL);
  /* The paper's numbers stand beside ours (grove, diffuse, 512 KB: packet
   * total 4409.57 MB, dynamic 564.75 MB). */
  EXPECT(strstr(out, "4451.86 / 4409.57 / 564.75") != NULL);

  snprintf(cmd, sizeof cmd,
           "cd %s && rm -rf %s/report-tl && RTSIM=%s SCENES=scenes/small POLICY=treelet sh "
           "results/traffic/run.sh %s/report-tl 16 2 2>/dev/null && cat %s/report-tl/all.csv",
           RTSIM_SOURCE_DIR, RTSIM_TMP, RTSIM_BINARY, RTSIM_TMP, RTSIM_TMP);
  EXPECT(testing_run(cmd, out, sizeof out) == 0);
  /* With its baseline: recursive beside it, as in every traffic table. */
  EXPECT(count(out, "\n") == 1 + 12 * 2 * 13 && count(out, ",treelet,") == 12 * 13);
  snprintf(cmd, sizeof cmd,
           "cd %s && sh results/traffic/tables.sh %s/report/all.csv results/traffic/paper.csv "
           "%s/report-tl/all.csv",
           RTSIM_SOURCE_DIR, RTSIM_TMP, RTSIM_TMP);
  EXPECT(testing_run(cmd, out, sizeof out) == 0);
  EXPECT(count(out, "### ") == 12);
  EXPECT(count(out, "| total MB rec / pkt / dyn / tl |") == 12);
  EXPECT(count(out, "| 4096 K |") == 12);
  /* Every row has a treelet figure: four geometry numbers before the paper's. */
  EXPECT(count(out, " / nan") == 0 && count(out, " / inf") == 0);
  return testing_done("test_report");
}
