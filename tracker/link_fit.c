/* link_fit.c — a live track's fits to its last points (link_internal.h):
 * the line and the quadratic through a window of points, the long
 * constant-velocity fit and the short constant-acceleration one that
 * predict its next point (link_predict.c), its mean intensity over a span.
 * Shared by the step (link.c), gap filling (link_fill.c) and the reviews
 * (link_repair.c). */
#include <math.h>
#include <string.h>

#include "link_internal.h"

/* Shared with link_fill.c (link_internal.h). */
double elfm_link_mean_intensity(const elfm_track *t, size_t a, size_t b)
{
  double s = 0;
  for (size_t k = a; k < b; k++) s += t->pts[k].intensity;
  return b > a ? s / (double)(b - a) : 0;
}

/* Shared with link_repair.c (link_internal.h). */
int elfm_link_fit_quad(const elfm_detection *pts, size_t k0, size_t k1, int64_t tr,
                       double pos[3], double vel[3], double acc[3])
{
  /* normal equations of p = c0 + c1 t + c2 t^2 over the window */
  double S[5] = {0, 0, 0, 0, 0}, R[3][3] = {{0}};
  for (size_t k = k0; k < k1; k++) {
    double tm = (double)(pts[k].t_us - tr) * 1e-3, tp = 1;
    const double p[3] = {pts[k].x_um, pts[k].y_um, pts[k].z_um};
    for (int e = 0; e < 5; e++, tp *= tm) S[e] += tp;
    for (int a = 0; a < 3; a++) {
      R[a][0] += p[a];
      R[a][1] += tm * p[a];
      R[a][2] += tm * tm * p[a];
    }
  }
  double M[3][3] = {{S[0], S[1], S[2]}, {S[1], S[2], S[3]}, {S[2], S[3], S[4]}};
  const double det = link_det3(M);
  if (!(fabs(det) > 1e-9)) return 0;  /* fewer than 3 distinct times */
  for (int a = 0; a < 3; a++) {
    double c[3];
    link_cramer3(M, det, R[a], c);
    pos[a] = c[0];
    vel[a] = c[1];
    acc[a] = 2 * c[2];
  }
  return 1;
}

/* Shared with link_repair.c (link_internal.h). */
int elfm_link_fit_line(const elfm_detection *pts, size_t k0, size_t k1, int64_t tr, double pos[3],
                       double vel[3])
{
  double m = 0, st = 0, stt = 0, sx[3] = {0, 0, 0}, stx[3] = {0, 0, 0};
  for (size_t k = k0; k < k1; k++) {
    const double tm = (double)(pts[k].t_us - tr) * 1e-3;
    const double p[3] = {pts[k].x_um, pts[k].y_um, pts[k].z_um};
    m += 1;
    st += tm;
    stt += tm * tm;
    for (int a = 0; a < 3; a++) {
      sx[a] += p[a];
      stx[a] += tm * p[a];
    }
  }
  const double den = m * stt - st * st;
  if (!(den > 1e-12)) return 0;
  for (int a = 0; a < 3; a++) {
    vel[a] = (m * stx[a] - st * sx[a]) / den;
    pos[a] = (sx[a] - vel[a] * st) / m;
  }
  return 1;
}

int elfm_link_local_velocity(const elfm_track *t, int64_t frame, int half_frames, double v[3])
{
  if (!t || !t->n || half_frames < 0) return 0;
  /* the points are in frame order: those within the window are a run,
   * found by bisection (a long track holds thousands) */
  size_t lo = 0, up = t->n;
  while (lo < up) {
    const size_t mid = lo + (up - lo) / 2;
    if (t->pts[mid].frame < frame - half_frames) lo = mid + 1;
    else up = mid;
  }
  size_t hi = lo;
  while (hi < t->n && t->pts[hi].frame <= frame + half_frames) hi++;
  double pos[3];
  if (hi - lo < 3 || !elfm_link_fit_line(t->pts, lo, hi, t->pts[lo].t_us, pos, v)) return 0;
  return (int)(hi - lo);
}

/* The first of the points [lo, n) of t that the last path_um of path
 * (the anisotropic steps between the points, z / kz) reaches back to,
 * keeping at least min_points (when there are). */
static size_t path_start(const elfm_track *t, size_t lo, size_t n, double path_um, size_t min_points,
                         double kz)
{
  double path = 0;
  size_t k = n - 1;
  while (k > lo) {
    const elfm_detection *a = &t->pts[k - 1], *b = &t->pts[k];
    const double dx = b->x_um - a->x_um, dy = b->y_um - a->y_um, dz = (b->z_um - a->z_um) / kz;
    path += sqrt(dx * dx + dy * dy + dz * dz);
    if (path > path_um && n - k >= min_points) break;
    k--;
  }
  return k;
}

/* Points of the next frame's circle (elfm_link_options.circle_next_path_um):
 * at most this many, whatever the path (a slow track's 45 um). */
#define CIRCLE_NEXT_MAX_POINTS 64

/* Shared with link_repair.c (link_internal.h). */
void elfm_link_fit_velocity(live_track *lt, const elfm_link_options *o)
{
  const int history = o->history, short_history = o->short_history;
  const double *prior = o->prior_velocity_um_per_ms;
  const elfm_track *t = lt->t;
  size_t n = t->n;
  const int64_t tr = t->pts[n - 1].t_us;
  memcpy(lt->vel_um_per_ms, prior, sizeof lt->vel_um_per_ms);
  lt->lin_pos[0] = t->pts[n - 1].x_um;
  lt->lin_pos[1] = t->pts[n - 1].y_um;
  lt->lin_pos[2] = t->pts[n - 1].z_um;
  lt->has_short = 0;
  lt->circ.ok = 0;
  if (o->circle_points > 0) {
    const size_t c0 = n > (size_t)o->circle_points ? n - (size_t)o->circle_points : 0;
    elfm_link_fit_circle(o, t->pts, c0, n, tr, &lt->circ);
  }
  lt->circ_next.ok = 0;
  if (o->circle_next_path_um > 0 && n >= 6) {
    const size_t lo = n > CIRCLE_NEXT_MAX_POINTS ? n - CIRCLE_NEXT_MAX_POINTS : 0;
    elfm_link_fit_circle(o, t->pts, path_start(t, lo, n, o->circle_next_path_um, 6, o->kz), n, tr,
                         &lt->circ_next);
  }
  size_t k0 = n > (size_t)history ? n - (size_t)history : 0;
  /* with all points at one time, the prior is kept */
  if (n - k0 >= 2) elfm_link_fit_line(t->pts, k0, n, tr, lt->lin_pos, lt->vel_um_per_ms);
  k0 = n > (size_t)short_history ? n - (size_t)short_history : 0;
  if (n - k0 < 4) return;
  if (o->short_path_um > 0)
    /* At most short_path_um of path (the anisotropic steps between the
     * points, z / kz), and at least 4 points: a parabola through a turn is
     * a good prediction only over a fraction of it, and what limits the
     * fraction is the arc travelled, not the number of frames. A flow bead
     * at 2.5-4 um/ms on a helix of radius 8-20 um covers 20 um in the 8
     * points the fit keeps; at 5-8 um/ms, 8 points span 40-55 um, more
     * than a radian of its turn, and the linker lost it between frames
     * (docs/tracker.md "Fast beads"). */
    k0 = path_start(t, k0, n, o->short_path_um, 4, o->kz);
  lt->has_short = elfm_link_fit_quad(t->pts, k0, n, tr, lt->fit_pos, lt->fit_vel, lt->fit_acc);
}
