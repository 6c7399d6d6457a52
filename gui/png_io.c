/* png_io.c — screenshots out, MIP pictures in, through libpng.
 *
 * libpng reports errors by longjmp to the setjmp point; every local that
 * must survive it is volatile or set before setjmp.
 */
#include <errno.h>
#include <png.h>
#include <setjmp.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "gl_internal.h"

/* libpng's default handlers print to stderr; library code must not. These
 * keep libpng's message for our error object and jump back (error_ptr is a
 * char[200] owned by the calling function). */
static void png_quiet_error(png_structp png, png_const_charp msg)
{
  char *keep = png_get_error_ptr(png);
  if (keep) snprintf(keep, 200, "%s", msg);
  png_longjmp(png, 1);
}

static void png_quiet_warning(png_structp png, png_const_charp msg)
{
  (void)png;
  (void)msg;
}

elfm_status elfm_png_write_rgb(const char *path, int width, int height, const uint8_t *rgb,
                               elfm_error *err)
{
  if (width < 1 || height < 1 || !rgb)
    return elfm_error_set(err, ELFM_ERR_INVALID, path, -1, "empty picture");
  FILE *f = fopen(path, "wb");
  if (!f) return elfm_error_set(err, ELFM_ERR_IO, path, -1, "cannot create: %s", strerror(errno));
  char why[200] = "";
  png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, why, png_quiet_error,
                                            png_quiet_warning);
  png_infop info = png ? png_create_info_struct(png) : NULL;
  if (!png || !info) {
    png_destroy_write_struct(&png, &info);
    fclose(f);
    return elfm_error_set(err, ELFM_ERR_NOMEM, path, -1, "libpng: out of memory");
  }
  if (setjmp(png_jmpbuf(png))) {
    png_destroy_write_struct(&png, &info);
    fclose(f);
    return elfm_error_set(err, ELFM_ERR_IO, path, -1, "libpng could not write the picture: %s",
                          why);
  }
  png_init_io(png, f);
  png_set_IHDR(png, info, (png_uint_32)width, (png_uint_32)height, 8, PNG_COLOR_TYPE_RGB,
               PNG_INTERLACE_NONE, PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
  png_write_info(png, info);
  for (int y = 0; y < height; y++)
    png_write_row(png, (png_const_bytep)(rgb + (size_t)y * width * 3));
  png_write_end(png, NULL);
  png_destroy_write_struct(&png, &info);
  if (fclose(f) != 0)
    return elfm_error_set(err, ELFM_ERR_IO, path, -1, "write failed: %s", strerror(errno));
  return ELFM_OK;
}

elfm_status gui_png_read_into(const char *path, uint8_t **buf, size_t *cap, int *width,
                              int *height, elfm_error *err)
{
  FILE *f = fopen(path, "rb");
  if (!f) return elfm_error_set(err, ELFM_ERR_IO, path, -1, "cannot open: %s", strerror(errno));
  uint8_t sig[8];
  if (fread(sig, 1, 8, f) != 8 || png_sig_cmp(sig, 0, 8)) {
    fclose(f);
    return elfm_error_set(err, ELFM_ERR_FORMAT, path, 0, "not a PNG file");
  }
  char why[200] = "";
  png_structp png = png_create_read_struct(PNG_LIBPNG_VER_STRING, why, png_quiet_error,
                                           png_quiet_warning);
  png_infop info = png ? png_create_info_struct(png) : NULL;
  if (!png || !info) {
    png_destroy_read_struct(&png, &info, NULL);
    fclose(f);
    return elfm_error_set(err, ELFM_ERR_NOMEM, path, -1, "libpng: out of memory");
  }
  if (setjmp(png_jmpbuf(png))) {
    png_destroy_read_struct(&png, &info, NULL);
    fclose(f);
    return elfm_error_set(err, ELFM_ERR_FORMAT, path, -1, "corrupt or truncated PNG (%s)", why);
  }
  png_init_io(png, f);
  png_set_sig_bytes(png, 8);
  png_read_info(png, info);
  png_uint_32 w = png_get_image_width(png, info), h = png_get_image_height(png, info);
  /* Whatever the file holds, hand back 8-bit RGBA. */
  png_set_expand(png);
  png_set_strip_16(png);
  png_set_gray_to_rgb(png);
  png_set_add_alpha(png, 0xFF, PNG_FILLER_AFTER);
  int passes = png_set_interlace_handling(png);
  png_read_update_info(png, info);
  if (w == 0 || h == 0 || w > 65536 || h > 65536 || png_get_rowbytes(png, info) != (size_t)w * 4)
    png_error(png, "unsupported size or layout");
  size_t need = (size_t)w * h * 4;
  if (need > *cap) {
    uint8_t *nb = realloc(*buf, need);
    if (!nb) png_error(png, "out of memory");
    *buf = nb;
    *cap = need;
  }
  /* Row by row, once per interlace pass (libpng merges the passes). */
  for (int pass = 0; pass < passes; pass++)
    for (png_uint_32 y = 0; y < h; y++) png_read_row(png, *buf + (size_t)y * w * 4, NULL);
  png_read_end(png, NULL);
  png_destroy_read_struct(&png, &info, NULL);
  fclose(f);
  *width = (int)w;
  *height = (int)h;
  return ELFM_OK;
}

elfm_status elfm_png_read_rgba(const char *path, int *width, int *height, uint8_t **rgba,
                               elfm_error *err)
{
  uint8_t *buf = NULL;
  size_t cap = 0;
  elfm_status st = gui_png_read_into(path, &buf, &cap, width, height, err);
  if (st != ELFM_OK) {
    free(buf);
    *rgba = NULL;
    return st;
  }
  *rgba = buf;
  return ELFM_OK;
}
