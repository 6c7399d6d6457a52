/* analysis.c — stage velocity from tracks, the rigid shift between two
 * frames' points, FWHM of isolated beads (see elfm_analysis.h). */
#include "elfm_analysis.h"

#include <math.h>
#include <stdlib.h>

elfm_status elfm_analysis_stage(const elfm_track_store *s, const double *sv,
                                elfm_stage_result *r, elfm_error *err)
{
  elfm_track_info *ti = malloc((s->n ? s->n : 1) * sizeof *ti);
  if (!ti) return elfm_error_set(err, ELFM_ERR_NOMEM, NULL, -1, "stage analysis: out of memory");
  for (size_t i = 0; i < s->n; i++) elfm_track_info_get(s->tracks[i], &ti[i]);
  elfm_status st = elfm_analysis_stage_info(ti, s->n, sv, r, err);
  free(ti);
  return st;
}

/* The acceleration (elfm_stage_result): the rows' sums about each track's
 * means, moved to the sums about the means of all rows (parallel axes),
 * give the pooled slope; each long track's own slope its spread. */
static void stage_accel(const elfm_track_info *ti, size_t nt, elfm_stage_result *r)
{
  double n = 0, t_ref = NAN, mt = 0, mv[3] = {0, 0, 0};
  for (size_t i = 0; i < nt; i++) {
    if (!ti[i].smoothed || !ti[i].n_rows || !isfinite(ti[i].mean_vel_um_per_ms[0])) continue;
    if (isnan(t_ref)) t_ref = ti[i].mean_t_us;
    const double w = (double)ti[i].n_rows;
    n += w;
    mt += w * 1e-3 * (ti[i].mean_t_us - t_ref);
    for (int a = 0; a < 3; a++) mv[a] += w * ti[i].mean_vel_um_per_ms[a];
  }
  double stt = 0, stv[3] = {0, 0, 0}, s1[3] = {0, 0, 0}, s2[3] = {0, 0, 0};
  size_t n_long = 0;
  if (n > 0) {
    mt /= n;
    for (int a = 0; a < 3; a++) mv[a] /= n;
  }
  for (size_t i = 0; i < nt; i++) {
    if (!ti[i].smoothed || !ti[i].n_rows || !isfinite(ti[i].mean_vel_um_per_ms[0])) continue;
    const double w = (double)ti[i].n_rows, dt = 1e-3 * (ti[i].mean_t_us - t_ref) - mt;
    stt += ti[i].s_tt_ms2 + w * dt * dt;
    for (int a = 0; a < 3; a++) stv[a] += ti[i].s_tv_um[a] + w * dt * (ti[i].mean_vel_um_per_ms[a] - mv[a]);
    if (ti[i].n_rows < ELFM_STAGE_ACCEL_MIN_ROWS || !(ti[i].s_tt_ms2 > 0)) continue;
    n_long++;
    for (int a = 0; a < 3; a++) {
      const double g = ti[i].s_tv_um[a] / ti[i].s_tt_ms2;
      s1[a] += g;
      s2[a] += g * g;
    }
  }
  for (int a = 0; a < 3; a++) {
    r->accel_um_per_ms2[a] = stt > 0 ? stv[a] / stt : NAN;
    const double m = n_long ? s1[a] / (double)n_long : 0;
    r->accel_sd_um_per_ms2[a] =
        n_long > 1 ? sqrt(fmax(0, (s2[a] - (double)n_long * m * m) / (double)(n_long - 1))) : NAN;
  }
}

elfm_status elfm_analysis_stage_info(const elfm_track_info *ti, size_t nt, const double *sv,
                                     elfm_stage_result *r, elfm_error *err)
{
  double sw = 0, m[3] = {0, 0, 0}, um[3] = {0, 0, 0}, uss[3] = {0, 0, 0}, sp = 0, sp2 = 0;
  double swp = 0, mp[3] = {0, 0, 0}, swv[3] = {0, 0, 0}, mv[3] = {0, 0, 0};
  size_t n = 0;
  for (size_t i = 0; i < nt; i++) {
    /* a track of one frame has no measured velocity (elfm_track_velocity_known) */
    if (!ti[i].smoothed || !isfinite(ti[i].mean_vel_um_per_ms[0])) continue;
    const double *v = ti[i].mean_vel_um_per_ms;
    double w = (double)ti[i].n, speed = sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
    const double wp = ti[i].s_tt_ms2 > 0 && isfinite(ti[i].s_tt_ms2) ? ti[i].s_tt_ms2 : 0;
    for (int a = 0; a < 3; a++) {
      m[a] += w * v[a];
      mp[a] += wp * v[a];
      um[a] += v[a];
      uss[a] += v[a] * v[a];
    }
    swp += wp;
    /* ... and by how well its points place it on each axis (elfm_stage_result) */
    const double nr = (double)ti[i].n_res;
    if (wp > 0 && ti[i].n_res >= ELFM_STAGE_POOL_MIN_POINTS)
      for (int a = 0; a < 3; a++) {
        const double var = (ti[i].s_res2_um2[a] - ti[i].s_res_um[a] * ti[i].s_res_um[a] / nr) / (nr - 2);
        if (!isfinite(var)) continue;
        const double wv = wp / fmax(var, ELFM_STAGE_POOL_MIN_VAR_UM2);
        swv[a] += wv;
        mv[a] += wv * v[a];
      }
    sp += speed;
    sp2 += speed * speed;
    sw += w;
    n++;
  }
  if (!n) return elfm_error_set(err, ELFM_ERR_INVALID, NULL, -1, "stage analysis: no smoothed track of more than one frame");
  r->n_tracks = n;
  for (int a = 0; a < 3; a++) {
    r->v_um_per_ms[a] = m[a] / sw;
    r->v_pooled_um_per_ms[a] = swv[a] > 0 ? mv[a] / swv[a] : swp > 0 ? mp[a] / swp : NAN;
    double mu = um[a] / (double)n;
    r->v_sd_um_per_ms[a] = n > 1 ? sqrt(fmax(0, (uss[a] - n * mu * mu) / (double)(n - 1))) : NAN;
  }
  r->speed_um_per_ms = sqrt(r->v_um_per_ms[0] * r->v_um_per_ms[0] +
                            r->v_um_per_ms[1] * r->v_um_per_ms[1] +
                            r->v_um_per_ms[2] * r->v_um_per_ms[2]);
  double msp = sp / (double)n;
  r->speed_sd_um_per_ms = n > 1 ? sqrt(fmax(0, (sp2 - n * msp * msp) / (double)(n - 1))) : NAN;
  stage_accel(ti, nt, r);
  r->rel_error = r->speed_rel_error = r->rel_error_pooled = NAN;
  if (sv) {
    double ns = sqrt(sv[0] * sv[0] + sv[1] * sv[1] + sv[2] * sv[2]);
    if (!(ns > 0) || !isfinite(ns))
      return elfm_error_set(err, ELFM_ERR_INVALID, NULL, -1, "stage analysis: stage velocity is zero or not finite");
    double d2 = 0, dp2 = 0;
    for (int a = 0; a < 3; a++) {
      d2 += pow(r->v_um_per_ms[a] - sv[a], 2);
      dp2 += pow(r->v_pooled_um_per_ms[a] - sv[a], 2);
    }
    r->rel_error = sqrt(d2) / ns;
    r->rel_error_pooled = sqrt(dp2) / ns; /* NaN when the pooled velocity is */
    r->speed_rel_error = (r->speed_um_per_ms - ns) / ns;
  }
  return ELFM_OK;
}

/* Distance (voxels, fractional) from the peak voxel to the half-maximum
 * crossing going in direction `dir` along an axis; -1 if the profile leaves
 * the volume first. */
static double half_crossing(const float *d, size_t ic, ptrdiff_t stride, int pos, int len, int dir,
                            double half)
{
  double prev = d[ic];
  for (int k = 1;; k++) {
    int p = pos + dir * k;
    if (p < 0 || p >= len) return -1;
    double cur = d[(size_t)((ptrdiff_t)ic + dir * k * stride)];
    if (cur <= half) return (k - 1) + (prev - half) / (prev - cur);
    prev = cur;
  }
}

elfm_status elfm_analysis_fwhm(const elfm_volume *v, const elfm_detection *det, int n,
                               double isolation_um, elfm_fwhm *out, int cap, int *n_out,
                               elfm_error *err)
{
  *n_out = 0;
  if (!v || !v->data || (n > 0 && !det) || cap < 0 || (cap > 0 && !out) || !(v->um_per_px > 0) ||
      !(v->z_step_um > 0))
    return elfm_error_set(err, ELFM_ERR_INVALID, NULL, -1, "fwhm: bad arguments");
  int m = 0;
  for (int i = 0; i < n && m < cap; i++) {
    int iso = 1;
    for (int j = 0; j < n && iso; j++) {
      if (j == i) continue;
      double dx = det[i].x_um - det[j].x_um, dy = det[i].y_um - det[j].y_um;
      iso = dx * dx + dy * dy >= isolation_um * isolation_um;
    }
    if (!iso) continue;
    int X = (int)lround(elfm_volume_x_vox(v, det[i].x_um));
    int Y = (int)lround(elfm_volume_y_vox(v, det[i].y_um));
    int K = (int)lround(elfm_volume_z_vox(v, det[i].z_um));
    if (X < 0 || X >= v->w || Y < 0 || Y >= v->h || K < 0 || K >= v->nz) continue;
    size_t ic = ((size_t)K * v->h + Y) * v->w + X;
    double peak = v->data[ic];
    if (!(peak > 0)) continue;
    double half = 0.5 * peak;
    double xl = half_crossing(v->data, ic, 1, X, v->w, -1, half),
           xr = half_crossing(v->data, ic, 1, X, v->w, 1, half),
           yl = half_crossing(v->data, ic, v->w, Y, v->h, -1, half),
           yr = half_crossing(v->data, ic, v->w, Y, v->h, 1, half),
           zl = half_crossing(v->data, ic, (ptrdiff_t)v->w * v->h, K, v->nz, -1, half),
           zr = half_crossing(v->data, ic, (ptrdiff_t)v->w * v->h, K, v->nz, 1, half);
    if (xl < 0 || xr < 0 || yl < 0 || yr < 0 || zl < 0 || zr < 0) continue;
    out[m].x_um = det[i].x_um;
    out[m].y_um = det[i].y_um;
    out[m].z_um = det[i].z_um;
    out[m].fwhm_xy_um = 0.5 * ((xl + xr) + (yl + yr)) * v->um_per_px;
    out[m].fwhm_z_um = (zl + zr) * v->z_step_um;
    m++;
  }
  *n_out = m;
  return ELFM_OK;
}

static int dcmp(const void *a, const void *b)
{
  double x = *(const double *)a, y = *(const double *)b;
  return (x > y) - (x < y);
}

void elfm_analysis_median(double *x, size_t n, double *median, double *spread)
{
  if (!n) {
    *median = *spread = NAN;
    return;
  }
  qsort(x, n, sizeof *x, dcmp);
  double med = n % 2 ? x[n / 2] : 0.5 * (x[n / 2 - 1] + x[n / 2]);
  for (size_t i = 0; i < n; i++) x[i] = fabs(x[i] - med);
  qsort(x, n, sizeof *x, dcmp);
  double mad = n % 2 ? x[n / 2] : 0.5 * (x[n / 2 - 1] + x[n / 2]);
  *median = med;
  *spread = 1.4826 * mad;
}

/* Matches of a + d onto b, each point of b used once; sums the matched
 * displacements and their squares (z / kz) into sum[0..3) and sum[3..6)
 * when sum is not NULL. used: nb flags, cleared here. */
static int shift_matches(const double *a, int na, const double *b, int nb, const double d[3],
                         double tol2, double kz, unsigned char *used, double sum[6])
{
  int m = 0;
  for (int j = 0; j < nb; j++) used[j] = 0;
  for (int i = 0; i < na; i++) {
    const double *p = a + 3 * (size_t)i;
    for (int j = 0; j < nb; j++) {
      if (used[j]) continue;
      const double *q = b + 3 * (size_t)j;
      const double ex = q[0] - p[0] - d[0], ey = q[1] - p[1] - d[1];
      const double ez = (q[2] - p[2] - d[2]) / kz;
      if (ex * ex + ey * ey + ez * ez > tol2) continue;
      used[j] = 1;
      m++;
      if (sum)
        for (int k = 0; k < 3; k++) {
          const double e = (q[k] - p[k]) / (k == 2 ? kz : 1.0);
          sum[k] += q[k] - p[k];
          sum[3 + k] += e * e;
        }
      break;
    }
  }
  return m;
}

static int all_finite(const double *x, int n3)
{
  for (int i = 0; i < n3; i++)
    if (!isfinite(x[i])) return 0;
  return 1;
}

elfm_status elfm_analysis_shift_vote(const double *a_um, int na, const double *b_um, int nb,
                                     double tol_um, double kz, int *n_matched, double d_um[3],
                                     double *rms_um, elfm_error *err)
{
  *n_matched = 0;
  d_um[0] = d_um[1] = d_um[2] = NAN;
  if (rms_um) *rms_um = NAN;
  if (na < 0 || nb < 0 || !(tol_um > 0) || !(kz > 0) || !isfinite(tol_um) || !isfinite(kz))
    return elfm_error_set(err, ELFM_ERR_INVALID, NULL, -1,
                          "shift vote: %d and %d points, tolerance %g um, kz %g", na, nb, tol_um,
                          kz);
  if (!all_finite(a_um, 3 * na) || !all_finite(b_um, 3 * nb))
    return elfm_error_set(err, ELFM_ERR_INVALID, NULL, -1, "shift vote: a point is not finite");
  if (na == 0 || nb == 0) return ELFM_OK;
  unsigned char *used = malloc((size_t)nb);
  if (!used) return elfm_error_set(err, ELFM_ERR_NOMEM, NULL, -1, "shift vote: out of memory");
  const double tol2 = tol_um * tol_um;
  int best = 0, bi = 0, bj = 0;
  for (int i = 0; i < na; i++)
    for (int j = 0; j < nb; j++) {
      const double *p = a_um + 3 * (size_t)i, *q = b_um + 3 * (size_t)j;
      const double d[3] = {q[0] - p[0], q[1] - p[1], q[2] - p[2]};
      const int m = shift_matches(a_um, na, b_um, nb, d, tol2, kz, used, NULL);
      if (m > best) {
        best = m;
        bi = i;
        bj = j;
      }
    }
  const double *p = a_um + 3 * (size_t)bi, *q = b_um + 3 * (size_t)bj;
  const double d[3] = {q[0] - p[0], q[1] - p[1], q[2] - p[2]};
  double sum[6] = {0, 0, 0, 0, 0, 0};
  const int m = shift_matches(a_um, na, b_um, nb, d, tol2, kz, used, sum);
  free(used);
  if (m == 0) return ELFM_OK;
  *n_matched = m;
  double var = 0;
  for (int k = 0; k < 3; k++) {
    d_um[k] = sum[k] / m;
    const double mk = d_um[k] / (k == 2 ? kz : 1.0);
    var += sum[3 + k] / m - mk * mk;
  }
  if (rms_um) *rms_um = sqrt(var > 0 ? var : 0);
  return ELFM_OK;
}
