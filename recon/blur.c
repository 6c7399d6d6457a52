/* blur.c — a small binomial blur of mostly-zero frames (see elfm_frames.h).
 *
 * A dim object sends each view about one event per frame, somewhere in its
 * image: the refocus then averages views that mostly miss the voxel where
 * the images meet, and the peak stays below any threshold noise allows.
 * Spreading each event over the image's size first (a matched filter for
 * the blur of the image) lets the views' events overlap at the voxel.
 * Refocusing is a sum of shifted views, so blurring the frame is blurring
 * each plane of the volume laterally, at the cost of the listed pixels only.
 *
 * Scatter per listed pixel: each adds value x kernel to its (2r+1)^2
 * neighbours; a byte mask lists each output pixel once. O(listed x (2r+1)^2).
 */
#include "elfm_frames.h"

#include <stdlib.h>

struct elfm_blur {
  int r, w, h;
  float k[5];     /* the 1D binomial kernel, 2r + 1 taps, sum 1 */
  uint8_t *mark;  /* [w * h] listed in the output */
};

elfm_status elfm_blur_create(int radius_px, int w, int h, elfm_blur **out, elfm_error *err)
{
  *out = NULL;
  if (radius_px < 1 || radius_px > 2)
    return elfm_error_set(err, ELFM_ERR_INVALID, NULL, -1, "blur radius %d px: use 1 or 2",
                          radius_px);
  if (w <= 0 || h <= 0)
    return elfm_error_set(err, ELFM_ERR_INVALID, NULL, -1, "blur frame size %d x %d", w, h);
  elfm_blur *b = calloc(1, sizeof *b);
  if (b) b->mark = calloc((size_t)w * (size_t)h, 1);
  if (!b || !b->mark) {
    elfm_blur_free(b);
    return elfm_error_set(err, ELFM_ERR_NOMEM, NULL, -1, "out of memory (blur %d x %d)", w, h);
  }
  b->r = radius_px;
  b->w = w;
  b->h = h;
  static const float k1[3] = {0.25f, 0.5f, 0.25f};
  static const float k2[5] = {0.0625f, 0.25f, 0.375f, 0.25f, 0.0625f};
  for (int i = 0; i <= 2 * b->r; i++) b->k[i] = b->r == 1 ? k1[i] : k2[i];
  *out = b;
  return ELFM_OK;
}

void elfm_blur_free(elfm_blur *b)
{
  if (!b) return;
  free(b->mark);
  free(b);
}

void elfm_blur_apply(elfm_blur *b, const elfm_frame *in, elfm_frame *out)
{
  elfm_frame_clear_like(out, in);
  if (in->w != b->w || in->h != b->h || out->w != b->w || out->h != b->h) return;
  const int r = b->r, w = b->w, h = b->h;
  for (size_t n = 0; n < in->nnz; n++) {
    const uint32_t i = in->idx[n];
    const float a = in->data[i];
    if (a == 0.0f) continue;
    const int x = (int)(i % (uint32_t)w), y = (int)(i / (uint32_t)w);
    for (int dy = -r; dy <= r; dy++) {
      const int yy = y + dy;
      if (yy < 0 || yy >= h) continue;
      const float ay = a * b->k[dy + r];
      for (int dx = -r; dx <= r; dx++) {
        const int xx = x + dx;
        if (xx < 0 || xx >= w) continue;
        const uint32_t q = (uint32_t)yy * (uint32_t)w + (uint32_t)xx;
        if (!b->mark[q]) {
          b->mark[q] = 1;
          out->idx[out->nnz++] = q;
        }
        out->data[q] += ay * b->k[dx + r];
      }
    }
  }
  for (size_t n = 0; n < out->nnz; n++) b->mark[out->idx[n]] = 0;
}
