#include "testing.h"

#include <string.h>
#include <sys/wait.h>

int testing_failures = 0;
int testing_checks = 0;

int testing_done(const char *name) {
  printf("%s: %d checks, %d failed\n", name, testing_checks, testing_failures);
  return testing_failures ? 1 : 0;
}

int testing_run(const char *cmd, char *buf, unsigned buf_size) {
  char full[8192];
  snprintf(full, sizeof full, "%s 2>&1", cmd);
  FILE *p = popen(full, "r");
  if (!p) return -1;
  size_t n = fread(buf, 1, buf_size ? buf_size - 1 : 0, p);
  if (buf_size) buf[n] = '\0';
  char sink[4096];
  while (fread(sink, 1, sizeof sink, p) > 0) {
  }
  int st = pclose(p);
  return WIFEXITED(st) ? WEXITSTATUS(st) : -1;
}
