/* test_peaks.c — 3D peak detector on synthetic volumes with known blobs:
 * positions (sub-voxel), widths, thresholds, separation, bad input, and the
 * time-surface lag correction. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "check.h"
#include "elfm_tracker.h"

/* Paper resolution: FWHM 3.9 um lateral, 21.0 um axial -> Gaussian sigmas. */
#define SXY (3.9 / 2.3548)
#define SZ (21.0 / 2.3548)

static void add_blob(elfm_volume *v, double x, double y, double z, double amp, double sxy, double sz)
{
  for (int k = 0; k < v->nz; k++)
    for (int j = 0; j < v->h; j++)
      for (int i = 0; i < v->w; i++) {
        double dx = elfm_volume_x_um(v, i) - x, dy = elfm_volume_y_um(v, j) - y,
               dz = elfm_volume_z_um(v, k) - z;
        double e = dx * dx / (2 * sxy * sxy) + dy * dy / (2 * sxy * sxy) + dz * dz / (2 * sz * sz);
        if (e < 30) v->data[((size_t)k * v->h + j) * v->w + i] += (float)(amp * exp(-e));
      }
}

/* deterministic uniform noise in [-a, a] (xorshift) */
static void add_noise(elfm_volume *v, double a, uint64_t seed)
{
  size_t n = (size_t)v->w * v->h * v->nz;
  for (size_t i = 0; i < n; i++) {
    seed ^= seed << 13; seed ^= seed >> 7; seed ^= seed << 17;
    v->data[i] += (float)(a * ((double)(seed >> 11) / 9007199254740992.0 * 2 - 1));
  }
}

static const elfm_detection *nearest(const elfm_detection *d, int n, double x, double y, double z)
{
  const elfm_detection *best = NULL;
  double bd = 1e300;
  for (int i = 0; i < n; i++) {
    double e = pow(d[i].x_um - x, 2) + pow(d[i].y_um - y, 2) + pow((d[i].z_um - z) / 4, 2);
    if (e < bd) { bd = e; best = &d[i]; }
  }
  return best;
}

static int cmp_float(const void *a, const void *b)
{
  const float x = *(const float *)a, y = *(const float *)b;
  return (x > y) - (x < y);
}

/* The k-sigma rule's median and MAD exactly: a volume small enough that
 * the noise sample is every voxel, values with many ties, negatives,
 * zeros of both signs and, in the last case, mostly zeros (then only the
 * non-zero voxels are sampled). The threshold must be median + k x 1.4826
 * x MAD to the last bit of the floats, as from a full sort; a selection
 * off by one rank moves it by a step of the values. */
static void test_noise_exact(void)
{
  const int dims[3][3] = {{16, 16, 16}, {15, 15, 15}, {20, 17, 9}};
  for (int c = 0; c < 4; c++) {
    const int *dm = dims[c % 3];
    const size_t nvox = (size_t)dm[0] * dm[1] * dm[2];
    elfm_error err;
    elfm_error_clear(&err);
    elfm_volume *v = elfm_volume_create(dm[0], dm[1], dm[2], 1.0, -10, 2, &err);
    float *s = malloc(nvox * sizeof *s);
    CHECK(v != NULL && s != NULL);
    if (!v || !s) {
      free(s);
      elfm_volume_free(v);
      return;
    }
    uint64_t sd = 4242 + (uint64_t)c;
    size_t ns = 0, nz = 0;
    for (size_t i = 0; i < nvox; i++) {
      sd ^= sd << 13; sd ^= sd >> 7; sd ^= sd << 17;
      const unsigned r = (unsigned)(sd >> 40) % 100;
      float x;
      const float u = (float)((double)(sd >> 11) / 9007199254740992.0 * 40.0 - 5.0);
      if (c == 3) x = r < 80 ? 0.0f : u;                  /* mostly zeros */
      else if (r < 10) x = 0.0f;
      else if (r < 15) x = -0.0f;
      else if (r < 35) x = (float)((int)(r % 11) - 3);      /* ties, negatives */
      else x = u;
      v->data[i] = x;
      if (x != 0) nz++;
    }
    const int nonzero_only = nz * 2 < nvox;
    for (size_t i = 0; i < nvox; i++)
      if (!nonzero_only || v->data[i] != 0) s[ns++] = v->data[i];
    qsort(s, ns, sizeof *s, cmp_float);
    const float med = s[ns / 2];
    for (size_t i = 0; i < ns; i++) s[i] = fabsf(s[i] - med);
    qsort(s, ns, sizeof *s, cmp_float);
    const double want = (double)med + 6.0 * (1.4826 * (double)s[ns / 2]);
    elfm_peaks_options o;
    elfm_peaks_options_default(&o);
    o.k_sigma = 6;
    elfm_peaks *pk = elfm_peaks_create(&o, v->w, v->h, v->nz, &err);
    elfm_detection det[64];
    int n = 0;
    CHECK_OK(elfm_peaks_detect(pk, v, det, 64, &n, &err), &err);
    CHECK_MSG(elfm_peaks_last_threshold(pk) == want, "case %d: threshold %.9g, sorted %.9g (%zu samples)",
              c, elfm_peaks_last_threshold(pk), want, ns);
    elfm_peaks_free(pk);
    free(s);
    elfm_volume_free(v);
  }
}

/* A lone bright voxel at every column of an odd-width volume, with a
 * dimmer one after it (a slope voxel above the threshold; before it in the
 * last column): the candidate search marks a row's voxels above the
 * threshold and skips eight at a time where none is, so each column, the
 * first after eight empty ones and the row's last ones included, must
 * still be found, and only the peak. */
static void test_every_column(void)
{
  elfm_error err;
  const int W = 37, H = 5, NZ = 3;
  elfm_volume *v = elfm_volume_create(W, H, NZ, 1.0, 0, 4, &err);
  elfm_peaks_options o;
  elfm_peaks_options_default(&o);
  o.k_sigma = 0;
  o.absolute = 10;
  o.min_separation_um = 0;
  o.radius_xy_um = 1;
  o.radius_z_um = 1;
  elfm_peaks *pk = v ? elfm_peaks_create(&o, W, H, NZ, &err) : NULL;
  CHECK(pk != NULL);
  if (!pk) {
    elfm_volume_free(v);
    return;
  }
  elfm_detection det[8];
  int bad = 0;
  for (int x = 0; x < W; x++) {
    memset(v->data, 0, (size_t)W * H * NZ * sizeof *v->data);
    float *row = v->data + ((size_t)1 * H + 2) * W;
    row[x] = 100;
    row[x + 1 < W ? x + 1 : x - 1] = 50;
    int n = 0;
    CHECK_OK(elfm_peaks_detect(pk, v, det, 8, &n, &err), &err);
    if (n != 1 || fabs(det[0].x_um - elfm_volume_x_um(v, x)) > 0.5) {
      if (bad++ < 3) fprintf(stderr, "column %d: %d peaks\n", x, n);
    }
  }
  CHECK_EQ_INT(bad, 0);
  elfm_peaks_free(pk);
  elfm_volume_free(v);
}

int main(void)
{
  test_every_column();
  elfm_error err;
  elfm_error_clear(&err);
  elfm_volume *v = elfm_volume_create(64, 60, 51, 0.926, -50, 2, &err);
  CHECK(v != NULL);
  if (!v) return check_report();
  v->frame = 7;
  v->t_us = 1000000000123LL;
  const double P[4][3] = {{-10.3, 5.21, -12.7}, {12.44, -8.9, 20.3}, {0.37, 14.1, 3.1}, {-15.0, -15.0, 30.0}};
  for (int b = 0; b < 4; b++) add_blob(v, P[b][0], P[b][1], P[b][2], 100 + 20 * b, SXY, SZ);

  elfm_peaks_options o;
  elfm_peaks_options_default(&o);
  elfm_peaks *pk = elfm_peaks_create(&o, v->w, v->h, v->nz, &err);
  CHECK(pk != NULL);
  elfm_detection det[16];
  int n = 0;
  /* noiseless: the k-sigma rule sees mostly-nonzero tails; use an absolute threshold */
  o.k_sigma = 0;
  o.absolute = 10;
  elfm_peaks_free(pk);
  pk = elfm_peaks_create(&o, v->w, v->h, v->nz, &err);
  CHECK_OK(elfm_peaks_detect(pk, v, det, 16, &n, &err), &err);
  CHECK_EQ_INT(n, 4);
  for (int b = 0; b < 4; b++) {
    const elfm_detection *d = nearest(det, n, P[b][0], P[b][1], P[b][2]);
    CHECK(d != NULL);
    if (!d) continue;
    /* Gaussian refinement is exact for a Gaussian: tiny errors only */
    CHECK_NEAR(d->x_um, P[b][0], 0.02);
    CHECK_NEAR(d->y_um, P[b][1], 0.02);
    CHECK_NEAR(d->z_um, P[b][2], 0.1);
    CHECK_NEAR(d->sigma_x_um, SXY, 0.05);
    CHECK_NEAR(d->sigma_z_um, SZ, 0.3);
    CHECK_NEAR(d->intensity, 100 + 20 * b, 1.0);
    CHECK_EQ_INT(d->frame, 7);
    CHECK(d->t_us == 1000000000123LL);
  }
  /* strongest first */
  for (int i = 1; i < n; i++) CHECK(det[i - 1].intensity >= det[i].intensity - 1e-9);

  /* Quadratic refinement: biased but within a quarter voxel; no refinement:
   * on voxel centres (error up to half a voxel). */
  double err_q = 0, err_none = 0;
  for (int mode = ELFM_REFINE_QUADRATIC; mode <= ELFM_REFINE_NONE; mode++) {
    o.refine = (elfm_refine_mode)mode;
    elfm_peaks *pq = elfm_peaks_create(&o, v->w, v->h, v->nz, &err);
    CHECK_OK(elfm_peaks_detect(pq, v, det, 16, &n, &err), &err);
    CHECK_EQ_INT(n, 4);
    for (int b = 0; b < 4; b++) {
      const elfm_detection *d = nearest(det, n, P[b][0], P[b][1], P[b][2]);
      double e = fabs(d->x_um - P[b][0]) + fabs(d->y_um - P[b][1]);
      if (mode == ELFM_REFINE_QUADRATIC) err_q += e; else err_none += e;
    }
    elfm_peaks_free(pq);
  }
  CHECK_MSG(err_q < 8 * 0.25 * 0.926, "quadratic total error %g", err_q);
  CHECK_MSG(err_q < err_none, "quadratic %g should beat voxel centres %g", err_q, err_none);
  o.refine = ELFM_REFINE_GAUSSIAN;

  /* cap: only the strongest are kept */
  CHECK_OK(elfm_peaks_detect(pk, v, det, 2, &n, &err), &err);
  CHECK_EQ_INT(n, 2);
  CHECK_NEAR(det[0].intensity, 160, 1.0);
  CHECK_NEAR(det[1].intensity, 140, 1.0);

  /* relative threshold: 0.8 of the voxel max (~157) keeps the 140 and 160 blobs */
  o.absolute = 0;
  o.relative = 0.8;
  elfm_peaks_free(pk);
  pk = elfm_peaks_create(&o, v->w, v->h, v->nz, &err);
  CHECK_OK(elfm_peaks_detect(pk, v, det, 16, &n, &err), &err);
  CHECK_EQ_INT(n, 2);

  /* k-sigma threshold on a noisy volume: all 4 blobs, no noise peaks. */
  add_noise(v, 3.0, 12345);
  o.relative = 0;
  o.k_sigma = 6;
  elfm_peaks_free(pk);
  pk = elfm_peaks_create(&o, v->w, v->h, v->nz, &err);
  CHECK_OK(elfm_peaks_detect(pk, v, det, 16, &n, &err), &err);
  CHECK_EQ_INT(n, 4);
  double thr = elfm_peaks_last_threshold(pk);
  /* uniform noise in [-3,3] has sigma sqrt(3) ~1.73; the blob tails add a little */
  CHECK_MSG(thr > 6 && thr < 40, "threshold %g", thr);
  for (int b = 0; b < 4; b++) {
    const elfm_detection *d = nearest(det, n, P[b][0], P[b][1], P[b][2]);
    CHECK_NEAR(d->x_um, P[b][0], 0.15);
    CHECK_NEAR(d->z_um, P[b][2], 1.5);
  }
  /* without a threshold the noise gives many more peaks: the threshold matters */
  o.k_sigma = 0;
  elfm_peaks_free(pk);
  pk = elfm_peaks_create(&o, v->w, v->h, v->nz, &err);
  CHECK_OK(elfm_peaks_detect(pk, v, det, 16, &n, &err), &err);
  CHECK(n > 4);

  /* Minimum separation: two blobs 3 um apart laterally -> one peak with
   * separation 4 um (and a radius small enough that both are local maxima),
   * two with separation 2 um. */
  memset(v->data, 0, sizeof(float) * 64 * 60 * 51);
  add_blob(v, -1.5, 0, 0, 100, 0.7, SZ);
  add_blob(v, 1.5, 0, 0, 90, 0.7, SZ);
  o.absolute = 5;
  o.radius_xy_um = 1.0;
  o.min_separation_um = 4.0;
  elfm_peaks_free(pk);
  pk = elfm_peaks_create(&o, v->w, v->h, v->nz, &err);
  CHECK_OK(elfm_peaks_detect(pk, v, det, 16, &n, &err), &err);
  CHECK_EQ_INT(n, 1);
  o.min_separation_um = 2.0;
  elfm_peaks_free(pk);
  pk = elfm_peaks_create(&o, v->w, v->h, v->nz, &err);
  CHECK_OK(elfm_peaks_detect(pk, v, det, 16, &n, &err), &err);
  CHECK_EQ_INT(n, 2);

  /* A flat plateau gives exactly one peak. */
  memset(v->data, 0, sizeof(float) * 64 * 60 * 51);
  for (int k = 20; k < 23; k++)
    for (int j = 30; j < 32; j++)
      for (int i = 10; i < 12; i++) v->data[((size_t)k * 60 + j) * 64 + i] = 50;
  CHECK_OK(elfm_peaks_detect(pk, v, det, 16, &n, &err), &err);
  CHECK_EQ_INT(n, 1);
  /* ... also with no least separation to merge its 12 voxels: of equal
   * values, only the first in memory order is a maximum */
  {
    elfm_peaks_options o0 = o;
    o0.min_separation_um = 0;
    elfm_peaks *p0 = elfm_peaks_create(&o0, v->w, v->h, v->nz, &err);
    CHECK(p0 != NULL);
    if (p0) {
      CHECK_OK(elfm_peaks_detect(p0, v, det, 16, &n, &err), &err);
      CHECK_EQ_INT(n, 1);
      elfm_peaks_free(p0);
    }
  }

  /* Depth-dependent threshold (elfm_peaks.h): a faint blob at z = 40 um
   * (amplitude 30) is below the absolute 50 but above 50 / (1 + (40/40)^2)
   * = 25; one of amplitude 20 is below that and above the floor 15 only
   * deeper, at z = -48 (50 / 2.44 = 20.5 -> missed, the floor is 15). */
  memset(v->data, 0, sizeof(float) * 64 * 60 * 51);
  add_blob(v, 5, 5, 40, 30, SXY, SZ);
  add_blob(v, -12, -10, 0, 30, SXY, SZ);   /* same amplitude in focus: below 50 */
  add_blob(v, 12, -10, -48, 20, SXY, SZ);
  {
    elfm_peaks_options od = o;
    od.absolute = 50;
    od.radius_xy_um = 3;
    od.min_separation_um = 4;
    elfm_peaks *pd = elfm_peaks_create(&od, v->w, v->h, v->nz, &err);
    CHECK_OK(elfm_peaks_detect(pd, v, det, 16, &n, &err), &err);
    CHECK_EQ_INT(n, 0);                     /* rule off: nothing above 50 */
    elfm_peaks_free(pd);
    od.depth_range_um = 40;
    od.absolute_min = 15;
    pd = elfm_peaks_create(&od, v->w, v->h, v->nz, &err);
    CHECK_OK(elfm_peaks_detect(pd, v, det, 16, &n, &err), &err);
    CHECK_EQ_INT(n, 1);
    if (n == 1) CHECK_NEAR(det[0].z_um, 40, 0.5);
    /* it is in only by the depth scaling: deep_only (track's view test) */
    if (n == 1) CHECK_EQ_INT(det[0].deep_only, 1);
    /* a blob the plain threshold lets in is not deep_only, at any depth */
    add_blob(v, -20, 15, 30, 80, SXY, SZ);
    CHECK_OK(elfm_peaks_detect(pd, v, det, 16, &n, &err), &err);
    CHECK_EQ_INT(n, 2);
    for (int i = 0; i < n; i++)
      CHECK_EQ_INT(det[i].deep_only, det[i].z_um > 35 && det[i].x_um > 0);
    add_blob(v, -20, 15, 30, -80, SXY, SZ);
    /* floor above the scaled value: z = 40 needs 26 > 25 */
    elfm_peaks_free(pd);
    od.absolute_min = 31;
    pd = elfm_peaks_create(&od, v->w, v->h, v->nz, &err);
    CHECK_OK(elfm_peaks_detect(pd, v, det, 16, &n, &err), &err);
    CHECK_EQ_INT(n, 0);
    elfm_peaks_free(pd);
    od.depth_range_um = -1;
    CHECK(elfm_peaks_create(&od, v->w, v->h, v->nz, &err) == NULL);
  }

  /* View counts (elfm_peaks_set_view_counts): two blobs of 80 over a
   * threshold of 50; where 10 of 25 views sample, the threshold becomes
   * 50 x 25/10 = 125 and that blob goes; where 20 do, 62.5: it stays; a
   * voxel no view samples never gives a peak. */
  memset(v->data, 0, sizeof(float) * 64 * 60 * 51);
  add_blob(v, -15, 0, 0, 80, SXY, SZ);
  add_blob(v, 15, 0, 0, 80, SXY, SZ);
  add_blob(v, 0, 20, -30, 200, SXY, SZ);
  {
    elfm_peaks_options ov = o;
    ov.absolute = 50;
    ov.radius_xy_um = 3;
    ov.min_separation_um = 4;
    elfm_peaks *pv = elfm_peaks_create(&ov, v->w, v->h, v->nz, &err);
    CHECK_OK(elfm_peaks_detect(pv, v, det, 16, &n, &err), &err);
    CHECK_EQ_INT(n, 3);
    size_t nvox = (size_t)64 * 60 * 51;
    uint8_t *cnt = malloc(nvox);
    for (size_t i = 0; i < nvox; i++) {
      int X = (int)(i % 64), Y = (int)(i / 64 % 60);
      cnt[i] = Y > 45 ? 0 : X < 32 ? 10 : 20;
    }
    CHECK_OK(elfm_peaks_set_view_counts(pv, cnt, 25, 1.0, &err), &err);
    memset(cnt, 0, nvox);                   /* copied: the caller's array may go */
    CHECK_OK(elfm_peaks_detect(pv, v, det, 16, &n, &err), &err);
    CHECK_EQ_INT(n, 1);
    if (n == 1) CHECK_NEAR(det[0].x_um, 15, 0.1);
    CHECK_EQ_INT(elfm_peaks_set_view_counts(pv, cnt, 0, 1.0, &err), ELFM_ERR_INVALID);
    CHECK_OK(elfm_peaks_set_view_counts(pv, NULL, 0, 1.0, &err), &err);   /* off again */
    CHECK_OK(elfm_peaks_detect(pv, v, det, 16, &n, &err), &err);
    CHECK_EQ_INT(n, 3);
    free(cnt);
    elfm_peaks_free(pv);
  }

  /* A single bright voxel at the end of the last row (the row-maximum
   * skip must still see it) and one at the very first voxel. */
  memset(v->data, 0, sizeof(float) * 64 * 60 * 51);
  v->data[(size_t)64 * 60 * 51 - 1] = 500;
  v->data[0] = 400;
  CHECK_OK(elfm_peaks_detect(pk, v, det, 16, &n, &err), &err);
  CHECK_EQ_INT(n, 2);

  /* Leading-edge term: a detection of width 2 um along x (sigma_x), moving
   * slowly along +x (trail 0.001 um: lag ~ its length), moves back by
   * 0.7 x 2 um; along y it uses sigma_y; with lead 0 nothing but the lag. */
  {
    elfm_detection dl;
    memset(&dl, 0, sizeof dl);
    dl.sigma_x_um = 2.0;
    dl.sigma_y_um = 1.0;
    dl.sigma_z_um = 8.0;
    elfm_detection_correct_lag_lead(&dl, 0.001, 0, 0, 1000, 0.7);
    CHECK_NEAR(dl.x_um, 0.001 - 1.4, 1e-3);
    CHECK_NEAR(dl.y_um, 0, 1e-12);
    dl.x_um = dl.y_um = dl.z_um = 0;
    elfm_detection_correct_lag_lead(&dl, 0, -0.001, 0, 1000, 0.7);
    CHECK_NEAR(dl.y_um, -(0.001 - 0.7), 1e-3);
    dl.x_um = dl.y_um = dl.z_um = 0;
    elfm_detection_correct_lag_lead(&dl, 0.001, 0, 0, 1000, 0);
    CHECK_NEAR(dl.x_um, 0.001, 1e-4);
  }

  /* Threshold = max of the rules. Non-negative noise in [0, 4]: median ~2,
   * MAD ~1, so 6 sigma gives ~2 + 6 x 1.48 = 10.9; with an absolute 8 the
   * noise rule wins, with an absolute 30 the absolute one. */
  memset(v->data, 0, sizeof(float) * 64 * 60 * 51);
  {
    uint64_t sd = 777;
    for (size_t i = 0; i < (size_t)64 * 60 * 51; i++) {
      sd ^= sd << 13; sd ^= sd >> 7; sd ^= sd << 17;
      v->data[i] = (float)(4.0 * (double)(sd >> 11) / 9007199254740992.0);
    }
    elfm_peaks_options on = o;
    on.k_sigma = 6;
    on.relative = 0;
    on.absolute = 0;
    elfm_peaks *pn = elfm_peaks_create(&on, v->w, v->h, v->nz, &err);
    CHECK_OK(elfm_peaks_detect(pn, v, det, 16, &n, &err), &err);
    double t_noise = elfm_peaks_last_threshold(pn);
    CHECK_MSG(t_noise > 9 && t_noise < 13, "noise threshold %g", t_noise);
    elfm_peaks_free(pn);
    on.absolute = 8;
    pn = elfm_peaks_create(&on, v->w, v->h, v->nz, &err);
    CHECK_OK(elfm_peaks_detect(pn, v, det, 16, &n, &err), &err);
    CHECK_NEAR(elfm_peaks_last_threshold(pn), t_noise, 1e-9);
    elfm_peaks_free(pn);
    on.absolute = 30;
    pn = elfm_peaks_create(&on, v->w, v->h, v->nz, &err);
    CHECK_OK(elfm_peaks_detect(pn, v, det, 16, &n, &err), &err);
    CHECK_NEAR(elfm_peaks_last_threshold(pn), 30, 1e-12);
    CHECK_EQ_INT(n, 0);
    elfm_peaks_free(pn);
  }

  /* Hysteresis: blobs of 80 and 40 over a threshold of 50 with a low one of
   * 30: both found, the second marked weak; without it only the first. */
  memset(v->data, 0, sizeof(float) * 64 * 60 * 51);
  add_blob(v, -12, 0, 0, 80, SXY, SZ);
  add_blob(v, 12, 0, 0, 40, SXY, SZ);
  {
    elfm_peaks_options oh = o;
    oh.absolute = 50;
    oh.radius_xy_um = 3;
    oh.min_separation_um = 4;
    elfm_peaks *ph = elfm_peaks_create(&oh, v->w, v->h, v->nz, &err);
    CHECK_OK(elfm_peaks_detect(ph, v, det, 16, &n, &err), &err);
    CHECK_EQ_INT(n, 1);
    if (n == 1) CHECK_EQ_INT(det[0].weak, 0);
    elfm_peaks_free(ph);
    oh.hysteresis_low = 30;
    ph = elfm_peaks_create(&oh, v->w, v->h, v->nz, &err);
    CHECK_OK(elfm_peaks_detect(ph, v, det, 16, &n, &err), &err);
    CHECK_EQ_INT(n, 2);
    if (n == 2) {
      CHECK_EQ_INT(det[0].weak, 0);
      CHECK_NEAR(det[0].x_um, -12, 0.1);
      CHECK_EQ_INT(det[1].weak, 1);
      CHECK_NEAR(det[1].x_um, 12, 0.1);
    }
    CHECK_NEAR(elfm_peaks_last_threshold(ph), 50, 1e-12);
    elfm_peaks_free(ph);
    oh.hysteresis_low = -1;
    CHECK(elfm_peaks_create(&oh, v->w, v->h, v->nz, &err) == NULL);
  }

  /* Track-guided search: a faint blob (amplitude 30) the detector misses
   * at threshold 50 is found near a prediction 1 um off, weak, at the blob;
   * not from 8 um away with a 3 um radius, not above its height, and the
   * bright blob beside it does not capture the search. */
  {
    memset(v->data, 0, sizeof(float) * 64 * 60 * 51);
    const double F[3] = {-6.1, 4.3, -20.5};
    add_blob(v, F[0], F[1], F[2], 30, SXY, SZ);
    add_blob(v, 10.0, -10.0, 10.0, 150, SXY, SZ);
    elfm_peaks_options og = o;
    og.absolute = 50;
    elfm_peaks *pg = elfm_peaks_create(&og, v->w, v->h, v->nz, &err);
    CHECK(pg != NULL);
    int ng = 0, found = 0;
    CHECK_OK(elfm_peaks_detect(pg, v, det, 16, &ng, &err), &err);
    CHECK_EQ_INT(ng, 1);  /* only the bright blob */
    elfm_detection g;
    const double q[3] = {F[0] + 0.8, F[1] - 0.6, F[2] + 2.0};
    CHECK_OK(elfm_peaks_find_near(pg, v, q, 3.0, 6.0, 20, &g, &found, &err), &err);
    CHECK_EQ_INT(found, 1);
    if (found) {
      CHECK(g.weak == 1);
      CHECK_NEAR(g.x_um, F[0], 0.1);
      CHECK_NEAR(g.y_um, F[1], 0.1);
      CHECK_NEAR(g.z_um, F[2], 0.5);
      CHECK(g.frame == v->frame && g.t_us == v->t_us);
    }
    const double far[3] = {F[0] + 8.0, F[1], F[2]};
    CHECK_OK(elfm_peaks_find_near(pg, v, far, 3.0, 6.0, 20, &g, &found, &err), &err);
    CHECK_EQ_INT(found, 0);  /* only the blob's slope is within reach: no maximum */
    CHECK_OK(elfm_peaks_find_near(pg, v, q, 3.0, 6.0, 31, &g, &found, &err), &err);
    CHECK_EQ_INT(found, 0);
    const double out_q[3] = {500, 0, 0};
    CHECK_OK(elfm_peaks_find_near(pg, v, out_q, 3.0, 6.0, 1, &g, &found, &err), &err);
    CHECK_EQ_INT(found, 0);
    CHECK_EQ_INT(elfm_peaks_find_near(pg, v, q, -1, 6.0, 1, &g, &found, &err), ELFM_ERR_INVALID);
    elfm_peaks_free(pg);
  }

  /* Empty volume: no peaks, no error. */
  memset(v->data, 0, sizeof(float) * 64 * 60 * 51);
  CHECK_OK(elfm_peaks_detect(pk, v, det, 16, &n, &err), &err);
  CHECK_EQ_INT(n, 0);

  /* Errors: NaN voxel, wrong geometry, bad options. */
  v->data[1234] = NAN;
  CHECK_EQ_INT(elfm_peaks_detect(pk, v, det, 16, &n, &err), ELFM_ERR_NUMERIC);
  CHECK(strstr(err.message, "NaN") != NULL);
  elfm_volume *v2 = elfm_volume_create(10, 10, 10, 1, 0, 1, &err);
  CHECK_EQ_INT(elfm_peaks_detect(pk, v2, det, 16, &n, &err), ELFM_ERR_INVALID);
  elfm_volume_free(v2);
  o.radius_z_um = -1;
  CHECK(elfm_peaks_create(&o, 10, 10, 10, &err) == NULL);
  CHECK_EQ_INT(err.code, ELFM_ERR_INVALID);
  /* the message names the option, its value and what it takes */
  CHECK_MSG(strstr(err.message, "radius_z_um = -1 is out of range (> 0)") != NULL, "%s", err.message);
  elfm_peaks_free(NULL);
  o.radius_z_um = 15;

  /* Lag correction. A leaky surface of an object moving at 1 um/ms along
   * +x, tau = 2 ms: sum over the past of exp(-age/tau) * blob. The raw peak
   * lies behind the current position; the corrected one is much closer. */
  memset(v->data, 0, sizeof(float) * 64 * 60 * 51);
  const double speed = 1.0, tau_us = 2000, x_now = 5.0;
  for (int s = 0; s < 400; s++) {           /* 25 us steps over 10 ms (5 tau) */
    double age_us = s * 25.0;
    add_blob(v, x_now - speed * age_us * 1e-3, 0, 0, 25.0 / tau_us * exp(-age_us / tau_us) * 100,
             SXY, SZ);
  }
  o.radius_xy_um = 3;
  o.min_separation_um = 4;
  o.absolute = 1;
  elfm_peaks_free(pk);
  pk = elfm_peaks_create(&o, v->w, v->h, v->nz, &err);
  CHECK_OK(elfm_peaks_detect(pk, v, det, 16, &n, &err), &err);
  CHECK_EQ_INT(n, 1);
  double raw_err = det[0].x_um - x_now;
  /* the blob seen by the detector is wider than SXY along x (the trail) */
  elfm_detection c = det[0];
  c.sigma_x_um = SXY;  /* the object's own width along the motion */
  elfm_detection_correct_lag(&c, speed, 0, 0, tau_us);
  double cor_err = c.x_um - x_now;
  fprintf(stderr, "lag: raw error %.3f um, corrected %.3f um (model lag %.3f um)\n", raw_err,
          cor_err, elfm_peaks_trail_lag_um(speed * tau_us * 1e-3, SXY));
  CHECK_MSG(raw_err < -0.5, "raw detection should trail: %g", raw_err);
  CHECK_MSG(fabs(cor_err) < 0.25 * fabs(raw_err), "correction %g vs raw %g", cor_err, raw_err);
  CHECK_NEAR(c.y_um, det[0].y_um, 1e-12);
  /* No motion, no shift; tiny trail -> tiny lag; long trail -> lag < trail. */
  elfm_detection c2 = det[0];
  elfm_detection_correct_lag(&c2, 0, 0, 0, tau_us);
  CHECK(c2.x_um == det[0].x_um);
  CHECK(elfm_peaks_trail_lag_um(1e-6, 1.0) < 1e-5);
  double lg = elfm_peaks_trail_lag_um(50, 1.0);
  CHECK(lg >= 0 && lg < 50);
  CHECK(elfm_peaks_trail_lag_um(NAN, 1.0) == 0);

  /* The peak's width along its widest lateral axis (elfm_detection.width_um):
   * an elongated blob (sigma 3 um along its long axis, 1.5 um across) at
   * 0 / 30 / 60 / 90 degrees reads the same width whatever the angle (the
   * per-axis fits do not: at 0 degrees sigma_x is the long axis, at 90 the
   * short one), and a round blob of sigma 2 um reads 2/3 of it (the width is
   * a second moment over the values above half the peak: proportional to
   * sigma). A view-fit point has none. */
  {
    double w_deg[4], sx_deg[4];
    const double ang[4] = {0, 30, 60, 90};
    elfm_peaks_options ow;
    elfm_peaks_options_default(&ow);
    ow.absolute = 10;
    for (int r = 0; r < 5; r++) {
      elfm_volume *vw = elfm_volume_create(48, 48, 11, 0.926, -10, 2, &err);
      CHECK(vw != NULL);
      if (!vw) break;
      const double th = r < 4 ? ang[r] * 3.14159265358979 / 180 : 0;
      const double sa = r < 4 ? 3.0 : 2.0, sb = r < 4 ? 1.5 : 2.0;
      for (int k = 0; k < vw->nz; k++)
        for (int j = 0; j < vw->h; j++)
          for (int i = 0; i < vw->w; i++) {
            double dx = elfm_volume_x_um(vw, i) - 0.2, dy = elfm_volume_y_um(vw, j) + 0.3,
                   dz = elfm_volume_z_um(vw, k);
            double a = dx * cos(th) + dy * sin(th), b = -dx * sin(th) + dy * cos(th);
            double e = a * a / (2 * sa * sa) + b * b / (2 * sb * sb) + dz * dz / (2 * 64.0);
            vw->data[((size_t)k * vw->h + j) * vw->w + i] = (float)(200 * exp(-e));
          }
      elfm_peaks *pw = elfm_peaks_create(&ow, vw->w, vw->h, vw->nz, &err);
      elfm_detection dw[4];
      int nw = 0;
      CHECK_OK(elfm_peaks_detect(pw, vw, dw, 4, &nw, &err), &err);
      CHECK_EQ_INT(nw, 1);
      if (nw >= 1 && r < 4) {
        w_deg[r] = dw[0].width_um;
        sx_deg[r] = dw[0].sigma_x_um;
      }
      if (nw >= 1 && r == 4) {
        fprintf(stderr, "width: elongated %.3f %.3f %.3f %.3f um, round %.3f um\n", w_deg[0],
                w_deg[1], w_deg[2], w_deg[3], dw[0].width_um);
        for (int q = 0; q < 4; q++) CHECK_NEAR(w_deg[q] / w_deg[0], 1.0, 0.03);
        CHECK_NEAR(dw[0].width_um / w_deg[0], 2.0 / 3.0, 0.03);
        CHECK(sx_deg[0] > 1.5 * sx_deg[3]);
      }
      elfm_peaks_free(pw);
      elfm_volume_free(vw);
    }
  }

  elfm_peaks_free(pk);
  elfm_volume_free(v);
  test_noise_exact();
  return check_report();
}
