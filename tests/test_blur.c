/* test_blur.c — the sparse binomial blur against a dense convolution on
 * random frames (sparse and dense, signed, clusters at the borders), its
 * list of pixels, the sum it keeps away from the borders, and bad sizes. */
#include <math.h>
#include <stdlib.h>

#include "check.h"
#include "elfm_recon.h"

enum { W = 57, H = 41 };

/* The dense blur: sum over the (2r+1)^2 neighbours inside the frame. */
static double brute(const float *img, int x, int y, int r)
{
  static const double k1[3] = {0.25, 0.5, 0.25};
  static const double k2[5] = {0.0625, 0.25, 0.375, 0.25, 0.0625};
  const double *k = r == 1 ? k1 : k2;
  double s = 0;
  for (int dy = -r; dy <= r; dy++)
    for (int dx = -r; dx <= r; dx++) {
      int xx = x - dx, yy = y - dy;
      if (xx < 0 || yy < 0 || xx >= W || yy >= H) continue;
      s += k[dy + r] * k[dx + r] * img[yy * W + xx];
    }
  return s;
}

static void random_frame(elfm_frame *f, uint32_t *s, double fill, int signed_values)
{
  elfm_frame_clear(f);
  for (uint32_t i = 0; i < (uint32_t)(W * H); i++) {
    *s = *s * 1664525u + 1013904223u;
    if ((*s >> 8) % 10000 < fill * 10000) {
      *s = *s * 1664525u + 1013904223u;
      float v = (float)(1 + (*s >> 24) % 200);
      if (signed_values && ((*s >> 7) & 1)) v = -v;
      elfm_frame_set(f, i, v);
    }
  }
  /* pixels on the corner and the last row */
  elfm_frame_set(f, 0, 9.0f);
  elfm_frame_set(f, (uint32_t)(W * H - 1), 11.0f);
}

int main(void)
{
  elfm_error err;
  elfm_frame *in = elfm_frame_create(W, H, &err), *out = elfm_frame_create(W, H, &err);
  uint32_t s = 7;
  for (int r = 1; r <= 2; r++) {
    elfm_blur *b = NULL;
    CHECK_OK(elfm_blur_create(r, W, H, &b, &err), &err);
    const double fills[] = {0.005, 0.1, 0.5, 1.0};
    for (int fi = 0; fi < 4; fi++)
      for (int sg = 0; sg < 2; sg++) {
        random_frame(in, &s, fills[fi], sg);
        in->t_us = 4321;
        in->n_events = 17;
        elfm_blur_apply(b, in, out);
        CHECK_EQ_INT(out->t_us, 4321);
        CHECK_EQ_INT(out->n_events, 17);
        int bad = 0, listed_ok = 1;
        for (int y = 0; y < H; y++)
          for (int x = 0; x < W; x++)
            if (fabs(out->data[y * W + x] - brute(in->data, x, y, r)) > 1e-4) bad++;
        /* every pixel the blur reached is listed once, and only those
         * (the next call clears through the list) */
        char *seen = calloc(W * H, 1);
        for (size_t i = 0; i < out->nnz; i++) seen[out->idx[i]]++;
        for (int i = 0; i < W * H; i++)
          if ((out->data[i] != 0.0f && seen[i] != 1) || seen[i] > 1) listed_ok = 0;
        free(seen);
        CHECK_MSG(bad == 0, "radius %d fill %.3f signed %d: %d pixels differ", r, fills[fi], sg,
                  bad);
        CHECK(listed_ok);
      }
    /* one event away from the borders: its value spread, the sum kept, the
     * centre the kernel's peak; then cleared by the next call */
    elfm_frame_clear(in);
    elfm_frame_set(in, 20 * W + 30, 160.0f);
    elfm_blur_apply(b, in, out);
    double sum = 0;
    for (size_t i = 0; i < out->nnz; i++) sum += out->data[out->idx[i]];
    CHECK(fabs(sum - 160.0) < 1e-3);
    CHECK_EQ_INT(out->nnz, (size_t)((2 * r + 1) * (2 * r + 1)));
    CHECK(fabs(out->data[20 * W + 30] - 160.0 * (r == 1 ? 0.25 : 0.140625)) < 1e-4);
    elfm_frame_clear(in);
    elfm_frame_set(in, 5 * W + 5, 1.0f);
    elfm_blur_apply(b, in, out);
    CHECK(out->data[20 * W + 30] == 0.0f);
    /* a frame of another size leaves the output empty */
    elfm_frame *other = elfm_frame_create(W + 1, H, &err);
    elfm_frame_set(other, 3, 5.0f);
    elfm_blur_apply(b, other, out);
    CHECK_EQ_INT(out->nnz, 0);
    elfm_frame_free(other);
    elfm_blur_free(b);
  }
  /* bad radii and sizes */
  elfm_blur *bad = NULL;
  CHECK(elfm_blur_create(0, W, H, &bad, &err) == ELFM_ERR_INVALID && bad == NULL);
  CHECK(elfm_blur_create(3, W, H, &bad, &err) == ELFM_ERR_INVALID && bad == NULL);
  CHECK(elfm_blur_create(1, 0, H, &bad, &err) == ELFM_ERR_INVALID);
  elfm_blur_free(NULL);
  elfm_frame_free(in);
  elfm_frame_free(out);
  return check_report();
}
