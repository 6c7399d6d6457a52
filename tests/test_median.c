/* test_median.c — the sparse median against a brute-force dense median on
 * random frames (sparse and dense, signed, with clusters at the borders),
 * and the filter's purpose: isolated noise removed, a blob kept. */
#include <stdlib.h>
#include <string.h>

#include "check.h"
#include "elfm_recon.h"

enum { W = 57, H = 41 };

static int cmp_float(const void *a, const void *b)
{
  float x = *(const float *)a, y = *(const float *)b;
  return (x > y) - (x < y);
}

static float brute(const float *img, int x, int y, int size)
{
  float win[25];
  int r = size / 2, k = 0;
  for (int dy = -r; dy <= r; dy++)
    for (int dx = -r; dx <= r; dx++) {
      int xx = x + dx, yy = y + dy;
      win[k++] = (xx < 0 || yy < 0 || xx >= W || yy >= H) ? 0.0f : img[yy * W + xx];
    }
  qsort(win, (size_t)k, sizeof *win, cmp_float);
  return win[k / 2];
}

static void random_frame(elfm_frame *f, uint32_t *s, double fill, int signed_values)
{
  elfm_frame_clear(f);
  for (uint32_t i = 0; i < (uint32_t)(W * H); i++) {
    *s = *s * 1664525u + 1013904223u;
    if ((*s >> 8) % 10000 < fill * 10000) {
      *s = *s * 1664525u + 1013904223u;
      float v = (float)(1 + (*s >> 24) % 50); /* few levels: ties happen */
      if (signed_values && ((*s >> 7) & 1)) v = -v;
      elfm_frame_set(f, i, v);
    }
  }
  /* a dense blob touching the corner */
  for (int y = 0; y < 4; y++)
    for (int x = 0; x < 5; x++) elfm_frame_set(f, (uint32_t)(y * W + x), 7.0f + x);
}

int main(void)
{
  elfm_error err;
  elfm_frame *in = elfm_frame_create(W, H, &err), *out = elfm_frame_create(W, H, &err);
  uint32_t s = 99;
  for (int size = 3; size <= 5; size += 2) {
    elfm_median *m = NULL;
    CHECK_OK(elfm_median_create(size, W, H, &m, &err), &err);
    const double fills[] = {0.01, 0.2, 0.6, 1.0};
    for (int fi = 0; fi < 4; fi++)
      for (int sg = 0; sg < 2; sg++) {
        random_frame(in, &s, fills[fi], sg);
        out->t_us = -5;
        in->t_us = 1234;
        elfm_median_apply(m, in, out);
        CHECK_EQ_INT(out->t_us, 1234);
        int bad = 0, listed_ok = 1;
        for (int y = 0; y < H; y++)
          for (int x = 0; x < W; x++)
            if (out->data[y * W + x] != brute(in->data, x, y, size)) bad++;
        char *seen = calloc(W * H, 1);
        for (size_t i = 0; i < out->nnz; i++) seen[out->idx[i]]++;
        for (int i = 0; i < W * H; i++)
          if ((out->data[i] != 0.0f && seen[i] != 1) || seen[i] > 1) listed_ok = 0;
        free(seen);
        CHECK_MSG(bad == 0, "size %d fill %.2f signed %d: %d pixels differ", size, fills[fi], sg, bad);
        CHECK(listed_ok);
      }
    elfm_median_free(m);
  }
  /* isolated events vanish, a 4x4 blob's inside survives */
  elfm_median *m3 = NULL;
  CHECK_OK(elfm_median_create(3, W, H, &m3, &err), &err);
  elfm_frame_clear(in);
  elfm_frame_set(in, 10 * W + 10, 200.0f);
  elfm_frame_set(in, 30 * W + 40, 100.0f);
  for (int y = 20; y < 24; y++)
    for (int x = 20; x < 24; x++) elfm_frame_set(in, (uint32_t)(y * W + x), 50.0f);
  elfm_median_apply(m3, in, out);
  CHECK(out->data[10 * W + 10] == 0.0f);
  CHECK(out->data[30 * W + 40] == 0.0f);
  CHECK(out->data[21 * W + 21] == 50.0f);
  CHECK(out->data[20 * W + 20] == 0.0f); /* a corner has 4 of 9 set */
  CHECK_EQ_INT(out->nnz, 12);
  /* bad sizes */
  elfm_median *bad = NULL;
  CHECK(elfm_median_create(4, W, H, &bad, &err) == ELFM_ERR_INVALID && bad == NULL);
  CHECK(elfm_median_create(3, 0, H, &bad, &err) == ELFM_ERR_INVALID);
  elfm_median_free(m3);
  elfm_median_free(NULL);
  elfm_frame_free(in);
  elfm_frame_free(out);
  return check_report();
}
