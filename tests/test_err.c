/* The CHECK family (sim/err.h): a failed comparison aborts and prints the
 * source line, the expression and both values; a passing one does nothing. */
#include "sim/err.h"

#include <signal.h>
#include <stdint.h>
#include <string.h>
#include <sys/wait.h>
#include <unistd.h>

#include "testing.h"

/* The checks a child runs, by number; each fails. */
static void fail_case(int k) {
  int five = 5, three = 3;
  uint64_t big = UINT64_MAX;
  long long neg = -7;
  double half = 0.5;
  const char *p = NULL;
  switch (k) {
  case 0: CHECK_LT(five, three); break;
  case 1: CHECK_EQ(big, 0u); break;
  case 2: CHECK_GE(neg, 0); break;
  case 3: CHECK_GT(half, 1.0); break;
  case 4: CHECK_NE(p, NULL); break;
  case 5: CHECK_LE(five + 1, three * 2 - 1); break;
  case 6: CHECK(five == three); break;
  }
}

/* Run fail_case(k) in a child; its stderr into buf; true if it aborted. */
static bool run_case(int k, char *buf, size_t cap) {
  int fd[2];
  if (pipe(fd) != 0) return false;
  pid_t pid = fork();
  if (pid == 0) {
    close(fd[0]);
    dup2(fd[1], 2);
    fail_case(k);
    _exit(0);
  }
  close(fd[1]);
  size_t n = 0;
  ssize_t got;
  while (n + 1 < cap && (got = read(fd[0], buf + n, cap - 1 - n)) > 0) n += (size_t)got;
  buf[n] = '\0';
  close(fd[0]);
  int st = 0;
  waitpid(pid, &st, 0);
  return WIFSIGNALED(st) && WTERMSIG(st) == SIGABRT;
}

int main(void) {
  static const struct {
    const char *want;
  } cases[] = {
      {"test_err.c:21: internal error: CHECK(five < three) failed: five = 5, three = 3\n"},
      {"internal error: CHECK(big == 0u) failed: big = 18446744073709551615, 0u = 0\n"},
      {"internal error: CHECK(neg >= 0) failed: neg = -7, 0 = 0\n"},
      {"internal error: CHECK(half > 1.0) failed: half = 0.5, 1.0 = 1\n"},
      {"internal error: CHECK(p != NULL) failed: p = "},
      {"internal error: CHECK(five + 1 <= three * 2 - 1) failed: five + 1 = 6, three * 2 - 1 = 5\n"},
      {"internal error: CHECK(five == three) failed\n"},
  };
  for (int k = 0; k < (int)(sizeof cases / sizeof cases[0]); k++) {
    char buf[1024];
    bool aborted = run_case(k, buf, sizeof buf);
    EXPECTF(aborted, "case %d did not abort: %s", k, buf);
    EXPECTF(strstr(buf, cases[k].want) != NULL, "case %d: got '%s', want '%s'", k, buf,
            cases[k].want);
  }
  /* Passing checks: no output, no abort; each operand evaluated once. */
  int calls = 0, x = 2;
  CHECK_LT(x, 3);
  CHECK_EQ(x, 2);
  CHECK_GE((calls++, x), 2);
  CHECK_NE(&x, NULL);
  EXPECT(calls == 1);

  /* A record quotes user text (a --set, a key, a cell) and stays one line:
   * control characters become escapes, in the file and in the message. */
  struct err e;
  memset(&e, 0, sizeof e);
  err_set(&e, "--set cores=4\n8", 0, 0, "key 'a\nb\r\x01\x7f\tc': bad");
  EXPECTF(!strcmp(e.file, "--set cores=4\\n8"), "file: %s", e.file);
  EXPECTF(!strcmp(e.msg, "key 'a\\nb\\r\\x01\\x7f\\tc': bad"), "msg: %s", e.msg);
  /* Cut to fit, never in the middle of an escape. */
  char many[ERR_MSG_MAX];
  memset(many, '\n', sizeof many - 1);
  many[sizeof many - 1] = '\0';
  memset(&e, 0, sizeof e);
  err_set(&e, NULL, 0, 0, "%s", many);
  EXPECTF(strlen(e.msg) == ERR_MSG_MAX - 2 && !strchr(e.msg, '\n'), "len %zu", strlen(e.msg));
  return testing_done("test_err");
}
