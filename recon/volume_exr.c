/* volume_exr.c — volumes as OpenEXR files through OpenEXR's C API
 * (libOpenEXRCore), layout in elfm_pipeline.h: W x H scanlines, one FLOAT
 * channel per z plane ("z000".."zNNN"), ZIP compression, axes and time as
 * header attributes.
 *
 * A channel per plane (rather than a tall W x (H*Nz) image) keeps every
 * plane a proper image in any EXR viewer and puts the plane index in the
 * channel name. OpenEXR's default error callback prints to stderr; ours is
 * silent and the message comes from the returned code instead.
 */
#include "elfm_pipeline.h"

#include <openexr.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static void exr_silent(exr_const_context_t ctxt, exr_result_t code, const char *msg)
{
  (void)ctxt, (void)code, (void)msg;
}

/* Plane-name width: at least 3 digits, enough for nz - 1. */
static int name_digits(int nz)
{
  int d = 3;
  for (int n = 1000; nz > n && d < 9; n *= 10) d++;
  return d;
}

/* Plane index of channel name "zNNN", or -1. */
static int plane_of(const char *name, int nz)
{
  if (!name || name[0] != 'z' || !name[1]) return -1;
  int k = 0;
  for (const char *c = name + 1; *c; c++) {
    if (*c < '0' || *c > '9' || k > 100000) return -1;
    k = k * 10 + (*c - '0');
  }
  return k < nz ? k : -1;
}

#define EXR_TRY(call, what)                                                                 \
  do {                                                                                      \
    exr_result_t r_ = (call);                                                               \
    if (r_ != EXR_ERR_SUCCESS) {                                                            \
      st = elfm_error_set(err, r_ == EXR_ERR_FILE_ACCESS ? ELFM_ERR_IO : ELFM_ERR_FORMAT,   \
                          path, -1, "%s: %s", what, exr_get_default_error_message(r_));     \
      goto done;                                                                            \
    }                                                                                       \
  } while (0)

elfm_status elfm_volume_write_exr(const elfm_volume *v, const char *path, elfm_error *err)
{
  elfm_status st = ELFM_OK;
  exr_context_t ctxt = NULL;
  exr_context_initializer_t init = EXR_DEFAULT_CONTEXT_INITIALIZER;
  init.error_handler_fn = exr_silent;
  int part = 0;
  const int digits = name_digits(v->nz);
  exr_encode_pipeline_t enc; /* see the chunk loop */
  memset(&enc, 0, sizeof enc);
  int enc_live = 0;
  EXR_TRY(exr_start_write(&ctxt, path, EXR_WRITE_FILE_DIRECTLY, &init), "create");
  EXR_TRY(exr_add_part(ctxt, "volume", EXR_STORAGE_SCANLINE, &part), "add part");
  EXR_TRY(exr_initialize_required_attr_simple(ctxt, part, v->w, v->h, EXR_COMPRESSION_ZIP),
          "header");
  for (int k = 0; k < v->nz; k++) {
    char name[16];
    snprintf(name, sizeof name, "z%0*d", digits, k);
    EXR_TRY(exr_add_channel(ctxt, part, name, EXR_PIXEL_FLOAT, EXR_PERCEPTUALLY_LINEAR, 1, 1),
            "add channel");
  }
  EXR_TRY(exr_attr_set_double(ctxt, part, "t_us", (double)v->t_us), "t_us");
  EXR_TRY(exr_attr_set_int(ctxt, part, "frame", (int32_t)v->frame), "frame");
  EXR_TRY(exr_attr_set_double(ctxt, part, "um_per_px", v->um_per_px), "um_per_px");
  EXR_TRY(exr_attr_set_double(ctxt, part, "z_min_um", v->z_min_um), "z_min_um");
  EXR_TRY(exr_attr_set_double(ctxt, part, "z_step_um", v->z_step_um), "z_step_um");
  EXR_TRY(exr_attr_set_int(ctxt, part, "nz", v->nz), "nz");
  EXR_TRY(exr_write_header(ctxt), "write header");
  int32_t lines = 1;
  EXR_TRY(exr_get_scanlines_per_chunk(ctxt, part, &lines), "chunk size");
  /* One encoder for the whole file, updated chunk by chunk: it keeps its
   * packing and compression buffers (~1 MB each at 144 x 101 floats per
   * line, 16 lines per ZIP chunk). An encoder per chunk allocated them
   * anew each time, above glibc's mmap threshold: fresh pages, faulted
   * in and unmapped, 238,000 page faults for `recon --save-volumes` on
   * 50 volumes (docs/recon.md "Volumes on huge pages, reused copies, one
   * EXR encoder per file"). */
  for (int y = 0; y < v->h; y += lines) {
    exr_chunk_info_t ci;
    EXR_TRY(exr_write_scanline_chunk_info(ctxt, part, y, &ci), "chunk info");
    exr_result_t r = EXR_ERR_SUCCESS;
    const int first = !enc_live;
    if (first) {
      EXR_TRY(exr_encoding_initialize(ctxt, part, &ci, &enc), "encoder");
      enc_live = 1;
    } else {
      r = exr_encoding_update(ctxt, part, &ci, &enc);
    }
    for (int c = 0; c < enc.channel_count && r == EXR_ERR_SUCCESS; c++) {
      int k = plane_of(enc.channels[c].channel_name, v->nz);
      if (k < 0) k = 0; /* cannot happen: we named them */
      enc.channels[c].encode_from_ptr =
          (const uint8_t *)(v->data + ((size_t)k * v->h + (size_t)ci.start_y) * v->w);
      enc.channels[c].user_pixel_stride = (int32_t)sizeof(float);
      enc.channels[c].user_line_stride = (int32_t)(sizeof(float) * (size_t)v->w);
    }
    /* the routines are chosen once, with the channels' strides set, as
     * before the encoder was kept (they do not change from chunk to chunk) */
    if (first && r == EXR_ERR_SUCCESS) r = exr_encoding_choose_default_routines(ctxt, part, &enc);
    if (r == EXR_ERR_SUCCESS) r = exr_encoding_run(ctxt, part, &enc);
    EXR_TRY(r, "encode");
  }
done:
  if (enc_live) exr_encoding_destroy(ctxt, &enc);
  if (ctxt) {
    exr_result_t r = exr_finish(&ctxt);
    if (!st && r != EXR_ERR_SUCCESS)
      st = elfm_error_set(err, ELFM_ERR_IO, path, -1, "finish: %s", exr_get_default_error_message(r));
  }
  return st;
}

elfm_status elfm_volume_read_exr(const char *path, elfm_volume **out, elfm_error *err)
{
  *out = NULL;
  elfm_status st = ELFM_OK;
  exr_context_t ctxt = NULL;
  elfm_volume *v = NULL;
  exr_decode_pipeline_t dec; /* see the chunk loop */
  memset(&dec, 0, sizeof dec);
  int dec_live = 0;
  exr_context_initializer_t init = EXR_DEFAULT_CONTEXT_INITIALIZER;
  init.error_handler_fn = exr_silent;
  EXR_TRY(exr_start_read(&ctxt, path, &init), "open");
  exr_attr_box2i_t dw;
  EXR_TRY(exr_get_data_window(ctxt, 0, &dw), "data window");
  int32_t nz = 0, frame = 0;
  double t_us = 0, um_per_px = 0, z_min = 0, z_step = 0;
  EXR_TRY(exr_attr_get_int(ctxt, 0, "nz", &nz), "attribute nz");
  EXR_TRY(exr_attr_get_int(ctxt, 0, "frame", &frame), "attribute frame");
  EXR_TRY(exr_attr_get_double(ctxt, 0, "t_us", &t_us), "attribute t_us");
  EXR_TRY(exr_attr_get_double(ctxt, 0, "um_per_px", &um_per_px), "attribute um_per_px");
  EXR_TRY(exr_attr_get_double(ctxt, 0, "z_min_um", &z_min), "attribute z_min_um");
  EXR_TRY(exr_attr_get_double(ctxt, 0, "z_step_um", &z_step), "attribute z_step_um");
  const exr_attr_chlist_t *ch = NULL;
  EXR_TRY(exr_get_channels(ctxt, 0, &ch), "channels");
  /* In 64 bits: a window from INT32_MIN to INT32_MAX would overflow int. */
  int64_t w64 = (int64_t)dw.max.x - dw.min.x + 1, h64 = (int64_t)dw.max.y - dw.min.y + 1;
  if (w64 > 65535 || h64 > 65535) {
    st = elfm_error_set(err, ELFM_ERR_RANGE, path, -1,
                        "data window %lld x %lld is larger than 65535 px on a side",
                        (long long)w64, (long long)h64);
    goto done;
  }
  int w = w64 > 0 ? (int)w64 : 0, h = h64 > 0 ? (int)h64 : 0;
  if (nz <= 0 || ch->num_channels != nz || w <= 0 || h <= 0) {
    st = elfm_error_set(err, ELFM_ERR_FORMAT, path, -1,
                        "not an EventLFM volume: %d channels for nz %d, %d x %d", ch->num_channels,
                        nz, w, h);
    goto done;
  }
  /* The data window is a claim the file makes; ZIP can pack a huge zero
   * volume into a few bytes, so the file's size does not bound it. */
  if ((size_t)w * (size_t)h * (size_t)nz > ELFM_VOLUME_MAX_VOXELS) {
    st = elfm_error_set(err, ELFM_ERR_RANGE, path, -1,
                        "data window %d x %d with %d planes exceeds the limit of %zu voxels", w,
                        h, nz, ELFM_VOLUME_MAX_VOXELS);
    goto done;
  }
  for (int c = 0; c < ch->num_channels; c++)
    if (plane_of(ch->entries[c].name.str, nz) < 0 || ch->entries[c].pixel_type != EXR_PIXEL_FLOAT ||
        ch->entries[c].x_sampling != 1 || ch->entries[c].y_sampling != 1) {
      st = elfm_error_set(err, ELFM_ERR_FORMAT, path, -1, "channel '%s' is not a float z plane",
                          ch->entries[c].name.str);
      goto done;
    }
  /* Attributes are numbers from a file: check them before they become axes
   * (and t_us an int64: beyond +-2^62 us the conversion is undefined). */
  if (!(isfinite(t_us) && fabs(t_us) < 4.0e18) || !(isfinite(um_per_px) && um_per_px > 0) ||
      !isfinite(z_min) || !(isfinite(z_step) && z_step > 0)) {
    st = elfm_error_set(err, ELFM_ERR_RANGE, path, -1,
                        "attributes out of range: t_us %g, um_per_px %g, z_min_um %g, "
                        "z_step_um %g",
                        t_us, um_per_px, z_min, z_step);
    goto done;
  }
  v = elfm_volume_create(w, h, nz, um_per_px, z_min, z_step, err);
  if (!v) {
    st = err ? err->code : ELFM_ERR_NOMEM;
    goto done;
  }
  v->t_us = (int64_t)t_us;
  v->t_start_us = v->t_end_us = v->t_us;
  v->n_events = 0;
  v->n_triggers = 0;
  v->frame = frame;
  int32_t lines = 1;
  EXR_TRY(exr_get_scanlines_per_chunk(ctxt, 0, &lines), "chunk size");
  /* one decoder for the file, updated chunk by chunk (as the writer's
   * encoder: its buffers are allocated once per file, not per chunk) */
  for (int y = dw.min.y; y <= dw.max.y; y += lines) {
    exr_chunk_info_t ci;
    EXR_TRY(exr_read_scanline_chunk_info(ctxt, 0, y, &ci), "chunk info");
    exr_result_t r;
    if (!dec_live) {
      EXR_TRY(exr_decoding_initialize(ctxt, 0, &ci, &dec), "decoder");
      dec_live = 1;
      r = EXR_ERR_SUCCESS;
    } else {
      r = exr_decoding_update(ctxt, 0, &ci, &dec);
    }
    for (int c = 0; c < dec.channel_count && r == EXR_ERR_SUCCESS; c++) {
      int k = plane_of(dec.channels[c].channel_name, nz);
      dec.channels[c].decode_to_ptr =
          (uint8_t *)(v->data + ((size_t)k * h + (size_t)(ci.start_y - dw.min.y)) * w);
      dec.channels[c].user_pixel_stride = (int32_t)sizeof(float);
      dec.channels[c].user_line_stride = (int32_t)(sizeof(float) * (size_t)w);
    }
    /* the routines depend on the pointers and strides set just above */
    if (r == EXR_ERR_SUCCESS) r = exr_decoding_choose_default_routines(ctxt, 0, &dec);
    if (r == EXR_ERR_SUCCESS) r = exr_decoding_run(ctxt, 0, &dec);
    EXR_TRY(r, "decode");
  }
done:
  if (dec_live) exr_decoding_destroy(ctxt, &dec);
  if (ctxt) exr_finish(&ctxt);
  if (st) elfm_volume_free(v);
  else *out = v;
  return st;
}
