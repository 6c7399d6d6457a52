/* smooth_models.c — smoothing a whole track over its span (the C side of
 * elfm_smooth.h: the options' defaults, frame grid, gap times, storing the
 * result in the track). */
#include "elfm_smooth.h"
#include "elfm_analysis.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* b(w) of one image moving at (wx, wy) um/ms (elfm_smooth.h). */
static double image_bias_factor(const elfm_smooth_options *o, double wx, double wy)
{
  const double sp = hypot(wx, wy);
  const double lead = o->motion_lead_um + o->motion_slow_lead_ms * fmax(0.0, o->motion_slow_um_per_ms - sp);
  return lead / fmax(sp, o->motion_lead_fade_um_per_ms) - o->motion_delay_us * 1e-3;
}

void elfm_smooth_options_default(elfm_smooth_options *o)
{
  memset(o, 0, sizeof *o);
  o->model = ELFM_MODEL_AUTO;
  o->loss = ELFM_LOSS_HUBER;
  o->loss_scale = 3.0;   /* |r| > 3 sigma (3D norm): ~3 % of inliers for chi2 with 3 dof */
  o->spline_weight_ms3 = 0;
  o->gcv_gamma = 1;      /* classical GCV; track: 1.4 (elfm_smooth.h) */
  o->spline_order = 2;   /* acceleration penalty */
  o->solver = ELFM_SOLVER_AUTO;
  o->max_iterations = 50;
  o->min_sigma_xy_um = 0.02;
  o->min_sigma_z_um = 0.08;
  o->allow_spline = 1;
  o->view_fit_sigma_factor = 1.5;  /* view fits vs peaks at equal depth (elfm_smooth.h) */
  o->fit_sd_power = 0;             /* each point's own view-fit scatter: off (elfm_smooth.h) */
  o->motion_lead_fade_um_per_ms = 0.5;  /* the lead's fade speed (elfm_smooth.h) */
}

void elfm_smooth_options_set_views(elfm_smooth_options *o, const elfm_calib *c)
{
  o->motion_n_views = c->n_views;
  for (int k = 0; k < c->n_views; k++) {
    o->motion_view_g[k][0] = c->views[k].dx_px_per_um * c->um_per_px;
    o->motion_view_g[k][1] = c->views[k].dy_px_per_um * c->um_per_px;
  }
}

/* elfm_motion_bias, or with vl (the velocity delay before, non-NULL) the
 * model along the path (elfm_smooth.h motion_along_path): each image's lead
 * along its velocity then, and the delay's way back the mean of its
 * velocities then and now (the trapezoid rule: on a circle it keeps the
 * chord's inward sag, which a straight step back along v leaves out). */
static void motion_bias_lagged(const elfm_smooth_options *o, const double v[3], const double *vl,
                               double b[3])
{
  b[0] = b[1] = b[2] = 0;
  if (o->motion_lead_um == 0 && o->motion_delay_us == 0 && o->motion_slow_lead_ms == 0) return;
  if (o->motion_n_views <= 0 && !vl) {
    double f = image_bias_factor(o, v[0], v[1]);
    b[0] = f * v[0];
    b[1] = f * v[1];
    return;
  }
  /* The equal-weight least-squares fit of u_v = p + z g_v to images each
   * off by b_v = b(w_v): dz = sum (b_v - mean b).(g_v - mean g) /
   * sum |g_v - mean g|^2 and dp = mean b - dz mean g. Without views, one
   * image at g = 0: dz = 0 and dp = its b. */
  const int n = o->motion_n_views > 0 ? o->motion_n_views : 1;
  const double d_ms = o->motion_delay_us * 1e-3;
  double sb[2] = {0, 0}, sg[2] = {0, 0}, sbg = 0, sgg = 0;
  for (int k = 0; k < n; k++) {
    const double gx = o->motion_n_views > 0 ? o->motion_view_g[k][0] : 0;
    const double gy = o->motion_n_views > 0 ? o->motion_view_g[k][1] : 0;
    const double wx = v[0] + v[2] * gx, wy = v[1] + v[2] * gy;
    if (vl) {
      /* image_bias_factor with the delay taken out is the lead's factor */
      const double ux = vl[0] + vl[2] * gx, uy = vl[1] + vl[2] * gy;
      const double fl = image_bias_factor(o, ux, uy) + d_ms;
      const double bx = fl * ux - d_ms * 0.5 * (wx + ux), by = fl * uy - d_ms * 0.5 * (wy + uy);
      sb[0] += bx;
      sb[1] += by;
      sbg += bx * gx + by * gy;
    } else {
      const double f = image_bias_factor(o, wx, wy);
      sb[0] += f * wx;
      sb[1] += f * wy;
      sbg += f * (wx * gx + wy * gy);
    }
    sg[0] += gx;
    sg[1] += gy;
    sgg += gx * gx + gy * gy;
  }
  const double den = sgg - (sg[0] * sg[0] + sg[1] * sg[1]) / n;
  b[2] = den > 1e-12 ? (sbg - (sb[0] * sg[0] + sb[1] * sg[1]) / n) / den : 0;
  b[0] = (sb[0] - b[2] * sg[0]) / n;
  b[1] = (sb[1] - b[2] * sg[1]) / n;
}

void elfm_motion_bias(const elfm_smooth_options *o, const double v[3], double b[3])
{
  motion_bias_lagged(o, v, NULL, b);
}

/* The median fit_sd_px over t's points that have one (> 0); 0 when fewer
 * than 3 have. scratch: n doubles. */
static double fit_sd_median(const elfm_track *t, double *scratch)
{
  size_t m = 0;
  for (size_t i = 0; i < t->n; i++)
    if (t->pts[i].fit_sd_px > 0 && isfinite(t->pts[i].fit_sd_px)) scratch[m++] = t->pts[i].fit_sd_px;
  if (m < 3) return 0;
  double med, spread;
  elfm_analysis_median(scratch, m, &med, &spread);
  return med;
}

/* The turn rate of a smoothed path (spline_turn, elfm_smooth.h): the
 * median over its intervals of the angle between the velocities at their
 * ends over their length (rad per ms), where both speeds exceed 0.5
 * um/ms (below it the direction is noise); 0 with fewer than 5 such
 * intervals. A mean would follow the noisy turns of slow stretches. */
static double turn_rate(const double *vel, const int64_t *t_us, size_t ns, double *scratch)
{
  size_t m = 0;
  for (size_t k = 0; k + 1 < ns; k++) {
    const double *u = vel + 3 * k, *w = vel + 3 * (k + 1);
    const double nu = sqrt(u[0] * u[0] + u[1] * u[1] + u[2] * u[2]);
    const double nw = sqrt(w[0] * w[0] + w[1] * w[1] + w[2] * w[2]);
    const double dt_ms = (double)(t_us[k + 1] - t_us[k]) * 1e-3;
    if (!(nu > 0.5 && nw > 0.5 && dt_ms > 0)) continue;
    const double c = (u[0] * w[0] + u[1] * w[1] + u[2] * w[2]) / (nu * nw);
    scratch[m++] = acos(fmin(1.0, fmax(-1.0, c))) / dt_ms;
  }
  if (m < 5) return 0;
  double med, spread;
  elfm_analysis_median(scratch, m, &med, &spread);
  return isfinite(med) && med > 0 ? med : 0;
}

/* xyz (n x 3) = t's points moved by the motion bias of the smoothed
 * velocity vel (one per frame from t's first, at times tq) at their
 * frames; along the path (motion_along_path), of that velocity and the
 * one a delay before. */
static void points_unbiased(const elfm_smooth_options *o, const elfm_track *t, const double *vel,
                            const int64_t *tq, size_t ns, double *xyz)
{
  const int64_t f0 = t->pts[0].frame;
  const double lag_us = o->motion_along_path ? o->motion_delay_us : 0;
  for (size_t i = 0; i < t->n; i++) {
    const elfm_detection *d = &t->pts[i];
    const size_t s = (size_t)(d->frame - f0);
    double b[3];
    if (lag_us > 0 && ns >= 2) {
      /* the fitted velocity delay before, linear between the samples
       * around that time (from the first two before the span's start) */
      const double tt = (double)tq[s] - lag_us;
      size_t k = s > 0 ? s - 1 : 0;
      while (k > 0 && (double)tq[k] > tt) k--;
      const double span = (double)(tq[k + 1] - tq[k]);
      const double f = span > 0 ? (tt - (double)tq[k]) / span : 0;
      double vl[3];
      for (int a = 0; a < 3; a++) vl[a] = vel[3 * k + a] + f * (vel[3 * (k + 1) + a] - vel[3 * k + a]);
      motion_bias_lagged(o, vel + 3 * s, vl, b);
    } else {
      elfm_motion_bias(o, vel + 3 * s, b);
    }
    xyz[3 * i] = d->x_um - b[0];
    xyz[3 * i + 1] = d->y_um - b[1];
    xyz[3 * i + 2] = d->z_um - b[2];
  }
}

elfm_status elfm_track_smooth(elfm_track *t, const elfm_smooth_options *o, elfm_error *err)
{
  if (!t || !o || t->n == 0)
    return elfm_error_set(err, ELFM_ERR_INVALID, NULL, -1, "smooth: empty track");
  if (!(fabs(o->motion_lead_um) <= 100) || !(fabs(o->motion_delay_us) <= 1e6))
    return elfm_error_set(err, ELFM_ERR_INVALID, NULL, -1,
                          "smooth: motion bias out of range (lead %g um, delay %g us; "
                          "at most 100 um and 1 s)", o->motion_lead_um, o->motion_delay_us);
  if (!(o->motion_lead_fade_um_per_ms > 0 && o->motion_lead_fade_um_per_ms <= 100))
    return elfm_error_set(err, ELFM_ERR_INVALID, NULL, -1,
                          "smooth: motion lead fade speed %g um/ms is not in (0, 100]",
                          o->motion_lead_fade_um_per_ms);
  if (!(o->motion_slow_lead_ms >= 0 && o->motion_slow_lead_ms <= 10) ||
      !(o->motion_slow_um_per_ms >= 0 && o->motion_slow_um_per_ms <= 100))
    return elfm_error_set(err, ELFM_ERR_INVALID, NULL, -1,
                          "smooth: slow lead %g ms below %g um/ms is out of range "
                          "(0..10 ms, 0..100 um/ms)", o->motion_slow_lead_ms, o->motion_slow_um_per_ms);
  if (!(o->fit_sd_power >= 0 && o->fit_sd_power <= 4))
    return elfm_error_set(err, ELFM_ERR_INVALID, NULL, -1,
                          "smooth: fit_sd_power %g is not in [0, 4]", o->fit_sd_power);
  if (o->motion_along_path != 0 && o->motion_along_path != 1)
    return elfm_error_set(err, ELFM_ERR_INVALID, NULL, -1, "smooth: motion_along_path %d is not 0 or 1",
                          o->motion_along_path);
  if (o->motion_n_views < 0 || o->motion_n_views > ELFM_MAX_VIEWS)
    return elfm_error_set(err, ELFM_ERR_INVALID, NULL, -1, "smooth: %d views for the motion bias",
                          o->motion_n_views);
  for (int k = 0; k < o->motion_n_views; k++)
    if (!(fabs(o->motion_view_g[k][0]) <= 100) || !(fabs(o->motion_view_g[k][1]) <= 100))
      return elfm_error_set(err, ELFM_ERR_INVALID, NULL, -1,
                            "smooth: view %d's disparity for the motion bias is out of range", k);
  const size_t n = t->n;
  const int64_t f0 = t->pts[0].frame, f1 = t->pts[n - 1].frame;
  if (f1 - f0 > 100000000)  /* 1e8 frames = a day at 1 kHz */
    return elfm_error_set(err, ELFM_ERR_RANGE, NULL, -1, "smooth: track %lld spans %lld frames",
                          (long long)t->id, (long long)(f1 - f0 + 1));
  const size_t ns = (size_t)(f1 - f0 + 1);
  int64_t *tq = malloc(ns * sizeof *tq), *td = malloc(n * sizeof *td);
  int32_t *raw = malloc(ns * sizeof *raw);
  double *xyz = malloc(3 * n * sizeof *xyz), *sig = NULL, *omega_scratch = NULL;
  double *pos = malloc(3 * ns * sizeof *pos), *vel = malloc(3 * ns * sizeof *vel),
         *psd = malloc(3 * ns * sizeof *psd), *vsd = malloc(3 * ns * sizeof *vsd);
  elfm_status st = ELFM_OK;
  if (!tq || !td || !raw || !xyz || !pos || !vel || !psd || !vsd) {
    st = elfm_error_set(err, ELFM_ERR_NOMEM, NULL, -1, "smooth: out of memory");
    goto fail;
  }
  for (size_t k = 0; k < ns; k++) raw[k] = -1;
  for (size_t i = 0; i < n; i++) {
    const elfm_detection *d = &t->pts[i];
    td[i] = d->t_us;
    xyz[3 * i] = d->x_um;
    xyz[3 * i + 1] = d->y_um;
    xyz[3 * i + 2] = d->z_um;
    raw[d->frame - f0] = (int32_t)i;
    tq[d->frame - f0] = d->t_us;
  }
  /* Gap frames: the run's recorded time (o->frame_times), else time
   * interpolated between the real neighbours (exact for a fixed frame
   * rate; windows opened by trigger edges are not evenly spaced). A
   * recorded time must lie strictly between the gap's ends, as the
   * frames' order says; else the interpolation stands. */
  for (size_t i = 0; i + 1 < n; i++) {
    int64_t fa = t->pts[i].frame, fb = t->pts[i + 1].frame;
    int64_t ta = t->pts[i].t_us, tb = t->pts[i + 1].t_us;
    for (int64_t f = fa + 1; f < fb; f++) {
      int64_t tr;
      if (o->frame_times && elfm_frame_times_get(o->frame_times, f, &tr) && tr > ta && tr < tb)
        tq[f - f0] = tr;
      else
        tq[f - f0] = ta + (int64_t)llround((double)(tb - ta) * (double)(f - fa) / (double)(fb - fa));
    }
  }
  /* Points the view fit found where no peak stood out (gap filling, the
   * guided search) are noisier than the peaks: per-point sigmas, the
   * peaks' the estimated noise, those points' view_fit_sigma_factor times
   * it. Why 1.5 by default: on flow the fills' lateral RMSE is 0.75-0.88 um
   * at |z| 40-60 um against 0.52-0.55 for the peaks there, and a deep
   * track's own noise estimate already holds its peaks'; 20 seeds, alpha at
   * 1 / 1.5 / 2 / 3: 0.7655 / 0.7681 / 0.7680 / 0.7657 (docs/tracker.md,
   * "Smoother"). */
  size_t n_view_fit = 0;
  for (size_t i = 0; i < n; i++) n_view_fit += t->pts[i].view_fit != 0;
  /* and each point by its own view fit's scatter (fit_sd_power) */
  double sd_med = 0;
  if (o->fit_sd_power > 0) {
    if (!(sig = malloc(3 * n * sizeof *sig))) {
      st = elfm_error_set(err, ELFM_ERR_NOMEM, NULL, -1, "smooth: out of memory");
      goto fail;
    }
    sd_med = fit_sd_median(t, sig);
  }
  if ((n_view_fit > 0 && o->view_fit_sigma_factor != 1.0) || sd_med > 0) {
    if (!(o->view_fit_sigma_factor > 0) || !(o->view_fit_sigma_factor <= 1e3)) {
      st = elfm_error_set(err, ELFM_ERR_INVALID, NULL, -1,
                          "smooth: view-fit sigma factor %g is not in (0, 1000]",
                          o->view_fit_sigma_factor);
      goto fail;
    }
    double s0[3];
    if ((st = elfm_smooth_estimate_noise(o, n, td, xyz, s0, err)) != ELFM_OK) goto fail;
    if (!sig && !(sig = malloc(3 * n * sizeof *sig))) {
      st = elfm_error_set(err, ELFM_ERR_NOMEM, NULL, -1, "smooth: out of memory");
      goto fail;
    }
    for (size_t i = 0; i < n; i++) {
      const double q = t->pts[i].fit_sd_px;
      double f = t->pts[i].view_fit ? o->view_fit_sigma_factor : 1.0;
      if (sd_med > 0 && q > 0 && isfinite(q)) f *= fmin(fmax(pow(q / sd_med, o->fit_sd_power), 0.5), 3.0);
      for (int a = 0; a < 3; a++) sig[3 * i + a] = s0[a] * f;
    }
  } else {
    free(sig); /* nothing to scale: the fit estimates the noise itself */
    sig = NULL;
  }
  elfm_smooth_info info;
  const int bias = o->motion_lead_um != 0 || o->motion_delay_us != 0 || o->motion_slow_lead_ms != 0;
  /* With the bias, a second fit follows (below) and only its result is
   * kept: the first is IRLS's alone, without Ceres's polish (on 66
   * recordings, one track on 6 of them moved, alpha the same: docs/
   * tracker.md "Fewer Ceres solves"); the last fit is always Ceres's. */
  elfm_smooth_options o1 = *o;
  o1.irls_only = o->irls_only || (bias && n >= 3);
  st = elfm_smooth_fit(&o1, n, td, xyz, sig, ns, tq, pos, vel, psd, vsd, &info, err);
  if (st != ELFM_OK) goto fail;
  double omega = 0;
  if (o->spline_turn && o->spline_order == 3 && info.model == ELFM_MODEL_SPLINE) {
    if (!(omega_scratch = malloc(ns * sizeof *omega_scratch))) {
      st = elfm_error_set(err, ELFM_ERR_NOMEM, NULL, -1, "smooth: out of memory");
      goto fail;
    }
    omega = turn_rate(vel, tq, ns, omega_scratch);
  }
  if ((bias || omega > 0) && n >= 3 && info.model != ELFM_MODEL_STATIC) {
    /* Second fit on the points moved by the motion bias (elfm_smooth.h).
     * The velocity comes from the first fit, not from neighbouring
     * points, whose noise over 1 ms is as large as the bias itself. The
     * model and the spline weight stay those of the first fit: the bias is
     * a smooth function of the motion, so it changes neither choice, and
     * a second GCV search would double the cost. Except along a turn
     * (spline_turn): the prior then leaves the track's circle alone, and
     * the weight that suits the new prior is larger (chosen again). */
    if (bias) points_unbiased(o, t, vel, tq, ns, xyz);
    elfm_smooth_options o2 = *o;
    o2.model = info.model;
    /* and a third after this one: the bias again along the turn */
    o2.irls_only = o->irls_only || (bias && omega > 0 && info.model == ELFM_MODEL_SPLINE);
    if (info.model == ELFM_MODEL_SPLINE && !(omega > 0)) o2.spline_weight_ms3 = info.spline_weight_ms3;
    o2.spline_omega_rad_per_ms = omega > 0 ? omega : o->spline_omega_rad_per_ms;
    st = elfm_smooth_fit(&o2, n, td, xyz, sig, ns, tq, pos, vel, psd, vsd, &info, err);
    if (st != ELFM_OK) goto fail;
    if (bias && omega > 0 && info.model == ELFM_MODEL_SPLINE) {
      /* ... and the bias once more, from this fit's velocity, which
       * follows the turn better than the first fit's: the raw points
       * moved again, the same prior and weight (no third search). Flow
       * 100 ms seeds 1-20 alpha 0.8749 -> 0.8768; the turn rate measured
       * again as well: 0.8769; the weight chosen again: 0.8763. */
      points_unbiased(o, t, vel, tq, ns, xyz);
      o2.spline_weight_ms3 = info.spline_weight_ms3;
      o2.irls_only = o->irls_only;
      st = elfm_smooth_fit(&o2, n, td, xyz, sig, ns, tq, pos, vel, psd, vsd, &info, err);
      if (st != ELFM_OK) goto fail;
    }
  }
  free(omega_scratch);
  omega_scratch = NULL;
  /* sigmas from the noise floors alone (elfm_smooth_noise_known): the
   * uncertainties are undetermined, not 0.02 um */
  if (!elfm_smooth_noise_known(n, td))
    for (size_t i = 0; i < 3 * ns; i++) psd[i] = vsd[i] = NAN;
  free(t->span_t_us);
  free(t->pos_um);
  free(t->vel_um_per_ms);
  free(t->pos_sd_um);
  free(t->vel_sd_um_per_ms);
  free(t->raw_index);
  t->n_span = ns;
  t->span_t_us = tq;
  t->pos_um = pos;
  t->vel_um_per_ms = vel;
  t->pos_sd_um = psd;
  t->vel_sd_um_per_ms = vsd;
  t->raw_index = raw;
  t->model = info.model;
  t->spline_weight_ms3 = info.model == ELFM_MODEL_SPLINE ? info.spline_weight_ms3 : 0;
  t->spline_omega_rad_per_ms = info.model == ELFM_MODEL_SPLINE ? omega : 0;
  t->edf = info.edf;
  t->n_outliers = info.n_outliers;
  t->ceres = info.ceres;
  free(td);
  free(xyz);
  free(sig);
  return ELFM_OK;
fail:
  free(omega_scratch);
  free(tq);
  free(td);
  free(raw);
  free(xyz);
  free(sig);
  free(pos);
  free(vel);
  free(psd);
  free(vsd);
  return st;
}
