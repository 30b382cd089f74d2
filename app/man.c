/* rtsim --man: the manual page, in roff, made from the help texts themselves
 * (the program's usage, then each command's --help-full), so that the page
 * and the help cannot disagree. The build runs it (cmake/man.cmake) and
 * `cmake --install` puts the page in share/man/man1. */
#include "app/app.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "sim/err.h"

/* What cmd writes on stdout for `cmd --help-full`, read back through a
 * temporary file standing in for file descriptor 1 (malloc'd; NULL on a host
 * failure). */
static char *capture_help(const struct app_command *c) {
  fflush(stdout);
  FILE *tmp = tmpfile();
  int saved = dup(1);
  if (!tmp || saved < 0 || dup2(fileno(tmp), 1) < 0) {
    if (tmp) fclose(tmp);
    if (saved >= 0) close(saved);
    return NULL;
  }
  char name[64], full[] = "--help-full";
  snprintf(name, sizeof name, "%s", c->name);
  char *argv[] = {name, full, NULL};
  int rc = c->run(2, argv);
  fflush(stdout);
  dup2(saved, 1);
  close(saved);
  long n = rc == 0 && fseek(tmp, 0, SEEK_END) == 0 ? ftell(tmp) : -1;
  char *text = n >= 0 ? xmalloc((size_t)n + 1) : NULL;
  if (text) {
    rewind(tmp);
    text[fread(text, 1, (size_t)n, tmp)] = '\0';
  }
  fclose(tmp);
  return text;
}

/* text as roff lines kept as they are (.nf): backslashes and minus signs
 * escaped, a line that starts with a control character made plain. */
static void roff_block(FILE *f, const char *text) {
  fputs(".nf\n", f);
  bool line_start = true;
  for (const char *p = text; *p; p++) {
    if (line_start && (*p == '.' || *p == '\'')) fputs("\\&", f);
    if (*p == '\\') fputs("\\e", f);
    else if (*p == '-') fputs("\\-", f);
    else fputc(*p, f);
    line_start = *p == '\n';
  }
  if (!line_start) fputc('\n', f);
  fputs(".fi\n", f);
}

int app_man(FILE *f, const char *usage, const struct app_command *cmds, unsigned n) {
  fputs(".TH RTSIM 1 \"\" \"rtsim\" \"User Commands\"\n"
        ".SH NAME\n"
        "rtsim \\- ray tracing kernels on a simulated many\\-core chip: DRAM traffic,\n"
        "cycles and latency hiding of ray scheduling policies\n"
        ".SH SYNOPSIS\n"
        ".B rtsim\n"
        ".I COMMAND\n"
        "[options]\n"
        ".SH DESCRIPTION\n",
        f);
  roff_block(f, usage);
  fputs(".SH COMMANDS\n", f);
  for (unsigned i = 0; i < n; i++) {
    char *text = capture_help(&cmds[i]);
    if (!text) {
      fprintf(stderr, "rtsim: error: --man: cannot capture 'rtsim %s --help-full'\n", cmds[i].name);
      return 1;
    }
    fputs(".SS rtsim ", f);
    for (const char *p = cmds[i].name; *p; p++)
      if (*p == '-') fputs("\\-", f);
      else fputc(*p, f);
    fputc('\n', f);
    roff_block(f, text);
    free(text);
  }
  fputs(".SH FILES\n"
        "Machine configs, DRAM presets and sweeps are in share/rtsim/configs, scenes in\n"
        "share/rtsim/scenes (the source tree's configs/ and scenes/).\n"
        ".SH SEE ALSO\n"
        "README.md and the manual in docs/ (share/doc/rtsim): the machine model, config\n"
        "keys, numbers, sweeps and outputs in full.\n",
        f);
  return fflush(f) == 0 && !ferror(f) ? 0 : 1;
}
