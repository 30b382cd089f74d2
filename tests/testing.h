/* Minimal test harness: each test program counts failures and returns them. */
#ifndef RTSIM_TESTS_TESTING_H
#define RTSIM_TESTS_TESTING_H

#include <stdbool.h>
#include <stdint.h>
#include <stdio.h>

extern int testing_failures;
extern int testing_checks;

#define EXPECT(cond)                                                                               \
  do {                                                                                             \
    testing_checks++;                                                                              \
    if (!(cond)) {                                                                                 \
      testing_failures++;                                                                          \
      fprintf(stderr, "%s:%d: FAILED: %s\n", __FILE__, __LINE__, #cond);                           \
    }                                                                                              \
  } while (0)

#define EXPECTF(cond, ...)                                                                         \
  do {                                                                                             \
    testing_checks++;                                                                              \
    if (!(cond)) {                                                                                 \
      testing_failures++;                                                                          \
      fprintf(stderr, "%s:%d: FAILED: %s: ", __FILE__, __LINE__, #cond);                           \
      fprintf(stderr, __VA_ARGS__);                                                                \
      fputc('\n', stderr);                                                                         \
    }                                                                                              \
  } while (0)

/* Print a summary line and return the failure count (use as main's return). */
int testing_done(const char *name);

struct scene;
struct kd_tree;
/* Load a scene file and build its k-d tree with default parameters; on
 * failure print the error and return 0. */
int testing_load_world(struct scene *s, struct kd_tree *kd, const char *path);
/* scenes/small/NAME.yaml and its k-d tree; 0, with a failed check, when it
 * does not load. */
int testing_load_small(struct scene *s, struct kd_tree *kd, const char *name);

struct policy_setup;
struct shade_ctx;
struct framebuffer;
/* A policy setup of the world (s, kd): the default layout, sc and fb
 * (borrowed), no tested set, no progress. */
void testing_policy_setup(struct policy_setup *ps, const struct scene *s, const struct kd_tree *kd,
                          const struct shade_ctx *sc, struct framebuffer *fb);

struct ray;
/* A ray with origin o, direction d, extent (tmin, tmax), no ignored
 * primitive and no pending hit. */
struct ray testing_make_ray(float ox, float oy, float oz, float dx, float dy, float dz, float tmin,
                            float tmax);

/* The dynamic policy's queue slots as its accesses show them, in issue order:
 * a slot is stored before it is loaded, loaded once per store, and never
 * stored over while it holds a ray. Zero-initialise; testing_slots_fini. */
struct testing_slots {
  uint8_t *pending; /* per slot: stored and not yet loaded */
  uint64_t n, stores, loads, bad;
};
/* A store (store true) or load of slot k; one out of order counts in bad. */
void testing_slots_access(struct testing_slots *t, uint64_t k, bool store);
/* Slots still holding a ray: stored and never loaded. */
uint64_t testing_slots_left(const struct testing_slots *t);
void testing_slots_fini(struct testing_slots *t);

/* Temporaries of sim/outfile.h left beside path (".<name>.*.tmp" in its
 * directory): 0 when none, or when the directory does not exist. */
unsigned testing_temps_of(const char *path);

/* Run a shell command, capture its stderr+stdout into buf; return exit code
 * (or -1 if it did not exit normally). */
int testing_run(const char *cmd, char *buf, unsigned buf_size);
/* testing_run of a command made by printf. */
int testing_runf(char *buf, unsigned buf_size, const char *fmt, ...)
    __attribute__((format(printf, 3, 4)));

/* Write path with printf's text (a check fails, and false, if it cannot). */
bool testing_writef(const char *path, const char *fmt, ...) __attribute__((format(printf, 2, 3)));
/* Write text to path as it is (the same checks). */
bool testing_write(const char *path, const char *text);

struct stats_table;
/* Number `name` of a stats table (a count as a double); NAN if absent. */
double testing_stat(const struct stats_table *t, const char *name);

/* The whole of dir/name (caller frees; *len its length if len), or NULL. */
char *testing_slurp(const char *dir, const char *name, size_t *len);
/* A number member of dir/stats.json ("cycles"); NAN when absent. */
double testing_json_num(const char *dir, const char *name);
/* A two-line CSV file (a header and one row: stats.csv, rtsim dram-replay's
 * output) as names and values, RFC 4180 quotes undone. */
#define TESTING_CSV_COLS 512
struct testing_csv {
  char name[TESTING_CSV_COLS][128];
  char value[TESTING_CSV_COLS][128];
  int n;
};
bool testing_csv_load(const char *path, struct testing_csv *c);
/* Column `name`'s value; a failed expectation (and "") when there is none. */
const char *testing_csv_get(const struct testing_csv *c, const char *name);
double testing_csv_num(const struct testing_csv *c, const char *name);
/* The RGB planes of two EXR files are equal, bit for bit. */
bool testing_same_rgb(const char *a, const char *b);

/* A DDR4-2400 x8 part's banked parameters (1200 MHz, 1 channel, 1 rank,
 * 4 x 4 banks, open page, queues of 32), refresh off: the DRAM tests' part. */
struct dram_banked_params testing_ddr4_params(void);
/* A DRAM of level `model` (enum dram_model): latency 40, 8 bytes a cycle, a queue of `depth`,
 * 1200 MHz, the banked part above. */
struct dram_params testing_dram_params(unsigned model, uint32_t depth);

#endif
