/* test_smooth_timescale.c — the smoothing spline on frames closer than a
 * millisecond: GCV's grid and the weight's bounds move with the states'
 * spacing (elfm_spline_lambda_unit), so that a track at 1 us per frame is
 * fitted as the same track at 1 ms per frame, and not as a straight line,
 * nor left unfitted. Why: `track --stride-us 1` (windows 1 us apart) ended
 * with "smooth: no model could be fitted" after 24 s: the grid's smallest
 * weight was 10^15 times stiffer there than at 1 kHz, beyond what the banded
 * factorisation holds (docs/tracker.md "Frames microseconds apart"). */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "check.h"
#include "elfm_tracker.h"
#include "smooth_banded.h"

#include "smooth_test_util.h"

enum { N = 160 };

/* A bead circling at 3 um/ms on a radius of 15 um (0.2 rad/ms) while it
 * drifts in z, seen every `step_us`, its time scaled so that the path is
 * the same per frame: frame k at k x step_us, the circle's angle 0.2 k. */
static void circle(int64_t t0_us, int64_t step_us, int64_t *t, double *x, double *truth)
{
  rng = 0x9E3779B97F4A7C15ULL; /* the same noise for every step */
  for (int k = 0; k < N; k++) {
    const double a = 0.2 * k;
    const double p[3] = {15 * cos(a), 15 * sin(a), 0.05 * k};
    t[k] = t0_us + step_us * k;
    for (int j = 0; j < 3; j++) {
      truth[3 * k + j] = p[j];
      x[3 * k + j] = p[j] + (j == 2 ? 0.4 : 0.1) * gauss();
    }
  }
}

static double rmse(const double *a, const double *b)
{
  double s = 0;
  for (int i = 0; i < 3 * N; i++) s += (a[i] - b[i]) * (a[i] - b[i]);
  return sqrt(s / (3 * N));
}

int main(void)
{
  elfm_error err;
  elfm_error_clear(&err);

  /* 1. The unit: the median spacing's power of ten, to the prior's power
   * 2 order - 1; 1 from 0.32 to 3.2 ms, so 1 kHz, 500 Hz and half strides
   * keep the grid they had. */
  {
    double ts[8];
    const double steps[] = {1, 0.5, 2, 3, 0.2, 0.001, 10, 0.0001};
    const double want3[] = {1, 1, 1, 1, 1e-5, 1e-15, 1e5, 1e-20};
    for (int s = 0; s < 8; s++) {
      for (int k = 0; k < 8; k++) ts[k] = -3.5 * steps[s] + k * steps[s];
      const double u3 = elfm_spline_lambda_unit(ts, 8, 3), u2 = elfm_spline_lambda_unit(ts, 8, 2);
      CHECK_MSG(fabs(u3 / want3[s] - 1) < 1e-12, "step %g ms: unit %g, want %g", steps[s], u3,
                want3[s]);
      CHECK_MSG(fabs(u2 / pow(want3[s], 0.6) - 1) < 1e-9, "order 2, step %g ms: unit %g",
                steps[s], u2);
    }
    /* the median, not the mean: frames 1 us apart across a gap of a second */
    for (int k = 0; k < 8; k++) ts[k] = k < 4 ? 0.001 * k : 1000 + 0.001 * k;
    CHECK(fabs(elfm_spline_lambda_unit(ts, 8, 3) / 1e-15 - 1) < 1e-12);
    /* nothing to measure: 1 */
    CHECK(elfm_spline_lambda_unit(ts, 1, 3) == 1);
    CHECK(elfm_spline_lambda_unit(ts, 0, 3) == 1);
  }

  /* 2. The same circle at 1 ms and at 1 us per frame (and at 10 ms): the
   * weight scales by the step^5, the positions and the effective
   * parameters are the same, the velocities scale by the step. With a
   * jerk prior (order 3) and the circle's own prior (omega), with IRLS
   * alone and with Ceres's polish, as track's three fits are. Without the
   * unit (elfm_spline_lambda_unit returning 1) 29 of these checks fail: at
   * 1 us the IRLS fit fails ("no model could be fitted"), Ceres's ends 15
   * um from the 1 ms fit (edf 0), the circle's prior's at edf 3.0 against
   * 13.1; at 10 ms the grid's top (10^8) held the circle's prior's weight
   * at a tenth of the 1 ms fit's, scaled. */
  {
    static int64_t t[N];
    static double x[3 * N], truth[3 * N];
    static double pos[3][3 * N], vel[3][3 * N];
    const int64_t steps[3] = {1000, 1, 10000};
    for (int variant = 0; variant < 3; variant++) {
      elfm_smooth_info info[3];
      for (int s = 0; s < 3; s++) {
        circle(1000000000000LL, steps[s], t, x, truth);
        elfm_smooth_options o;
        elfm_smooth_options_default(&o);
        o.model = ELFM_MODEL_SPLINE;
        o.spline_order = 3;
        o.gcv_gamma = 1.6;
        o.loss = ELFM_LOSS_CAUCHY;
        o.irls_only = variant != 1;
        /* rad per ms: the same turn per frame */
        o.spline_omega_rad_per_ms = variant == 2 ? 0.2 * 1000.0 / (double)steps[s] : 0;
        CHECK_OK(elfm_smooth_fit(&o, N, t, x, NULL, N, t, pos[s], vel[s], NULL, NULL, &info[s], &err),
                 &err);
        CHECK_EQ_INT(info[s].model, ELFM_MODEL_SPLINE);
      }
      const double e0 = rmse(pos[0], truth);
      CHECK_MSG(e0 < 0.2, "variant %d: 1 ms per frame, RMSE %g um", variant, e0);
      CHECK_MSG(info[0].edf > 4, "variant %d: edf %g: the turn is followed", variant, info[0].edf);
      for (int s = 1; s < 3; s++) {
        const double r = (double)steps[s] / 1000.0; /* ms per frame */
        CHECK_MSG(fabs(info[s].spline_weight_ms3 / (info[0].spline_weight_ms3 * pow(r, 5)) - 1) < 1e-6,
                  "variant %d, step %lld us: weight %g against %g x %g", variant,
                  (long long)steps[s], info[s].spline_weight_ms3, info[0].spline_weight_ms3,
                  pow(r, 5));
        CHECK_MSG(fabs(info[s].edf - info[0].edf) < 1e-4 * info[0].edf,
                  "variant %d, step %lld us: edf %g against %g", variant, (long long)steps[s],
                  info[s].edf, info[0].edf);
        double dp = 0, dv = 0;
        for (int i = 0; i < 3 * N; i++) {
          dp = fmax(dp, fabs(pos[s][i] - pos[0][i]));
          dv = fmax(dv, fabs(vel[s][i] * r - vel[0][i]));
        }
        CHECK_MSG(dp < 1e-4, "variant %d, step %lld us: positions differ by %g um", variant,
                  (long long)steps[s], dp);
        CHECK_MSG(dv < 1e-4, "variant %d, step %lld us: velocities differ by %g um per frame",
                  variant, (long long)steps[s], dv);
      }
    }
  }
  return check_report();
}
