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

typedef struct elfm_refocus_box {
  int x0, y0, x1, y1; /* sensor pixels [x0, x1) x [y0, y1) */
} elfm_refocus_box;

struct elfm_refocus_plan {
  elfm_calib calib;
  elfm_refocus_options opt;
  int w, h, nz, nv, sw, sh;
  double box_area;            /* sum of crop box areas, px */
  elfm_refocus_box *box;      /* [nv] */
  elfm_refocus_shift *shift;  /* [k * nv + v] */
  float *inv_count;           /* [k][Y][X]: 1 / views sampling, 0 if none */
  uint8_t *count;             /* [k][Y][X]: views sampling */
  uint8_t *need;              /* [k][Y][X]: views that must agree, NULL if off */
};

/* One (view, pixel) pair of the sparse path. */
typedef struct elfm_refocus_tap {
  int u, v;  /* sensor column, row */
  float a;   /* pixel value */
  int view;
} elfm_refocus_tap;

struct elfm_refocus_workspace {
  const elfm_refocus_plan *plan;
  elfm_refocus_path last_path;
  /* dense */
  uint8_t *plane_cnt;         /* [W*H] agreeing views on one plane */
  /* sparse */
  elfm_refocus_tap *taps;
  size_t n_taps, cap_taps;
  uint8_t *vox_cnt;           /* [nz*H*W] agreeing views (agreement on) */
  uint8_t *vox_last;          /* [nz*H*W] last view + 1 that counted */
  uint8_t *row_dirty;         /* [nz*H] */
  uint32_t *rows;             /* dirty rows k*H + Y */
  size_t n_rows;
  const float *dirty_data;    /* volume data the dirty rows refer to */
  int dirty_all;              /* that volume may be non-zero anywhere */
};

/* ghost.c: the view-agreement rule on one row of W voxels (plane k, row Y):
 * zero voxels whose agreeing views cnt[X] < need. */
void elfm_ghost_agree_row(const elfm_refocus_plan *p, int k, int Y, float *row,
                          const uint8_t *cnt);
/* ghost.c: the plan's threshold on the rows (k*H + Y) of vol, or on the
 * whole volume when rows == NULL. */
void elfm_ghost_threshold_apply(const elfm_refocus_plan *p, elfm_volume *vol,
                                const uint32_t *rows, size_t n_rows);

/* refocus_sparse.c */
elfm_status elfm_refocus_sparse(const elfm_refocus_plan *p, const elfm_frame *frame,
                                elfm_volume *vol, elfm_refocus_workspace *ws, elfm_error *err);

#endif
