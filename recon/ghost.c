/* ghost.c — ghost suppression after shift-and-add (see elfm_refocus.h).
 *
 * Threshold (the paper's): voxels below a level are set to 0. The level is
 * absolute, a fraction of the volume's maximum, or median + k robust sigma
 * of the non-zero voxels (sigma = 1.4826 MAD, the Gaussian-consistent
 * scale). Zero voxels are left out of the statistics: a 1 ms event frame
 * leaves most of the volume exactly 0, which would make the MAD 0.
 * The median and MAD come from 4096-bin histograms (resolution 1/4096 of
 * the value range, far below the spread of a noise floor), so no sort and
 * no allocation.
 *
 * Agreement (ours): a voxel is kept only when at least `need` of the views
 * sampling it see signal there (need = ceil(agree_frac x views), from the plan).
 */
#include "refocus_internal.h"

#include <math.h>
#include <string.h>

#define GHOST_BINS 4096

void elfm_ghost_agree_row(const elfm_refocus_plan *p, int k, int Y, float *row, const uint8_t *cnt)
{
  const uint8_t *need = p->need + ((size_t)k * p->h + Y) * p->w;
  for (int X = 0; X < p->w; X++)
    if (cnt[X] < need[X]) row[X] = 0.0f;
}

/* Visit the rows (or the whole volume) as (pointer, length) runs. */
#define FOR_RUNS(vol, rows, n_rows, body)                                         \
  do {                                                                            \
    const size_t W_ = (size_t)(vol)->w;                                           \
    size_t nr_ = (rows) ? (n_rows) : 1;                                           \
    for (size_t ri_ = 0; ri_ < nr_; ri_++) {                                      \
      float *run = (rows) ? (vol)->data + (size_t)(rows)[ri_] * W_ : (vol)->data; \
      size_t len = (rows) ? W_ : W_ * (size_t)(vol)->h * (size_t)(vol)->nz;       \
      body                                                                        \
    }                                                                             \
  } while (0)

/* Value at rank `rank` (0-based) among `n` values binned in hist over
 * [lo, lo + GHOST_BINS * width): the centre of its bin. */
static double hist_rank(const uint32_t *hist, size_t rank, double lo, double width)
{
  size_t acc = 0;
  for (int b = 0; b < GHOST_BINS; b++) {
    acc += hist[b];
    if (acc > rank) return lo + (b + 0.5) * width;
  }
  return lo + GHOST_BINS * width;
}

static double ghost_mad_level(elfm_volume *vol, const uint32_t *rows, size_t n_rows, double k)
{
  double lo = INFINITY, hi = -INFINITY;
  size_t n = 0;
  FOR_RUNS(vol, rows, n_rows, {
    for (size_t i = 0; i < len; i++) {
      float a = fabsf(run[i]);
      if (a == 0.0f) continue;
      n++;
      if (a < lo) lo = a;
      if (a > hi) hi = a;
    }
  });
  if (n == 0) return 0.0;
  if (hi <= lo) return lo; /* every non-zero voxel equal: nothing to tell apart */
  uint32_t hist[GHOST_BINS];
  memset(hist, 0, sizeof hist);
  double width = (hi - lo) / GHOST_BINS * (1.0 + 1e-9);
  FOR_RUNS(vol, rows, n_rows, {
    for (size_t i = 0; i < len; i++) {
      float a = fabsf(run[i]);
      if (a == 0.0f) continue;
      int b = (int)((a - lo) / width);
      hist[b < GHOST_BINS ? b : GHOST_BINS - 1]++;
    }
  });
  double med = hist_rank(hist, n / 2, lo, width);
  double dev_hi = fmax(hi - med, med - lo);
  memset(hist, 0, sizeof hist);
  double dw = dev_hi / GHOST_BINS * (1.0 + 1e-9);
  if (!(dw > 0.0)) return med;
  FOR_RUNS(vol, rows, n_rows, {
    for (size_t i = 0; i < len; i++) {
      float a = fabsf(run[i]);
      if (a == 0.0f) continue;
      int b = (int)(fabs(a - med) / dw);
      hist[b < GHOST_BINS ? b : GHOST_BINS - 1]++;
    }
  });
  double mad = hist_rank(hist, n / 2, 0.0, dw);
  return med + k * 1.4826 * mad;
}

void elfm_ghost_threshold_apply(const elfm_refocus_plan *p, elfm_volume *vol,
                                const uint32_t *rows, size_t n_rows)
{
  double level = 0.0, v = p->opt.threshold_value;
  switch (p->opt.threshold) {
  case ELFM_GHOST_THR_NONE:
    return;
  case ELFM_GHOST_THR_ABS:
    level = v;
    break;
  case ELFM_GHOST_THR_FRAC_MAX: {
    float mx = 0.0f;
    FOR_RUNS(vol, rows, n_rows, {
      for (size_t i = 0; i < len; i++) {
        float a = fabsf(run[i]);
        if (a > mx) mx = a;
      }
    });
    level = v * mx;
    break;
  }
  case ELFM_GHOST_THR_MAD:
    level = ghost_mad_level(vol, rows, n_rows, v);
    break;
  }
  const float lf = (float)level;
  FOR_RUNS(vol, rows, n_rows, {
    for (size_t i = 0; i < len; i++)
      if (fabsf(run[i]) < lf) run[i] = 0.0f;
  });
}
