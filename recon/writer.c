/* writer.c — event writers: buffered output, argument checks, and the
 * dispatch to the EVT 3.0 (writer_evt3.c) and CSV (writer_csv.c) encoders. */
#include <errno.h>
#include <stdlib.h>
#include <string.h>

#include "events_internal.h"

/* 1 MiB output buffer: one fwrite per ~500 k EVT3 words. */
#define ELFM_WRITE_BUF_BYTES ((size_t)1 << 20)

elfm_status elfm_writer_flush(elfm_writer *w, elfm_error *err)
{
  if (w->len && fwrite(w->buf, 1, w->len, w->f) != w->len) {
    w->failed = 1;
    return elfm_error_set(err, ELFM_ERR_IO, w->path, w->bytes_written, "write failed: %s",
                          strerror(errno));
  }
  w->bytes_written += (int64_t)w->len;
  w->len = 0;
  return ELFM_OK;
}

elfm_status elfm_writer_reserve(elfm_writer *w, size_t need, elfm_error *err)
{
  if (w->len + need <= w->cap) return ELFM_OK;
  return elfm_writer_flush(w, err);
}

elfm_status elfm_writer_open(const char *path, elfm_event_format fmt, int width, int height,
                             elfm_writer **out, elfm_error *err)
{
  if (!out) return elfm_error_set(err, ELFM_ERR_INVALID, path, -1, "no output pointer");
  *out = NULL;
  if (!path) return elfm_error_set(err, ELFM_ERR_INVALID, NULL, -1, "no path");
  if (fmt != ELFM_FMT_EVT3 && fmt != ELFM_FMT_CSV)
    return elfm_error_set(err, ELFM_ERR_UNSUPPORTED, path, -1,
                          "cannot write %s files (writers: evt3, csv)", elfm_format_name(fmt));
  /* EVT3 addresses 11-bit x/y; CSV stores uint16 and may leave the
   * geometry unknown (0x0). */
  int maxd = fmt == ELFM_FMT_EVT3 ? 2048 : 65536;
  int min = fmt == ELFM_FMT_EVT3 ? 1 : 0;
  if (width < min || height < min || width > maxd || height > maxd || (!width) != (!height))
    return elfm_error_set(err, ELFM_ERR_INVALID, path, -1,
                          "geometry %dx%d cannot be written as %s (1..%d)", width, height,
                          elfm_format_name(fmt), maxd);
  elfm_writer *w = calloc(1, sizeof *w);
  if (!w) return elfm_error_set(err, ELFM_ERR_NOMEM, path, -1, "out of memory");
  w->path = strdup(path);
  w->buf = malloc(ELFM_WRITE_BUF_BYTES);
  if (!w->path || !w->buf) {
    free(w->path);
    free(w->buf);
    free(w);
    return elfm_error_set(err, ELFM_ERR_NOMEM, path, -1, "out of memory");
  }
  w->cap = ELFM_WRITE_BUF_BYTES;
  w->fmt = fmt;
  w->width = width;
  w->height = height;
  w->t_last = -1;
  w->evt3.th_abs = -1;
  w->evt3.low = -1;
  w->evt3.y = -1;
  w->f = fopen(path, "wb");
  if (!w->f) {
    elfm_status st = elfm_error_set(err, ELFM_ERR_IO, path, -1, "cannot create: %s",
                                    strerror(errno));
    free(w->path);
    free(w->buf);
    free(w);
    return st;
  }
  elfm_status st = fmt == ELFM_FMT_EVT3 ? elfm_evt3_write_header(w, err)
                                        : elfm_csv_write_header(w, err);
  if (st != ELFM_OK) {
    elfm_writer_close(w, NULL);
    return st;
  }
  *out = w;
  return ELFM_OK;
}

/* Check a whole chunk before encoding any of it, so a rejected chunk
 * leaves the file as it was. */
static elfm_status check_chunk(const elfm_writer *w, const elfm_event_chunk *c, elfm_error *err)
{
  int64_t t = w->t_last < 0 ? 0 : w->t_last;
  uint32_t xl = w->width ? (uint32_t)w->width : 65536u, yl = w->height ? (uint32_t)w->height : 65536u;
  for (size_t i = 0; i < c->n; i++) {
    if (c->t_us[i] < t)
      return elfm_error_set(err, c->t_us[i] < 0 ? ELFM_ERR_RANGE : ELFM_ERR_INVALID, w->path, -1,
                            "event %zu of the chunk: time %lld us is before %lld us", i,
                            (long long)c->t_us[i], (long long)t);
    if (c->x[i] >= xl || c->y[i] >= yl || c->p[i] > 1)
      return elfm_error_set(err, ELFM_ERR_RANGE, w->path, -1,
                            "event %zu of the chunk: x=%u y=%u p=%u outside the %dx%d sensor", i,
                            c->x[i], c->y[i], c->p[i], w->width, w->height);
    t = c->t_us[i];
  }
  t = w->t_last < 0 ? 0 : w->t_last;
  for (size_t i = 0; i < c->n_trig; i++) {
    if (c->trig[i].t_us < t)
      return elfm_error_set(err, ELFM_ERR_INVALID, w->path, -1,
                            "trigger %zu of the chunk: time %lld us is before %lld us", i,
                            (long long)c->trig[i].t_us, (long long)t);
    if (w->fmt == ELFM_FMT_EVT3 && c->trig[i].channel > 15)
      return elfm_error_set(err, ELFM_ERR_RANGE, w->path, -1,
                            "trigger %zu: channel %u does not fit EVT3's 4 bits", i,
                            c->trig[i].channel);
    t = c->trig[i].t_us;
  }
  return ELFM_OK;
}

elfm_status elfm_writer_write(elfm_writer *w, const elfm_event_chunk *c, elfm_error *err)
{
  if (!w || !c) return elfm_error_set(err, ELFM_ERR_INVALID, w ? w->path : NULL, -1, "no writer or chunk");
  if (w->failed) return elfm_error_set(err, ELFM_ERR_IO, w->path, -1, "writer failed earlier");
  elfm_status st = check_chunk(w, c, err);
  if (st != ELFM_OK) return st;
  st = w->fmt == ELFM_FMT_EVT3 ? elfm_evt3_write_events(w, c, err)
                               : elfm_csv_write_events(w, c, err);
  if (st != ELFM_OK) w->failed = 1;
  return st;
}

elfm_status elfm_writer_close(elfm_writer *w, elfm_error *err)
{
  if (!w) return ELFM_OK;
  elfm_status st = ELFM_OK;
  if (w->f) {
    /* Even after a failed write, flush what was encoded: a converter that
     * meets an input error keeps a valid file up to that point. */
    st = elfm_writer_flush(w, err);
    if (fclose(w->f) != 0 && st == ELFM_OK)
      st = elfm_error_set(err, ELFM_ERR_IO, w->path, w->bytes_written, "close failed: %s",
                          strerror(errno));
  }
  free(w->path);
  free(w->buf);
  free(w);
  return st;
}
