/* localize.c — a point's 3D position from its 25 images (elfm_refocus_localize).
 *
 * The refocused volume is the mean of the views' bilinear samples; a peak in
 * it is located by a parabola through three voxels per axis. That throws away
 * most of what the views say: each view holds a whole image of the object,
 * and in a Fourier LFM the image in view v sits at
 *     u_v = X + cx_v - (W-1)/2 + z dx_v,   w_v = Y + cy_v - (H-1)/2 + z dy_v
 * (the refocus geometry, elfm_refocus.h), linear in the unknowns (X, Y, z).
 * So: measure each view's image centre (the centroid of the frame in a small
 * window, re-centred as the fit moves) and solve the 2 x n_views linear
 * equations for (X, Y, z) by weighted least squares. Lateral position comes
 * from all views together, depth from how the images spread with the views'
 * disparities dx_v, dy_v: the classical Fourier LFM localisation.
 *
 * Other objects' images share some views' windows (in a 5 x 5 array of
 * views, 25 images per object crowd the sensor). So, after a few plain
 * re-centring passes, views whose centroid misses the fit by more than
 * outlier_px are dropped and the rest weighted by a Cauchy function of
 * their miss; each view's weight (its mass) is capped at the median mass,
 * as an unusually bright window most likely holds a second object. Windows
 * clipped by the view's crop box are not used (their centroid is pulled
 * inwards). tests/test_localize.c: 0.002 px and 0.005 um from the truth on
 * noise-free in-focus images, 0.04 px and 0.08 um on images twice as wide.
 *
 * Where the caller knows other objects nearby (elfm_refocus_localize_near),
 * their light is taken out of each window instead of judged afterwards:
 * the images of a C. elegans neuron pair 6 um apart overlap in every view,
 * so no view is free of the partner and the robust passes cannot help.
 */
#include <math.h>
#include <string.h>

#include "elfm_refocus.h"
#include "refocus_internal.h"

/* passes with outlier dropping and robust weights, after the re-centring */
#define ROBUST_PASSES 3
/* floor of the robust scale: noise-free synthetic images fit to 1e-3 px,
 * and a scale that small would weight every view down */
#define MIN_SCALE_PX 0.05
/* a neighbour's image closer than this to the object's is not taken out */
#define NEAR_MIN_PX 2.0
/* room for one pass's windows (localize): 25 views of 64 frames fit */
#define WIN_KEY_MAX 4096

void elfm_localize_options_default(elfm_localize_options *o)
{
  memset(o, 0, sizeof *o);
  o->half_window_px = 2;
  o->iterations = 4;
  o->outlier_px = 1.5;
  o->min_views = 6;
  o->power = 3;
  o->deep_z_um = INFINITY;
}

/* The frame's value at (x, y) by bilinear interpolation, positive part
 * only, 0 outside box b (another view's light is not this one's). */
static double sample_box(const elfm_frame *f, const elfm_refocus_box *b, int ro, double x, double y)
{
  if (!(x >= b->x0 && y >= b->y0 && x <= b->x1 - 1 && y <= b->y1 - 1)) return 0;
  long ix = (long)floor(x), iy = (long)floor(y);
  if (ix > b->x1 - 2) ix = b->x1 - 2;
  if (iy > b->y1 - 2) iy = b->y1 - 2;
  const double fx = x - (double)ix, fy = y - (double)iy;
  const float *r0 = f->data + (size_t)iy * (size_t)f->w + ix, *r1 = r0 + f->w;
  const float fl = ro ? f->recent_floor : 0.0f; /* 0: every pixel counts */
  const double v00 = r0[0] > 0 && r0[0] >= fl ? r0[0] : 0, v01 = r0[1] > 0 && r0[1] >= fl ? r0[1] : 0;
  const double v10 = r1[0] > 0 && r1[0] >= fl ? r1[0] : 0, v11 = r1[1] > 0 && r1[1] >= fl ? r1[1] : 0;
  return (1 - fy) * ((1 - fx) * v00 + fx * v01) + fy * ((1 - fx) * v10 + fx * v11);
}

/* Centroid of the frame over the (2r+1)^2 window at the nearest pixel to
 * (u, w), inside box b only. Returns the mass (0: nothing, -1: the window
 * leaves the box). With neighbours (nb[2k], nb[2k+1]: neighbour k's image
 * centre in this view; elfm_refocus_localize_near), their light is taken
 * out first: a neighbour's light at pixel x is estimated as the value at x
 * mirrored through its centre (2 nb - x), as if its image were symmetric:
 * the far side of a neighbour holds its own light and not this object's. */
static double window_centroid_at(const elfm_frame *f, const elfm_refocus_box *b, int ro, long iu,
                                 long iw, int r, int pw, const double *nb, int n_nb, double *cu,
                                 double *cw)
{
  const float fl = ro ? f->recent_floor : 0.0f;
  if (iu - r < b->x0 || iu + r >= b->x1 || iw - r < b->y0 || iw + r >= b->y1) return -1;
  double m = 0, su = 0, sw = 0;
  for (long y = iw - r; y <= iw + r; y++) {
    const float *row = f->data + (size_t)y * (size_t)f->w;
    double rm = 0, ru = 0;
    for (long x = iu - r; x <= iu + r; x++) {
      /* positive values only: on a signed surface (ON - OFF) the OFF
       * trail is not the object, and negative weights could put a
       * centroid outside its window */
      double f0 = row[x] > 0 && row[x] >= fl ? row[x] : 0;
      for (int k = 0; k < n_nb && f0 > 0; k++)
        f0 -= sample_box(f, b, ro, 2 * nb[2 * k] - (double)x, 2 * nb[2 * k + 1] - (double)y);
      if (!(f0 > 0)) continue;
      double v = f0;
      for (int k = 1; k < pw; k++) v *= f0;
      rm += v;
      ru += v * (double)(x - iu);
    }
    m += rm;
    su += ru;
    sw += rm * (double)(y - iw);
  }
  if (!(m > 0)) return 0;
  *cu = (double)iu + su / m;
  *cw = (double)iw + sw / m;
  return m;
}

/* A window's centre pixel: the nearest to u, or WIN_OFF where lround's
 * range ends (far off any box anyway). */
#define WIN_OFF INT32_MIN
static int32_t win_round(double u) { return fabs(u) < 1e7 ? (int32_t)lround(u) : WIN_OFF; }

static double window_centroid(const elfm_frame *f, const elfm_refocus_box *b, int ro, double u,
                              double w, int r, int pw, const double *nb, int n_nb, double *cu,
                              double *cw)
{
  const int32_t iu = win_round(u), iw = win_round(w);
  if (iu == WIN_OFF || iw == WIN_OFF) return -1;
  return window_centroid_at(f, b, ro, iu, iw, r, pw, nb, n_nb, cu, cw);
}

/* Insert x into a[0 .. *n), kept ascending (for the medians of at most
 * MAXV views: an insertion sort is all that is needed). */
static void insert_sorted(double *a, int *n, double x)
{
  int k = (*n)++;
  while (k > 0 && a[k - 1] > x) {
    a[k] = a[k - 1];
    k--;
  }
  a[k] = x;
}

/* Weighted least squares for (X, Y, z) from per-view centroids: rows
 * cu - a_u = X + z du, cw - a_w = Y + z dw. Solves the 3 x 3 normal
 * equations; 0 when singular (all disparities equal: no depth information). */
static int solve_xyz(int n, const double *wt, const double *ru, const double *rw, const double *du,
                     const double *dw, double out[3])
{
  double sw = 0, sdu = 0, sdw = 0, sdd = 0, bu = 0, bw = 0, bz = 0;
  for (int i = 0; i < n; i++) {
    const double w = wt[i];
    if (!(w > 0)) continue;
    sw += w;
    sdu += w * du[i];
    sdw += w * dw[i];
    sdd += w * (du[i] * du[i] + dw[i] * dw[i]);
    bu += w * ru[i];
    bw += w * rw[i];
    bz += w * (du[i] * ru[i] + dw[i] * rw[i]);
  }
  /* [sw 0 sdu; 0 sw sdw; sdu sdw sdd] (X Y z)' = (bu bw bz)'. Eliminating
   * X and Y leaves D z = sw bz - sdu bu - sdw bw with D = sw^2 x the weighted
   * variance of the disparities: 0 when they are all equal (no depth). */
  if (!(sw > 0)) return 0;
  const double D = sw * sdd - sdu * sdu - sdw * sdw;
  if (!(D > 1e-9 * sw * sdd)) return 0;
  const double z = (sw * bz - sdu * bu - sdw * bw) / D;
  if (!isfinite(z)) return 0;
  out[0] = (bu - sdu * z) / sw;
  out[1] = (bw - sdw * z) / sw;
  out[2] = z;
  return 1;
}

/* The centroid of one view's image over n frames: frame j's window sits
 * where the object was then (q + off[j]; its centre pixel c[2j], c[2j+1],
 * view_centres), and its centroid is moved back by that offset's image
 * shift (off[j][0] + off[j][2] du in u, the same in w), so that all
 * frames' events add up at the object's position in frame 0. Frames whose
 * window leaves the view's box are skipped. Returns the summed mass (0:
 * nothing; -1: no frame's window fits). */
static double view_centroid(const elfm_frame *const *frames, const double (*off)[3], int n_frames,
                            const elfm_refocus_box *b, int ro, const int32_t *c, double du,
                            double dw, int r, int pw, double *cu, double *cw)
{
  if (n_frames == 1 && !off) { /* the single-frame fit, exactly as it always was */
    if (c[0] == WIN_OFF || c[1] == WIN_OFF) return -1;
    return window_centroid_at(frames[0], b, ro, c[0], c[1], r, pw, NULL, 0, cu, cw);
  }
  double m = 0, su = 0, sw = 0;
  int any = 0;
  for (int j = 0; j < n_frames; j++) {
    const double ox = off ? off[j][0] : 0, oy = off ? off[j][1] : 0, oz = off ? off[j][2] : 0;
    const double su0 = ox + oz * du, sw0 = oy + oz * dw;
    double u, w;
    if (c[2 * j] == WIN_OFF || c[2 * j + 1] == WIN_OFF) continue;
    const double mj =
        window_centroid_at(frames[j], b, ro, c[2 * j], c[2 * j + 1], r, pw, NULL, 0, &u, &w);
    if (mj < 0) continue;
    any = 1;
    if (mj == 0) continue;
    m += mj;
    su += mj * (u - su0);
    sw += mj * (w - sw0);
  }
  if (!any) return -1;
  if (!(m > 0)) return 0;
  *cu = su / m;
  *cw = sw / m;
  return m;
}

/* The centre pixels of view v's windows at q, one pair per frame (frame
 * j's at q + off[j], moved by that offset's image shift). */
static void view_centres(const double (*off)[3], int n_frames, const double q[3], double au,
                         double aw, double du, double dw, int32_t *c)
{
  for (int j = 0; j < n_frames; j++) {
    const double ox = off ? off[j][0] : 0, oy = off ? off[j][1] : 0, oz = off ? off[j][2] : 0;
    const double su0 = ox + oz * du, sw0 = oy + oz * dw;
    c[2 * j] = win_round(q[0] + au + q[2] * du + su0);
    c[2 * j + 1] = win_round(q[1] + aw + q[2] * dw + sw0);
  }
}

/* The window of view v at q where neighbours are known (nq[0 .. nn): its
 * centre pixel in c[0], c[1], and the neighbours whose images lie close
 * enough to reach it, but not on top of it (mirrored, an image on top
 * would take out the object's own light: the robust passes judge that
 * view), listed in nb[0 .. 2 n_nb) as image centres. Returns their bits. */
static int32_t near_pick(const double q[3], double au, double aw, double du, double dw,
                         const double (*nq)[3], int nn, double reach, int32_t *c, double *nb,
                         int *n_nb)
{
  const double pu = q[0] + au + q[2] * du, pw = q[1] + aw + q[2] * dw;
  c[0] = win_round(pu);
  c[1] = win_round(pw);
  int32_t bits = 0;
  *n_nb = 0;
  for (int k = 0; k < nn; k++) {
    const double bu = nq[k][0] + au + nq[k][2] * du;
    const double bw = nq[k][1] + aw + nq[k][2] * dw;
    const double d2 = (bu - pu) * (bu - pu) + (bw - pw) * (bw - pw);
    if (d2 < reach * reach && d2 > NEAR_MIN_PX * NEAR_MIN_PX) {
      nb[2 * *n_nb] = bu;
      nb[2 * *n_nb + 1] = bw;
      (*n_nb)++;
      bits |= (int32_t)1 << k;
    }
  }
  return bits;
}

int elfm_refocus_localize(const elfm_refocus_plan *p, const elfm_frame *frame, double x_vox,
                          double y_vox, double z_vox, const elfm_localize_options *o,
                          elfm_localize_result *out)
{
  return elfm_refocus_localize_frames(p, &frame, NULL, 1, x_vox, y_vox, z_vox, o, out);
}

static int localize(const elfm_refocus_plan *p, const elfm_frame *const *frames,
                    const double (*off_vox)[3], int n_frames, double x_vox, double y_vox,
                    double z_vox, const double (*near_vox)[3], int n_near,
                    const elfm_localize_options *o, elfm_localize_result *out, double *miss_px,
                    double *weight);

int elfm_refocus_localize_frames(const elfm_refocus_plan *p, const elfm_frame *const *frames,
                                 const double (*off_vox)[3], int n_frames, double x_vox,
                                 double y_vox, double z_vox, const elfm_localize_options *o,
                                 elfm_localize_result *out)
{
  return localize(p, frames, off_vox, n_frames, x_vox, y_vox, z_vox, NULL, 0, o, out, NULL, NULL);
}

int elfm_refocus_localize_misses(const elfm_refocus_plan *p, const elfm_frame *frame, double x_vox,
                                 double y_vox, double z_vox, const elfm_localize_options *o,
                                 elfm_localize_result *out, double *miss_px, double *weight)
{
  if (!miss_px || !weight) return 0;
  return localize(p, &frame, NULL, 1, x_vox, y_vox, z_vox, NULL, 0, o, out, miss_px, weight);
}

int elfm_refocus_localize_near(const elfm_refocus_plan *p, const elfm_frame *frame, double x_vox,
                               double y_vox, double z_vox, const double (*near_vox)[3], int n_near,
                               const elfm_localize_options *o, elfm_localize_result *out)
{
  if (n_near < 0 || (n_near > 0 && !near_vox)) return 0;
  return localize(p, &frame, NULL, 1, x_vox, y_vox, z_vox, near_vox, n_near, o, out, NULL, NULL);
}

static int localize(const elfm_refocus_plan *p, const elfm_frame *const *frames,
                    const double (*off_vox)[3], int n_frames, double x_vox, double y_vox,
                    double z_vox, const double (*near_vox)[3], int n_near,
                    const elfm_localize_options *o, elfm_localize_result *out, double *miss_px,
                    double *weight)
{
  enum { MAXV = 256, MAXF = 64, MAXN = 16 };
  const elfm_calib *c = &p->calib;
  if (!frames || n_frames < 1 || n_frames > MAXF || p->nv > MAXV || !o ||
      o->half_window_px < 1 || o->half_window_px > 32 || !(o->outlier_px > 0) || o->min_views < 2 ||
      o->power < 1 || o->power > 8 || o->iterations > 100 ||
      !isfinite(x_vox) || !isfinite(y_vox) || !isfinite(z_vox))
    return 0;
  /* neighbours: the first MAXN given (the caller lists the near ones; a
   * window meets a few images) */
  double nq[MAXN][3];
  int nn = 0;
  for (int k = 0; k < n_near && nn < MAXN; k++) {
    if (!(isfinite(near_vox[k][0]) && isfinite(near_vox[k][1]) && isfinite(near_vox[k][2])))
      return 0;
    nq[nn][0] = near_vox[k][0];
    nq[nn][1] = near_vox[k][1];
    nq[nn][2] = p->calib.z_min_um + near_vox[k][2] * p->calib.z_step_um;
    nn++;
  }
  for (int j = 0; j < n_frames; j++) {
    if (!frames[j] || frames[j]->w != p->sw || frames[j]->h != p->sh) return 0;
    if (off_vox && !(isfinite(off_vox[j][0]) && isfinite(off_vox[j][1]) && isfinite(off_vox[j][2])))
      return 0;
  }
  const double hw = 0.5 * (p->w - 1), hh = 0.5 * (p->h - 1);
  double au[MAXV], aw[MAXV], du[MAXV], dw[MAXV], ru[MAXV], rw[MAXV], wt[MAXV];
  int keep[MAXV];
  for (int v = 0; v < p->nv; v++) {
    au[v] = c->views[v].cx_px - hw;
    aw[v] = c->views[v].cy_px - hh;
    du[v] = c->views[v].dx_px_per_um;
    dw[v] = c->views[v].dy_px_per_um;
    keep[v] = 1;
  }
  /* unknowns: X, Y (volume voxels = sensor px), z (um) */
  double q[3] = {x_vox, y_vox, c->z_min_um + z_vox * c->z_step_um};
  /* a fit started nearer focus than deep_z_um reads a deep window's
   * frames as the window alone, as the refocus did; a deeper one reads
   * every pixel (elfm_localize_options.deep_z_um) */
  const int ro = !(fabs(q[2]) >= o->deep_z_um);
  const double zlo = c->z_min_um - c->z_step_um, zhi = c->z_min_um + p->nz * c->z_step_um;
  const double out2 = o->outlier_px * o->outlier_px;
  const int passes = o->iterations < 1 ? 1 : o->iterations;
  double mass[MAXV], fac[MAXV], e2[MAXV];
  for (int v = 0; v < p->nv; v++) fac[v] = 1;
  /* Each pass reads the frames only through its windows: per view (and
   * frame) the centre pixel, and with neighbours the ones taken out. A
   * plain pass whose windows are the last pass's computes the same
   * centroids and leaves q where it is, as does every plain pass after
   * it: the robust passes then start at once. The same bits in fewer
   * passes (docs/recon.md "Passes that would repeat"). So, view by view:
   * a view whose windows are the last pass's has the last pass's
   * centroid (prev_m, prev_cu, prev_cw), and only q's fit to it is new.
   * The windows of the last two passes are kept (win[cur], win[cur ^ 1])
   * where they fit, per view: 2 per frame, and with neighbours the bits
   * of those taken out. */
  const int per = 2 * n_frames + (nn > 0);
  const int fits = p->nv * per <= WIN_KEY_MAX;
  int32_t win[2][WIN_KEY_MAX], scratch[2 * MAXF + 1];
  double nbv[MAXV][2 * MAXN], prev_m[MAXV], prev_cu[MAXV], prev_cw[MAXV];
  int n_nbv[MAXV];
  int cur = 0, have_last = 0;
  const double reach = 3.0 * (2 * o->half_window_px + 1);
  for (int it = 0; it < passes + ROBUST_PASSES; it++) {
    if (fits) {
      for (int v = 0; v < p->nv; v++) {
        int32_t *c = win[cur] + (size_t)v * (size_t)per;
        if (!keep[v]) {
          for (int k = 0; k < per; k++) c[k] = WIN_OFF;
          continue;
        }
        if (nn > 0)
          c[2] = near_pick(q, au[v], aw[v], du[v], dw[v], nq, nn, reach, c, nbv[v], &n_nbv[v]);
        else
          view_centres(off_vox, n_frames, q, au[v], aw[v], du[v], dw[v], c);
      }
      if (it < passes && have_last &&
          memcmp(win[cur], win[cur ^ 1], (size_t)(p->nv * per) * sizeof win[0][0]) == 0)
        it = passes; /* the plain passes have settled: on to the robust ones */
    }
    int n_used = 0;
    for (int v = 0; v < p->nv; v++) {
      mass[v] = 0;
      if (!keep[v]) continue;
      double cu = 0, cw = 0, m;
      const int32_t *c = fits ? win[cur] + (size_t)v * (size_t)per : scratch;
      if (fits && have_last &&
          memcmp(c, win[cur ^ 1] + (size_t)v * (size_t)per, (size_t)per * sizeof *c) == 0) {
        m = prev_m[v]; /* the same windows: the same centroid */
        cu = prev_cu[v];
        cw = prev_cw[v];
      } else {
        if (!fits && nn > 0)
          scratch[2] = near_pick(q, au[v], aw[v], du[v], dw[v], nq, nn, reach, scratch, nbv[v],
                                 &n_nbv[v]);
        else if (!fits)
          view_centres(off_vox, n_frames, q, au[v], aw[v], du[v], dw[v], scratch);
        if (nn > 0)
          m = c[0] == WIN_OFF || c[1] == WIN_OFF
                  ? -1
                  : window_centroid_at(frames[0], &p->box[v], ro, c[0], c[1], o->half_window_px,
                                       o->power, nbv[v], n_nbv[v], &cu, &cw);
        else
          m = view_centroid(frames, off_vox, n_frames, &p->box[v], ro, c, du[v], dw[v],
                            o->half_window_px, o->power, &cu, &cw);
        prev_m[v] = m;
        prev_cu[v] = cu;
        prev_cw[v] = cw;
      }
      if (m <= 0) continue;
      mass[v] = m;
      ru[v] = cu - au[v];
      rw[v] = cw - aw[v];
      const double eu = ru[v] - (q[0] + q[2] * du[v]), ew = rw[v] - (q[1] + q[2] * dw[v]);
      e2[v] = eu * eu + ew * ew;
    }
    if (it >= passes) {
      /* Robust passes: a view whose centroid misses by more than
       * outlier_px holds another object (or only noise) and is dropped;
       * the others are weighted by a Cauchy function of their miss over
       * 2.5 x its robust scale (1.4826 x median), so that a view where a
       * neighbour's image overlaps part of the window and pulls its
       * centroid by a fraction of a pixel counts little. */
      double sorted[MAXV];
      int ns = 0;
      for (int v = 0; v < p->nv; v++) {
        if (!(mass[v] > 0)) continue;
        if (e2[v] > out2) {
          keep[v] = 0;
          mass[v] = 0;
          continue;
        }
        insert_sorted(sorted, &ns, sqrt(e2[v]));
      }
      if (ns > 0) {
        const double med = ns % 2 ? sorted[ns / 2] : 0.5 * (sorted[ns / 2 - 1] + sorted[ns / 2]);
        const double scale = 2.5 * fmax(1.4826 * med, MIN_SCALE_PX);
        for (int v = 0; v < p->nv; v++)
          if (mass[v] > 0) fac[v] = 1.0 / (1.0 + e2[v] / (scale * scale));
      }
    }
    /* Weight = the window's mass, capped at the median mass: a view with
     * little signal has a noisy centroid, but one far brighter than the
     * others most likely holds a second object as well (with values^3, an
     * overlapping image 1.6 x brighter outweighed the bead's own 4 x). */
    double ms[MAXV];
    for (int v = 0; v < p->nv; v++)
      if (mass[v] > 0) insert_sorted(ms, &n_used, mass[v]);
    const double mcap = n_used ? ms[n_used / 2] : 0;
    for (int v = 0; v < p->nv; v++) wt[v] = fmin(mass[v], mcap) * fac[v];
    if (n_used < o->min_views) return 0;
    double nq[3];
    if (!solve_xyz(p->nv, wt, ru, rw, du, dw, nq)) return 0;
    if (!(nq[2] >= zlo && nq[2] <= zhi) || fabs(nq[0] - x_vox) > 2 * o->half_window_px ||
        fabs(nq[1] - y_vox) > 2 * o->half_window_px)
      return 0; /* walked off: not a point this fit can follow */
    memcpy(q, nq, sizeof q);
    cur ^= 1;
    have_last = fits;
  }
  /* the views that agree: kept, with signal, and weighted at least half */
  int n_final = 0;
  double ss = 0, sw = 0;
  for (int v = 0; v < p->nv; v++) {
    if (miss_px) miss_px[2 * v] = miss_px[2 * v + 1] = weight[v] = 0;
    if (!(mass[v] > 0)) continue;
    const double eu = ru[v] - (q[0] + q[2] * du[v]), ew = rw[v] - (q[1] + q[2] * dw[v]);
    if (miss_px) {
      /* every view kept, also one the robust weight played down: a view
       * whose centre is off misses every point by the same sub-pixel
       * amount, which is what a calibration wants to see */
      miss_px[2 * v] = eu;
      miss_px[2 * v + 1] = ew;
      weight[v] = wt[v];
    }
    if (fac[v] < 0.5) continue;
    ss += wt[v] * (eu * eu + ew * ew);
    sw += wt[v];
    n_final++;
  }
  if (n_final < o->min_views) return 0;
  /* of those, the views whose window in frames[0] alone has signal that
   * agrees with the fit: with several frames, how much of the result the
   * wanted frame itself supports */
  int n_first = n_final;
  if (n_frames > 1) {
    n_first = 0;
    for (int v = 0; v < p->nv; v++) {
      if (!(mass[v] > 0) || fac[v] < 0.5) continue;
      double cu, cw;
      const double m = window_centroid(frames[0], &p->box[v], ro, q[0] + au[v] + q[2] * du[v],
                                       q[1] + aw[v] + q[2] * dw[v], o->half_window_px, o->power,
                                       NULL, 0, &cu, &cw);
      if (m <= 0) continue;
      const double eu = cu - au[v] - (q[0] + q[2] * du[v]), ew = cw - aw[v] - (q[1] + q[2] * dw[v]);
      if (eu * eu + ew * ew <= out2) n_first++;
    }
  }
  out->n_views_first = n_first;
  out->x_vox = q[0];
  out->y_vox = q[1];
  out->z_vox = (q[2] - c->z_min_um) / c->z_step_um;
  out->n_views = n_final;
  out->rms_px = sw > 0 ? sqrt(ss / sw) : 0;
  out->sd_px = out->rms_px / sqrt((double)n_final);
  return 1;
}
