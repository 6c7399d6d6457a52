/* test_smooth_along_path.c — the motion bias along the fitted path
 * (elfm_smooth_options.motion_along_path): a detection shows the object
 * where it was delay ago, its image ahead by the lead along its motion
 * then. Detections are made here from that picture itself (each view's
 * image placed and the views fitted by least squares, as the view fit
 * does), not from elfm_motion_bias, so the smoother's model is checked
 * against the physics it stands for:
 *  - a bead circling tightly: with the model along the path the smoothed
 *    track lies on the circle (as near as a track without any bias), with
 *    the straight model it keeps an outward offset of ~lead x delay x turn
 *    rate;
 *  - the same with 3 x 3 views and the bead rising in z (a helix): each
 *    view's image moves its own way; laterally the same gain, and z (the
 *    delay's step back, the lead's share) taken out by both models;
 *  - a straight track at constant velocity: both models agree to 1e-9 um;
 *  - no delay: the model along the path is the straight one, bit for bit;
 *  - a value other than 0 or 1 is refused with an error. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "check.h"
#include "elfm_tracker.h"

#include "smooth_test_util.h"

enum { NF = 120 };

/* a helix: radius R um, angular rate w rad/ms, rising vz um/ms */
static void helix(double R, double w, double vz, double t_ms, double p[3], double v[3])
{
  p[0] = R * cos(w * t_ms);
  p[1] = R * sin(w * t_ms);
  p[2] = -20 + vz * t_ms;
  v[0] = -R * w * sin(w * t_ms);
  v[1] = R * w * cos(w * t_ms);
  v[2] = vz;
}

/* The detection of an object on the helix at t_ms: each view's image where
 * the object was delay_ms before (u = p_xy + z g) plus lead along that
 * image's velocity then, the views fitted for (x, y, z) by least squares;
 * without views (nv 0) the lateral position alone, z as it was. */
static void detect(double R, double w, double vz, double t_ms, double lead, double delay_ms,
                   int nv, const double (*g)[2], double out[3])
{
  double p[3], v[3];
  helix(R, w, vz, t_ms - delay_ms, p, v);
  if (nv == 0) {
    const double s = hypot(v[0], v[1]);
    out[0] = p[0] + lead * v[0] / s;
    out[1] = p[1] + lead * v[1] / s;
    out[2] = p[2];
    return;
  }
  /* u_v = q + z g_v: normal equations in (qx, qy, z) */
  double A[3][3] = {{0}}, b[3] = {0};
  for (int k = 0; k < nv; k++) {
    const double wx = v[0] + v[2] * g[k][0], wy = v[1] + v[2] * g[k][1], s = hypot(wx, wy);
    const double ux = p[0] + p[2] * g[k][0] + lead * wx / s, uy = p[1] + p[2] * g[k][1] + lead * wy / s;
    /* rows (1, 0, gx) . (qx, qy, z) = ux and (0, 1, gy) . (...) = uy */
    const double r0[3] = {1, 0, g[k][0]}, r1[3] = {0, 1, g[k][1]};
    for (int i = 0; i < 3; i++) {
      for (int j = 0; j < 3; j++) A[i][j] += r0[i] * r0[j] + r1[i] * r1[j];
      b[i] += r0[i] * ux + r1[i] * uy;
    }
  }
  /* Cramer's rule: 3 x 3, well conditioned for a spread of g */
  const double det = A[0][0] * (A[1][1] * A[2][2] - A[1][2] * A[2][1]) -
                     A[0][1] * (A[1][0] * A[2][2] - A[1][2] * A[2][0]) +
                     A[0][2] * (A[1][0] * A[2][1] - A[1][1] * A[2][0]);
  for (int c = 0; c < 3; c++) {
    double M[3][3];
    memcpy(M, A, sizeof M);
    for (int i = 0; i < 3; i++) M[i][c] = b[i];
    out[c] = (M[0][0] * (M[1][1] * M[2][2] - M[1][2] * M[2][1]) -
              M[0][1] * (M[1][0] * M[2][2] - M[1][2] * M[2][0]) +
              M[0][2] * (M[1][0] * M[2][1] - M[1][1] * M[2][0])) / det;
  }
}

/* A track of NF frames at 1 kHz on the helix, detected with the given lead
 * and delay and noise sxy / sz; truth[] the positions at the frames. */
static elfm_track *helix_track(int64_t id, double R, double w, double vz, double lead, double delay_ms,
                               int nv, const double (*g)[2], double sxy, double sz, double *truth)
{
  elfm_error err;
  elfm_track *t = elfm_track_create(id, &err);
  if (!t) return NULL;
  rng = 0xABCDEF12345ULL;
  for (int f = 0; f < NF; f++) {
    const double tm = f;
    double p[3], v[3], d3[3];
    helix(R, w, vz, tm, p, v);
    memcpy(truth + 3 * f, p, sizeof p);
    detect(R, w, vz, tm, lead, delay_ms, nv, g, d3);
    elfm_detection d;
    memset(&d, 0, sizeof d);
    d.frame = f;
    d.t_us = 1000000000000LL + 1000 * f;
    d.x_um = d3[0] + sxy * gauss();
    d.y_um = d3[1] + sxy * gauss();
    d.z_um = d3[2] + sz * gauss();
    if (elfm_track_append(t, &d, &err) != ELFM_OK) {
      elfm_track_free(t);
      return NULL;
    }
  }
  return t;
}

/* RMS of the smoothed positions' error, frames 10..NF-10 (the ends' fits
 * extrapolate), lateral or z */
static double err_rms(const elfm_track *t, const double *truth, int axis_z)
{
  double s = 0;
  int n = 0;
  for (int f = 10; f < NF - 10; f++, n++) {
    const double *p = t->pos_um + 3 * f, *q = truth + 3 * f;
    s += axis_z ? (p[2] - q[2]) * (p[2] - q[2]) : (p[0] - q[0]) * (p[0] - q[0]) + (p[1] - q[1]) * (p[1] - q[1]);
  }
  return sqrt(s / n);
}

int main(void)
{
  elfm_error err;
  elfm_error_clear(&err);
  elfm_smooth_options o;
  elfm_smooth_options_default(&o);
  o.spline_order = 3;
  o.spline_turn = 1;
  const double lead = 1.25, delay_ms = 0.3;
  double truth[3 * NF];

  /* 1. A bead circling 6 um out at 1.5 um/ms (0.25 rad/ms), flow_random's
   * slow turns: outward offset lead x delay x rate = 0.09 um, and the
   * chord's sag of the straight step back. */
  {
    const double R = 6, w = 0.25;
    elfm_smooth_options straight = o, path = o, none = o;
    straight.motion_lead_um = path.motion_lead_um = lead;
    straight.motion_delay_us = path.motion_delay_us = delay_ms * 1000;
    path.motion_along_path = 1;
    elfm_track *ts = helix_track(1, R, w, 0, lead, delay_ms, 0, NULL, 0.02, 0.1, truth);
    elfm_track *tp = helix_track(2, R, w, 0, lead, delay_ms, 0, NULL, 0.02, 0.1, truth);
    elfm_track *tn = helix_track(3, R, w, 0, 0, 0, 0, NULL, 0.02, 0.1, truth);
    CHECK(ts && tp && tn);
    CHECK_OK(elfm_track_smooth(ts, &straight, &err), &err);
    CHECK_OK(elfm_track_smooth(tp, &path, &err), &err);
    CHECK_OK(elfm_track_smooth(tn, &none, &err), &err);
    const double es = err_rms(ts, truth, 0), ep = err_rms(tp, truth, 0), en = err_rms(tn, truth, 0);
    printf("circle 6 um at 1.5 um/ms: lateral RMS straight model %.4f um, along the path %.4f um, "
           "no bias %.4f um\n", es, ep, en);
    CHECK_MSG(es > 0.07, "the straight model's offset %.4f um: the case is gone", es);
    CHECK_MSG(ep < 0.4 * es, "along the path %.4f um, straight %.4f um", ep, es);
    CHECK_MSG(ep < en + 0.01, "along the path %.4f um, without a bias %.4f um", ep, en);
    elfm_track_free(ts);
    elfm_track_free(tp);
    elfm_track_free(tn);
  }

  /* 2. The same on 3 x 3 views (disparities -0.3, 0, 0.3 um per um) with
   * the bead rising at 1 um/ms: each view's image moves its own way, the
   * fitted z carries a share of the lead, which turns with the path. */
  {
    double g[9][2];
    for (int k = 0; k < 9; k++) {
      g[k][0] = 0.3 * (k % 3 - 1);
      g[k][1] = 0.3 * (k / 3 - 1);
    }
    elfm_smooth_options straight = o, path = o;
    straight.motion_lead_um = path.motion_lead_um = lead;
    straight.motion_delay_us = path.motion_delay_us = delay_ms * 1000;
    straight.motion_n_views = path.motion_n_views = 9;
    memcpy(straight.motion_view_g, g, sizeof g);
    memcpy(path.motion_view_g, g, sizeof g);
    path.motion_along_path = 1;
    const double R = 6, w = 0.25, vz = 1.0;
    elfm_track *ts = helix_track(4, R, w, vz, lead, delay_ms, 9, (const double (*)[2])g, 0.02, 0.1, truth);
    elfm_track *tp = helix_track(5, R, w, vz, lead, delay_ms, 9, (const double (*)[2])g, 0.02, 0.1, truth);
    CHECK(ts && tp);
    CHECK_OK(elfm_track_smooth(ts, &straight, &err), &err);
    CHECK_OK(elfm_track_smooth(tp, &path, &err), &err);
    const double es = err_rms(ts, truth, 0), ep = err_rms(tp, truth, 0);
    const double zs = err_rms(ts, truth, 1), zp = err_rms(tp, truth, 1);
    printf("helix on 3 x 3 views: lateral RMS straight %.4f um, along the path %.4f um; z %.4f / %.4f um\n",
           es, ep, zs, zp);
    CHECK_MSG(ep < 0.5 * es, "views: along the path %.4f um, straight %.4f um", ep, es);
    /* z: the delay's step back (0.3 um here) and the lead's share are
     * taken out both ways; the turn moves the lead's share little here */
    CHECK_MSG(zp < 0.06 && zs < 0.06, "views: z along the path %.4f um, straight %.4f um", zp, zs);
    elfm_track_free(ts);
    elfm_track_free(tp);
  }

  /* 3. A straight track at constant velocity: the velocity then is the
   * velocity now, so both models move each point alike. */
  {
    elfm_smooth_options straight = o, path = o;
    straight.motion_lead_um = path.motion_lead_um = lead;
    straight.motion_delay_us = path.motion_delay_us = delay_ms * 1000;
    path.motion_along_path = 1;
    elfm_track *t2[2];
    for (int c = 0; c < 2; c++) {
      t2[c] = elfm_track_create(6 + c, &err);
      CHECK(t2[c] != NULL);
      rng = 0x55AA55AAULL;
      for (int f = 0; f < 60; f++) {
        elfm_detection d;
        memset(&d, 0, sizeof d);
        d.frame = f;
        d.t_us = 1000 * f;
        /* exactly straight and even: the fit's velocity is the same at every sample */
        d.x_um = 2.0 * f - 30;
        d.y_um = -1.5 * f + 10;
        d.z_um = 5;
        CHECK_OK(elfm_track_append(t2[c], &d, &err), &err);
      }
    }
    CHECK_OK(elfm_track_smooth(t2[0], &straight, &err), &err);
    CHECK_OK(elfm_track_smooth(t2[1], &path, &err), &err);
    double dmax = 0;
    for (size_t i = 0; i < 3 * t2[0]->n_span; i++) dmax = fmax(dmax, fabs(t2[0]->pos_um[i] - t2[1]->pos_um[i]));
    printf("straight track: the two models differ by %.3g um at most\n", dmax);
    CHECK_MSG(dmax < 1e-9, "straight track: %.3g um apart", dmax);
    for (int c = 0; c < 2; c++) elfm_track_free(t2[c]);
  }

  /* 4. Without a delay the path's model is the straight one, bit for bit
   * (the integral's bias: a lead, no delay). */
  {
    elfm_smooth_options straight = o, path = o;
    straight.motion_lead_um = path.motion_lead_um = -0.05;
    straight.motion_lead_fade_um_per_ms = path.motion_lead_fade_um_per_ms = 0.05;
    path.motion_along_path = 1;
    elfm_track *ts = helix_track(8, 6, 0.25, 0, 0.3, 0.2, 0, NULL, 0.02, 0.1, truth);
    elfm_track *tp = helix_track(9, 6, 0.25, 0, 0.3, 0.2, 0, NULL, 0.02, 0.1, truth);
    CHECK(ts && tp);
    CHECK_OK(elfm_track_smooth(ts, &straight, &err), &err);
    CHECK_OK(elfm_track_smooth(tp, &path, &err), &err);
    CHECK(ts->n_span == tp->n_span && memcmp(ts->pos_um, tp->pos_um, 3 * ts->n_span * sizeof *ts->pos_um) == 0);

    /* 5. Neither 0 nor 1: an error, the track as it was. */
    path.motion_along_path = 2;
    CHECK_EQ_INT(elfm_track_smooth(tp, &path, &err), ELFM_ERR_INVALID);
    CHECK(strstr(err.message, "motion_along_path") != NULL);
    CHECK(tp->n_span == NF);
    elfm_track_free(ts);
    elfm_track_free(tp);
  }
  return check_report();
}
