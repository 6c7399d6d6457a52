/* test_smooth.c — the Ceres smoother: model choice (constant velocity,
 * constant acceleration, spline), robust loss against outliers, uncertainty,
 * and the numerical-stability cases of issue 5 (1-3 points, gaps, repeated
 * times, times near 1e12 us, offsets, static/collinear, extreme weights,
 * NaN/inf). Whole tracks through elfm_track_smooth (gaps' rows, per-point
 * sigmas, the motion bias): test_smooth_track.c; the helpers both use:
 * smooth_test_util.h. */
#include <stdlib.h>
#include <string.h>

#include "check.h"
#include "elfm_tracker.h"

#include "smooth_test_util.h"

/* the fits' query times and outputs */
static int64_t Q[NMAX];
static double P[3 * NMAX], V[3 * NMAX], PS[3 * NMAX], VS[3 * NMAX];

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

  /* 1b. The BIC's parameter counts (elfm_smooth.h): on a noise-free straight
   * track both polynomials fit exactly (chi2 ~ 0), so each BIC is its
   * penalty alone, k ln(3 n) with k = 6 and 9; the line is chosen. */
  make(0, 50, 0, 0, 0);
  CHECK_OK(elfm_smooth_fit(&o, 50, T, X, NULL, 50, T, P, V, NULL, NULL, &info, &err), &err);
  CHECK_EQ_INT(info.model, ELFM_MODEL_CONST_VELOCITY);
  CHECK_NEAR(info.bic[ELFM_MODEL_CONST_VELOCITY], 6 * log(150.0), 1e-6);
  CHECK_NEAR(info.bic[ELFM_MODEL_CONST_ACCEL], 9 * log(150.0), 1e-6);

  /* 2. Constant acceleration: CA chosen, acceleration within 5 %. */
  make(1, 400, T0, 0.1, 0.4);
  CHECK_OK(elfm_smooth_fit(&o, 400, T, X, NULL, 400, T, P, V, PS, VS, &info, &err), &err);
  CHECK_EQ_INT(info.model, ELFM_MODEL_CONST_ACCEL);
  CHECK_NEAR(info.accel_um_per_ms2[0], 0.002, 0.0001);
  CHECK_NEAR(info.accel_um_per_ms2[2], 0.001, 0.0002);
  CHECK(isfinite(info.bic[ELFM_MODEL_CONST_VELOCITY]) &&
        info.bic[ELFM_MODEL_CONST_VELOCITY] > info.bic[ELFM_MODEL_CONST_ACCEL]);
  /* The chosen polynomial is bit for bit the fit asked for by name,
   * although auto runs Ceres only on the polynomials that could be chosen
   * (the constant velocity here lies hundreds of BIC units above). With
   * the outliers of 1., the constant velocity likewise. */
  for (int c = 0; c < 2; c++) {
    static double P1[3 * 400], V1[3 * 400], PS1[3 * 400];
    if (c == 1) {
      make(0, 300, T0, 0.1, 0.4);
      for (int k = 0; k < 4; k++) X[3 * (40 + 60 * k)] += 6.0;
    }
    const size_t m = c ? 300 : 400;
    elfm_smooth_options on = o;
    on.model = c ? ELFM_MODEL_CONST_VELOCITY : ELFM_MODEL_CONST_ACCEL;
    elfm_smooth_info i1, i2;
    CHECK_OK(elfm_smooth_fit(&o, m, T, X, NULL, m, T, P, V, PS, NULL, &i1, &err), &err);
    CHECK_OK(elfm_smooth_fit(&on, m, T, X, NULL, m, T, P1, V1, PS1, NULL, &i2, &err), &err);
    CHECK_EQ_INT(i1.model, on.model);
    CHECK(i1.ceres == 1 && i2.ceres == 1); /* the chosen polynomial polished */
    CHECK_MSG(memcmp(P, P1, 3 * m * sizeof *P) == 0 && memcmp(V, V1, 3 * m * sizeof *V) == 0 &&
                  memcmp(PS, PS1, 3 * m * sizeof *PS) == 0,
              "case %d: auto's fit is not the named model's (x %.17g / %.17g)", c, P[0], P1[0]);
  }

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
  /* irls_only: the spline as the reweighted linear fits leave it, Ceres's
   * polish skipped (info.ceres says which), and here the same as Ceres's
   * to 1e-3 um, with outliers and either loss: a fit that only feeds
   * another may skip the polish (elfm_track_smooth). */
  for (int c = 0; c < 4; c++) {
    elfm_smooth_options oi = o;
    oi.loss = c & 1 ? ELFM_LOSS_CAUCHY : ELFM_LOSS_HUBER;
    double X2[3 * 300], P1[3 * 300], P2[3 * 300];
    memcpy(X2, X, sizeof X2);
    if (c & 2)
      for (int k = 0; k < 6; k++) X2[3 * (20 + 45 * k) + k % 3] += 3.0 + k;
    elfm_smooth_info ii;
    CHECK_OK(elfm_smooth_fit(&oi, 300, T, X2, NULL, 300, T, P1, NULL, NULL, NULL, &ii, &err), &err);
    CHECK_MSG(ii.model == ELFM_MODEL_SPLINE && ii.ceres == 1, "case %d: model %d, ceres %d", c,
              ii.model, ii.ceres);
    oi.irls_only = 1;
    CHECK_OK(elfm_smooth_fit(&oi, 300, T, X2, NULL, 300, T, P2, NULL, NULL, NULL, &ii, &err), &err);
    CHECK_MSG(ii.model == ELFM_MODEL_SPLINE && ii.ceres == 0, "case %d irls_only: model %d, ceres %d",
              c, ii.model, ii.ceres);
    double md = 0;
    for (int i = 0; i < 900; i++) md = fmax(md, fabs(P2[i] - P1[i]));
    CHECK_MSG(md < 1e-3, "case %d: IRLS's fit %g um from Ceres's", c, md);
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
    /* a lone point tells no noise: its uncertainty is undetermined, not
     * the noise floor's 0.02 um; given a sigma, it is that sigma */
    CHECK(P[0] == 1 && P[1] == 2 && P[2] == 3 && V[0] == 0 && isnan(VS[0]) && isnan(PS[0]));
    const double s1[3] = {0.3, 0.3, 1.2};
    CHECK_OK(elfm_smooth_fit(&o, 1, t1, x1, s1, 1, t1, P, V, PS, VS, &info, &err), &err);
    CHECK(fabs(PS[0] - 0.3) < 1e-9 && fabs(PS[2] - 1.2) < 1e-9 && isnan(VS[0]));
    CHECK_OK(elfm_smooth_fit(&o, 2, t1, x1, NULL, 3, t1, P, V, PS, VS, &info, &err), &err);
    CHECK_EQ_INT(info.model, ELFM_MODEL_CONST_VELOCITY);
    CHECK_NEAR(V[0], 1.0, 1e-6);
    CHECK_NEAR(V[2], 4.0, 1e-6);
    CHECK_NEAR(P[6], 3.0, 1e-6);  /* extrapolated to the third time */
    CHECK_OK(elfm_smooth_fit(&o, 3, t1, x1, NULL, 3, t1, P, V, PS, VS, &info, &err), &err);
    CHECK(info.model == ELFM_MODEL_CONST_VELOCITY || info.model == ELFM_MODEL_CONST_ACCEL);
    for (int i = 0; i < 9; i++) CHECK(isfinite(P[i]) && isfinite(V[i]));
    for (int i = 0; i < 9; i++) CHECK(isnan(PS[i]) && isnan(VS[i])); /* 3 points: noise unknown */
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
    CHECK(strstr(err.message, "point 1 has a non-finite coordinate") != NULL);
    X[5] = INFINITY;
    CHECK_EQ_INT(elfm_smooth_fit(&o, 10, T, X, NULL, 10, T, P, V, PS, VS, &info, &err), ELFM_ERR_NUMERIC);
    /* refused as input, not failing later in the fit with the same code */
    CHECK_MSG(strstr(err.message, "point 1 has a non-finite coordinate") != NULL, "%s", err.message);
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

  /* 14. Outliers also this far (outlier_min_um). A bead of blink_moving
   * (seed 7, 200 ms) seen in 17 pulses 3 ms apart on the stage at 2.5
   * um/ms: its x wanders by 0.3-0.6 um from point to point together, so
   * the second differences put the lateral noise at ~0.13 um and 6 of its
   * own points lay beyond the Cauchy loss's twice 2 sigma: more than the
   * third track drops. With the floor of 1.5 um only its last point (3.2
   * um short, the bead leaving the field dimly) counts. The same points
   * with the last 6 moved 5 um aside (the track went on along another
   * bead) still count 4 of those: the spline bends towards the block at
   * its near end. (Points alternating between two beads are a different
   * case: their second differences make the noise large and few count
   * as outliers with or without the floor.) */
  {
    static const double pts[17][3] = {
        {5.98, -56.74, -60.74}, {5.80, -48.86, -60.70}, {5.80, -41.43, -61.79},
        {5.48, -33.90, -60.37}, {5.32, -26.34, -60.06}, {5.21, -19.00, -60.60},
        {5.84, -11.57, -60.65}, {5.93, -4.14, -60.44},  {6.02, 3.36, -60.30},
        {5.90, 10.88, -60.53},  {5.14, 18.30, -60.42},  {5.89, 25.74, -60.44},
        {5.99, 33.23, -60.50},  {5.96, 40.52, -60.49},  {5.75, 48.27, -60.68},
        {5.71, 55.63, -60.44},  {5.89, 59.89, -60.55}};
    int64_t tb[17];
    double xb[51];
    for (int i = 0; i < 17; i++) {
      tb[i] = T0 + 3000 * i;
      for (int a = 0; a < 3; a++) xb[3 * i + a] = pts[i][a];
    }
    elfm_smooth_options ob = o;
    ob.loss = ELFM_LOSS_CAUCHY;
    ob.loss_scale = 2;
    int n_out[2][2];
    for (int mixed = 0; mixed < 2; mixed++) {
      if (mixed)
        for (int i = 11; i < 17; i++) xb[3 * i] += 5.0;
      for (int floor = 0; floor < 2; floor++) {
        ob.outlier_min_um = floor ? 1.5 : 0;
        CHECK_OK(elfm_smooth_fit(&ob, 17, tb, xb, NULL, 17, tb, P, V, NULL, NULL, &info, &err), &err);
        n_out[mixed][floor] = info.n_outliers;
      }
    }
    fprintf(stderr, "14: outliers of one bead %d, with the 1.5 um floor %d; with 6 points 5 um aside "
            "%d / %d\n", n_out[0][0], n_out[0][1], n_out[1][0], n_out[1][1]);
    CHECK_MSG(n_out[0][0] * 3 > 17, "only %d outliers without the floor: the case tests nothing",
              n_out[0][0]);
    CHECK_MSG(n_out[0][1] * 3 <= 17 && n_out[0][1] <= 1, "%d outliers with the floor", n_out[0][1]);
    CHECK_MSG(n_out[1][1] >= 4, "another bead's 6 points: %d outliers with the floor", n_out[1][1]);
    ob.outlier_min_um = -1;
    CHECK_EQ_INT(elfm_smooth_fit(&ob, 17, tb, xb, NULL, 17, tb, P, V, NULL, NULL, &info, &err),
                 ELFM_ERR_INVALID);
  }
  return check_report();
}
