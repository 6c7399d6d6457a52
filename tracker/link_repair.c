/* link_repair.c — the linker's repair steps (see elfm_link.h), run at the
 * end of each elfm_link_step once the frame's detections are attached and
 * births made: they rewrite tracks already linked rather than link new
 * detections.
 *  5. stitching: a young track that retraces the recent path of a dormant
 *     one is appended to it (elfm_link_stitch);
 *  5b. late stitching: a track about to end goes on as a young one on its
 *     path that step 5 has not judged yet (elfm_link_stitch_late, run in
 *     step 1 with the twins);
 *  6. swap review: a gap closing that does not fit is revisited once its
 *     tail has a few points, and two tracks' tails are exchanged when that
 *     fits better (elfm_link_review_swaps);
 *  7. encounter review: two tracks that came within encounter_um of each
 *     other are revisited the same way once both have a few points after
 *     it (elfm_link_mark_encounters, elfm_link_review_encounters);
 *  8. twins: a track about to end whose last points a younger one holds
 *     too goes on as that one (elfm_link_join_twins, run in step 1).
 * The per-frame linking, the scratch and the fits they use are in link.c;
 * the linker's state in link_internal.h. */
#include "link_internal.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* Mean squared anisotropic distance from each point of y to the nearest of
 * the last `history` real points of d (its recent path). */
static double path_distance2(const elfm_track *y, const elfm_track *d, size_t history, double kz)
{
  size_t h0 = d->n > history ? d->n - history : 0;
  double sum = 0;
  for (size_t j = 0; j < y->n; j++) {
    double best = INFINITY;
    for (size_t k = h0; k < d->n; k++) {
      double ex = y->pts[j].x_um - d->pts[k].x_um, ey = y->pts[j].y_um - d->pts[k].y_um,
             ez = (y->pts[j].z_um - d->pts[k].z_um) / kz;
      double e2 = ex * ex + ey * ey + ez * ez;
      if (e2 < best) best = e2;
    }
    sum += best;
  }
  return y->n ? sum / (double)y->n : INFINITY;
}

/* Does the dormant track d run straight over its recent path (its last
 * `history` real points span >= 10 frames and a chord of >= 10 um, and
 * they lie within frac x the chord of it, root mean square, anisotropic),
 * with the young start p behind its end along that chord by more than
 * margin_um? (elfm_link_options.stitch_straight_frac says why.) Stage 200
 * ms seeds 1-3 tracked with --motion auto: alpha 0.702 / 0.586 / 0.672 ->
 * 0.758 / 0.807 / 0.732 (a bead entering on the line another has left was
 * stitched to it, the track jumping back 60 um); blink_moving with --repr
 * lin, seeds 1-4: 0.555 / 0.536 / 0.555 / 0.510 -> 0.653 / 0.721 / 0.667 /
 * 0.706; flow seeds 1-20 and worm (integral) seeds 1-4: tracks.csv byte for
 * byte the same, flow 21-24 and blink the same alpha (0.2: the same). */
static int straight_and_behind(const elfm_track *d, const double p[3], size_t history,
                               double kz, double frac, double margin_um)
{
  const size_t h0 = d->n > history ? d->n - history : 0, m = d->n - h0;
  if (m < 6 || d->pts[d->n - 1].frame - d->pts[h0].frame < 10) return 0;
  /* the chord between the means of the first and of the last 3 points
   * (z divided by kz throughout) */
  double a[3] = {0, 0, 0}, b[3] = {0, 0, 0};
  for (size_t k = 0; k < 3; k++) {
    const elfm_detection *u = &d->pts[h0 + k], *w = &d->pts[d->n - 1 - k];
    a[0] += u->x_um / 3;
    a[1] += u->y_um / 3;
    a[2] += u->z_um / kz / 3;
    b[0] += w->x_um / 3;
    b[1] += w->y_um / 3;
    b[2] += w->z_um / kz / 3;
  }
  double c[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]};
  const double L = sqrt(c[0] * c[0] + c[1] * c[1] + c[2] * c[2]);
  if (L < 10) return 0;
  for (int i = 0; i < 3; i++) c[i] /= L;
  double s2 = 0;
  for (size_t k = h0; k < d->n; k++) {
    double e[3] = {d->pts[k].x_um - a[0], d->pts[k].y_um - a[1], d->pts[k].z_um / kz - a[2]};
    const double along = e[0] * c[0] + e[1] * c[1] + e[2] * c[2];
    for (int i = 0; i < 3; i++) e[i] -= along * c[i];
    s2 += e[0] * e[0] + e[1] * e[1] + e[2] * e[2];
  }
  if (sqrt(s2 / (double)m) > frac * L) return 0;
  const double q[3] = {p[0] - b[0], p[1] - b[1], p[2] / kz - b[2]};
  return q[0] * c[0] + q[1] * c[1] + q[2] * c[2] < -margin_um;
}

/* Remove the live slots a repair step emptied (t = NULL: the track went
 * on in another slot), keeping the others' order (steps 5 and 8). */
static void drop_removed(elfm_linker *l)
{
  size_t w = 0;
  for (size_t i = 0; i < l->n_live; i++)
    if (l->live[i].t) l->live[w++] = l->live[i];
  l->n_live = w;
}

/* Append to a the points of y after a's last frame (y's in frame order;
 * those in a's frames, the overlap, stay a's): stitching's and the twins'
 * join. */
static elfm_status append_after(elfm_track *a, const elfm_track *y, elfm_error *err)
{
  const int64_t end = a->pts[a->n - 1].frame;
  for (size_t k = 0; k < y->n; k++) {
    if (y->pts[k].frame <= end) continue;
    elfm_status st = elfm_track_append(a, &y->pts[k], err);
    if (st != ELFM_OK) return st;
  }
  return ELFM_OK;
}

/* The stitching test of young track y against dormant track d: INFINITY
 * when y cannot continue d (born more than max_gap_frames after d's last
 * point, out of reach, or behind d's end along a straight path), else the
 * mean squared distance of y's points to d's recent path. */
static double stitch_distance2(const elfm_link_options *o, const live_track *d, const live_track *y)
{
  /* gap -1: the young track was born in the dormant one's last frame,
   * from a second detection of the same bead (a twin that then took the
   * bead: a one-point track's gate, widened for its unknown speed, makes
   * its normalised cost the lower); that frame keeps the dormant's point.
   * Flow 100 ms seeds 1-20: alpha 0.7335 -> 0.7355, seeds 2, 3 and 16 up
   * (0.727 -> 0.749, 0.806 -> 0.810, 0.695 -> 0.708), none down. */
  int64_t gap = y->t->pts[0].frame - d->last_frame - 1;
  if (gap < -1 || gap > o->max_gap_frames) return INFINITY;
  /* Reachable: from the dormant end to the young start at no more than
   * 1.5 x the faster one's speed. Without it a bead trailing another on
   * the same line (stage scene) lies on the other's path, and stitching
   * them ran tracks backwards (stage alpha 0.717 -> 0.075). */
  const double *vd = elfm_link_current_velocity(d), *vy = elfm_link_current_velocity(y);
  double sd = sqrt(vd[0] * vd[0] + vd[1] * vd[1] + vd[2] * vd[2]),
         sy = sqrt(vy[0] * vy[0] + vy[1] * vy[1] + vy[2] * vy[2]);
  double reach = o->stitch_gate_um + 1.5 * (sd > sy ? sd : sy) *
                                         (double)(y->t->pts[0].t_us - d->last_t_us) * 1e-3;
  double jx = y->t->pts[0].x_um - d->last[0], jy = y->t->pts[0].y_um - d->last[1],
         jz = (y->t->pts[0].z_um - d->last[2]) / o->kz;
  if (jx * jx + jy * jy + jz * jz > reach * reach) return INFINITY;
  const double p0[3] = {y->t->pts[0].x_um, y->t->pts[0].y_um, y->t->pts[0].z_um};
  if (o->stitch_straight_frac > 0 &&
      straight_and_behind(d->t, p0, (size_t)o->stitch_history, o->kz,
                          o->stitch_straight_frac, o->stitch_gate_um))
    return INFINITY;
  return path_distance2(y->t, d->t, (size_t)o->stitch_history, o->kz);
}

/* 5. Stitching: a track that has just reached stitch_points real points
 * (young) may be the continuation of a live track dark since before the
 * young one's first point (dormant). The forward gap closing cannot find
 * it after a long gap on a curved path: flow beads circle (radius 8-20 um,
 * ~17 degrees per ms), and an extrapolation over 10-40 frames missed the
 * true continuation by 20-140 um, no closer than other beads' tracks. But
 * such paths recirculate (a droplet's streaming; a blinking bead stays
 * put), so the object comes back onto its own earlier path: the young
 * track's points are compared with the dormant one's recent path (mean
 * squared distance to its nearest point). Measured on flow 100 ms seeds 1
 * and 2 over all dormant/young pairs: the same bead 1.0-7.0 um (9 of 14
 * such pairs; the others 11-20 um), different beads >= 10 um except one
 * track that had already swapped. Pairs within stitch_gate_um are assigned
 * optimally; the young track's points are appended to the dormant one,
 * which continues with the young one's state (its own fits). */
elfm_status elfm_link_stitch(elfm_linker *l, int64_t frame, size_t nd, elfm_error *err)
{
  const elfm_link_options *o = &l->o;
  const size_t nl = l->n_live;
  elfm_status st = elfm_link_reserve(l, nl, nd, err);
  if (st != ELFM_OK) return st;
  int nr = 0, nc = 0;
  for (size_t i = 0; i < nl; i++) {
    const live_track *lt = &l->live[i];
    if (lt->last_frame < frame && lt->t->n >= (size_t)o->stitch_points) l->rows[nr++] = (int)i;
    else if (lt->last_frame == frame && lt->t->n == (size_t)o->stitch_points) l->cols[nc++] = (int)i;
  }
  if (nr == 0 || nc == 0 || nr > 500 || nc > 500) return ELFM_OK;
  size_t need = (size_t)nr * (size_t)nc;
  st = elfm_link_reserve_cost(l, need, err);
  if (st != ELFM_OK) return st;
  const double g2 = o->stitch_gate_um * o->stitch_gate_um;
  int any = 0;
  for (int c = 0; c < nc; c++) {
    const live_track *y = &l->live[l->cols[c]];
    for (int r = 0; r < nr; r++) {
      const live_track *d = &l->live[l->rows[r]];
      double *cost = &l->cost[(size_t)r * nc + c];
      *cost = INFINITY;
      const double h2 = stitch_distance2(o, d, y);
      if (h2 < g2) {
        *cost = h2 / g2;
        any = 1;
      }
    }
  }
  if (!any) return ELFM_OK;
  st = elfm_assign_hungarian(l->cost, nr, nc, l->row_to_col, NULL, l->aws, err);
  if (st != ELFM_OK) return st;
  for (int r = 0; r < nr; r++) {
    int c = l->row_to_col[r];
    if (c < 0 || !isfinite(l->cost[(size_t)r * nc + c])) continue;
    live_track *d = &l->live[l->rows[r]], *y = &l->live[l->cols[c]];
    if ((st = append_after(d->t, y->t, err)) != ELFM_OK) return st;
    /* this frame's detection now belongs to the dormant track */
    for (size_t j = 0; j < nd; j++)
      if (l->det_id[j] == y->t->id) l->det_id[j] = d->t->id;
    elfm_track *keep = d->t;
    elfm_track_free(y->t);
    *d = *y;      /* continue with the young track's state (its own fits) */
    d->t = keep;
    d->tail0 = 0; /* y's gap closing (if any) indexed y's points */
    d->review = 0;
    y->t = NULL;  /* removed below, keeping the order */
  }
  drop_removed(l);
  return ELFM_OK;
}

/* Squared anisotropic distance, at the middle of the gap, between the end
 * state of hp[0 .. hn) and the start state of tp[0 .. tn), each fitted
 * over up to `points` points: quadratic fits, turning as predict_track in
 * link.c, or with `straight`, straight lines (the slow line of
 * elfm_link_predict_track); INFINITY when either has fewer than 4 points. */
static double junction_cost2(const elfm_detection *hp, size_t hn, const elfm_detection *tp, size_t tn,
                             int points, int straight, double kz)
{
  const size_t np = (size_t)points;
  size_t hk = hn < np ? hn : np, tk = tn < np ? tn : np;
  if (hk < 4 || tk < 4) return INFINITY;
  const int64_t th = hp[hn - 1].t_us, tt = tp[0].t_us, tm = th + (tt - th) / 2;
  const double dh = (double)(tm - th) * 1e-3, dt = (double)(tm - tt) * 1e-3;
  double hpos[3], hvel[3], hacc[3], tpos[3], tvel[3], tacc[3], a[3], b[3];
  if (straight) {
    if (!elfm_link_fit_line(hp, hn - hk, hn, th, hpos, hvel) ||
        !elfm_link_fit_line(tp, 0, tk, tt, tpos, tvel))
      return INFINITY;
    for (int k = 0; k < 3; k++) {
      a[k] = hpos[k] + hvel[k] * dh;
      b[k] = tpos[k] + tvel[k] * dt;
    }
  } else {
    if (!elfm_link_fit_quad(hp, hn - hk, hn, th, hpos, hvel, hacc) ||
        !elfm_link_fit_quad(tp, 0, tk, tt, tpos, tvel, tacc))
      return INFINITY;
    elfm_link_predict_turn(hpos, hvel, hacc, dh, a);
    elfm_link_predict_turn(tpos, tvel, tacc, dt, b);
  }
  double dx = a[0] - b[0], dy = a[1] - b[1], dz = (a[2] - b[2]) / kz;
  return dx * dx + dy * dy + dz * dz;
}

/* The exchange's two joins (alt: their summed squared distances) are
 * within review_join_factor x gate_um, root mean square. Why: around a
 * sharp turn, or after a long gap, neither head's extrapolation says where
 * its bead went, and the ratio of two bad joins decides nothing. Twelfth
 * session, the exchanges steps 6 and 7 made on 57 simulated recordings
 * (flow, dense, brighter, faster, noisier), judged against the truth: the
 * 17 that joined the beads back had joins of 1.1-12.0 um, the 11 that
 * parted them 7.3-38 um (9 of them above 12). Flow 100 ms seeds 1-20,
 * step 6 capped at 2 x gate too: alpha 0.8136 -> 0.8184 (five seeds up,
 * none down); held-out seeds 21-24 0.8061 -> 0.8100; 1.5 x the same, 3 x
 * 0.8167 (docs/tracker.md "Encounter review"). */
static int joins_known(const elfm_link_options *o, double alt)
{
  const double g = o->review_join_factor * o->gate_um;
  return o->review_join_factor <= 0 || alt <= 2 * g * g;
}

/* Replace track a's points from a_t0 on by b's from b_t0 on and vice versa. */
static elfm_status exchange_tails(elfm_track *a, size_t a_t0, elfm_track *b, size_t b_t0,
                                  elfm_error *err)
{
  size_t an = a_t0 + (b->n - b_t0), bn = b_t0 + (a->n - a_t0);
  elfm_detection *pa = malloc((an ? an : 1) * sizeof *pa), *pb = malloc((bn ? bn : 1) * sizeof *pb);
  if (!pa || !pb) {
    free(pa);
    free(pb);
    return elfm_error_set(err, ELFM_ERR_NOMEM, NULL, -1, "link: out of memory");
  }
  memcpy(pa, a->pts, a_t0 * sizeof *pa);
  memcpy(pa + a_t0, b->pts + b_t0, (b->n - b_t0) * sizeof *pa);
  memcpy(pb, b->pts, b_t0 * sizeof *pb);
  memcpy(pb + b_t0, a->pts + a_t0, (a->n - a_t0) * sizeof *pb);
  free(a->pts);
  free(b->pts);
  a->pts = pa;
  a->n = a->cap = an;
  b->pts = pb;
  b->n = b->cap = bn;
  return ELFM_OK;
}

/* lt's last point and fits again from its track's points, after
 * exchange_tails rewrote them. */
static void refresh_state(const elfm_link_options *o, live_track *lt)
{
  const elfm_detection *p = &lt->t->pts[lt->t->n - 1];
  lt->last_frame = p->frame;
  lt->last_t_us = p->t_us;
  lt->last[0] = p->x_um;
  lt->last[1] = p->y_um;
  lt->last[2] = p->z_um;
  elfm_link_fit_velocity(lt, o);
}

/* 6. Swap review, a deferred decision at close passes. Two flow beads
 * passing within a few um give one detection for a few frames; one track
 * coasts, the other takes the shared detections, and when they part the
 * coasting track may close its gap on the other bead (flow seed 2: beads 5
 * and 16, frames 45-52; seed 7: beads 2 and 15). A frame later nothing
 * tells them apart, but once the tails have swap_points points their
 * motion does. So a track B that closed a gap (head up to frame hB, tail
 * from fB) is revisited once its tail has swap_points points, if its own
 * junction does not fit (head and tail extrapolated to the middle of the
 * gap miss each other by more than gate_um). Every other track A with a
 * point inside the gap (hB < frame <= fB) may have taken B's object there:
 * for each such split of A, B's head joined to A's tail and A's head to
 * B's tail are compared with the junctions as they are; when the best
 * exchange fits swap_ratio times better (root of the summed squared
 * distances), the tails are exchanged. Each gap closing is reviewed once. */
elfm_status elfm_link_review_swaps(elfm_linker *l, size_t nd, elfm_error *err)
{
  const elfm_link_options *o = &l->o;
  const size_t K = (size_t)o->swap_points;
  const int sh = o->short_history;
  const double kz = o->kz;
  for (size_t b = 0; b < l->n_live; b++) {
    live_track *B = &l->live[b];
    if (!B->review || B->t->n - B->tail0 < K) continue;
    const elfm_detection *bp = B->t->pts;
    const size_t bt = B->tail0, bn = B->t->n;
    const int64_t hB = bp[bt - 1].frame, fB = bp[bt].frame;
    const double jb = junction_cost2(bp, bt, bp + bt, bn - bt, sh, 0, kz);
    double best_ratio = o->swap_ratio * o->swap_ratio;
    size_t best_a = 0, best_s = 0;
    int found = 0;
    for (size_t a = 0; a < l->n_live; a++) {
      if (a == b) continue;
      const elfm_detection *ap = l->live[a].t->pts;
      const size_t an = l->live[a].t->n;
      for (size_t s = an; s-- > 4;) {
        if (ap[s].frame <= hB) break;
        if (ap[s].frame > fB || an - s < K) continue;
        double cur = jb + junction_cost2(ap, s, ap + s, an - s, sh, 0, kz);
        double alt = junction_cost2(bp, bt, ap + s, an - s, sh, 0, kz) +
                     junction_cost2(ap, s, bp + bt, bn - bt, sh, 0, kz);
        if (isfinite(cur) && jb > o->gate_um * o->gate_um && alt < best_ratio * cur &&
            joins_known(o, alt)) {
          best_ratio = alt / cur;
          best_a = a;
          best_s = s;
          found = 1;
        }
      }
    }
    if (found) {
      live_track *A = &l->live[best_a];
      elfm_status st = exchange_tails(B->t, bt, A->t, best_s, err);
      if (st != ELFM_OK) return st;
      for (size_t j = 0; j < nd; j++) {
        if (l->det_id[j] == A->t->id) l->det_id[j] = B->t->id;
        else if (l->det_id[j] == B->t->id) l->det_id[j] = A->t->id;
      }
      refresh_state(o, A);
      refresh_state(o, B);
      /* the junctions now: B's head meets A's old tail at bt, A's head
       * meets B's old tail at best_s; both reviewed */
      A->tail0 = best_s;
      A->review = 0;
      B->tail0 = bt;
    }
    B->review = 0;
  }
  return ELFM_OK;
}

static int cmp_xkey(const void *a, const void *b)
{
  double xa = ((const link_xkey *)a)->x_um, xb = ((const link_xkey *)b)->x_um;
  return (xa > xb) - (xa < xb);
}

/* Where track i is in this frame for step 7: the detection it took, or,
 * when it lost its object this frame (seen the frame before), its
 * prediction; NULL otherwise (dark before this frame too: its prediction
 * drifts). */
static const double *encounter_position(const elfm_linker *l, size_t i)
{
  const live_track *t = &l->live[i];
  if (l->track_det[i] >= 0) return t->last;
  return t->missed > 0 ? NULL : t->pred;
}

elfm_status elfm_link_mark_encounters(elfm_linker *l, int64_t frame, size_t nt, elfm_error *err)
{
  const double e = l->o.encounter_um, e2 = e * e, kz = l->o.kz;
  /* A sweep over the tracks sorted by x: only pairs within e in x are
   * compared, so a field of many tracks costs n log n, not n^2. */
  size_t n = 0;
  for (size_t i = 0; i < nt; i++) {
    const double *p = encounter_position(l, i);
    if (p) l->xkeys[n++] = (link_xkey){p[0], (int)i};
  }
  if (n < 2) return ELFM_OK; /* no pair (and with no track yet, no xkeys array) */
  qsort(l->xkeys, n, sizeof *l->xkeys, cmp_xkey);
  for (size_t u = 0; u < n; u++) {
    const size_t i = (size_t)l->xkeys[u].track;
    const double *pa = encounter_position(l, i);
    for (size_t v = u + 1; v < n && l->xkeys[v].x_um - l->xkeys[u].x_um < e; v++) {
      const size_t k = (size_t)l->xkeys[v].track;
      if (l->track_det[i] < 0 && l->track_det[k] < 0) continue;  /* neither was seen */
      const double *pb = encounter_position(l, k);
      double dx = pa[0] - pb[0], dy = pa[1] - pb[1], dz = (pa[2] - pb[2]) / kz;
      if (dx * dx + dy * dy + dz * dz >= e2) continue;
      const int64_t ida = l->live[i].t->id, idb = l->live[k].t->id;
      const int64_t ia = ida < idb ? ida : idb, ib = ida < idb ? idb : ida;
      size_t m = 0;
      while (m < l->n_enc && !(l->enc[m].a_id == ia && l->enc[m].b_id == ib && l->enc[m].last >= frame - 1))
        m++;
      if (m < l->n_enc) {
        l->enc[m].last = frame;
        continue;
      }
      if (l->n_enc == l->cap_enc) {
        size_t c = l->cap_enc ? 2 * l->cap_enc : 16;
        link_encounter *q = realloc(l->enc, c * sizeof *q);
        if (!q) return elfm_error_set(err, ELFM_ERR_NOMEM, NULL, -1, "link: out of memory");
        l->enc = q;
        l->cap_enc = c;
      }
      l->enc[l->n_enc++] = (link_encounter){ia, ib, frame, frame};
    }
  }
  return ELFM_OK;
}

/* Index of t's first point at or after `frame` (t->n when none). */
static size_t first_from(const elfm_track *t, int64_t frame)
{
  size_t s = t->n;
  while (s > 0 && t->pts[s - 1].frame >= frame) s--;
  return s;
}

/* Point of t in `frame` (NULL when none); t's points are in frame order. */
static const elfm_detection *point_at(const elfm_track *t, int64_t frame)
{
  size_t lo = 0, hi = t->n;
  while (lo < hi) {
    size_t m = lo + (hi - lo) / 2;
    if (t->pts[m].frame < frame) lo = m + 1;
    else hi = m;
  }
  return lo < t->n && t->pts[lo].frame == frame ? &t->pts[lo] : NULL;
}

/* 0: a and b have points in `frame` and they are within e2 (squared,
 * anisotropic); 1: both there and apart; -1: one of them has none. */
static int apart_at(const elfm_track *a, const elfm_track *b, int64_t frame, double e2, double kz)
{
  const elfm_detection *p = point_at(a, frame), *q = point_at(b, frame);
  if (!p || !q) return -1;
  double dx = p->x_um - q->x_um, dy = p->y_um - q->y_um, dz = (p->z_um - q->z_um) / kz;
  return dx * dx + dy * dy + dz * dz >= e2;
}

/* Mean squared miss (linker metric) of the circle through the last
 * circle_points points of hp[0 .. hn), travelled at its rate, at
 * tp[0 .. tn); INFINITY when the head is shorter or follows no circle
 * (elfm_link_fit_circle's tests: arc, radius, better than a line). */
static double circle_miss2(const elfm_link_options *o, const elfm_detection *hp, size_t hn,
                           const elfm_detection *tp, size_t tn)
{
  const size_t cp = (size_t)o->circle_points;
  if (cp == 0 || hn < cp || tn == 0) return INFINITY;
  elfm_link_circle c;
  const int64_t tr = hp[hn - 1].t_us;
  if (!elfm_link_fit_circle(o, hp, hn - cp, hn, tr, &c)) return INFINITY;
  double s = 0;
  for (size_t k = 0; k < tn; k++) {
    double q[3];
    elfm_link_circle_predict(&c, (double)(tp[k].t_us - tr) * 1e-3, q);
    const double dx = tp[k].x_um - q[0], dy = tp[k].y_um - q[1], dz = (tp[k].z_um - q[2]) / o->kz;
    s += dx * dx + dy * dy + dz * dz;
  }
  return s / (double)tn;
}

/* Step 7's second test, along the heads' circles (elfm_link.h
 * encounter_circle_ratio): a's head [0, ah) and tail from at, b's likewise;
 * 1 when joining them crosswise misses the tails' first k points
 * encounter_circle_ratio times less than as they are. Why the heads'
 * circles and not both ends' quadratic fits: flow 1 s seeds 1-8, over the
 * 1171 encounter reviews that kept the tracks as they were, 18 left two
 * beads exchanged; there the crosswise quadratic junctions fit 0.52-1.42
 * times as well as the present ones, against 0.26-1.24 for the circles,
 * whose ratio was below 0.5 for 9 of the 18 and for none of the 1153
 * right ones (a Python prototype on tracks.csv). */
static int circle_says_exchange(const elfm_link_options *o, const elfm_track *a, size_t ah,
                                size_t at, const elfm_track *b, size_t bh, size_t bt, size_t k)
{
  if (!(o->encounter_circle_ratio > 0) || o->circle_points <= 0) return 0;
  const double rc2 = o->encounter_circle_ratio * o->encounter_circle_ratio;
  const elfm_detection *ap = a->pts, *bp = b->pts;
  const double cur = circle_miss2(o, ap, ah, ap + at, k) + circle_miss2(o, bp, bh, bp + bt, k);
  const double alt = circle_miss2(o, ap, ah, bp + bt, k) + circle_miss2(o, bp, bh, ap + at, k);
  return isfinite(cur) && isfinite(alt) && alt < rc2 * cur && joins_known(o, alt);
}

/* Step 7's third test, for objects at rest (elfm_link.h
 * encounter_line_ratio): 1 when straight lines through up to `history`
 * points of each head and tail join crosswise encounter_line_ratio times
 * better than as they are, and within joins_known. Why lines: where two
 * slow objects stay merged for tens of frames (worm neurons crossing in z
 * within the axial blur), the 8-point quadratic fits extrapolated over the
 * encounter carry their curvature's noise, and a slow object's 8 points
 * span little more than its placement noise (as for the slow line of
 * elfm_link_predict_track). Worm 500 ms seed 1, tracks 6 and 7 over frames
 * 30-84 (neurons 2 and 6 crossing 10 um apart in z, 0.3 um laterally):
 * the quadratic junctions' ratio 0.86, the lines' 0.47 (docs/tracker.md
 * "Slow encounters along straight lines"). */
static int lines_say_exchange(const elfm_link_options *o, const elfm_track *a, size_t ah,
                              size_t at, const elfm_track *b, size_t bh, size_t bt)
{
  const int H = o->history;
  const double kz = o->kz, rl2 = o->encounter_line_ratio * o->encounter_line_ratio;
  const elfm_detection *ap = a->pts, *bp = b->pts;
  const double cur = junction_cost2(bp, bh, bp + bt, b->n - bt, H, 1, kz) +
                     junction_cost2(ap, ah, ap + at, a->n - at, H, 1, kz);
  const double alt = junction_cost2(bp, bh, ap + at, a->n - at, H, 1, kz) +
                     junction_cost2(ap, ah, bp + bt, b->n - bt, H, 1, kz);
  return isfinite(cur) && alt < rl2 * cur && joins_known(o, alt);
}

/* 7. Encounter review. Flow seed 7, beads 14 and 17 at frame 54: 3 um
 * apart laterally and 10 um in z, well inside the axial blur, they gave
 * two detections at bead 17; both tracks took one, and the next frame each
 * went on with the other's bead. No track coasted, so step 6 never saw
 * it. Here the frames the two tracks stayed within encounter_um (and
 * encounter_pad frames before, whose points the merging already pulls)
 * are left out; each head is joined to each tail at the encounter's
 * middle as in step 6, and the tails are exchanged when that fits
 * encounter_ratio times better than the tracks as they are (and within
 * joins_known). */
elfm_status elfm_link_review_encounters(elfm_linker *l, int64_t frame, size_t nd, elfm_error *err)
{
  const elfm_link_options *o = &l->o;
  const size_t K = (size_t)o->swap_points;
  const int sh = o->short_history;
  const double kz = o->kz, r2 = o->encounter_ratio * o->encounter_ratio;
  /* Objects at rest (a crawling worm's neurons): the straight lines'
   * test, over `history` points, so the tails must have that many. */
  const int lines = o->encounter_line_ratio > 0 && o->rest_speed_um_per_ms > 0 &&
                    elfm_link_objects_at_rest(l);
  const size_t H = (size_t)o->history, KT = lines && H > K ? H : K;
  size_t w = 0;
  for (size_t e = 0; e < l->n_enc; e++) {
    link_encounter E = l->enc[e];
    live_track *A = NULL, *B = NULL;
    for (size_t i = 0; i < l->n_live; i++) {
      if (l->live[i].t->id == E.a_id) A = &l->live[i];
      else if (l->live[i].t->id == E.b_id) B = &l->live[i];
    }
    if (!A || !B) continue;  /* one of them ended: dropped */
    /* The points as they are now: the gap fills (the command's) may have
     * put both tracks on one bead in frames the linker saw one of them
     * dark. The encounter runs on while the two stay together or one is
     * missing, up to the last frame they were together. */
    const double e2 = o->encounter_um * o->encounter_um;
    int64_t f1 = E.last, f0 = E.first;
    int apart_run = 0; /* up to encounter_apart frames apart in a row */
    for (int64_t f = E.last + 1; f < frame; f++) {
      const int r = apart_at(A->t, B->t, f, e2, kz);
      if (r == 1 && ++apart_run > o->encounter_apart) break;
      if (r == 0) {
        f1 = f;
        apart_run = 0;
      }
    }
    for (int64_t f = E.first - 1; f >= E.first - 2 * (int64_t)K; f--) {
      int r = apart_at(A->t, B->t, f, e2, kz);
      if (r == 1) break;
      if (r == 0) f0 = f;
    }
    f0 -= o->encounter_pad;
    const size_t bt = first_from(B->t, f1 + 1), at = first_from(A->t, f1 + 1);
    if (f1 >= frame || B->t->n - bt < KT || A->t->n - at < KT) {  /* not yet */
      l->enc[w++] = E;
      continue;
    }
    const size_t bh = first_from(B->t, f0), ah = first_from(A->t, f0);
    const elfm_detection *bp = B->t->pts, *ap = A->t->pts;
    double cur = junction_cost2(bp, bh, bp + bt, B->t->n - bt, sh, 0, kz) +
                 junction_cost2(ap, ah, ap + at, A->t->n - at, sh, 0, kz);
    double alt = junction_cost2(bp, bh, ap + at, A->t->n - at, sh, 0, kz) +
                 junction_cost2(ap, ah, bp + bt, B->t->n - bt, sh, 0, kz);
    /* The circles decide only where the quadratic junctions lean the same
     * way (crosswise below as they are): flow 100 ms seed 20, beads 8 and
     * 12 crossing 1-3 um apart while one turns in z, the circles' ratio
     * 0.49 against 2.5 for the junctions, which were right. */
    if (!(isfinite(cur) && alt < r2 * cur && joins_known(o, alt)) &&
        !(isfinite(cur) && alt < cur && circle_says_exchange(o, A->t, ah, at, B->t, bh, bt, K)) &&
        !(lines && lines_say_exchange(o, A->t, ah, at, B->t, bh, bt)))
      continue;
    /* a gap closing still to be reviewed in a tail moves with it */
    size_t a_tail0 = A->tail0, b_tail0 = B->tail0;
    int a_rev = A->review && a_tail0 >= at, b_rev = B->review && b_tail0 >= bt;
    elfm_status st = exchange_tails(B->t, bt, A->t, at, err);
    if (st != ELFM_OK) return st;
    if (a_rev) {
      B->tail0 = bt + (a_tail0 - at);
      B->review = 1;
    } else if (B->review && b_tail0 >= bt) {
      B->review = 0;
    }
    if (b_rev) {
      A->tail0 = at + (b_tail0 - bt);
      A->review = 1;
    } else if (A->review && a_tail0 >= at) {
      A->review = 0;
    }
    for (size_t j = 0; j < nd; j++) {
      if (l->det_id[j] == A->t->id) l->det_id[j] = B->t->id;
      else if (l->det_id[j] == B->t->id) l->det_id[j] = A->t->id;
    }
    refresh_state(o, A);
    refresh_state(o, B);
    /* later encounters of either track were their tails' */
    for (size_t g = e + 1; g < l->n_enc; g++) {
      link_encounter *G = &l->enc[g];
      if (G->first <= f1) {
        /* The same two tracks' encounter begun within this one (they
         * were apart a frame or a few in it) is this meeting, judged now:
         * dropped (no track has id -1). Reviewed on the exchanged tracks,
         * its shorter heads undid the exchange: worm 500 ms seed 1, tracks
         * 6 and 7, encounters 30-84, 61-84 and 81-84 (alpha 0.903 ->
         * 0.913; flow's tracks.csv the same). */
        if (G->a_id == E.a_id && G->b_id == E.b_id && G->first >= f0) G->a_id = G->b_id = -1;
        continue;
      }
      int64_t *ids[2] = {&G->a_id, &G->b_id};
      for (int m = 0; m < 2; m++) {
        if (*ids[m] == E.a_id) *ids[m] = E.b_id;
        else if (*ids[m] == E.b_id) *ids[m] = E.a_id;
      }
      if (G->a_id > G->b_id) {
        int64_t t = G->a_id;
        G->a_id = G->b_id;
        G->b_id = t;
      }
    }
  }
  l->n_enc = w;
  return ELFM_OK;
}

/* 8. Twins (elfm_link_options.twin_um says why). How many of a's points
 * [j0, j1) b holds too, within r2 (squared, anisotropic) in the same
 * frame. */
static int twin_count(const elfm_track *a, size_t j0, size_t j1, const elfm_track *b, double r2,
                      double kz)
{
  int n = 0;
  for (size_t j = j0; j < j1; j++) {
    const elfm_detection *p = &a->pts[j], *q = point_at(b, p->frame);
    if (!q) continue;
    const double dx = p->x_um - q->x_um, dy = p->y_um - q->y_um, dz = (p->z_um - q->z_um) / kz;
    n += dx * dx + dy * dy + dz * dz < r2;
  }
  return n;
}

/* Track a, ending, goes on as the younger live track y: y's points after
 * a's last are appended to a's, y's slot carries on with a's track and
 * y's own state (its fits), and a's slot is marked for removal (the
 * caller's drop_removed). On failure (no memory) both stay live. */
static elfm_status continue_as(elfm_linker *l, live_track *a, live_track *y, elfm_error *err)
{
  const int64_t y_id = y->t->id, a_id = a->t->id;
  elfm_status st = append_after(a->t, y->t, err);
  if (st != ELFM_OK) return st;
  /* y's pending encounters are a's now (the pair kept in id order) */
  for (size_t e = 0; e < l->n_enc; e++) {
    link_encounter *E = &l->enc[e];
    if (E->a_id == y_id) E->a_id = a_id;
    if (E->b_id == y_id) E->b_id = a_id;
    if (E->a_id > E->b_id) {
      const int64_t t = E->a_id;
      E->a_id = E->b_id;
      E->b_id = t;
    }
  }
  elfm_track *keep = a->t;
  elfm_track_free(y->t);
  y->t = keep;  /* y's slot goes on with y's state (its own fits) */
  y->tail0 = 0; /* y's gap closing (if any) indexed y's points */
  y->review = 0;
  a->t = NULL;  /* not ended: removed by drop_removed, keeping the order */
  return ELFM_OK;
}

elfm_status elfm_link_join_twins(elfm_linker *l, int64_t frame, elfm_error *err)
{
  const elfm_link_options *o = &l->o;
  const double r2 = o->twin_um * o->twin_um;
  const size_t m = 4 * (size_t)o->twin_points;
  elfm_status st = ELFM_OK;
  for (size_t i = 0; i < l->n_live && st == ELFM_OK; i++) {
    live_track *a = &l->live[i];
    /* a track of fewer points is not judged (flow-60 seed 4: a 12-point
     * track, its last points partly another bead's, was joined: alpha
     * 0.7586 -> 0.7554) */
    if (!a->t || frame - a->last_frame - 1 <= o->max_gap_frames || a->t->n < m) continue;
    /* the younger track (a later id) that holds most of a's last points,
     * still live, with points after a's last, and whole (no pieces given:
     * those are written under its own id) */
    size_t best = l->n_live;
    int best_n = o->twin_points - 1;
    for (size_t k = 0; k < l->n_live; k++) {
      const live_track *y = &l->live[k];
      if (k == i || !y->t || y->t->id <= a->t->id || y->t->partial ||
          frame - y->last_frame - 1 > o->max_gap_frames || y->last_frame <= a->last_frame)
        continue;
      /* of a's last 4 x twin_points points, and of y's first as many:
       * y was born on a's object, not met by a drifting onto y's (flow-60
       * seed 5: alpha 0.7184 -> 0.7069 without the second) */
      const int n = twin_count(a->t, a->t->n - m, a->t->n, y->t, r2, o->kz);
      if (n <= best_n ||
          twin_count(y->t, 0, y->t->n < m ? y->t->n : m, a->t, r2, o->kz) < o->twin_points)
        continue;
      best = k;
      best_n = n;
    }
    if (best == l->n_live) continue;
    if ((st = continue_as(l, a, &l->live[best], err)) != ELFM_OK) break;
    l->n_twins++;
  }
  drop_removed(l);
  return st;
}

/* 5b. Late stitching (o.stitch_late_points > 0), at the start of a step
 * with the twins: a track ending in this frame (dark for more than
 * max_gap_frames) goes on as the young track of stitch_late_points to
 * stitch_points - 1 points that step 5 has not judged yet, born after its
 * end and lying on its recent path by step 5's test. A deep bead seen in
 * a few frames at a time is otherwise lost when its new track reaches
 * stitch_points just after the old one ended (flow 1 s seed 8, frame 741:
 * a bead's track dark since 689, the next one 4 points old since 711). */
elfm_status elfm_link_stitch_late(elfm_linker *l, int64_t frame, elfm_error *err)
{
  const elfm_link_options *o = &l->o;
  const double g2 = o->stitch_gate_um * o->stitch_gate_um;
  elfm_status st = ELFM_OK;
  for (size_t i = 0; i < l->n_live && st == ELFM_OK; i++) {
    live_track *a = &l->live[i];
    if (!a->t || frame - a->last_frame - 1 <= o->max_gap_frames ||
        a->t->n < (size_t)o->stitch_points)
      continue;
    size_t best = l->n_live;
    double best_h2 = g2;
    for (size_t k = 0; k < l->n_live; k++) {
      const live_track *y = &l->live[k];
      if (k == i || !y->t || y->t->partial || y->t->n < (size_t)o->stitch_late_points ||
          y->t->n >= (size_t)o->stitch_points || y->t->pts[0].frame <= a->last_frame ||
          frame - y->last_frame - 1 > o->max_gap_frames)
        continue;
      const double h2 = stitch_distance2(o, a, y);
      if (h2 < best_h2) {
        best = k;
        best_h2 = h2;
      }
    }
    if (best == l->n_live) continue;
    if ((st = continue_as(l, a, &l->live[best], err)) != ELFM_OK) break;
    l->n_late_stitches++;
  }
  drop_removed(l);
  return st;
}
