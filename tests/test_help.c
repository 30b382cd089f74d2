/* The help a person reads (#40): `rtsim --help` and every command's --help
 * fit a screen (40 lines of 100 columns) with an example each; the commands
 * that take --policy list every policy of renderer/policy's table, with what
 * it does; --help-full starts with --help; the manual page holds every
 * command; and every example runs as printed (outputs under a temporary
 * directory in place of build/). */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "renderer/policy/policy.h"
#include "testing.h"

#define SCREEN_LINES 40
#define SCREEN_COLUMNS 100

static char out[1 << 17];

/* The commands `rtsim --help` lists: its lines "  name ..." after
 * "commands:", up to the blank line. */
static unsigned command_names(const char *help, char names[][32], unsigned cap) {
  const char *p = strstr(help, "commands:\n");
  unsigned n = 0;
  for (p = p ? strchr(p, '\n') + 1 : ""; *p && *p != '\n' && n < cap; p = strchr(p, '\n') + 1) {
    if (p[0] == ' ' && p[1] == ' ' && p[2] >= 'a' && p[2] <= 'z')
      snprintf(names[n++], 32, "%.*s", (int)strcspn(p + 2, " \n"), p + 2);
    if (!strchr(p, '\n')) break;
  }
  return n;
}

/* text fits a screen: at most SCREEN_LINES lines of SCREEN_COLUMNS. */
static void check_screen(const char *what, const char *text) {
  unsigned lines = 0, widest = 0;
  for (const char *p = text; *p;) {
    size_t w = strcspn(p, "\n");
    if (w > widest) widest = (unsigned)w;
    lines++;
    p += w + (p[w] == '\n');
  }
  EXPECTF(lines <= SCREEN_LINES && widest <= SCREEN_COLUMNS,
          "%s: %u lines, %u columns (a screen: %d x %d)", what, lines, widest, SCREEN_LINES,
          SCREEN_COLUMNS);
}

/* The example of a help: the command lines under "example", each with its
 * continuation lines joined (after a backslash, dropped, or a pipe), into
 * cmds (one a line). */
static void example_of(const char *help, char *cmds, size_t cap) {
  cmds[0] = '\0';
  const char *p = strstr(help, "\nexample");
  if (!p) return;
  p = strchr(p + 1, '\n') + 1;
  size_t n = 0;
  while (!strncmp(p, "  ", 2)) {
    size_t w = strcspn(p, "\n");
    const char *text = p + strspn(p, " ");
    size_t tw = w - (size_t)(text - p);
    const bool more = tw > 0 && text[tw - 1] == '\\', pipe = tw > 0 && text[tw - 1] == '|';
    n += (size_t)snprintf(cmds + n, cap - n, "%.*s%s", (int)(tw - more), text,
                          more   ? ""
                          : pipe ? " "
                                 : "\n");
    p += w + (p[w] == '\n');
  }
}

/* Run an example's lines from the source tree, with the program for "rtsim"
 * and a fresh directory for "build/". */
static void run_example(const char *cmd, const char *cmds) {
  char script[8192] = "", tmp[512];
  snprintf(tmp, sizeof tmp, "%s/help-example-%s", RTSIM_TMP, cmd);
  size_t n = (size_t)snprintf(script, sizeof script, "(set -e; rm -rf %s; mkdir -p %s; cd %s; ",
                              tmp, tmp, RTSIM_SOURCE_DIR);
  for (const char *p = cmds; *p && n < sizeof script;) {
    size_t w = strcspn(p, "\n");
    for (size_t i = 0; i < w && n + 600 < sizeof script; i++) {
      if (!strncmp(p + i, "rtsim ", 6) && (i == 0 || p[i - 1] == ' ')) {
        n += (size_t)snprintf(script + n, sizeof script - n, "%s ", RTSIM_BINARY);
        i += 5;
      } else if (!strncmp(p + i, "build/", 6) && (i == 0 || p[i - 1] == ' ')) {
        n += (size_t)snprintf(script + n, sizeof script - n, "%s/", tmp);
        i += 5;
      } else {
        script[n++] = p[i];
      }
    }
    n += (size_t)snprintf(script + n, sizeof script - n, " >/dev/null; ");
    p += w + (p[w] == '\n');
  }
  /* One group, so that testing_run's 2>&1 takes every line's stderr. */
  if (n + 2 < sizeof script) strcat(script, ")");
  int rc = testing_run(script, out, sizeof out);
  EXPECTF(rc == 0, "rtsim %s --help's example failed (%d): %s\n%s", cmd, rc, cmds, out);
}

/* Examples too long for the suite: the example sweep has 120 points
 * (tests/test_sweep.c runs sweeps and merges). */
static const char *const NOT_RUN[] = {"sweep", "merge"};

static bool listed(const char *const *list, size_t n, const char *name) {
  for (size_t i = 0; i < n; i++)
    if (!strcmp(list[i], name)) return true;
  return false;
}

/* The commands taking --policy list every policy of the table and what it
 * does. */
static void check_policies(const char *cmd, const char *help) {
  static const char *const TAKE[] = {"render", "traffic", "trace", "run", "bench"};
  if (!listed(TAKE, sizeof TAKE / sizeof TAKE[0], cmd)) return;
  for (int k = 0; k < POLICY_COUNT; k++) {
    char line[256];
    snprintf(line, sizeof line, "%-10s %s\n", policy_name((enum policy_kind)k),
             policy_about((enum policy_kind)k));
    EXPECTF(strstr(help, line), "rtsim %s --help does not list policy %s ('%s')", cmd,
            policy_name((enum policy_kind)k), line);
  }
}

int main(void) {
  char top[1 << 14], names[32][32], help[1 << 14];
  int rc = testing_runf(top, sizeof top, "%s --help", RTSIM_BINARY);
  EXPECTF(rc == 0, "rtsim --help: %d %s", rc, top);
  check_screen("rtsim --help", top);
  EXPECTF(strstr(top, "\nexample"), "rtsim --help has no example: %s", top);
  unsigned n = command_names(top, names, 32);
  EXPECTF(n >= 11, "rtsim --help lists %u commands", n);
  rc = testing_runf(out, sizeof out, "%s --man", RTSIM_BINARY);
  EXPECTF(rc == 0 && !strncmp(out, ".TH RTSIM 1 ", 12), "rtsim --man: %d %.60s", rc, out);
  static char man[1 << 17];
  snprintf(man, sizeof man, "%s", out);
  for (unsigned i = 0; i < n; i++) {
    const char *cmd = names[i];
    rc = testing_runf(help, sizeof help, "%s %s --help 2>&1", RTSIM_BINARY, cmd);
    EXPECTF(rc == 0, "rtsim %s --help: %d %s", cmd, rc, help);
    /* The section's title, its minus signs escaped as roff wants them. */
    char ss[96] = ".SS rtsim ";
    for (const char *c = cmd; *c && strlen(ss) + 3 < sizeof ss; c++)
      strcat(ss, *c == '-' ? "\\-" : (char[]){*c, '\0'});
    strcat(ss, "\n");
    EXPECTF(strstr(man, ss), "the manual page has no section '%s'", ss);
    rc = testing_runf(out, sizeof out, "%s %s --help-full 2>&1", RTSIM_BINARY, cmd);
    EXPECTF(rc == 0 && !strncmp(out, help, strlen(help)),
            "rtsim %s --help-full does not start with --help", cmd);
    check_policies(cmd, help);
    char what[64];
    snprintf(what, sizeof what, "rtsim %.31s --help", cmd);
    check_screen(what, help);
    char cmds[2048];
    example_of(help, cmds, sizeof cmds);
    EXPECTF(cmds[0], "rtsim %s --help has no example", cmd);
    if (cmds[0] && !listed(NOT_RUN, sizeof NOT_RUN / sizeof NOT_RUN[0], cmd))
      run_example(cmd, cmds);
  }
  char cmds[2048];
  example_of(top, cmds, sizeof cmds);
  run_example("top", cmds);
  return testing_done("test_help");
}
