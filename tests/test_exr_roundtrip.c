/* test_exr_roundtrip.c — a volume written as EXR reads back bit for bit,
 * whatever its height is in ZIP chunks (16 scanlines each).
 *
 * Why: the writer runs one encoder per file and updates it chunk by chunk
 * (its buffers reused; volume_exr.c). A chunk that kept the previous
 * chunk's rows, line count or channel pointers would pass a one-chunk
 * volume and fail here: heights 1, 15, 16, 17, 53 and 144 (the paper's
 * field), 200, widths and plane counts that differ, values of every kind a
 * refocused volume can hold (zeros, negatives after ghost subtraction,
 * subnormals, large ones). Volumes made as a run's slots are, too. */
#include <stdint.h>
#include <stdio.h>
#include <string.h>

#include "big_alloc.h" /* elfm_volume_create_kept */
#include "check.h"
#include "elfm_recon.h"

/* A value per voxel that differs from its neighbours in every axis, with a
 * few exact zeros, negatives and extremes: bits that a shifted or stale
 * chunk cannot reproduce. */
static float voxel_value(uint32_t *state, size_t i)
{
  *state = *state * 1664525u + 1013904223u;
  const uint32_t r = *state >> 8;
  switch (r % 11) {
  case 0: return 0.0f;
  case 1: return -(float)(r % 1000) * 0.37f;
  case 2: return 1.0e-40f * (float)(1 + r % 7); /* subnormal */
  case 3: return 3.0e38f;
  default: return (float)i * 0.001f + (float)(r % 100000) * 1e-3f;
  }
}

/* kept: the volume as a run's slot makes it (elfm_volume_create_kept: on
 * 2 MiB pages where there are any), which elfm_volume_free must free as
 * such. */
static void roundtrip(int w, int h, int nz, int kept, const char *path)
{
  elfm_error err;
  elfm_error_clear(&err);
  elfm_volume *v = kept ? elfm_volume_create_kept(w, h, nz, 0.926, -100.0, 2.0, &err)
                        : elfm_volume_create(w, h, nz, 0.926, -100.0, 2.0, &err);
  CHECK_MSG(v != NULL, "create %d x %d x %d", w, h, nz);
  if (!v) return;
  CHECK_EQ_INT(v->data_big, kept);
  const size_t n = (size_t)w * h * nz;
  uint32_t state = (uint32_t)(w * 7919 + h * 104729 + nz);
  for (size_t i = 0; i < n; i++) v->data[i] = voxel_value(&state, i);
  v->t_us = 123456789;
  v->frame = 4242;
  CHECK_OK(elfm_volume_write_exr(v, path, &err), &err);
  elfm_volume *back = NULL;
  CHECK_OK(elfm_volume_read_exr(path, &back, &err), &err);
  if (back) {
    CHECK_MSG(back->w == w && back->h == h && back->nz == nz, "%d x %d x %d read as %d x %d x %d",
              w, h, nz, back->w, back->h, back->nz);
    CHECK_EQ_INT(back->frame, 4242);
    CHECK_EQ_INT(back->t_us, 123456789);
    /* the geometry that places each voxel in um (SPEC 5's attributes) */
    CHECK_MSG(back->um_per_px == 0.926 && back->z_min_um == -100.0 && back->z_step_um == 2.0,
              "um_per_px %.17g, z_min_um %.17g, z_step_um %.17g", back->um_per_px, back->z_min_um,
              back->z_step_um);
    if (back->w == w && back->h == h && back->nz == nz) {
      size_t differ = 0, first = n;
      for (size_t i = 0; i < n; i++)
        if (memcmp(&back->data[i], &v->data[i], sizeof(float)) != 0) {
          if (first == n) first = i;
          differ++;
        }
      CHECK_MSG(differ == 0, "%d x %d x %d: %zu of %zu voxels differ, the first at row %zu plane %zu",
                w, h, nz, differ, n, first < n ? first / (size_t)w % (size_t)h : 0,
                first < n ? first / ((size_t)w * h) : 0);
    }
  }
  elfm_volume_free(back);
  elfm_volume_free(v);
  remove(path);
}

int main(void)
{
  const char *path = "exr_roundtrip.exr";
  /* heights around the chunk size, and the paper's 144 x 144 x 101 */
  const int shapes[][3] = {{1, 1, 1},  {7, 15, 3},  {16, 16, 1},   {5, 17, 4},
                           {37, 53, 5}, {3, 200, 2}, {144, 144, 101}};
  for (size_t s = 0; s < sizeof shapes / sizeof shapes[0]; s++)
    roundtrip(shapes[s][0], shapes[s][1], shapes[s][2], 0, path);
  /* a small file after a large one, in the same process: nothing carried */
  roundtrip(9, 33, 2, 0, path);
  /* a slot's volume, small (calloc's) and of the paper's size (mapped) */
  roundtrip(9, 33, 2, 1, path);
  roundtrip(144, 144, 101, 1, path);
  return check_report();
}
