/* mip_png.c — depth-colour-coded maximum intensity projections of a volume
 * as an RGB PNG through libpng's simplified API (layout in elfm_pipeline.h).
 * The colour of a projected pixel says where along the projection axis its
 * maximum lies: hue from blue (z_min) to red (z_max), as in the paper's
 * depth-coded MIPs; side panels are coloured by their own plane's depth.
 */
#include "elfm_pipeline.h"

#include <math.h>
#include <png.h>
#include <stdlib.h>
#include <string.h>

/* depth t in [0, 1] -> RGB at value `val` in [0, 1]: HSV hue 240 deg (blue)
 * down to 0 deg (red), full saturation. */
static void depth_rgb(double t, double val, uint8_t *rgb)
{
  double h = (1.0 - t) * 4.0; /* 0..4 in 60-degree sectors, red..blue */
  int s = (int)floor(h);
  double f = h - s, r = 0, g = 0, b = 0;
  switch (s) {
  case 0: r = 1; g = f; b = 0; break;
  case 1: r = 1 - f; g = 1; b = 0; break;
  case 2: r = 0; g = 1; b = f; break;
  case 3: r = 0; g = 1 - f; b = 1; break;
  default: r = 0; g = 0; b = 1; break;
  }
  if (val < 0) val = 0;
  if (val > 1) val = 1;
  rgb[0] = (uint8_t)lround(255.0 * r * val);
  rgb[1] = (uint8_t)lround(255.0 * g * val);
  rgb[2] = (uint8_t)lround(255.0 * b * val);
}

elfm_status elfm_volume_write_mip_png(const elfm_volume *v, const char *path, double scale,
                                      int z_px, elfm_error *err)
{
  if (z_px < 0 || z_px > 64)
    return elfm_error_set(err, ELFM_ERR_INVALID, path, -1, "z_px %d outside 0..64", z_px);
  if (z_px == 0) z_px = 1;
  const int W = v->w, H = v->h, NZ = v->nz, PZ = NZ * z_px;
  const int IW = W + PZ, IH = H + PZ;
  if (scale <= 0) {
    float m = 0.0f;
    for (size_t i = 0; i < (size_t)W * H * NZ; i++) m = fmaxf(m, v->data[i]);
    scale = m > 0.0f ? m : 1.0;
  }
  uint8_t *img = calloc((size_t)IW * IH * 3, 1);
  if (!img) return elfm_error_set(err, ELFM_ERR_NOMEM, path, -1, "out of memory (MIP)");
  const double tden = NZ > 1 ? (double)(NZ - 1) : 1.0;
  /* x-y: max over k */
  for (int Y = 0; Y < H; Y++)
    for (int X = 0; X < W; X++) {
      float m = 0.0f;
      int km = 0;
      for (int k = 0; k < NZ; k++) {
        float a = v->data[((size_t)k * H + Y) * W + X];
        if (a > m) { m = a; km = k; }
      }
      depth_rgb(km / tden, m / scale, img + ((size_t)Y * IW + X) * 3);
    }
  /* x-z below (z down), y-z right (z rightwards): max over the other axis */
  for (int k = 0; k < NZ; k++) {
    const float *pl = v->data + (size_t)k * H * W;
    for (int X = 0; X < W; X++) {
      float m = 0.0f;
      for (int Y = 0; Y < H; Y++) m = fmaxf(m, pl[(size_t)Y * W + X]);
      for (int r = 0; r < z_px; r++)
        depth_rgb(k / tden, m / scale, img + ((size_t)(H + k * z_px + r) * IW + X) * 3);
    }
    for (int Y = 0; Y < H; Y++) {
      float m = 0.0f;
      for (int X = 0; X < W; X++) m = fmaxf(m, pl[(size_t)Y * W + X]);
      for (int r = 0; r < z_px; r++)
        depth_rgb(k / tden, m / scale, img + ((size_t)Y * IW + W + k * z_px + r) * 3);
    }
  }
  png_image im;
  memset(&im, 0, sizeof im);
  im.version = PNG_IMAGE_VERSION;
  im.width = (png_uint_32)IW;
  im.height = (png_uint_32)IH;
  im.format = PNG_FORMAT_RGB;
  elfm_status st = ELFM_OK;
  if (!png_image_write_to_file(&im, path, 0, img, 0, NULL))
    st = elfm_error_set(err, ELFM_ERR_IO, path, -1, "cannot write PNG: %s", im.message);
  png_image_free(&im);
  free(img);
  return st;
}
