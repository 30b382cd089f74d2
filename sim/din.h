/* Dinero IV "din" traces (traditional format, `dineroIV -informat d`): one
 * record per line, "LABEL ADDRESS", both hexadecimal, rest of the line ignored.
 * Labels: 0 data read, 1 data write, 2 instruction fetch, 3 misc, 4 copy-back,
 * 5 invalidate (Dinero IV's d4.h access types). Dinero reads no size: every din
 * record is a 4-byte access at ADDRESS & ~3 (dinfmt.c), so the writer emits one
 * record per cache line touched: replayed in a cache with the writer's line size
 * (>= 4 bytes), the trace gives exactly the line accesses that were written. */
#ifndef RTSIM_SIM_DIN_H
#define RTSIM_SIM_DIN_H

#include <stdbool.h>
#include <stdint.h>

struct err;

enum din_label {
  DIN_LABEL_READ = 0,
  DIN_LABEL_WRITE = 1,
  DIN_LABEL_IFETCH = 2,
  DIN_LABEL_MISC = 3,
  DIN_LABEL_COPYBACK = 4,
  DIN_LABEL_INVALIDATE = 5,
  DIN_LABEL_MAX = 5
};

struct din_writer;

/* Start a trace for path: records go to a temporary beside it (outfile.h),
 * renamed to path by a successful din_writer_close. Lines are 2^lg2_line
 * bytes (2 <= lg2_line <= 20). NULL with e set (file = path) when the file cannot be created. */
struct din_writer *din_writer_open(const char *path, unsigned lg2_line, struct err *e);

/* One record at addr (label 1 if is_store else 0). */
void din_writer_record(struct din_writer *w, uint64_t addr, bool is_store);

/* One record per line touched by [addr, addr + size_bytes), size_bytes > 0: the
 * first at addr, the others at their line's first byte. */
void din_writer_access(struct din_writer *w, uint64_t addr, uint32_t size_bytes, bool is_store);

/* Records written so far. */
uint64_t din_writer_records(const struct din_writer *w);

/* Flush, close and rename to the final path. On any failure (including an
 * earlier write error) the temporary is removed and e is set. Frees w (NULL ok:
 * returns true). */
bool din_writer_close(struct din_writer *w, struct err *e);

/* Abandon the trace: close, remove the temporary, free w (NULL ok). */
void din_writer_discard(struct din_writer *w);

/* Called once per record read: label in [0, DIN_LABEL_MAX], addr as written
 * (NOTE: Dinero itself uses addr & ~3 as a 4-byte access). */
typedef void (*din_record_fn)(void *ctx, unsigned label, uint64_t addr);

/* Read a din file, calling fn for each record in order. Accepts the variations
 * Dinero's reader accepts: leading blanks, multi-digit hex labels, an optional
 * 0x on label and address, anything after the address (comments). Rejects, with
 * file:line:column, blank lines, non-hex labels or addresses, labels above 5
 * and addresses beyond 64 bits. Returns false with e set on the first error
 * (records before it have been delivered). records_out (may be NULL) gets the
 * number of records delivered. */
bool din_read_file(const char *path, din_record_fn fn, void *ctx, uint64_t *records_out,
                   struct err *e);

#endif
