/* refocus_internal.h — the refocus plan and workspace layouts, shared by
 * refocus.c (plan, dense path), refocus_sparse.c and ghost.c. Not public. */
#ifndef ELFM_REFOCUS_INTERNAL_H
#define ELFM_REFOCUS_INTERNAL_H

#include "elfm_refocus.h"

/* Geometry of view v on plane k: voxel X samples sensor columns X + ix and
 * X + ix + 1 with weights 1 - fx and fx (rows likewise); it does so for
 * X in [xlo, xhi) and Y in [ylo, yhi), where both taps lie in the crop box. */
typedef struct elfm_refocus_shift {
  int ix, iy;
  float fx, fy;
  int xlo, xhi, ylo, yhi; /* empty when lo >= hi */
} elfm_refocus_shift;

/* The bilinear weights of tap (0,0), (0,1), (1,0), (1,1) (row, column):
 * every path computes them here, so that their sums are the same floats
 * (the sparse agreement path keeps exactly the dense path's voxels). */
static inline void elfm_refocus_shift_weights(const elfm_refocus_shift *s, float w[4])
{
  w[0] = (1.0f - s->fx) * (1.0f - s->fy);
  w[1] = s->fx * (1.0f - s->fy);
  w[2] = (1.0f - s->fx) * s->fy;
  w[3] = s->fx * s->fy;
}

typedef struct elfm_refocus_box {
  int x0, y0, x1, y1; /* sensor pixels [x0, x1) x [y0, y1) */
} elfm_refocus_box;

struct elfm_refocus_plan {
  elfm_calib calib;
  elfm_refocus_options opt;
  int w, h, nz, nv, sw, sh;
  double box_area;            /* sum of crop box areas, px */
  elfm_refocus_box *box;      /* [nv] */
  uint8_t *in_boxes;          /* [sh][sw]: the crop boxes holding the pixel (at most 255),
                                 for elfm_refocus_occupancy */
  elfm_refocus_shift *shift;  /* [k * nv + v] */
  uint8_t *count;             /* [k][Y][X]: views sampling */
  float inv_table[256];       /* 1 / n, 0 for n = 0 */
  /* [k * h + Y]: where that plane row's 1 / count (inv_table of each
   * voxel's count) starts in inv_rows. A row's counts change only where a
   * view's rows begin or end, so the rows of a plane share a few such rows
   * (at most 2 nv + 1), and inv_rows stays small enough to stay in cache.
   * The paths scale a row by it in a loop the compiler vectorises. */
  size_t *inv_row_off;
  float *inv_rows;
  /* [k * h + Y]: the columns [samp_lo, samp_hi) of that plane row some
   * view samples (empty: 0, 0) */
  int32_t *samp_lo, *samp_hi;
  /* [nv]: where view v's box rows (and one end mark) start in the sparse
   * workspace's run index by row (vrow), n_vrow in all */
  size_t *vrow_off, n_vrow;
  uint8_t *need;              /* [k][Y][X]: views that must agree, NULL if off */
  uint8_t *need_row_min;      /* [k][Y]: least non-zero `need` of the row (255: none) */
  /* [k][Y][b][need_words]: bit b of each voxel's `need`, 63 where no view
   * samples it (the sparse path's bit-sliced compare, refocus_agree.c);
   * + 4 words of padding at the end; NULL if off */
  uint64_t *need_bits;
  size_t need_words;          /* ceil(W / 64) */
};

/* Runs of one view's row with at most this many zero pixels between them
 * are scattered as one. A time-surface frame's runs are short (flow at 12.5 Mev/s: 5,600
 * pixels in 2,600 runs per 1 ms window), and each run costs its bounds and
 * row bookkeeping on every plane; adding a few zeros in a vectorised loop
 * is cheaper. The sums are the same bits: a voxel between two runs gets
 * w0 a + w1 0 either way, and the rows' dirty extents already span the
 * gaps. bench_refocus, flow 1 s seed 1, 1 thread: 5.3-5.5 ms per volume at
 * 0 (runs as they come), 4.6-4.7 at 16, 4.2-4.3 at 32, 4.5 at 64, 4.5-4.7
 * for a whole view row (docs/recon.md "Runs joined across gaps"). The
 * workspace holds it (merge_gap_px) so that a test can compare 0. */
#define ELFM_REFOCUS_MERGE_GAP_PX 32u

/* A run of pixels of one sensor row inside one view's crop box (sparse
 * path): consecutive non-zero ones, and the zeros of gaps up to
 * merge_gap_px between them. Its values sit at vals[off + 1 .. off + n], with a
 * zero on each side (vals[off] and vals[off + n + 1], then ELFM_RUN_PAD more
 * zeros for the scatter's groups of eight) so that the scatter of
 * the run is a short gather over n + 1 voxels without edge cases. */
#define ELFM_RUN_PAD 8
typedef struct elfm_refocus_run {
  int view, row, c0, n;
  size_t off;
} elfm_refocus_run;

struct elfm_refocus_workspace {
  const elfm_refocus_plan *plan;
  elfm_refocus_path last_path;
  /* dense */
  uint8_t *plane_cnt;         /* [W*H] agreeing views on one plane */
  float *window_img;          /* [sw*sh] a deep window's frame, its window's pixels only
                               * (made on first use; all zero between calls) */
  /* sparse: the frame's listed pixels sorted by row, then cut into runs */
  uint32_t *row_start;        /* [sh + 1] counting sort by sensor row */
  uint64_t *row_bits;         /* [(sw + 63) / 64] one sensor row's columns, a bit each;
                               * all zero between uses */
  uint32_t *sorted;           /* [cap_sorted] columns, grouped by row */
  size_t cap_sorted;
  elfm_refocus_run *runs;
  size_t n_runs, cap_runs;
  /* view v's runs of box row y are runs[vrow[p->vrow_off[v] + y - y0] ..
   * vrow[p->vrow_off[v] + y - y0 + 1]) (sparse_runs makes them view by view,
   * row by row), so a plane takes only the rows that reach it */
  uint32_t *vrow;             /* [p->n_vrow] */
  float *vals;
  size_t n_vals, cap_vals;
  /* agreement on (refocus_agree.c): per view, a bit map over its crop box,
   * bit c of box row y at bit sup_bit[v] + y sup_stride_bits[v] + c of
   * sup, set where a voxel whose first tap is there could see signal
   * (either tap column or row is a listed pixel: the frame's support
   * dilated by the 2 x 2 tap footprint). Rows are packed (stride: the box
   * width rounded up to bytes), with >= W zero bits before the first map
   * and >= 256 ceil(W / 256) + 128 after the last one, which the windows
   * read across. All zero between calls (cleared at the end of each). */
  uint64_t *sup;
  size_t *sup_bit;            /* [nv] */
  size_t *sup_stride_bits;    /* [nv] */
  int *sup_ylo, *sup_yhi;     /* [nv] box rows [lo, hi) touched this call */
  uint64_t *agree_win;        /* [32][agree_win_ld] one row's view windows, 32-byte aligned */
  size_t agree_win_ld;        /* 4 ceil(W / 256) + 4 words */
  uint64_t *agree_mask;       /* [33][agree_win_ld] a plane's views' sampled voxels [xlo, xhi),
                               * then the voxels X < W; 32-byte aligned */
  uint64_t *agree_candw;      /* [agree_win_ld] one row's candidates, a bit per voxel */
  /* tests only (through this header): 1 runs the portable agreement code
   * even where AVX2 is available; the result is the same */
  int agree_portable;
  uint32_t merge_gap_px;      /* ELFM_REFOCUS_MERGE_GAP_PX; tests set 0 */
  uint8_t *row_dirty;         /* [nz*H] */
  int32_t *row_lo, *row_hi;   /* [nz*H] written columns [lo, hi) of a dirty row */
  uint32_t *rows;             /* dirty rows k*H + Y, in plane order */
  size_t n_rows;
  uint32_t *rows_old;         /* the previous call's rows while they are cleared */
  const float *dirty_data;    /* volume data the dirty rows refer to */
  int dirty_all;              /* that volume may be non-zero anywhere */
  float *scatter_plane;       /* [W*H] the sparse scatter's plane, all zero between its blocks */
};

/* ghost.c: the view-agreement rule on one row of W voxels (plane k, row Y):
 * zero voxels whose agreeing views cnt[X] < need. */
void elfm_ghost_agree_row(const elfm_refocus_plan *p, int k, int Y, float *row,
                          const uint8_t *cnt);
/* ghost.c: the plan's threshold on the rows (k*H + Y) of vol, or on the
 * whole volume when rows == NULL. */
void elfm_ghost_threshold_apply(const elfm_refocus_plan *p, elfm_volume *vol,
                                const uint32_t *rows, size_t n_rows);

/* Remember that row r (k*H + Y) was written in columns [lo, hi). */
static inline void elfm_refocus_mark_row(elfm_refocus_workspace *ws, uint32_t r, int lo, int hi)
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

/* refocus_agree.c: the agreement rule on the sparse path. Support maps
 * from ws->runs (start of call), plane k's kept voxels, maps cleared (end
 * of call); avx2 from elfm_agree_avx2 (0: the portable code). */
void elfm_agree_support(const elfm_refocus_plan *p, elfm_refocus_workspace *ws);
void elfm_agree_support_clear(const elfm_refocus_plan *p, elfm_refocus_workspace *ws);
int elfm_agree_avx2(const elfm_refocus_workspace *ws);
void elfm_agree_plane(const elfm_refocus_plan *p, const elfm_frame *frame, elfm_volume *vol,
                      elfm_refocus_workspace *ws, int k, int avx2);

/* refocus_sparse.c */
elfm_status elfm_refocus_sparse(const elfm_refocus_plan *p, const elfm_frame *frame,
                                elfm_volume *vol, elfm_refocus_workspace *ws, elfm_error *err);

#endif
