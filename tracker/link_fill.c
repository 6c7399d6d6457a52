/* link_fill.c — the linker's side of gap filling (elfm_link.h, "Gap
 * filling"): which gaps of the live tracks are settled, where their object
 * was, and taking the points the caller found there.
 *
 * Why after the fact: a deep bead leaves no peak in some frames and its
 * track coasts. While it coasts, the only guess of where it is comes from
 * its past (elfm_link_predict, the track-guided fit); once the track has
 * found the bead again, both ends of the gap are known, and a search
 * between them starts much nearer the bead. Points given back only fill
 * the track's past, so the linker's later decisions (made from the last
 * points) are the same as without them: a setting that changes what the
 * linker sees flips crossings and moves a seed's alpha by +-0.05 for no
 * net gain (docs/tracker.md "Gap filling"). */
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "link_internal.h"

/* The points' fit at pts[ref]: constant acceleration over [k0, k1) (the
 * linker's short history) when they are 4 with 3 distinct times, else a
 * constant velocity through the first and last, else at rest. */
static void end_fit(const elfm_track *t, size_t k0, size_t k1, size_t ref, double pos[3],
                    double vel[3], double acc[3])
{
  const elfm_detection *r = &t->pts[ref];
  pos[0] = r->x_um;
  pos[1] = r->y_um;
  pos[2] = r->z_um;
  memset(vel, 0, 3 * sizeof *vel);
  memset(acc, 0, 3 * sizeof *acc);
  if (k1 - k0 >= 4 && elfm_link_fit_quad(t->pts, k0, k1, r->t_us, pos, vel, acc)) return;
  const elfm_detection *a = &t->pts[k0], *b = &t->pts[k1 - 1];
  double dt_ms = (double)(b->t_us - a->t_us) * 1e-3;
  if (dt_ms > 0) {
    vel[0] = (b->x_um - a->x_um) / dt_ms;
    vel[1] = (b->y_um - a->y_um) / dt_ms;
    vel[2] = (b->z_um - a->z_um) / dt_ms;
  }
}

/* Mean intensity of up to 3 points each side of pts[k-1] | pts[k]
 * (k = 0: after only). */
static double ends_intensity(const elfm_track *t, size_t k)
{
  return elfm_link_mean_intensity(t, k >= 3 ? k - 3 : 0, t->n - k > 3 ? k + 3 : t->n);
}

/* The gap between pts[k-1] and pts[k] of t; h: points each end's fit uses. */
static void make_gap(const elfm_link_options *o, const elfm_track *t, size_t k, size_t h,
                     elfm_link_gap *g)
{
  memset(g, 0, sizeof *g);
  g->track_id = t->id;
  g->frame0 = t->pts[k - 1].frame;
  g->frame1 = t->pts[k].frame;
  g->t0_us = t->pts[k - 1].t_us;
  g->t1_us = t->pts[k].t_us;
  end_fit(t, k > h ? k - h : 0, k, k - 1, g->p0_um, g->v0_um_per_ms, g->a0_um_per_ms2);
  end_fit(t, k, t->n - k > h ? k + h : t->n, k, g->p1_um, g->v1_um_per_ms, g->a1_um_per_ms2);
  g->intensity = ends_intensity(t, k);
  /* Across the gap: the circle through circle_gap_points points on each
   * side (at least 3), where the two ends' turns each extrapolate over
   * half of it (elfm_link_options.circle_gap_points says what it gains). */
  if (o->circle_points > 0 && o->circle_gap_points >= 3) {
    const size_t side = (size_t)o->circle_gap_points;
    const size_t c0 = k > side ? k - side : 0, c1 = t->n - k > side ? k + side : t->n;
    if (k - c0 >= 3 && c1 - k >= 3)
      elfm_link_fit_circle(o, t->pts, c0, c1, g->t0_us, &g->circle);
  }
}

/* The open gap at one end of t (t->n >= 1): before its first point
 * (open_start, the tail's fit over its first h points) or after its last
 * (open_end, the head's fit over its last h points), up to max_gap frames
 * away; with o->circle_end_points, also the circle through that many
 * points at that end (reference time: the end point's), which a circling
 * bead follows where the end's turn leaves it within 2-3 frames
 * (test_link_fill 3c). */
static void open_gap(const elfm_link_options *o, const elfm_track *t, int at_end, size_t h,
                     int max_gap, elfm_link_gap *g)
{
  const size_t n = t->n;
  const size_t c = o->circle_points > 0 ? (size_t)o->circle_end_points : 0;
  memset(g, 0, sizeof *g);
  g->track_id = t->id;
  if (at_end) {
    g->open_end = 1;
    g->frame0 = t->pts[n - 1].frame;
    g->t0_us = g->t1_us = t->pts[n - 1].t_us;
    g->frame1 = g->frame0 + max_gap + 1;
    end_fit(t, n > h ? n - h : 0, n, n - 1, g->p0_um, g->v0_um_per_ms, g->a0_um_per_ms2);
    g->intensity = ends_intensity(t, n);
    if (c) elfm_link_fit_circle(o, t->pts, n > c ? n - c : 0, n, g->t0_us, &g->circle);
  } else {
    g->open_start = 1;
    g->frame1 = t->pts[0].frame;
    g->t0_us = g->t1_us = t->pts[0].t_us;
    g->frame0 = g->frame1 - max_gap - 1;
    end_fit(t, 0, n > h ? h : n, 0, g->p1_um, g->v1_um_per_ms, g->a1_um_per_ms2);
    g->intensity = ends_intensity(t, 0);
    if (c) elfm_link_fit_circle(o, t->pts, 0, n > c ? c : n, g->t0_us, &g->circle);
  }
}

elfm_status elfm_link_settled_gaps(const elfm_linker *l, int settle_points, int all,
                                   elfm_link_gap *out, int cap, int *n_out, elfm_error *err)
{
  if (!l || !n_out || settle_points < 1 || cap < 0 || (cap > 0 && !out))
    return elfm_error_set(err, ELFM_ERR_INVALID, NULL, -1, "link: bad arguments to settled_gaps");
  int n = 0;
  const size_t s = (size_t)settle_points;
  const size_t h = (size_t)l->o.short_history; /* >= 4, checked at create */
  for (size_t i = 0; i < l->n_live && n < cap; i++) {
    const elfm_track *t = l->live[i].t;
    if (!all) {
      if (l->live[i].last_frame != l->last_frame || t->n < s) continue;
      size_t k = t->n - s;
      if (k > 0 && t->pts[k].frame > t->pts[k - 1].frame + 1) make_gap(&l->o, t, k, h, &out[n++]);
      else if (k == 0 && !t->partial)  /* the track's birth (a piece's first point is not) */
        open_gap(&l->o, t, 0, h, l->o.max_gap_frames, &out[n++]);
    } else {
      for (size_t k = t->n > s ? t->n - s + 1 : 1; k < t->n && n < cap; k++)
        if (t->pts[k].frame > t->pts[k - 1].frame + 1) make_gap(&l->o, t, k, h, &out[n++]);
    }
  }
  *n_out = n;
  return ELFM_OK;
}

void elfm_link_gap_predict(const elfm_link_gap *g, int64_t t_us, double xyz_um[3])
{
  double f[3], b[3], vb[3];
  const double d0 = (double)(t_us - g->t0_us) * 1e-3, d1 = (double)(g->t1_us - t_us) * 1e-3;
  elfm_link_predict_turn(g->p0_um, g->v0_um_per_ms, g->a0_um_per_ms2, d0, f);
  /* backward along the same circle: the reversed velocity turns the other
   * way under the same normal acceleration */
  for (int a = 0; a < 3; a++) vb[a] = -g->v1_um_per_ms[a];
  elfm_link_predict_turn(g->p1_um, vb, g->a1_um_per_ms2, d1, b);
  if (g->circle.ok) { /* an open gap's circle has its end's time for reference: d0 <= 0 before */
    elfm_link_circle_predict(&g->circle, d0, xyz_um);
    return;
  }
  if (g->open_start || g->open_end) {
    memcpy(xyz_um, g->open_start ? b : f, sizeof b);
    return;
  }
  const double span = d0 + d1, w = span > 0 ? d0 / span : 0.5;
  for (int a = 0; a < 3; a++) xyz_um[a] = (1 - w) * f[a] + w * b[a];
}

int elfm_link_fill_confirmed(const elfm_link_gap *g, const elfm_detection *pts, int m, int j,
                             double kz, double r_um)
{
  const double r2 = r_um * r_um;
  const elfm_detection *a = &pts[j];
  for (int i = 0; i < m; i++) {
    if (i == j || llabs(pts[i].frame - a->frame) != 1) continue;
    const double dx = pts[i].x_um - a->x_um, dy = pts[i].y_um - a->y_um,
                 dz = (pts[i].z_um - a->z_um) / kz;
    if (dx * dx + dy * dy + dz * dz < r2) return 1;
  }
  for (int e = 0; e < 2; e++) {
    const int have = e ? !g->open_end && a->frame == g->frame1 - 1
                       : !g->open_start && a->frame == g->frame0 + 1;
    if (!have) continue;
    const double *pe = e ? g->p1_um : g->p0_um;
    const double dx = pe[0] - a->x_um, dy = pe[1] - a->y_um, dz = (pe[2] - a->z_um) / kz;
    if (dx * dx + dy * dy + dz * dz < r2) return 1;
  }
  return 0;
}

void elfm_link_track_end(const elfm_track *t, const elfm_link_options *o, int max_gap_frames,
                         elfm_link_gap *g)
{
  memset(g, 0, sizeof *g);
  if (!t || t->n == 0 || !o) return;
  open_gap(o, t, 1, o->short_history > 1 ? (size_t)o->short_history : 1,
           max_gap_frames > 0 ? max_gap_frames : 0, g);
}

elfm_status elfm_link_fill(elfm_linker *l, int64_t track_id, const elfm_detection *d, int n,
                           elfm_error *err)
{
  if (!l || n < 0 || (n > 0 && !d))
    return elfm_error_set(err, ELFM_ERR_INVALID, NULL, -1, "link: bad arguments to fill");
  live_track *lt = NULL;
  for (size_t i = 0; i < l->n_live; i++)
    if (l->live[i].t->id == track_id) lt = &l->live[i];
  if (!lt) return elfm_error_set(err, ELFM_ERR_INVALID, NULL, -1, "link: track %lld is not live",
                                 (long long)track_id);
  elfm_track *t = lt->t;
  for (int j = 0; j < n; j++) {
    if (!(isfinite(d[j].x_um) && isfinite(d[j].y_um) && isfinite(d[j].z_um)))
      return elfm_error_set(err, ELFM_ERR_NUMERIC, NULL, -1, "link: fill point %d is not finite", j);
    if (d[j].frame >= t->pts[t->n - 1].frame)
      return elfm_error_set(err, ELFM_ERR_INVALID, NULL, -1,
                            "link: fill frame %lld not before track %lld's last frame %lld",
                            (long long)d[j].frame, (long long)track_id,
                            (long long)t->pts[t->n - 1].frame);
    /* Only a gap closing still under review needs its index kept: once
     * reviewed, or after a stitch or an exchange of tails, tail0 may index
     * past the track's points (it is not maintained then). */
    const int64_t tail_frame =
        lt->review && lt->tail0 > 0 && lt->tail0 < t->n ? t->pts[lt->tail0].frame : INT64_MIN;
    elfm_status st = elfm_track_insert(t, &d[j], err);
    if (st != ELFM_OK) return st;
    if (d[j].frame < tail_frame) lt->tail0++; /* the gap closing under review keeps its point */
  }
  /* the fits over the last points: the long one may now include some */
  elfm_link_fit_velocity(lt, &l->o);
  return ELFM_OK;
}
