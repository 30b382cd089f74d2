/* User-error records: a failure in user input (config, scene, mesh, command
 * line) travels up as a value carrying file, line, column and one message.
 * Only main prints it, once, and exits with code 2. */
#ifndef RTSIM_SIM_ERR_H
#define RTSIM_SIM_ERR_H

#include <stdbool.h>
#include <stddef.h>
#include <stdio.h>

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

/* Copy s into out (cap bytes, cut short to fit) with its control characters
 * written as escapes (\n, \r, \t, \xNN), so that a message quoting user
 * text stays one line. err_set does it to every file name and message. */
void err_escape(char *out, size_t cap, const char *s);

/* Format as "file:line:col: error: msg" (parts omitted when unknown). */
void err_format(const struct err *e, char *buf, unsigned buf_size);

/* Fatal programmer or allocation error: prints and aborts. Never for user input. */
#define CHECK(cond)                                                                                \
  do {                                                                                             \
    if (!(cond)) err_check_failed(__FILE__, __LINE__, #cond);                                      \
  } while (0)
_Noreturn void err_check_failed(const char *file, int line, const char *expr);

/* CHECK(a OP b) that also prints both values: "file:line: internal error:
 * CHECK(a < b) failed: a = 5, b = 3". The test is CHECK's, (a) OP (b) with C's
 * conversions and warnings, and costs the same. Integers print as integers,
 * floating values as %.17Lg, pointers as %p. NOTE: a and b are evaluated
 * again to print them, so they must have no side effects (use CHECK for
 * `fclose(f) == 0`); holding them in temporaries would need __typeof__ and
 * would turn `unsigned > 0` into a signed/unsigned comparison warning. */
#define CHECK_EQ(a, b) ERR_CHECK_OP_(a, ==, b, #a, #b)
#define CHECK_NE(a, b) ERR_CHECK_OP_(a, !=, b, #a, #b)
#define CHECK_LT(a, b) ERR_CHECK_OP_(a, <, b, #a, #b)
#define CHECK_LE(a, b) ERR_CHECK_OP_(a, <=, b, #a, #b)
#define CHECK_GT(a, b) ERR_CHECK_OP_(a, >, b, #a, #b)
#define CHECK_GE(a, b) ERR_CHECK_OP_(a, >=, b, #a, #b)

/* The operands' text is taken before expansion, so NULL prints as NULL. */
#define ERR_CHECK_OP_(a, op, b, a_text, b_text)                                                    \
  do {                                                                                             \
    if (!((a)op(b)))                                                                               \
      err_check_op_failed(__FILE__, __LINE__, a_text, #op, b_text, ERR_VALUE_(a), ERR_VALUE_(b));  \
  } while (0)

/* One value of a failed CHECK_*, for printing. */
struct err_value {
  enum { ERR_VALUE_SIGNED, ERR_VALUE_UNSIGNED, ERR_VALUE_FLOAT, ERR_VALUE_POINTER } kind;
  long long i;
  unsigned long long u;
  long double f;
  const volatile void *p;
};
static inline struct err_value err_value_signed(long long v) {
  struct err_value x = {ERR_VALUE_SIGNED, v, 0, 0, 0};
  return x;
}
static inline struct err_value err_value_unsigned(unsigned long long v) {
  struct err_value x = {ERR_VALUE_UNSIGNED, 0, v, 0, 0};
  return x;
}
static inline struct err_value err_value_float(long double v) {
  struct err_value x = {ERR_VALUE_FLOAT, 0, 0, v, 0};
  return x;
}
static inline struct err_value err_value_pointer(const volatile void *v) {
  struct err_value x = {ERR_VALUE_POINTER, 0, 0, 0, v};
  return x;
}
#define ERR_VALUE_(x)                                                                              \
  _Generic((x), _Bool                                                                              \
           : err_value_unsigned, char                                                              \
           : err_value_signed, signed char                                                         \
           : err_value_signed, short                                                               \
           : err_value_signed, int                                                                 \
           : err_value_signed, long                                                                \
           : err_value_signed, long long                                                           \
           : err_value_signed, unsigned char                                                       \
           : err_value_unsigned, unsigned short                                                    \
           : err_value_unsigned, unsigned                                                          \
           : err_value_unsigned, unsigned long                                                     \
           : err_value_unsigned, unsigned long long                                                \
           : err_value_unsigned, float                                                             \
           : err_value_float, double                                                               \
           : err_value_float, long double                                                          \
           : err_value_float, default                                                              \
           : err_value_pointer)(x)
_Noreturn void err_check_op_failed(const char *file, int line, const char *a, const char *op,
                                   const char *b, struct err_value va, struct err_value vb);

/* Open a user's input file for reading (binary), refusing anything but a
 * regular file before it is opened: a named pipe would block forever, a
 * device would never end or act on being opened. stat first, then open with
 * O_NONBLOCK (so a file swapped for a pipe in between cannot block) and fstat
 * again. On failure returns NULL and sets *why to a reason for a message:
 * the system's ("No such file or directory") or "not a regular file (a named
 * pipe)". */
FILE *err_fopen_regular(const char *path, const char **why);
/* The same check without opening, for a reader that opens the file by name
 * itself (a library): NULL when path is a regular file, else the reason. */
const char *err_not_regular(const char *path);

/* malloc/calloc/realloc that abort with a clear message on exhaustion. */
void *xmalloc(unsigned long long size);
void *xcalloc(unsigned long long n, unsigned long long size);
void *xrealloc(void *p, unsigned long long size);
/* Zeroed memory at a multiple of align (a power of two), freed by free. */
void *xcalloc_aligned(unsigned long long align, unsigned long long size);

#endif
