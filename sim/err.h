/* User-error records: a failure in user input (config, scene, mesh, command
 * line) travels up as a value carrying file, line, column and one message.
 * Only main prints it, once, and exits with code 2. */
#ifndef RTSIM_SIM_ERR_H
#define RTSIM_SIM_ERR_H

#include <stdbool.h>

#define ERR_FILE_MAX 512
#define ERR_MSG_MAX 1024

struct err {
  bool set;
  char file[ERR_FILE_MAX]; /* "" when the error has no file */
  int line, col;           /* 1-based; 0 when unknown */
  char msg[ERR_MSG_MAX];
};

/* Record an error (the first one wins; later calls are ignored so the root
 * cause is what the user sees). file may be NULL; line/col 0 = unknown.
 * Always returns false so callers can write `return err_set(...)`. */
bool err_set(struct err *e, const char *file, int line, int col, const char *fmt, ...)
    __attribute__((format(printf, 5, 6)));

/* Format as "file:line:col: error: msg" (parts omitted when unknown). */
void err_format(const struct err *e, char *buf, unsigned buf_size);

/* Fatal programmer or allocation error: prints and aborts. Never for user input. */
#define CHECK(cond)                                                                     \
  do {                                                                                  \
    if (!(cond)) err_check_failed(__FILE__, __LINE__, #cond);                           \
  } while (0)
_Noreturn void err_check_failed(const char *file, int line, const char *expr);

/* malloc/calloc/realloc that abort with a clear message on exhaustion. */
void *xmalloc(unsigned long long size);
void *xcalloc(unsigned long long n, unsigned long long size);
void *xrealloc(void *p, unsigned long long size);

#endif
