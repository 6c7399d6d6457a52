/* smooth_models.c — smoothing a whole track over its span (the C side of
 * elfm_smooth.h: frame grid, gap times, storing the result in the track). */
#include "elfm_smooth.h"

#include <math.h>
#include <stdlib.h>

/* Below this lateral speed the motion's direction is mostly noise, so the
 * lead (a distance along that direction) fades out in proportion. */
#define MOTION_LEAD_FADE_UM_PER_MS 0.5

elfm_status elfm_track_smooth(elfm_track *t, const elfm_smooth_options *o, elfm_error *err)
{
  if (!t || !o || t->n == 0)
    return elfm_error_set(err, ELFM_ERR_INVALID, NULL, -1, "smooth: empty track");
  if (!(fabs(o->motion_lead_um) <= 100) || !(fabs(o->motion_delay_us) <= 1e6))
    return elfm_error_set(err, ELFM_ERR_INVALID, NULL, -1,
                          "smooth: motion bias out of range (lead %g um, delay %g us; "
                          "at most 100 um and 1 s)", o->motion_lead_um, o->motion_delay_us);
  const size_t n = t->n;
  const int64_t f0 = t->pts[0].frame, f1 = t->pts[n - 1].frame;
  if (f1 - f0 > 100000000)  /* 1e8 frames = a day at 1 kHz */
    return elfm_error_set(err, ELFM_ERR_RANGE, NULL, -1, "smooth: track %lld spans %lld frames",
                          (long long)t->id, (long long)(f1 - f0 + 1));
  const size_t ns = (size_t)(f1 - f0 + 1);
  int64_t *tq = malloc(ns * sizeof *tq), *td = malloc(n * sizeof *td);
  int32_t *raw = malloc(ns * sizeof *raw);
  double *xyz = malloc(3 * n * sizeof *xyz);
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
  /* Gap frames: time interpolated between the real neighbours (frames are
   * evenly spaced in time, so this is exact for a fixed frame rate). */
  for (size_t i = 0; i + 1 < n; i++) {
    int64_t fa = t->pts[i].frame, fb = t->pts[i + 1].frame;
    int64_t ta = t->pts[i].t_us, tb = t->pts[i + 1].t_us;
    for (int64_t f = fa + 1; f < fb; f++)
      tq[f - f0] = ta + (int64_t)llround((double)(tb - ta) * (double)(f - fa) / (double)(fb - fa));
  }
  elfm_smooth_info info;
  st = elfm_smooth_fit(o, n, td, xyz, NULL, ns, tq, pos, vel, psd, vsd, &info, err);
  if (st != ELFM_OK) goto fail;
  if ((o->motion_lead_um != 0 || o->motion_delay_us != 0) && n >= 3 &&
      info.model != ELFM_MODEL_STATIC) {
    /* Second fit on the points moved by the motion bias (elfm_smooth.h).
     * The velocity comes from the first fit, not from neighbouring
     * points, whose noise over 1 ms is as large as the bias itself. The
     * model and the spline weight stay those of the first fit: the bias is
     * a smooth function of the motion, so it changes neither choice, and
     * a second GCV search would double the cost. */
    const double delay_ms = o->motion_delay_us * 1e-3;
    for (size_t i = 0; i < n; i++) {
      const double *v = vel + 3 * (size_t)(t->pts[i].frame - f0);
      const double s = hypot(v[0], v[1]);
      const double lead = o->motion_lead_um / fmax(s, MOTION_LEAD_FADE_UM_PER_MS);
      xyz[3 * i] += v[0] * (delay_ms - lead);
      xyz[3 * i + 1] += v[1] * (delay_ms - lead);
    }
    elfm_smooth_options o2 = *o;
    o2.model = info.model;
    if (info.model == ELFM_MODEL_SPLINE) o2.spline_weight_ms3 = info.spline_weight_ms3;
    st = elfm_smooth_fit(&o2, n, td, xyz, NULL, ns, tq, pos, vel, psd, vsd, &info, err);
    if (st != ELFM_OK) goto fail;
  }
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
  t->edf = info.edf;
  t->n_outliers = info.n_outliers;
  free(td);
  free(xyz);
  return ELFM_OK;
fail:
  free(tq);
  free(td);
  free(raw);
  free(xyz);
  free(pos);
  free(vel);
  free(psd);
  free(vsd);
  return st;
}
