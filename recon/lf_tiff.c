/* lf_tiff.c — conventional light-field frames: multi-page grey TIFF stacks
 * (e.g. 16-bit sCMOS Fourier LFM recordings) through libtiff, for
 * side-by-side comparisons with event volumes (see elfm_pipeline.h).
 *
 * libtiff's messages go to a per-handle handler (TIFFOpenExt, libtiff >= 4.5)
 * that keeps the last one in the stack object: no global handler is
 * replaced and nothing is printed.
 */
#include "elfm_pipeline.h"

#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <tiffio.h>

/* Larger pages than this are not light-field camera frames (and would let
 * a corrupt header ask for gigabytes). */
#define TIFF_MAX_SIDE 32768
#define TIFF_MAX_ALLOC ((tmsize_t)256 << 20)

struct elfm_tiff_stack {
  TIFF *tif;
  char path[512];
  char msg[256];
  int w, h, page, done;
  void *line;
  size_t line_cap; /* bytes of line: pages may differ in sample size (8, 16, 32 bits) */
};

struct elfm_tiff_writer {
  TIFF *tif;
  char path[512];
  char msg[256];
  int page;
  uint16_t *line;
  int line_w;
};

static int tiff_keep_message(TIFF *tif, void *user, const char *module, const char *fmt, va_list ap)
{
  (void)tif;
  char *msg = user; /* the stack's/writer's msg[256] */
  int n = snprintf(msg, 256, "%s: ", module ? module : "libtiff");
  if (n < 0 || n >= 256) n = 0;
  vsnprintf(msg + n, (size_t)(256 - n), fmt, ap);
  return 1; /* handled: do not call the global handler */
}

static int tiff_ignore(TIFF *tif, void *user, const char *module, const char *fmt, va_list ap)
{
  (void)tif, (void)user, (void)module, (void)fmt, (void)ap;
  return 1;
}

static TIFF *tiff_open(const char *path, const char *mode, char *msg)
{
  TIFFOpenOptions *o = TIFFOpenOptionsAlloc();
  if (!o) return NULL;
  TIFFOpenOptionsSetErrorHandlerExtR(o, tiff_keep_message, msg);
  TIFFOpenOptionsSetWarningHandlerExtR(o, tiff_ignore, NULL);
  TIFFOpenOptionsSetMaxSingleMemAlloc(o, TIFF_MAX_ALLOC);
  TIFF *t = TIFFOpenExt(path, mode, o);
  TIFFOpenOptionsFree(o);
  return t;
}

void elfm_tiff_close(elfm_tiff_stack *s)
{
  if (!s) return;
  if (s->tif) TIFFClose(s->tif);
  free(s->line);
  free(s);
}

int elfm_tiff_width(const elfm_tiff_stack *s) { return s->w; }
int elfm_tiff_height(const elfm_tiff_stack *s) { return s->h; }

/* Check the current directory: grey, one sample of 8/16 bit unsigned or
 * 32-bit float, strips, the stack's size. */
static elfm_status tiff_check_page(elfm_tiff_stack *s, uint16_t *bps, uint16_t *fmt, elfm_error *err)
{
  uint32_t w = 0, h = 0;
  uint16_t spp = 1, planar = PLANARCONFIG_CONTIG;
  *bps = 1;
  *fmt = SAMPLEFORMAT_UINT;
  if (!TIFFGetField(s->tif, TIFFTAG_IMAGEWIDTH, &w) || !TIFFGetField(s->tif, TIFFTAG_IMAGELENGTH, &h))
    return elfm_error_set(err, ELFM_ERR_FORMAT, s->path, -1, "page %d: no image size", s->page);
  TIFFGetFieldDefaulted(s->tif, TIFFTAG_BITSPERSAMPLE, bps);
  TIFFGetFieldDefaulted(s->tif, TIFFTAG_SAMPLESPERPIXEL, &spp);
  TIFFGetFieldDefaulted(s->tif, TIFFTAG_SAMPLEFORMAT, fmt);
  TIFFGetFieldDefaulted(s->tif, TIFFTAG_PLANARCONFIG, &planar);
  if (w == 0 || h == 0 || w > TIFF_MAX_SIDE || h > TIFF_MAX_SIDE)
    return elfm_error_set(err, ELFM_ERR_RANGE, s->path, -1, "page %d: size %u x %u outside 1..%d",
                          s->page, w, h, TIFF_MAX_SIDE);
  if (spp != 1)
    return elfm_error_set(err, ELFM_ERR_UNSUPPORTED, s->path, -1,
                          "page %d: %u samples per pixel (a grey stack has 1)", s->page, spp);
  int ok = (*fmt == SAMPLEFORMAT_UINT && (*bps == 8 || *bps == 16)) ||
           (*fmt == SAMPLEFORMAT_IEEEFP && *bps == 32);
  if (!ok)
    return elfm_error_set(err, ELFM_ERR_UNSUPPORTED, s->path, -1,
                          "page %d: %u-bit samples of format %u (8/16-bit unsigned or 32-bit float)",
                          s->page, *bps, *fmt);
  if (TIFFIsTiled(s->tif))
    return elfm_error_set(err, ELFM_ERR_UNSUPPORTED, s->path, -1, "page %d: tiled TIFF", s->page);
  if (s->w && ((int)w != s->w || (int)h != s->h))
    return elfm_error_set(err, ELFM_ERR_FORMAT, s->path, -1, "page %d is %u x %u, page 0 was %d x %d",
                          s->page, w, h, s->w, s->h);
  s->w = (int)w;
  s->h = (int)h;
  return ELFM_OK;
}

elfm_status elfm_tiff_open(const char *path, elfm_tiff_stack **out, elfm_error *err)
{
  *out = NULL;
  elfm_tiff_stack *s = calloc(1, sizeof *s);
  if (!s) return elfm_error_set(err, ELFM_ERR_NOMEM, path, -1, "out of memory");
  snprintf(s->path, sizeof s->path, "%s", path);
  FILE *probe = fopen(path, "rb");
  if (!probe) {
    elfm_tiff_close(s);
    return elfm_error_set(err, ELFM_ERR_IO, path, -1, "cannot open");
  }
  fclose(probe);
  s->tif = tiff_open(path, "r", s->msg);
  if (!s->tif) {
    elfm_status st = elfm_error_set(err, ELFM_ERR_FORMAT, path, 0, "not a readable TIFF: %s", s->msg);
    elfm_tiff_close(s);
    return st;
  }
  uint16_t bps, fmt;
  elfm_status st = tiff_check_page(s, &bps, &fmt, err);
  if (!st) {
    tmsize_t n = TIFFScanlineSize(s->tif);
    if (n <= 0 || n > TIFF_MAX_ALLOC || !(s->line = malloc((size_t)n)))
      st = elfm_error_set(err, ELFM_ERR_FORMAT, path, -1, "page 0: bad scanline size");
    else
      s->line_cap = (size_t)n;
  }
  if (st) {
    elfm_tiff_close(s);
    return st;
  }
  *out = s;
  return ELFM_OK;
}

elfm_status elfm_tiff_read(elfm_tiff_stack *s, elfm_frame *out, int *got, elfm_error *err)
{
  *got = 0;
  if (s->done) return ELFM_OK;
  uint16_t bps, fmt;
  elfm_status st = tiff_check_page(s, &bps, &fmt, err);
  if (st) return st;
  if (out->w != s->w || out->h != s->h)
    return elfm_error_set(err, ELFM_ERR_INVALID, s->path, -1, "frame %d x %d for %d x %d pages",
                          out->w, out->h, s->w, s->h);
  tmsize_t need = (tmsize_t)s->w * (bps / 8);
  const tmsize_t line = TIFFScanlineSize(s->tif);
  if (line < need)
    return elfm_error_set(err, ELFM_ERR_FORMAT, s->path, -1, "page %d: scanline too short", s->page);
  /* TIFFReadScanline writes a whole scanline of this page, which is longer
   * than page 0's when its samples are wider (libFuzzer found the overflow:
   * an 8-bit page 0, then a 32-bit page of the same size) */
  if ((size_t)line > s->line_cap) {
    void *b = line <= TIFF_MAX_ALLOC ? realloc(s->line, (size_t)line) : NULL;
    if (!b)
      return elfm_error_set(err, ELFM_ERR_FORMAT, s->path, -1, "page %d: bad scanline size", s->page);
    s->line = b;
    s->line_cap = (size_t)line;
  }
  elfm_frame_clear(out);
  for (int y = 0; y < s->h; y++) {
    s->msg[0] = '\0';
    if (TIFFReadScanline(s->tif, s->line, (uint32_t)y, 0) < 0)
      return elfm_error_set(err, ELFM_ERR_FORMAT, s->path, -1, "page %d, row %d: %s", s->page, y,
                            s->msg[0] ? s->msg : "cannot read");
    float *row = out->data + (size_t)y * s->w;
    for (int x = 0; x < s->w; x++) {
      float v;
      if (bps == 8) v = ((const uint8_t *)s->line)[x];
      else if (bps == 16) v = ((const uint16_t *)s->line)[x];
      else {
        v = ((const float *)s->line)[x];
        if (!(v == v) || v > 3.4e38f || v < -3.4e38f) v = 0.0f; /* NaN/inf pages: no signal */
      }
      if (v != 0.0f) {
        row[x] = v;
        out->idx[out->nnz++] = (uint32_t)(y * s->w + x);
      }
    }
  }
  *got = 1;
  s->page++;
  if (!TIFFReadDirectory(s->tif)) s->done = 1;
  return ELFM_OK;
}

elfm_status elfm_tiff_writer_open(const char *path, elfm_tiff_writer **out, elfm_error *err)
{
  *out = NULL;
  elfm_tiff_writer *w = calloc(1, sizeof *w);
  if (!w) return elfm_error_set(err, ELFM_ERR_NOMEM, path, -1, "out of memory");
  snprintf(w->path, sizeof w->path, "%s", path);
  w->tif = tiff_open(path, "w", w->msg);
  if (!w->tif) {
    elfm_status st = elfm_error_set(err, ELFM_ERR_IO, path, -1, "cannot create: %s", w->msg);
    free(w);
    return st;
  }
  *out = w;
  return ELFM_OK;
}

elfm_status elfm_tiff_writer_add(elfm_tiff_writer *w, const elfm_frame *f, elfm_error *err)
{
  if (w->line_w != f->w) {
    free(w->line);
    w->line = malloc((size_t)f->w * sizeof *w->line);
    w->line_w = w->line ? f->w : 0;
    if (!w->line) return elfm_error_set(err, ELFM_ERR_NOMEM, w->path, -1, "out of memory");
  }
  TIFF *t = w->tif;
  TIFFSetField(t, TIFFTAG_IMAGEWIDTH, (uint32_t)f->w);
  TIFFSetField(t, TIFFTAG_IMAGELENGTH, (uint32_t)f->h);
  TIFFSetField(t, TIFFTAG_BITSPERSAMPLE, 16);
  TIFFSetField(t, TIFFTAG_SAMPLESPERPIXEL, 1);
  TIFFSetField(t, TIFFTAG_SAMPLEFORMAT, SAMPLEFORMAT_UINT);
  TIFFSetField(t, TIFFTAG_PHOTOMETRIC, PHOTOMETRIC_MINISBLACK);
  TIFFSetField(t, TIFFTAG_PLANARCONFIG, PLANARCONFIG_CONTIG);
  TIFFSetField(t, TIFFTAG_COMPRESSION, COMPRESSION_NONE);
  TIFFSetField(t, TIFFTAG_ROWSPERSTRIP, (uint32_t)16);
  TIFFSetField(t, TIFFTAG_SUBFILETYPE, FILETYPE_PAGE);
  for (int y = 0; y < f->h; y++) {
    const float *row = f->data + (size_t)y * f->w;
    for (int x = 0; x < f->w; x++) {
      float v = row[x] + 0.5f;
      w->line[x] = v <= 0.0f ? 0 : v >= 65535.0f ? 65535 : (uint16_t)v;
    }
    if (TIFFWriteScanline(t, w->line, (uint32_t)y, 0) < 0)
      return elfm_error_set(err, ELFM_ERR_IO, w->path, -1, "page %d: %s", w->page, w->msg);
  }
  if (!TIFFWriteDirectory(t))
    return elfm_error_set(err, ELFM_ERR_IO, w->path, -1, "page %d: %s", w->page, w->msg);
  w->page++;
  return ELFM_OK;
}

elfm_status elfm_tiff_writer_close(elfm_tiff_writer *w, elfm_error *err)
{
  if (!w) return ELFM_OK;
  elfm_status st = ELFM_OK;
  if (!TIFFFlush(w->tif)) st = elfm_error_set(err, ELFM_ERR_IO, w->path, -1, "flush: %s", w->msg);
  TIFFClose(w->tif);
  free(w->line);
  free(w);
  return st;
}
