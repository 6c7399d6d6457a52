/* test_mip_png.c — elfm_volume_write_mip_png (recon/mip_png.c) pixel by
 * pixel on a small volume whose projections are known. The driver's own
 * MIP of a moving bead is checked in test_recon_pipeline. */
#include <math.h>
#include <png.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "check.h"
#include "elfm_recon.h"

/* The MIP's every pixel on a small volume whose projections are known:
 * a tie between planes (the first wins), a NaN voxel (never wins), a
 * negative one (black), the volume's maximum in the last columns (the
 * row maxima's tail past the groups of 8), with the scale from the volume
 * and given. Colours: plane 0 blue, 1 green, 2 red (3 planes), brightness
 * value / scale rounded. */
static void test_mip_exact(const char *dir)
{
  elfm_error err;
  const int W = 20, H = 3, NZ = 3, ZP = 2;
  elfm_volume *v = elfm_volume_create(W, H, NZ, 1.0, 0.0, 1.0, &err);
  CHECK(v != NULL);
  if (!v) return;
#define VOX(X, Y, k) v->data[((size_t)(k) * H + (Y)) * W + (X)]
  VOX(0, 0, 1) = 2.0f;
  VOX(0, 0, 2) = 2.0f;  /* tie with plane 1 */
  VOX(19, 2, 2) = 4.0f; /* the volume's maximum */
  VOX(1, 1, 0) = NAN;
  VOX(1, 1, 2) = 1.0f;
  VOX(2, 0, 0) = -5.0f;
  VOX(9, 1, 0) = 3.0f;
#undef VOX
  char png[600];
  snprintf(png, sizeof png, "%s/mip_exact.png", dir);
  for (int pass = 0; pass < 2; pass++) {
    const double scale = pass ? 8.0 : 0.0; /* 0: the volume's maximum, 4 */
    const double s = pass ? 8.0 : 4.0;
    CHECK_OK(elfm_volume_write_mip_png(v, png, scale, ZP, &err), &err);
    png_image im;
    memset(&im, 0, sizeof im);
    im.version = PNG_IMAGE_VERSION;
    CHECK(png_image_begin_read_from_file(&im, png));
    const int IW = W + NZ * ZP, IH = H + NZ * ZP;
    CHECK_EQ_INT(im.width, (unsigned)IW);
    CHECK_EQ_INT(im.height, (unsigned)IH);
    im.format = PNG_FORMAT_RGB;
    uint8_t *rgb = malloc(PNG_IMAGE_SIZE(im));
    CHECK(rgb && png_image_finish_read(&im, NULL, rgb, 0, NULL));
    if (!rgb) break;
    /* expected: [row][col] = plane (0 blue, 1 green, 2 red) and value */
    int *want_k = calloc((size_t)IW * IH, sizeof *want_k);
    double *want_v = calloc((size_t)IW * IH, sizeof *want_v);
#define WANT(row, col, k, val) (want_k[(row) * IW + (col)] = (k), want_v[(row) * IW + (col)] = (val))
    WANT(0, 0, 1, 2.0);  /* x-y: the first of the tied planes */
    WANT(2, 19, 2, 4.0);
    WANT(1, 1, 2, 1.0);  /* the NaN passed over */
    WANT(1, 9, 0, 3.0);  /* (row 0, col 2), negative only: black, as every pixel not named */
    for (int r = 0; r < ZP; r++) {
      /* x-z below: row H + k ZP + r, the maximum over Y */
      WANT(H + 0 * ZP + r, 9, 0, 3.0);
      WANT(H + 1 * ZP + r, 0, 1, 2.0);
      WANT(H + 2 * ZP + r, 0, 2, 2.0);
      WANT(H + 2 * ZP + r, 1, 2, 1.0);
      WANT(H + 2 * ZP + r, 19, 2, 4.0);
      /* y-z right: column W + k ZP + r, the maximum over X */
      WANT(1, W + 0 * ZP + r, 0, 3.0);
      WANT(0, W + 1 * ZP + r, 1, 2.0);
      WANT(0, W + 2 * ZP + r, 2, 2.0);
      WANT(1, W + 2 * ZP + r, 2, 1.0);
      WANT(2, W + 2 * ZP + r, 2, 4.0);
    }
#undef WANT
    int bad = 0;
    for (int i = 0; i < IW * IH; i++) {
      const int q = (int)lround(255.0 * want_v[i] / s);
      const int e[3] = {want_k[i] == 2 ? q : 0, want_k[i] == 1 ? q : 0, want_k[i] == 0 ? q : 0};
      for (int c = 0; c < 3; c++)
        if (rgb[3 * i + c] != e[c] && bad++ < 5)
          fprintf(stderr, "MIP pixel (row %d, col %d) channel %d: %d, expected %d (scale %g)\n",
                  i / IW, i % IW, c, rgb[3 * i + c], e[c], scale);
    }
    CHECK(bad == 0);
    free(want_k);
    free(want_v);
    free(rgb);
  }
  elfm_volume_free(v);
}

/* The depth colours between the ends: 9 planes, one voxel each at full
 * scale, plane k at column k of the x-y projection. Expected: HSV with the
 * hue 240 (1 - t) degrees, t = k / 8, full saturation and value, by the
 * textbook formula (X = 255 (1 - |(H / 60) mod 2 - 1|)), not mip_png.c's. */
static void test_mip_hues(const char *dir)
{
  elfm_error err;
  const int W = 9, H = 1, NZ = 9;
  elfm_volume *v = elfm_volume_create(W, H, NZ, 1.0, 0.0, 1.0, &err);
  CHECK(v != NULL);
  if (!v) return;
  for (int k = 0; k < NZ; k++) v->data[(size_t)k * W + k] = 1.0f;
  char png[600];
  snprintf(png, sizeof png, "%s/mip_hues.png", dir);
  CHECK_OK(elfm_volume_write_mip_png(v, png, 1.0, 1, &err), &err);
  png_image im;
  memset(&im, 0, sizeof im);
  im.version = PNG_IMAGE_VERSION;
  CHECK(png_image_begin_read_from_file(&im, png));
  im.format = PNG_FORMAT_RGB;
  uint8_t *rgb = malloc(PNG_IMAGE_SIZE(im));
  CHECK(rgb && png_image_finish_read(&im, NULL, rgb, 0, NULL));
  for (int k = 0; rgb && k < NZ; k++) {
    const double hue = 240.0 * (1.0 - k / 8.0), x = 1.0 - fabs(fmod(hue / 60.0, 2.0) - 1.0);
    const int sector = (int)(hue / 60.0) < 4 ? (int)(hue / 60.0) : 4;
    const double e[5][3] = {{1, x, 0}, {x, 1, 0}, {0, 1, x}, {0, x, 1}, {0, 0, 1}};
    for (int c = 0; c < 3; c++)
      CHECK_MSG(abs(rgb[3 * k + c] - (int)lround(255.0 * e[sector][c])) <= 1,
                "plane %d of 9 (hue %.0f): channel %d is %d, expected %ld", k, hue, c, rgb[3 * k + c],
                lround(255.0 * e[sector][c]));
  }
  free(rgb);
  elfm_volume_free(v);
}

int main(void)
{
  char dir[] = "/tmp/elfm_mip_XXXXXX";
  if (!mkdtemp(dir)) SKIP("cannot make a temporary directory");
  test_mip_exact(dir);
  test_mip_hues(dir);
  char cmd[600];
  snprintf(cmd, sizeof cmd, "rm -rf '%s'", dir);
  if (system(cmd) != 0) fprintf(stderr, "could not remove %s\n", dir);
  return check_report();
}
