/* refocus.c — refocus plan, workspace and the dense (gather) path
 * (see elfm_refocus.h; the sparse path is refocus_sparse.c, ghosts ghost.c).
 */
#include "refocus_internal.h"

#include "big_alloc.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

void elfm_refocus_options_default(elfm_refocus_options *o)
{
  memset(o, 0, sizeof *o);
  o->path = ELFM_PATH_AUTO;
  /* bench_refocus on flow (docs/recon.md): sparse costs ~0.8 us of CPU per
   * listed pixel (11k pixels: 9 ms), dense ~20 ms whatever the frame, so
   * they cross near 25k pixels, 5 % of the 25 crop boxes (533k px). */
  o->sparse_max_fill = 0.05;
  o->crop_margin_px = 0;
  o->threshold = ELFM_GHOST_THR_NONE;
  o->threshold_value = 0.0;
  /* View agreement removed far more ghosts than any threshold at equal
   * recall on simulated flow and stage (tests/test_recon_sim --study,
   * docs/recon.md): 0.3 of the views (7-8 of 25) must see signal. */
  o->agree_frac = 0.3;
}

void elfm_refocus_plan_free(elfm_refocus_plan *p)
{
  if (!p) return;
  free(p->box);
  free(p->in_boxes);
  free(p->shift);
  free(p->count);
  free(p->inv_row_off);
  free(p->inv_rows);
  free(p->samp_lo);
  free(p->samp_hi);
  free(p->vrow_off);
  free(p->need);
  free(p->need_row_min);
  free(p->need_bits);
  free(p);
}

static int imax(int a, int b) { return a > b ? a : b; }
static int imin(int a, int b) { return a < b ? a : b; }

/* Whether plane row r (k * h + Y) needs inverses of its own: the first
 * row of a plane, or counts other than those of the row above. */
static int row_counts_new(const elfm_refocus_plan *p, size_t r)
{
  const size_t W = (size_t)p->w;
  return r % (size_t)p->h == 0 || memcmp(p->count + r * W, p->count + (r - 1) * W, W) != 0;
}

/* Each plane row's 1 / count (inv_row_off, inv_rows: refocus_internal.h):
 * a row whose counts equal those of the row above shares its inverses.
 * Returns nonzero when out of memory. */
static int plan_inverse_rows(elfm_refocus_plan *p)
{
  const size_t W = (size_t)p->w, H = (size_t)p->h;
  size_t n = 0;
  for (size_t r = 0; r < H * (size_t)p->nz; r++) n += (size_t)row_counts_new(p, r);
  p->inv_rows = malloc(n * W * sizeof *p->inv_rows);
  if (!p->inv_rows) return 1;
  size_t at = 0;
  for (size_t r = 0; r < H * (size_t)p->nz; r++) {
    if (row_counts_new(p, r)) {
      for (size_t X = 0; X < W; X++) p->inv_rows[at + X] = p->inv_table[p->count[r * W + X]];
      at += W;
    }
    p->inv_row_off[r] = at - W;
    const uint8_t *cnt = p->count + r * W;
    int lo = 0, hi = (int)W;
    while (lo < hi && !cnt[lo]) lo++;
    while (hi > lo && !cnt[hi - 1]) hi--;
    p->samp_lo[r] = lo < hi ? lo : 0;
    p->samp_hi[r] = lo < hi ? hi : 0;
  }
  return 0;
}

elfm_status elfm_refocus_plan_create(const elfm_calib *c, const elfm_refocus_options *opt,
                                     elfm_refocus_plan **out, elfm_error *err)
{
  *out = NULL;
  elfm_refocus_options o;
  if (opt) o = *opt;
  else elfm_refocus_options_default(&o);
  if ((unsigned)o.path > ELFM_PATH_SPARSE)
    return elfm_error_set(err, ELFM_ERR_INVALID, NULL, -1, "unknown refocus path %d", (int)o.path);
  if (!(o.sparse_max_fill >= 0.0) || !isfinite(o.sparse_max_fill))
    return elfm_error_set(err, ELFM_ERR_INVALID, NULL, -1, "sparse_max_fill must be >= 0");
  if (o.crop_margin_px < 0 || o.crop_margin_px > 1000)
    return elfm_error_set(err, ELFM_ERR_INVALID, NULL, -1, "crop margin %d px outside 0..1000",
                          o.crop_margin_px);
  if (!(o.agree_frac >= 0.0 && o.agree_frac <= 1.0))
    return elfm_error_set(err, ELFM_ERR_INVALID, NULL, -1, "agree_frac must be in [0, 1]");
  if ((unsigned)o.threshold > ELFM_GHOST_THR_MAD || !isfinite(o.threshold_value) ||
      o.threshold_value < 0.0)
    return elfm_error_set(err, ELFM_ERR_INVALID, NULL, -1,
                          "ghost threshold mode %d with value %g is invalid", (int)o.threshold,
                          o.threshold_value);
  if (c->n_views <= 0 || c->n_views > ELFM_MAX_VIEWS || c->n_views > 254)
    return elfm_error_set(err, ELFM_ERR_INVALID, NULL, -1, "calibration has %d views", c->n_views);
  /* The sparse path keeps a row's views in 32-bit masks and counts them in
   * 6 bit planes (refocus_agree.c). */
  if (o.agree_frac > 0.0 && c->n_views > 32)
    return elfm_error_set(err, ELFM_ERR_UNSUPPORTED, NULL, -1,
                          "the view-agreement rule handles up to 32 views (calibration has %d): "
                          "set agree_frac to 0", c->n_views);
  if (c->view_w_px <= 0 || c->view_h_px <= 0 || c->view_w_px > 8192 || c->view_h_px > 8192 ||
      c->sensor_width_px <= 0 || c->sensor_height_px <= 0)
    return elfm_error_set(err, ELFM_ERR_INVALID, NULL, -1,
                          "calibration view %d x %d / sensor %d x %d is invalid", c->view_w_px,
                          c->view_h_px, c->sensor_width_px, c->sensor_height_px);
  if (!(c->z_step_um > 0.0) || !isfinite(c->z_min_um) || !(c->z_max_um >= c->z_min_um))
    return elfm_error_set(err, ELFM_ERR_INVALID, NULL, -1, "calibration z range is invalid");
  int nz = elfm_calib_n_planes(c);
  if (nz <= 0 || nz > 4096)
    return elfm_error_set(err, ELFM_ERR_INVALID, NULL, -1, "%d z planes (1..4096)", nz);

  elfm_refocus_plan *p = calloc(1, sizeof *p);
  if (!p) return elfm_error_set(err, ELFM_ERR_NOMEM, NULL, -1, "out of memory (plan)");
  p->calib = *c;
  p->opt = o;
  p->w = c->view_w_px;
  p->h = c->view_h_px;
  p->nz = nz;
  p->nv = c->n_views;
  p->sw = c->sensor_width_px;
  p->sh = c->sensor_height_px;
  size_t nvox = (size_t)p->w * p->h * nz;
  p->box = calloc((size_t)p->nv, sizeof *p->box);
  p->shift = calloc((size_t)p->nv * nz, sizeof *p->shift);
  /* + 32: the sparse path's AVX2 code reads a row's need and count 8
   * bytes at a time from any voxel on, up to 7 past the end of the row */
  p->count = calloc(nvox + 32, 1);
  p->inv_row_off = calloc((size_t)p->h * (size_t)nz, sizeof *p->inv_row_off);
  p->samp_lo = calloc((size_t)p->h * (size_t)nz, sizeof *p->samp_lo);
  p->samp_hi = calloc((size_t)p->h * (size_t)nz, sizeof *p->samp_hi);
  p->vrow_off = calloc((size_t)p->nv, sizeof *p->vrow_off);
  p->in_boxes = calloc((size_t)p->sw * (size_t)p->sh, 1);
  if (o.agree_frac > 0.0) {
    p->need = calloc(nvox + 32, 1);
    p->need_row_min = calloc((size_t)p->h * (size_t)nz, 1);
    p->need_words = ((size_t)p->w + 63) / 64;
    p->need_bits = calloc((size_t)p->h * (size_t)nz * 6 * p->need_words + 4, sizeof *p->need_bits);
  }
  if (!p->box || !p->shift || !p->count || !p->inv_row_off || !p->samp_lo || !p->samp_hi ||
      !p->vrow_off || !p->in_boxes ||
      (o.agree_frac > 0.0 && (!p->need || !p->need_row_min || !p->need_bits))) {
    elfm_refocus_plan_free(p);
    return elfm_error_set(err, ELFM_ERR_NOMEM, NULL, -1, "out of memory (plan, %zu voxels)", nvox);
  }
  const double hw = 0.5 * (p->w - 1), hh = 0.5 * (p->h - 1);
  for (int v = 0; v < p->nv; v++) {
    const elfm_view *vw = &c->views[v];
    if (!isfinite(vw->cx_px) || !isfinite(vw->cy_px) || !isfinite(vw->dx_px_per_um) ||
        !isfinite(vw->dy_px_per_um) || fabs(vw->cx_px) > 1e6 || fabs(vw->cy_px) > 1e6) {
      elfm_refocus_plan_free(p);
      return elfm_error_set(err, ELFM_ERR_INVALID, NULL, -1, "view %d of the calibration is not finite", v);
    }
    /* The crop box holds both taps of every voxel at focus: columns
     * floor(cx - hw) .. floor(cx + hw) + 1. */
    elfm_refocus_box *b = &p->box[v];
    double x0 = floor(vw->cx_px - hw) - o.crop_margin_px, y0 = floor(vw->cy_px - hh) - o.crop_margin_px;
    double x1 = floor(vw->cx_px + hw) + 2 + o.crop_margin_px, y1 = floor(vw->cy_px + hh) + 2 + o.crop_margin_px;
    b->x0 = (int)fmax(0.0, x0);
    b->y0 = (int)fmax(0.0, y0);
    b->x1 = (int)fmin((double)p->sw, x1);
    b->y1 = (int)fmin((double)p->sh, y1);
    if (b->x1 < b->x0) b->x1 = b->x0;
    if (b->y1 < b->y0) b->y1 = b->y0;
    p->box_area += (double)(b->x1 - b->x0) * (b->y1 - b->y0);
    /* The bounds in locals: stores through a uint8_t pointer may alias
     * anything, so with b->x1 or s->xhi in the loop test the compiler
     * reloads it per byte and does not vectorise (these two loops were 70 %
     * of the plan's time under perf, 10 % of a 50 ms `track`). */
    const int bx0 = b->x0, bx1 = b->x1;
    for (int y = b->y0; y < b->y1; y++) {
      uint8_t *q = p->in_boxes + (size_t)y * (size_t)p->sw;
      for (int x = bx0; x < bx1; x++) q[x] += q[x] < 255;
    }
    p->vrow_off[v] = p->n_vrow;
    p->n_vrow += (size_t)(b->y1 - b->y0) + 1;
    for (int k = 0; k < nz; k++) {
      double z = c->z_min_um + k * c->z_step_um;
      double ox = vw->cx_px - hw + z * vw->dx_px_per_um;
      double oy = vw->cy_px - hh + z * vw->dy_px_per_um;
      elfm_refocus_shift *s = &p->shift[(size_t)k * p->nv + v];
      double fix = floor(ox), fiy = floor(oy);
      if (fabs(fix) > 1e7 || fabs(fiy) > 1e7) { /* so far off the sensor it samples nothing */
        s->xlo = s->xhi = s->ylo = s->yhi = 0;
        continue;
      }
      s->ix = (int)fix;
      s->iy = (int)fiy;
      s->fx = (float)(ox - fix);
      s->fy = (float)(oy - fiy);
      s->xlo = imax(0, b->x0 - s->ix);
      s->xhi = imin(p->w, b->x1 - 1 - s->ix);
      s->ylo = imax(0, b->y0 - s->iy);
      s->yhi = imin(p->h, b->y1 - 1 - s->iy);
      if (s->xhi < s->xlo) s->xhi = s->xlo;
      if (s->yhi < s->ylo) s->yhi = s->ylo;
      const int xlo = s->xlo, xhi = s->xhi;
      for (int Y = s->ylo; Y < s->yhi; Y++) {
        uint8_t *row = p->count + ((size_t)k * p->h + Y) * p->w;
        for (int X = xlo; X < xhi; X++) row[X]++;
      }
    }
  }
  p->inv_table[0] = 0.0f;
  for (int n = 1; n < 256; n++) p->inv_table[n] = 1.0f / (float)n;
  if (plan_inverse_rows(p)) {
    elfm_refocus_plan_free(p);
    return elfm_error_set(err, ELFM_ERR_NOMEM, NULL, -1, "out of memory (plan's 1 / count rows)");
  }
  if (p->need)
    for (size_t i = 0; i < nvox; i++) {
      int n = (int)ceil(o.agree_frac * p->count[i] - 1e-9);
      p->need[i] = (uint8_t)(n < 1 && p->count[i] ? 1 : n);
    }
  if (p->need)
    for (size_t r = 0; r < (size_t)p->h * (size_t)nz; r++) {
      /* the sparse path skips a row where fewer views have signal than
       * this: no voxel of the row can pass */
      uint8_t m = 255;
      for (size_t X = 0; X < (size_t)p->w; X++) {
        const uint8_t q = p->need[r * (size_t)p->w + X];
        if (q && q < m) m = q;
      }
      p->need_row_min[r] = m;
      uint64_t *nb = p->need_bits + r * 6 * p->need_words;
      for (size_t X = 0; X < (size_t)p->w; X++) {
        const size_t i = r * (size_t)p->w + X;
        const unsigned q = p->count[i] ? p->need[i] : 63u; /* 63 > 32 views: never reached */
        for (int b = 0; b < 6; b++)
          nb[(size_t)b * p->need_words + X / 64] |= (uint64_t)((q >> b) & 1u) << (X % 64);
      }
    }
  *out = p;
  return ELFM_OK;
}

void elfm_refocus_plan_size(const elfm_refocus_plan *p, int *w, int *h, int *nz)
{
  if (w) *w = p->w;
  if (h) *h = p->h;
  if (nz) *nz = p->nz;
}

int elfm_refocus_plan_views_at(const elfm_refocus_plan *p, int X, int Y, int k)
{
  if (X < 0 || Y < 0 || k < 0 || X >= p->w || Y >= p->h || k >= p->nz) return 0;
  return p->count[((size_t)k * p->h + Y) * p->w + X];
}

const elfm_calib *elfm_refocus_plan_calib(const elfm_refocus_plan *p) { return &p->calib; }

/* The bilinear sample of the four pixels r0[0], r0[1], r1[0], r1[1] with
 * weights w; on a deep window's frame (floor fl > 0) its older pixels, below
 * the floor, are not the window's and count as 0. view_sample and
 * elfm_refocus_plane_piece both take it, so their values are the same. */
static inline float tap_sample(const float *r0, const float *r1, const float w[4], float fl)
{
  if (fl > 0)
    return w[0] * (r0[0] >= fl ? r0[0] : 0.0f) + w[1] * (r0[1] >= fl ? r0[1] : 0.0f) +
           w[2] * (r1[0] >= fl ? r1[0] : 0.0f) + w[3] * (r1[1] >= fl ? r1[1] : 0.0f);
  return w[0] * r0[0] + w[1] * r0[1] + w[2] * r1[0] + w[3] * r1[1];
}

/* View v's bilinear sample at voxel (X, Y, k), as the dense path takes it,
 * into *a; 0 when the view does not sample the voxel. (X, Y, k) must lie
 * in the volume. */
static int view_sample(const elfm_refocus_plan *p, const elfm_frame *frame, int X, int Y, int k,
                       int v, float *a)
{
  const elfm_refocus_shift *sh = p->shift + (size_t)k * p->nv + v;
  if (X < sh->xlo || X >= sh->xhi || Y < sh->ylo || Y >= sh->yhi) return 0;
  float w[4];
  elfm_refocus_shift_weights(sh, w);
  const float *r0 = frame->data + (size_t)(Y + sh->iy) * (size_t)p->sw + (X + sh->ix);
  *a = tap_sample(r0, r0 + p->sw, w, frame->recent_floor);
  return 1;
}

static int in_volume(const elfm_refocus_plan *p, int X, int Y, int k)
{
  return X >= 0 && Y >= 0 && k >= 0 && X < p->w && Y < p->h && k < p->nz;
}

/* The views' samples at voxel (X, Y, k): how many views sample it, how
 * many of those are non-zero, and their sum. */
static void voxel_samples(const elfm_refocus_plan *p, const elfm_frame *frame, int X, int Y, int k,
                          int *n_sampling, int *n_nonzero, double *sum)
{
  int n = 0, ns = 0;
  double s = 0;
  float a;
  if (in_volume(p, X, Y, k))
    for (int v = 0; v < p->nv; v++) {
      if (!view_sample(p, frame, X, Y, k, v, &a)) continue;
      ns++;
      n += a != 0.0f;
      s += a;
    }
  *n_sampling = ns;
  *n_nonzero = n;
  *sum = s;
}

int elfm_refocus_view_support(const elfm_refocus_plan *p, const elfm_frame *frame, int X, int Y,
                              int k, int *n_sampling)
{
  int n, ns;
  double s;
  voxel_samples(p, frame, X, Y, k, &ns, &n, &s);
  if (n_sampling) *n_sampling = ns;
  return n;
}

double elfm_refocus_occupancy(const elfm_refocus_plan *p, const elfm_frame *frame)
{
  if (!(p->box_area > 0) || frame->w != p->sw || frame->h != p->sh) return 0;
  size_t n = 0;
  /* a deep window's older pixels are not the window's crowd */
  const size_t n_list = elfm_frame_n_window(frame);
  for (size_t i = 0; i < n_list; i++) {
    const uint32_t pix = frame->idx[i];
    const float v = frame->data[pix];
    if (v != 0.0f && elfm_frame_in_window(frame, v)) n += p->in_boxes[pix];
  }
  return (double)n / p->box_area;
}

/* Where view v puts the image of a point at voxel (X, Y, k), k fractional:
 * the sample point of the planes around k, linear between them (the shift
 * is linear in z), k clamped to the planes. */
static void view_image_at(const elfm_refocus_plan *p, int v, double X, double Y, double k,
                          double *u, double *w)
{
  if (!(k > 0)) k = 0; /* NaN too */
  if (k > p->nz - 1) k = p->nz - 1;
  int k0 = (int)k;
  if (k0 > p->nz - 2) k0 = p->nz > 1 ? p->nz - 2 : 0;
  const double a = p->nz > 1 ? k - k0 : 0;
  const elfm_refocus_shift *s0 = p->shift + (size_t)k0 * p->nv + v;
  const elfm_refocus_shift *s1 = p->nz > 1 ? s0 + p->nv : s0;
  *u = X + (1 - a) * (s0->ix + s0->fx) + a * (s1->ix + s1->fx);
  *w = Y + (1 - a) * (s0->iy + s0->fy) + a * (s1->iy + s1->fy);
}

int elfm_refocus_view_support_unexplained(const elfm_refocus_plan *p, const elfm_frame *frame,
                                          int X, int Y, int k, const double (*others)[3],
                                          int n_others, double r_px, int *n_sampling,
                                          int *n_explained)
{
  int n = 0, ns = 0, ne = 0;
  const double r2 = r_px * r_px;
  float a;
  if (in_volume(p, X, Y, k))
    for (int v = 0; v < p->nv; v++) {
      if (!view_sample(p, frame, X, Y, k, v, &a)) continue;
      ns++;
      if (a == 0.0f) continue;
      const elfm_refocus_shift *sh = p->shift + (size_t)k * p->nv + v;
      const double u = X + sh->ix + sh->fx, uy = Y + sh->iy + sh->fy;
      int explained = 0;
      for (int o = 0; o < n_others && !explained; o++) {
        double uo, wo;
        view_image_at(p, v, others[o][0], others[o][1], others[o][2], &uo, &wo);
        explained = (u - uo) * (u - uo) + (uy - wo) * (uy - wo) < r2;
      }
      if (explained) ne++;
      else n++;
    }
  if (n_sampling) *n_sampling = ns;
  if (n_explained) *n_explained = ne;
  return n;
}

double elfm_refocus_value_at(const elfm_refocus_plan *p, const elfm_frame *frame, int X, int Y,
                             int k)
{
  int n, ns;
  double s;
  voxel_samples(p, frame, X, Y, k, &ns, &n, &s);
  return ns > 0 ? s / ns : 0;
}

void elfm_refocus_plane_piece(const elfm_refocus_plan *p, const elfm_frame *frame, int X0, int Y0,
                              int w, int h, int k, double *out)
{
  for (int i = 0; i < w * h; i++) out[i] = 0;
  if (k < 0 || k >= p->nz) return;
  /* a view at a time, each voxel's views summed in the order
   * elfm_refocus_value_at sums them: the same values */
  const float fl = frame->recent_floor;
  for (int v = 0; v < p->nv; v++) {
    const elfm_refocus_shift *sh = p->shift + (size_t)k * p->nv + v;
    const int xa = imax(X0, sh->xlo), xb = imin(X0 + w, sh->xhi);
    const int ya = imax(Y0, sh->ylo), yb = imin(Y0 + h, sh->yhi);
    float wt[4];
    elfm_refocus_shift_weights(sh, wt);
    /* columns: the piece's from 0, the sensor row's from the view's first
     * sampled pixel (xa + ix >= 0 by the shift's bounds) */
    const int n = xb - xa;
    if (n <= 0) continue;
    for (int Y = ya; Y < yb; Y++) {
      const float *r0 = frame->data + (size_t)(Y + sh->iy) * (size_t)p->sw + (size_t)(xa + sh->ix);
      const float *r1 = r0 + p->sw;
      double *o = out + (size_t)(Y - Y0) * w + (xa - X0);
      for (int i = 0; i < n; i++) o[i] += tap_sample(r0 + i, r1 + i, wt, fl);
    }
  }
  for (int Y = imax(Y0, 0); Y < imin(Y0 + h, p->h); Y++)
    for (int X = imax(X0, 0); X < imin(X0 + w, p->w); X++) {
      const int n = p->count[((size_t)k * p->h + Y) * p->w + X];
      double *o = out + (size_t)(Y - Y0) * w + (X - X0);
      *o = n > 0 ? *o / n : 0;
    }
}

double elfm_refocus_sample(const elfm_refocus_plan *p, const elfm_frame *frame, double X, double Y,
                           double k)
{
  /* far outside (or NaN): nothing samples it; the floors below stay in int */
  if (!(fabs(X) < 1e6 && fabs(Y) < 1e6 && fabs(k) < 1e6)) return 0;
  const double fx = floor(X), fy = floor(Y), fk = floor(k);
  const double ax = X - fx, ay = Y - fy, ak = k - fk;
  const int x0 = (int)fx, y0 = (int)fy, k0 = (int)fk;
  double s = 0;
  for (int c = 0; c < 8; c++) {
    const int dx = c & 1, dy = (c >> 1) & 1, dk = c >> 2;
    const double w = (dx ? ax : 1 - ax) * (dy ? ay : 1 - ay) * (dk ? ak : 1 - ak);
    if (w == 0) continue; /* on a voxel: its 7 neighbours need no views' sums */
    s += w * elfm_refocus_value_at(p, frame, x0 + dx, y0 + dy, k0 + dk);
  }
  return s;
}

elfm_status elfm_refocus_plan_fits(const elfm_refocus_plan *p, const elfm_calib *c,
                                   elfm_error *err)
{
  const int nz = elfm_calib_n_planes(c);
  if (p->sw == c->sensor_width_px && p->sh == c->sensor_height_px && p->w == c->view_w_px &&
      p->h == c->view_h_px && p->nv == c->n_views && p->nz == nz &&
      p->calib.z_min_um == c->z_min_um && p->calib.z_step_um == c->z_step_um)
    return ELFM_OK;
  return elfm_error_set(err, ELFM_ERR_INVALID, NULL, -1,
                        "the refocus plan given was made for another calibration "
                        "(%d x %d px, %d views, %d planes; the calibration's %d x %d, %d, %d)",
                        p->sw, p->sh, p->nv, p->nz, c->sensor_width_px, c->sensor_height_px,
                        c->n_views, nz);
}

elfm_volume *elfm_refocus_volume_create(const elfm_refocus_plan *p, elfm_error *err)
{
  return elfm_volume_create_kept(p->w, p->h, p->nz, p->calib.um_per_px, p->calib.z_min_um,
                                 p->calib.z_step_um, err);
}

elfm_status elfm_refocus_workspace_create(const elfm_refocus_plan *p,
                                          elfm_refocus_workspace **out, elfm_error *err)
{
  *out = NULL;
  elfm_refocus_workspace *ws = calloc(1, sizeof *ws);
  if (!ws) return elfm_error_set(err, ELFM_ERR_NOMEM, NULL, -1, "out of memory (workspace)");
  ws->plan = p;
  ws->merge_gap_px = ELFM_REFOCUS_MERGE_GAP_PX;
  /* dense: a plane of counts of agreeing views */
  ws->plane_cnt = calloc((size_t)p->w * (size_t)p->h, 1);
  ws->row_start = calloc((size_t)p->sh + 1, sizeof *ws->row_start);
  ws->row_bits = calloc(((size_t)p->sw + 63) / 64, sizeof *ws->row_bits);
  ws->cap_sorted = 1u << 14;
  ws->sorted = malloc(ws->cap_sorted * sizeof *ws->sorted);
  ws->cap_runs = 1u << 12;
  ws->runs = malloc(ws->cap_runs * sizeof *ws->runs);
  ws->cap_vals = 1u << 15;
  ws->vals = malloc(ws->cap_vals * sizeof *ws->vals);
  ws->row_dirty = calloc((size_t)p->nz * p->h, 1);
  ws->row_lo = malloc((size_t)p->nz * p->h * sizeof *ws->row_lo);
  ws->row_hi = malloc((size_t)p->nz * p->h * sizeof *ws->row_hi);
  ws->rows = malloc((size_t)p->nz * p->h * sizeof *ws->rows);
  ws->rows_old = malloc((size_t)p->nz * p->h * sizeof *ws->rows_old);
  ws->vrow = calloc(p->n_vrow, sizeof *ws->vrow);
  ws->scatter_plane = calloc((size_t)p->w * (size_t)p->h, sizeof *ws->scatter_plane);
  int sup_ok = 1;
  if (p->need) {
    /* support bit maps (refocus_agree.c), packed: 25 views x 145 rows x
     * 19 bytes = 69 kB at the paper's geometry, where byte maps with
     * margins were 1.5 MB. Padding: a window starts up to W - 1 bits
     * before its row and reads up to 256 ceil(W / 256) + 64 bits on */
    const size_t nch = ((size_t)p->w + 255) / 256;
    size_t bits = 64 * (((size_t)p->w + 63) / 64);
    ws->agree_win_ld = 4 * nch + 4;
    ws->sup_bit = malloc((size_t)p->nv * sizeof *ws->sup_bit);
    ws->sup_stride_bits = malloc((size_t)p->nv * sizeof *ws->sup_stride_bits);
    ws->sup_ylo = malloc((size_t)p->nv * sizeof *ws->sup_ylo);
    ws->sup_yhi = malloc((size_t)p->nv * sizeof *ws->sup_yhi);
    ws->agree_win = aligned_alloc(32, 32 * ws->agree_win_ld * sizeof *ws->agree_win);
    /* 32 views' lane masks, then the voxels X < W */
    ws->agree_mask = aligned_alloc(32, 33 * ws->agree_win_ld * sizeof *ws->agree_mask);
    ws->agree_candw = malloc(ws->agree_win_ld * sizeof *ws->agree_candw);
    sup_ok = ws->sup_bit && ws->sup_stride_bits && ws->sup_ylo && ws->sup_yhi && ws->agree_win &&
             ws->agree_mask && ws->agree_candw;
    for (int v = 0; sup_ok && v < p->nv; v++) {
      ws->sup_bit[v] = bits;
      ws->sup_stride_bits[v] = 8 * (((size_t)(p->box[v].x1 - p->box[v].x0) + 7) / 8);
      ws->sup_ylo[v] = ws->sup_yhi[v] = 0;
      bits += ws->sup_stride_bits[v] * (size_t)(p->box[v].y1 - p->box[v].y0);
    }
    for (size_t i = 0; sup_ok && i < ws->agree_win_ld; i++) {
      const size_t keep = (size_t)p->w > 64 * i ? (size_t)p->w - 64 * i : 0;
      ws->agree_mask[32 * ws->agree_win_ld + i] =
          keep >= 64 ? ~(uint64_t)0 : ((uint64_t)1 << keep) - 1;
    }
    if (sup_ok) {
      ws->sup = calloc((bits + 256 * nch + 128) / 64 + 1, sizeof *ws->sup);
      sup_ok = ws->sup != NULL;
    }
  }
  if (!ws->plane_cnt || !ws->row_start || !ws->row_bits || !ws->sorted || !ws->runs || !ws->vals ||
      !ws->row_dirty || !ws->row_lo || !ws->row_hi || !ws->rows || !ws->rows_old || !ws->vrow ||
      !ws->scatter_plane || !sup_ok) {
    elfm_refocus_workspace_free(ws);
    return elfm_error_set(err, ELFM_ERR_NOMEM, NULL, -1, "out of memory (workspace)");
  }
  ws->last_path = ELFM_PATH_AUTO;
  *out = ws;
  return ELFM_OK;
}

void elfm_refocus_workspace_free(elfm_refocus_workspace *ws)
{
  if (!ws) return;
  free(ws->plane_cnt);
  free(ws->window_img);
  free(ws->row_start);
  free(ws->row_bits);
  free(ws->sorted);
  free(ws->runs);
  free(ws->vals);
  free(ws->row_lo);
  free(ws->row_hi);
  free(ws->sup);
  free(ws->sup_bit);
  free(ws->sup_stride_bits);
  free(ws->sup_ylo);
  free(ws->sup_yhi);
  free(ws->agree_win);
  free(ws->agree_mask);
  free(ws->agree_candw);
  free(ws->row_dirty);
  free(ws->rows);
  free(ws->rows_old);
  free(ws->vrow);
  free(ws->scatter_plane);
  free(ws);
}

void elfm_refocus_workspace_forget(elfm_refocus_workspace *ws)
{
  for (size_t i = 0; i < ws->n_rows; i++) ws->row_dirty[ws->rows[i]] = 0;
  ws->n_rows = 0;
  ws->dirty_data = NULL;
  ws->dirty_all = 0;
}

elfm_refocus_path elfm_refocus_workspace_last_path(const elfm_refocus_workspace *ws)
{
  return ws->last_path;
}

/* Plane by plane: gather every view's bilinear sample into the plane, count
 * the views that see signal, then take the mean over sampling views. */
static void refocus_dense(const elfm_refocus_plan *p, const float *img, elfm_volume *vol,
                          elfm_refocus_workspace *ws)
{
  const int W = p->w, H = p->h, SW = p->sw;
  for (int k = 0; k < p->nz; k++) {
    float *plane = vol->data + (size_t)k * W * H;
    memset(plane, 0, (size_t)W * H * sizeof *plane);
    if (p->need) memset(ws->plane_cnt, 0, (size_t)W * H);
    for (int v = 0; v < p->nv; v++) {
      const elfm_refocus_shift *s = &p->shift[(size_t)k * p->nv + v];
      float w[4];
      elfm_refocus_shift_weights(s, w);
      const float w00 = w[0], w01 = w[1], w10 = w[2], w11 = w[3];
      const int n = s->xhi - s->xlo;
      for (int Y = s->ylo; Y < s->yhi; Y++) {
        /* both taps of X lie in the crop box, inside the sensor (plan) */
        const float *r0 = img + (size_t)(Y + s->iy) * SW + (size_t)(s->ix + s->xlo);
        const float *r1 = r0 + SW;
        float *o = plane + (size_t)Y * W + s->xlo;
        if (p->need) {
          uint8_t *cnt = ws->plane_cnt + (size_t)Y * W + s->xlo;
          for (int i = 0; i < n; i++) {
            float a = w00 * r0[i] + w01 * r0[i + 1] + w10 * r1[i] + w11 * r1[i + 1];
            o[i] += a;
            cnt[i] += a != 0.0f;
          }
        } else {
          for (int i = 0; i < n; i++)
            o[i] += w00 * r0[i] + w01 * r0[i + 1] + w10 * r1[i] + w11 * r1[i + 1];
        }
      }
    }
    for (int Y = 0; Y < H; Y++) {
      const float *inv = p->inv_rows + p->inv_row_off[(size_t)k * H + Y];
      float *row = plane + (size_t)Y * W;
      for (int X = 0; X < W; X++) row[X] *= inv[X];
    }
    if (p->need)
      for (int Y = 0; Y < H; Y++)
        elfm_ghost_agree_row(p, k, Y, plane + (size_t)Y * W, ws->plane_cnt + (size_t)Y * W);
  }
  elfm_ghost_threshold_apply(p, vol, NULL, 0);
}

void elfm_refocus_stamp(const elfm_refocus_plan *p, const elfm_frame *frame, elfm_volume *vol)
{
  vol->t_us = frame->t_us;
  vol->frame = frame->index;
  vol->t_start_us = frame->t_start_us;
  vol->t_end_us = frame->t_end_us;
  vol->n_events = frame->n_events;
  vol->n_triggers = frame->n_triggers;
  vol->um_per_px = p->calib.um_per_px;
  vol->z_min_um = p->calib.z_min_um;
  vol->z_step_um = p->calib.z_step_um;
}

elfm_status elfm_refocus_execute_path(const elfm_refocus_plan *p, elfm_refocus_path path,
                                      const elfm_frame *frame, elfm_volume *vol,
                                      elfm_refocus_workspace *ws, elfm_error *err)
{
  if (!frame || frame->w != p->sw || frame->h != p->sh)
    return elfm_error_set(err, ELFM_ERR_INVALID, NULL, -1,
                          "frame %d x %d does not match the calibration's %d x %d sensor",
                          frame ? frame->w : 0, frame ? frame->h : 0, p->sw, p->sh);
  if (!vol || vol->w != p->w || vol->h != p->h || vol->nz != p->nz)
    return elfm_error_set(err, ELFM_ERR_INVALID, NULL, -1,
                          "volume does not match the plan's %d x %d x %d", p->w, p->h, p->nz);
  if (!ws || ws->plan != p)
    return elfm_error_set(err, ELFM_ERR_INVALID, NULL, -1, "workspace was made for another plan");
  if (path == ELFM_PATH_AUTO) path = p->opt.path;
  /* auto on a deep window's frame: the sparse path, which reads the
   * window's pixels from the list (the dense path below must first copy
   * them out) */
  if (path == ELFM_PATH_AUTO && frame->recent_floor > 0) path = ELFM_PATH_SPARSE;
  if (path == ELFM_PATH_AUTO)
    path = (double)frame->nnz < p->opt.sparse_max_fill * p->box_area ? ELFM_PATH_SPARSE
                                                                     : ELFM_PATH_DENSE;
  elfm_refocus_stamp(p, frame, vol);
  ws->last_path = path;
  if (path == ELFM_PATH_SPARSE) return elfm_refocus_sparse(p, frame, vol, ws, err);
  if (frame->recent_floor > 0) {
    /* The gather reads every pixel of the crop boxes, so on a deep
     * window's frame it reads a copy holding the window's pixels alone
     * (the older ones are there for the view fits: elfm_frame.recent_floor),
     * and the volume is the one the window's frame would give. */
    if (!ws->window_img &&
        !(ws->window_img = calloc((size_t)p->sw * (size_t)p->sh, sizeof *ws->window_img)))
      return elfm_error_set(err, ELFM_ERR_NOMEM, NULL, -1, "out of memory (a deep frame's copy)");
    const size_t n = elfm_frame_n_window(frame);
    for (size_t i = 0; i < n; i++) {
      const float v = frame->data[frame->idx[i]];
      if (elfm_frame_in_window(frame, v)) ws->window_img[frame->idx[i]] = v;
    }
    refocus_dense(p, ws->window_img, vol, ws);
    for (size_t i = 0; i < n; i++) ws->window_img[frame->idx[i]] = 0.0f;
  } else {
    refocus_dense(p, frame->data, vol, ws);
  }
  /* every voxel may now be non-zero: a later sparse call clears it all */
  elfm_refocus_workspace_forget(ws);
  ws->dirty_data = vol->data;
  ws->dirty_all = 1;
  return ELFM_OK;
}

elfm_status elfm_refocus_execute(const elfm_refocus_plan *p, const elfm_frame *frame,
                                 elfm_volume *vol, elfm_refocus_workspace *ws, elfm_error *err)
{
  return elfm_refocus_execute_path(p, ELFM_PATH_AUTO, frame, vol, ws, err);
}
