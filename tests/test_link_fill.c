/* test_link_fill.c — gap filling's parts (elfm_link.h "Gap filling",
 * elfm_track_insert): which gaps are settled and when, each reported once;
 * where a gap's object is predicted on lines and circles (and past a
 * finished track's end); points given back
 * land in the track's past without changing what the linker predicts next;
 * bad fills are errors. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "check.h"
#include "elfm_tracker.h"
#include "link_test_util.h"

static elfm_detection mk(int64_t frame, int64_t t_us, double x, double y, double z)
{
  elfm_detection d;
  memset(&d, 0, sizeof d);
  d.frame = frame;
  d.t_us = t_us;
  d.x_um = x;
  d.y_um = y;
  d.z_um = z;
  d.intensity = 1;
  return d;
}

/* A bead on a circle of radius R um at w rad/ms in x-y, rising in z. */
static void circle(double t_ms, double p[3])
{
  const double R = 20, w = 0.1;
  p[0] = R * cos(w * t_ms);
  p[1] = R * sin(w * t_ms);
  p[2] = 0.5 * t_ms;
}

/* A flow bead at frame f (ms): circling at 0.3 rad per frame on 12 um while
 * its depth wobbles 10 um over 50 ms (case 3c). */
static void wobbling_circle(double f, double p[3])
{
  p[0] = 12 * cos(0.3 * f);
  p[1] = 12 * sin(0.3 * f);
  p[2] = 10 * sin(2 * M_PI / 50 * f);
}

/* How far the gap's prediction at t_us lies from p, in the linker's metric. */
static double gap_miss(const elfm_link_gap *g, int64_t t_us, const double p[3], double kz)
{
  double q[3];
  elfm_link_gap_predict(g, t_us, q);
  const double dx = p[0] - q[0], dy = p[1] - q[1], dz = (p[2] - q[2]) / kz;
  return sqrt(dx * dx + dy * dy + dz * dz);
}

int main(void)
{
  elfm_error err;
  elfm_error_clear(&err);
  const int64_t T0 = 1000000000000LL; /* absolute times near 1e12 us */

  /* 1. elfm_track_insert: middle, front, end, growth past capacity; a taken
   * frame is an error and changes nothing. */
  {
    elfm_track *t = elfm_track_create(7, &err);
    CHECK(t != NULL);
    for (int f = 0; f < 40; f += 2) {
      elfm_detection d = mk(f + 10, T0 + f, f, 0, 0);
      CHECK_OK(elfm_track_append(t, &d, &err), &err);
    }
    for (int f = 1; f < 40; f += 2) {  /* 20 more: past the first capacity of 16 */
      elfm_detection d = mk(f + 10, T0 + f, f, 1, 0);
      CHECK_OK(elfm_track_insert(t, &d, &err), &err);
    }
    elfm_detection d = mk(5, T0 - 5, -5, 0, 0);
    CHECK_OK(elfm_track_insert(t, &d, &err), &err);
    d = mk(60, T0 + 50, 50, 0, 0);
    CHECK_OK(elfm_track_insert(t, &d, &err), &err);
    CHECK(t->n == 42);
    int ordered = 1;
    for (size_t k = 1; k < t->n; k++) ordered &= t->pts[k].frame > t->pts[k - 1].frame;
    CHECK(ordered);
    CHECK(t->pts[0].frame == 5 && t->pts[1].frame == 10 && t->pts[2].frame == 11);
    CHECK(t->pts[2].y_um == 1 && t->pts[41].frame == 60);
    d = mk(21, T0, 99, 99, 99);
    CHECK(elfm_track_insert(t, &d, &err) == ELFM_ERR_INVALID);
    CHECK(t->n == 42 && t->pts[12].x_um == 11);
    elfm_track_free(t);
  }

  /* 2. A bead on a circle, unseen in frames 20-29 (a gap of 10), linked at
   * 1 kHz. Settle points 8: the gap is reported in the step of frame 37
   * (the 8th point after it), once; its ends are the real points 19 and
   * 30, and the prediction in the gap lies near the circle (the two ends'
   * turns, blended). The birth is reported at frame 7 (8th point). */
  {
    elfm_link_options o;
    elfm_link_options_default(&o);
    o.stitch_points = 0;
    o.swap_points = 0;
    elfm_linker *l = elfm_link_create(&o, &err);
    CHECK(l != NULL);
    elfm_link_gap g[8];
    int n_rep = 0, gap_at = -1, birth_at = -1;
    elfm_link_gap gap, birth;
    memset(&gap, 0, sizeof gap);
    memset(&birth, 0, sizeof birth);
    for (int f = 0; f < 60; f++) {
      double p[3];
      circle(f, p);
      elfm_detection d = mk(f, T0 + 1000 * f, p[0], p[1], p[2]);
      int nd = f >= 20 && f < 30 ? 0 : 1;
      CHECK_OK(elfm_link_step(l, f, T0 + 1000 * f, &d, nd, &err), &err);
      int ng = -1;
      CHECK_OK(elfm_link_settled_gaps(l, 8, 0, g, 8, &ng, &err), &err);
      for (int i = 0; i < ng; i++) {
        n_rep++;
        if (g[i].open_start) {
          birth_at = f;
          birth = g[i];
        } else {
          gap_at = f;
          gap = g[i];
        }
      }
    }
    CHECK(n_rep == 2);
    CHECK(birth_at == 7 && birth.frame1 == 0);
    CHECK(gap_at == 37 && gap.frame0 == 19 && gap.frame1 == 30 && !gap.open_start);
    CHECK(gap.t0_us == T0 + 19000 && gap.t1_us == T0 + 30000);
    double worst = 0, worst_head = 0;
    for (int f = 20; f < 30; f++) {
      double p[3], q[3];
      circle(f, p);
      elfm_link_gap_predict(&gap, T0 + 1000 * f, q);
      double e = sqrt((p[0] - q[0]) * (p[0] - q[0]) + (p[1] - q[1]) * (p[1] - q[1]) +
                      (p[2] - q[2]) * (p[2] - q[2]));
      if (e > worst) worst = e;
      /* the head's turn alone, for comparison: a gap whose far end is
       * far away (the blend then weighs the head's turn ~fully) */
      elfm_link_gap h = gap;
      h.t1_us = gap.t1_us + 1000000000LL;
      elfm_link_gap_predict(&h, T0 + 1000 * f, q);
      e = sqrt((p[0] - q[0]) * (p[0] - q[0]) + (p[1] - q[1]) * (p[1] - q[1]) +
               (p[2] - q[2]) * (p[2] - q[2]));
      if (e > worst_head) worst_head = e;
    }
    /* 1 rad of arc (20 um) unseen: both ends' fits keep the gap within
     * 1 um (0.64 measured); extrapolating the head alone misses by 2.3 */
    CHECK_MSG(worst < 1.0, "worst %g head alone %g", worst, worst_head);
    CHECK(worst_head > 2 * worst);
    end_linker(l);
  }

  /* 3. A straight line: the prediction is exact in the gap, and before the
   * birth (open start) too. */
  {
    elfm_link_options o;
    elfm_link_options_default(&o);
    elfm_linker *l = elfm_link_create(&o, &err);
    CHECK(l != NULL);
    elfm_link_gap g[4], gap, birth;
    int have_gap = 0, have_birth = 0;
    for (int f = 0; f < 30; f++) {
      elfm_detection d = mk(f, T0 + 1000 * f, 2.0 * f, -1.0 * f, 0.5 * f);
      CHECK_OK(elfm_link_step(l, f, T0 + 1000 * f, &d, f >= 10 && f < 14 ? 0 : 1, &err), &err);
      int ng = 0;
      CHECK_OK(elfm_link_settled_gaps(l, 8, 0, g, 4, &ng, &err), &err);
      for (int i = 0; i < ng; i++) {
        if (g[i].open_start) {
          birth = g[i];
          have_birth = 1;
        } else {
          gap = g[i];
          have_gap = 1;
        }
      }
    }
    CHECK(have_gap && have_birth);
    if (have_gap && have_birth) {
      double q[3];
      elfm_link_gap_predict(&gap, T0 + 12000, q);
      CHECK(fabs(q[0] - 24) < 1e-6 && fabs(q[1] + 12) < 1e-6 && fabs(q[2] - 6) < 1e-6);
      elfm_link_gap_predict(&birth, T0 - 3000, q);
      CHECK(fabs(q[0] + 6) < 1e-6 && fabs(q[1] - 3) < 1e-6 && fabs(q[2] + 1.5) < 1e-6);
    }
    end_linker(l);
  }

  /* 3b. A finished track's open end (elfm_link_track_end): on a line the
   * head's fit is exact past the last point; on the circle of case 2 the
   * head's constant-rate turn stays within 1 um for 5 frames (0.25 rad). */
  {
    elfm_link_options lo;
    elfm_link_options_default(&lo);
    lo.short_history = 8;
    elfm_track *t = elfm_track_create(9, &err);
    CHECK(t != NULL);
    for (int f = 0; f < 20 && t; f++) {
      elfm_detection d = mk(f, T0 + 1000 * f, 2.0 * f, -1.0 * f, 0.5 * f);
      d.intensity = f < 17 ? 1 : 4;
      CHECK_OK(elfm_track_append(t, &d, &err), &err);
    }
    elfm_link_gap g;
    elfm_link_track_end(t, &lo, 50, &g);
    CHECK(g.open_end && !g.open_start && g.track_id == 9);
    CHECK(g.frame0 == 19 && g.frame1 == 70 && g.t0_us == T0 + 19000);
    CHECK(fabs(g.intensity - 4) < 1e-12); /* the last 3 points' */
    double q[3];
    elfm_link_gap_predict(&g, T0 + 25000, q);
    CHECK_MSG(fabs(q[0] - 50) < 1e-6 && fabs(q[1] + 25) < 1e-6 && fabs(q[2] - 12.5) < 1e-6,
              "line end %g %g %g", q[0], q[1], q[2]);
    elfm_track_free(t);
    /* Three points, too few for the head's quadratic fit: the velocity
     * from the first and last of them, per axis (vy and vz differ) */
    t = elfm_track_create(11, &err);
    CHECK(t != NULL);
    for (int f = 0; f < 3 && t; f++) {
      elfm_detection d = mk(f, T0 + 1000 * f, 2.0 * f, -1.0 * f, 0.5 * f);
      CHECK_OK(elfm_track_append(t, &d, &err), &err);
    }
    elfm_link_track_end(t, &lo, 50, &g);
    CHECK_MSG(fabs(g.v0_um_per_ms[0] - 2) < 1e-9 && fabs(g.v0_um_per_ms[1] + 1) < 1e-9 &&
                  fabs(g.v0_um_per_ms[2] - 0.5) < 1e-9,
              "3-point end velocity %g %g %g", g.v0_um_per_ms[0], g.v0_um_per_ms[1], g.v0_um_per_ms[2]);
    elfm_link_gap_predict(&g, T0 + 6000, q);
    CHECK_MSG(fabs(q[0] - 12) < 1e-6 && fabs(q[1] + 6) < 1e-6 && fabs(q[2] - 3) < 1e-6,
              "3-point line end %g %g %g", q[0], q[1], q[2]);
    elfm_track_free(t);

    t = elfm_track_create(10, &err);
    CHECK(t != NULL);
    for (int f = 0; f < 20 && t; f++) {
      double p[3];
      circle(f, p);
      elfm_detection d = mk(f, T0 + 1000 * f, p[0], p[1], p[2]);
      CHECK_OK(elfm_track_append(t, &d, &err), &err);
    }
    elfm_link_track_end(t, &lo, 50, &g);
    double worst = 0;
    for (int f = 20; f <= 24; f++) {
      double p[3];
      circle(f, p);
      elfm_link_gap_predict(&g, T0 + 1000 * f, q);
      double e = sqrt((p[0] - q[0]) * (p[0] - q[0]) + (p[1] - q[1]) * (p[1] - q[1]) +
                      (p[2] - q[2]) * (p[2] - q[2]));
      if (e > worst) worst = e;
    }
    CHECK_MSG(worst < 1.0, "circle end worst %g um", worst);
    elfm_track_free(t);
    elfm_link_track_end(NULL, &lo, 50, &g); /* no track: an empty gap, no crash */
    CHECK(!g.open_end && g.track_id == 0);
  }

  /* 3c. The open gaps along the circle (circle_end_points): a flow bead
   * circling at 0.3 rad per frame (radius 12 um) while its depth wobbles
   * (10 um, period 50 ms), as flow's do. Past a finished track's end the
   * circle through its last 8 points follows the bead for 10 frames (3
   * rad) where the head's constant-rate turn leaves it; before a track's
   * birth (reported at its 8th point) the circle through those 8 points
   * does the same backwards. Worst misses in the linker's metric (z / kz),
   * measured: end 1.21 um against the turn's 35.8 um, birth 2.88 um (the
   * wobble, which the circle's plane does not follow) against 18.5 um.
   * Off (0): no circle, the turn as before. */
  {
    elfm_link_options o;
    elfm_link_options_default(&o);
    o.circle_points = 15;
    o.circle_end_points = 8;
    o.stitch_points = 0;
    o.swap_points = 0;
    elfm_link_options off = o;
    off.circle_end_points = 0;
    elfm_track *t = elfm_track_create(11, &err);
    CHECK(t != NULL);
    for (int f = 0; f < 40 && t; f++) {
      double p[3];
      wobbling_circle(f, p);
      elfm_detection d = mk(f, T0 + 1000 * f, p[0], p[1], p[2]);
      CHECK_OK(elfm_track_append(t, &d, &err), &err);
    }
    elfm_link_gap g, g_off;
    elfm_link_track_end(t, &o, 50, &g);
    elfm_link_track_end(t, &off, 50, &g_off);
    CHECK(g.circle.ok && !g_off.circle.ok);
    double worst = 0, worst_off = 0;
    for (int f = 40; f < 50; f++) {
      double p[3];
      wobbling_circle(f, p);
      worst = fmax(worst, gap_miss(&g, T0 + 1000 * f, p, o.kz));
      worst_off = fmax(worst_off, gap_miss(&g_off, T0 + 1000 * f, p, o.kz));
    }
    CHECK_MSG(worst < 2 && worst_off > 10 * worst, "open end: circle %g um, turn %g um", worst,
              worst_off);
    elfm_track_free(t);

    elfm_linker *l = elfm_link_create(&o, &err);
    CHECK(l != NULL);
    elfm_link_gap gs[4], birth;
    int have_birth = 0;
    for (int f = 0; f < 12 && l; f++) {
      double p[3];
      wobbling_circle(f, p);
      elfm_detection d = mk(f, T0 + 1000 * f, p[0], p[1], p[2]);
      CHECK_OK(elfm_link_step(l, f, T0 + 1000 * f, &d, 1, &err), &err);
      int ng = 0;
      CHECK_OK(elfm_link_settled_gaps(l, 8, 0, gs, 4, &ng, &err), &err);
      for (int i = 0; i < ng; i++)
        if (gs[i].open_start) {
          birth = gs[i];
          have_birth = 1;
        }
    }
    CHECK(have_birth);
    if (have_birth) {
      CHECK(birth.circle.ok);
      elfm_link_gap birth_off = birth; /* the tail's turn, as with the option off */
      birth_off.circle.ok = 0;
      worst = worst_off = 0;
      for (int f = -6; f < 0; f++) {
        double p[3];
      wobbling_circle(f, p);
        worst = fmax(worst, gap_miss(&birth, T0 + 1000 * f, p, o.kz));
        worst_off = fmax(worst_off, gap_miss(&birth_off, T0 + 1000 * f, p, o.kz));
      }
      CHECK_MSG(worst < 4 && worst_off > 5 * worst, "open start: circle %g um, turn %g um", worst,
                worst_off);
    }
    if (l) end_linker(l);
    /* fewer than 6 end points (but 0) is refused, naming the option */
    o.circle_end_points = 5;
    elfm_linker *bad = elfm_link_create(&o, &err);
    CHECK(bad == NULL && strstr(err.message, "circle_end_points") != NULL);
    if (bad) end_linker(bad);
    elfm_error_clear(&err);
  }

  /* 3d. elfm_link_fill_confirmed: a find is confirmed by a point of the
   * next or the last frame within r (z / kz), another find or the gap's
   * end there; not by one two frames away, nor by an open gap's unset end,
   * nor by itself. */
  {
    elfm_link_gap g;
    memset(&g, 0, sizeof g);
    g.frame0 = 10;
    g.frame1 = 20;
    g.p0_um[0] = 0;   /* the head's fit at frame 10 */
    g.p1_um[0] = 100; /* the tail's fit at frame 20 */
    elfm_detection pts[5] = {
        mk(11, T0 + 11000, 2, 0, 3),   /* 2 um (z 3 / 1.5) from the head's end */
        mk(14, T0 + 14000, 50, 0, 0),  /* 13 and 15: within 4 um? 3 and 4.5 */
        mk(13, T0 + 13000, 47, 0, 0),
        mk(15, T0 + 15000, 54.5, 0, 0),
        mk(17, T0 + 17000, 70, 0, 0),  /* nothing at 16 or 18 */
    };
    const double kz = 1.5;
    CHECK(elfm_link_fill_confirmed(&g, pts, 5, 0, kz, 4));   /* by the end: sqrt(4 + 4) */
    CHECK(!elfm_link_fill_confirmed(&g, pts, 5, 0, kz, 2.5));
    CHECK(elfm_link_fill_confirmed(&g, pts, 5, 1, kz, 4));   /* by frame 13, 3 um */
    CHECK(!elfm_link_fill_confirmed(&g, pts, 5, 1, kz, 3));  /* 3 is not < 3; 15 is 4.5 */
    CHECK(elfm_link_fill_confirmed(&g, pts, 5, 2, kz, 4));   /* by frame 14 */
    CHECK(!elfm_link_fill_confirmed(&g, pts, 5, 3, kz, 4));  /* 4.5 from frame 14 */
    CHECK(elfm_link_fill_confirmed(&g, pts, 5, 3, kz, 5));
    CHECK(!elfm_link_fill_confirmed(&g, pts, 5, 4, kz, 100)); /* alone: 16 and 18 empty */
    /* the end at frame 19 is the tail's (x 100); an open_end gap has none */
    elfm_detection late = mk(19, T0 + 19000, 99, 0, 0);
    CHECK(elfm_link_fill_confirmed(&g, &late, 1, 0, kz, 4));
    g.open_end = 1;
    CHECK(!elfm_link_fill_confirmed(&g, &late, 1, 0, kz, 4));
    g.open_start = 1;
    CHECK(!elfm_link_fill_confirmed(&g, pts, 1, 0, kz, 4)); /* the head's end unset */
    /* z counts over kz: 3 um in z at kz 1.5 is 2 um */
    elfm_detection zz[2] = {mk(5, T0 + 5000, 0, 0, 0), mk(6, T0 + 6000, 0, 0, 5.9)};
    CHECK(elfm_link_fill_confirmed(&g, zz, 2, 0, kz, 4));
    CHECK(!elfm_link_fill_confirmed(&g, zz, 2, 0, 1.0, 4));
  }

  /* 4. Filling: points given back land in the gap (and before the first
   * point), the linker's next prediction is unchanged, the finished track
   * holds them in order; all = 1 reports the gaps never settled; bad fills
   * are errors that change nothing. */
  {
    elfm_link_options o;
    elfm_link_options_default(&o);
    elfm_linker *l = elfm_link_create(&o, &err);
    CHECK(l != NULL);
    int64_t id = -1;
    for (int f = 5; f < 30; f++) {
      elfm_detection d = mk(f, T0 + 1000 * f, 1.0 * f, 0, 0);
      CHECK_OK(elfm_link_step(l, f, T0 + 1000 * f, &d, f >= 10 && f < 15 ? 0 : 1, &err), &err);
      if (f == 5) id = elfm_link_last_track_id(l, 0);
    }
    double before[3], after[3];
    int np = 0;
    CHECK_OK(elfm_link_predict(l, 30, T0 + 30000, 1, before, NULL, 1, &np, &err), &err);
    CHECK(np == 1);
    elfm_detection fill[3] = {mk(12, T0 + 12000, 12.1, 0, 0), mk(11, T0 + 11000, 11.1, 0, 0),
                              mk(3, T0 + 3000, 3.1, 0, 0)};
    CHECK_OK(elfm_link_fill(l, id, fill, 3, &err), &err);
    CHECK_OK(elfm_link_predict(l, 30, T0 + 30000, 1, after, NULL, 1, &np, &err), &err);
    CHECK(np == 1 && before[0] == after[0] && before[1] == after[1] && before[2] == after[2]);
    /* taken frame, at / after the last point, unknown track, NaN */
    elfm_detection bad = mk(12, T0 + 12000, 0, 0, 0);
    CHECK(elfm_link_fill(l, id, &bad, 1, &err) == ELFM_ERR_INVALID);
    bad = mk(29, T0 + 29000, 0, 0, 0);
    CHECK(elfm_link_fill(l, id, &bad, 1, &err) == ELFM_ERR_INVALID);
    bad = mk(13, T0 + 13000, 0, 0, 0);
    CHECK(elfm_link_fill(l, id + 100, &bad, 1, &err) == ELFM_ERR_INVALID);
    bad.x_um = NAN;
    CHECK(elfm_link_fill(l, id, &bad, 1, &err) == ELFM_ERR_NUMERIC);
    CHECK(elfm_link_settled_gaps(l, 0, 0, NULL, 0, &np, &err) == ELFM_ERR_INVALID);
    /* a gap with 3 points after it, never settled at 8: all = 1 gives it */
    for (int f = 30; f < 40; f++) {
      elfm_detection d = mk(f, T0 + 1000 * f, 1.0 * f, 0, 0);
      CHECK_OK(elfm_link_step(l, f, T0 + 1000 * f, &d, f < 37 ? 0 : 1, &err), &err);
    }
    elfm_link_gap g[4];
    int ng = 0;
    CHECK_OK(elfm_link_settled_gaps(l, 8, 1, g, 4, &ng, &err), &err);
    CHECK(ng == 1 && g[0].frame0 == 29 && g[0].frame1 == 37);
    CHECK_OK(elfm_link_finish(l, &err), &err);
    elfm_track *t = elfm_link_pop_finished(l);
    CHECK(t != NULL);
    if (t) {
      CHECK(t->n == 20 + 3 + 3);
      CHECK(t->pts[0].frame == 3 && t->pts[1].frame == 5);
      int ordered = 1;
      for (size_t k = 1; k < t->n; k++) ordered &= t->pts[k].frame > t->pts[k - 1].frame;
      CHECK(ordered);
      elfm_track_free(t);
    }
    elfm_link_free(l);
  }

  /* 5. Filling after a swap review exchanged two tracks' tails. P moves
   * along +x at 3 um/ms from frame 0; Q, born at frame 24, at 20 degrees to
   * it; one detection between them while closer than 5 um (frames 29-31).
   * The review gives each track its own object's tail; the exchange leaves
   * Q's track far shorter than P's head, and the index of P's gap closing
   * (its review done) once outlived the exchange: a fill then read past the
   * end of Q's points (heap overflow under AddressSanitizer; flow 1 s seed 5
   * with the circle fit on). Both tracks take a point before their first. */
  {
    elfm_link_options ow;
    elfm_link_options_default(&ow);
    ow.swap_points = 6;
    elfm_linker *l = elfm_link_create(&ow, &err);
    CHECK(l != NULL);
    const double th = 20 * M_PI / 180;
    int64_t ids[2] = {-1, -1};
    for (int f = 4; f < 46; f++) {
      double t = f - 30, px = 3 * t, py = 0, qx = 3 * t * cos(th), qy = 3 * t * sin(th);
      elfm_detection d[2];
      int n = 0;
      if (hypot(px - qx, py - qy) < 5) {
        d[n++] = mk(f, T0 + 1000 * f, 0.5 * (px + qx), 0.5 * (py + qy), 5);
      } else {
        d[n++] = mk(f, T0 + 1000 * f, px, py, 5);
        if (f >= 24) d[n++] = mk(f, T0 + 1000 * f, qx, qy, 5);
      }
      CHECK_OK(elfm_link_step(l, f, T0 + 1000 * f, d, n, &err), &err);
      if (f == 45)
        for (int i = 0; i < 2; i++) ids[i] = elfm_link_last_track_id(l, i);
    }
    for (int i = 0; i < 2; i++) {
      elfm_detection early = mk(1 + i, T0 + 1000 * (1 + i), -90, 0, 5);
      CHECK_OK(elfm_link_fill(l, ids[i], &early, 1, &err), &err);
    }
    CHECK_OK(elfm_link_finish(l, &err), &err);
    int n = 0, own = 0;
    elfm_track *t;
    while ((t = elfm_link_pop_finished(l))) {
      n++;
      int ordered = t->pts[0].frame <= 2;
      for (size_t k = 1; k < t->n; k++) ordered &= t->pts[k].frame > t->pts[k - 1].frame;
      CHECK(ordered);
      /* started on P (y = 0 after the filled point) or on Q: the same at the end? */
      int start_p = fabs(t->pts[1].y_um) < 1, end_p = fabs(t->pts[t->n - 1].y_um) < 1;
      own += start_p == end_p;
      elfm_track_free(t);
    }
    CHECK_MSG(n == 2 && own == 2, "swap then fill: %d tracks, %d on their own object", n, own);
    elfm_link_free(l);
  }
  return check_report();
}
