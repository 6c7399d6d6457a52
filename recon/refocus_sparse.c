/* refocus_sparse.c — the event-sparse refocus path: scatter the frame's
 * non-zero pixels onto the planes, the adjoint of the dense bilinear gather
 * (see elfm_refocus.h), touching only the volume rows (and columns) reached.
 *
 * Pixel u of view v lands on voxel X = u - ix with weight 1 - fx and on
 * X - 1 with weight fx (rows likewise). Event frames come in short runs of
 * neighbouring pixels (a bead's image is a few pixels wide), so the scatter
 * is done per run: a run of n pixels covers voxels X0 - 1 .. X0 + n - 1,
 * each receiving (1 - fx) * a[i] + fx * a[i + 1] from the zero-padded run,
 * a short contiguous loop the compiler vectorises instead of 4 scattered
 * adds per pixel.
 *
 * The workspace remembers the rows and column extents it wrote, so the
 * next call clears only those (a 144 x 144 x 101 volume is 8.4 MB: clearing
 * it whole would cost more than refocusing a typical 1 ms frame).
 */
#include "refocus_internal.h"

#include <limits.h>
#include <stddef.h>
#include <stdlib.h>
#include <string.h>

/* Start a call: when the volume is not the one this workspace last wrote
 * sparsely (or was written densely), clear it whole; otherwise keep the
 * previous call's rows in rows_old, to be cleared plane by plane just
 * before each plane is scattered (the plane is then in cache once). */
static size_t sparse_begin(const elfm_refocus_plan *p, elfm_volume *vol, elfm_refocus_workspace *ws)
{
  size_t n_old = 0;
  if (ws->dirty_data != vol->data || ws->dirty_all) {
    const size_t nvox = (size_t)p->w * p->h * p->nz;
    memset(vol->data, 0, nvox * sizeof *vol->data);
    for (size_t i = 0; i < ws->n_rows; i++) ws->row_dirty[ws->rows[i]] = 0;
  } else {
    uint32_t *t = ws->rows_old;
    ws->rows_old = ws->rows;
    ws->rows = t;
    n_old = ws->n_rows;
  }
  ws->n_rows = 0;
  ws->dirty_data = vol->data;
  ws->dirty_all = 0;
  return n_old;
}

/* Clear the previous call's rows of plane k: rows_old[*at ..] in plane order. */
static void sparse_clear_plane(const elfm_refocus_plan *p, elfm_volume *vol,
                               elfm_refocus_workspace *ws, int k, size_t *at, size_t n_old)
{
  const size_t W = (size_t)p->w, H = (size_t)p->h;
  for (; *at < n_old && ws->rows_old[*at] / H == (size_t)k; (*at)++) {
    const size_t r = ws->rows_old[*at], lo = (size_t)ws->row_lo[r];
    const size_t n = (size_t)(ws->row_hi[r] - ws->row_lo[r]);
    memset(vol->data + r * W + lo, 0, n * sizeof *vol->data);
    ws->row_dirty[r] = 0;
  }
}

static int grow(void **buf, size_t *cap, size_t need, size_t elem)
{
  if (need <= *cap) return 1;
  size_t c = *cap;
  while (c < need) c *= 2;
  void *b = realloc(*buf, c * elem);
  if (!b) return 0;
  *buf = b;
  *cap = c;
  return 1;
}

/* Sort a row's n distinct columns in place: insertion sort for the usual
 * handful, otherwise through a bit per sensor column (bits[], all zero on
 * entry and on return): set, then read back in order. A busy row (several
 * beads across its 5 views at ~20 Mev/s) has dozens of pixels, where a
 * comparison sort was a tenth of the sparse path under perf. */
static void sort_cols(uint32_t *a, size_t n, uint64_t *bits)
{
  if (n <= 16) {
    for (size_t i = 1; i < n; i++) {
      uint32_t v = a[i];
      size_t j = i;
      while (j > 0 && a[j - 1] > v) {
        a[j] = a[j - 1];
        j--;
      }
      a[j] = v;
    }
    return;
  }
  uint32_t lo = UINT32_MAX, hi = 0;
  for (size_t i = 0; i < n; i++) {
    bits[a[i] >> 6] |= (uint64_t)1 << (a[i] & 63);
    if (a[i] < lo) lo = a[i];
    if (a[i] > hi) hi = a[i];
  }
  size_t k = 0;
  for (uint32_t w = lo >> 6; w <= hi >> 6; w++) {
    uint64_t b = bits[w];
    bits[w] = 0;
    while (b) {
      a[k++] = (w << 6) + (uint32_t)__builtin_ctzll(b);
      b &= b - 1;
    }
  }
}

/* Sort the listed non-zero pixels by row (counting sort) and column, then
 * cut each view's rows into runs, view by view (one view's runs then hit
 * the same plane rows together, which keeps them in cache). */
static elfm_status sparse_runs(const elfm_refocus_plan *p, const elfm_frame *frame,
                               elfm_refocus_workspace *ws, elfm_error *err)
{
  const uint32_t SW = (uint32_t)p->sw;
  uint32_t *start = ws->row_start;
  memset(start, 0, ((size_t)p->sh + 1) * sizeof *start);
  size_t n = 0;
  for (size_t i = 0; i < frame->nnz; i++)
    if (frame->data[frame->idx[i]] != 0.0f) {
      start[frame->idx[i] / SW + 1]++;
      n++;
    }
  if (!grow((void **)&ws->sorted, &ws->cap_sorted, n, sizeof *ws->sorted))
    return elfm_error_set(err, ELFM_ERR_NOMEM, NULL, -1, "out of memory (%zu pixels)", n);
  for (int y = 0; y < p->sh; y++) start[y + 1] += start[y];
  /* place: start[y] runs ahead while filling, then is restored */
  for (size_t i = 0; i < frame->nnz; i++) {
    uint32_t pix = frame->idx[i];
    if (frame->data[pix] != 0.0f) ws->sorted[start[pix / SW]++] = pix % SW;
  }
  for (int y = p->sh; y > 0; y--) start[y] = start[y - 1];
  start[0] = 0;
  for (int y = 0; y < p->sh; y++) {
    size_t a = start[y], b = start[y + 1];
    if (b - a > 1) sort_cols(ws->sorted + a, b - a, ws->row_bits);
  }
  ws->n_runs = 0;
  ws->n_vals = 0;
  for (int v = 0; v < p->nv; v++) {
    const elfm_refocus_box *bx = &p->box[v];
    for (int y = bx->y0; y < bx->y1; y++) {
      size_t a = start[y], b = start[y + 1];
      const float *row = frame->data + (size_t)y * SW;
      for (size_t i = a; i < b;) {
        uint32_t c0 = ws->sorted[i];
        if ((int)c0 < bx->x0) { i++; continue; }
        if ((int)c0 >= bx->x1) break;
        size_t j = i + 1;
        while (j < b && ws->sorted[j] == ws->sorted[j - 1] + 1 && (int)ws->sorted[j] < bx->x1) j++;
        int len = (int)(j - i);
        if (!grow((void **)&ws->runs, &ws->cap_runs, ws->n_runs + 1, sizeof *ws->runs) ||
            !grow((void **)&ws->vals, &ws->cap_vals, ws->n_vals + (size_t)len + 2, sizeof *ws->vals))
          return elfm_error_set(err, ELFM_ERR_NOMEM, NULL, -1, "out of memory (runs)");
        elfm_refocus_run *r = &ws->runs[ws->n_runs++];
        r->view = v;
        r->row = y;
        r->c0 = (int)c0;
        r->n = len;
        r->off = ws->n_vals;
        float *o = ws->vals + ws->n_vals;
        o[0] = 0.0f;
        memcpy(o + 1, row + c0, (size_t)len * sizeof *o);
        o[len + 1] = 0.0f;
        ws->n_vals += (size_t)len + 2;
        i = j;
      }
    }
  }
  return ELFM_OK;
}

static inline void mark_row(elfm_refocus_workspace *ws, uint32_t r, int lo, int hi)
{
  if (!ws->row_dirty[r]) {
    ws->row_dirty[r] = 1;
    ws->rows[ws->n_rows++] = r;
    ws->row_lo[r] = lo;
    ws->row_hi[r] = hi;
  } else {
    if (lo < ws->row_lo[r]) ws->row_lo[r] = lo;
    if (hi > ws->row_hi[r]) ws->row_hi[r] = hi;
  }
}

/* Agreement, step 1: each view's support map from the runs. A pixel at box
 * position (c, y) is a tap of the voxels whose first tap is (c - 1 .. c,
 * y - 1 .. y), so a run of n pixels sets n + 1 bytes on two rows. Taking
 * both taps regardless of the plane's weights gives a superset of the views
 * that see signal (a tap of weight 0, fx = 0, adds nothing): the exact count
 * is taken in step 3. */
static void agree_support(const elfm_refocus_plan *p, elfm_refocus_workspace *ws)
{
  for (int v = 0; v < p->nv; v++) {
    ws->sup_ylo[v] = INT_MAX;
    ws->sup_yhi[v] = 0;
  }
  for (size_t t = 0; t < ws->n_runs; t++) {
    const elfm_refocus_run *run = &ws->runs[t];
    const int v = run->view;
    const elfm_refocus_box *bx = &p->box[v];
    const int bw = bx->x1 - bx->x0;
    const size_t stride = (size_t)bw + 2 * (size_t)p->w;
    const int y = run->row - bx->y0;
    int c = run->c0 - bx->x0 - 1;
    int n = run->n + 1;
    if (c < 0) {
      c = 0;
      n--;
    }
    /* the box's last column is never a first tap (both taps lie in the
     * box): it stays 0, like the zero margins */
    if (c + n > bw - 1) n = bw - 1 - c;
    uint8_t *m = ws->sup + ws->sup_off[v] + (size_t)p->w + (size_t)c;
    uint8_t *rf = ws->sup_row + ws->sup_row_off[v];
    if (n > 0) memset(m + (size_t)y * stride, 1, (size_t)n);
    rf[y] = 1;
    const int ya = y > 0 ? y - 1 : 0;
    if (y > 0) {
      if (n > 0) memset(m + (size_t)(y - 1) * stride, 1, (size_t)n);
      rf[y - 1] = 1;
    }
    if (ya < ws->sup_ylo[v]) ws->sup_ylo[v] = ya;
    if (y + 1 > ws->sup_yhi[v]) ws->sup_yhi[v] = y + 1;
  }
}

/* Agreement, end of call: zero the rows of the maps this call set. */
static void agree_support_clear(const elfm_refocus_plan *p, elfm_refocus_workspace *ws)
{
  for (int v = 0; v < p->nv; v++) {
    if (ws->sup_ylo[v] >= ws->sup_yhi[v]) continue;
    const elfm_refocus_box *bx = &p->box[v];
    const size_t bw = (size_t)(bx->x1 - bx->x0), stride = bw + 2 * (size_t)p->w;
    uint8_t *m = ws->sup + ws->sup_off[v] + (size_t)p->w; /* margins stay 0 */
    for (int y = ws->sup_ylo[v]; y < ws->sup_yhi[v]; y++) memset(m + (size_t)y * stride, 0, bw);
    memset(ws->sup_row + ws->sup_row_off[v] + ws->sup_ylo[v], 0,
           (size_t)(ws->sup_yhi[v] - ws->sup_ylo[v]));
  }
}

/* Agreement, step 2 on one row: cnt[X] = sum over the n >= 1 views of
 * src[j][X], X = 0..W-1. Adding view by view into cnt makes every view's
 * add wait for the previous view's store to the same bytes (store-to-load
 * forwarding, ~5 cycles: it was the hottest instruction under perf); with
 * AVX2 a 32-byte block is summed over all views in a register and stored
 * once. The blocks read up to 31 bytes past src[j] + W and write up to 31
 * past cnt + W (both buffers are padded for it, refocus.c). */
#if defined(__x86_64__) && defined(__GNUC__)
#include <immintrin.h>
__attribute__((target("avx2")))
static void agree_count_row_avx2(uint8_t *cnt, const uint8_t *const *src, int n, int W)
{
  for (int q = 0; q < W; q += 32) {
    __m256i acc = _mm256_loadu_si256((const __m256i *)(const void *)(src[0] + q));
    for (int j = 1; j < n; j++)
      acc = _mm256_add_epi8(acc, _mm256_loadu_si256((const __m256i *)(const void *)(src[j] + q)));
    _mm256_storeu_si256((__m256i *)(void *)(cnt + q), acc);
  }
}
#define ELFM_HAVE_AVX2_PATH 1
#endif

static inline void agree_count_row(uint8_t *cnt, const uint8_t *const *src, int n, int W, int avx2)
{
#ifdef ELFM_HAVE_AVX2_PATH
  if (avx2) {
    agree_count_row_avx2(cnt, src, n, W);
    return;
  }
#else
  (void)avx2;
#endif
  if (n < 1) return;
  memcpy(cnt, src[0], (size_t)W);
  for (int j = 1; j < n; j++)
    for (int i = 0; i < W; i++) cnt[i] = (uint8_t)(cnt[i] + src[j][i]);
}

/* Agreement, steps 2 and 3 with AVX2 on one row (plane k, row Y), the
 * scalar steps fused so that nothing is a loop over the row's W voxels:
 * the count is compared with `need` 32 voxels at a time into a bit mask of
 * candidates; then the gather takes 8 voxels X0 .. X0 + 7 from the lowest
 * candidate X0 on, summed over all the listed views in registers (a row's
 * candidates are ~7 voxels in one or two clusters, over ~23 views at
 * ~20 Mev/s: one candidate at a time, with a load-add-store of its sum per
 * view, was half of agree_plane under perf), and stores the kept voxels
 * with one masked store.
 * Lanes outside a view's [xlo, xhi) are masked loads: 0 and never read, so
 * they add exactly 0, as the view not sampling them does in the dense path.
 * The arithmetic is the dense path's, in its order (AVX2 has no FMA): the
 * same floats. wv[j][4] are the bilinear weights of list[j]; pass[] holds
 * (W + 31) / 32 words. Reads up to 31
 * bytes past the row in `need`, `count` and the maps (all padded). Widens [*lo, *hi) by the kept voxels. */
#ifdef ELFM_HAVE_AVX2_PATH
__attribute__((target("avx2")))
static void agree_row_avx2(const elfm_refocus_plan *p, const elfm_refocus_shift *sk,
                           const uint8_t *list, const float (*wv)[4],
                           const uint8_t *const *src, int n, const float *frame, int Y,
                           const uint8_t *need, const uint8_t *count, uint32_t *pass,
                           float *row, int *lo, int *hi)
{
  const int W = p->w;
  const size_t SW = (size_t)p->sw;
  /* step 2: counts and the candidate mask, 32 voxels per block */
  const int nb = (W + 31) / 32;
  uint32_t any = 0;
  for (int b = 0; b < nb; b++) {
    const int q = 32 * b;
    __m256i acc = _mm256_loadu_si256((const __m256i *)(const void *)(src[0] + q));
    for (int j = 1; j < n; j++)
      acc = _mm256_add_epi8(acc, _mm256_loadu_si256((const __m256i *)(const void *)(src[j] + q)));
    const __m256i nd = _mm256_loadu_si256((const __m256i *)(const void *)(need + q));
    /* cnt >= need (unsigned) and cnt != 0 */
    const __m256i ge = _mm256_cmpeq_epi8(_mm256_max_epu8(acc, nd), acc);
    const __m256i nz = _mm256_xor_si256(_mm256_cmpeq_epi8(acc, _mm256_setzero_si256()),
                                        _mm256_set1_epi8(-1));
    uint32_t m = (uint32_t)_mm256_movemask_epi8(_mm256_and_si256(ge, nz));
    if (W - q < 32) m &= (1u << (W - q)) - 1u;
    pass[b] = m;
    any |= m;
  }
  if (!any) return;
  /* step 3: gather 8 voxels from each lowest candidate left */
  const __m256i lane = _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7);
  const __m256i bit = _mm256_setr_epi32(1, 2, 4, 8, 16, 32, 64, 128);
  for (int b = 0; b < nb;) {
    if (!pass[b]) { b++; continue; }
    const int X0 = 32 * b + __builtin_ctz(pass[b]);
    /* the lanes' candidate bits, X0 .. X0 + 7 (may cross into block b + 1) */
    uint64_t bits = pass[b] >> (X0 - 32 * b);
    if (b + 1 < nb) bits |= (uint64_t)pass[b + 1] << (32 - (X0 - 32 * b));
    bits &= 0xFFu;
    const __m256i xv = _mm256_add_epi32(_mm256_set1_epi32(X0), lane);
    __m256 sum = _mm256_setzero_ps();
    __m256i seen = _mm256_setzero_si256();
    for (int j = 0; j < n; j++) {
      const elfm_refocus_shift *s = sk + list[j];
      if (s->xlo >= X0 + 8 || s->xhi <= X0) continue;
      /* the first tap of lane 0 */
      const float *r0 = frame + (size_t)(Y + s->iy) * SW;
      const float *r1 = r0 + SW;
      const ptrdiff_t u = (ptrdiff_t)X0 + s->ix;
      __m256 a00, a01, a10, a11;
      if (s->xlo <= X0 && X0 + 8 <= s->xhi) { /* all lanes sampled: the usual case */
        a00 = _mm256_loadu_ps(r0 + u);
        a01 = _mm256_loadu_ps(r0 + u + 1);
        a10 = _mm256_loadu_ps(r1 + u);
        a11 = _mm256_loadu_ps(r1 + u + 1);
      } else { /* a masked lane's address is never read */
        const __m256i m = _mm256_and_si256(_mm256_cmpgt_epi32(xv, _mm256_set1_epi32(s->xlo - 1)),
                                           _mm256_cmpgt_epi32(_mm256_set1_epi32(s->xhi), xv));
        a00 = _mm256_maskload_ps(r0 + u, m);
        a01 = _mm256_maskload_ps(r0 + u + 1, m);
        a10 = _mm256_maskload_ps(r1 + u, m);
        a11 = _mm256_maskload_ps(r1 + u + 1, m);
      }
      __m256 a = _mm256_add_ps(_mm256_mul_ps(_mm256_set1_ps(wv[j][0]), a00),
                               _mm256_mul_ps(_mm256_set1_ps(wv[j][1]), a01));
      a = _mm256_add_ps(a, _mm256_mul_ps(_mm256_set1_ps(wv[j][2]), a10));
      a = _mm256_add_ps(a, _mm256_mul_ps(_mm256_set1_ps(wv[j][3]), a11));
      sum = _mm256_add_ps(sum, a);
      /* a != 0 is all ones (-1) in the lane: subtracting it counts one */
      seen = _mm256_sub_epi32(seen, _mm256_castps_si256(_mm256_cmp_ps(a, _mm256_setzero_ps(), _CMP_NEQ_UQ)));
    }
    /* kept: a candidate lane whose non-zero samples reach need[X]; the
     * value is the mean over the views sampling the voxel, 1 / count[X]
     * from the plan's table */
    const __m256i cand = _mm256_cmpeq_epi32(_mm256_and_si256(_mm256_set1_epi32((int)bits), bit), bit);
    const __m256i nd = _mm256_cvtepu8_epi32(_mm_loadl_epi64((const __m128i *)(const void *)(need + X0)));
    const __m256i ci = _mm256_cvtepu8_epi32(_mm_loadl_epi64((const __m128i *)(const void *)(count + X0)));
    const __m256i keep = _mm256_andnot_si256(_mm256_cmpgt_epi32(nd, seen), cand);
    const __m256 val = _mm256_mul_ps(sum, _mm256_i32gather_ps(p->inv_table, ci, 4));
    _mm256_maskstore_ps(row + X0, keep, val);
    const unsigned kb = (unsigned)_mm256_movemask_ps(_mm256_castsi256_ps(keep));
    if (kb) {
      if (X0 + __builtin_ctz(kb) < *lo) *lo = X0 + __builtin_ctz(kb);
      *hi = X0 + 32 - __builtin_clz(kb);
    }
    /* drop the candidates X0 .. X0 + 7 */
    const int e = X0 + 8;
    for (int q = b; q < nb && 32 * q < e; q++) {
      const int drop = e - 32 * q; /* bits [0, drop) of block q */
      pass[q] &= drop >= 32 ? 0u : ~((1u << drop) - 1u);
    }
  }
}
#endif

/* Agreement on plane k, row by row.
 * Step 2: add the views' support rows (shifted by the plane's integer
 * shift) into a byte count per voxel: ~W/16 vector adds per view and row,
 * instead of a loop per run of pixels, plane and tap row.
 * Step 3: voxels whose count reaches the plan's `need` are candidates; for
 * those only, the dense path's gather in its view order and arithmetic
 * (views whose map is 0 there have an exactly-0 sample and are skipped), and
 * its rule: kept when at least `need` samples are non-zero. So the result is
 * the dense path's, voxel for voxel. */
#if defined(__x86_64__) && defined(__GNUC__) && defined(__linux__)
/* the byte adds are 16 bytes per SSE2 instruction, 32 with AVX2 (picked at
 * load time when the CPU has it; AVX2 has no FMA, so the arithmetic is the
 * same) */
__attribute__((target_clones("avx2", "default")))
#endif
static void agree_plane(const elfm_refocus_plan *p, const elfm_frame *frame, elfm_volume *vol,
                        elfm_refocus_workspace *ws, int k, int avx2)
{
  const int W = p->w, H = p->h, nv = p->nv;
  const size_t SW = (size_t)p->sw;
  const elfm_refocus_shift *sk = p->shift + (size_t)k * nv;
  uint8_t *cnt = ws->plane_cnt, *pass = ws->plane_cnt + W;
  /* per view on this plane: sampled rows [ylo, yhi), where row Y's "any"
   * flag and map row start (agreement is on: nv <= 32, plan) */
  int ylo[32], yhi[32];
  ptrdiff_t flag_at[32], map_at[32], map_stride[32];
  float wk[32][4]; /* bilinear weights, as the dense path computes them */
  for (int v = 0; v < nv; v++) {
    const elfm_refocus_shift *s = sk + v;
    wk[v][0] = (1.0f - s->fx) * (1.0f - s->fy);
    wk[v][1] = s->fx * (1.0f - s->fy);
    wk[v][2] = (1.0f - s->fx) * s->fy;
    wk[v][3] = s->fx * s->fy;
    const elfm_refocus_box *bx = &p->box[v];
    ylo[v] = s->ylo;
    yhi[v] = s->xlo < s->xhi ? s->yhi : s->ylo;
    /* row Y is box row Y + iy - y0, in [0, box height - 1) for sampled Y */
    flag_at[v] = (ptrdiff_t)ws->sup_row_off[v] + s->iy - bx->y0;
    map_stride[v] = (ptrdiff_t)(bx->x1 - bx->x0) + 2 * (ptrdiff_t)W;
    map_at[v] = (ptrdiff_t)ws->sup_off[v] + (ptrdiff_t)(s->iy - bx->y0) * map_stride[v] + W +
                (s->ix - bx->x0);
  }
  /* per row, the views whose map row has signal, in view order: built view
   * by view over the rows where its map has any (no branch per view and
   * row: which one has signal is unpredictable) */
  uint8_t *lists = ws->agree_list;
  int *nlist = ws->agree_n;
  memset(nlist, 0, (size_t)H * sizeof *nlist);
  for (int v = 0; v < nv; v++) {
    if (ws->sup_ylo[v] >= ws->sup_yhi[v]) continue; /* no signal in this view */
    const elfm_refocus_shift *s = sk + v;
    const elfm_refocus_box *bx = &p->box[v];
    int y0 = ylo[v], y1 = yhi[v];
    const int off = bx->y0 - s->iy; /* box row y is volume row y + off */
    if (y0 < ws->sup_ylo[v] + off) y0 = ws->sup_ylo[v] + off;
    if (y1 > ws->sup_yhi[v] + off) y1 = ws->sup_yhi[v] + off;
    for (int Y = y0; Y < y1; Y++) {
      lists[(size_t)Y * 32 + (size_t)nlist[Y]] = (uint8_t)v;
      nlist[Y] += ws->sup_row[flag_at[v] + Y] != 0;
    }
  }
  for (int Y = 0; Y < H; Y++) {
    const size_t r = (size_t)k * (size_t)H + (size_t)Y;
    /* too few views with signal for any voxel of the row to reach `need` */
    const int n = nlist[Y];
    const uint8_t *list = lists + (size_t)Y * 32;
    if (n < p->need_row_min[r]) continue;
    /* the whole row X = 0..W-1 of each view, not [xlo, xhi): the maps'
     * zero margins (W wide) and zero last column give 0 outside [xlo, xhi)
     * (bench_refocus on flow: 3.5 -> 2.9 ms CPU per volume with this) */
    const uint8_t *src[32];
    float wl[32][4];
    for (int j = 0; j < n; j++) {
      src[j] = ws->sup + (map_at[list[j]] + (ptrdiff_t)Y * map_stride[list[j]]);
      memcpy(wl[j], wk[list[j]], sizeof wl[j]);
    }
    const uint8_t *need = p->need + r * (size_t)W;
#ifdef ELFM_HAVE_AVX2_PATH
    if (avx2) {
      int lo = W, hi = 0;
      agree_row_avx2(p, sk, list, wl, src, n, frame->data, Y, need, p->count + r * (size_t)W,
                     (uint32_t *)(void *)ws->agree_cand,
                     vol->data + r * (size_t)W, &lo, &hi);
      if (lo < hi) mark_row(ws, (uint32_t)r, lo, hi);
      continue;
    }
#endif
    agree_count_row(cnt, src, n, W, avx2);
    uint8_t hit = 0;
    for (int X = 0; X < W; X++) {
      const uint8_t ok = (uint8_t)((cnt[X] >= need[X]) & (cnt[X] != 0));
      pass[X] = ok;
      hit |= ok;
    }
    if (!hit) continue;
    /* the candidates of the row, then the gather view by view over them
     * (one view's weights and frame rows for the whole row) */
    int32_t *cand = ws->agree_cand;
    float *sum = ws->agree_sum;
    uint8_t *seen = pass; /* pass[] is read into cand[] first */
    int nc = 0;
    for (int X = 0; X < W; X++) { /* no branch: pass[X] is unpredictable */
      cand[nc] = X;
      nc += pass[X];
    }
    float *row = vol->data + r * (size_t)W;
    const uint8_t *count = p->count + r * (size_t)W;
    int lo = W, hi = 0;
    for (int c = 0; c < nc; c++) {
      sum[c] = 0.0f;
      seen[c] = 0;
    }
    /* views not in the list have exactly-0 samples on this row (their map
     * row is empty) or do not sample it; the list is in view order */
    for (int j = 0; j < n; j++) {
      const elfm_refocus_shift *s = sk + list[j];
      const float w00 = (1.0f - s->fx) * (1.0f - s->fy), w01 = s->fx * (1.0f - s->fy);
      const float w10 = (1.0f - s->fx) * s->fy, w11 = s->fx * s->fy;
      const float *r0 = frame->data + (size_t)(Y + s->iy) * SW;
      const float *r1 = r0 + SW;
      /* cand[] is sorted: the view samples cand[c0 .. c1) */
      int c0 = 0, c1 = nc;
      while (c0 < c1 && cand[c0] < s->xlo) c0++;
      while (c1 > c0 && cand[c1 - 1] >= s->xhi) c1--;
      for (int c = c0; c < c1; c++) {
        const int X = cand[c];
        const int u = X + s->ix; /* both taps in the crop box (plan) */
        const float a = w00 * r0[u] + w01 * r0[u + 1] + w10 * r1[u] + w11 * r1[u + 1];
        sum[c] += a;
        seen[c] = (uint8_t)(seen[c] + (a != 0.0f));
      }
    }
    for (int c = 0; c < nc; c++) {
      const int X = cand[c];
      if (seen[c] < need[X]) continue;
      row[X] = sum[c] * p->inv_table[count[X]];
      if (X < lo) lo = X;
      hi = X + 1;
    }
    if (lo < hi) mark_row(ws, (uint32_t)r, lo, hi);
  }
}

elfm_status elfm_refocus_sparse(const elfm_refocus_plan *p, const elfm_frame *frame,
                                elfm_volume *vol, elfm_refocus_workspace *ws, elfm_error *err)
{
  elfm_status st = sparse_runs(p, frame, ws, err);
  if (st) return st;
  const size_t n_old = sparse_begin(p, vol, ws);
  size_t old_at = 0;
  if (p->need) {
    agree_support(p, ws);
#ifdef ELFM_HAVE_AVX2_PATH
    const int avx2 = __builtin_cpu_supports("avx2");
#else
    const int avx2 = 0;
#endif
    for (int k = 0; k < p->nz; k++) {
      sparse_clear_plane(p, vol, ws, k, &old_at, n_old);
      agree_plane(p, frame, vol, ws, k, avx2);
    }
    agree_support_clear(p, ws);
    elfm_ghost_threshold_apply(p, vol, ws->rows, ws->n_rows);
    return ELFM_OK;
  }
  const int W = p->w, H = p->h;
  const elfm_refocus_run *runs = ws->runs;
  const size_t nr = ws->n_runs;
  for (int k = 0; k < p->nz; k++) {
    sparse_clear_plane(p, vol, ws, k, &old_at, n_old);
    const size_t first_row = ws->n_rows;
    const elfm_refocus_shift *sk = p->shift + (size_t)k * p->nv;
    float *plane = vol->data + (size_t)k * W * H;
    for (size_t t = 0; t < nr; t++) {
      const elfm_refocus_run *run = &runs[t];
      const elfm_refocus_shift *s = sk + run->view;
      /* voxel Xs + i receives (1 - fx) b[i] + fx b[i + 1], i = 0..n */
      const int Xs = run->c0 - s->ix - 1;
      int i0 = s->xlo - Xs, i1 = s->xhi - Xs; /* [i0, i1) keeps X in [xlo, xhi) */
      if (i0 < 0) i0 = 0;
      if (i1 > run->n + 1) i1 = run->n + 1;
      if (i0 >= i1) continue;
      const float *b = ws->vals + run->off;
      const float gx0 = 1.0f - s->fx, gx1 = s->fx;
      for (int dy = 0; dy < 2; dy++) {
        const int Y = run->row - s->iy - dy;
        if (Y < s->ylo || Y >= s->yhi) continue;
        const float wy = dy ? s->fy : 1.0f - s->fy;
        if (wy == 0.0f) continue; /* an integer row shift: one row only */
        const float w0 = wy * gx0, w1 = wy * gx1;
        const uint32_t r = (uint32_t)k * (uint32_t)H + (uint32_t)Y;
        mark_row(ws, r, Xs + i0, Xs + i1);
        const int m = i1 - i0;
        const float *bb = b + i0;
        float *o = plane + (size_t)Y * W + (size_t)(Xs + i0);
        for (int i = 0; i < m; i++) o[i] += w0 * bb[i] + w1 * bb[i + 1];
      }
    }
    /* while the plane is in cache: the mean over sampling views.
     * 1/count through a 256-entry table: the counts are 2 MB of bytes,
     * a float inverse per voxel would be 8.4 MB of memory traffic */
    for (size_t i = first_row; i < ws->n_rows; i++) {
      const size_t r = ws->rows[i];
      float *row = vol->data + r * W;
      const uint8_t *cnt = p->count + r * W;
      for (int X = ws->row_lo[r]; X < ws->row_hi[r]; X++) row[X] *= p->inv_table[cnt[X]];
    }
  }
  elfm_ghost_threshold_apply(p, vol, ws->rows, ws->n_rows);
  return ELFM_OK;
}
