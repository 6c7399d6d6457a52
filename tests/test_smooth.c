/* test_smooth.c — the Ceres smoother: model choice (constant velocity,
 * constant acceleration, spline), robust loss against outliers, uncertainty,
 * and the numerical-stability cases of issue 5 (1-3 points, gaps, repeated
 * times, times near 1e12 us, offsets, static/collinear, extreme weights,
 * NaN/inf). */
#include <stdlib.h>
#include <string.h>

#include "check.h"
#include "elfm_tracker.h"

static uint64_t rng = 0x9E3779B97F4A7C15ULL;
static double urand(void)
{
  rng ^= rng << 13; rng ^= rng >> 7; rng ^= rng << 17;
  return (double)(rng >> 11) / 9007199254740992.0;
}
static double gauss(void)
{
  double u = urand() + 1e-300, v = urand();
  return sqrt(-2 * log(u)) * cos(6.283185307179586 * v);
}

enum { NMAX = 1200 };
static int64_t T[NMAX], Q[NMAX];
static double X[3 * NMAX], TRUTH[3 * NMAX], P[3 * NMAX], V[3 * NMAX], PS[3 * NMAX], VS[3 * NMAX];

/* motion kinds */
static void truth_at(int kind, double t_ms, double p[3], double v[3])
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
static void make(int kind, int n, int64_t t0, double sxy, double sz)
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

static double rmse_xy(const double *a, const double *b, int n)
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
static elfm_track *circle_track(int64_t id, int64_t t0, uint64_t seed, int noise, double *truth,
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
static void noisy_helix(int64_t t0)
{
  for (int i = 0; i < 100; i++) {
    T[i] = t0 + (int64_t)i * 1000;
    TRUTH[3 * i] = 10 * cos(0.3 * i);
    TRUTH[3 * i + 1] = 10 * sin(0.3 * i);
    TRUTH[3 * i + 2] = 0.5 * i;
    for (int a = 0; a < 3; a++) X[3 * i + a] = TRUTH[3 * i + a] + (a < 2 ? 0.3 : 1.2) * gauss();
  }
}

int main(void)
{
  elfm_error err;
  elfm_error_clear(&err);
  elfm_smooth_options o;
  elfm_smooth_options_default(&o);
  elfm_smooth_info info;
  const int64_t T0 = 1000000000000LL;

  /* 1. Constant velocity with 4 gross outliers: CV chosen, outliers flagged,
   * velocity accurate, smoothed error well below the raw noise. */
  make(0, 300, T0, 0.1, 0.4);
  for (int k = 0; k < 4; k++) X[3 * (40 + 60 * k)] += 6.0;
  CHECK_OK(elfm_smooth_fit(&o, 300, T, X, NULL, 300, T, P, V, PS, VS, &info, &err), &err);
  CHECK_EQ_INT(info.model, ELFM_MODEL_CONST_VELOCITY);
  CHECK(info.n_outliers >= 4 && info.n_outliers <= 10);
  CHECK_NEAR(V[0], 0.3, 0.005);
  CHECK_NEAR(V[1], -0.1, 0.005);
  CHECK_NEAR(V[2], 0.05, 0.02);
  CHECK_NEAR(info.sigma_um[0], 0.1, 0.03);   /* estimated noise */
  CHECK_NEAR(info.sigma_um[2], 0.4, 0.1);
  CHECK(rmse_xy(P, TRUTH, 300) < 0.04);
  CHECK(PS[0] > 0 && PS[0] < 0.05 && VS[0] > 0 && VS[0] < 0.01);
  /* without the robust loss the outliers pull the fit: a worse x error */
  {
    elfm_smooth_options on = o;
    on.loss = ELFM_LOSS_NONE;
    on.model = ELFM_MODEL_CONST_VELOCITY;
    double P2[3 * 300];
    CHECK_OK(elfm_smooth_fit(&on, 300, T, X, NULL, 300, T, P2, NULL, NULL, NULL, NULL, &err), &err);
    CHECK_MSG(rmse_xy(P2, TRUTH, 300) > 1.5 * rmse_xy(P, TRUTH, 300), "plain %g robust %g",
              rmse_xy(P2, TRUTH, 300), rmse_xy(P, TRUTH, 300));
    on.loss = ELFM_LOSS_CAUCHY;
    elfm_smooth_info ci;
    CHECK_OK(elfm_smooth_fit(&on, 300, T, X, NULL, 300, T, P2, NULL, NULL, NULL, &ci, &err), &err);
    CHECK(rmse_xy(P2, TRUTH, 300) < 0.04);
    /* an outlier is a point beyond twice the loss scale for either loss:
     * the 4 moved points and at most a few of the noise's tail. Counted
     * by Cauchy's weight (below 1/2 from one scale on) it was 3 x more,
     * and the outlier rule dropped whole tracks */
    CHECK_MSG(ci.n_outliers >= 4 && ci.n_outliers <= info.n_outliers + 1, "cauchy %d huber %d",
              ci.n_outliers, info.n_outliers);
  }

  /* 2. Constant acceleration: CA chosen, acceleration within 5 %. */
  make(1, 400, T0, 0.1, 0.4);
  CHECK_OK(elfm_smooth_fit(&o, 400, T, X, NULL, 400, T, P, V, PS, VS, &info, &err), &err);
  CHECK_EQ_INT(info.model, ELFM_MODEL_CONST_ACCEL);
  CHECK_NEAR(info.accel_um_per_ms2[0], 0.002, 0.0001);
  CHECK_NEAR(info.accel_um_per_ms2[2], 0.001, 0.0002);
  CHECK(isfinite(info.bic[ELFM_MODEL_CONST_VELOCITY]) &&
        info.bic[ELFM_MODEL_CONST_VELOCITY] > info.bic[ELFM_MODEL_CONST_ACCEL]);

  /* 3. Wiggle: the spline is chosen, with a data-chosen weight, and beats
   * the raw positions. */
  make(2, 300, T0, 0.1, 0.4);
  CHECK_OK(elfm_smooth_fit(&o, 300, T, X, NULL, 300, T, P, V, PS, VS, &info, &err), &err);
  CHECK_EQ_INT(info.model, ELFM_MODEL_SPLINE);
  CHECK(info.spline_weight_ms3 > 0 && info.edf > 3);
  double raw_rmse = rmse_xy(X, TRUTH, 300), sm_rmse = rmse_xy(P, TRUTH, 300);
  CHECK_MSG(sm_rmse < 0.6 * raw_rmse, "smoothed %g raw %g", sm_rmse, raw_rmse);
  {
    double ve = 0;
    for (int i = 5; i < 295; i++) {
      double p[3], v[3];
      truth_at(2, i, p, v);
      ve += pow(V[3 * i] - v[0], 2);
    }
    CHECK_MSG(sqrt(ve / 290) < 0.05, "velocity rmse %g (peak speed 0.42 um/ms)", sqrt(ve / 290));
  }
  /* sparse and dense solvers agree */
  {
    elfm_smooth_options od = o;
    od.model = ELFM_MODEL_SPLINE;
    od.spline_weight_ms3 = info.spline_weight_ms3;
    od.solver = ELFM_SOLVER_DENSE;
    double P2[3 * 300], P3[3 * 300];
    CHECK_OK(elfm_smooth_fit(&od, 300, T, X, NULL, 300, T, P2, NULL, NULL, NULL, NULL, &err), &err);
    od.solver = ELFM_SOLVER_SPARSE;
    CHECK_OK(elfm_smooth_fit(&od, 300, T, X, NULL, 300, T, P3, NULL, NULL, NULL, NULL, &err), &err);
    double md = 0;
    for (int i = 0; i < 900; i++) md = fmax(md, fabs(P2[i] - P3[i]));
    CHECK_MSG(md < 1e-4, "dense vs sparse %g", md);
  }

  /* 4. Offsets: the same track at t ~ 0 vs ~1e12 us, and shifted by
   * (1e4, -3e3, 500) um, gives the same answer. */
  {
    make(2, 200, 0, 0.1, 0.4);
    double P0[3 * 200], V0[3 * 200], X2[3 * 200];
    elfm_smooth_info i0, i1;
    CHECK_OK(elfm_smooth_fit(&o, 200, T, X, NULL, 200, T, P0, V0, NULL, NULL, &i0, &err), &err);
    int64_t T2[200];
    for (int i = 0; i < 200; i++) {
      T2[i] = T[i] + 999999999999LL;
      X2[3 * i] = X[3 * i] + 1e4;
      X2[3 * i + 1] = X[3 * i + 1] - 3e3;
      X2[3 * i + 2] = X[3 * i + 2] + 500;
    }
    CHECK_OK(elfm_smooth_fit(&o, 200, T2, X2, NULL, 200, T2, P, V, NULL, NULL, &i1, &err), &err);
    CHECK_EQ_INT(i0.model, i1.model);
    double dp = 0, dv = 0;
    for (int i = 0; i < 200; i++) {
      dp = fmax(dp, fabs(P[3 * i] - 1e4 - P0[3 * i]));
      dp = fmax(dp, fabs(P[3 * i + 1] + 3e3 - P0[3 * i + 1]));
      dp = fmax(dp, fabs(P[3 * i + 2] - 500 - P0[3 * i + 2]));
      for (int a = 0; a < 3; a++) dv = fmax(dv, fabs(V[3 * i + a] - V0[3 * i + a]));
    }
    CHECK_MSG(dp < 1e-6 && dv < 1e-6, "offset changed the result: %g um, %g um/ms", dp, dv);
  }

  /* 5. Tracks of 1, 2 and 3 points. */
  {
    int64_t t1[3] = {T0, T0 + 1000, T0 + 2000};
    double x1[9] = {1, 2, 3, 2, 2, 7, 3, 2, 11};
    CHECK_OK(elfm_smooth_fit(&o, 1, t1, x1, NULL, 1, t1, P, V, PS, VS, &info, &err), &err);
    CHECK_EQ_INT(info.model, ELFM_MODEL_STATIC);
    CHECK(P[0] == 1 && P[1] == 2 && P[2] == 3 && V[0] == 0 && isnan(VS[0]) && PS[0] > 0);
    CHECK_OK(elfm_smooth_fit(&o, 2, t1, x1, NULL, 3, t1, P, V, PS, VS, &info, &err), &err);
    CHECK_EQ_INT(info.model, ELFM_MODEL_CONST_VELOCITY);
    CHECK_NEAR(V[0], 1.0, 1e-6);
    CHECK_NEAR(V[2], 4.0, 1e-6);
    CHECK_NEAR(P[6], 3.0, 1e-6);  /* extrapolated to the third time */
    CHECK_OK(elfm_smooth_fit(&o, 3, t1, x1, NULL, 3, t1, P, V, PS, VS, &info, &err), &err);
    CHECK(info.model == ELFM_MODEL_CONST_VELOCITY || info.model == ELFM_MODEL_CONST_ACCEL);
    for (int i = 0; i < 9; i++) CHECK(isfinite(P[i]) && isfinite(V[i]));
    o.model = ELFM_MODEL_SPLINE;  /* asked for, but 3 points cannot carry it */
    CHECK_OK(elfm_smooth_fit(&o, 3, t1, x1, NULL, 3, t1, P, V, PS, VS, &info, &err), &err);
    CHECK(info.model != ELFM_MODEL_SPLINE);
    o.model = ELFM_MODEL_AUTO;
  }

  /* 6. Gaps: a constant-velocity bead dark for 40 of 120 frames; the
   * spline (forced) and the chosen model fill the gap on the line. */
  {
    make(0, 120, T0, 0.1, 0.4);
    int64_t td[120];
    double xd[360];
    int n = 0;
    for (int i = 0; i < 120; i++) {
      if (i >= 40 && i < 80) continue;
      td[n] = T[i];
      memcpy(xd + 3 * n, X + 3 * i, sizeof(double) * 3);
      n++;
    }
    for (int pass = 0; pass < 2; pass++) {
      elfm_smooth_options og = o;
      if (pass) og.model = ELFM_MODEL_SPLINE;
      CHECK_OK(elfm_smooth_fit(&og, (size_t)n, td, xd, NULL, 120, T, P, V, PS, VS, &info, &err), &err);
      CHECK_MSG(fabs(P[3 * 60] - TRUTH[3 * 60]) < 0.2, "gap fill %g vs %g", P[3 * 60], TRUTH[3 * 60]);
      /* less certain inside the gap than with the frames present */
      double PSg = PS[3 * 60], PSfull[360];
      og.model = info.model;
      og.spline_weight_ms3 = info.spline_weight_ms3;
      CHECK_OK(elfm_smooth_fit(&og, 120, T, X, NULL, 120, T, P, V, PSfull, VS, &info, &err), &err);
      CHECK_MSG(PSg > PSfull[3 * 60], "gap sd %g vs full %g", PSg, PSfull[3 * 60]);
    }
  }

  /* 7. Repeated timestamps (two detections in one frame). */
  {
    make(0, 60, T0, 0.1, 0.4);
    int64_t tr[61];
    double xr[183];
    memcpy(tr, T, sizeof(int64_t) * 30);
    memcpy(xr, X, sizeof(double) * 90);
    tr[30] = T[29];
    xr[90] = X[87] + 0.05; xr[91] = X[88]; xr[92] = X[89];
    memcpy(tr + 31, T + 30, sizeof(int64_t) * 30);
    memcpy(xr + 93, X + 90, sizeof(double) * 90);
    for (int m = ELFM_MODEL_AUTO; m <= ELFM_MODEL_SPLINE; m++) {
      elfm_smooth_options orp = o;
      orp.model = (elfm_motion_model)m;
      CHECK_OK(elfm_smooth_fit(&orp, 61, tr, xr, NULL, 60, T, P, V, PS, VS, &info, &err), &err);
      int finite = 1;
      for (int i = 0; i < 180; i++) finite &= isfinite(P[i]) && isfinite(V[i]);
      CHECK(finite);
      CHECK_NEAR(V[3 * 30], 0.3, 0.03);
    }
    /* all points at one time: static */
    int64_t ts[3] = {T0, T0, T0};
    double xs[9] = {1, 1, 1, 2, 2, 2, 3, 3, 3};
    CHECK_OK(elfm_smooth_fit(&o, 3, ts, xs, NULL, 1, ts, P, V, PS, VS, &info, &err), &err);
    CHECK_EQ_INT(info.model, ELFM_MODEL_STATIC);
    CHECK_NEAR(P[0], 2, 1e-12);
  }

  /* 8. Static and collinear tracks. */
  {
    for (int i = 0; i < 100; i++) {
      T[i] = T0 + i * 1000;
      X[3 * i] = 7 + 0.1 * gauss();
      X[3 * i + 1] = -3 + 0.1 * gauss();
      X[3 * i + 2] = 20 + 0.4 * gauss();
    }
    CHECK_OK(elfm_smooth_fit(&o, 100, T, X, NULL, 100, T, P, V, PS, VS, &info, &err), &err);
    CHECK_EQ_INT(info.model, ELFM_MODEL_CONST_VELOCITY);
    CHECK_NEAR(V[0], 0, 0.002);
    CHECK_NEAR(P[3 * 50], 7, 0.03);
    /* exactly collinear, noiseless (noise floor applies) */
    for (int i = 0; i < 100; i++) {
      X[3 * i] = 0.2 * i;
      X[3 * i + 1] = 0.2 * i;
      X[3 * i + 2] = 0.2 * i;
    }
    CHECK_OK(elfm_smooth_fit(&o, 100, T, X, NULL, 100, T, P, V, PS, VS, &info, &err), &err);
    CHECK_NEAR(V[3 * 50 + 2], 0.2, 1e-6);
    CHECK_NEAR(P[3 * 99], 19.8, 1e-6);
  }

  /* 9. Extreme spline weights: 1e-12 interpolates, 1e12 is the straight line. */
  {
    make(2, 100, T0, 0.1, 0.4);
    elfm_smooth_options oe = o;
    oe.model = ELFM_MODEL_SPLINE;
    oe.loss = ELFM_LOSS_NONE;
    oe.spline_weight_ms3 = 1e-12;
    CHECK_OK(elfm_smooth_fit(&oe, 100, T, X, NULL, 100, T, P, V, PS, VS, &info, &err), &err);
    double md = 0;
    for (int i = 0; i < 300; i++) md = fmax(md, fabs(P[i] - X[i]));
    CHECK_MSG(md < 0.01, "interpolation error %g", md);
    oe.spline_weight_ms3 = 1e12;
    CHECK_OK(elfm_smooth_fit(&oe, 100, T, X, NULL, 100, T, P, V, PS, VS, &info, &err), &err);
    double Pl[300];
    elfm_smooth_options ol = oe;
    ol.model = ELFM_MODEL_CONST_VELOCITY;
    CHECK_OK(elfm_smooth_fit(&ol, 100, T, X, NULL, 100, T, Pl, NULL, NULL, NULL, NULL, &err), &err);
    md = 0;
    for (int i = 0; i < 300; i++) md = fmax(md, fabs(P[i] - Pl[i]));
    CHECK_MSG(md < 0.05, "heavy spline vs line %g", md);
    for (int i = 0; i < 300; i++) CHECK(isfinite(PS[i]) && isfinite(VS[i]));
  }

  /* 9b. GCV's price per effective parameter (gcv_gamma). A bead circling
   * at 3 um/ms (radius 10 um, the flow scene's turn of ~17 degrees per ms),
   * 100 frames, 16 tracks. With errors correlated from frame to frame as
   * the flow scene's detections are (AR(1), rho 0.55: their measured lag-1
   * autocorrelation is 0.54-0.58 laterally, 0.38 in z; 0.3 um marginal)
   * classical GCV (gamma 1) follows part of the errors and gamma 1.4 does
   * better; with independent errors of the same size gamma 1 is the better
   * one (why the library default stays 1 and `eventlfm track` sets 1.4).
   * Gamma below 1 or not finite is an error. */
  {
    const int n = 100, ntr = 16;
    rng = 22;  /* same gains with seeds 11, 33, 44, 55: 4-7 % and 25-35 % */
    double e_corr[2] = {0, 0}, e_iid[2] = {0, 0}, lam_c[2] = {0, 0};
    for (int corr = 0; corr <= 1; corr++)
      for (int k = 0; k < ntr; k++) {
        double ex = 0, ey = 0, ez = 0;
        for (int i = 0; i < n; i++) {
          const double th = 0.3 * i;
          T[i] = T0 + (int64_t)i * 1000;
          TRUTH[3 * i] = 10 * cos(th);
          TRUTH[3 * i + 1] = 10 * sin(th);
          TRUTH[3 * i + 2] = 0.5 * i;
          const double rho = corr ? 0.55 : 0, g = sqrt(1 - rho * rho);
          ex = (i ? rho * ex : 0) + (i ? g : 1) * 0.3 * gauss();
          ey = (i ? rho * ey : 0) + (i ? g : 1) * 0.3 * gauss();
          ez = (i ? rho * ez : 0) + (i ? g : 1) * 1.2 * gauss();
          X[3 * i] = TRUTH[3 * i] + ex;
          X[3 * i + 1] = TRUTH[3 * i + 1] + ey;
          X[3 * i + 2] = TRUTH[3 * i + 2] + ez;
        }
        for (int gi = 0; gi < 2; gi++) {
          elfm_smooth_options og = o;
          og.model = ELFM_MODEL_SPLINE;
          og.gcv_gamma = gi ? 1.4 : 1.0;
          CHECK_OK(elfm_smooth_fit(&og, n, T, X, NULL, n, T, P, NULL, NULL, NULL, &info, &err), &err);
          const double e = rmse_xy(P, TRUTH, n) / ntr;
          if (corr) {
            e_corr[gi] += e;
            lam_c[gi] += log10(info.spline_weight_ms3) / ntr;
          } else {
            e_iid[gi] += e;
          }
        }
      }
    CHECK_MSG(e_corr[1] < e_corr[0], "correlated errors: gamma 1 %.4f, 1.4 %.4f um",
              e_corr[0], e_corr[1]);
    CHECK_MSG(lam_c[1] > lam_c[0], "mean log10 lambda: gamma 1 %.2f, 1.4 %.2f", lam_c[0], lam_c[1]);
    CHECK_MSG(e_iid[0] < e_iid[1], "independent errors: gamma 1 %.4f, 1.4 %.4f um", e_iid[0],
              e_iid[1]);
    elfm_smooth_options og = o;
    og.gcv_gamma = 0.9;
    CHECK_EQ_INT(elfm_smooth_fit(&og, n, T, X, NULL, n, T, P, NULL, NULL, NULL, NULL, &err),
                 ELFM_ERR_INVALID);
    og.gcv_gamma = NAN;
    CHECK_EQ_INT(elfm_smooth_fit(&og, n, T, X, NULL, n, T, P, NULL, NULL, NULL, NULL, &err),
                 ELFM_ERR_INVALID);
    printf("9b: correlated errors gamma 1 / 1.4: %.4f / %.4f um; independent %.4f / %.4f um\n",
           e_corr[0], e_corr[1], e_iid[0], e_iid[1]);
  }

  /* 9c. The jerk penalty (spline_order 3). (i) Its stiff limit is a
   * constant acceleration: on a track with one (0.002 um/ms^2 along x),
   * lambda 1e9 (the largest taken) gives the constant-acceleration model's
   * positions (measured: within 0.002-0.007 um) and, through the heptadiagonal
   * selected inverse, its position sd (within 2 %; at 1e7 / 1e8 35 % / 13 %:
   * the limit is approached as lambda grows), where the acceleration
   * penalty's limit is a line, the constant-velocity model (within 0.001 um). (ii) A bead circling at
   * 3 um/ms (radius 10 um, 0.3 rad per frame), independent 0.3 um errors,
   * 16 tracks, lambda by GCV: the jerk penalty leaves the turn alone and
   * places the bead closer than the acceleration penalty, which pulls it
   * inside its circle. (iii) Other orders are an error. */
  {
    const int n = 120;
    make(1, n, T0, 0.1, 0.4);
    elfm_smooth_options oj = o;
    oj.model = ELFM_MODEL_SPLINE;
    oj.spline_order = 3;
    oj.spline_weight_ms3 = 1e9;
    oj.loss = ELFM_LOSS_NONE;
    double Pj[3 * 120], PSj[3 * 120], Pc[3 * 120], PSc[3 * 120], Pa[3 * 120], Pv[3 * 120];
    CHECK_OK(elfm_smooth_fit(&oj, n, T, X, NULL, n, T, Pj, NULL, PSj, NULL, &info, &err), &err);
    CHECK_EQ_INT(info.model, ELFM_MODEL_SPLINE);
    elfm_smooth_options oc = oj;
    oc.model = ELFM_MODEL_CONST_ACCEL;
    CHECK_OK(elfm_smooth_fit(&oc, n, T, X, NULL, n, T, Pc, NULL, PSc, NULL, &info, &err), &err);
    elfm_smooth_options oa = oj;
    oa.spline_order = 2;
    CHECK_OK(elfm_smooth_fit(&oa, n, T, X, NULL, n, T, Pa, NULL, NULL, NULL, &info, &err), &err);
    elfm_smooth_options ov = oj;
    ov.model = ELFM_MODEL_CONST_VELOCITY;
    CHECK_OK(elfm_smooth_fit(&ov, n, T, X, NULL, n, T, Pv, NULL, NULL, NULL, &info, &err), &err);
    double dmax = 0, smax = 0, vmax = 0;
    for (int i = 0; i < 3 * n; i++) {
      dmax = fmax(dmax, fabs(Pj[i] - Pc[i]));
      smax = fmax(smax, fabs(PSj[i] - PSc[i]) / PSc[i]);
      vmax = fmax(vmax, fabs(Pa[i] - Pv[i]));
    }
    CHECK_MSG(dmax < 0.02, "stiff jerk spline vs constant acceleration: %.4f um", dmax);
    CHECK_MSG(smax < 0.05, "position sd: relative difference %.4f", smax);
    CHECK_MSG(vmax < 0.005, "stiff acceleration spline vs constant velocity: %.4f um", vmax);
    CHECK_MSG(rmse_xy(Pa, TRUTH, n) > 2 * rmse_xy(Pj, TRUTH, n), "stiff limits: line %.4f, "
              "constant acceleration %.4f um", rmse_xy(Pa, TRUTH, n), rmse_xy(Pj, TRUTH, n));

    double e_ord[2] = {0, 0};
    rng = 33;
    for (int k = 0; k < 16; k++) {
      noisy_helix(T0);
      for (int ord = 2; ord <= 3; ord++) {
        elfm_smooth_options og = o;
        og.model = ELFM_MODEL_SPLINE;
        og.spline_order = ord;
        CHECK_OK(elfm_smooth_fit(&og, 100, T, X, NULL, 100, T, P, NULL, NULL, NULL, &info, &err), &err);
        e_ord[ord - 2] += rmse_xy(P, TRUTH, 100) / 16;
      }
    }
    CHECK_MSG(e_ord[1] < 0.95 * e_ord[0], "circle: acceleration penalty %.4f, jerk %.4f um",
              e_ord[0], e_ord[1]);
    printf("9c: circle, GCV: acceleration penalty %.4f um, jerk penalty %.4f um\n", e_ord[0],
           e_ord[1]);
    elfm_smooth_options ob = o;
    ob.spline_order = 4;
    CHECK_EQ_INT(elfm_smooth_fit(&ob, 100, T, X, NULL, 100, T, P, NULL, NULL, NULL, NULL, &err),
                 ELFM_ERR_INVALID);
    ob.spline_order = 1;
    CHECK_EQ_INT(elfm_smooth_fit(&ob, 100, T, X, NULL, 100, T, P, NULL, NULL, NULL, NULL, &err),
                 ELFM_ERR_INVALID);
  }

  /* 9d. The prior along the turn (spline_omega_rad_per_ms,
   * spline_turn). (i) The 16 circling tracks of 9c (0.3 rad per frame,
   * rising 0.5 um per frame), GCV each time: the prior that leaves a circle
   * at 0.3 rad/ms alone places them closer than the jerk prior. (ii)
   * elfm_track_smooth with spline_turn finds the turn rate of circle_track
   * (2 um/ms on 12 um: 1/6 rad/ms) from its first fit, reports it, and
   * places the bead closer than without (measured: 0.1085 against 0.1610
   * um; 0.0722 against 0.1021 um, rate 0.1668 rad/ms). (iii) A negative or non-finite
   * rate is an error. */
  {
    double e_turn[2] = {0, 0};
    rng = 33;
    for (int k = 0; k < 16; k++) {
      noisy_helix(T0);
      for (int w = 0; w < 2; w++) {
        elfm_smooth_options og = o;
        og.model = ELFM_MODEL_SPLINE;
        og.spline_order = 3;
        og.spline_omega_rad_per_ms = w ? 0.3 : 0;
        CHECK_OK(elfm_smooth_fit(&og, 100, T, X, NULL, 100, T, P, NULL, NULL, NULL, &info, &err), &err);
        e_turn[w] += rmse_xy(P, TRUTH, 100) / 16;
      }
    }
    printf("9d: circle, GCV: jerk prior %.4f um, with the turn rate %.4f um\n", e_turn[0], e_turn[1]);
    CHECK_MSG(e_turn[1] < 0.9 * e_turn[0], "circle: jerk %.4f, turn %.4f um", e_turn[0], e_turn[1]);

    double e_tr[2] = {0, 0}, rate = 0;
    for (int k = 0; k < 8; k++) {
      for (int w = 0; w < 2; w++) {
        double truth[3 * 90];
        elfm_track *t = circle_track(70 + k, T0, 500 + (uint64_t)k, 1, truth, &err);
        CHECK(t != NULL);
        if (!t) continue;
        elfm_smooth_options ot = o;
        ot.spline_order = 3;
        ot.spline_turn = w;
        CHECK_OK(elfm_track_smooth(t, &ot, &err), &err);
        if (t->model == ELFM_MODEL_SPLINE && t->n_span == 90) {
          e_tr[w] += rmse_xy(t->pos_um, truth, 90) / 8;
          if (w) rate += t->spline_omega_rad_per_ms / 8;
          else CHECK(t->spline_omega_rad_per_ms == 0);
        } else {
          CHECK_MSG(0, "track %d: model %d, %zu rows", k, (int)t->model, t->n_span);
        }
        elfm_track_free(t);
      }
    }
    printf("9d: circle_track: jerk prior %.4f um, spline_turn %.4f um, rate %.4f rad/ms\n",
           e_tr[0], e_tr[1], rate);
    CHECK_MSG(fabs(rate - 1.0 / 6) < 0.1 / 6, "turn rate %.4f rad/ms, not 1/6", rate);
    CHECK_MSG(e_tr[1] < 0.85 * e_tr[0], "spline_turn %.4f um, without %.4f um", e_tr[1], e_tr[0]);

    elfm_smooth_options ob = o;
    ob.spline_order = 3;
    ob.spline_omega_rad_per_ms = -0.1;
    CHECK_EQ_INT(elfm_smooth_fit(&ob, 100, T, X, NULL, 100, T, P, NULL, NULL, NULL, NULL, &err),
                 ELFM_ERR_INVALID);
    ob.spline_omega_rad_per_ms = NAN;
    CHECK_EQ_INT(elfm_smooth_fit(&ob, 100, T, X, NULL, 100, T, P, NULL, NULL, NULL, NULL, &err),
                 ELFM_ERR_INVALID);
  }

  /* 10. Bad input. */
  {
    make(0, 10, T0, 0.1, 0.4);
    X[5] = NAN;
    CHECK_EQ_INT(elfm_smooth_fit(&o, 10, T, X, NULL, 10, T, P, V, PS, VS, &info, &err), ELFM_ERR_NUMERIC);
    X[5] = INFINITY;
    CHECK_EQ_INT(elfm_smooth_fit(&o, 10, T, X, NULL, 10, T, P, V, PS, VS, &info, &err), ELFM_ERR_NUMERIC);
    X[5] = 1;
    double sg[30];
    for (int i = 0; i < 30; i++) sg[i] = 0.1;
    sg[7] = 0;
    CHECK_EQ_INT(elfm_smooth_fit(&o, 10, T, X, sg, 10, T, P, V, PS, VS, &info, &err), ELFM_ERR_NUMERIC);
    sg[7] = 0.1;
    CHECK_OK(elfm_smooth_fit(&o, 10, T, X, sg, 10, T, P, V, PS, VS, &info, &err), &err);
    CHECK_NEAR(info.sigma_um[0], 0.1, 1e-12);
    int64_t tt = T[3]; T[3] = T[5]; T[5] = tt;
    CHECK_EQ_INT(elfm_smooth_fit(&o, 10, T, X, NULL, 10, Q, P, V, PS, VS, &info, &err), ELFM_ERR_INVALID);
    CHECK_EQ_INT(elfm_smooth_fit(&o, 0, T, X, NULL, 10, T, P, V, PS, VS, &info, &err), ELFM_ERR_INVALID);
  }

  /* 11. A whole track with a gap: frames first..last, raw_index -1 on gaps. */
  {
    elfm_track *t = elfm_track_create(3, &err);
    for (int f = 0; f < 60; f++) {
      if (f >= 20 && f < 30) continue;
      elfm_detection d;
      memset(&d, 0, sizeof d);
      d.frame = 100 + f;
      d.t_us = T0 + 1000 * f;
      d.x_um = 0.5 * f + 0.05 * gauss();
      d.y_um = 1;
      d.z_um = 2;
      elfm_track_append(t, &d, &err);
    }
    CHECK_OK(elfm_track_smooth(t, &o, &err), &err);
    CHECK_EQ_INT(t->n_span, 60);
    CHECK_EQ_INT(t->raw_index[25], -1);
    CHECK_EQ_INT(t->raw_index[30], 20);
    CHECK(t->span_t_us[25] == T0 + 25000);
    CHECK_NEAR(t->pos_um[3 * 25], 12.5, 0.1);
    double mv[3];
    elfm_track_mean_velocity(t, mv);
    CHECK_NEAR(mv[0], 0.5, 0.01);
    CHECK(t->model != ELFM_MODEL_AUTO);
    elfm_track_free(t);
  }

  /* 11b. View-fit points (elfm_detection.view_fit: gap filling, the guided
   * search) weighted as noisier (view_fit_sigma_factor). A bead on a circle
   * of 12 um at 2 um/ms; peaks with 0.1 um noise, every third point a view
   * fit with 0.3 um (flow: the fills are 1.5-4x the peaks' error at the
   * same depth). Weighted 1.5x the smoothed track is nearer the truth than
   * with all points alike (RMSE per axis 0.080 against 0.099 um); the noise estimate is the one the fit makes
   * itself; a factor out of range is an error. */
  {
    double truth[3 * 90];
    elfm_track *tv[2];
    for (int c = 0; c < 2; c++) tv[c] = circle_track(8 + c, T0, 0x7654321ULL, 0, truth, &err);
    elfm_smooth_options o1 = o, o15 = o;
    o1.view_fit_sigma_factor = 1;
    o15.view_fit_sigma_factor = 1.5;
    CHECK_OK(elfm_track_smooth(tv[0], &o1, &err), &err);
    CHECK_OK(elfm_track_smooth(tv[1], &o15, &err), &err);
    double e1 = rmse_xy(tv[0]->pos_um, truth, 90), e15 = rmse_xy(tv[1]->pos_um, truth, 90);
    CHECK_MSG(e15 < 0.9 * e1, "weighted %.4f um, alike %.4f um", e15, e1);
    /* the estimate is the fit's own */
    int64_t tq[90];
    double xq[3 * 90], s_est[3];
    for (int f = 0; f < 90; f++) {
      tq[f] = tv[0]->pts[f].t_us;
      xq[3 * f] = tv[0]->pts[f].x_um;
      xq[3 * f + 1] = tv[0]->pts[f].y_um;
      xq[3 * f + 2] = tv[0]->pts[f].z_um;
    }
    elfm_smooth_info inf;
    CHECK_OK(elfm_smooth_fit(&o1, 90, tq, xq, NULL, 0, NULL, NULL, NULL, NULL, NULL, &inf, &err), &err);
    CHECK_OK(elfm_smooth_estimate_noise(&o1, 90, tq, xq, s_est, &err), &err);
    for (int a = 0; a < 3; a++) CHECK_NEAR(s_est[a], inf.sigma_um[a], 1e-12);
    /* without view-fit points the factor changes nothing */
    for (int f = 0; f < 90; f++) tv[0]->pts[f].view_fit = tv[1]->pts[f].view_fit = 0;
    CHECK_OK(elfm_track_smooth(tv[0], &o1, &err), &err);
    CHECK_OK(elfm_track_smooth(tv[1], &o15, &err), &err);
    int same = 1;
    for (int i = 0; i < 3 * 90; i++) same &= tv[0]->pos_um[i] == tv[1]->pos_um[i];
    CHECK(same);
    tv[1]->pts[5].view_fit = 1;
    o15.view_fit_sigma_factor = 0;
    CHECK_EQ_INT(elfm_track_smooth(tv[1], &o15, &err), ELFM_ERR_INVALID);
    CHECK(strstr(err.message, "view-fit") != NULL);
    o15.view_fit_sigma_factor = NAN;
    CHECK_EQ_INT(elfm_track_smooth(tv[1], &o15, &err), ELFM_ERR_INVALID);
    CHECK(tv[1]->n_span == 90);
    for (int c = 0; c < 2; c++) elfm_track_free(tv[c]);
  }

  /* 11c. Each point's own view-fit scatter (elfm_detection.fit_sd_px,
   * fit_sd_power). The same circle; every point's noise is 0.1 um x its
   * fit_sd_px, which runs from 0.5 to 4 (a point whose views agreed less
   * lies further off). With power 1 the smoothed track is nearer the truth
   * than with all points alike (RMSE per axis 0.096 against 0.128 um);
   * points without a scatter (0) keep factor 1,
   * so a track with none is smoothed as before; a power out of [0, 4] is an
   * error. */
  {
    double truth[3 * 90];
    elfm_track *tw[2];
    for (int c = 0; c < 2; c++) tw[c] = circle_track(20 + c, T0, 0x1234567ULL, 1, truth, &err);
    elfm_smooth_options p0 = o, p1 = o;
    p0.fit_sd_power = 0;
    p1.fit_sd_power = 1;
    CHECK_OK(elfm_track_smooth(tw[0], &p0, &err), &err);
    CHECK_OK(elfm_track_smooth(tw[1], &p1, &err), &err);
    double e0 = rmse_xy(tw[0]->pos_um, truth, 90), e1 = rmse_xy(tw[1]->pos_um, truth, 90);
    printf("11c: scatter-weighted %.4f um, alike %.4f um\n", e1, e0);
    CHECK_MSG(e1 < 0.85 * e0, "weighted by scatter %.4f um, alike %.4f um", e1, e0);
    /* no scatter on any point: the same as off */
    for (int f = 0; f < 90; f++) tw[0]->pts[f].fit_sd_px = tw[1]->pts[f].fit_sd_px = 0;
    CHECK_OK(elfm_track_smooth(tw[0], &p0, &err), &err);
    CHECK_OK(elfm_track_smooth(tw[1], &p1, &err), &err);
    int same = 1;
    for (int i = 0; i < 3 * 90; i++) same &= tw[0]->pos_um[i] == tw[1]->pos_um[i];
    CHECK(same);
    p1.fit_sd_power = 5;
    CHECK_EQ_INT(elfm_track_smooth(tw[1], &p1, &err), ELFM_ERR_INVALID);
    CHECK(strstr(err.message, "fit_sd_power") != NULL);
    p1.fit_sd_power = NAN;
    CHECK_EQ_INT(elfm_track_smooth(tw[1], &p1, &err), ELFM_ERR_INVALID);
    for (int c = 0; c < 2; c++) elfm_track_free(tw[c]);
  }

  /* 12. Motion bias (elfm_smooth_options.motion_lead_um / motion_delay_us):
   * a bead on a circle of 12 um whose speed rises from 1 to 4 um/ms,
   * detected lead - delay x speed along its motion (0.8 um and 300 us, the
   * flow scene's ON surface), noise 0.05 um. Corrected, the smoothed track
   * is back on the circle; uncorrected it keeps the bias (0.8 - 0.3 x 2.5
   * on average, but from +0.5 to -0.4 um along the path). */
  {
    const double lead = 0.8, delay_ms = 0.3, R = 12;
    elfm_track *tb[3] = {NULL, NULL, NULL};  /* biased x 2, unbiased reference */
    double truth[3 * 80];
    for (int c = 0; c < 3; c++) {
      tb[c] = elfm_track_create(4 + c, &err);
      rng = 0x1234567ULL;
      for (int f = 0; f < 80; f++) {
        double tm = f, th = (1.0 * tm + 0.5 * (3.0 / 79) * tm * tm) / R;  /* speed 1 + 3 t / 79 */
        double sp = 1.0 + 3.0 * tm / 79, ux = -sin(th), uy = cos(th);
        truth[3 * f] = R * cos(th);
        truth[3 * f + 1] = R * sin(th);
        truth[3 * f + 2] = -40 + 0.1 * tm;
        elfm_detection d;
        memset(&d, 0, sizeof d);
        d.frame = f;
        d.t_us = T0 + 1000 * f;
        double b = c < 2 ? lead - delay_ms * sp : 0;
        d.x_um = truth[3 * f] + b * ux + 0.05 * gauss();
        d.y_um = truth[3 * f + 1] + b * uy + 0.05 * gauss();
        d.z_um = truth[3 * f + 2] + 0.2 * gauss();
        CHECK_OK(elfm_track_append(tb[c], &d, &err), &err);
      }
    }
    elfm_smooth_options ob = o;
    ob.motion_lead_um = lead;
    ob.motion_delay_us = delay_ms * 1000;
    CHECK_OK(elfm_track_smooth(tb[0], &o, &err), &err);
    CHECK_OK(elfm_track_smooth(tb[1], &ob, &err), &err);
    CHECK_OK(elfm_track_smooth(tb[2], &o, &err), &err);
    double e_off = rmse_xy(tb[0]->pos_um, truth, 80), e_on = rmse_xy(tb[1]->pos_um, truth, 80);
    double e_ref = rmse_xy(tb[2]->pos_um, truth, 80);
    /* per axis: bias 0.19 um uncorrected; corrected as good as no bias at all */
    CHECK(e_off > 0.15);
    CHECK(e_on < e_ref + 0.01);
    CHECK(e_ref < 0.06);
    /* the points stay the detections as measured */
    CHECK(tb[1]->pts[40].x_um == tb[0]->pts[40].x_um && tb[1]->pts[40].y_um == tb[0]->pts[40].y_um);
    /* z is left alone: the bias is along the lateral motion */
    double dz = 0;
    for (int f = 0; f < 80; f++) dz = fmax(dz, fabs(tb[1]->pos_um[3 * f + 2] - tb[0]->pos_um[3 * f + 2]));
    CHECK(dz < 0.05);
    /* out of range: an error, the track untouched */
    ob.motion_delay_us = 2e6;
    CHECK_EQ_INT(elfm_track_smooth(tb[1], &ob, &err), ELFM_ERR_INVALID);
    CHECK(strstr(err.message, "motion bias") != NULL);
    ob.motion_delay_us = NAN;
    CHECK_EQ_INT(elfm_track_smooth(tb[1], &ob, &err), ELFM_ERR_INVALID);
    CHECK(tb[1]->n_span == 80);
    for (int c = 0; c < 3; c++) elfm_track_free(tb[c]);

    /* A bead at rest (noise only): the lead fades out below 0.5 um/ms, so
     * the correction moves it by much less than the lead. */
    elfm_track *ts = elfm_track_create(6, &err);
    for (int f = 0; f < 50; f++) {
      elfm_detection d;
      memset(&d, 0, sizeof d);
      d.frame = f;
      d.t_us = T0 + 1000 * f;
      d.x_um = 3 + 0.05 * gauss();
      d.y_um = -2 + 0.05 * gauss();
      d.z_um = 1;
      CHECK_OK(elfm_track_append(ts, &d, &err), &err);
    }
    ob.motion_delay_us = 300;
    CHECK_OK(elfm_track_smooth(ts, &ob, &err), &err);
    double moved = 0;
    for (int f = 0; f < 50; f++) moved = fmax(moved, hypot(ts->pos_um[3 * f] - 3, ts->pos_um[3 * f + 1] + 2));
    CHECK(moved < 0.1);
    elfm_track_free(ts);

    /* The views' model (elfm_motion_bias): a 3 x 3 array of disparities
     * -0.3, 0, 0.3 um per um. Lateral motion alone: every image moves
     * alike, so the bias equals the lateral model's and z gets none. */
    elfm_smooth_options ov = ob, ol = ob;
    ov.motion_lead_um = ol.motion_lead_um = 0.8;
    ov.motion_delay_us = ol.motion_delay_us = 300;
    ol.motion_n_views = 0;
    ov.motion_n_views = 9;
    for (int k = 0; k < 9; k++) {
      ov.motion_view_g[k][0] = 0.3 * (k % 3 - 1);
      ov.motion_view_g[k][1] = 0.3 * (k / 3 - 1);
    }
    double vl[3] = {2.0, -1.0, 0}, bv[3], bl[3];
    elfm_motion_bias(&ov, vl, bv);
    elfm_motion_bias(&ol, vl, bl);
    double s5 = sqrt(5.0), f = 0.8 / s5 - 0.3;
    CHECK_NEAR(bl[0], 2 * f, 1e-12);
    CHECK_NEAR(bl[1], -f, 1e-12);
    CHECK_NEAR(bl[2], 0, 1e-12);
    for (int a = 0; a < 3; a++) CHECK_NEAR(bv[a], bl[a], 1e-12);
    /* Motion along z alone at 3 um/ms: the 8 outer images move at 0.9 or
     * 1.27 um/ms outwards, each led by 0.8 um along its own motion, which
     * the fit reads as z: dz = (0.8 sum |g| - 0.3 x 3 sum |g|^2) / sum |g|^2,
     * no lateral bias; the lateral model sees no lateral motion at all. */
    double vz[3] = {0, 0, 3};
    elfm_motion_bias(&ov, vz, bv);
    elfm_motion_bias(&ol, vz, bl);
    double sg = 4 * 0.3 + 4 * 0.3 * sqrt(2.0), sgg = 4 * 0.09 + 4 * 0.18;
    CHECK_NEAR(bv[2], (0.8 * sg - 0.9 * sgg) / sgg, 1e-9);
    CHECK_NEAR(bv[0], 0, 1e-12);
    CHECK_NEAR(bv[1], 0, 1e-12);
    CHECK(bl[0] == 0 && bl[1] == 0 && bl[2] == 0);
    /* Slow images lead further: lead + 0.17 ms x (3 um/ms - |w|) below 3
     * um/ms, nothing above; below the fade speed that fades with the lead
     * (a bead at rest is not moved). Lateral motion at sqrt(5) um/ms: lead
     * 0.8 + 0.17 (3 - sqrt 5); at 4 um/ms the line alone. */
    elfm_smooth_options os = ol;
    os.motion_slow_lead_ms = 0.17;
    os.motion_slow_um_per_ms = 3;
    elfm_motion_bias(&os, vl, bl);
    const double fs = (0.8 + 0.17 * (3 - s5)) / s5 - 0.3;
    CHECK_NEAR(bl[0], 2 * fs, 1e-12);
    CHECK_NEAR(bl[1], -fs, 1e-12);
    double v4[3] = {0, 4, 0}, b4[3], b4l[3];
    elfm_motion_bias(&os, v4, b4);
    elfm_motion_bias(&ol, v4, b4l);
    CHECK_NEAR(b4[1], b4l[1], 1e-12);
    CHECK_NEAR(b4[1], 0.8 - 1.2, 1e-12);
    double v01[3] = {0.1, 0, 0}, b01[3];
    elfm_motion_bias(&os, v01, b01); /* fade 0.5: (0.8 + 0.17 x 2.9) x 0.1 / 0.5 - 0.03 */
    CHECK_NEAR(b01[0], (0.8 + 0.17 * 2.9) * 0.2 - 0.03, 1e-12);
    /* the views' model sums each image's own bend: at 3 um/ms in z the
     * outer images move at 0.9 and 1.27 um/ms, each with its extra lead */
    elfm_smooth_options osv = ov;
    osv.motion_slow_lead_ms = 0.17;
    osv.motion_slow_um_per_ms = 3;
    elfm_motion_bias(&osv, vz, bv);
    const double g1 = 0.3, g2 = 0.3 * sqrt(2.0);
    const double sl = 4 * g1 * (0.8 + 0.17 * (3 - 3 * g1)) + 4 * g2 * (0.8 + 0.17 * (3 - 3 * g2));
    CHECK_NEAR(bv[2], (sl - 0.9 * sgg) / sgg, 1e-9);
    /* alone (lead and delay 0) it still applies; out of range is an error */
    elfm_smooth_options o0 = os;
    o0.motion_lead_um = o0.motion_delay_us = 0;
    elfm_motion_bias(&o0, v4, b4);
    CHECK(b4[1] == 0);
    elfm_motion_bias(&o0, vl, bl);
    CHECK_NEAR(bl[0], 2 * 0.17 * (3 - s5) / s5, 1e-12);
    elfm_track *tr = elfm_track_create(8, &err);
    elfm_detection dr;
    memset(&dr, 0, sizeof dr);
    CHECK_OK(elfm_track_append(tr, &dr, &err), &err);
    o0.motion_slow_lead_ms = -1;
    CHECK_EQ_INT(elfm_track_smooth(tr, &o0, &err), ELFM_ERR_INVALID);
    CHECK(strstr(err.message, "slow lead") != NULL);
    o0.motion_slow_lead_ms = 0.17;
    o0.motion_slow_um_per_ms = NAN;
    CHECK_EQ_INT(elfm_track_smooth(tr, &o0, &err), ELFM_ERR_INVALID);
    elfm_track_free(tr);
    /* off: zeros whatever the views */
    ov.motion_lead_um = ov.motion_delay_us = 0;
    elfm_motion_bias(&ov, vz, bv);
    CHECK(bv[0] == 0 && bv[1] == 0 && bv[2] == 0);
    /* a bad disparity is an error */
    ov.motion_lead_um = 0.8;
    ov.motion_view_g[4][1] = NAN;
    elfm_track *t1 = elfm_track_create(7, &err);
    elfm_detection d1;
    memset(&d1, 0, sizeof d1);
    CHECK_OK(elfm_track_append(t1, &d1, &err), &err);
    CHECK_EQ_INT(elfm_track_smooth(t1, &ov, &err), ELFM_ERR_INVALID);
    ov.motion_view_g[4][1] = 0;
    ov.motion_n_views = ELFM_MAX_VIEWS + 1;
    CHECK_EQ_INT(elfm_track_smooth(t1, &ov, &err), ELFM_ERR_INVALID);
    elfm_track_free(t1);
  }
  /* 13. Ceres starts at the robust fit: reweighted linear fits (IRLS) put
   * every model where the loss has its minimum, so one Ceres iteration
   * ends where fifty do. From the old starts (the polynomials at p = 0,
   * the spline at the unweighted linear fit) one iteration leaves the
   * fit 0.2-1.1 um away (a fast bead, 4 gross outliers, Cauchy loss). */
  {
    const elfm_motion_model models[3] = {ELFM_MODEL_CONST_VELOCITY, ELFM_MODEL_CONST_ACCEL,
                                         ELFM_MODEL_SPLINE};
    static double P1[3 * NMAX];
    for (int k = 0; k < 3; k++) {
      rng = 0x1234567ULL + (uint64_t)k;
      make(k, 300, T0, 0.1, 0.4);
      for (int i = 0; i < 300; i++) X[3 * i] *= 8;  /* 2.4 um/ms */
      for (int j = 0; j < 4; j++) X[3 * (30 + 70 * j) + 1] += 6.0;
      elfm_smooth_options oc = o;
      oc.loss = ELFM_LOSS_CAUCHY;
      oc.model = models[k];
      CHECK_OK(elfm_smooth_fit(&oc, 300, T, X, NULL, 300, T, P, NULL, NULL, NULL, &info, &err), &err);
      CHECK(info.n_outliers >= 4);
      oc.max_iterations = 1;
      CHECK_OK(elfm_smooth_fit(&oc, 300, T, X, NULL, 300, T, P1, NULL, NULL, NULL, NULL, &err), &err);
      double worst = 0;
      for (int i = 0; i < 900; i++) worst = fmax(worst, fabs(P1[i] - P[i]));
      fprintf(stderr, "model %d: one iteration within %.3g um\n", k, worst);
      CHECK_MSG(worst < 1e-3, "model %d: one Ceres iteration leaves the fit %g um off", k, worst);
    }
  }
  return check_report();
}
