/* Configuration files: YAML read with libyaml into a plain tree that keeps
 * every value's 1-based source position, plus typed getters that report
 * "file:line:col: error: key.path: what (got X, expected Y)". No libyaml type
 * leaves this module; the libyaml document is freed as soon as the tree exists.
 * Every read marks the key used, and every key a reader asks a map for is
 * recorded, present or not; cfg_check_keys turns unread keys into errors that
 * list what the reader asked for ("expected one of: ...").
 * Used for machine configs (sim) and scene files (renderer): it knows nothing
 * of either. */
#ifndef RTSIM_SIM_CFG_H
#define RTSIM_SIM_CFG_H

#include <stdbool.h>
#include <stdint.h>

struct err;

/* Limits on every YAML input (scenes, machine configs, any later file), so a
 * hostile file is refused within milliseconds and a few MB of memory, as a user
 * error at file:line:col (where the limit is crossed):
 * - CFG_MAX_FILE_BYTES: size of the file (or text);
 * - CFG_MAX_SCALAR_BYTES: length of one scalar, a value or a key;
 * - CFG_MAX_DEPTH: levels of lists and maps between the root (level 0) and any
 *   node, counted with aliases expanded;
 * - CFG_MAX_NODES: scalars, lists, maps and keys of the document with every
 *   alias expanded (an alias of a node counts all the nodes it stands for);
 * - CFG_MAX_ALIAS_NODES: of those, the nodes reached through aliases (the
 *   "billion laughs" file stops at the alias that crosses it).
 * An alias must follow its anchor and may not stand inside the node it names. */
#define CFG_MAX_FILE_BYTES (1u << 20)
#define CFG_MAX_SCALAR_BYTES 4096u
#define CFG_MAX_DEPTH 64u
#define CFG_MAX_NODES 100000u
#define CFG_MAX_ALIAS_NODES 10000u

enum cfg_kind { CFG_SCALAR, CFG_MAP, CFG_SEQ };

struct cfg_node {
  enum cfg_kind kind;
  int line, col;          /* position of the value, 1-based */
  char *text;             /* scalar text (the document's); NULL for maps and sequences */
  char *key;              /* key text when this node is a map value (the document's) */
  int key_line, key_col;  /* position of the key */
  struct cfg_node *items; /* map entries or sequence items (owned) */
  uint32_t count;
  bool used;   /* read by a getter (for unknown-key checks) */
  char *asked; /* a map: the keys readers asked for, ", "-separated, in the
                * order first asked (owned; NULL: none yet) */
  uint32_t asked_len;
};

struct cfg_doc {
  char file[512];
  struct cfg_node root;
  char *strings; /* every scalar's text, shared by alias copies (owned) */
};

/* Parse a YAML file (or text, named `name` in messages): the first document,
 * aliases expanded into copies that keep the anchored node's positions. An
 * empty document or a limit above passed is an error. On failure fills e and
 * returns false (d is then empty, safe to cfg_free). */
bool cfg_load_file(struct cfg_doc *d, const char *path, struct err *e);
bool cfg_load_text(struct cfg_doc *d, const char *name, const char *text, struct err *e);
void cfg_free(struct cfg_doc *d);

/* Entry `key` of map node m (marked used), or NULL when absent. Either way
 * m records that its reader asks for `key` (for cfg_check_keys). */
struct cfg_node *cfg_get(struct cfg_node *m, const char *key);
/* Entry `key` of map node m, or NULL: a look that neither marks it used nor
 * records the key as one the reader takes (a check of which keys a map has). */
struct cfg_node *cfg_peek(struct cfg_node *m, const char *key);

/* Fail with an error at node n: "<path>: <message>". Always returns false. */
bool cfg_fail(const struct cfg_doc *d, const struct cfg_node *n, const char *path, struct err *e,
              const char *fmt, ...) __attribute__((format(printf, 5, 6)));

/* Require n to be a map / sequence / scalar; else an error naming path. */
bool cfg_expect_map(const struct cfg_doc *d, const struct cfg_node *n, const char *path,
                    struct err *e);
bool cfg_expect_seq(const struct cfg_doc *d, const struct cfg_node *n, const char *path,
                    struct err *e);

/* Typed values of scalar node n, range-checked (inclusive). */
bool cfg_f64(const struct cfg_doc *d, const struct cfg_node *n, const char *path, double lo,
             double hi, double *out, struct err *e);
bool cfg_u64(const struct cfg_doc *d, const struct cfg_node *n, const char *path, uint64_t lo,
             uint64_t hi, uint64_t *out, struct err *e);
bool cfg_bool(const struct cfg_doc *d, const struct cfg_node *n, const char *path, bool *out,
              struct err *e);
/* A string of at most cap-1 bytes, copied into out. */
bool cfg_str(const struct cfg_doc *d, const struct cfg_node *n, const char *path, char *out,
             unsigned cap, struct err *e);
/* A sequence of exactly `count` numbers in [lo, hi]. */
bool cfg_f64_list(const struct cfg_doc *d, const struct cfg_node *n, const char *path,
                  unsigned count, double lo, double hi, double *out, struct err *e);
/* One of `choices` (NULL-terminated); *out = its index. */
bool cfg_enum(const struct cfg_doc *d, const struct cfg_node *n, const char *path,
              const char *const *choices, int *out, struct err *e);

/* Every key of map m must have been read; otherwise "unknown key 'k'
 * (expected one of: <the keys asked of m, in the order first asked>)" at the
 * first unread key. */
bool cfg_check_keys(const struct cfg_doc *d, const struct cfg_node *m, const char *path,
                    struct err *e);

#endif
