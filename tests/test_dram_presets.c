/* The DRAM presets against their table of sources (configs/dram/README.md):
 * every key a preset sets has a row, every row's value is the preset's
 * resolved value, a value that is not its source's value has a note saying
 * why, and every preset in configs/dram has a table. The two cannot drift. */
#include <dirent.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "sim/err.h"
#include "sim/machine_cfg.h"
#include "testing.h"

#define DIR_DRAM RTSIM_SOURCE_DIR "/configs/dram"

/* A table row: the five cells, trimmed of blanks and backticks. */
struct row {
  char key[64], value[64], source[160], source_value[64], note[512];
};

/* Copy cell [b, e) into out, without surrounding blanks, and without the
 * backticks of a cell that is one code span ("`16`" is 16, "ini `CL`" stays). */
static void cell(const char *b, const char *e, char *out, size_t cap) {
  while (b < e && *b == ' ') b++;
  while (e > b && e[-1] == ' ') e--;
  if (e - b >= 2 && *b == '`' && e[-1] == '`' && !memchr(b + 1, '`', (size_t)(e - b - 2))) b++, e--;
  size_t n = (size_t)(e - b);
  if (n >= cap) n = cap - 1;
  memcpy(out, b, n);
  out[n] = '\0';
}

/* Parse one "| a | b | c | d | e |" line into r; false if it has not five cells. */
static bool parse_row(const char *line, const char *end, struct row *r) {
  char *dst[5] = {r->key, r->value, r->source, r->source_value, r->note};
  const size_t cap[5] = {sizeof r->key, sizeof r->value, sizeof r->source, sizeof r->source_value,
                         sizeof r->note};
  if (*line != '|') return false;
  const char *b = line + 1;
  for (int i = 0; i < 5; i++) {
    const char *bar = memchr(b, '|', (size_t)(end - b));
    if (!bar) return false;
    cell(b, bar, dst[i], cap[i]);
    b = bar + 1;
  }
  return b == end;
}

/* The rows of preset `name`'s table (after its marker, header skipped);
 * returns how many (at most cap), or -1 when README has no such table. */
static int table_of(const char *readme, const char *name, struct row *rows, int cap) {
  char marker[128];
  snprintf(marker, sizeof marker, "<!-- preset: %s -->\n", name);
  const char *p = strstr(readme, marker);
  if (!p) return -1;
  p += strlen(marker);
  int n = 0, line_no = 0;
  while (*p == '|') {
    const char *end = strchr(p, '\n');
    if (!end) end = p + strlen(p);
    if (line_no++ >= 2) { /* the header and its rule */
      EXPECTF(n < cap, "%s: more than %d rows", name, cap);
      if (n >= cap) break;
      EXPECTF(parse_row(p, end, &rows[n]), "%s: row %d is not five cells: %.80s", name, n + 1, p);
      n++;
    }
    p = *end ? end + 1 : end;
  }
  return n;
}

static void check_preset(const char *readme, const char *name) {
  struct row rows[MACHINE_CFG_KEYS_MAX];
  const int n = table_of(readme, name, rows, MACHINE_CFG_KEYS_MAX);
  EXPECTF(n > 0, "configs/dram/README.md has no table for %s", name);
  if (n <= 0) return;

  char path[1024];
  snprintf(path, sizeof path, "%s/%s", DIR_DRAM, name);
  struct machine_cfg c;
  machine_cfg_defaults(&c);
  struct err e;
  memset(&e, 0, sizeof e);
  const bool ok = machine_cfg_load(&c, path, &e) && machine_cfg_check(&c, &e);
  char msg[512] = "";
  if (!ok) err_format(&e, msg, sizeof msg);
  EXPECTF(ok, "%s does not load: %s", name, msg);
  if (!ok) return;

  bool listed[MACHINE_CFG_KEYS_MAX] = {false};
  for (int j = 0; j < n; j++) {
    const struct row *r = &rows[j];
    const int i = machine_cfg_find(r->key);
    EXPECTF(i >= 0, "%s: row '%s' is no key", name, r->key);
    if (i < 0) continue;
    EXPECTF(!listed[i], "%s: key %s has two rows", name, r->key);
    listed[i] = true;
    char have[128];
    machine_cfg_value(&c, (unsigned)i, have, sizeof have);
    EXPECTF(!strcmp(have, r->value), "%s: %s is %s in the preset, %s in its table", name, r->key,
            have, r->value);
    EXPECTF(r->source[0], "%s: %s has no source", name, r->key);
    /* A figure not the source's (or a source with no figure: [ours]) says why. */
    EXPECTF(!strcmp(r->value, r->source_value) || r->note[0],
            "%s: %s is %s, its source %s says %s, and no note says why", name, r->key, r->value,
            r->source, r->source_value[0] ? r->source_value : "nothing");
  }
  /* A preset states its part's energy figures (itself or by an include): a
   * default's would be another part's. And its idle write drain, rtsim's own
   * departure from DRAMsim3, which moves the energy's background split. */
  static const char *const stated[] = {
      "dram.device_width", "dram.VDD",    "dram.IDD0",
      "dram.IDD2N",        "dram.IDD3N",  "dram.IDD4R",
      "dram.IDD4W",        "dram.IDD5AB", "dram.idle_drain_cycles"};
  for (unsigned j = 0; j < sizeof stated / sizeof stated[0]; j++) {
    const int i = machine_cfg_find(stated[j]);
    EXPECTF(i >= 0 && c.at[i].file[0], "%s does not set %s (a figure each preset states)", name,
            stated[j]);
  }
  /* Every key the preset itself sets (not one of a file it includes). */
  for (unsigned i = 0; i < machine_cfg_count(); i++)
    if (c.at[i].file[0] && !c.at[i].included)
      EXPECTF(listed[i], "%s sets %s, which its table in configs/dram/README.md lacks", name,
              machine_cfg_key(i));
}

int main(void) {
  char *readme = testing_slurp(DIR_DRAM, "README.md", NULL);
  EXPECTF(readme != NULL, "cannot read %s/README.md", DIR_DRAM);
  if (!readme) return testing_done("test_dram_presets");
  /* Every preset in the folder, in no particular order (each is checked alone). */
  DIR *dir = opendir(DIR_DRAM);
  EXPECT(dir != NULL);
  int presets = 0;
  for (struct dirent *de; dir && (de = readdir(dir));) {
    const size_t len = strlen(de->d_name);
    if (len > 5 && !strcmp(de->d_name + len - 5, ".yaml")) {
      check_preset(readme, de->d_name);
      presets++;
    }
  }
  if (dir) closedir(dir);
  EXPECTF(presets >= 3, "found %d presets in configs/dram", presets);

  /* The test itself: a value that is not its source's needs a note. */
  const char *bad = "<!-- preset: x.yaml -->\n| key | value | source | source's value | note |\n"
                    "|---|---|---|---|---|\n| `dram.tCL` | `17` | ini `CL` | `16` | |\n";
  struct row r[2];
  EXPECT(table_of(bad, "x.yaml", r, 2) == 1);
  EXPECT(!strcmp(r[0].key, "dram.tCL") && !strcmp(r[0].value, "17") &&
         !strcmp(r[0].source, "ini `CL`"));
  EXPECT(!strcmp(r[0].source_value, "16") && r[0].note[0] == '\0');
  free(readme);
  return testing_done("test_dram_presets");
}
