/* calib_sweep.c — the views' centres from one bright object swept through z.
 *
 * The recording a microscopist makes to check depth: one bead moved along
 * the axis by a piezo or the focus drive. `calib refine`'s coarse step
 * finds the views from refocused peaks, and a calibration from the optics
 * alone (centres 2-10 px off) refocuses such a bead into no peak: from
 * centres 2.3 px RMS off it turned the array by -3.3 degrees on noise and
 * fitted nothing (docs/recon.md "A sweep's views, frame by frame").
 *
 * So each view is looked at on its own. In every frame each view holds one
 * image of the object (and noise): the brightest 3 x 3 spot of the view's
 * crop, when it stands out (at least ELFM_CALIB_SWEEP_CONTRAST times the
 * view's next spot 5 px or more away), gives the image's place p(v, f), the
 * centroid of the 5 x 5 about it. With one object
 *
 *   p(v, f) = c(v) + b + d(v) z(f)
 *
 * c the view's centre, d its disparity (from the optics, as in refine), b
 * the object's lateral place and z(f) its depth at frame f, both unknown.
 * Alternating, each step exact for the other fixed: z(f) from the views
 * (a median first, then least squares over the images near the model), c(v)
 * the median over the frames of p - d z. The two moves no recording can
 * see (all views alike, which b is, and in proportion to d, an offset of
 * z) are cleared as refine clears them. Nothing here needs the centres
 * near right: only that each view's image lies in the crop about them.
 *
 * A view with few images (the central one sees an axial sweep only as its
 * image's slow defocus) goes where the grid of the others puts it, as in
 * refine (calib_internal.h).
 *
 * Several objects swept together (beads on a slide) fit no one object:
 * the brightest spot is now one's image, now another's. Their spots are
 * then matched to one pattern, and its translation in each view and frame
 * fitted as the one object's image (calib_sweep_pattern.c).
 */
#include "calib_internal.h"
#include "elfm_calib.h"
#include "elfm_frames.h"

#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

/* A spot's centroid window, half-width px, and how far its rival lies */
#define SWEEP_HALF_PX 2
#define SWEEP_RIVAL_PX 5
/* Several objects: a view's spots down to this share of its brightest */
#define SWEEP_SPOT_FRAC 0.3
/* Several objects in the views, not moving as one pattern, when the views'
 * median share of frames with two spots or more is this or more: one bead
 * swept, 0.18-0.24 (zsweep seeds 1-4, the noise's spots where the bead is
 * faint); two to five beads, 0.84-0.93, and a flow 1.0. The brightest
 * spots of two beads fitted one in most views and the other in a few, 9 px
 * off, at a median 0.76 of the spots near the fit. */
#define SWEEP_SEVERAL ELFM_CALIB_SWEEP_SEVERAL
/* The alternation's steps and their outlier radii, px (the first: none) */
#define SWEEP_ITERATIONS 8
static const double sweep_radius_px[SWEEP_ITERATIONS] = {INFINITY, 8, 4, 2, 1.5, 1.5, 1.5, 1.5};
/* Views whose disparity is below this share of the largest tell nothing
 * of z (the central view's d is 0) */
#define SWEEP_D_MIN_FRAC 0.1
/* Of a view's spots in the frames that told the depth, the share that lie
 * near the fitted model: one bead swept through z, 0.63-0.95 in every view
 * that tells the depth (zsweep seeds 1 and 4, the array turned 3 degrees,
 * a 3 x 3 array, a sweep both ways; the views' median 0.76-0.92 on every
 * sweep measured); five beads 10 um apart swept together, 0-0.83, median
 * 0.21, and the fit 9.8 px RMS off where it was taken. With the median
 * over the views below SWEEP_AGREE nothing moves. */
#define SWEEP_AGREE 0.5

struct elfm_calib_sweep {
  int nv, w, h;
  uint8_t *view_of; /* [w * h] the view whose crop holds the pixel (nearest centre), 255: none */
  size_t cap, n;    /* frames held */
  float *pu, *pw;   /* [cap][nv] the spots, NaN: none */
  uint8_t *n_spots; /* [cap][nv] and each view's spots for several objects, */
  float *strength;  /* [cap][nv] the brightest's strength, */
  float *spots;     /* [cap][nv][ELFM_CALIB_SWEEP_MAX_SPOTS][2] */
  double *t_us;     /* [cap] the frames' times */
  elfm_calib_sweep_fit fit; /* the last apply's */
};

elfm_status elfm_calib_sweep_create(const elfm_calib *c, size_t max_frames, elfm_calib_sweep **out,
                                    elfm_error *err)
{
  *out = NULL;
  if (c->n_views < 1 || c->n_views > ELFM_MAX_VIEWS || c->n_views > 255 || max_frames < 1 ||
      max_frames > 10000000 || c->sensor_width_px < 1 || c->sensor_height_px < 1)
    return elfm_error_set(err, ELFM_ERR_INVALID, NULL, -1,
                          "calib sweep: %d views, %zu frames (1..%d views, 1..10^7 frames)", c->n_views,
                          max_frames, ELFM_MAX_VIEWS);
  elfm_calib_sweep *s = calloc(1, sizeof *s);
  const size_t npx = (size_t)c->sensor_width_px * (size_t)c->sensor_height_px;
  if (s) {
    s->nv = c->n_views;
    s->w = c->sensor_width_px;
    s->h = c->sensor_height_px;
    s->cap = max_frames;
    s->view_of = malloc(npx);
    s->pu = malloc(max_frames * (size_t)c->n_views * sizeof *s->pu);
    s->pw = malloc(max_frames * (size_t)c->n_views * sizeof *s->pw);
    s->t_us = malloc(max_frames * sizeof *s->t_us);
    s->n_spots = malloc(max_frames * (size_t)c->n_views);
    s->strength = malloc(max_frames * (size_t)c->n_views * sizeof *s->strength);
    s->spots = malloc(max_frames * (size_t)c->n_views * ELFM_CALIB_SWEEP_MAX_SPOTS * 2 * sizeof *s->spots);
  }
  if (!s || !s->view_of || !s->pu || !s->pw || !s->t_us || !s->n_spots || !s->strength || !s->spots) {
    elfm_calib_sweep_free(s);
    return elfm_error_set(err, ELFM_ERR_NOMEM, NULL, -1, "calib sweep: out of memory");
  }
  /* each pixel to the view of the nearest centre whose crop holds it */
  for (int y = 0; y < s->h; y++)
    for (int x = 0; x < s->w; x++) {
      int best = 255;
      double bd = INFINITY;
      for (int v = 0; v < s->nv; v++) {
        const double du = x - c->views[v].cx_px, dw = y - c->views[v].cy_px;
        if (fabs(du) > 0.5 * c->view_w_px || fabs(dw) > 0.5 * c->view_h_px) continue;
        if (du * du + dw * dw < bd) {
          bd = du * du + dw * dw;
          best = v;
        }
      }
      s->view_of[(size_t)y * (size_t)s->w + (size_t)x] = (uint8_t)best;
    }
  *out = s;
  return ELFM_OK;
}

void elfm_calib_sweep_free(elfm_calib_sweep *s)
{
  if (!s) return;
  free(s->view_of);
  free(s->pu);
  free(s->pw);
  free(s->t_us);
  free(s->n_spots);
  free(s->strength);
  free(s->spots);
  free(s);
}

/* The frame's value at (x, y) if it is the window's and above 0, else 0 */
static float value_at(const elfm_frame *f, int x, int y)
{
  if (x < 0 || y < 0 || x >= f->w || y >= f->h) return 0;
  const float a = f->data[(size_t)y * (size_t)f->w + (size_t)x];
  return a > 0 && elfm_frame_in_window(f, a) ? a : 0;
}

/* A spot's strength: the 3 x 3 sum about (x, y) less its brightest pixel,
 * so that a hot pixel (one pixel firing on its own, brighter in the
 * integral than any bead's image: zsweep seed 3's took two inner views
 * 37-87 px off) is as weak as the noise about it */
static float box3(const elfm_frame *f, int x, int y)
{
  float s = 0, top = 0;
  for (int b = -1; b <= 1; b++)
    for (int a = -1; a <= 1; a++) {
      const float q = value_at(f, x + a, y + b);
      s += q;
      top = q > top ? q : top;
    }
  return s - top;
}

/* the 5 x 5 centroid about (x, y) */
static void centroid5(const elfm_frame *f, int x, int y, double *u, double *w)
{
  double sv = 0, su = 0, sw = 0;
  for (int b = -SWEEP_HALF_PX; b <= SWEEP_HALF_PX; b++)
    for (int a = -SWEEP_HALF_PX; a <= SWEEP_HALF_PX; a++) {
      const double q = value_at(f, x + a, y + b);
      sv += q;
      su += q * (x + a);
      sw += q * (y + b);
    }
  *u = su / sv;
  *w = sw / sv;
}

typedef struct sweep_candidate {
  float b;
  int x, y, v;
} sweep_candidate;

static int cmp_candidate(const void *a, const void *b)
{
  const sweep_candidate *p = a, *q = b;
  if (p->b != q->b) return p->b < q->b ? 1 : -1;
  return p->y != q->y ? (p->y > q->y) - (p->y < q->y) : (p->x > q->x) - (p->x < q->x);
}

elfm_status elfm_calib_sweep_spots(const elfm_calib_sweep *s, const elfm_frame *f, elfm_calib_sweep_image *img,
                                   elfm_error *err)
{
  float best[ELFM_MAX_VIEWS], rival[ELFM_MAX_VIEWS];
  int bx[ELFM_MAX_VIEWS], by[ELFM_MAX_VIEWS];
  for (int v = 0; v < s->nv; v++) {
    best[v] = rival[v] = 0;
    bx[v] = by[v] = -1;
    img->at_px[2 * v] = img->at_px[2 * v + 1] = NAN;
    img->contrast[v] = img->strength[v] = 0;
    img->n_spots[v] = 0;
  }
  if (f->w != s->w || f->h != s->h) return ELFM_OK;
  const size_t n = elfm_frame_n_window(f);
  sweep_candidate *cand = malloc((n + 1) * sizeof *cand);
  if (!cand) return elfm_error_set(err, ELFM_ERR_NOMEM, NULL, -1, "calib sweep: out of memory");
  size_t nc = 0;
  /* the brightest spot of each view, then its rival: the brightest 5 px or
   * more from it (a second object, or the noise); and the candidates for
   * several objects' spots, down to SWEEP_SPOT_FRAC of the brightest */
  for (int pass = 0; pass < 2; pass++)
    for (size_t k = 0; k < n; k++) {
      const uint32_t p = f->idx[k];
      const int x = (int)(p % (uint32_t)f->w), y = (int)(p / (uint32_t)f->w);
      const int v = s->view_of[p];
      if (v == 255 || value_at(f, x, y) <= 0) continue;
      const float b = box3(f, x, y);
      if (pass == 0 && b > best[v]) {
        best[v] = b;
        bx[v] = x;
        by[v] = y;
      } else if (pass == 1) {
        if (b > rival[v] && (abs(x - bx[v]) >= SWEEP_RIVAL_PX || abs(y - by[v]) >= SWEEP_RIVAL_PX)) rival[v] = b;
        if (b > 0 && b >= (float)SWEEP_SPOT_FRAC * best[v]) cand[nc++] = (sweep_candidate){b, x, y, v};
      }
    }
  for (int v = 0; v < s->nv; v++) {
    if (bx[v] < 0) continue;
    centroid5(f, bx[v], by[v], &img->at_px[2 * v], &img->at_px[2 * v + 1]);
    img->contrast[v] = rival[v] > 0 ? (double)best[v] / rival[v] : INFINITY;
    img->strength[v] = best[v];
  }
  /* Every view's spots for several objects side by side: the strongest
   * with no stronger one within SWEEP_RIVAL_PX - 1 px (either axis) */
  qsort(cand, nc, sizeof *cand, cmp_candidate);
  int sx[ELFM_MAX_VIEWS][ELFM_CALIB_SWEEP_MAX_SPOTS], sy[ELFM_MAX_VIEWS][ELFM_CALIB_SWEEP_MAX_SPOTS];
  for (size_t k = 0; k < nc; k++) {
    const int v = cand[k].v, m = img->n_spots[v];
    if (m >= ELFM_CALIB_SWEEP_MAX_SPOTS) continue;
    int near = 0;
    for (int j = 0; j < m && !near; j++)
      near = abs(cand[k].x - sx[v][j]) < SWEEP_RIVAL_PX && abs(cand[k].y - sy[v][j]) < SWEEP_RIVAL_PX;
    if (near) continue;
    sx[v][m] = cand[k].x;
    sy[v][m] = cand[k].y;
    double u, w;
    centroid5(f, cand[k].x, cand[k].y, &u, &w);
    img->spot_px[v][m][0] = (float)u;
    img->spot_px[v][m][1] = (float)w;
    img->n_spots[v] = m + 1;
  }
  free(cand);
  return ELFM_OK;
}

int elfm_calib_sweep_add(elfm_calib_sweep *s, int64_t t_us, const elfm_calib_sweep_image *img)
{
  if (s->n >= s->cap) return 0;
  s->t_us[s->n] = (double)t_us;
  float *pu = s->pu + s->n * (size_t)s->nv, *pw = s->pw + s->n * (size_t)s->nv;
  uint8_t *ns = s->n_spots + s->n * (size_t)s->nv;
  float *sp = s->spots + s->n * (size_t)s->nv * ELFM_CALIB_SWEEP_MAX_SPOTS * 2;
  for (int v = 0; v < s->nv; v++) {
    const int ok = img->contrast[v] >= ELFM_CALIB_SWEEP_CONTRAST && isfinite(img->at_px[2 * v]) &&
                   isfinite(img->at_px[2 * v + 1]);
    pu[v] = ok ? (float)img->at_px[2 * v] : NAN;
    pw[v] = ok ? (float)img->at_px[2 * v + 1] : NAN;
    ns[v] = (uint8_t)img->n_spots[v];
    s->strength[s->n * (size_t)s->nv + (size_t)v] = (float)img->strength[v];
    memcpy(sp + (size_t)v * ELFM_CALIB_SWEEP_MAX_SPOTS * 2, img->spot_px[v], sizeof img->spot_px[v]);
  }
  s->n++;
  return 1;
}

size_t elfm_calib_sweep_frames(const elfm_calib_sweep *s)
{
  return s->n;
}

static int cmp_double(const void *a, const void *b)
{
  const double x = *(const double *)a, y = *(const double *)b;
  return (x > y) - (x < y);
}

double elfm_calib_median(double *a, size_t n)
{
  qsort(a, n, sizeof *a, cmp_double);
  return n % 2 ? a[n / 2] : 0.5 * (a[n / 2 - 1] + a[n / 2]);
}

/* z of frame f (NaN when fewer than 3 views tell it): at radius r the least
 * squares over the images within r px of the model at z_prev, else (r
 * infinite, or no z_prev) the median of the views' own z */
static double frame_z(const elfm_calib_sweep *s, const elfm_calib *c, const int *tells, size_t f, double z_prev,
                      double r, double *tmp)
{
  const float *pu = s->pu + f * (size_t)s->nv, *pw = s->pw + f * (size_t)s->nv;
  double num = 0, den = 0;
  size_t n = 0;
  if (isnan(z_prev)) r = INFINITY;
  for (int v = 0; v < s->nv; v++) {
    if (!tells[v] || isnan(pu[v])) continue;
    const elfm_view *w = &c->views[v];
    const double eu = pu[v] - w->cx_px, ew = pw[v] - w->cy_px;
    const double dd = w->dx_px_per_um * w->dx_px_per_um + w->dy_px_per_um * w->dy_px_per_um;
    if (isinf(r)) {
      tmp[n++] = (w->dx_px_per_um * eu + w->dy_px_per_um * ew) / dd;
    } else if (hypot(eu - w->dx_px_per_um * z_prev, ew - w->dy_px_per_um * z_prev) <= r) {
      num += w->dx_px_per_um * eu + w->dy_px_per_um * ew;
      den += dd;
      n++;
    }
  }
  if (n < 3) return NAN;
  return isinf(r) ? elfm_calib_median(tmp, n) : num / den;
}

/* The object's axial speed by the disparities as they are: the median and
 * the middle half of |dz/dt| over spans of SWEEP_SPEED_SPAN_US (a piezo's
 * ramp, up or down; spans across a turn are the few), into s->fit. Only
 * spans within the middle half of the depths the sweep went through: far
 * from focus the images widen past the 5 x 5 centroid and the fitted
 * depths fall short (zsweep seed 1 with its own calibration: -87.2 um at
 * -90; 0.1983 um/ms by a straight line over the whole sweep, 0.2001 over
 * |z| < 30 um, the truth 0.2), and focus itself is where the calibration
 * puts it, which may be off (the optics' calibration of a relay 2.4 %
 * longer put the sweep's middle at +21.7 um). tmp: room for s->n values. */
#define SWEEP_SPEED_SPAN_US 40000.0
static void sweep_speed(elfm_calib_sweep *s, const double *z, double *tmp)
{
  size_t n = 0;
  for (size_t f = 0; f < s->n; f++)
    if (!isnan(z[f])) tmp[n++] = z[f];
  s->fit.speed_um_per_ms = s->fit.speed_lo_um_per_ms = s->fit.speed_hi_um_per_ms = NAN;
  if (n < 20) return;
  qsort(tmp, n, sizeof *tmp, cmp_double);
  const double lo = tmp[n / 4], hi = tmp[(3 * n) / 4];
  n = 0;
  for (size_t f = 0, g = 0; f < s->n; f++) {
    if (isnan(z[f]) || z[f] < lo || z[f] > hi) continue;
    if (g < f) g = f;
    while (g < s->n && s->t_us[g] - s->t_us[f] < SWEEP_SPEED_SPAN_US) g++;
    if (g >= s->n) break;
    if (isnan(z[g]) || z[g] < lo || z[g] > hi) continue;
    tmp[n++] = 1000.0 * fabs(z[g] - z[f]) / (s->t_us[g] - s->t_us[f]);
  }
  if (n < 20) return;
  s->fit.speed_um_per_ms = elfm_calib_median(tmp, n); /* (sorting tmp) */
  s->fit.speed_lo_um_per_ms = tmp[n / 4];
  s->fit.speed_hi_um_per_ms = tmp[(3 * n) / 4];
}

/* Where the sweep went through focus: the depth at which the views'
 * images are strongest. A bead's image is sharpest in focus and widens
 * with its distance from it (defocus), and a sharper image fires more of
 * its pixels, more often: the median over the views that tell the depth
 * of their brightest spot's strength, on the integral of zsweep seed 1,
 * 421 at z -10..0 um and 423 at 0..10, 269 / 303 at -30..-20 / 20..30, 3-6
 * at the ends (+-80..90). The focal plane is what no fit of the images'
 * places can see (a move of every view in proportion to its disparity is
 * an offset of z: the gauge above), and a calibration from the optics puts
 * it where the optics say (a relay 2.4 % longer than the optics': 22 um
 * off). log(strength) is fitted with a parabola in z over the frames at
 * SWEEP_FOCUS_FRAC of the peak or more; its vertex is the focus (seeds 1-4,
 * a relay 1.25 or 1.28: -0.11..+1.46 um from the truth's focus, mean +0.4;
 * the half-maximum's middle, -1.6..+2.7). NaN unless the profile falls
 * below half its peak on both sides of the vertex (the sweep went through
 * focus and out of it both ways) and the parabola opens down. z: each
 * frame's depth (NaN: none) in the fit's depths; way 0: every
 * frame's, +1 / -1: only those of frames going up / down (way_of[f]); zq,
 * run, tmp: room for s->n values. */
#define SWEEP_FOCUS_FRAC 0.25
#define SWEEP_FOCUS_RISE 8.0
#define SWEEP_FOCUS_SMOOTH 10 /* frames either side of the running median */
typedef struct sweep_depth {
  double z, q; /* a frame's depth, and its views' median strength */
} sweep_depth;

static int cmp_depth(const void *a, const void *b)
{
  const double x = ((const sweep_depth *)a)->z, y = ((const sweep_depth *)b)->z;
  return (x > y) - (x < y);
}

static double sweep_focus(const elfm_calib_sweep *s, const int *tells, const double *z, const signed char *way_of,
                          int way, sweep_depth *zq, double *run, double *tmp)
{
  double v_tmp[ELFM_MAX_VIEWS];
  size_t n = 0;
  for (size_t f = 0; f < s->n; f++) {
    if (isnan(z[f]) || (way != 0 && way_of[f] != way)) continue;
    size_t k = 0;
    for (int v = 0; v < s->nv; v++) {
      const double a = s->strength[f * (size_t)s->nv + (size_t)v];
      if (tells[v] && a > 0) v_tmp[k++] = a;
    }
    if (k < 3) continue;
    zq[n++] = (sweep_depth){z[f], elfm_calib_median(v_tmp, k)};
  }
  if (n < 20) return NAN;
  qsort(zq, n, sizeof *zq, cmp_depth);
  /* the profile's peak, on a running median of the strengths (one frame's
   * strength scatters by a third) */
  double peak = 0, win[2 * SWEEP_FOCUS_SMOOTH + 1];
  for (size_t i = 0; i < n; i++) {
    const size_t a = i > SWEEP_FOCUS_SMOOTH ? i - SWEEP_FOCUS_SMOOTH : 0;
    const size_t b = i + SWEEP_FOCUS_SMOOTH < n ? i + SWEEP_FOCUS_SMOOTH : n - 1;
    for (size_t k = a; k <= b; k++) win[k - a] = zq[k].q;
    run[i] = elfm_calib_median(win, b - a + 1);
    peak = fmax(peak, run[i]);
  }
  if (!(peak > 0)) return NAN;
  /* The profile must rise from its floor (the running median's tenth
   * percentile) to SWEEP_FOCUS_RISE times it or more, else the frames at
   * SWEEP_FOCUS_FRAC of the peak take in the floor's noise: a faint bead
   * (flux 8-10 x 10^3 Hz, where the built-in's is 25-35), its strengths
   * ~5 far from focus and 21-24 at it, put the focus 28 um off; bright
   * ones rose 11-36 times (the least: a way down under haze 0.3) */
  memcpy(tmp, run, n * sizeof *tmp);
  qsort(tmp, n, sizeof *tmp, cmp_double);
  if (!(tmp[n / 10] * SWEEP_FOCUS_RISE <= peak)) return NAN;
  /* log q = c0 + c1 t + c2 t^2 over the frames at the fraction of the peak
   * or more, t = (z - mean) / spread for the normal equations' sake */
  double zm = 0, zs = 0;
  size_t m = 0;
  for (size_t i = 0; i < n; i++)
    if (zq[i].q >= SWEEP_FOCUS_FRAC * peak) {
      zm += zq[i].z;
      m++;
    }
  if (m < 10) return NAN;
  zm /= (double)m;
  for (size_t i = 0; i < n; i++)
    if (zq[i].q >= SWEEP_FOCUS_FRAC * peak) zs += (zq[i].z - zm) * (zq[i].z - zm);
  zs = sqrt(zs / (double)m);
  if (!(zs > 0)) return NAN;
  double a[3][4] = {{0}};
  for (size_t i = 0; i < n; i++) {
    if (zq[i].q < SWEEP_FOCUS_FRAC * peak) continue;
    const double t = (zq[i].z - zm) / zs, x[3] = {1, t, t * t}, y = log(zq[i].q);
    for (int r = 0; r < 3; r++) {
      for (int c = 0; c < 3; c++) a[r][c] += x[r] * x[c];
      a[r][3] += x[r] * y;
    }
  }
  double c[3];
  if (!elfm_calib_solve3(a, c) || !(c[2] < 0)) return NAN;
  const double focus = zm - zs * c[1] / (2 * c[2]);
  /* through focus and out of it both ways */
  int below_lo = 0, below_hi = 0;
  for (size_t i = 0; i < n; i++) {
    if (run[i] >= 0.5 * peak) continue;
    below_lo |= zq[i].z < focus;
    below_hi |= zq[i].z > focus;
  }
  return below_lo && below_hi ? focus : NAN;
}

/* Which way each frame's object went: +1 up, -1 down, 0 not known (the
 * depths SWEEP_WAY_US before and after it, or either missing, the same);
 * returns 1 when the sweep went both ways, each in SWEEP_WAY_SHARE of the
 * frames whose way is known or more (a one-way sweep of 30 beads on a
 * slide had frames "going down" where its fit slipped, whose own focus
 * lay 11-33 um off).
 * A one-way sweep's focus lies on the side the object went to, by 0-2.4
 * um (the images of a bead coming into focus and leaving it differ), and
 * a sweep up and down fitted at once by 0.1-1.5 um; the mean of the two
 * ways' foci, each fitted alone, came within 0.4 um (seeds 1-4,
 * docs/recon.md "The focal plane from a sweep"). */
#define SWEEP_WAY_US 10000.0
#define SWEEP_WAY_SHARE 0.25
static int sweep_ways(const elfm_calib_sweep *s, const double *z, signed char *way_of)
{
  size_t up = 0, down = 0;
  for (size_t f = 0, a = 0, b = 0; f < s->n; f++) {
    while (s->t_us[f] - s->t_us[a] > SWEEP_WAY_US) a++;
    if (b < f) b = f;
    while (b + 1 < s->n && s->t_us[b + 1] - s->t_us[f] <= SWEEP_WAY_US) b++;
    const double dz = z[b] - z[a];
    way_of[f] = (signed char)(isnan(dz) || dz == 0 ? 0 : dz > 0 ? 1 : -1);
    up += way_of[f] > 0;
    down += way_of[f] < 0;
  }
  return up + down > 0 && (double)(up < down ? up : down) >= SWEEP_WAY_SHARE * (double)(up + down);
}

/* The alternation (the file's head) from c's centres into m, its views
 * with enough images near the model in use[], the views' shares of spots
 * near it into share[]; z, tu, tw: room for s->n values. Into s->fit:
 * frames_used, images, rms_px, agree. */
static void sweep_fit(elfm_calib_sweep *s, const elfm_calib *c, const int *tells, int min_images, double *z,
                      double *tu, double *tw, elfm_calib *m, int *use)
{
  const int nv = s->nv;
  double tmp[ELFM_MAX_VIEWS], share[ELFM_MAX_VIEWS];
  *m = *c;
  for (size_t f = 0; f < s->n; f++) z[f] = NAN;
  double ss = 0;
  size_t nss = 0;
  for (int it = 0; it < SWEEP_ITERATIONS; it++) {
    const double r = sweep_radius_px[it];
    int frames = 0;
    for (size_t f = 0; f < s->n; f++) {
      z[f] = frame_z(s, m, tells, f, z[f], r, tmp);
      frames += !isnan(z[f]);
    }
    s->fit.frames_used = frames;
    ss = 0;
    nss = 0;
    for (int v = 0; v < nv; v++) {
      const elfm_view *w = &m->views[v];
      size_t n = 0, told = 0;
      for (size_t f = 0; f < s->n; f++) {
        const double pu = s->pu[f * (size_t)nv + (size_t)v], pw = s->pw[f * (size_t)nv + (size_t)v];
        if (isnan(pu) || isnan(z[f])) continue;
        told++;
        const double eu = pu - w->dx_px_per_um * z[f], ew = pw - w->dy_px_per_um * z[f];
        if (!isinf(r) && hypot(eu - w->cx_px, ew - w->cy_px) > r) continue;
        tu[n] = eu;
        tw[n] = ew;
        n++;
      }
      s->fit.images[v] = (int)n;
      use[v] = n >= (size_t)min_images;
      share[v] = told > 0 ? (double)n / (double)told : NAN; /* the last step's is kept */
      if (!use[v]) continue;
      m->views[v].cx_px = elfm_calib_median(tu, n);
      m->views[v].cy_px = elfm_calib_median(tw, n);
    }
    /* the last step's fit: RMS distance of the images kept from the model */
    for (int v = 0; v < nv && it == SWEEP_ITERATIONS - 1; v++)
      for (size_t f = 0; use[v] && f < s->n; f++) {
        const double pu = s->pu[f * (size_t)nv + (size_t)v], pw = s->pw[f * (size_t)nv + (size_t)v];
        if (isnan(pu) || isnan(z[f])) continue;
        const elfm_view *w = &m->views[v];
        const double d = hypot(pu - w->cx_px - w->dx_px_per_um * z[f], pw - w->cy_px - w->dy_px_per_um * z[f]);
        if (d > r) continue;
        ss += d * d;
        nss++;
      }
  }
  s->fit.rms_px = nss > 0 ? sqrt(ss / (double)nss) : NAN;
  /* the views' median share of spots near the model: several objects
   * taken for one fit none of them */
  size_t ns = 0;
  for (int v = 0; v < nv; v++)
    if (tells[v] && !isnan(share[v])) tmp[ns++] = share[v];
  s->fit.agree = ns > 0 ? elfm_calib_median(tmp, ns) : 0;
}

/* The views' (those with tells[v]) median share of their frames with a
 * spot that hold two or more */
static double several_share(const elfm_calib_sweep *s, const int *tells)
{
  double tmp[ELFM_MAX_VIEWS];
  size_t n = 0;
  for (int v = 0; v < s->nv; v++) {
    size_t one = 0, two = 0;
    for (size_t f = 0; tells[v] && f < s->n; f++) {
      const int k = s->n_spots[f * (size_t)s->nv + (size_t)v];
      one += k >= 1;
      two += k >= 2;
    }
    if (one > 0) tmp[n++] = (double)two / (double)one;
  }
  return n > 0 ? elfm_calib_median(tmp, n) : 0;
}

elfm_status elfm_calib_sweep_apply(elfm_calib_sweep *s, int min_images, elfm_calib *c, double *shift_px,
                                   int *n_moved, elfm_error *err)
{
  if (c->n_views != s->nv)
    return elfm_error_set(err, ELFM_ERR_INVALID, NULL, -1,
                          "calib sweep: the calibration has %d views, the images %d", c->n_views, s->nv);
  if (min_images < 1) min_images = 1;
  const int nv = s->nv;
  double *z = malloc((s->n + 1) * sizeof *z), *tu = malloc((s->n + 1) * sizeof *tu),
         *tw = malloc((s->n + 1) * sizeof *tw);
  sweep_depth *zq = malloc((s->n + 1) * sizeof *zq);
  double *tq = malloc((s->n + 1) * sizeof *tq);
  if (!z || !tu || !tw || !zq || !tq) {
    free(tq);
    free(zq);
    free(z);
    free(tu);
    free(tw);
    return elfm_error_set(err, ELFM_ERR_NOMEM, NULL, -1, "calib sweep: out of memory");
  }
  double dmax = 0;
  for (int v = 0; v < nv; v++) dmax = fmax(dmax, hypot(c->views[v].dx_px_per_um, c->views[v].dy_px_per_um));
  int tells[ELFM_MAX_VIEWS];
  for (int v = 0; v < nv; v++)
    tells[v] = hypot(c->views[v].dx_px_per_um, c->views[v].dy_px_per_um) > SWEEP_D_MIN_FRAC * dmax;
  /* Several objects side by side, moving together? Then their pattern's
   * translations (calib_sweep_pattern.c) in place of the brightest spots,
   * which are now one object's image, now another's: two beads 10 um apart
   * fitted one object in most views and the other in a few, 9 px off, at a
   * median 0.5 or more of the spots near the fit. One object makes no
   * pattern of two, and its brightest spots are fitted. */
  float *qu = malloc(s->cap * (size_t)nv * sizeof *qu), *qw = malloc(s->cap * (size_t)nv * sizeof *qw);
  if (!qu || !qw) {
    free(qu);
    free(qw);
    free(tq);
    free(zq);
    free(z);
    free(tu);
    free(tw);
    return elfm_error_set(err, ELFM_ERR_NOMEM, NULL, -1, "calib sweep: out of memory");
  }
  s->fit.objects = elfm_calib_sweep_pattern(c, s->n, tells, s->n_spots, s->strength, s->spots, qu, qw,
                                            &s->fit.pattern_share, &s->fit.depth_um);
  if (s->fit.objects >= 2 && s->fit.pattern_share >= SWEEP_AGREE) {
    float *t = s->pu;
    s->pu = qu;
    qu = t;
    t = s->pw;
    s->pw = qw;
    qw = t;
  } else {
    s->fit.objects = 1;
  }
  free(qu);
  free(qw);
  s->fit.several_share = several_share(s, tells);
  /* the centres as they go, on a copy: c keeps the start until the end */
  elfm_calib m;
  int use[ELFM_MAX_VIEWS] = {0};
  sweep_fit(s, c, tells, min_images, z, tu, tw, &m, use);
  sweep_speed(s, z, tu);
  /* Centres fitted to another object's images in some views (beads in a
   * row taken for their neighbours, 11 px apart) still fit their images;
   * they lie off the lenslets' grid, which a calibration does not (the
   * optics' is affine in (i, j); a lens array's pitch errs by far less
   * than a pixel) */
  int on_grid[ELFM_MAX_VIEWS];
  for (int v = 0; v < nv; v++) on_grid[v] = use[v] && tells[v];
  s->fit.off_grid_px = elfm_calib_off_grid(&m, on_grid, &s->fit.off_grid_view);
  if (!(s->fit.agree >= SWEEP_AGREE) || (s->fit.objects == 1 && s->fit.several_share >= SWEEP_SEVERAL) ||
      s->fit.off_grid_px > ELFM_CALIB_SWEEP_OFF_GRID_PX)
    for (int v = 0; v < nv; v++) use[v] = 0;
  /* the moves, cleared of the gauge; views without enough images on the
   * grid of the others */
  double su[ELFM_MAX_VIEWS] = {0}, sw[ELFM_MAX_VIEWS] = {0};
  int moved = 0;
  for (int v = 0; v < nv; v++) {
    s->fit.placed[v] = 0;
    if (!use[v]) continue;
    su[v] = m.views[v].cx_px - c->views[v].cx_px;
    sw[v] = m.views[v].cy_px - c->views[v].cy_px;
    moved++;
  }
  /* views that do not tell z (the central one) see an axial sweep's
   * image stand still, its defocus alone: their centre rests on one pixel
   * phase (as refine's still views, settle_views), and goes on the grid of
   * the others when enough of them moved; so do views with too few images */
  int from[ELFM_MAX_VIEWS] = {0}, to[ELFM_MAX_VIEWS] = {0}, n_from = 0;
  for (int v = 0; v < nv; v++) {
    from[v] = use[v] && tells[v];
    to[v] = !from[v];
    n_from += from[v];
  }
  double sh[2 * ELFM_MAX_VIEWS] = {0};
  if (n_from >= ELFM_CALIB_GRID_MIN_VIEWS && n_from < nv) {
    elfm_calib_move_gauge_free(c, from, su, sw, sh);
    if (elfm_calib_place_on_grid(c, from, to, sh))
      for (int v = 0; v < nv; v++) s->fit.placed[v] = to[v];
    moved = n_from;
  } else {
    elfm_calib_move_gauge_free(c, use, su, sw, sh);
  }
  if (shift_px) memcpy(shift_px, sh, 2 * (size_t)nv * sizeof *shift_px);
  if (n_moved) *n_moved = moved;
  /* The focus, over the frames that told the depth, in the fit's depths z
   * (m's), then in those of c as it is now: images = m + d z = c + b + d
   * (z + g), b the objects' place, which m's centres hold and c's do not,
   * and g the gauge cleared from the moves (their part in proportion to
   * the disparities, least squares over the views fitted). Depths taken
   * anew from c's centres without b fit no view off the axis (a bead 47
   * um out, a slide's pattern: no frame within 1.5 px). */
  s->fit.focus_um = s->fit.focus_up_um = s->fit.focus_down_um = NAN;
  if (moved > 0) {
    double num = 0, den = 0;
    for (int axis = 0; axis < 2; axis++) {
      double n = 0, sd = 0, se = 0, sdd = 0, sde = 0;
      for (int v = 0; v < nv; v++) {
        if (!from[v]) continue;
        const double d = axis ? c->views[v].dy_px_per_um : c->views[v].dx_px_per_um;
        const double e = axis ? m.views[v].cy_px - c->views[v].cy_px : m.views[v].cx_px - c->views[v].cx_px;
        n += 1;
        sd += d;
        se += e;
        sdd += d * d;
        sde += d * e;
      }
      if (n < 1) continue;
      num += sde - sd * se / n;
      den += sdd - sd * sd / n;
    }
    const double g = den > 0 ? num / den : 0;
    signed char *way_of = (signed char *)tw; /* tw's room, no longer needed */
    if (sweep_ways(s, z, way_of)) {
      s->fit.focus_up_um = sweep_focus(s, tells, z, way_of, 1, zq, tu, tq);
      s->fit.focus_down_um = sweep_focus(s, tells, z, way_of, -1, zq, tu, tq);
    }
    s->fit.focus_um = isfinite(s->fit.focus_up_um) && isfinite(s->fit.focus_down_um)
                          ? 0.5 * (s->fit.focus_up_um + s->fit.focus_down_um)
                          : sweep_focus(s, tells, z, way_of, 0, zq, tu, tq);
    s->fit.focus_um += g;
    s->fit.focus_up_um += g;
    s->fit.focus_down_um += g;
  }
  free(tq);
  free(zq);
  free(z);
  free(tu);
  free(tw);
  s->n = 0;
  return ELFM_OK;
}

void elfm_calib_sweep_result(const elfm_calib_sweep *s, elfm_calib_sweep_fit *fit)
{
  *fit = s->fit;
}
