/* smooth_banded.c — the smoothing spline's banded algebra, its linear fit
 * and its weight by GCV (see smooth_banded.h). Moved out of the Ceres bridge as it was, operation for
 * operation: the smoothed tracks are the same bits. */
#include "smooth_banded.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* Second divided difference coefficients at interior state k (1..K-2),
 * scaled by sqrt(hbar): prior row r = sqrt(lambda) * coef . p / sigma_ref. */
static void accel_coef(const double *ts, size_t k, double c[3])
{
  double h0 = ts[k] - ts[k - 1], h1 = ts[k + 1] - ts[k], hb = 0.5 * (h0 + h1);
  double s = sqrt(hb) / hb;
  c[0] = s / h0;
  c[1] = -s * (1 / h0 + 1 / h1);
  c[2] = s / h1;
}

/* Third divided difference coefficients over states k .. k+3, times 6 (the
 * third derivative of the cubic through them) and scaled by sqrt(hbar),
 * hbar = (t_{k+3} - t_k) / 3: for frames h apart, (-1, 3, -3, 1) / h^3 x
 * sqrt(h), the analogue of accel_coef one order up. */
static void jerk_coef(const double *ts, size_t k, double c[4])
{
  const double hb = (ts[k + 3] - ts[k]) / 3, s = 6 * sqrt(hb);
  for (int i = 0; i < 4; i++) {
    double den = 1;
    for (int j = 0; j < 4; j++)
      if (j != i) den *= ts[k + i] - ts[k + j];
    c[i] = s / den;
  }
}

void elfm_spline_prior_coef(const double *ts, int order, size_t k, double c[4])
{
  if (order == 3) jerk_coef(ts, k, c);
  else accel_coef(ts, k + 1, c);
}

void elfm_spline_prior_table(const double *ts, size_t K, int order, double *coef)
{
  for (size_t k = 0; k + (size_t)order + 1 <= K; k++) elfm_spline_prior_coef(ts, order, k, coef + 4 * k);
}

void elfm_spline_prior_table_omega(const double *ts, size_t K, double omega, double *coef)
{
  for (size_t k = 0; k + 4 <= K; k++) {
    double *c = coef + 4 * k;
    jerk_coef(ts, k, c);
    const double hb = (ts[k + 3] - ts[k]) / 3, h = ts[k + 2] - ts[k + 1];
    const double we = 2 * sin(0.5 * omega * h) / h, f = sqrt(hb) * we * we / h;
    c[1] -= f;
    c[2] += f;
  }
}

void elfm_banded_init(elfm_banded *bd) { memset(bd, 0, sizeof *bd); }

void elfm_banded_free(elfm_banded *bd)
{
  for (int d = 0; d < 4; d++) {
    free(bd->a[d]);
    free(bd->l[d]);
    free(bd->z[d]);
  }
  free(bd->D);
  elfm_banded_init(bd);
}

int elfm_banded_resize(elfm_banded *bd, size_t K)
{
  const size_t n = K + 3;
  if (n > bd->cap) {
    double **arr[13];
    int m = 0;
    for (int d = 0; d < 4; d++) {
      arr[m++] = &bd->a[d];
      arr[m++] = &bd->l[d];
      arr[m++] = &bd->z[d];
    }
    arr[m++] = &bd->D;
    for (int i = 0; i < m; i++) {
      double *p = realloc(*arr[i], n * sizeof *p);
      if (!p) return 0;
      *arr[i] = p;
    }
    bd->cap = n;
  }
  bd->K = K;
  /* Only the 3 entries past K: build, factor and inverse write every entry
   * below K that they or solve read (l and z up to the band b, a up to 3),
   * so zeroing the whole arrays on every linear fit bought nothing (memset
   * under perf, a one-thread `track` on flow 1 s: 3.7 % of the samples,
   * 2.7 % without it; thirty-eighth session). The tail stays 0 for
   * whoever copies K + 3 entries (smooth.cc). */
  for (int d = 0; d < 4; d++) {
    memset(bd->a[d] + K, 0, 3 * sizeof(double));
    memset(bd->l[d] + K, 0, 3 * sizeof(double));
    memset(bd->z[d] + K, 0, 3 * sizeof(double));
  }
  memset(bd->D + K, 0, 3 * sizeof(double));
  return 1;
}

/* The prior's rows from ts, or from coef (elfm_spline_prior_table) when
 * not NULL. */
static void banded_build(elfm_banded *bd, const double *W, const double *ts, const double *coef,
                         double mu, int order)
{
  bd->b = order;
  const size_t K = bd->K;
  for (size_t k = 0; k < K; k++) {
    bd->a[0][k] = W[k];
    for (int d = 1; d < 4; d++) bd->a[d][k] = 0;
  }
  const size_t m = (size_t)order + 1;
  for (size_t k = 0; k + m <= K; k++) { /* rows over states k .. k + order */
    double cr[4];
    const double *c = coef ? coef + 4 * k : cr;
    if (!coef) elfm_spline_prior_coef(ts, order, k, cr);
    for (size_t i = 0; i < m; i++)
      for (size_t d = 0; i + d < m; d++) bd->a[d][k + i] += mu * c[i] * c[i + d];
  }
}

void elfm_banded_build(elfm_banded *bd, const double *W, const double *ts, double mu, int order)
{
  banded_build(bd, W, ts, NULL, mu, order);
}

void elfm_banded_build_table(elfm_banded *bd, const double *W, const double *coef, double mu,
                             int order)
{
  banded_build(bd, W, NULL, coef, mu, order);
}

int elfm_banded_factor(elfm_banded *bd)
{
  const size_t K = bd->K;
  const int b = bd->b;
  double **l = bd->l, *D = bd->D;
  for (size_t k = 0; k < K; k++) {
    double d = bd->a[0][k];
    for (int i = 1; i <= b && (size_t)i <= k; i++) d -= l[i][k - i] * l[i][k - i] * D[k - i];
    if (!(d > 0) || !isfinite(d)) return 0;
    D[k] = d;
    for (int j = 1; j <= b; j++) {
      if (k + (size_t)j >= K) {
        l[j][k] = 0;
        continue;
      }
      double e = bd->a[j][k];
      /* L(k+j, m) L(k, m) D(m) over m = k-1 down to k+j-b */
      for (int i = 1; i + j <= b && (size_t)i <= k; i++) e -= l[i + j][k - i] * l[i][k - i] * D[k - i];
      l[j][k] = e / d;
    }
  }
  return 1;
}

/* How many of the b rows below row k exist (k + i < K). */
static int band_below(size_t K, size_t k, int b)
{
  const size_t left = K - 1 - k;
  return left < (size_t)b ? (int)left : b;
}

void elfm_banded_solve(const elfm_banded *bd, const double *rhs, double *x)
{
  const size_t K = bd->K;
  const int b = bd->b;
  double *const *l = bd->l;
  for (size_t k = 0; k < K; k++) {
    double y = rhs[k];
    for (int i = 1; i <= b && (size_t)i <= k; i++) y -= l[i][k - i] * x[k - i];
    x[k] = y;
  }
  for (size_t k = 0; k < K; k++) x[k] /= bd->D[k];
  for (size_t k = K; k-- > 0;) {
    const int m = band_below(K, k, b);
    for (int i = 1; i <= m; i++) x[k] -= l[i][k] * x[k + i];
  }
}

void elfm_banded_solve3(const elfm_banded *bd, double *const x[3])
{
  const size_t K = bd->K;
  const int b = bd->b;
  double *const *l = bd->l;
  double *x0 = x[0], *x1 = x[1], *x2 = x[2];
  /* in place: row k reads its own right side before writing it, and only
   * rows already solved besides */
  for (size_t k = 0; k < K; k++) {
    double y0 = x0[k], y1 = x1[k], y2 = x2[k];
    for (int i = 1; i <= b && (size_t)i <= k; i++) {
      const double li = l[i][k - i];
      y0 -= li * x0[k - i];
      y1 -= li * x1[k - i];
      y2 -= li * x2[k - i];
    }
    x0[k] = y0;
    x1[k] = y1;
    x2[k] = y2;
  }
  for (size_t k = 0; k < K; k++) {
    x0[k] /= bd->D[k];
    x1[k] /= bd->D[k];
    x2[k] /= bd->D[k];
  }
  for (size_t k = K; k-- > 0;) {
    const int m = band_below(K, k, b);
    for (int i = 1; i <= m; i++) {
      const double li = l[i][k];
      x0[k] -= li * x0[k + i];
      x1[k] -= li * x1[k + i];
      x2[k] -= li * x2[k + i];
    }
  }
}

void elfm_banded_inverse(elfm_banded *bd)
{
  const size_t K = bd->K;
  const int b = bd->b;
  double *const *l = bd->l, *const *z = bd->z;
  for (size_t k = K; k-- > 0;) {
    /* Rows past K are 0 in L and in A^-1: only the m below k count (the
     * same sums as over all b, whose extra terms were 0 x 0). */
    const int m = band_below(K, k, b);
    for (int j = 1; j <= b; j++) {
      if (j > m) {
        z[j][k] = 0;
        continue;
      }
      /* A^-1(k + i, k + j), both within the band already computed */
      double s = 0;
      for (int i = 1; i <= m; i++) s += l[i][k] * (i <= j ? z[j - i][k + i] : z[i - j][k + j]);
      z[j][k] = -s;
    }
    double z00 = 1 / bd->D[k];
    for (int i = 1; i <= b; i++) z00 -= l[i][k] * z[i][k];
    z[0][k] = z00;
  }
}

int elfm_spline_isotropic(const elfm_spline_problem *sp)
{
  for (int a = 0; a < 3; a++)
    if (!(sp->sig_ref[a] > 0) || !isfinite(sp->sig_ref[a])) return 0;
  for (size_t i = 0; i < sp->n; i++) {
    const double r0 = sp->sig[3 * i] / sp->sig_ref[0];
    for (int a = 1; a < 3; a++) {
      const double ra = sp->sig[3 * i + a] / sp->sig_ref[a];
      if (!(fabs(ra - r0) <= 1e-12 * r0)) return 0;
    }
  }
  return 1;
}

int elfm_spline_linear(const elfm_spline_problem *sp, const double *w, double lambda,
                       elfm_banded *bd, double *work, double *rss, double *edf, double *p)
{
  const size_t K = sp->K;
  double *W = work, *b = work + K, *x = work + 2 * K;
  *rss = 0;
  if (edf) *edf = 0;
  if (!elfm_banded_resize(bd, K)) return 0;
  if (p) memset(p, 0, 3 * K * sizeof *p);
  if (sp->iso) {
    /* The axes' matrices are one matrix over sig_ref[a]^2: its weights
     * w_i (sig_ref / sig_i)^2 (axis 0's ratio, the others' to 1e-12),
     * its prior lambda. Built, factored and inverted once instead of
     * three times (under perf, flow 1 s seed 1, one thread, the build,
     * the factorisation and the inverse were 6 % of the whole run, the
     * solves 2.5 %), each axis then one solve (elfm_banded_solve3); the
     * hat matrix's trace is the same on each axis. */
    const double s0 = sp->sig_ref[0] * sp->sig_ref[0];
    memset(W, 0, K * sizeof *W);
    for (size_t i = 0; i < sp->n; i++)
      W[sp->state_of[i]] += w[i] * s0 / (sp->sig[3 * i] * sp->sig[3 * i]);
    banded_build(bd, W, sp->ts, sp->coef, lambda, sp->order);
    if (!elfm_banded_factor(bd)) return 0;
    double *const xs[3] = {b, x, work + 3 * K}; /* each axis's right side, then its states */
    for (int a = 0; a < 3; a++) memset(xs[a], 0, K * sizeof *xs[a]);
    for (size_t i = 0; i < sp->n; i++) {
      const double wi = w[i] * s0 / (sp->sig[3 * i] * sp->sig[3 * i]);
      for (int a = 0; a < 3; a++) xs[a][sp->state_of[i]] += wi * sp->x[3 * i + a];
    }
    elfm_banded_solve3(bd, xs);
    for (int a = 0; a < 3; a++) {
      for (size_t i = 0; i < sp->n; i++) {
        double r = (xs[a][sp->state_of[i]] - sp->x[3 * i + a]) / sp->sig[3 * i + a];
        *rss += w[i] * r * r;
      }
      if (p)
        for (size_t k = 0; k < K; k++) p[3 * k + a] = xs[a][k];
    }
    if (edf) {
      elfm_banded_inverse(bd);
      double e = 0;
      for (size_t k = 0; k < K; k++) e += bd->z[0][k] * W[k];
      *edf = 3 * e;
    }
    return 1;
  }
  for (int a = 0; a < 3; a++) {
    memset(W, 0, K * sizeof *W);
    memset(b, 0, K * sizeof *b);
    for (size_t i = 0; i < sp->n; i++) {
      double wi = w[i] / (sp->sig[3 * i + a] * sp->sig[3 * i + a]);
      W[sp->state_of[i]] += wi;
      b[sp->state_of[i]] += wi * sp->x[3 * i + a];
    }
    banded_build(bd, W, sp->ts, sp->coef, lambda / (sp->sig_ref[a] * sp->sig_ref[a]), sp->order);
    if (!elfm_banded_factor(bd)) return 0;
    elfm_banded_solve(bd, b, x);
    if (edf) elfm_banded_inverse(bd);
    for (size_t i = 0; i < sp->n; i++) {
      double r = (x[sp->state_of[i]] - sp->x[3 * i + a]) / sp->sig[3 * i + a];
      *rss += w[i] * r * r;
    }
    if (edf)
      for (size_t k = 0; k < K; k++) *edf += bd->z[0][k] * W[k];
    if (p)
      for (size_t k = 0; k < K; k++) p[3 * k + a] = x[k];
  }
  return 1;
}

/* smooth_banded.h. The median spacing's decade from a count per decade
 * (the decade of the median is the median of the decades, rounding being
 * monotone): one pass, no sort. */
double elfm_spline_lambda_unit(const double *ts, size_t K, int order)
{
  enum { E_LO = -12, E_HI = 12 };
  size_t count[E_HI - E_LO + 1] = {0}, m = 0;
  for (size_t k = 1; k < K; k++) {
    const double h = ts[k] - ts[k - 1];
    if (!(h > 0) || !isfinite(h)) continue;
    long e = lround(log10(h));
    if (e < E_LO) e = E_LO;
    if (e > E_HI) e = E_HI;
    count[e - E_LO]++;
    m++;
  }
  if (m == 0) return 1;
  size_t below = 0;
  int e = E_LO;
  for (; e < E_HI; e++) { /* the lower median: the (m + 1) / 2-th spacing */
    below += count[e - E_LO];
    if (below >= (m + 1) / 2) break;
  }
  return pow(10.0, (double)e * (2 * order - 1));
}

/* GCV's score at lam (n RSS / (n - gamma edf)^2, n the 3 x points
 * observed); *best and *best_g move there when it is lower. */
static void gcv_try(const elfm_spline_problem *sp, const double *w, double gamma, double lam,
                    elfm_banded *bd, double *work, double *best, double *best_g)
{
  const double nobs = 3.0 * (double)sp->n;
  double rss, edf;
  if (!elfm_spline_linear(sp, w, lam, bd, work, &rss, &edf, NULL)) return;
  const double dof = nobs - gamma * edf;
  if (dof < 0.5) return;
  const double g = nobs * rss / (dof * dof);
  if (g < *best_g * (1 - 1e-9)) {
    *best_g = g;
    *best = lam;
  }
}

/* Halve the step around the grid's best three times (1/4, 1/8, 1/16
 * decade): GCV's minimum often lies between the half decades, and on
 * test_smooth_banded's path the grid's best scored up to 3.4 % above it.
 * Six more linear fits. Mean alpha (twenty-third session) flow 100 ms
 * 0.8430 -> 0.8432 (24 of 32 seeds up), flow 1 s 0.7727 -> 0.7729 (6 of
 * 8), worm 0.5 s 0.9199 -> 0.9205 (21 of 28), worm 200 ms 0.9505 ->
 * 0.9504 (5 up, 7 down), stage, blink, blink_moving the same. */
static void gcv_refine(const elfm_spline_problem *sp, const double *w, double gamma,
                       elfm_banded *bd, double *work, double *best, double *best_g)
{
  for (double step = 0.25; isfinite(*best_g) && step > 0.05; step *= 0.5) {
    const double centre = *best;
    gcv_try(sp, w, gamma, centre * pow(10.0, -step), bd, work, best, best_g);
    gcv_try(sp, w, gamma, centre * pow(10.0, step), bd, work, best, best_g);
  }
}

/* The grid: 10^(e / 2) for e in GCV_E_MIN .. GCV_E_MAX (10^-4 .. 10^8),
 * times the problem's lambda_unit. */
#define GCV_E_MIN (-8)
#define GCV_E_MAX 16

static double gcv_grid(const elfm_spline_problem *sp, int e)
{
  return (sp->lambda_unit > 0 ? sp->lambda_unit : 1.0) * pow(10.0, 0.5 * e);
}

/* How a search starts: every grid point, or every other one (whole
 * decades) and then a walk. */
typedef enum { GCV_ALL, GCV_DECADES } gcv_start;

/* From the grid's best so far (*best_e), downhill along the grid, first
 * towards smaller weights, else larger, until the score stops falling. */
static void gcv_walk(const elfm_spline_problem *sp, const double *w, double gamma, elfm_banded *bd,
                     double *work, int *best_e, double *best, double *best_g)
{
  const int e0 = *best_e;
  for (int dir = -1; dir <= 1; dir += 2) {
    for (int e = e0 + dir; e >= GCV_E_MIN && e <= GCV_E_MAX; e += dir) {
      const double before = *best;
      gcv_try(sp, w, gamma, gcv_grid(sp, e), bd, work, best, best_g);
      if (*best == before) break;
      *best_e = e;
    }
    if (*best_e != e0) return;
  }
}

static double gcv_search(const elfm_spline_problem *sp, const double *w, double gamma,
                         gcv_start how)
{
  elfm_banded bd;
  elfm_banded_init(&bd);
  double *work = malloc((5 * sp->K + 1) * sizeof *work);
  double best = gcv_grid(sp, 0), best_g = INFINITY; /* the unit, where no score is found */
  int best_e = 0;
  for (int e = GCV_E_MIN; work && e <= GCV_E_MAX; e += how == GCV_ALL ? 1 : 2) {
    const double before = best;
    gcv_try(sp, w, gamma, gcv_grid(sp, e), &bd, work, &best, &best_g);
    if (best != before) best_e = e;
  }
  if (work && isfinite(best_g)) {
    if (how == GCV_DECADES) gcv_walk(sp, w, gamma, &bd, work, &best_e, &best, &best_g);
    gcv_refine(sp, w, gamma, &bd, work, &best, &best_g);
  }
  free(work);
  elfm_banded_free(&bd);
  /* no score on the decades: the whole grid */
  if (how == GCV_DECADES && !isfinite(best_g)) return gcv_search(sp, w, gamma, GCV_ALL);
  return best;
}

double elfm_spline_gcv_lambda(const elfm_spline_problem *sp, const double *w, double gamma)
{
  return gcv_search(sp, w, gamma, GCV_ALL);
}

double elfm_spline_gcv_lambda_coarse(const elfm_spline_problem *sp, const double *w, double gamma)
{
  return gcv_search(sp, w, gamma, GCV_DECADES);
}

/* smooth_banded.h */
int elfm_invert_small(double *M, int m)
{
  double A[3][6];
  for (int i = 0; i < m; i++)
    for (int j = 0; j < 2 * m; j++) A[i][j] = j < m ? M[i * m + j] : (j - m == i);
  for (int c = 0; c < m; c++) {
    int p = c;
    for (int r = c + 1; r < m; r++)
      if (fabs(A[r][c]) > fabs(A[p][c])) p = r;
    if (!(fabs(A[p][c]) > 1e-300)) return 0;
    if (p != c)
      for (int j = 0; j < 2 * m; j++) {
        const double t = A[p][j];
        A[p][j] = A[c][j];
        A[c][j] = t;
      }
    double d = A[c][c];
    for (int j = 0; j < 2 * m; j++) A[c][j] /= d;
    for (int r = 0; r < m; r++)
      if (r != c) {
        double f = A[r][c];
        for (int j = 0; j < 2 * m; j++) A[r][j] -= f * A[c][j];
      }
  }
  for (int i = 0; i < m; i++)
    for (int j = 0; j < m; j++) M[i * m + j] = A[i][j + m];
  return 1;
}
