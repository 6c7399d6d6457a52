/* test_smooth_noise.c — the smoother's noise estimate
 * (elfm_smooth_estimate_noise, elfm_smooth.h NOISE): on a noisy straight
 * track, with gaps and absolute times near 1e12 us, the estimate lies near
 * the noise; on a bead turning 0.6 rad per frame, whose second differences
 * hold the turn (their estimate 4x the noise), the estimate is under 0.6 x
 * theirs (capped by the fourth differences') while its slowly swinging z
 * keeps theirs, and the robust fit with it lies nearer the bead than with
 * theirs; a track too short for fourth differences keeps the second
 * differences' estimate. */
#include <math.h>
#include <stdint.h>
#include <string.h>

#include "check.h"
#include "elfm_tracker.h"

static const int64_t T0 = 1000000000000LL;
enum { N_MAX = 120 };

/* A deterministic normal deviate (xorshift64* and Box-Muller). */
static double normal(uint64_t *s)
{
  double u[2];
  for (int i = 0; i < 2; i++) {
    *s ^= *s >> 12;
    *s ^= *s << 25;
    *s ^= *s >> 27;
    u[i] = ((double)((*s * 2685821657736338717ULL) >> 11) + 0.5) / 9007199254740992.0;
  }
  return sqrt(-2 * log(u[0])) * cos(2 * M_PI * u[1]);
}

/* n points of a circle of radius r_um in the x-y plane turning w rad per
 * frame (r_um 0: a straight line at 3 um per frame), z a slow line (on the
 * circle a swing of 6 um, a quarter of the turn's rate); noise
 * sd_xy / sd_z; frames 1 ms apart, every 9th frame missing when gaps. */
static void make_track(int n, double r_um, double w, double sd_xy, double sd_z, int gaps,
                       uint64_t seed, int64_t *t, double *x, double *truth)
{
  uint64_t s = seed;
  for (int i = 0, f = 0; i < n; i++, f++) {
    if (gaps && f % 9 == 8) f++;
    t[i] = T0 + 1000 * (int64_t)f;
    double p[3];
    if (r_um > 0) {
      p[0] = 40 + r_um * cos(w * f);
      p[1] = -20 + r_um * sin(w * f);
    } else {
      p[0] = 40 + 3.0 * f;
      p[1] = -20 + 1.0 * f;
    }
    p[2] = r_um > 0 ? 10 + 6 * sin(0.25 * w * f) : 10 + 0.3 * f;
    for (int a = 0; a < 3; a++) {
      if (truth) truth[3 * i + a] = p[a];
      x[3 * i + a] = p[a] + (a == 2 ? sd_z : sd_xy) * normal(&s);
    }
  }
}

/* The second differences' estimate alone (1.4826 MAD of |x[i+1] - 2 x[i]
 * + x[i-1]| / sqrt 6, frames evenly spaced), per axis. */
static void second_difference_sigma(int n, const double *x, double out[3])
{
  double r[N_MAX];
  for (int a = 0; a < 3; a++) {
    int m = 0;
    for (int i = 1; i + 1 < n; i++)
      r[m++] = fabs(x[3 * (i + 1) + a] - 2 * x[3 * i + a] + x[3 * (i - 1) + a]) / sqrt(6);
    /* the median as nth_element takes it: the (m / 2)-th smallest */
    for (int i = 0; i < m; i++)
      for (int j = i + 1; j < m; j++)
        if (r[j] < r[i]) {
          const double q = r[i];
          r[i] = r[j];
          r[j] = q;
        }
    out[a] = 1.4826 * r[m / 2];
  }
}

/* Lateral RMSE of p against truth over n points. */
static double rmse_xy(const double *p, const double *truth, int n)
{
  double e = 0;
  for (int i = 0; i < n; i++)
    for (int a = 0; a < 2; a++) e += (p[3 * i + a] - truth[3 * i + a]) * (p[3 * i + a] - truth[3 * i + a]);
  return sqrt(e / (2 * n));
}

int main(void)
{
  elfm_error err;
  elfm_smooth_options o;
  elfm_smooth_options_default(&o);
  enum { N = N_MAX };
  int64_t t[N];
  double x[3 * N], truth[3 * N], s[3];

  /* 1. A straight track: noise 0.3 um laterally, 1 um in z, with gaps. The
   * estimate is the second differences' (within 25 % of the noise). */
  make_track(N, 0, 0, 0.3, 1.0, 1, 11, t, x, NULL);
  CHECK_OK(elfm_smooth_estimate_noise(&o, N, t, x, s, &err), &err);
  fprintf(stderr, "straight: noise estimate %.3f / %.3f / %.3f um (0.3 / 0.3 / 1)\n", s[0], s[1],
          s[2]);
  CHECK_MSG(fabs(s[0] - 0.3) < 0.075 && fabs(s[1] - 0.3) < 0.075 && fabs(s[2] - 1) < 0.25,
            "straight track: %g %g %g", s[0], s[1], s[2]);

  /* 2. A bead on a circle of 9 um turning 0.6 rad per frame, noise 0.3 um
   * laterally: its second differences swing by 9 x 0.36 = 3.2 um, and
   * their estimate alone is > 0.9 um; capped by the fourth differences it
   * is under 0.6 x that. z, a slow swing, keeps its estimate. */
  make_track(N, 9, 0.6, 0.3, 1.0, 0, 12, t, x, truth);
  /* every 25th point another bead's, 5 um off (a wrong link) */
  for (int i = 7; i < N; i += 25) x[3 * i] += 5;
  CHECK_OK(elfm_smooth_estimate_noise(&o, N, t, x, s, &err), &err);
  double s2[3];
  second_difference_sigma(N, x, s2);
  fprintf(stderr, "turning 0.6 rad per frame: noise estimate %.3f / %.3f / %.3f um, second "
                  "differences alone %.3f / %.3f / %.3f um\n", s[0], s[1], s[2], s2[0], s2[1], s2[2]);
  CHECK_MSG(s2[0] > 0.9 && s2[1] > 0.9, "second differences %g %g", s2[0], s2[1]);
  CHECK_MSG(s[0] > 0.2 && s[0] < 0.6 * s2[0] && s[1] > 0.2 && s[1] < 0.6 * s2[1] &&
                fabs(s[2] - 1) < 0.25 && fabs(s[2] - s2[2]) < 1e-12,
            "turning track: %g %g %g", s[0], s[1], s[2]);
  /* ... and the spline with that estimate, under `track`'s robust loss
   * (Cauchy from 2 sigma), lies nearer the bead than with the second
   * differences' (given as the points' sigmas), where the wrong points
   * lie within the loss's scale and pull the curve */
  o.loss = ELFM_LOSS_CAUCHY;
  o.loss_scale = 2;
  double pos[3 * N], pos2[3 * N], sig2[3 * N];
  for (int i = 0; i < N; i++)
    for (int a = 0; a < 3; a++) sig2[3 * i + a] = s2[a];
  elfm_smooth_info inf;
  CHECK_OK(elfm_smooth_fit(&o, N, t, x, NULL, N, t, pos, NULL, NULL, NULL, &inf, &err), &err);
  CHECK_OK(elfm_smooth_fit(&o, N, t, x, sig2, N, t, pos2, NULL, NULL, NULL, &inf, &err), &err);
  const double e_raw = rmse_xy(x, truth, N), e_fit = rmse_xy(pos, truth, N),
               e_fit2 = rmse_xy(pos2, truth, N);
  fprintf(stderr, "turning: lateral RMSE %.3f um fitted, %.3f with the second differences' "
                  "noise, %.3f um the points\n", e_fit, e_fit2, e_raw);
  CHECK_MSG(e_fit < 0.9 * e_raw && e_fit < 0.9 * e_fit2, "fitted %.3f um, %.3f um, points %.3f um",
            e_fit, e_fit2, e_raw);

  /* 3. Six points (two fourth differences: too few for their estimate):
   * the second differences' estimate, the same as that of the first six
   * of a longer track's points computed by hand. */
  make_track(6, 9, 0.6, 0.3, 1.0, 0, 13, t, x, NULL);
  CHECK_OK(elfm_smooth_estimate_noise(&o, 6, t, x, s, &err), &err);
  second_difference_sigma(6, x, s2);
  for (int a = 0; a < 3; a++) {
    const double want = fmax(s2[a], a == 2 ? o.min_sigma_z_um : o.min_sigma_xy_um);
    CHECK_MSG(fabs(s[a] - want) < 1e-12, "axis %d: %g, second differences %g", a, s[a], want);
  }

  /* 4. Which points tell their own noise (elfm_smooth_noise_known): 3
   * second differences of distinct times, so 5 points; a repeated time
   * takes two of them away. */
  {
    const int64_t tk[7] = {0, 1000, 2000, 3000, 4000, 5000, 6000};
    const int64_t tr[7] = {0, 1000, 1000, 2000, 3000, 4000, 5000};
    CHECK(!elfm_smooth_noise_known(0, tk) && !elfm_smooth_noise_known(1, tk));
    CHECK(!elfm_smooth_noise_known(4, tk) && elfm_smooth_noise_known(5, tk));
    CHECK(!elfm_smooth_noise_known(6, tr) && elfm_smooth_noise_known(7, tr));
  }
  return check_report();
}
