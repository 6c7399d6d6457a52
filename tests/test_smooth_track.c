/* test_smooth_track.c — whole tracks through the smoother
 * (elfm_track_smooth): the span's frames with the gaps' rows, per-point
 * sigmas (view fits, fit_sd_px), and the motion bias taken off the points
 * (elfm_smooth_options.motion_lead_um / motion_delay_us). Split from
 * test_smooth.c, which tests elfm_smooth_fit itself. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "check.h"
#include "elfm_tracker.h"

#include "smooth_test_util.h"

int main(void)
{
  elfm_error err;
  elfm_error_clear(&err);
  elfm_smooth_options o;
  elfm_smooth_options_default(&o);
  const int64_t T0 = 1000000000000LL;

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
    /* with the bias, the first fit only feeds the second: IRLS's alone;
     * the fit kept is Ceres's (the spline along the turn: a third) */
    CHECK(tb[0]->ceres == 1 && tb[1]->ceres == 1 && tb[2]->ceres == 1);
    {
      elfm_smooth_options ot = ob;
      ot.spline_turn = 1;
      ot.spline_order = 3;
      CHECK_OK(elfm_track_smooth(tb[1], &ot, &err), &err);
      CHECK_MSG(tb[1]->model == ELFM_MODEL_SPLINE && tb[1]->spline_omega_rad_per_ms > 0 &&
                    tb[1]->ceres == 1,
                "turn: model %d omega %g ceres %d", tb[1]->model, tb[1]->spline_omega_rad_per_ms,
                tb[1]->ceres);
      CHECK_OK(elfm_track_smooth(tb[1], &ob, &err), &err); /* back as it was */
    }
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

  /* 13. A track too short to tell its noise (elfm_smooth_noise_known):
   * the tracker's path, with per-point sigmas from the points' fit_sd_px,
   * reports its uncertainties as NaN (tracks.csv: empty), where the noise
   * floor's sigmas made them ~0.02 um; with 5 points they are the fit's. */
  for (int n = 4; n <= 5; n++) {
    elfm_track *ts = elfm_track_create(20 + n, &err);
    for (int f = 0; f < n; f++) {
      elfm_detection d;
      memset(&d, 0, sizeof d);
      d.frame = f;
      d.t_us = T0 + 3000 * f;
      d.x_um = 7.5 * f + 0.3 * gauss();
      d.y_um = 0.3 * gauss();
      d.z_um = -60 + gauss();
      d.fit_sd_px = 0.05 + 0.01 * f;
      CHECK_OK(elfm_track_append(ts, &d, &err), &err);
    }
    elfm_smooth_options on = o;
    on.fit_sd_power = 1;
    CHECK_OK(elfm_track_smooth(ts, &on, &err), &err);
    int nan = 0, pos_ok = 1;
    for (size_t i = 0; i < 3 * ts->n_span; i++) {
      nan += isnan(ts->pos_sd_um[i]) && isnan(ts->vel_sd_um_per_ms[i]);
      pos_ok &= isfinite(ts->pos_um[i]) && isfinite(ts->vel_um_per_ms[i]);
    }
    CHECK(pos_ok);
    if (n == 4) CHECK_MSG(nan == 3 * n, "%d of %d uncertainties NaN", nan, 3 * n);
    else CHECK_MSG(nan == 0 && ts->pos_sd_um[0] > 0.02, "%d NaN, sd_x %g", nan, ts->pos_sd_um[0]);
    elfm_track_free(ts);
  }
  return check_report();
}
