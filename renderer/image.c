/* Float images with named channels and their EXR files, through OpenEXR's C
 * API (OpenEXRCore). Writes go to a temporary (sim/outfile.h) renamed only
 * when the library reports the file complete. The library's error messages are caught
 * by a handler that stores the first one per context, so the user sees one
 * line (ours) carrying the root cause, and nothing is printed to stderr. */
#include "renderer/image.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <openexr.h>

#include "sim/err.h"
#include "sim/outfile.h"

#define IMAGE_EXR_MSG_MAX 512

/* Where a context's error handler leaves the library's first message. */
struct image_exr_msg {
  char text[IMAGE_EXR_MSG_MAX];
};

void image_init(struct image *im, uint32_t width, uint32_t height, uint32_t channel_count,
                const char *const *names) {
  CHECK_LE(channel_count, IMAGE_MAX_CHANNELS);
  memset(im, 0, sizeof *im);
  im->width = width;
  im->height = height;
  im->channel_count = channel_count;
  unsigned long long pixels = (unsigned long long)width * height;
  for (uint32_t c = 0; c < channel_count; c++) {
    CHECK_LT(strlen(names[c]), IMAGE_NAME_MAX);
    snprintf(im->names[c], IMAGE_NAME_MAX, "%s", names[c]);
    im->planes[c] = xcalloc(pixels, sizeof(float));
  }
}

void image_fini(struct image *im) {
  if (!im) return;
  for (uint32_t c = 0; c < IMAGE_MAX_CHANNELS; c++) free(im->planes[c]);
  memset(im, 0, sizeof *im);
}

int image_channel(const struct image *im, const char *name) {
  for (uint32_t c = 0; c < im->channel_count; c++)
    if (strcmp(im->names[c], name) == 0) return (int)c;
  return -1;
}

/* Keep the first message: later ones are usually consequences of it. The
 * context may be NULL for argument errors; then there is nowhere to store. */
static void image_exr_on_error(exr_const_context_t ctxt, exr_result_t code, const char *msg) {
  (void)code;
  void *ud = NULL;
  if (!ctxt || exr_get_user_data(ctxt, &ud) != EXR_ERR_SUCCESS || !ud) return;
  struct image_exr_msg *m = ud;
  if (!m->text[0]) snprintf(m->text, sizeof m->text, "%s", msg ? msg : "");
}

static exr_context_initializer_t image_exr_init(struct image_exr_msg *m) {
  exr_context_initializer_t init = EXR_DEFAULT_CONTEXT_INITIALIZER;
  init.error_handler_fn = image_exr_on_error;
  init.user_data = m;
  return init;
}

/* The library's own message if it gave one, else the generic text for rv. */
static const char *image_exr_why(const struct image_exr_msg *m, exr_result_t rv) {
  return m->text[0] ? m->text : exr_get_default_error_message(rv);
}

/* Point the pipeline's channels (sorted by name in the file, so matched by
 * name, not position) at image row `row` of the float planes. */
static bool image_bind_channels(const struct image *im, exr_coding_channel_info_t *chans, int count,
                                int32_t row, bool decode) {
  for (int k = 0; k < count; k++) {
    int c = image_channel(im, chans[k].channel_name);
    if (c < 0) return false;
    uint8_t *p = (uint8_t *)(im->planes[c] + (size_t)row * im->width);
    chans[k].user_bytes_per_element = (int16_t)sizeof(float);
    chans[k].user_data_type = (uint16_t)EXR_PIXEL_FLOAT;
    chans[k].user_pixel_stride = (int32_t)sizeof(float);
    chans[k].user_line_stride = (int32_t)(sizeof(float) * im->width);
    if (decode) chans[k].decode_to_ptr = p;
    else chans[k].encode_from_ptr = p;
  }
  return true;
}

bool image_write_exr_to(const struct image *im, struct outfile *out, bool half, struct err *e) {
  const char *path = out->path;
  struct image_exr_msg msg = {{0}};
  exr_context_initializer_t init = image_exr_init(&msg);
  exr_context_t ctx = NULL;
  exr_encode_pipeline_t enc = EXR_ENCODE_PIPELINE_INITIALIZER;
  bool enc_live = false, ok = false;
  exr_result_t rv = EXR_ERR_SUCCESS;
  const char *stage = "";
  int part = 0;
  int32_t lines = 0;

  if (im->width == 0 || im->height == 0 || im->channel_count == 0 || im->width > INT32_MAX ||
      im->height > INT32_MAX) {
    err_set(e, path, 0, 0, "cannot write EXR: empty image (%ux%u, %u channels)", im->width,
            im->height, im->channel_count);
    goto done;
  }

  stage = "cannot create file";
  rv = exr_start_write(&ctx, out->tmp, EXR_WRITE_FILE_DIRECTLY, &init);
  if (rv != EXR_ERR_SUCCESS) goto fail;

  stage = "cannot define header";
  rv = exr_add_part(ctx, NULL, EXR_STORAGE_SCANLINE, &part);
  if (rv == EXR_ERR_SUCCESS)
    rv = exr_initialize_required_attr_simple(ctx, part, (int32_t)im->width, (int32_t)im->height,
                                             EXR_COMPRESSION_ZIP);
  for (uint32_t c = 0; rv == EXR_ERR_SUCCESS && c < im->channel_count; c++)
    rv = exr_add_channel(ctx, part, im->names[c], half ? EXR_PIXEL_HALF : EXR_PIXEL_FLOAT,
                         EXR_PERCEPTUALLY_LINEAR, 1, 1);
  if (rv == EXR_ERR_SUCCESS) rv = exr_write_header(ctx);
  if (rv != EXR_ERR_SUCCESS) goto fail;

  stage = "cannot write pixels";
  rv = exr_get_scanlines_per_chunk(ctx, part, &lines);
  if (rv != EXR_ERR_SUCCESS) goto fail;
  for (int32_t y = 0; y < (int32_t)im->height; y += lines) {
    exr_chunk_info_t ci;
    rv = exr_write_scanline_chunk_info(ctx, part, y, &ci);
    if (rv != EXR_ERR_SUCCESS) goto fail;
    rv = enc_live ? exr_encoding_update(ctx, part, &ci, &enc)
                  : exr_encoding_initialize(ctx, part, &ci, &enc);
    if (rv != EXR_ERR_SUCCESS) goto fail;
    bool first = !enc_live;
    enc_live = true;
    CHECK(image_bind_channels(im, enc.channels, enc.channel_count, ci.start_y, false));
    if (first) {
      rv = exr_encoding_choose_default_routines(ctx, part, &enc);
      if (rv != EXR_ERR_SUCCESS) goto fail;
    }
    rv = exr_encoding_run(ctx, part, &enc);
    if (rv != EXR_ERR_SUCCESS) goto fail;
  }
  exr_encoding_destroy(ctx, &enc);
  enc_live = false;

  /* exr_finish writes the chunk offset table: the file is complete only if
   * it succeeds. */
  stage = "cannot finish file";
  rv = exr_finish(&ctx);
  if (rv != EXR_ERR_SUCCESS) goto fail;
  ok = true;
  goto done;

fail:
  err_set(e, path, 0, 0, "cannot write EXR: %s: %s", stage, image_exr_why(&msg, rv));
done:
  if (enc_live) exr_encoding_destroy(ctx, &enc);
  if (ctx) exr_finish(&ctx);
  return ok;
}

bool image_write_exr(const struct image *im, const char *path, bool half, struct err *e) {
  struct outfile out = {0};
  bool ok = outfile_open_named(&out, path, "EXR", e) && image_write_exr_to(im, &out, half, e) &&
            outfile_commit(&out, e);
  outfile_abort(&out);
  return ok;
}

bool image_read_exr(struct image *im, const char *path, struct err *e) {
  struct image_exr_msg msg = {{0}};
  exr_context_initializer_t init = image_exr_init(&msg);
  exr_context_t ctx = NULL;
  exr_decode_pipeline_t dec = EXR_DECODE_PIPELINE_INITIALIZER;
  bool dec_live = false, ok = false;
  exr_result_t rv;
  exr_storage_t storage = EXR_STORAGE_LAST_TYPE;
  exr_attr_box2i_t dw;
  const exr_attr_chlist_t *chl = NULL;
  const char *names[IMAGE_MAX_CHANNELS];
  int64_t w, h;
  int32_t lines = 0;

  memset(im, 0, sizeof *im);
  init.flags |= EXR_CONTEXT_FLAG_DISABLE_CHUNK_RECONSTRUCTION;
  rv = exr_start_read(&ctx, path, &init);
  if (rv != EXR_ERR_SUCCESS) {
    err_set(e, path, 0, 0, "cannot read EXR: %s", image_exr_why(&msg, rv));
    goto done;
  }

  rv = exr_get_storage(ctx, 0, &storage);
  if (rv == EXR_ERR_SUCCESS) rv = exr_get_data_window(ctx, 0, &dw);
  if (rv == EXR_ERR_SUCCESS) rv = exr_get_channels(ctx, 0, &chl);
  if (rv != EXR_ERR_SUCCESS) {
    err_set(e, path, 0, 0, "cannot read EXR header: %s", image_exr_why(&msg, rv));
    goto done;
  }
  if (storage != EXR_STORAGE_SCANLINE) {
    err_set(e, path, 0, 0, "unsupported EXR layout (got %s, expected scanline)",
            storage == EXR_STORAGE_TILED           ? "tiled"
            : storage == EXR_STORAGE_DEEP_SCANLINE ? "deep scanline"
                                                   : "deep tiled");
    goto done;
  }
  w = (int64_t)dw.max.x - dw.min.x + 1;
  h = (int64_t)dw.max.y - dw.min.y + 1;
  if (w <= 0 || h <= 0) {
    err_set(e, path, 0, 0, "EXR has an empty data window");
    goto done;
  }
  if (chl->num_channels < 1 || chl->num_channels > IMAGE_MAX_CHANNELS) {
    err_set(e, path, 0, 0, "unsupported EXR channel count (got %d, expected 1..%d)",
            chl->num_channels, IMAGE_MAX_CHANNELS);
    goto done;
  }
  for (int c = 0; c < chl->num_channels; c++) {
    const exr_attr_chlist_entry_t *ch = &chl->entries[c];
    names[c] = ch->name.str;
    if (ch->pixel_type != EXR_PIXEL_HALF && ch->pixel_type != EXR_PIXEL_FLOAT) {
      err_set(e, path, 0, 0,
              "EXR channel '%s': unsupported pixel type (got uint, expected "
              "half or float)",
              ch->name.str);
      goto done;
    }
    if (ch->x_sampling != 1 || ch->y_sampling != 1) {
      err_set(e, path, 0, 0, "EXR channel '%s': subsampled channels are not supported",
              ch->name.str);
      goto done;
    }
    if (strlen(ch->name.str) >= IMAGE_NAME_MAX) {
      err_set(e, path, 0, 0, "EXR channel name too long (got %zu chars, max %d): %s",
              strlen(ch->name.str), IMAGE_NAME_MAX - 1, ch->name.str);
      goto done;
    }
  }
  image_init(im, (uint32_t)w, (uint32_t)h, (uint32_t)chl->num_channels, names);

  rv = exr_get_scanlines_per_chunk(ctx, 0, &lines);
  for (int64_t y = dw.min.y; rv == EXR_ERR_SUCCESS && y <= dw.max.y; y += lines) {
    exr_chunk_info_t ci;
    rv = exr_read_scanline_chunk_info(ctx, 0, (int)y, &ci);
    if (rv != EXR_ERR_SUCCESS) break;
    rv = dec_live ? exr_decoding_update(ctx, 0, &ci, &dec)
                  : exr_decoding_initialize(ctx, 0, &ci, &dec);
    if (rv != EXR_ERR_SUCCESS) break;
    bool first = !dec_live;
    dec_live = true;
    CHECK(image_bind_channels(im, dec.channels, dec.channel_count, ci.start_y - dw.min.y, true));
    if (first) {
      rv = exr_decoding_choose_default_routines(ctx, 0, &dec);
      if (rv != EXR_ERR_SUCCESS) break;
    }
    rv = exr_decoding_run(ctx, 0, &dec);
  }
  if (rv != EXR_ERR_SUCCESS) {
    err_set(e, path, 0, 0, "cannot read EXR pixels: %s", image_exr_why(&msg, rv));
    goto done;
  }
  ok = true;

done:
  if (dec_live) exr_decoding_destroy(ctx, &dec);
  if (ctx) exr_finish(&ctx);
  if (!ok) image_fini(im);
  return ok;
}
