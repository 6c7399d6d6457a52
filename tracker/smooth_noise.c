/* smooth_noise.c — the smoother's noise per axis from the points themselves
 * (elfm_smooth_estimate_noise, elfm_smooth.h NOISE): plain arithmetic, in
 * C, out of the Ceres bridge (smooth.cc), which calls it. */
#include <math.h>
#include <stdlib.h>

#include "elfm_smooth.h"

/* The fourth differences' estimate (below) over this ratio caps the second
 * differences'. On noise alone the two agree (white noise: ratio 1; the
 * time surface's errors, correlated from frame to frame: ~0.95), so the cap
 * leaves them be; where it bites, the second differences hold the path's
 * own turn. Flow at 2 ms frames turns 0.55-0.9 rad per frame, and its
 * second differences put the lateral noise at 0.95 um where the fourth put
 * 0.22 um (medians over the tracks, seeds 1-4); the robust loss, whose
 * scale is in these sigmas, then took wrong points (another bead's) at
 * full weight, and the smoothed points lay no nearer the beads than the
 * detections (seeds 1-8: mean distance 0.520 against 0.525 um; 0.452 with
 * the cap; test_smooth_noise 2 has such a case). Flow 100 ms seeds 1-8 /
 * 9-16 at 2 ms frames alpha 0.7801 -> 0.8049 / 0.7490 -> 0.7608 at 0.6
 * (0.8060 on seeds 1-8 at 0.8); at 1 ms frames seeds 1-20 / 21-32 -0.0002 /
 * -0.0003, stage seeds 1-3 and worm (integral) seeds 1-4 the same,
 * flow_random seeds 1-12 +0.0004, blink seeds 1-4 -0.0008 (docs/tracker.md
 * "The noise of fast turns"). */
#define FOURTH_TO_SECOND 0.6

static int cmp_double(const void *a, const void *b)
{
  const double x = *(const double *)a, y = *(const double *)b;
  return (x > y) - (x < y);
}

/* 1.4826 x the median of r[0 .. m) (reorders r): the element at m / 2 in
 * ascending order. */
static double mad_sigma(double *r, size_t m)
{
  qsort(r, m, sizeof *r, cmp_double);
  return 1.4826 * r[m / 2];
}

/* Robust noise of axis a from normalised second differences of
 * consecutive points (uneven spacing allowed, repeated times skipped), r
 * the scratch (n doubles): -1 when fewer than 3. A straight or slowly
 * curving track has none. */
static double second_difference_sigma(size_t n, const int64_t *t, const double *x, int a, double *r)
{
  size_t m = 0;
  for (size_t i = 1; i + 1 < n; i++) {
    const int64_t h0 = t[i] - t[i - 1], h1 = t[i + 1] - t[i];
    if (h0 <= 0 || h1 <= 0) continue;
    const double rho = (double)h1 / (double)h0;
    const double e = x[3 * (i + 1) + a] - x[3 * i + a] - rho * (x[3 * i + a] - x[3 * (i - 1) + a]);
    /* var(e) = sigma^2 (1 + (1 + rho)^2 + rho^2) for independent noise */
    r[m++] = fabs(e) / sqrt(1 + (1 + rho) * (1 + rho) + rho * rho);
  }
  return m < 3 ? -1 : mad_sigma(r, m);
}

/* The same from fourth divided differences (any spacing; windows with a
 * repeated time skipped). A path of constant jerk has none, so a turn
 * enters only by its fourth derivative, (turn per frame)^4 x radius. */
static double fourth_difference_sigma(size_t n, const int64_t *t, const double *x, int a, double *r)
{
  size_t m = 0;
  for (size_t i = 0; i + 4 < n; i++) {
    double c[5], ss = 0, e = 0;
    int ok = 1;
    for (int j = 0; j <= 4 && ok; j++) {
      double p = 1;
      for (int k = 0; k <= 4; k++)
        if (k != j) p *= (double)(t[i + j] - t[i + k]);
      ok = p != 0;
      c[j] = ok ? 1 / p : 0;
    }
    if (!ok) continue;
    for (int j = 0; j <= 4; j++) {
      ss += c[j] * c[j];
      e += c[j] * x[3 * (i + j) + a];
    }
    r[m++] = fabs(e) / sqrt(ss); /* var(e) = sigma^2 ss for independent noise */
  }
  return m < 3 ? -1 : mad_sigma(r, m);
}

int elfm_smooth_noise_known(size_t n, const int64_t *t_us)
{
  /* the triples second_difference_sigma uses: 3 or more */
  size_t m = 0;
  for (size_t i = 1; i + 1 < n && m < 3; i++) m += t_us[i] > t_us[i - 1] && t_us[i + 1] > t_us[i];
  return m >= 3;
}

elfm_status elfm_smooth_estimate_noise(const elfm_smooth_options *o, size_t n,
                                       const int64_t *t_us, const double *xyz_um,
                                       double sigma_um[3], elfm_error *err)
{
  if (!o || (n > 0 && (!t_us || !xyz_um)) || !sigma_um)
    return elfm_error_set(err, ELFM_ERR_INVALID, NULL, -1, "smooth: no points");
  double *r = n ? malloc(n * sizeof *r) : NULL;
  if (n && !r) return elfm_error_set(err, ELFM_ERR_NOMEM, NULL, -1, "smooth: out of memory");
  const double floor_um[3] = {o->min_sigma_xy_um, o->min_sigma_xy_um, o->min_sigma_z_um};
  for (int a = 0; a < 3; a++) {
    double s = second_difference_sigma(n, t_us, xyz_um, a, r);
    if (s < 0) {
      s = 0;
    } else {
      const double s4 = fourth_difference_sigma(n, t_us, xyz_um, a, r);
      if (s4 >= 0 && s4 / FOURTH_TO_SECOND < s) s = s4 / FOURTH_TO_SECOND;
    }
    sigma_um[a] = s > floor_um[a] ? s : floor_um[a];
  }
  free(r);
  return ELFM_OK;
}
