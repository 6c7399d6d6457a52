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
 * The plain path (sparse_scatter) sums each block of plane rows in the
 * workspace and streams it into the volume whole. The agreement path
 * writes into the volume itself: the workspace remembers the rows and
 * column extents written, so that the next call clears only those (a
 * 144 x 144 x 101 volume is 8.4 MB: clearing it whole would cost more than
 * refocusing a typical 1 ms frame).
 */
#include "refocus_internal.h"

#include <stddef.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#if defined(__SSE2__)
#include <emmintrin.h>
#endif

/* Eight floats, operated on lane by lane (GCC's vector extension), loaded
 * and stored unaligned through memcpy. Passed by pointer: by value they
 * would change the ABI between sparse_scatter's targets. */
typedef float v8f __attribute__((vector_size(32)));

/* o[i] += w0[i] b0[i] + w1[i] b1[i], i < 8: the scalar loop's products and
 * sums, in its order */
__attribute__((always_inline)) static inline void add8(float *o, const v8f *w0, const v8f *b0,
                                                      const v8f *w1, const v8f *b1)
{
  v8f acc;
  memcpy(&acc, o, sizeof acc);
  acc += *w0 * *b0 + *w1 * *b1;
  memcpy(o, &acc, sizeof acc);
}

/* Plane rows per block of the scatter (elfm_refocus_sparse): the rows'
 * written flags live on the stack, and the block is summed in the
 * workspace's plane. bench_refocus on flow 1 s, 1 thread, 101 planes: 96
 * rows 1.99-2.05, 48 2.09-2.19, 32 2.32-2.62 ms per volume (docs/recon.md
 * "Planes streamed into the volume"). Summed in the volume itself, earlier,
 * ms per volume over 4 alternating runs (before the groups of four): 16
 * rows 5.5-5.6, 32 5.3-5.4, 48 4.87-4.94, 64 4.92-5.01, 96 4.65-4.89, a
 * whole 144-row plane 4.74-4.85. */
#define SPARSE_BLOCK_ROWS 96

/* Start a call. writes_all: the call writes every voxel (sparse_scatter),
 * so the previous call's rows are only forgotten. Otherwise (the
 * agreement path), when the volume is not the one this workspace last
 * wrote sparsely (or was written densely), clear it whole; else keep the
 * previous call's rows in rows_old, to be cleared plane by plane just
 * before each plane is written (the plane is then in cache once). */
static size_t sparse_begin(const elfm_refocus_plan *p, elfm_volume *vol, elfm_refocus_workspace *ws,
                           int writes_all)
{
  size_t n_old = 0;
  if (writes_all || ws->dirty_data != vol->data || ws->dirty_all) {
    const size_t nvox = (size_t)p->w * p->h * p->nz;
    if (!writes_all) memset(vol->data, 0, nvox * sizeof *vol->data);
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
 * the same plane rows together, which keeps them in cache). Pixels up to
 * gap_px apart join one run, zeros between them (see
 * ELFM_REFOCUS_MERGE_GAP_PX). */
static elfm_status sparse_runs(const elfm_refocus_plan *p, const elfm_frame *frame, uint32_t gap_px,
                               elfm_refocus_workspace *ws, elfm_error *err)
{
  const uint32_t SW = (uint32_t)p->sw;
  uint32_t *start = ws->row_start;
  memset(start, 0, ((size_t)p->sh + 1) * sizeof *start);
  /* a deep window's older pixels (below the floor) are not the window's:
   * left out, and 0 where a run spans them */
  const float fl = frame->recent_floor;
  const size_t n_list = elfm_frame_n_window(frame); /* the older ones after */
  size_t n = 0;
  for (size_t i = 0; i < n_list; i++) {
    const float v = frame->data[frame->idx[i]];
    if (v != 0.0f && elfm_frame_in_window(frame, v)) {
      start[frame->idx[i] / SW + 1]++;
      n++;
    }
  }
  if (!grow((void **)&ws->sorted, &ws->cap_sorted, n, sizeof *ws->sorted))
    return elfm_error_set(err, ELFM_ERR_NOMEM, NULL, -1, "out of memory (%zu pixels)", n);
  for (int y = 0; y < p->sh; y++) start[y + 1] += start[y];
  /* place: start[y] runs ahead while filling, then is restored */
  for (size_t i = 0; i < n_list; i++) {
    uint32_t pix = frame->idx[i];
    const float v = frame->data[pix];
    if (v != 0.0f && elfm_frame_in_window(frame, v)) ws->sorted[start[pix / SW]++] = pix % SW;
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
    uint32_t *vr = ws->vrow + p->vrow_off[v] - bx->y0; /* indexed by box row */
    for (int y = bx->y0; y < bx->y1; y++) {
      vr[y] = (uint32_t)ws->n_runs;
      size_t a = start[y], b = start[y + 1];
      const float *row = frame->data + (size_t)y * SW;
      for (size_t i = a; i < b;) {
        uint32_t c0 = ws->sorted[i];
        if ((int)c0 < bx->x0) { i++; continue; }
        if ((int)c0 >= bx->x1) break;
        size_t j = i + 1;
        while (j < b && ws->sorted[j] <= ws->sorted[j - 1] + 1 + gap_px && (int)ws->sorted[j] < bx->x1) j++;
        int len = (int)(ws->sorted[j - 1] - c0 + 1); /* the frame is 0 in the gaps */
        if (!grow((void **)&ws->runs, &ws->cap_runs, ws->n_runs + 1, sizeof *ws->runs) ||
            !grow((void **)&ws->vals, &ws->cap_vals, ws->n_vals + (size_t)len + 2 + ELFM_RUN_PAD,
                  sizeof *ws->vals))
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
        for (int z = 1; z <= 1 + ELFM_RUN_PAD; z++) o[len + z] = 0.0f;
        if (fl > 0)
          for (int z = 1; z <= len; z++)
            if (o[z] < fl) o[z] = 0.0f;
        ws->n_vals += (size_t)len + 2 + ELFM_RUN_PAD;
        i = j;
      }
    }
    if (bx->y1 > bx->y0) vr[bx->y1] = (uint32_t)ws->n_runs;
  }
  return ELFM_OK;
}

/* dst[0 .. n) = src[0 .. n), with non-temporal stores where the CPU has
 * them (SSE2: every x86-64). Such stores write whole cache lines to memory
 * without reading them first; the caller ends its run of them with
 * _mm_sfence. */
static void stream_floats(float *restrict dst, const float *restrict src, size_t n)
{
#if defined(__SSE2__)
  size_t i = 0;
  for (; i < n && ((uintptr_t)(dst + i) & 15); i++) dst[i] = src[i];
  for (; i + 4 <= n; i += 4) _mm_stream_ps(dst + i, _mm_loadu_ps(src + i));
  for (; i < n; i++) dst[i] = src[i];
#else
  memcpy(dst, src, n * sizeof *dst);
#endif
}

/* The plain path's planes (no agreement rule). On x86-64 Linux it is built
 * twice, for AVX2 and for any x86-64 (SSE2), and the loader picks one; the
 * source is the same, and its vectors of 8 are one instruction with AVX2,
 * two without. */
#if defined(__x86_64__) && defined(__GNUC__) && defined(__linux__)
__attribute__((target_clones("avx2", "default")))
#endif
static void sparse_scatter(const elfm_refocus_plan *p, elfm_volume *vol, elfm_refocus_workspace *ws)
{
  const int W = p->w, H = p->h;
  const elfm_refocus_run *runs = ws->runs;
  for (int k = 0; k < p->nz; k++) {
    const elfm_refocus_shift *sk = p->shift + (size_t)k * p->nv;
    /* The scatter sums into the workspace's plane, which stays in cache
     * (83 kB at the paper's geometry), and each block of rows is then
     * streamed into the volume whole, zeros included, by non-temporal
     * stores. Summed in the volume itself, each plane's rows were first
     * cleared there: a write to lines last touched a frame-ring ago,
     * which the CPU reads from memory before writing. Those reads were
     * 3-18 % of `track`'s samples under perf, from run to run of the same
     * command (the machine's other work sharing its memory); the stores
     * stream without them. `track` on flow 1 s seed 1, 2 threads, 11
     * pairs: 0.856 of the wall time of the summing in the volume, and
     * 0.929 of streaming by plain stores (memcpy), which read the lines
     * as the clearing did (docs/recon.md "Planes streamed into the
     * volume"). The dense path, which gathers every view into every
     * voxel, gained nothing from the same (bench_refocus --path dense:
     * 18.4-20.2 ms per volume against 18.6-20.9) and clears and sums in
     * the volume itself. */
    float *plane = ws->scatter_plane;
    float *vplane = vol->data + (size_t)k * W * H;
    const float *vals = ws->vals;
    /* A block of plane rows at a time, view by view: each view takes only
     * its runs on the box rows that reach the block (vrow). Which rows were
     * written is kept on the stack, a flag per row, and each such row is
     * marked once with the columns some view samples there (the plan's
     * samp_lo, samp_hi): the written columns are most of a row anyway
     * (below), and a flag stored per run and tap row is cheaper than the
     * written columns' bounds, a load and a compare each, which took ~10 %
     * of the sparse path (bench_refocus on flow 1 s, 1 thread, 6 runs of
     * each alternating: 1.86-2.01 against 2.10-2.29 ms per volume; the
     * zeros the wider rows scale and clear included). Each
     * voxel still receives its views in the same order (view, then the
     * upper tap row before the lower), so the sums are the same floats as
     * one pass over all the runs per plane, which paid the bounds of every
     * run, including those whose rows miss the plane at this depth, and the
     * row bookkeeping per run and tap row (docs/recon.md "Views by rows
     * that reach the plane"). */
    for (int Yb = 0; Yb < H; Yb += SPARSE_BLOCK_ROWS) {
      const int Ye = Yb + SPARSE_BLOCK_ROWS < H ? Yb + SPARSE_BLOCK_ROWS : H;
      unsigned char wrote[SPARSE_BLOCK_ROWS];
      memset(wrote, 0, sizeof wrote);
      for (int v = 0; v < p->nv; v++) {
        const elfm_refocus_shift *s = sk + v;
        const int ya = Yb > s->ylo ? Yb : s->ylo, yb = Ye < s->yhi ? Ye : s->yhi;
        if (ya >= yb) continue;
        const elfm_refocus_box *bx = &p->box[v];
        /* plane row Y takes box rows Y + iy (upper tap) and Y + iy + 1 */
        int ra = ya + s->iy, rb = yb + s->iy + 1;
        if (ra < bx->y0) ra = bx->y0;
        if (rb > bx->y1) rb = bx->y1;
        if (ra >= rb) continue;
        const uint32_t *vr = ws->vrow + p->vrow_off[v] - bx->y0;
        const float gx0 = 1.0f - s->fx, gx1 = s->fx;
        /* the two tap rows' weights, upper row (1 - fy) and lower fy, times
         * the two columns' (1 - fx and fx) */
        const float wa = 1.0f - s->fy, wb = s->fy;
        const float a0 = wa * gx0, a1 = wa * gx1, c0 = wb * gx0, c1 = wb * gx1;
        const v8f va0 = {a0, a0, a0, a0, a0, a0, a0, a0}, va1 = {a1, a1, a1, a1, a1, a1, a1, a1};
        const v8f vc0 = {c0, c0, c0, c0, c0, c0, c0, c0}, vc1 = {c1, c1, c1, c1, c1, c1, c1, c1};
        for (uint32_t t = vr[ra]; t < vr[rb]; t++) {
          const elfm_refocus_run *run = &runs[t];
          /* voxel Xs + i receives (1 - fx) b[i] + fx b[i + 1], i = 0..n */
          const int Xs = run->c0 - s->ix - 1;
          int i0 = s->xlo - Xs, i1 = s->xhi - Xs; /* [i0, i1) keeps X in [xlo, xhi) */
          if (i0 < 0) i0 = 0;
          if (i1 > run->n + 1) i1 = run->n + 1;
          if (i0 >= i1) continue;
          const float *b = vals + run->off;
          /* Both tap rows in one pass where both are in the block and
           * weighed, in groups of eight (below): each group of the run's
           * values is loaded once for the two rows. Every voxel gets the
           * same products and sums as from the loop over dy, and from the
           * runs in the same order (the two rows are other voxels). */
          const int Y0 = run->row - s->iy;
          const int m8 = (i1 - i0 + 7) & ~7;
          if (Y0 - 1 >= ya && Y0 < yb && wa != 0.0f && wb != 0.0f && i1 == run->n + 1 &&
              Xs + i0 + m8 <= W) {
            wrote[Y0 - 1 - Yb] = wrote[Y0 - Yb] = 1;
            const float *bb = b + i0;
            float *oa = plane + (size_t)Y0 * W + (size_t)(Xs + i0), *oc = oa - W;
            for (int i = 0; i < m8; i += 8) {
              v8f b0, b1;
              memcpy(&b0, bb + i, sizeof b0);
              memcpy(&b1, bb + i + 1, sizeof b1);
              add8(oa + i, &va0, &b0, &va1, &b1);
              add8(oc + i, &vc0, &b0, &vc1, &b1);
            }
            continue;
          }
          for (int dy = 0; dy < 2; dy++) {
            const int Y = run->row - s->iy - dy;
            if (Y < ya || Y >= yb) continue;
            if ((dy ? wb : wa) == 0.0f) continue; /* an integer row shift: one row only */
            wrote[Y - Yb] = 1;
            const int m = i1 - i0;
            const float *bb = b + i0;
            float *o = plane + (size_t)Y * W + (size_t)(Xs + i0);
            /* Eight voxels at a time, the last group running past the run
             * onto its padding zeros: those voxels get + 0, their own value.
             * Not where the run is cut at xhi (the values go on there), nor
             * past the row's end. The same products and sums in the same
             * order as the loop below, so the same floats (neither target
             * has FMA to contract them into); the loop's vectorised body
             * with its scalar tail cost more on runs of ~8 (bench_refocus on
             * flow 1 s: 4.78-4.82 -> 4.46-4.70 ms per volume, 4 at a time);
             * m8 is m rounded up to the group. */
            if (i1 == run->n + 1 && Xs + i0 + m8 <= W) {
              const v8f v0 = dy ? vc0 : va0, v1 = dy ? vc1 : va1;
              for (int i = 0; i < m8; i += 8) {
                v8f b0, b1;
                memcpy(&b0, bb + i, sizeof b0);
                memcpy(&b1, bb + i + 1, sizeof b1);
                add8(o + i, &v0, &b0, &v1, &b1);
              }
              continue;
            }
            const float w0 = dy ? c0 : a0, w1 = dy ? c1 : a1;
            for (int i = 0; i < m; i++) o[i] += w0 * bb[i] + w1 * bb[i + 1];
          }
        }
      }
      /* The mean over sampling views, row by row in memory order, each
       * voxel times its row's 1 / count (the plan's inv_rows), in a loop
       * the compiler vectorises. The runs write most of each row (flow
       * 1 s: 107 of 144 columns on 7,319 of 7,344 plane rows per frame),
       * about half of it where not every view samples. Scaled there through the
       * 256-entry table one voxel at a time (a count and a table entry
       * loaded per voxel), `track` on flow 1 s took 1.08 times the CPU it
       * took with these rows (docs/recon.md "One over the count, a row at
       * a time"). The same products, so the same floats. */
      for (int Y = Yb; Y < Ye; Y++) {
        if (!wrote[Y - Yb]) continue;
        const uint32_t r = (uint32_t)k * (uint32_t)H + (uint32_t)Y;
        const int lo = p->samp_lo[r], hi = p->samp_hi[r];
        elfm_refocus_mark_row(ws, r, lo, hi);
        float *row = plane + (size_t)Y * W;
        const float *inv = p->inv_rows + p->inv_row_off[r];
        for (int X = lo; X < hi; X++) row[X] *= inv[X];
      }
      /* the block into the volume, and its written rows back to zero (the
       * unwritten ones are zero still) */
      stream_floats(vplane + (size_t)Yb * W, plane + (size_t)Yb * W, (size_t)(Ye - Yb) * W);
      for (int Y = Yb; Y < Ye; Y++)
        if (wrote[Y - Yb]) memset(plane + (size_t)Y * W, 0, (size_t)W * sizeof *plane);
    }
  }
#if defined(__SSE2__)
  _mm_sfence(); /* the streamed stores before the volume is handed on */
#endif
}

elfm_status elfm_refocus_sparse(const elfm_refocus_plan *p, const elfm_frame *frame,
                                elfm_volume *vol, elfm_refocus_workspace *ws, elfm_error *err)
{
  /* the agreement rule reads each run as signal: its runs stay exact */
  elfm_status st = sparse_runs(p, frame, p->need ? 0 : ws->merge_gap_px, ws, err);
  if (st) return st;
  if (p->need) {
    const size_t n_old = sparse_begin(p, vol, ws, 0);
    size_t old_at = 0;
    /* the view-agreement rule: refocus_agree.c, which reads the frame
     * itself (not a deep window's: track's, where the rule is off) */
    if (frame->recent_floor > 0)
      return elfm_error_set(err, ELFM_ERR_INVALID, NULL, -1,
                            "the view-agreement rule takes no deep window's frames");
    elfm_agree_support(p, ws);
    const int avx2 = elfm_agree_avx2(ws);
    for (int k = 0; k < p->nz; k++) {
      sparse_clear_plane(p, vol, ws, k, &old_at, n_old);
      elfm_agree_plane(p, frame, vol, ws, k, avx2);
    }
    elfm_agree_support_clear(p, ws);
    elfm_ghost_threshold_apply(p, vol, ws->rows, ws->n_rows);
    return ELFM_OK;
  }
  sparse_begin(p, vol, ws, 1);
  sparse_scatter(p, vol, ws);
  elfm_ghost_threshold_apply(p, vol, ws->rows, ws->n_rows);
  return ELFM_OK;
}
