/* test_analysis.c — FWHM of isolated beads in a synthetic volume (paper
 * widths 3.9 / 21.0 um), the stage velocity from smoothed tracks, and the
 * rigid shift between two frames' points. */
#include <string.h>

#include "check.h"
#include "elfm_tracker.h"

/* A detection of frame f at t0_us + 1 ms x f, its x_um a uniform noise
 * in +-0.1 um drawn from *seed (the caller places it). */
static elfm_detection stage_point(int f, int64_t t0_us, uint64_t *seed)
{
  elfm_detection d;
  memset(&d, 0, sizeof d);
  d.frame = f;
  d.t_us = t0_us + 1000LL * f;
  *seed = *seed * 6364136223846793005ULL + 1442695040888963407ULL;
  d.x_um = ((double)(*seed >> 11) / 9007199254740992.0 - 0.5) * 0.2;
  return d;
}

static void add_blob(elfm_volume *v, double x, double y, double z, double amp, double sxy, double sz)
{
  for (int k = 0; k < v->nz; k++)
    for (int j = 0; j < v->h; j++)
      for (int i = 0; i < v->w; i++) {
        double dx = elfm_volume_x_um(v, i) - x, dy = elfm_volume_y_um(v, j) - y,
               dz = elfm_volume_z_um(v, k) - z;
        double e = (dx * dx + dy * dy) / (2 * sxy * sxy) + dz * dz / (2 * sz * sz);
        if (e < 30) v->data[((size_t)k * v->h + j) * v->w + i] += (float)(amp * exp(-e));
      }
}

static double norm3(const double v[3]) { return sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]); }

/* |v - s| / |s| */
static double rel_dist(const double v[3], const double s[3])
{
  const double d[3] = {v[0] - s[0], v[1] - s[1], v[2] - s[2]};
  return norm3(d) / norm3(s);
}

/* elfm_analysis_shift_vote: one frame's beads moved by one shift (with
 * noise), some missing and some new in the other frame; beads moving each
 * their own way; bad input. */
static void test_shift_vote(void)
{
  elfm_error err;
  elfm_error_clear(&err);
  uint64_t seed = 7;
  double a[12][3], b[14][3], d[3], rms;
  const double shift[3] = {0.3, 17.9, -2.0}; /* a stage's 3 ms at 6 mm/s, a little z */
  for (int i = 0; i < 12; i++) {
    for (int k = 0; k < 3; k++) {
      seed = seed * 6364136223846793005ULL + 1442695040888963407ULL;
      a[i][k] = ((double)(seed >> 11) / 9007199254740992.0 - 0.5) * (k == 2 ? 120 : 100);
    }
  }
  /* b: a's beads 2..11 shifted, +-0.2 um of noise (z +-0.8), in reverse
   * order; beads 0 and 1 left the field; four new ones came in */
  int nb = 0;
  for (int i = 11; i >= 2; i--, nb++)
    for (int k = 0; k < 3; k++) b[nb][k] = a[i][k] + shift[k] + ((i + k) % 3 - 1) * (k == 2 ? 0.8 : 0.2);
  const double fresh[4][3] = {{40, 40, 0}, {-45, 30, 30}, {0, -48, -60}, {10, 5, 70}};
  for (int i = 0; i < 4; i++, nb++)
    for (int k = 0; k < 3; k++) b[nb][k] = fresh[i][k];
  int m = 0;
  CHECK_OK(elfm_analysis_shift_vote(&a[0][0], 12, &b[0][0], nb, 2.0, 4.0, &m, d, &rms, &err), &err);
  CHECK(m == 10);
  for (int k = 0; k < 3; k++) CHECK(fabs(d[k] - shift[k]) < (k == 2 ? 0.4 : 0.1));
  CHECK(rms > 0.05 && rms < 0.4);
  /* the same with b's points shifted back by the vote: d ~ 0 */
  double b0[14][3];
  for (int j = 0; j < nb; j++)
    for (int k = 0; k < 3; k++) b0[j][k] = b[j][k] - d[k];
  double d0[3];
  CHECK_OK(elfm_analysis_shift_vote(&a[0][0], 12, &b0[0][0], nb, 2.0, 4.0, &m, d0, NULL, &err), &err);
  CHECK(m == 10 && fabs(d0[0]) < 1e-9 && fabs(d0[1]) < 1e-9 && fabs(d0[2]) < 1e-9);
  /* each bead its own way (a flow): no shift carries more than a few */
  double c[12][3];
  for (int i = 0; i < 12; i++)
    for (int k = 0; k < 3; k++) c[i][k] = a[i][k] + 3.5 * cos(1.7 * i + 2.1 * k) * (k == 2 ? 2 : 1);
  CHECK_OK(elfm_analysis_shift_vote(&a[0][0], 12, &c[0][0], 12, 2.0, 4.0, &m, d, &rms, &err), &err);
  CHECK(m >= 1 && m <= 4);
  /* a tighter tolerance takes fewer of the noisy matches */
  CHECK_OK(elfm_analysis_shift_vote(&a[0][0], 12, &b[0][0], nb, 0.1, 4.0, &m, d, &rms, &err), &err);
  CHECK(m >= 1 && m < 10);
  /* empty frames: nothing matched, NaN */
  CHECK_OK(elfm_analysis_shift_vote(&a[0][0], 0, &b[0][0], nb, 2.0, 4.0, &m, d, &rms, &err), &err);
  CHECK(m == 0 && isnan(d[0]) && isnan(rms));
  CHECK_OK(elfm_analysis_shift_vote(&a[0][0], 12, NULL, 0, 2.0, 4.0, &m, d, &rms, &err), &err);
  CHECK(m == 0 && isnan(d[1]));
  /* bad input */
  a[3][1] = NAN;
  CHECK(elfm_analysis_shift_vote(&a[0][0], 12, &b[0][0], nb, 2.0, 4.0, &m, d, &rms, &err) ==
        ELFM_ERR_INVALID);
  a[3][1] = 0;
  b[5][2] = INFINITY;
  CHECK(elfm_analysis_shift_vote(&a[0][0], 12, &b[0][0], nb, 2.0, 4.0, &m, d, &rms, &err) ==
        ELFM_ERR_INVALID);
  b[5][2] = 0;
  CHECK(elfm_analysis_shift_vote(&a[0][0], 12, &b[0][0], nb, 0.0, 4.0, &m, d, &rms, &err) ==
        ELFM_ERR_INVALID);
  CHECK(elfm_analysis_shift_vote(&a[0][0], 12, &b[0][0], nb, 2.0, NAN, &m, d, &rms, &err) ==
        ELFM_ERR_INVALID);
  CHECK(elfm_analysis_shift_vote(&a[0][0], -1, &b[0][0], nb, 2.0, 4.0, &m, d, &rms, &err) ==
        ELFM_ERR_INVALID);
  CHECK(m == 0);
}

int main(void)
{
  elfm_error err;
  elfm_error_clear(&err);
  elfm_volume *v = elfm_volume_create(80, 80, 61, 0.926, -60, 2, &err);
  const double fx = 3.9, fz = 21.0;
  /* three isolated beads and a close pair (excluded) */
  const double P[5][3] = {{-20, -20, 0}, {20, -15, 10.5}, {-10, 22, -20}, {15, 20, 0}, {21, 20, 0}};
  for (int b = 0; b < 5; b++) add_blob(v, P[b][0], P[b][1], P[b][2], 100, fx / 2.3548, fz / 2.3548);
  elfm_peaks_options po;
  elfm_peaks_options_default(&po);
  po.k_sigma = 0;
  po.absolute = 10;
  po.min_separation_um = 2;
  po.radius_xy_um = 1.5;
  elfm_peaks *pk = elfm_peaks_create(&po, v->w, v->h, v->nz, &err);
  elfm_detection det[16];
  int n = 0;
  CHECK_OK(elfm_peaks_detect(pk, v, det, 16, &n, &err), &err);
  CHECK_EQ_INT(n, 5);
  elfm_fwhm fw[16];
  int m = 0;
  CHECK_OK(elfm_analysis_fwhm(v, det, n, 8.0, fw, 16, &m, &err), &err);
  CHECK_EQ_INT(m, 3);
  double xy[16], z[16];
  for (int i = 0; i < m; i++) {
    CHECK_NEAR(fw[i].fwhm_xy_um, fx, 0.25);
    CHECK_NEAR(fw[i].fwhm_z_um, fz, 1.0);
    xy[i] = fw[i].fwhm_xy_um;
    z[i] = fw[i].fwhm_z_um;
  }
  double med, spr;
  elfm_analysis_median(xy, (size_t)m, &med, &spr);
  CHECK_NEAR(med, fx, 0.25);
  CHECK(spr >= 0 && spr < 0.3);
  elfm_analysis_median(z, (size_t)m, &med, &spr);
  CHECK_NEAR(med, fz, 1.0);
  /* a wider bead reads wider */
  memset(v->data, 0, sizeof(float) * 80 * 80 * 61);
  add_blob(v, 0, 0, 0, 100, 2 * fx / 2.3548, fz / 2.3548);
  CHECK_OK(elfm_peaks_detect(pk, v, det, 16, &n, &err), &err);
  CHECK_OK(elfm_analysis_fwhm(v, det, n, 8.0, fw, 16, &m, &err), &err);
  CHECK_EQ_INT(m, 1);
  if (m == 1) CHECK_NEAR(fw[0].fwhm_xy_um, 2 * fx, 0.4);
  /* a bead at the edge whose profile leaves the volume is skipped */
  memset(v->data, 0, sizeof(float) * 80 * 80 * 61);
  add_blob(v, 0, 0, -59, 100, fx / 2.3548, fz / 2.3548);
  CHECK_OK(elfm_peaks_detect(pk, v, det, 16, &n, &err), &err);
  CHECK_OK(elfm_analysis_fwhm(v, det, n, 8.0, fw, 16, &m, &err), &err);
  CHECK_EQ_INT(m, 0);
  double e[1];
  elfm_analysis_median(e, 0, &med, &spr);
  CHECK(isnan(med));
  elfm_peaks_free(pk);
  elfm_volume_free(v);

  /* Stage: 5 tracks moving at (0.2, -0.1, 0.05) um/ms with small noise. */
  elfm_track_store s;
  elfm_track_store_init(&s);
  elfm_stage_result r;
  CHECK_EQ_INT(elfm_analysis_stage(&s, NULL, &r, &err), ELFM_ERR_INVALID);
  elfm_smooth_options so;
  elfm_smooth_options_default(&so);
  uint64_t seed = 7;
  for (int k = 0; k < 5; k++) {
    elfm_track *t = elfm_track_create(k, &err);
    for (int f = 0; f < 200; f++) {
      elfm_detection d = stage_point(f, 5000000000LL, &seed);
      const double noise = d.x_um;
      d.x_um = 10 * k + 0.2 * f + noise;
      d.y_um = -0.1 * f;
      d.z_um = 0.05 * f - noise;
      elfm_track_append(t, &d, &err);
    }
    CHECK_OK(elfm_track_smooth(t, &so, &err), &err);
    elfm_track_store_add(&s, t, &err);
  }
  const double sv[3] = {0.2, -0.1, 0.05};
  CHECK_OK(elfm_analysis_stage(&s, sv, &r, &err), &err);
  CHECK_EQ_INT(r.n_tracks, 5);
  CHECK(r.rel_error < 0.01);
  CHECK(fabs(r.speed_rel_error) < 0.01);
  CHECK_NEAR(r.speed_um_per_ms, sqrt(0.04 + 0.01 + 0.0025), 0.003);
  CHECK(r.v_sd_um_per_ms[0] < 0.01);
  /* a wrong stage velocity shows */
  const double sv2[3] = {0.22, -0.1, 0.05};
  CHECK_OK(elfm_analysis_stage(&s, sv2, &r, &err), &err);
  CHECK(r.rel_error > 0.05);
  const double sv0[3] = {0, 0, 0};
  CHECK_EQ_INT(elfm_analysis_stage(&s, sv0, &r, &err), ELFM_ERR_INVALID);
  /* a stage at constant velocity: no acceleration, within the noise */
  for (int a = 0; a < 3; a++) CHECK(fabs(r.accel_um_per_ms2[a]) < 2e-4);
  CHECK(isfinite(r.accel_sd_um_per_ms2[0]));
  /* long tracks alike: the pooled velocity is theirs too */
  CHECK_OK(elfm_analysis_stage(&s, sv, &r, &err), &err);
  CHECK(r.rel_error_pooled < 0.01);
  CHECK(fabs(r.v_pooled_um_per_ms[0] - r.v_um_per_ms[0]) < 1e-3);
  /* Tracks of one frame (a bead in one LED pulse) have no measured
   * velocity: the smoother's static 0 is not averaged in. With 40 such
   * tracks of one point beside the 5 x 200 points it would pull the mean
   * by 40 / 1040 = 3.8 %. */
  {
    const double rel_before = r.rel_error;
    uint64_t seed1 = 11; /* its own: the cases below draw from seed */
    for (int k = 0; k < 40; k++) {
      elfm_track *t = elfm_track_create(100 + k, &err);
      elfm_detection d = stage_point(50 + k, 5000000000LL, &seed1);
      d.x_um = 3.0 * k;
      CHECK_OK(elfm_track_append(t, &d, &err), &err);
      CHECK_OK(elfm_track_smooth(t, &so, &err), &err);
      CHECK(!elfm_track_velocity_known(t));
      elfm_track_store_add(&s, t, &err);
    }
    CHECK_OK(elfm_analysis_stage(&s, sv, &r, &err), &err);
    CHECK_EQ_INT(r.n_tracks, 5);
    CHECK_NEAR(r.rel_error, rel_before, 1e-12);
    for (int a = 0; a < 3; a++) CHECK(fabs(r.accel_um_per_ms2[a]) < 2e-4);
    /* ... and alone they are no stage */
    elfm_track_store one;
    elfm_track_store_init(&one);
    elfm_track *t = elfm_track_create(200, &err);
    elfm_detection d = stage_point(3, 5000000000LL, &seed1);
    CHECK_OK(elfm_track_append(t, &d, &err), &err);
    CHECK_OK(elfm_track_smooth(t, &so, &err), &err);
    elfm_track_store_add(&one, t, &err);
    CHECK_EQ_INT(elfm_analysis_stage(&one, sv, &r, &err), ELFM_ERR_INVALID);
    elfm_track_store_clear(&one);
    /* the 40 out again: the store as the cases below expect it */
    while (s.n > 5) elfm_track_free(s.tracks[--s.n]);
  }

  /* A slow stage with a short, biased track (a bead crossing the field
   * stop's edge: 25 points whose image moves 60 % faster than the stage,
   * as on stage 0.2 mm/s seed 26): by points it pulls the mean by 2.6 %,
   * by its time spread the pooled velocity hardly moves. */
  {
    elfm_track *t = elfm_track_create(5, &err);
    for (int f = 60; f < 85; f++) {
      elfm_detection d = stage_point(f, 5000000000LL, &seed);
      const double noise = d.x_um;
      d.x_um = 60 + 0.32 * f + noise;
      d.y_um = -0.16 * f;
      d.z_um = 0.08 * f - noise;
      elfm_track_append(t, &d, &err);
    }
    CHECK_OK(elfm_track_smooth(t, &so, &err), &err);
    elfm_track_store_add(&s, t, &err);
  }
  CHECK_OK(elfm_analysis_stage(&s, sv, &r, &err), &err);
  CHECK_EQ_INT(r.n_tracks, 6);
  CHECK_MSG(r.rel_error > 0.01, "by points %g", r.rel_error);
  CHECK_MSG(r.rel_error_pooled < 0.003, "pooled %g", r.rel_error_pooled);
  CHECK(r.v_pooled_um_per_ms[0] < r.v_um_per_ms[0]);
  /* each error is its velocity's distance from the stage's over the
   * stage's speed (the bounds above alone pass a squared distance too) */
  CHECK_NEAR(r.rel_error, rel_dist(r.v_um_per_ms, sv), 1e-12);
  CHECK_NEAR(r.rel_error_pooled, rel_dist(r.v_pooled_um_per_ms, sv), 1e-12);
  CHECK_NEAR(r.speed_rel_error, r.speed_um_per_ms / norm3(sv) - 1, 1e-12);
  /* no given velocity: no errors, the pooled velocity still */
  CHECK_OK(elfm_analysis_stage(&s, NULL, &r, &err), &err);
  CHECK(isnan(r.rel_error_pooled) && isfinite(r.v_pooled_um_per_ms[1]));
  elfm_track_store_clear(&s);

  /* Each axis weighed by how well the track's points place it: two tracks
   * over the same frames, one of a bead in focus (z scatter 0.1 um), one
   * of a deep bead whose z points scatter 3 um and drift (its z velocity
   * 0.03 um/ms off, as a bead at |z| 70-87 um on a slow stage's long
   * windows). By the time spread alone each counts half on z (0.065
   * um/ms against the stage's 0.05); by its scatter too the deep one's z
   * hardly counts. x and y, placed alike by both, stay the mean of the two. */
  for (int k = 0; k < 2; k++) {
    elfm_track *t = elfm_track_create(k, &err);
    for (int f = 0; f < 100; f++) {
      elfm_detection d = stage_point(f, 5000000000LL, &seed);
      const double noise = d.x_um; /* +-0.1 um */
      d.x_um = 10 * k + 0.2 * f + noise;
      d.y_um = -0.1 * f - noise;
      d.z_um = k == 0 ? 0.05 * f + noise : -70 + 0.08 * f + 30 * noise * ((f % 2) ? 1 : -1);
      elfm_track_append(t, &d, &err);
    }
    CHECK_OK(elfm_track_smooth(t, &so, &err), &err);
    elfm_track_store_add(&s, t, &err);
  }
  CHECK_OK(elfm_analysis_stage(&s, sv, &r, &err), &err);
  CHECK_MSG(fabs(r.v_pooled_um_per_ms[2] - 0.05) < 0.003, "pooled vz %g, not 0.05", r.v_pooled_um_per_ms[2]);
  CHECK_MSG(fabs(r.v_um_per_ms[2] - 0.065) < 0.005, "by points vz %g, not 0.065", r.v_um_per_ms[2]);
  CHECK(fabs(r.v_pooled_um_per_ms[0] - 0.2) < 0.002 && fabs(r.v_pooled_um_per_ms[1] + 0.1) < 0.002);
  CHECK_MSG(r.rel_error_pooled < 0.02, "pooled error %g", r.rel_error_pooled);
  /* with fewer than ELFM_STAGE_POOL_MIN_POINTS real points per track, the
   * time spread alone weighs, as before */
  {
    elfm_track_info ti2[2];
    for (int k = 0; k < 2; k++) {
      elfm_track_info_get(s.tracks[k], &ti2[k]);
      ti2[k].n_res = ELFM_STAGE_POOL_MIN_POINTS - 1;
    }
    CHECK_OK(elfm_analysis_stage_info(ti2, 2, sv, &r, &err), &err);
    CHECK_MSG(fabs(r.v_pooled_um_per_ms[2] - 0.065) < 0.005, "spread-pooled vz %g", r.v_pooled_um_per_ms[2]);
  }
  elfm_track_store_clear(&s);

  /* An accelerating stage: v_y = 0.1 + 0.003 t um/ms (t in ms), beads in
   * view over different 60-120 ms stretches of a 400 ms ramp, at absolute
   * times near 1e12 us. Each track alone spans little of the ramp; pooled
   * over all rows the slope is the stage's acceleration. */
  for (int k = 0; k < 6; k++) {
    elfm_track *t = elfm_track_create(k, &err);
    const int f0 = 50 * k, nf = 60 + 12 * k;
    for (int f = f0; f < f0 + nf; f++) {
      elfm_detection d = stage_point(f, 1000000000000LL, &seed);
      const double noise = d.x_um;
      d.x_um = 7 * k + noise;
      d.y_um = 0.1 * f + 0.0015 * f * f - noise;
      d.z_um = 3 * k;
      elfm_track_append(t, &d, &err);
    }
    CHECK_OK(elfm_track_smooth(t, &so, &err), &err);
    elfm_track_store_add(&s, t, &err);
  }
  CHECK_OK(elfm_analysis_stage(&s, NULL, &r, &err), &err);
  CHECK_MSG(fabs(r.accel_um_per_ms2[1] - 0.003) < 0.003 * 0.02, "acceleration %g, not 0.003",
            r.accel_um_per_ms2[1]);
  CHECK(fabs(r.accel_um_per_ms2[0]) < 2e-4 && fabs(r.accel_um_per_ms2[2]) < 2e-4);
  CHECK(r.accel_sd_um_per_ms2[1] >= 0 && r.accel_sd_um_per_ms2[1] < 0.003);
  /* one track: no spread across tracks; one row: no slope */
  elfm_track_info one;
  elfm_track_info_get(s.tracks[0], &one);
  CHECK_OK(elfm_analysis_stage_info(&one, 1, NULL, &r, &err), &err);
  CHECK(isfinite(r.accel_um_per_ms2[1]) && isnan(r.accel_sd_um_per_ms2[1]));
  one.n_rows = 1;
  one.s_tt_ms2 = 0;
  CHECK_OK(elfm_analysis_stage_info(&one, 1, NULL, &r, &err), &err);
  CHECK(isnan(r.accel_um_per_ms2[1]));
  CHECK(isnan(r.v_pooled_um_per_ms[1]) && isfinite(r.v_um_per_ms[1])); /* no time spread */
  elfm_track_store_clear(&s);
  test_shift_vote();
  return check_report();
}
