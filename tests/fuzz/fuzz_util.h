/* Shared by the libFuzzer targets (tests/fuzz/fuzz_*.c). The readers take
 * file names, and relative paths inside a file (a config's include, a sweep's
 * machine and scene, a scene's mesh) are resolved against the file's folder:
 * each input is written into a scratch folder laid out like the repository
 * (its configs/, scenes/ and tests/data/ reached through symbolic links), so
 * the committed corpora's paths resolve as they do in a checkout. The folder
 * is made per process at first use and removed at exit. */
#ifndef RTSIM_TESTS_FUZZ_UTIL_H
#define RTSIM_TESTS_FUZZ_UTIL_H

#include <stddef.h>
#include <stdint.h>

struct err;
struct machine_cfg;

/* The scratch folder (absolute, no trailing slash). */
const char *fuzz_dir(void);
/* Write the input to fuzz_dir()/rel (rel's folder must be one of the
 * repository's mirrored above, or the top); returns the full path, valid
 * until the next call. */
const char *fuzz_file(const char *rel, const uint8_t *data, size_t size);
/* A refusal: one message, non-empty, on one line. */
void fuzz_check_err(const struct err *e);
/* An accepted machine config: every key's value prints, and the printed text
 * (what stats files and --emit-jobs carry) reads back to the same machine. */
void fuzz_check_machine(const struct machine_cfg *c);

/* Generators and mesh import run for real only when small (at most about
 * FUZZ_GEN_TRIANGLES triangles, meshes only from the repository's test data);
 * anything larger stands in as one triangle, so a fuzz input is parsed and
 * checked like any scene file but cannot build a large scene. */
#define FUZZ_GEN_TRIANGLES 5000u

#endif
