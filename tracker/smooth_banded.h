/* smooth_banded.h — private to tracker/: the smoothing spline's banded
 * algebra, in C: the Ceres bridge (smooth.cc) is the project's one C++
 * file, for what needs Ceres, not for plain arithmetic. The spline has
 * one state per frame of a track's span; its prior penalises the second
 * (order 2) or third (order 3) divided difference of the states, so
 * A = diag(W) + mu x the prior's rows is banded with bandwidth b = order
 * (pentadiagonal or heptadiagonal). A banded LDL^T solves it and the
 * selected (Takahashi) inverse gives A^-1 on the band, the hat matrix's
 * trace for GCV and the posterior variances, all in O(K). Not public:
 * callers use elfm_smooth.h. */
#ifndef ELFM_SMOOTH_BANDED_H
#define ELFM_SMOOTH_BANDED_H

#include <stddef.h>

#ifdef __cplusplus
extern "C" {
#endif

/* The prior's row over states k .. k + order of the state times ts (ms):
 * order 2, the second divided difference centred on k + 1 (3 coefficients);
 * order 3, the third over four states times 6 (4); both scaled by
 * sqrt(hbar), hbar the mean spacing, so that the penalty is lambda x the
 * integral of the squared derivative. The robust fit's prior residuals use
 * the same rows. */
void elfm_spline_prior_coef(const double *ts, int order, size_t k, double c[4]);
/* All K - order rows' coefficients into coef (4 per row, row k at
 * coef[4 k]): the prior depends on the state times only, and a fit builds
 * A for ~100 weights and axes (GCV, IRLS), where computing the rows each
 * time was 1.2 % of a 2-thread `track` on flow 1 s under perf (the
 * smoothing 16 %). */
void elfm_spline_prior_table(const double *ts, size_t K, int order, double *coef);
/* The order-3 table with omega (rad per ms of ts): each row also
 * penalises omega_eff^2 times the first difference of its middle states,
 * omega_eff = 2 sin(omega h / 2) / h over that interval h, so that a
 * sampled circle at omega (any plane, any phase) leaves the rows 0. */
void elfm_spline_prior_table_omega(const double *ts, size_t K, double omega, double *coef);

/* Diagonal d of A, L and A^-1: a[d], l[d] (l[d][k] = L(k+d, k)) and z[d]
 * (z[d][k] = A^-1(k, k+d)), each K + 3 long; D the LDL^T pivots. */
typedef struct elfm_banded {
  size_t K, cap;
  int b;
  double *a[4], *l[4], *z[4], *D;
} elfm_banded;

void elfm_banded_init(elfm_banded *bd);
void elfm_banded_free(elfm_banded *bd);
/* Room for K states (the 3 entries past K zeroed; build, factor and
 * inverse write the rest); 0 when out of memory. */
int elfm_banded_resize(elfm_banded *bd, size_t K);
/* A = diag(W) + mu x the prior's rows over the state times ts; with
 * _table, the rows from elfm_spline_prior_table (the same numbers). */
void elfm_banded_build(elfm_banded *bd, const double *W, const double *ts, double mu, int order);
void elfm_banded_build_table(elfm_banded *bd, const double *W, const double *coef, double mu,
                             int order);
/* LDL^T in place; 0 when A is not positive definite (or not finite). */
int elfm_banded_factor(elfm_banded *bd);
/* x = A^-1 rhs (after factor); x has K entries. */
void elfm_banded_solve(const elfm_banded *bd, const double *rhs, double *x);
/* x[j] = A^-1 x[j] for j = 0, 1, 2 in place (after factor): three right
 * sides at once, each the same operations in the same order as
 * elfm_banded_solve (so the same bits); the three recurrences interleaved
 * keep the processor busy where one waits on its last row. */
void elfm_banded_solve3(const elfm_banded *bd, double *const x[3]);
/* A^-1 on the band into z (after factor), from the last row up. */
void elfm_banded_inverse(elfm_banded *bd);

/* ---- The spline's linear fit, and its weight by GCV ----
 * n data points x (n x 3, um) with sigmas sig (n x 3) on K states at times
 * ts (ms), point i on state state_of[i]; the prior of `order` scaled per
 * axis by 1 / sig_ref[a]^2. */
typedef struct elfm_spline_problem {
  size_t n, K;
  const double *x, *sig, *ts, *sig_ref;
  const size_t *state_of;
  int order;
  const double *coef; /* elfm_spline_prior_table of ts, or NULL: rows computed as needed */
  /* 1: every point's sigma is one factor times sig_ref on all three axes
   * (elfm_spline_isotropic), so the axes share one matrix and one
   * factorisation; 0 (a zero-initialised problem): one per axis */
  int iso;
  /* The unit of lambda for GCV's grid (below): the grid is lambda_unit x
   * 10^-4 .. 10^8. 0 (a zero-initialised problem) is 1, ms^3 as is, the
   * span for states about 1 ms apart; elfm_spline_lambda_unit moves the
   * grid with the states' spacing. */
  double lambda_unit;
} elfm_spline_problem;

/* The unit of lambda for states at ts (K, ms, increasing) under the prior
 * of `order`: T^(2 order - 1), T the states' median spacing rounded to a
 * power of ten (1 for spacings of 0.32-3.2 ms). Why: the prior's rows grow
 * as h^-(order - 1/2) for states h apart, so the same lambda is T^(2 order
 * - 1) times stiffer on states T times closer. On frames 1 us apart the
 * grid's 10^-4 was already far beyond "straight line", and the banded
 * factorisation lost its digits (docs/tracker.md "Frames microseconds
 * apart"). Powers of ten keep the grid's points on their decades. */
double elfm_spline_lambda_unit(const double *ts, size_t K, int order);

/* Whether sig[3 i + a] / sig_ref[a] is the same on the three axes for
 * every point, to 1e-12 of itself: each axis's matrix is then the same
 * matrix over sig_ref[a]^2, and its solution the same one. */
int elfm_spline_isotropic(const elfm_spline_problem *sp);

/* Per axis, the fit at lambda with point weights w (n): the states into p
 * (K x 3, when not NULL), the whitened weighted residual sum of squares
 * into *rss and the hat matrix's trace summed over the axes into *edf.
 * edf may be NULL: then A^-1 is not formed (a third of the fit's work),
 * as reweighting needs only the states. bd is the workspace (its band of
 * A^-1 is the last axis's afterwards when edf was asked for; with iso, the
 * shared matrix's, which is sig_ref[a]^2 times axis a's inverse);
 * work holds 5 K doubles. 0 when A is not positive definite or no memory. */
int elfm_spline_linear(const elfm_spline_problem *sp, const double *w, double lambda,
                       elfm_banded *bd, double *work, double *rss, double *edf, double *p);

/* The weight by GCV over the grid 10^-4 .. 10^8 ms^3 (times lambda_unit)
 * in half decades (the span from "follows every frame" to "straight line"
 * for 1 kHz frames and sub-um noise), then refined around the best to 1/16 decade, each
 * effective parameter priced gamma (1: classical):
 * the lambda minimising 3n RSS / (3n - gamma edf)^2; lambda_unit when
 * none can be computed. */
double elfm_spline_gcv_lambda(const elfm_spline_problem *sp, const double *w, double gamma);
/* The same search on whole decades first (13 fits), then downhill along
 * the half-decade grid from their best (first towards smaller weights,
 * else larger) until the score stops falling, then the same refinement:
 * the whole grid's weight unless the least lies in a dip narrower than a
 * decade, or the score is flat (to its rounding) where the two searches
 * look. The whole grid when no decade has a score. */
double elfm_spline_gcv_lambda_coarse(const elfm_spline_problem *sp, const double *w, double gamma);

/* Invert a small SPD matrix (m <= 3, row-major) in place by Gauss-Jordan
 * with partial pivoting; 0 (M undefined) when singular. */
int elfm_invert_small(double *M, int m);

#ifdef __cplusplus
}
#endif
#endif
