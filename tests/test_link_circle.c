/* test_link_circle.c — the linker's circle fit (elfm_link.h circle_points,
 * tracker/elfm_link_circle.c): exact circles in tilted planes recovered at
 * absolute times near 1e12 us and far from the origin; paths that do not
 * turn (straight, with noisy depths), short arcs, wide circles, too few
 * points, repeated times and a static point refused; and through the linker,
 * a noisy bead circling through a 20-frame gap kept in one track with the
 * circle where the short fit's turn loses it, while a bead moving straight
 * is linked exactly as without the circle; a settled gap's own circle
 * placing the bead inside a 16-frame gap at less than half the error of the
 * two ends' turns (the unwrap guided by the rate, not by the nearest
 * angle). Includes the tracker's private
 * link_internal.h to test the fit itself. */
#include <math.h>
#include <stdint.h>
#include <string.h>

#include "check.h"
#include "elfm_tracker.h"
#include "link_test_util.h"
#include "link_internal.h"

static const int64_t T0 = 1000000000000LL; /* absolute times near 1e12 us */

/* A deterministic normal deviate (the test's own generator: xorshift64*
 * and Box-Muller), so every run sees the same noise. */
static double normal(uint64_t *s)
{
  double u[2];
  for (int i = 0; i < 2; i++) {
    *s ^= *s >> 12;
    *s ^= *s << 25;
    *s ^= *s >> 27;
    u[i] = ((double)((*s * 2685821657736338717ULL) >> 11) + 0.5) / 9007199254740992.0;
  }
  return sqrt(-2 * log(u[0])) * cos(2 * M_PI * u[1]);
}

/* A path: centre c, radius r (0: a straight line along e1 at speed v), in
 * the plane of the unit vectors e1, e2, at rate w rad/ms from phase a0. */
typedef struct path {
  double c[3], e1[3], e2[3], r, w, a0, v;
} path;

static void path_at(const path *p, double t_ms, double out[3])
{
  for (int i = 0; i < 3; i++) {
    if (p->r > 0) {
      const double a = p->a0 + p->w * t_ms;
      out[i] = p->c[i] + p->r * (cos(a) * p->e1[i] + sin(a) * p->e2[i]);
    } else {
      out[i] = p->c[i] + p->v * t_ms * p->e1[i];
    }
  }
}

/* A plane tilted by th about x, then ph about z. */
static void tilted(path *p, double th, double ph)
{
  const double e1[3] = {cos(ph), sin(ph), 0};
  const double e2[3] = {-sin(ph) * cos(th), cos(ph) * cos(th), sin(th)};
  memcpy(p->e1, e1, sizeof e1);
  memcpy(p->e2, e2, sizeof e2);
}

static elfm_detection det_at(const path *p, int64_t frame, uint64_t *noise, double sd_xy,
                             double sd_z)
{
  double q[3];
  path_at(p, (double)frame, q);
  elfm_detection d;
  memset(&d, 0, sizeof d);
  d.frame = frame;
  d.t_us = T0 + 1000 * frame;
  d.x_um = q[0] + (noise ? sd_xy * normal(noise) : 0);
  d.y_um = q[1] + (noise ? sd_xy * normal(noise) : 0);
  d.z_um = q[2] + (noise ? sd_z * normal(noise) : 0);
  d.intensity = 1;
  return d;
}

/* The fit's settings throughout (set at the start of main): >= 1 rad, a
 * radius <= 60 um, 2 x better than a line, z / 4 (a test driver's static,
 * as check.h's counters). */
static elfm_link_options fit_opts;

/* Fit frames f0 .. f0+n-1 of p (noise as given); tr the last point's time. */
static int fit(const path *p, int f0, int n, uint64_t *noise, double sd_xy, double sd_z,
               elfm_link_circle *c)
{
  elfm_detection pts[64];
  for (int k = 0; k < n; k++) pts[k] = det_at(p, f0 + k, noise, sd_xy, sd_z);
  return elfm_link_fit_circle(&fit_opts, pts, 0, (size_t)n, pts[n - 1].t_us, c);
}

/* Track count and the longest track's points of a run of the linker over
 * frames 0-69 of p with frames 30-49 dark (noisy points). */
static void run_gap(const path *p, int circle_points, uint64_t seed, int *n_tracks,
                    size_t *longest)
{
  elfm_error err;
  elfm_link_options o;
  elfm_link_options_default(&o);
  o.circle_points = circle_points;
  elfm_linker *l = elfm_link_create(&o, &err);
  CHECK(l != NULL);
  *n_tracks = 0;
  *longest = 0;
  if (!l) return;
  uint64_t noise = seed;
  for (int f = 0; f < 70; f++) {
    elfm_detection d = det_at(p, f, &noise, 0.3, 1.0);
    const int n = f >= 30 && f < 50 ? 0 : 1;
    CHECK_OK(elfm_link_step(l, f, d.t_us, &d, n, &err), &err);
  }
  CHECK_OK(elfm_link_finish(l, &err), &err);
  elfm_track *t;
  while ((t = elfm_link_pop_finished(l))) {
    (*n_tracks)++;
    if (t->n > *longest) *longest = t->n;
    elfm_track_free(t);
  }
  elfm_link_free(l);
}

int main(void)
{
  elfm_link_options_default(&fit_opts);
  fit_opts.circle_min_arc_rad = 1.0;
  fit_opts.circle_max_radius_um = 60;
  fit_opts.circle_line_ratio = 0.5;
  fit_opts.kz = 4;
  /* 1. Exact circles in tilted planes: radius, rate and a prediction 20 ms
   * on, with times near 1e12 us, at the origin and 1e4 um from it. */
  for (int k = 0; k < 6; k++) {
    path p;
    memset(&p, 0, sizeof p);
    tilted(&p, 0.3 + 0.45 * k, 0.7 * k);
    p.r = 8 + 2.5 * k;
    p.w = (k % 2 ? -1 : 1) * 3.0 / p.r; /* 3 um/ms */
    p.a0 = 0.9 * k;
    for (int far = 0; far < 2; far++) {
      for (int i = 0; i < 3; i++) p.c[i] = far ? 1e4 * (i + 1) : 5.0 * i;
      elfm_link_circle c;
      CHECK(fit(&p, 100, 15, NULL, 0, 0, &c) && c.ok);
      CHECK_NEAR(c.r_um, p.r, 1e-6);
      /* the sign of the rate is the fitted plane's orientation's */
      CHECK_NEAR(fabs(c.omega_rad_per_ms), fabs(p.w), 1e-9);
      double q[3], want[3];
      elfm_link_circle_predict(&c, 20, q);
      path_at(&p, 114 + 20, want);
      for (int i = 0; i < 3; i++) CHECK_NEAR(q[i], want[i], 1e-5);
    }
  }

  /* 2. Refused: straight (exact, and with depth noise 2 um that bends the
   * plane), a 0.5 rad arc, a circle wider than 60 um, 5 points, all at one
   * time, a static point. */
  {
    path p;
    memset(&p, 0, sizeof p);
    tilted(&p, 0.5, 0.2);
    p.v = 2.5;
    elfm_link_circle c;
    CHECK(!fit(&p, 0, 15, NULL, 0, 0, &c) && !c.ok);
    int bent = 0;
    for (uint64_t s = 1; s <= 50; s++) {
      uint64_t noise = s * 7919;
      bent += fit(&p, 0, 15, &noise, 0.3, 2.0, &c);
    }
    CHECK_MSG(bent == 0, "%d of 50 noisy straight paths fitted a circle", bent);
    /* The line test: 6 pulses 3 frames apart of a bead moving straight at
     * 2.5 um/ms with depths 3.5 um off (a deep blinking bead), 500 draws.
     * Without it (ratio 1) 22 fitted a circle when this was written; with
     * 0.5, 1. */
    int with_test = 0, without = 0;
    elfm_link_options no_line_test = fit_opts;
    no_line_test.circle_line_ratio = 1.0;
    for (uint64_t s = 1; s <= 500; s++) {
      uint64_t noise = s * 2654435761ULL + 17;
      elfm_detection pts[6];
      for (int k = 0; k < 6; k++) {
        pts[k] = det_at(&p, 3 * k, NULL, 0, 0);
        pts[k].x_um += 0.5 * normal(&noise);
        pts[k].y_um += 0.5 * normal(&noise);
        pts[k].z_um += 3.5 * normal(&noise);
      }
      with_test += elfm_link_fit_circle(&fit_opts, pts, 0, 6, pts[5].t_us, &c);
      without += elfm_link_fit_circle(&no_line_test, pts, 0, 6, pts[5].t_us, &c);
    }
    fprintf(stderr, "pulses on a line: %d circles with the line test, %d without\n", with_test, without);
    CHECK_MSG(with_test <= 1 && without >= 5, "pulses on a line: %d circles with the line test, "
              "%d without", with_test, without);
    p.v = 0;
    p.r = 14;
    p.w = 0.5 / 14 / 1.0; /* 0.5 um/ms: 14 points span 0.5 rad */
    CHECK(!fit(&p, 0, 15, NULL, 0, 0, &c));
    p.r = 80;
    p.w = 3.0 / 80;
    CHECK(!fit(&p, 0, 30, NULL, 0, 0, &c));
    p.r = 14;
    p.w = 3.0 / 14;
    CHECK(!fit(&p, 0, 5, NULL, 0, 0, &c));
    CHECK(fit(&p, 0, 6, NULL, 0, 0, &c));
    elfm_detection pts[15];
    for (int k = 0; k < 15; k++) {
      pts[k] = det_at(&p, k, NULL, 0, 0);
      pts[k].t_us = T0; /* repeated times */
    }
    CHECK(!elfm_link_fit_circle(&fit_opts, pts, 0, 15, T0, &c));
    for (int k = 0; k < 15; k++) pts[k] = det_at(&p, 0, NULL, 0, 0), pts[k].frame = k,
                                 pts[k].t_us = T0 + 1000 * k; /* at rest */
    CHECK(!elfm_link_fit_circle(&fit_opts, pts, 0, 15, pts[14].t_us, &c));
  }

  /* 3. Through the linker: a bead circling at 3 um/ms on a radius of
   * 12-16 um (flow's beads), noise 0.3 um laterally and 1 um in depth,
   * dark for frames 30-49. With the circle (15 points) the track carries
   * on after the gap every time; with the short fit's turn alone it broke
   * in 6 of the 12 geometries when this was written.
   * A bead moving straight is linked the same either way. */
  {
    int kept_on = 0, kept_off = 0, trials = 12;
    for (int k = 0; k < trials; k++) {
      path p;
      memset(&p, 0, sizeof p);
      tilted(&p, 0.2 + 0.1 * k, 0.5 * k);
      p.r = 12 + (k % 3) * 2;
      p.w = (k % 2 ? 1 : -1) * 3.0 / p.r;
      p.a0 = 0.4 * k;
      int n_on, n_off;
      size_t long_on, long_off;
      run_gap(&p, 15, 1000 + k, &n_on, &long_on);
      run_gap(&p, 0, 1000 + k, &n_off, &long_off);
      kept_on += n_on == 1 && long_on == 50;
      kept_off += n_off == 1 && long_off == 50;
    }
    fprintf(stderr, "circling bead through a 20-frame gap: one track in %d of %d with the circle, "
                    "%d without\n", kept_on, trials, kept_off);
    CHECK_MSG(kept_on == trials && kept_off <= 3 * trials / 4, "circle %d, turn %d of %d", kept_on,
              kept_off, trials);
    path s;
    memset(&s, 0, sizeof s);
    tilted(&s, 0.4, 1.1);
    s.v = 2.5;
    int n_on, n_off;
    size_t long_on, long_off;
    run_gap(&s, 15, 77, &n_on, &long_on);
    run_gap(&s, 0, 77, &n_off, &long_off);
    CHECK(n_on == n_off && long_on == long_off);
  }

  /* 3b. Gaps settled 8 points after a 16-frame gap of such a bead carry
   * the circle through 4 points on each side; its prediction in the gap
   * lies nearer the bead than the two ends' turns blended (without it). */
  {
    double err_on = 0, err_off = 0;
    int n_on = 0, n_off = 0;
    for (int k = 0; k < 8; k++) {
      path p;
      memset(&p, 0, sizeof p);
      tilted(&p, 0.3 + 0.15 * k, 0.8 * k);
      p.r = 10 + k;
      p.w = (k % 2 ? 1 : -1) * 3.0 / p.r;
      p.a0 = 0.7 * k;
      for (int gp = 0; gp < 2; gp++) {
        elfm_error err;
        elfm_link_options o;
        elfm_link_options_default(&o);
        o.circle_points = 15;
        o.circle_gap_points = gp ? 4 : 0;
        elfm_linker *l = elfm_link_create(&o, &err);
        CHECK(l != NULL);
        if (!l) continue;
        uint64_t noise = 500 + k;
        for (int f = 0; f < 50; f++) {
          elfm_detection d = det_at(&p, f, &noise, 0.3, 1.0);
          const int n = f >= 20 && f < 36 ? 0 : 1;
          CHECK_OK(elfm_link_step(l, f, d.t_us, &d, n, &err), &err);
          elfm_link_gap g[4];
          int ng = 0;
          CHECK_OK(elfm_link_settled_gaps(l, 8, 0, g, 4, &ng, &err), &err);
          for (int i = 0; i < ng; i++) {
            if (g[i].open_start || g[i].frame1 - g[i].frame0 != 17) continue;
            CHECK(g[i].circle.ok == gp);
            for (int64_t fr = g[i].frame0 + 1; fr < g[i].frame1; fr++) {
              double q[3], want[3];
              elfm_link_gap_predict(&g[i], T0 + 1000 * fr, q);
              path_at(&p, (double)fr, want);
              const double e = sqrt((q[0] - want[0]) * (q[0] - want[0]) +
                                    (q[1] - want[1]) * (q[1] - want[1]) +
                                    (q[2] - want[2]) * (q[2] - want[2]) / 16);
              if (gp) err_on += e, n_on++;
              else err_off += e, n_off++;
            }
          }
        }
        end_linker(l);
      }
    }
    CHECK(n_on == 8 * 16 && n_off == 8 * 16);
    if (n_on && n_off) {
      err_on /= n_on;
      err_off /= n_off;
    }
    fprintf(stderr, "a 16-frame gap on a circle: mean error %.2f um on the gap's circle, %.2f um "
                    "from the ends' turns\n", err_on, err_off);
    CHECK_MSG(err_on < 3 && err_on < 0.5 * err_off, "gap circle %.2f um, turns %.2f um", err_on,
              err_off);
  }

  /* 3c. The next frame along a circle (circle_next_path_um): beads on
   * circles of radius 9-13 um at 6 um of path per frame (0.46-0.67 rad per
   * frame, as flow at 2 ms frames), noisy, short fit over 20 um of path as
   * in `track`. The linker's predictions for frames 20-59 (the track then
   * has its circle and its scores) lie nearer the bead with the circle than
   * from the short fit alone, and each bead stays one track. A bead moving
   * straight fits no circle: the same predictions and tracks either way. */
  {
    double miss_on = 0, miss_off = 0;
    int n_miss = 0;
    for (int k = 0; k < 10; k++) {
      path p;
      memset(&p, 0, sizeof p);
      tilted(&p, 0.2 + 0.1 * k, 0.6 * k);
      const int straight = k == 9;
      p.r = straight ? 0 : 9 + 0.5 * k;
      p.v = 6;
      p.w = (k % 2 ? 1 : -1) * 6.0 / (p.r > 0 ? p.r : 1);
      p.a0 = 0.5 * k;
      double miss[2] = {0, 0};
      int tracks[2] = {0, 0};
      for (int on = 0; on < 2; on++) {
        elfm_error err;
        elfm_link_options o;
        elfm_link_options_default(&o);
        o.short_path_um = 20;
        o.circle_next_path_um = on ? 45 : 0;
        elfm_linker *l = elfm_link_create(&o, &err);
        CHECK(l != NULL);
        if (!l) continue;
        uint64_t noise = 900 + k;
        for (int f = 0; f < 60; f++) {
          elfm_detection d = det_at(&p, f, &noise, 0.3, 1.0);
          if (f >= 20) {
            double q[3], want[3];
            int nq = 0;
            CHECK_OK(elfm_link_predict(l, f, d.t_us, 1, q, NULL, 1, &nq, &err), &err);
            CHECK(nq == 1);
            path_at(&p, (double)f, want);
            if (nq == 1)
              miss[on] += sqrt((q[0] - want[0]) * (q[0] - want[0]) +
                               (q[1] - want[1]) * (q[1] - want[1]) +
                               (q[2] - want[2]) * (q[2] - want[2]) / 16);
          }
          CHECK_OK(elfm_link_step(l, f, d.t_us, &d, 1, &err), &err);
        }
        CHECK_OK(elfm_link_finish(l, &err), &err);
        elfm_track *t;
        while ((t = elfm_link_pop_finished(l))) {
          tracks[on]++;
          elfm_track_free(t);
        }
        elfm_link_free(l);
      }
      if (straight) {
        CHECK_MSG(miss[1] == miss[0] && tracks[1] == tracks[0],
                  "straight bead: miss %g / %g um, %d / %d tracks", miss[1], miss[0], tracks[1],
                  tracks[0]);
        continue;
      }
      CHECK_MSG(tracks[1] == 1, "circle %d: %d tracks with the next frame's circle", k, tracks[1]);
      miss_on += miss[1];
      miss_off += miss[0];
      n_miss += 40;
    }
    if (n_miss) {
      miss_on /= n_miss;
      miss_off /= n_miss;
    }
    fprintf(stderr, "0.46-0.67 rad per frame: the next frame predicted %.2f um off with its circle, "
                    "%.2f um from the short fit\n", miss_on, miss_off);
    CHECK_MSG(n_miss == 9 * 40 && miss_on < 0.7 * miss_off, "circle %.2f um, short fit %.2f um",
              miss_on, miss_off);
  }

  /* 4. Options: circle points 1-5 and circle_after 0 are out of range. */
  {
    elfm_error err;
    elfm_link_options o;
    elfm_link_options_default(&o);
    CHECK(o.circle_points == 0); /* off unless asked for (track: 15) */
    o.circle_points = 5;
    CHECK(elfm_link_create(&o, &err) == NULL);
    o.circle_points = 6;
    o.circle_after = 0;
    CHECK(elfm_link_create(&o, &err) == NULL);
    o.circle_after = 2;
    o.circle_line_ratio = 1.5;
    CHECK(elfm_link_create(&o, &err) == NULL);
    o.circle_line_ratio = 0.5;
    CHECK(o.circle_next_path_um == 0); /* off unless asked for (track: 45) */
    o.circle_next_path_um = -1;
    CHECK(elfm_link_create(&o, &err) == NULL);
    o.circle_next_path_um = NAN;
    CHECK(elfm_link_create(&o, &err) == NULL);
    o.circle_next_path_um = 45;
    elfm_linker *l = elfm_link_create(&o, &err);
    CHECK(l != NULL);
    elfm_link_free(l);
  }
  return check_report();
}
