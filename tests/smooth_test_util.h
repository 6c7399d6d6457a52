/* smooth_test_util.h — what the smoother's tests share (include after
 * check.h and elfm_tracker.h): a random stream, the detections' arrays, the
 * motion kinds and the noisy tracks built on them. One test per process, so
 * the stream and the arrays are each test's own. */
#ifndef ELFM_TESTS_SMOOTH_TEST_UTIL_H
#define ELFM_TESTS_SMOOTH_TEST_UTIL_H

#include <math.h>
#include <stdint.h>
#include <string.h>

static uint64_t rng = 0x9E3779B97F4A7C15ULL;
static inline double urand(void)
{
  rng ^= rng << 13; rng ^= rng >> 7; rng ^= rng << 17;
  return (double)(rng >> 11) / 9007199254740992.0;
}
static inline double gauss(void)
{
  double u = urand() + 1e-300, v = urand();
  return sqrt(-2 * log(u)) * cos(6.283185307179586 * v);
}

enum { NMAX = 1200 };
static int64_t T[NMAX];
static double X[3 * NMAX], TRUTH[3 * NMAX];

/* motion kinds */
static inline void truth_at(int kind, double t_ms, double p[3], double v[3])
{
  switch (kind) {
  case 0: /* constant velocity */
    p[0] = 5 + 0.3 * t_ms; p[1] = -2 - 0.1 * t_ms; p[2] = 10 + 0.05 * t_ms;
    v[0] = 0.3; v[1] = -0.1; v[2] = 0.05;
    break;
  case 1: /* constant acceleration 0.002 um/ms^2 along x, 0.001 along z */
    p[0] = 0.1 * t_ms + 0.5 * 0.002 * t_ms * t_ms; p[1] = 3; p[2] = 0.5 * 0.001 * t_ms * t_ms;
    v[0] = 0.1 + 0.002 * t_ms; v[1] = 0; v[2] = 0.001 * t_ms;
    break;
  default: /* wiggle: 4 um, period 60 ms (a swimming worm's neuron) */
    p[0] = 4 * sin(6.283185307179586 * t_ms / 60); p[1] = 0.05 * t_ms;
    p[2] = 8 * cos(6.283185307179586 * t_ms / 60);
    v[0] = 4 * 6.283185307179586 / 60 * cos(6.283185307179586 * t_ms / 60); v[1] = 0.05;
    v[2] = -8 * 6.283185307179586 / 60 * sin(6.283185307179586 * t_ms / 60);
  }
}

/* n points at 1 kHz from t0, noise 0.1 um lateral, 0.4 um axial */
static inline void make(int kind, int n, int64_t t0, double sxy, double sz)
{
  for (int i = 0; i < n; i++) {
    T[i] = t0 + (int64_t)i * 1000;
    double p[3], v[3];
    truth_at(kind, i, p, v);
    memcpy(TRUTH + 3 * i, p, sizeof p);
    X[3 * i] = p[0] + sxy * gauss();
    X[3 * i + 1] = p[1] + sxy * gauss();
    X[3 * i + 2] = p[2] + sz * gauss();
  }
}

static inline double rmse_xy(const double *a, const double *b, int n)
{
  double s = 0;
  for (int i = 0; i < n; i++)
    s += pow(a[3 * i] - b[3 * i], 2) + pow(a[3 * i + 1] - b[3 * i + 1], 2);
  return sqrt(s / (2.0 * n));
}

/* A bead on a circle of 12 um at 2 um/ms, 90 frames (truth: 3 x 90), with
 * noisy points (random stream from seed). noise 0: every third point a view
 * fit with 0.3 um, the others 0.1 um; 1: each point's noise 0.1 um x its
 * fit_sd_px, drawn from 0.5-4 (tests 11b and 11c). Times from t0. */
static inline elfm_track *circle_track(int64_t id, int64_t t0, uint64_t seed, int noise, double *truth,
                                elfm_error *err)
{
  const double R = 12;
  elfm_track *t = elfm_track_create(id, err);
  if (!t) return NULL;
  rng = seed;
  for (int f = 0; f < 90; f++) {
    double th = 2.0 * f / R;
    truth[3 * f] = R * cos(th);
    truth[3 * f + 1] = R * sin(th);
    truth[3 * f + 2] = 30;
    elfm_detection d;
    memset(&d, 0, sizeof d);
    d.frame = f;
    d.t_us = t0 + 1000 * f;
    double sd;
    if (noise == 0) {
      d.view_fit = f % 3 == 1;
      sd = d.view_fit ? 0.3 : 0.1;
    } else {
      d.fit_sd_px = 0.5 + 3.5 * urand();
      sd = 0.1 * d.fit_sd_px;
    }
    d.x_um = truth[3 * f] + sd * gauss();
    d.y_um = truth[3 * f + 1] + sd * gauss();
    d.z_um = truth[3 * f + 2] + 4 * sd * gauss();
    CHECK_OK(elfm_track_append(t, &d, err), err);
  }
  return t;
}

/* A bead circling at 3 um/ms (radius 10 um, 0.3 rad per frame) and rising
 * 0.5 um per frame, 100 frames from t0, with independent errors of 0.3 um
 * laterally and 1.2 um in z (random stream rng): T, TRUTH, X (tests 9c, 9d). */
static inline void noisy_helix(int64_t t0)
{
  for (int i = 0; i < 100; i++) {
    T[i] = t0 + (int64_t)i * 1000;
    TRUTH[3 * i] = 10 * cos(0.3 * i);
    TRUTH[3 * i + 1] = 10 * sin(0.3 * i);
    TRUTH[3 * i + 2] = 0.5 * i;
    for (int a = 0; a < 3; a++) X[3 * i + a] = TRUTH[3 * i + a] + (a < 2 ? 0.3 : 1.2) * gauss();
  }
}

#endif
