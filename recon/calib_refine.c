/* calib_refine.c — the views' centres (cx, cy) fitted to a recording.
 *
 * A point fitted from all views (elfm_refocus_localize) leaves, in each
 * view, a miss: its image centre minus the point's projection. With the
 * right centres the misses scatter around 0; a view whose centre is off by
 * (a, b) px misses every point by about (a, b), less what the fit itself
 * absorbs. So the median of a view's misses over many points is how far to
 * move its centre; a few passes (each with the moved centres) converge.
 *
 * Two moves no recording can see (the gauge): the same shift of every view
 * (the whole volume moves sideways) and a shift in proportion to each view's
 * disparity (the volume moves in z). A point's fit takes both up, so the
 * misses carry neither; the moves are cleared of them anyway (least squares
 * on 1 and du per axis), so that refining never moves the volume's origin or
 * its focal plane. Only the centres are fitted: the disparities follow from
 * the optics, and SPEC §2 says to model more (rotation, scale) only when
 * data show it is needed. A turned lens array is such a case (the end of
 * this file): its disparities turn with its centres, and a turn of 3
 * degrees, the centres fitted, cost flow 0.024 of alpha until they did.
 * A view whose images never moved on the sensor tells nothing of its own
 * centre, and is set on the grid of the others (settle_views). */
#include "calib_internal.h"
#include "elfm_calib.h"
#include "elfm_frames.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

struct elfm_calib_refine {
  int nv;
  size_t cap;
  size_t n_points;
  size_t *n;      /* [nv] misses collected per view */
  float *mu, *mw; /* [nv][cap] */
  float *scratch; /* [cap] for the medians */
  int search_px;  /* the votes' half-width R (0: no votes) */
  double *votes;  /* [nv][(2R + 1)^2] frame values by offset from the projection */
  size_t n_votes; /* points voted */
  /* where each view's images lay on the sensor (Welford: count, mean u and
   * w, summed squared distance from the mean), for elfm_calib_refine_still */
  double at_n[ELFM_MAX_VIEWS], at_u[ELFM_MAX_VIEWS], at_w[ELFM_MAX_VIEWS], at_m2[ELFM_MAX_VIEWS];
  double spread_px[ELFM_MAX_VIEWS]; /* the last apply's: RMS distance from the mean, NaN: none */
  int placed[ELFM_MAX_VIEWS];       /* ... and the views it placed on the others' grid */
};

static void at_add(elfm_calib_refine *r, int v, double u, double w)
{
  if (!(fabs(u) < 1e7 && fabs(w) < 1e7)) return;
  const double n = ++r->at_n[v], du = u - r->at_u[v], dw = w - r->at_w[v];
  r->at_u[v] += du / n;
  r->at_w[v] += dw / n;
  r->at_m2[v] += du * (u - r->at_u[v]) + dw * (w - r->at_w[v]);
}

elfm_status elfm_calib_refine_create(int n_views, size_t max_points, elfm_calib_refine **out,
                                     elfm_error *err)
{
  *out = NULL;
  if (n_views < 1 || n_views > ELFM_MAX_VIEWS || max_points < 1 || max_points > 10000000)
    return elfm_error_set(err, ELFM_ERR_INVALID, NULL, -1,
                          "calib refine: %d views (1..%d), %zu points (1..10000000)", n_views,
                          ELFM_MAX_VIEWS, max_points);
  elfm_calib_refine *r = calloc(1, sizeof *r);
  if (!r) return elfm_error_set(err, ELFM_ERR_NOMEM, NULL, -1, "calib refine: out of memory");
  r->nv = n_views;
  r->cap = max_points;
  for (int v = 0; v < ELFM_MAX_VIEWS; v++) r->spread_px[v] = NAN;
  r->n = calloc((size_t)n_views, sizeof *r->n);
  r->mu = malloc((size_t)n_views * max_points * sizeof *r->mu);
  r->mw = malloc((size_t)n_views * max_points * sizeof *r->mw);
  r->scratch = malloc(max_points * sizeof *r->scratch);
  if (!r->n || !r->mu || !r->mw || !r->scratch) {
    elfm_calib_refine_free(r);
    return elfm_error_set(err, ELFM_ERR_NOMEM, NULL, -1,
                          "calib refine: out of memory for %zu points x %d views", max_points, n_views);
  }
  *out = r;
  return ELFM_OK;
}

void elfm_calib_refine_free(elfm_calib_refine *r)
{
  if (!r) return;
  free(r->n);
  free(r->mu);
  free(r->mw);
  free(r->scratch);
  free(r->votes);
  free(r);
}

int elfm_calib_refine_add(elfm_calib_refine *r, const double *at_px, const double *miss_px,
                          const double *weight)
{
  if (r->n_points >= r->cap) return 0;
  for (int v = 0; v < r->nv; v++) {
    const double a = miss_px[2 * v], b = miss_px[2 * v + 1];
    /* a view that does not agree, or a value no fit gives: not a miss */
    if (!(weight[v] > 0) || !(fabs(a) < 1e3 && fabs(b) < 1e3)) continue;
    const size_t k = r->n[v]++;
    r->mu[(size_t)v * r->cap + k] = (float)a;
    r->mw[(size_t)v * r->cap + k] = (float)b;
    if (at_px) at_add(r, v, at_px[2 * v], at_px[2 * v + 1]);
  }
  r->n_points++;
  return 1;
}

size_t elfm_calib_refine_points(const elfm_calib_refine *r)
{
  return r->n_points;
}

static int cmp_float(const void *a, const void *b)
{
  const float x = *(const float *)a, y = *(const float *)b;
  return (x > y) - (x < y);
}

static double median_of(float *tmp, const float *a, size_t n)
{
  memcpy(tmp, a, n * sizeof *tmp);
  qsort(tmp, n, sizeof *tmp, cmp_float);
  return n % 2 ? tmp[n / 2] : 0.5 * ((double)tmp[n / 2 - 1] + tmp[n / 2]);
}

void elfm_calib_gauge_clear(int nv, const int *use, const double *d, double *s)
{
  double n = 0, sd = 0, sdd = 0, ss = 0, sds = 0;
  for (int v = 0; v < nv; v++) {
    if (!use[v]) continue;
    n += 1;
    sd += d[v];
    sdd += d[v] * d[v];
    ss += s[v];
    sds += d[v] * s[v];
  }
  if (n < 1) return;
  const double det = n * sdd - sd * sd;
  double a = ss / n, b = 0;
  if (n >= 3 && det > 1e-12 * n * sdd) {
    b = (n * sds - sd * ss) / det;
    a = (ss - b * sd) / n;
  }
  for (int v = 0; v < nv; v++)
    if (use[v]) s[v] -= a + b * d[v];
}

void elfm_calib_move_gauge_free(elfm_calib *c, const int *use, double *su, double *sw, double *shift_px)
{
  double du[ELFM_MAX_VIEWS] = {0}, dw[ELFM_MAX_VIEWS] = {0};
  for (int v = 0; v < c->n_views; v++) {
    du[v] = c->views[v].dx_px_per_um;
    dw[v] = c->views[v].dy_px_per_um;
  }
  elfm_calib_gauge_clear(c->n_views, use, du, su);
  elfm_calib_gauge_clear(c->n_views, use, dw, sw);
  for (int v = 0; v < c->n_views; v++) {
    c->views[v].cx_px += su[v];
    c->views[v].cy_px += sw[v];
    if (shift_px) {
      shift_px[2 * v] = su[v];
      shift_px[2 * v + 1] = sw[v];
    }
  }
}

int elfm_calib_solve3(double m[3][4], double x[3])
{
  /* Gauss-Jordan with partial pivoting */
  const double scale = fabs(m[0][0]) + fabs(m[1][1]) + fabs(m[2][2]);
  for (int k = 0; k < 3; k++) {
    int p = k;
    for (int a = k + 1; a < 3; a++)
      if (fabs(m[a][k]) > fabs(m[p][k])) p = a;
    if (!(fabs(m[p][k]) > 1e-9 * scale)) return 0;
    for (int b = 0; b < 4; b++) {
      const double t = m[k][b];
      m[k][b] = m[p][b];
      m[p][b] = t;
    }
    for (int a = 0; a < 3; a++) {
      if (a == k) continue;
      const double f = m[a][k] / m[k][k];
      for (int b = k; b < 4; b++) m[a][b] -= f * m[k][b];
    }
  }
  for (int k = 0; k < 3; k++) x[k] = m[k][3] / m[k][k];
  return 1;
}

/* cx (or cy) = a + b i + c j over the views with use[v], least squares:
 * the lenslets' grid, turned and scaled as it may be. 0 when the views do
 * not span it (fewer than 3, or all in one row). */
static int grid_fit(const elfm_calib *c, const int *use, int axis, double abc[3])
{
  double m[3][4] = {{0}};
  for (int v = 0; v < c->n_views; v++) {
    if (!use[v]) continue;
    const double x[3] = {1, c->views[v].i, c->views[v].j};
    const double y = axis ? c->views[v].cy_px : c->views[v].cx_px;
    for (int a = 0; a < 3; a++) {
      for (int b = 0; b < 3; b++) m[a][b] += x[a] * x[b];
      m[a][3] += x[a] * y;
    }
  }
  return elfm_calib_solve3(m, abc);
}

double elfm_calib_off_grid(const elfm_calib *c, const int *use, int *worst)
{
  double gx[3], gy[3], off = -1;
  *worst = -1;
  if (!grid_fit(c, use, 0, gx) || !grid_fit(c, use, 1, gy)) return -1;
  for (int v = 0; v < c->n_views; v++) {
    if (!use[v]) continue;
    const elfm_view *w = &c->views[v];
    const double d = hypot(w->cx_px - (gx[0] + gx[1] * w->i + gx[2] * w->j),
                           w->cy_px - (gy[0] + gy[1] * w->i + gy[2] * w->j));
    if (d > off) {
      off = d;
      *worst = v;
    }
  }
  return off;
}

int elfm_calib_place_on_grid(elfm_calib *c, const int *from, const int *to, double *shift_px)
{
  double gx[3], gy[3];
  if (!grid_fit(c, from, 0, gx) || !grid_fit(c, from, 1, gy)) return 0;
  for (int v = 0; v < c->n_views; v++) {
    if (!to[v]) continue;
    elfm_view *w = &c->views[v];
    const double x = gx[0] + gx[1] * w->i + gx[2] * w->j, y = gy[0] + gy[1] * w->i + gy[2] * w->j;
    shift_px[2 * v] += x - w->cx_px;
    shift_px[2 * v + 1] += y - w->cy_px;
    w->cx_px = x;
    w->cy_px = y;
  }
  /* The moves of from were cleared of the gauge among themselves; a view
   * placed then brings its own start's error into the gauge of the whole:
   * the central view of a sweep 10 px off moved every view by 1/24 of
   * that (0.1-0.25 px: flow tracked with such a calibration lost 0.01-0.03
   * of alpha against the truth). So the moves of all the views are cleared
   * together, as refine's are when every view moves by its own misses. */
  int all[ELFM_MAX_VIEWS] = {0};
  double su[ELFM_MAX_VIEWS] = {0}, sw[ELFM_MAX_VIEWS] = {0}, du[ELFM_MAX_VIEWS] = {0}, dw[ELFM_MAX_VIEWS] = {0};
  for (int v = 0; v < c->n_views; v++) {
    all[v] = from[v] || to[v];
    su[v] = shift_px[2 * v];
    sw[v] = shift_px[2 * v + 1];
    du[v] = c->views[v].dx_px_per_um;
    dw[v] = c->views[v].dy_px_per_um;
  }
  elfm_calib_gauge_clear(c->n_views, all, du, su);
  elfm_calib_gauge_clear(c->n_views, all, dw, sw);
  for (int v = 0; v < c->n_views; v++) {
    if (!all[v]) continue;
    c->views[v].cx_px += su[v] - shift_px[2 * v];
    c->views[v].cy_px += sw[v] - shift_px[2 * v + 1];
    shift_px[2 * v] = su[v];
    shift_px[2 * v + 1] = sw[v];
  }
  return 1;
}

/* Move the views as elfm_calib_move_gauge_free does, except those whose
 * images all lay within ELFM_CALIB_STILL_PX of one place on the sensor:
 * their misses rest on one pixel phase and on whatever that place holds,
 * and a view that sees its object without its image moving sees little of
 * it (the central view of one bead swept through z fires on the image's
 * slow defocus only; its fit there followed its start: 0.65-0.73 px off
 * after refining from the right centres, 7.5 px after a coarse step on
 * noise; docs/recon.md "Refining on one bead swept through z"). Those
 * views go where the grid of the others puts them, when
 * ELFM_CALIB_GRID_MIN_VIEWS others span it; otherwise all move as before. */
static void settle_views(elfm_calib_refine *r, elfm_calib *c, const int *use, double *su, double *sw,
                         double *shift_px)
{
  int still[ELFM_MAX_VIEWS] = {0}, rest[ELFM_MAX_VIEWS] = {0}, n_still = 0, n_rest = 0;
  for (int v = 0; v < c->n_views; v++) {
    r->spread_px[v] = r->at_n[v] > 0 ? sqrt(r->at_m2[v] / r->at_n[v]) : NAN;
    r->placed[v] = 0;
    still[v] = use[v] && r->at_n[v] >= 2 && r->spread_px[v] < ELFM_CALIB_STILL_PX;
    rest[v] = use[v] && !still[v];
    n_still += still[v];
    n_rest += rest[v];
  }
  memset(r->at_n, 0, sizeof r->at_n);
  memset(r->at_u, 0, sizeof r->at_u);
  memset(r->at_w, 0, sizeof r->at_w);
  memset(r->at_m2, 0, sizeof r->at_m2);
  if (n_still > 0 && n_rest >= ELFM_CALIB_GRID_MIN_VIEWS) {
    elfm_calib moved = *c;
    double sh[2 * ELFM_MAX_VIEWS] = {0};
    elfm_calib_move_gauge_free(&moved, rest, su, sw, sh);
    if (elfm_calib_place_on_grid(&moved, rest, still, sh)) {
      for (int v = 0; v < c->n_views; v++) r->placed[v] = still[v];
      if (shift_px) memcpy(shift_px, sh, 2 * (size_t)c->n_views * sizeof *shift_px);
      *c = moved;
      return;
    }
  }
  elfm_calib_move_gauge_free(c, use, su, sw, shift_px);
}

int elfm_calib_refine_still(const elfm_calib_refine *r, int v, double *spread_px)
{
  if (v < 0 || v >= r->nv) {
    if (spread_px) *spread_px = NAN;
    return 0;
  }
  if (spread_px) *spread_px = r->spread_px[v];
  return r->placed[v];
}

elfm_status elfm_calib_refine_apply(elfm_calib_refine *r, int min_points, elfm_calib *c,
                                    double *shift_px, int *n_moved, elfm_error *err)
{
  if (c->n_views != r->nv)
    return elfm_error_set(err, ELFM_ERR_INVALID, NULL, -1,
                          "calib refine: the calibration has %d views, the misses %d", c->n_views,
                          r->nv);
  if (min_points < 1) min_points = 1;
  double su[ELFM_MAX_VIEWS] = {0}, sw[ELFM_MAX_VIEWS] = {0};
  int use[ELFM_MAX_VIEWS] = {0}, moved = 0;
  for (int v = 0; v < r->nv; v++) {
    use[v] = r->n[v] >= (size_t)min_points;
    su[v] = use[v] ? median_of(r->scratch, r->mu + (size_t)v * r->cap, r->n[v]) : 0;
    sw[v] = use[v] ? median_of(r->scratch, r->mw + (size_t)v * r->cap, r->n[v]) : 0;
    moved += use[v];
  }
  settle_views(r, c, use, su, sw, shift_px);
  if (n_moved) *n_moved = moved;
  memset(r->n, 0, (size_t)r->nv * sizeof *r->n);
  r->n_points = 0;
  return ELFM_OK;
}

/* ---- the coarse step: votes ----
 * The fine passes need each view's image within the view fit's window of
 * where the centres put it (a few px); a calibration from the optics alone
 * can be 10 px off (the MLA's placement). So first, for every point, each
 * view adds the frame's values around the point's projection into a map by
 * offset: other objects fall anywhere in it, the point's own image always
 * at the view's error, which the map's peak gives. */
elfm_status elfm_calib_refine_set_search(elfm_calib_refine *r, int radius_px, elfm_error *err)
{
  if (radius_px < 0 || radius_px > 64)
    return elfm_error_set(err, ELFM_ERR_INVALID, NULL, -1, "calib refine: search radius %d px (0..64)",
                          radius_px);
  free(r->votes);
  r->votes = NULL;
  r->search_px = radius_px;
  r->n_votes = 0;
  if (!radius_px) return ELFM_OK;
  const size_t side = 2 * (size_t)radius_px + 1;
  r->votes = calloc((size_t)r->nv * side * side, sizeof *r->votes);
  if (!r->votes) {
    r->search_px = 0;
    return elfm_error_set(err, ELFM_ERR_NOMEM, NULL, -1, "calib refine: out of memory for the votes");
  }
  return ELFM_OK;
}

void elfm_calib_refine_vote(elfm_calib_refine *r, const elfm_calib *c, const elfm_frame *f, double x_um,
                            double y_um, double z_um)
{
  const int R = r->search_px, side = 2 * R + 1;
  if (!R || !f || c->n_views != r->nv || !(fabs(x_um) < 1e5 && fabs(y_um) < 1e5 && fabs(z_um) < 1e5))
    return;
  for (int v = 0; v < r->nv; v++) {
    double u, w;
    elfm_calib_project(c, v, x_um, y_um, z_um, &u, &w);
    at_add(r, v, u, w);
    const long iu = lround(u), iw = lround(w);
    double *h = r->votes + (size_t)v * (size_t)side * (size_t)side;
    for (int b = -R; b <= R; b++) {
      const long y = iw + b;
      if (y < 0 || y >= f->h) continue;
      const float *row = f->data + (size_t)y * (size_t)f->w;
      for (int a = -R; a <= R; a++) {
        const long x = iu + a;
        if (x < 0 || x >= f->w || !(row[x] > 0)) continue;
        h[(size_t)(b + R) * (size_t)side + (size_t)(a + R)] += row[x];
      }
    }
  }
  r->n_votes++;
}

size_t elfm_calib_refine_votes(const elfm_calib_refine *r)
{
  return r->n_votes;
}

elfm_status elfm_calib_refine_apply_votes(elfm_calib_refine *r, elfm_calib *c, double *shift_px,
                                          int *n_moved, elfm_error *err)
{
  if (c->n_views != r->nv)
    return elfm_error_set(err, ELFM_ERR_INVALID, NULL, -1,
                          "calib refine: the calibration has %d views, the votes %d", c->n_views, r->nv);
  const int R = r->search_px, side = 2 * R + 1;
  double su[ELFM_MAX_VIEWS] = {0}, sw[ELFM_MAX_VIEWS] = {0};
  int use[ELFM_MAX_VIEWS] = {0}, moved = 0;
  const size_t cells = (size_t)side * (size_t)side;
  double *sm = R > 0 ? malloc(cells * sizeof *sm) : NULL;
  float *tmp = R > 0 ? malloc(cells * sizeof *tmp) : NULL;
  if (R > 0 && (!sm || !tmp)) {
    free(sm);
    free(tmp);
    return elfm_error_set(err, ELFM_ERR_NOMEM, NULL, -1, "calib refine: out of memory");
  }
  for (int v = 0; R > 0 && r->n_votes >= ELFM_CALIB_VOTES_MIN && v < r->nv; v++) {
    const double *h = r->votes + (size_t)v * cells;
    /* the peak of the map smoothed over 3 x 3 (an image is a few px wide),
     * then the centroid of the smoothed map above its median around it */
    double best = 0;
    int pa = 0, pb = 0;
    for (int b = 0; b < side; b++)
      for (int a = 0; a < side; a++) {
        double t = 0;
        for (int y = b - 1; y <= b + 1; y++)
          for (int x = a - 1; x <= a + 1; x++)
            if (x >= 0 && y >= 0 && x < side && y < side) t += h[(size_t)y * (size_t)side + (size_t)x];
        sm[(size_t)b * (size_t)side + (size_t)a] = t;
        if (t > best) {
          best = t;
          pa = a;
          pb = b;
        }
      }
    /* the median of the smoothed map: the background the other objects give */
    for (size_t k = 0; k < cells; k++) tmp[k] = (float)sm[k];
    qsort(tmp, cells, sizeof *tmp, cmp_float);
    const double bg = tmp[cells / 2];
    double m = 0, ma = 0, mb = 0;
    for (int b = pb - 1; b <= pb + 1; b++)
      for (int a = pa - 1; a <= pa + 1; a++) {
        if (a < 0 || b < 0 || a >= side || b >= side) continue;
        const double t = sm[(size_t)b * (size_t)side + (size_t)a] - bg;
        if (t <= 0) continue;
        m += t;
        ma += t * a;
        mb += t * b;
      }
    /* a peak that does not stand out of the background (no object seen by
     * this view, or a view off the sensor): no move */
    if (!(best > 2 * bg) || !(m > 0)) continue;
    use[v] = 1;
    su[v] = ma / m - R;
    sw[v] = mb / m - R;
    moved++;
  }
  free(sm);
  free(tmp);
  settle_views(r, c, use, su, sw, shift_px);
  if (n_moved) *n_moved = moved;
  if (R > 0) memset(r->votes, 0, (size_t)r->nv * cells * sizeof *r->votes);
  r->n_votes = 0;
  return ELFM_OK;
}

/* ---- the lens array's turn ----
 * A lens array turned against the sensor's rows turns both where its views
 * land and the direction in which their images move with depth (a view's
 * disparity lies along its lenslet's offset in the pupil). The centres'
 * fit sees the first; the second it cannot (a point's fit takes up no part
 * of it, but the misses it leaves grow with the point's depth, and the
 * median over points at all depths is no move of the centre). So the
 * disparities are turned to the grid of fitted centres: both are the
 * lenslets' lattice (i, j) turned, and each one's turn against it is
 * measured on its own, so that centres that came in off by a turn of their
 * own (moved at random, or by hand) leave no turn in the disparities. */

/* (x, y) turned by the angle whose cosine and sine are ca, sa */
static void turn_xy(double ca, double sa, double *x, double *y)
{
  const double x0 = *x, y0 = *y;
  *x = ca * x0 - sa * y0;
  *y = sa * x0 + ca * y0;
}

static void centres_mean(const elfm_calib *c, double *mx, double *my)
{
  *mx = *my = 0;
  for (int v = 0; v < c->n_views; v++) {
    *mx += c->views[v].cx_px;
    *my += c->views[v].cy_px;
  }
  if (c->n_views > 0) {
    *mx /= c->n_views;
    *my /= c->n_views;
  }
}

void elfm_calib_turn(elfm_calib *c, double angle_deg)
{
  double mx, my;
  centres_mean(c, &mx, &my);
  const double a = angle_deg * (3.14159265358979323846 / 180.0), ca = cos(a), sa = sin(a);
  for (int v = 0; v < c->n_views; v++) {
    elfm_view *w = &c->views[v];
    double x = w->cx_px - mx, y = w->cy_px - my;
    turn_xy(ca, sa, &x, &y);
    w->cx_px = mx + x;
    w->cy_px = my + y;
  }
  elfm_calib_turn_disparities(c, angle_deg);
}

void elfm_calib_turn_disparities(elfm_calib *c, double angle_deg)
{
  const double a = angle_deg * (3.14159265358979323846 / 180.0), ca = cos(a), sa = sin(a);
  for (int v = 0; v < c->n_views; v++)
    turn_xy(ca, sa, &c->views[v].dx_px_per_um, &c->views[v].dy_px_per_um);
  if (c->has_optics) {
    /* kept within the file's -45..45: a square lattice turned by 90
     * degrees is itself, only its views' (i, j) go round */
    double r = c->optics.mla_rotation_deg + angle_deg;
    r -= 90.0 * floor((r + 45.0) / 90.0);
    c->optics.mla_rotation_deg = r;
  }
}

void elfm_calib_move_focus(elfm_calib *c, double z_um)
{
  if (!isfinite(z_um)) return;
  for (int v = 0; v < c->n_views; v++) {
    c->views[v].cx_px += c->views[v].dx_px_per_um * z_um;
    c->views[v].cy_px += c->views[v].dy_px_per_um * z_um;
  }
}

double elfm_calib_grid_pitch(const elfm_calib *c)
{
  int all[ELFM_MAX_VIEWS];
  for (int v = 0; v < c->n_views; v++) all[v] = 1;
  double gx[3], gy[3];
  if (!grid_fit(c, all, 0, gx) || !grid_fit(c, all, 1, gy)) return NAN;
  return 0.5 * (hypot(gx[1], gy[1]) + hypot(gx[2], gy[2]));
}

void elfm_calib_scale_relay(elfm_calib *c, double k)
{
  if (!(isfinite(k) && k > 0)) return;
  c->um_per_px /= k;
  for (int v = 0; v < c->n_views; v++) {
    c->views[v].dx_px_per_um *= k;
    c->views[v].dy_px_per_um *= k;
  }
  if (c->has_optics) c->optics.relay *= k;
}

/* The least-squares turn carrying the lattice vectors (i, j) onto (x, y):
 * tan a = sum((i, j) x (x, y)) / sum((i, j) . (x, y)); 0 with no match. */
static double lattice_turn_deg(double cross, double dot)
{
  if (!(dot > 0)) return 0.0;
  return atan2(cross, dot) * (180.0 / 3.14159265358979323846);
}

void elfm_calib_turns(const elfm_calib *c, double *centres_deg, double *disparities_deg)
{
  double mx, my, cc = 0, cd = 0, dc = 0, dd = 0;
  centres_mean(c, &mx, &my);
  for (int v = 0; v < c->n_views; v++) {
    const elfm_view *w = &c->views[v];
    const double x = w->cx_px - mx, y = w->cy_px - my;
    cc += w->i * y - w->j * x;
    cd += w->i * x + w->j * y;
    dc += w->i * w->dy_px_per_um - w->j * w->dx_px_per_um;
    dd += w->i * w->dx_px_per_um + w->j * w->dy_px_per_um;
  }
  *centres_deg = lattice_turn_deg(cc, cd);
  *disparities_deg = lattice_turn_deg(dc, dd);
}
