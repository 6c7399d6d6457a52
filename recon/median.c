/* median.c — 3x3 / 5x5 median of mostly-zero frames (see elfm_frames.h).
 *
 * The paper cleans its time surfaces with a 3x3 median before refocusing.
 * Two shortcuts make it cost O(listed pixels) instead of O(sensor):
 *  - sorted, a window is negatives, zeros, positives: if fewer than half
 *    (5 of 9, 13 of 25) are positive and fewer than half negative, the
 *    middle one is a zero;
 *  - so each listed pixel adds 1 to the positive or negative count of every
 *    window it lies in (a 16-bit counter per pixel: low byte positive, high
 *    byte negative), and only windows reaching half are sorted. Isolated
 *    noise events never do. The pixels are visited in row order, so the
 *    counters are a ring of `size` rows; each row's are reset through the
 *    list of columns they were raised at.
 * Otherwise 3x3 uses the 19-exchange median network (Paeth, Graphics Gems,
 * "Median finding on a 3x3 grid"), 5x5 an insertion sort of 25.
 */
#include "elfm_frames.h"

#include <stdlib.h>

struct elfm_median {
  int size, w, h;
  /* Rows are finished in order, so only the size rows an input row can
   * reach are live: a ring of `size` rows (row y in slot y % size). */
  uint16_t *count;    /* [size][w] windows' positive (low byte) / negative (high byte) count */
  uint32_t *cand;     /* [size][w + 1] columns whose count was raised, per ring row */
  size_t ncand[5];    /* per ring row */
  uint32_t *row_start; /* [h + 1] counting sort of the listed pixels by row */
  uint32_t *sorted;    /* [w * h] the listed pixels in row order */
};

elfm_status elfm_median_create(int size, int w, int h, elfm_median **out, elfm_error *err)
{
  *out = NULL;
  if (size != 3 && size != 5)
    return elfm_error_set(err, ELFM_ERR_INVALID, NULL, -1, "median size %d: use 3 or 5", size);
  if (w <= 0 || h <= 0)
    return elfm_error_set(err, ELFM_ERR_INVALID, NULL, -1, "median frame size %d x %d", w, h);
  elfm_median *m = calloc(1, sizeof *m);
  size_t n = (size_t)w * (size_t)h;
  if (m) {
    m->count = calloc((size_t)size * (size_t)w, sizeof *m->count);
    /* + 1: the branch-free list writes one past its last entry */
    m->cand = malloc((size_t)size * ((size_t)w + 1) * sizeof *m->cand);
    m->row_start = malloc(((size_t)h + 1) * sizeof *m->row_start);
    m->sorted = malloc(n * sizeof *m->sorted);
  }
  if (!m || !m->count || !m->cand || !m->row_start || !m->sorted) {
    elfm_median_free(m);
    return elfm_error_set(err, ELFM_ERR_NOMEM, NULL, -1, "out of memory (median %d x %d)", w, h);
  }
  m->size = size;
  m->w = w;
  m->h = h;
  *out = m;
  return ELFM_OK;
}

void elfm_median_free(elfm_median *m)
{
  if (!m) return;
  free(m->count);
  free(m->cand);
  free(m->row_start);
  free(m->sorted);
  free(m);
}

/* Compare-exchange as min/max (minss/maxss), not a branch: in a bead's
 * image the order of neighbours is unpredictable. */
#define SORT2(a, b)                                 \
  do {                                              \
    const float lo_ = (a) > (b) ? (b) : (a);        \
    const float hi_ = (a) > (b) ? (a) : (b);        \
    (a) = lo_;                                      \
    (b) = hi_;                                      \
  } while (0)

static float median9(float *p)
{
  SORT2(p[1], p[2]); SORT2(p[4], p[5]); SORT2(p[7], p[8]);
  SORT2(p[0], p[1]); SORT2(p[3], p[4]); SORT2(p[6], p[7]);
  SORT2(p[1], p[2]); SORT2(p[4], p[5]); SORT2(p[7], p[8]);
  SORT2(p[0], p[3]); SORT2(p[5], p[8]); SORT2(p[4], p[7]);
  SORT2(p[3], p[6]); SORT2(p[1], p[4]); SORT2(p[2], p[5]);
  SORT2(p[4], p[7]); SORT2(p[4], p[2]); SORT2(p[6], p[4]);
  SORT2(p[4], p[2]);
  return p[4];
}

static float median_n(float *p, int n)
{
  for (int i = 1; i < n; i++) {
    float v = p[i];
    int j = i - 1;
    while (j >= 0 && p[j] > v) {
      p[j + 1] = p[j];
      j--;
    }
    p[j + 1] = v;
  }
  return p[n / 2];
}

/* 3x3 median at an interior pixel (no padding checks): the common case. */
static float median3_inner(const float *c, int w)
{
  float win[9] = {c[-w - 1], c[-w], c[-w + 1], c[-1], c[0], c[1], c[w - 1], c[w], c[w + 1]};
  int pos = 0, neg = 0;
  for (int i = 0; i < 9; i++) {
    pos += win[i] > 0.0f;
    neg += win[i] < 0.0f;
  }
  if (pos < 5 && neg < 5) return 0.0f;
  return median9(win);
}

/* Median at (x, y) with zero padding. */
static float median_at(const elfm_median *m, const float *img, int x, int y)
{
  if (m->size == 3 && x > 0 && y > 0 && x < m->w - 1 && y < m->h - 1)
    return median3_inner(img + (size_t)y * m->w + x, m->w);
  float win[25];
  const int r = m->size / 2, n = m->size * m->size;
  int pos = 0, neg = 0, k = 0;
  for (int dy = -r; dy <= r; dy++) {
    int yy = y + dy;
    for (int dx = -r; dx <= r; dx++) {
      int xx = x + dx;
      float v = (yy < 0 || yy >= m->h || xx < 0 || xx >= m->w) ? 0.0f
                                                                 : img[(size_t)yy * m->w + xx];
      pos += v > 0.0f;
      neg += v < 0.0f;
      win[k++] = v;
    }
  }
  if (2 * pos < n && 2 * neg < n) return 0.0f;
  return n == 9 ? median9(win) : median_n(win, n);
}

void elfm_median_apply(elfm_median *m, const elfm_frame *in, elfm_frame *out)
{
  elfm_frame_clear_like(out, in);
  if (in->w != m->w || in->h != m->h || out->w != m->w || out->h != m->h) return;
  const int r = m->size / 2, half = (m->size * m->size + 1) / 2;
  /* The listed pixels in row order (a counting sort by row). Each raises
   * the counters of the windows it lies in; row y's counts are complete
   * once input row y + r is in, and are then read and reset, so the counters
   * are a ring of `size` rows that stays in L1 (a full-sensor counter array
   * missed the cache on nearly every pixel: docs/recon.md). */
  const uint32_t W = (uint32_t)m->w, R = (uint32_t)m->size;
  uint32_t *start = m->row_start;
  for (int y = 0; y <= m->h; y++) start[y] = 0;
  for (size_t i = 0; i < in->nnz; i++)
    if (in->idx[i] < W * (uint32_t)m->h) start[in->idx[i] / W + 1]++;
  for (int y = 0; y < m->h; y++) start[y + 1] += start[y];
  for (size_t i = 0; i < in->nnz; i++) {
    const uint32_t pix = in->idx[i];
    if (pix < W * (uint32_t)m->h) m->sorted[start[pix / W]++] = pix;
  }
  /* now row y's pixels are sorted[start[y - 1] .. start[y]) (start[-1] = 0) */
  for (int yi = 0; yi < m->h + r; yi++) {
    if (yi < m->h) {
      const uint32_t i0 = yi ? start[yi - 1] : 0, i1 = start[yi];
      const int ya = yi - r < 0 ? 0 : yi - r, yb = yi + r >= m->h ? m->h - 1 : yi + r;
      for (uint32_t i = i0; i < i1; i++) {
        const uint32_t pix = m->sorted[i];
        const float a = in->data[pix];
        if (a == 0.0f) continue;
        const uint16_t inc = a > 0.0f ? 1 : 256;
        const int x0 = (int)(pix % W);
        const int xa = x0 - r < 0 ? 0 : x0 - r, xb = x0 + r >= m->w ? m->w - 1 : x0 + r;
        for (int y = ya; y <= yb; y++) {
          const size_t slot = (size_t)y % R;
          uint16_t *cnt = m->count + slot * W;
          uint32_t *cand = m->cand + slot * (W + 1);
          size_t nc = m->ncand[slot];
          /* a counter raised from 0 lists its column (no branch: whether a
           * neighbour already raised it is unpredictable) */
          for (int x = xa; x <= xb; x++) {
            cand[nc] = (uint32_t)x;
            nc += cnt[x] == 0;
            cnt[x] = (uint16_t)(cnt[x] + inc);
          }
          m->ncand[slot] = nc;
        }
      }
    }
    const int yo = yi - r; /* complete: read, reset, take the medians */
    if (yo < 0) continue;
    const size_t slot = (size_t)yo % R;
    uint16_t *cnt = m->count + slot * W;
    const uint32_t *cand = m->cand + slot * (W + 1);
    for (size_t j = 0; j < m->ncand[slot]; j++) {
      const uint32_t x = cand[j];
      const uint16_t k = cnt[x];
      cnt[x] = 0;
      if ((k & 0xff) < half && (k >> 8) < half) continue;
      const float v = median_at(m, in->data, (int)x, yo);
      if (v != 0.0f) {
        const uint32_t c = (uint32_t)yo * W + x;
        out->data[c] = v;
        out->idx[out->nnz++] = c;
      }
    }
    m->ncand[slot] = 0;
  }
}
