/* test_frame_times.c — elfm_frame_times (every frame's time, as runs of
 * evenly spaced frames) and the smoother's gap frames taking their times
 * from it: windows opened by trigger edges are not evenly spaced, so a
 * gap's times are not on the line between its ends. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "check.h"
#include "elfm_tracker.h"

/* The times of `track --start each-trigger` with 1 ms windows and rising
 * edges at 5300 and 9000 (test_frames' test_each_trigger), from 1e12 us on
 * (absolute times near 1e12 must stay exact). */
static const int64_t T0 = 1000000000000LL;
static const int64_t times[12] = {3500, 4500, 5300, 6300, 7300, 8300, 9000, 10000, 11000, 12000,
                                  13000, 14000};

static void test_runs(void)
{
  elfm_error err;
  elfm_frame_times ft;
  elfm_frame_times_init(&ft);
  int64_t t = -1;
  CHECK(!elfm_frame_times_get(&ft, 0, &t) && t == -1);
  for (int f = 0; f < 12; f++) CHECK_OK(elfm_frame_times_add(&ft, f, T0 + times[f], &err), &err);
  for (int f = 0; f < 12; f++) {
    CHECK(elfm_frame_times_get(&ft, f, &t));
    CHECK_EQ_INT(t - T0, times[f]);
  }
  CHECK(!elfm_frame_times_get(&ft, -1, &t));
  CHECK(!elfm_frame_times_get(&ft, 12, &t));
  /* runs, not frames: 0-1 (step 1000), 2-5, 6-11 */
  CHECK_EQ_INT(ft.n, 3);
  /* a fixed frame rate is one run, whatever its length */
  elfm_frame_times u;
  elfm_frame_times_init(&u);
  int added = 1;
  for (int f = 0; f < 100000; f++) added &= elfm_frame_times_add(&u, f, 500 + 2000LL * f, &err) == ELFM_OK;
  CHECK(added);
  CHECK_EQ_INT(u.n, 1);
  CHECK(elfm_frame_times_get(&u, 77777, &t) && t == 500 + 2000LL * 77777);
  /* out of order: refused, nothing changed */
  CHECK(elfm_frame_times_add(&u, 99999, 1LL << 40, &err) == ELFM_ERR_INVALID);
  CHECK(strstr(err.message, "does not follow") != NULL);
  CHECK(elfm_frame_times_add(&u, 100000, 500 + 2000LL * 99999, &err) == ELFM_ERR_INVALID);
  CHECK_EQ_INT(u.n, 1);
  CHECK_EQ_INT(u.last_frame, 99999);
  elfm_frame_times_free(&u);
  elfm_frame_times_free(&ft);
  elfm_frame_times_free(&ft); /* twice is harmless */
}

/* A static bead seen in frames 0, 1, 6, 7, 8 of the times above (pulses):
 * the smoothed span's gap frames 2-5 must carry the recorded times, and a
 * bead moving at constant velocity must be placed on its line at them. */
static void test_smooth_gap_times(void)
{
  elfm_error err;
  elfm_frame_times ft;
  elfm_frame_times_init(&ft);
  for (int f = 0; f < 12; f++) CHECK_OK(elfm_frame_times_add(&ft, f, T0 + times[f], &err), &err);
  const int seen[5] = {0, 1, 6, 7, 8};
  for (int with = 0; with < 2; with++) {
    elfm_track *t = elfm_track_create(1, &err);
    for (int k = 0; k < 5; k++) {
      elfm_detection d;
      memset(&d, 0, sizeof d);
      d.frame = seen[k];
      d.t_us = T0 + times[seen[k]];
      const double ms = (double)times[seen[k]] * 1e-3;
      d.x_um = 10.0 + 2.0 * ms; /* 2 um/ms */
      d.y_um = -5.0;
      d.z_um = 3.0 - 0.5 * ms;
      d.sigma_x_um = d.sigma_y_um = 0.2;
      d.sigma_z_um = 0.8;
      d.intensity = 100;
      CHECK_OK(elfm_track_append(t, &d, &err), &err);
    }
    elfm_smooth_options so;
    elfm_smooth_options_default(&so);
    so.model = ELFM_MODEL_CONST_VELOCITY;
    so.frame_times = with ? &ft : NULL;
    CHECK_OK(elfm_track_smooth(t, &so, &err), &err);
    CHECK_EQ_INT(t->n_span, 9);
    int exact = 1;
    double worst_um = 0;
    for (int f = 0; f < 9; f++) {
      exact &= t->span_t_us[f] == T0 + times[f];
      /* the position at the frame's time, from the true line */
      const double ms = (double)times[f] * 1e-3;
      worst_um = fmax(worst_um, fabs(t->pos_um[3 * f] - (10.0 + 2.0 * ms)));
    }
    if (with) {
      CHECK(exact);
      CHECK(worst_um < 1e-3);
    } else {
      /* without the times the gap frames are interpolated between 4500
       * and 9000: frame 5 at 8100, not 8300, 0.4 um off the line at
       * 2 um/ms (the case this guards) */
      CHECK(!exact);
      CHECK(worst_um > 0.3);
    }
    elfm_track_free(t);
  }
  elfm_frame_times_free(&ft);
}

/* Forgetting: a recording of 10,000 trigger edges, each opening a window
 * 1200 us after the previous one and a second 400 us later (two runs per
 * edge), while frames more than 300 behind the newest are forgotten: the
 * runs held stay bounded, the times kept are exact, the forgotten ones
 * unknown. */
static void test_forget(void)
{
  elfm_error err;
  elfm_frame_times ft;
  elfm_frame_times_init(&ft);
  size_t most = 0;
  int64_t frame = 0;
  for (int e = 0; e < 10000; e++)
    for (int k = 0; k < 2; k++, frame++) {
      CHECK_OK(elfm_frame_times_add(&ft, frame, 1000000 + 1600LL * e + 1200LL * k, &err), &err);
      elfm_frame_times_forget_before(&ft, frame - 300);
      if (ft.n > most) most = ft.n;
    }
  CHECK(most <= 2 * 301 + 2);
  int64_t t = 0;
  int ok = 1;
  for (int64_t f = frame - 300; f < frame; f++) {
    ok &= elfm_frame_times_get(&ft, f, &t);
    ok &= t == 1000000 + 1600LL * (f / 2) + 1200LL * (f % 2);
  }
  CHECK(ok);
  CHECK(!elfm_frame_times_get(&ft, 100, &t));
  /* forgetting before the first frame, or within the first run, keeps all */
  elfm_frame_times_free(&ft);
  for (int64_t f = 0; f < 10; f++) CHECK_OK(elfm_frame_times_add(&ft, f, 1000 * f, &err), &err);
  elfm_frame_times_forget_before(&ft, -5);
  elfm_frame_times_forget_before(&ft, 7);
  CHECK(ft.n == 1 && elfm_frame_times_get(&ft, 0, &t) && t == 0);
  elfm_frame_times_free(&ft);
}

int main(void)
{
  test_runs();
  test_smooth_gap_times();
  test_forget();
  return check_report();
}
