/* test_link_input.c — the linker's bad input (frames and times that go
 * back, NaN and infinite positions, NULL detections, out-of-range
 * options: each an error code, no crash), the options a caller sets
 * between frames (elfm_link_set_rescue_gate_factor, elfm_link_set_gate_um),
 * its lag correction, and what it tells of the track each detection joined
 * (elfm_link_last_velocity) and of a track's points around a frame
 * (elfm_link_local_velocity). */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "check.h"
#include "elfm_tracker.h"
#include "link_test_util.h"

static elfm_detection mk(double x, double y, double z) { return link_test_det(x, y, z, 1); }

int main(void)
{
  elfm_error err;
  elfm_error_clear(&err);
  elfm_link_options o;
  elfm_link_options_default(&o);
  const int64_t T0 = 1000000000000LL;  /* absolute times near 1e12 us */

  /* 1. Bad input. */
  {
    elfm_linker *l = elfm_link_create(&o, &err);
    elfm_detection d = mk(0, 0, 0);
    CHECK_OK(elfm_link_step(l, 5, T0, &d, 1, &err), &err);
    CHECK_EQ_INT(elfm_link_step(l, 5, T0 + 1000, &d, 1, &err), ELFM_ERR_INVALID);
    CHECK_EQ_INT(elfm_link_step(l, 6, T0 - 1, &d, 1, &err), ELFM_ERR_INVALID);
    d.y_um = NAN;
    CHECK_EQ_INT(elfm_link_step(l, 6, T0 + 1000, &d, 1, &err), ELFM_ERR_NUMERIC);
    d.y_um = INFINITY;
    CHECK_EQ_INT(elfm_link_step(l, 6, T0 + 1000, &d, 1, &err), ELFM_ERR_NUMERIC);
    CHECK_EQ_INT(elfm_link_step(l, 6, T0 + 1000, NULL, 3, &err), ELFM_ERR_INVALID);
    elfm_link_free(l);
    elfm_link_options bad = o;
    bad.gate_um = 0;
    CHECK(elfm_link_create(&bad, &err) == NULL);
    bad = o;
    bad.rest_speed_um_per_ms = -0.1;
    CHECK(elfm_link_create(&bad, &err) == NULL);
    bad.rest_speed_um_per_ms = NAN;
    CHECK(elfm_link_create(&bad, &err) == NULL);
    bad = o;
    bad.stitch_points = 3;  /* a young track needs 4 points for its path */
    CHECK(elfm_link_create(&bad, &err) == NULL);
    /* the message names the option, its value and what it takes */
    CHECK_MSG(strstr(err.message, "stitch_points = 3 is out of range (0 or >= 4)") != NULL, "%s",
              err.message);
    bad = o;
    bad.rest_speed_um_per_ms = -0.25;
    CHECK(elfm_link_create(&bad, &err) == NULL);
    CHECK_MSG(strstr(err.message, "rest_speed_um_per_ms = -0.25") != NULL, "%s", err.message);
    bad = o;
    bad.swap_points = 3;    /* a tail needs 4 points for its fit */
    CHECK(elfm_link_create(&bad, &err) == NULL);
    bad = o;
    bad.swap_points = 6;
    bad.swap_ratio = 1.5;
    CHECK(elfm_link_create(&bad, &err) == NULL);
    bad = o;
    bad.encounter_um = -1;
    CHECK(elfm_link_create(&bad, &err) == NULL);
    bad = o;
    bad.encounter_um = NAN;
    CHECK(elfm_link_create(&bad, &err) == NULL);
    bad = o;
    bad.encounter_pad = -1;
    CHECK(elfm_link_create(&bad, &err) == NULL);
    bad = o;
    bad.encounter_apart = -1;
    CHECK(elfm_link_create(&bad, &err) == NULL);
    bad = o;
    bad.encounter_ratio = 0;
    CHECK(elfm_link_create(&bad, &err) == NULL);
    bad = o;
    bad.encounter_ratio = 1.5;
    CHECK(elfm_link_create(&bad, &err) == NULL);
    bad = o;
    bad.review_join_factor = -0.5;
    CHECK(elfm_link_create(&bad, &err) == NULL);
    bad = o;
    bad.priority_points = -1;
    CHECK(elfm_link_create(&bad, &err) == NULL);
    bad = o;
    bad.history = 1;
    CHECK(elfm_link_create(&bad, &err) == NULL);
    elfm_link_free(NULL);
    CHECK(elfm_link_pop_finished(NULL) == NULL);
  }

  /* 1b. The rescue's factor set between frames (elfm_link_set_rescue_
   * gate_factor, as `track` does per crowded frame): the bead of test_link.c 5b comes
   * back as one track when the factor is raised from 0 to 2.5 just before
   * that frame, as two when it is lowered from 2.5 to 0; a negative or
   * non-finite factor is refused and leaves the factor as it was (2.5 kept
   * when -1 is refused there: one track). */
  {
    elfm_linker *l = elfm_link_create(&o, &err);
    CHECK(elfm_link_set_rescue_gate_factor(l, -1, &err) == ELFM_ERR_INVALID);
    CHECK(elfm_link_set_rescue_gate_factor(l, NAN, &err) == ELFM_ERR_INVALID);
    CHECK(elfm_link_set_rescue_gate_factor(l, INFINITY, &err) == ELFM_ERR_INVALID);
    CHECK(elfm_link_set_rescue_gate_factor(NULL, 1, &err) == ELFM_ERR_INVALID);
    elfm_link_free(l);
    elfm_error_clear(&err);
    int n = link_test_rescue_return(&o, 0, 2.5);
    CHECK_MSG(n == 1, "factor raised at the return: %d tracks", n);
    n = link_test_rescue_return(&o, 2.5, 0);
    CHECK_MSG(n == 2, "factor lowered at the return: %d tracks", n);
    n = link_test_rescue_return(&o, 2.5, -1);
    CHECK_MSG(n == 1, "factor -1 refused at the return: %d tracks", n);
  }

  /* 1c. The gate set between frames (elfm_link_set_gate_um): a bead at
   * 3 um/ms along x steps 5 um to the side at frame 40, rescue off. With
   * the gate at 6 um (6.9 with the speed's share) one track follows it; set
   * to 4 um (4.9) just before that frame, the step starts a second. 0,
   * negative and non-finite gates are refused. */
  for (int narrow = 0; narrow < 2; narrow++) {
    elfm_link_options og = o;
    og.rescue_gate_factor = 0;
    elfm_linker *l = elfm_link_create(&og, &err);
    CHECK(elfm_link_set_gate_um(l, 0, &err) == ELFM_ERR_INVALID);
    CHECK(elfm_link_set_gate_um(l, -4, &err) == ELFM_ERR_INVALID);
    CHECK(elfm_link_set_gate_um(l, INFINITY, &err) == ELFM_ERR_INVALID);
    CHECK(elfm_link_set_gate_um(NULL, 4, &err) == ELFM_ERR_INVALID);
    elfm_error_clear(&err);
    for (int f = 0; f < 60; f++) {
      if (f == 40 && narrow) CHECK_OK(elfm_link_set_gate_um(l, 4.0, &err), &err);
      elfm_detection d = mk(3.0 * f, f >= 40 ? 5.0 : 0.0, 5);
      CHECK_OK(elfm_link_step(l, f, T0 + f * 1000, &d, 1, &err), &err);
    }
    CHECK_OK(elfm_link_finish(l, &err), &err);
    int n = 0;
    elfm_track *t;
    while ((t = elfm_link_pop_finished(l))) { n++; elfm_track_free(t); }
    CHECK_MSG(n == (narrow ? 2 : 1), "gate %s at the step: %d tracks", narrow ? "4 um" : "6 um", n);
    elfm_link_free(l);
  }

  /* 2. Lag correction through the linker: detections trail a bead moving at
   * 1 um/ms by the model lag; with lag_tau_us set the attached points sit on
   * the truth again. */
  {
    elfm_link_options ol = o;
    ol.lag_tau_us = 2000;
    ol.min_points = 1;
    elfm_linker *l = elfm_link_create(&ol, &err);
    double lag = elfm_peaks_trail_lag_um(2.0, 1.6);
    double worst = 0;
    for (int f = 0; f < 30; f++) {
      elfm_detection d = mk(1.0 * f - lag, 0, 0);
      d.sigma_x_um = 1.6;
      CHECK_OK(elfm_link_step(l, f, T0 + f * 1000, &d, 1, &err), &err);
      if (f >= 1 && fabs(d.x_um - f) > worst) worst = fabs(d.x_um - f);
    }
    CHECK_MSG(lag > 0.5 && worst < 0.05, "lag %g, worst corrected error %g", lag, worst);
    elfm_link_free(l);
  }

  /* 3. What the linker tells of the track each detection joined (track's
   * test for a stage reads it): a bead at (0.8, -1.2, 0.4) um/ms, exactly
   * on its line, then a second bead born beside it. The first frame has no
   * velocity (a new track: 1 point), later ones the track's, both fits
   * exact on a line; a detection index past the last is no track. */
  {
    elfm_linker *l = elfm_link_create(&o, &err);
    CHECK(l != NULL);
    double v[3], vl[3], span;
    for (int f = 0; f < 25; f++) {
      elfm_detection d[2] = {mk(0.8 * f, -1.2 * f, 0.4 * f), mk(30, 30, 0)};
      const int n = f < 24 ? 1 : 2;
      CHECK_OK(elfm_link_step(l, f, T0 + f * 1000, d, n, &err), &err);
      const size_t np = elfm_link_last_velocity(l, 0, v, vl, &span);
      CHECK_EQ_INT((int)np, f + 1);
      if (f == 0) {
        CHECK(isnan(v[0]) && isnan(vl[2]) && isnan(span) && isnan(elfm_link_last_speed(l, 0)));
        continue;
      }
      /* the long fit's points: the last `history` (20), 1 ms apart */
      CHECK_NEAR(span, f < o.history ? f : o.history - 1, 1e-9);
      CHECK_NEAR(v[0], 0.8, 1e-6);
      CHECK_NEAR(v[1], -1.2, 1e-6);
      CHECK_NEAR(vl[0], 0.8, 1e-6);
      CHECK_NEAR(vl[1], -1.2, 1e-6);
      CHECK_NEAR(vl[2], 0.4, 1e-6);
      CHECK_NEAR(elfm_link_last_speed(l, 0), sqrt(0.64 + 1.44 + 0.16), 1e-6);
    }
    /* the newborn: one point, no velocity; past the last detection: none */
    CHECK_EQ_INT((int)elfm_link_last_velocity(l, 1, v, NULL, NULL), 1);
    CHECK(isnan(v[0]));
    CHECK_EQ_INT((int)elfm_link_last_velocity(l, 2, v, vl, &span), 0);
    CHECK(isnan(vl[1]) && isnan(span));
    CHECK_EQ_INT((int)elfm_link_last_velocity(NULL, 0, v, vl, NULL), 0);
    elfm_link_free(l);
  }
  /* How far each detection lay from its track's prediction
   * (elfm_link_last_miss_um): none before the track has 5 points, none for
   * a newborn or past the last detection; ~0 on the track's exact line; a
   * point put 1.5 um aside and 4 um deeper misses by sqrt(1.5^2 + (4 /
   * kz)^2); after a frame without its detection, none (the prediction
   * came across a gap). */
  {
    elfm_linker *l = elfm_link_create(&o, &err);
    CHECK(l != NULL);
    for (int f = 0; f < 25; f++) {
      if (f == 18) { /* the bead unseen */
        CHECK_OK(elfm_link_step(l, f, T0 + f * 1000, NULL, 0, &err), &err);
        continue;
      }
      elfm_detection d[2] = {mk(0.8 * f, -1.2 * f, 0.4 * f), mk(30, 30, 0)};
      if (f == 12) {
        d[0].y_um += 1.5;
        d[0].z_um += 4;
      }
      const int n = f == 24 ? 2 : 1;
      CHECK_OK(elfm_link_step(l, f, T0 + f * 1000, d, n, &err), &err);
      const double m = elfm_link_last_miss_um(l, 0);
      if (f < 5 || f == 19)
        CHECK_MSG(isnan(m), "frame %d: miss %g, none expected", f, m);
      else if (f == 12)
        CHECK_NEAR(m, sqrt(1.5 * 1.5 + (4 / o.kz) * (4 / o.kz)), 1e-6);
      else if (f < 12)
        CHECK_NEAR(m, 0, 1e-6);
      else
        CHECK_MSG(m >= 0 && m < 3, "frame %d: miss %g", f, m);
    }
    CHECK(isnan(elfm_link_last_miss_um(l, 1)));  /* the newborn */
    CHECK(isnan(elfm_link_last_miss_um(l, 2)));  /* past the last */
    CHECK(isnan(elfm_link_last_miss_um(l, -1)));
    CHECK(isnan(elfm_link_last_miss_um(NULL, 0)));
    elfm_link_free(l);
  }
  /* the line through a track's points around a frame: exact on a line
   * (x = 1 + 0.5 t_ms, z = -2 t_ms), at times near 1e12 us too; the window
   * counts frames, not points (frame 14 is a gap); fewer than 3 points, or
   * one time only: 0, v unchanged */
  {
    elfm_track *u = elfm_track_create(9, &err);
    const int64_t t0 = 1000000000000LL;
    for (int f = 10; f < 20; f++) {
      if (f == 14) continue;
      elfm_detection d;
      memset(&d, 0, sizeof d);
      d.frame = f;
      d.t_us = t0 + 1000 * f + (f % 3) * 37; /* windows not evenly spaced */
      const double tm = 1e-3 * (double)(d.t_us - t0);
      d.x_um = 1 + 0.5 * tm;
      d.y_um = 3;
      d.z_um = -2 * tm;
      CHECK_OK(elfm_track_append(u, &d, &err), &err);
    }
    double v[3] = {NAN, NAN, NAN};
    CHECK_EQ_INT(elfm_link_local_velocity(u, 15, 3, v), 6); /* 12, 13, 15-18 */
    CHECK_NEAR(v[0], 0.5, 1e-9);
    CHECK_NEAR(v[1], 0, 1e-9);
    CHECK_NEAR(v[2], -2, 1e-9);
    CHECK_EQ_INT(elfm_link_local_velocity(u, 10, 3, v), 4); /* the first: one side */
    CHECK_NEAR(v[2], -2, 1e-9);
    v[0] = 7;
    CHECK_EQ_INT(elfm_link_local_velocity(u, 23, 4, v), 0); /* 19 alone */
    CHECK_EQ_INT(elfm_link_local_velocity(u, 14, 1, v), 0); /* 13 and 15: two */
    CHECK(v[0] == 7);
    CHECK_EQ_INT(elfm_link_local_velocity(NULL, 14, 1, v), 0);
    elfm_track_free(u);
    /* three frames at one time (repeated timestamps): no line */
    u = elfm_track_create(10, &err);
    for (int f = 1; f <= 3; f++) {
      elfm_detection d;
      memset(&d, 0, sizeof d);
      d.frame = f;
      d.t_us = t0;
      d.x_um = f;
      CHECK_OK(elfm_track_append(u, &d, &err), &err);
    }
    CHECK_EQ_INT(elfm_link_local_velocity(u, 2, 1, v), 0);
    CHECK(v[0] == 7);
    elfm_track_free(u);
  }
  return check_report();
}
