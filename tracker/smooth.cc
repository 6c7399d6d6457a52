// smooth.cc — the Ceres bridge: robust trajectory fits (constant velocity,
// constant acceleration, smoothing spline) and the model choice (see
// elfm_smooth.h). The project's only C++; its interface is the extern "C"
// functions of elfm_smooth.h. No exceptions or output cross the boundary.
#include "elfm_smooth.h"
#include "smooth_banded.h"

#include <ceres/ceres.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <memory>
#include <new>
#include <vector>

namespace {

const double kNaN = std::numeric_limits<double>::quiet_NaN();

// ---- robust loss, mirrored in plain C++ for weights and the BIC --------

struct Loss {
  elfm_robust_loss kind;
  double a;          // scale (sigma units of the residual norm)
  double min2 = 0;   // outlier_min_um^2 (elfm_smooth.h): an outlier is also this far
  double rho(double s) const {
    if (kind == ELFM_LOSS_HUBER) return s <= a * a ? s : 2 * a * std::sqrt(s) - a * a;
    if (kind == ELFM_LOSS_CAUCHY) return a * a * std::log1p(s / (a * a));
    return s;
  }
  // IRLS weight rho'(s)
  double weight(double s) const {
    if (kind == ELFM_LOSS_HUBER) return s <= a * a ? 1.0 : a / std::sqrt(s);
    if (kind == ELFM_LOSS_CAUCHY) return 1.0 / (1.0 + s / (a * a));
    return 1.0;
  }
  // An outlier lies beyond twice the scale, where Huber's weight falls
  // below 1/2: the same points for either loss. Cauchy's weight is below
  // 1/2 from one scale on, so counting by weight called ~3x more points
  // outliers and the outlier rule (elfm_track.n_outliers) dropped whole
  // tracks: worm 0.5 s, 10 of 359 tracks.
  // d2: the squared distance from the fit, um^2 with z / 4
  bool outlier(double s, double d2) const {
    if (d2 <= min2) return false;
    if (kind == ELFM_LOSS_HUBER) return weight(s) < 0.5;
    if (kind == ELFM_LOSS_CAUCHY) return s > 4 * a * a;
    return false;
  }
  ceres::LossFunction *make() const {
    if (kind == ELFM_LOSS_HUBER) return new ceres::HuberLoss(a);
    if (kind == ELFM_LOSS_CAUCHY) return new ceres::CauchyLoss(a);
    return nullptr;
  }
};

// ---- data prepared once per fit ----------------------------------------

struct Data {
  size_t n = 0;
  std::vector<double> tau;  // ms relative to t_mid (exact int64 difference first)
  std::vector<double> x;    // n x 3, minus off
  std::vector<double> sig;  // n x 3
  double off[3] = {0, 0, 0};
  int64_t t_ref = 0;        // first data time
  double t_mid_ms = 0;      // centre of the data times, ms after t_ref
  double tau_of(int64_t t) const { return (double)(t - t_ref) * 1e-3 - t_mid_ms; }
};

// ---- Ceres residuals ---------------------------------------------------

struct CvResidual {
  double tau, x[3], inv_s[3];
  template <typename T> bool operator()(const T *p0, const T *v, T *r) const {
    for (int a = 0; a < 3; a++) r[a] = (p0[a] + v[a] * tau - x[a]) * inv_s[a];
    return true;
  }
};

struct CaResidual {
  double tau, x[3], inv_s[3];
  template <typename T> bool operator()(const T *p0, const T *v, const T *acc, T *r) const {
    for (int a = 0; a < 3; a++)
      r[a] = (p0[a] + v[a] * tau + 0.5 * acc[a] * tau * tau - x[a]) * inv_s[a];
    return true;
  }
};

struct PointResidual {
  double x[3], inv_s[3];
  template <typename T> bool operator()(const T *p, T *r) const {
    for (int a = 0; a < 3; a++) r[a] = (p[a] - x[a]) * inv_s[a];
    return true;
  }
};

// sqrt(lambda hbar) * (second divided difference) / sigma_ref, per axis
struct AccelResidual {
  double c0, c1, c2, scale[3];
  template <typename T> bool operator()(const T *pm, const T *p, const T *pp, T *r) const {
    for (int a = 0; a < 3; a++) r[a] = (c0 * pm[a] + c1 * p[a] + c2 * pp[a]) * scale[a];
    return true;
  }
};

// sqrt(lambda hbar) * (third derivative from a third divided difference) / sigma_ref
struct JerkResidual {
  double c[4], scale[3];
  template <typename T>
  bool operator()(const T *p0, const T *p1, const T *p2, const T *p3, T *r) const {
    for (int a = 0; a < 3; a++)
      r[a] = (c[0] * p0[a] + c[1] * p1[a] + c[2] * p2[a] + c[3] * p3[a]) * scale[a];
    return true;
  }
};

void solver_options(ceres::Solver::Options *so, bool sparse, int max_iter)
{
  so->logging_type = ceres::SILENT;
  so->minimizer_progress_to_stdout = false;
  so->max_num_iterations = max_iter;
  so->num_threads = 1;
  // Stop once the cost changes by less than 1e-8 of itself or a step moves
  // the positions by less than 1e-8 of them (~1 pm at 100 um): far below
  // the 0.1 nm that tracks.csv prints and the ~0.2 um the detector places
  // to. 1e-12 (and 1e-14 on the gradient) before kept Ceres iterating on
  // digits no output shows: the same tracks and points on flow, worm,
  // stage, blink and blink_moving (71 seeds; alpha within 4e-4, most
  // 1e-6), positions within 19 nm (99 % within 0.4 nm) on flow 1 s seed 1,
  // and 31-41 % less smoothing time (docs/tracker.md "Smoother").
  so->function_tolerance = 1e-8;
  so->gradient_tolerance = 1e-10;
  so->parameter_tolerance = 1e-8;
  if (sparse && ceres::IsSparseLinearAlgebraLibraryTypeAvailable(ceres::SUITE_SPARSE)) {
    so->linear_solver_type = ceres::SPARSE_NORMAL_CHOLESKY;
    so->sparse_linear_algebra_library_type = ceres::SUITE_SPARSE;
  } else if (sparse && ceres::IsSparseLinearAlgebraLibraryTypeAvailable(ceres::EIGEN_SPARSE)) {
    so->linear_solver_type = ceres::SPARSE_NORMAL_CHOLESKY;
    so->sparse_linear_algebra_library_type = ceres::EIGEN_SPARSE;
  } else {
    so->linear_solver_type = ceres::DENSE_QR;
  }
}

// Reweighted linear fits (IRLS) start every Ceres solve: at most this many, until
// no weight moves by the tolerance (from p = 0 Ceres crept: docs/tracker.md "Smoother").
const int kIrlsMaxIter = 200;
const double kIrlsWeightTol = 1e-5;
// fit_impl: Ceres polishes settled polynomial fits within this + 1e-4 x BIC of the lowest;
// unsettled ones within this + a tenth of their own (Ceres took up to 0.7 % off such costs).
const double kPolishMargin = 2.0, kUnsettledShare = 0.1;

// ---- parametric fits -----------------------------------------------------

struct PolyFit {
  int order = 1;              // 1: constant velocity, 2: constant acceleration
  double p[3][3] = {{0}};     // p[0] position, p[1] velocity, p[2] acceleration
  double cov[3][9] = {{0}};   // per axis, order+1 square
  double chi2 = 0;
  int outliers = 0;
  bool ok = false;
  bool polished = false;      // Ceres ran (poly_fit)
  int irls = 0;               // poly_start's verdict
};

// The polynomial by reweighted least squares per axis (IRLS, the robust
// weights shared by the axes as the loss shares them), in times scaled to
// [-1, 1] for long tracks' conditioning: Ceres from p = 0 crept there
// (bench_smooth, 1000 points: 4.9 -> 1.2 ms, acceleration 6.8 -> 1.5 ms).
// 2 when the weights settled (moving by under kIrlsWeightTol), 1 when not,
// 0 when no fit could be solved (p left as it was).
int poly_start(const Data &d, const Loss &loss, int order, double p[3][3])
{
  const int m = order + 1;
  double T = 0;
  for (size_t i = 0; i < d.n; i++) T = std::max(T, std::fabs(d.tau[i]));
  if (!(T > 0)) T = 1;
  // The first weights are the loss's at the data's mean at rest (p = 0,
  // where Ceres started before): unweighted least squares would start
  // from wherever an outlier pulls it, and a 5-point track (a blinking
  // bead's pulses) then settled in another minimum (blink seeds 1 and 3:
  // one track each, a point called an outlier or not).
  std::vector<double> w(d.n);
  for (size_t i = 0; i < d.n; i++) {
    double s = 0;
    for (int a = 0; a < 3; a++) s += d.x[3 * i + a] * d.x[3 * i + a] / (d.sig[3 * i + a] * d.sig[3 * i + a]);
    w[i] = loss.weight(s);
  }
  double q[3][3] = {{0}};  // coefficients in scaled time u = tau / T: sum_r q[r] u^r
  bool have = false, settled = false;
  for (int it = 0; it < kIrlsMaxIter; it++) {
    double M[3][9] = {{0}}, b[3][3] = {{0}};
    for (size_t i = 0; i < d.n; i++) {
      const double u = d.tau[i] / T, g[3] = {1, u, u * u};
      for (int a = 0; a < 3; a++) {
        const double wi = w[i] / (d.sig[3 * i + a] * d.sig[3 * i + a]);
        for (int r = 0; r < m; r++) {
          b[a][r] += wi * g[r] * d.x[3 * i + a];
          for (int c = 0; c < m; c++) M[a][r * m + c] += wi * g[r] * g[c];
        }
      }
    }
    bool solved = true;
    for (int a = 0; a < 3; a++) solved = solved && elfm_invert_small(M[a], m);
    if (!solved) break;  // too few distinct times (or weights): the last solution, if any
    for (int a = 0; a < 3; a++)
      for (int r = 0; r < m; r++) {
        q[a][r] = 0;
        for (int c = 0; c < m; c++) q[a][r] += M[a][r * m + c] * b[a][c];
      }
    have = true;
    double dw = 0;
    for (size_t i = 0; i < d.n; i++) {
      const double u = d.tau[i] / T;
      double s = 0;
      for (int a = 0; a < 3; a++) {
        const double pr = q[a][0] + q[a][1] * u + (m > 2 ? q[a][2] * u * u : 0);
        const double r = (pr - d.x[3 * i + a]) / d.sig[3 * i + a];
        s += r * r;
      }
      const double wn = loss.weight(s);
      dw = std::max(dw, std::fabs(wn - w[i]));
      w[i] = wn;
    }
    if (dw < kIrlsWeightTol) {
      settled = true;
      break;
    }
  }
  if (!have) return 0;  // Ceres starts from p as it is
  for (int a = 0; a < 3; a++) {
    p[0][a] = q[a][0];
    p[1][a] = q[a][1] / T;
    p[2][a] = m > 2 ? 2 * q[a][2] / (T * T) : 0;  // the model's 0.5 acc tau^2
  }
  return settled ? 2 : 1;
}

// Ceres from f->p (IRLS's fit, or 0 where it had none).
void poly_solve(const Data &d, const Loss &loss, int order, int max_iter, PolyFit *f)
{
  ceres::Problem::Options po;
  po.loss_function_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  ceres::Problem prob(po);
  std::unique_ptr<ceres::LossFunction> lf(loss.make());
  for (size_t i = 0; i < d.n; i++) {
    if (order == 1) {
      auto *r = new CvResidual{d.tau[i], {d.x[3 * i], d.x[3 * i + 1], d.x[3 * i + 2]},
                               {1 / d.sig[3 * i], 1 / d.sig[3 * i + 1], 1 / d.sig[3 * i + 2]}};
      prob.AddResidualBlock(new ceres::AutoDiffCostFunction<CvResidual, 3, 3, 3>(r), lf.get(),
                            f->p[0], f->p[1]);
    } else {
      auto *r = new CaResidual{d.tau[i], {d.x[3 * i], d.x[3 * i + 1], d.x[3 * i + 2]},
                               {1 / d.sig[3 * i], 1 / d.sig[3 * i + 1], 1 / d.sig[3 * i + 2]}};
      prob.AddResidualBlock(new ceres::AutoDiffCostFunction<CaResidual, 3, 3, 3, 3>(r), lf.get(),
                            f->p[0], f->p[1], f->p[2]);
    }
  }
  ceres::Solver::Options so;
  solver_options(&so, false, max_iter);
  ceres::Solver::Summary sum;
  ceres::Solve(so, &prob, &sum);
  f->ok = sum.IsSolutionUsable();
}

// At f->p: the robust chi2, the outliers and the covariance per axis
// (from the IRLS weights there).
void poly_stats(const Data &d, const Loss &loss, PolyFit *f)
{
  const int order = f->order;
  const int m = order + 1;
  double M[3][9] = {{0}};
  f->chi2 = 0;
  f->outliers = 0;
  for (size_t i = 0; i < d.n; i++) {
    double t = d.tau[i], g[3] = {1, t, 0.5 * t * t}, s = 0;
    double d2 = 0;
    for (int a = 0; a < 3; a++) {
      double pr = f->p[0][a] + f->p[1][a] * t + (order == 2 ? 0.5 * f->p[2][a] * t * t : 0);
      const double e = pr - d.x[3 * i + a], r = e / d.sig[3 * i + a];
      s += r * r;
      d2 += a == 2 ? e * e / 16 : e * e;
    }
    f->chi2 += loss.rho(s);
    double w = loss.weight(s);
    f->outliers += loss.outlier(s, d2);
    for (int a = 0; a < 3; a++) {
      double wi = w / (d.sig[3 * i + a] * d.sig[3 * i + a]);
      for (int r = 0; r < m; r++)
        for (int c = 0; c < m; c++) M[a][r * m + c] += wi * g[r] * g[c];
    }
  }
  for (int a = 0; a < 3; a++) {
    std::memcpy(f->cov[a], M[a], sizeof(double) * m * m);
    if (!elfm_invert_small(f->cov[a], m))
      for (int k = 0; k < m * m; k++) f->cov[a][k] = kNaN;
  }
}

// IRLS's fit; Ceres's where IRLS had none.
void poly_fit(const Data &d, const Loss &loss, int order, int max_iter, PolyFit *f)
{
  f->order = order;
  f->irls = poly_start(d, loss, order, f->p);
  f->polished = f->irls == 0;
  if (f->polished) poly_solve(d, loss, order, max_iter, f);
  else f->ok = true;
  poly_stats(d, loss, f);
}

// Ceres from IRLS's fit (poly_fit left it in f->p).
void poly_polish(const Data &d, const Loss &loss, int max_iter, PolyFit *f)
{
  f->polished = true;
  poly_solve(d, loss, f->order, max_iter, f);
  poly_stats(d, loss, f);
}

void poly_eval(const PolyFit &f, const Data &d, size_t nq, const int64_t *q, double *pos,
               double *vel, double *psd, double *vsd)
{
  const int m = f.order + 1;
  for (size_t k = 0; k < nq; k++) {
    double t = d.tau_of(q[k]);
    double g[3] = {1, t, 0.5 * t * t}, h[3] = {0, 1, t};
    for (int a = 0; a < 3; a++) {
      double acc = f.order == 2 ? f.p[2][a] : 0;
      if (pos) pos[3 * k + a] = f.p[0][a] + f.p[1][a] * t + 0.5 * acc * t * t + d.off[a];
      if (vel) vel[3 * k + a] = f.p[1][a] + acc * t;
      double vp = 0, vv = 0;
      for (int r = 0; r < m; r++)
        for (int c = 0; c < m; c++) {
          vp += g[r] * f.cov[a][r * m + c] * g[c];
          vv += h[r] * f.cov[a][r * m + c] * h[c];
        }
      if (psd) psd[3 * k + a] = vp >= 0 ? std::sqrt(vp) : kNaN;
      if (vsd) vsd[3 * k + a] = vv >= 0 ? std::sqrt(vv) : kNaN;
    }
  }
}

// ---- spline: the banded algebra is C (smooth_banded.c) ---------------------

// One workspace of it, freed with its owner.
struct Banded {
  elfm_banded w;
  Banded() { elfm_banded_init(&w); }
  ~Banded() { elfm_banded_free(&w); }
  Banded(const Banded &) = delete;
  Banded &operator=(const Banded &) = delete;
};

struct SplineSetup {
  std::vector<double> ts;           // state times (ms, relative)
  std::vector<int64_t> ts_abs;      // state times (us, absolute)
  std::vector<size_t> state_of;     // data i -> state
  std::vector<double> coef;         // the prior's rows (elfm_spline_prior_table)
  double sig_ref[3] = {1, 1, 1};
  int order = 2;                    // penalised derivative: 2 acceleration, 3 jerk
};

// The linear fit and GCV are C (smooth_banded.c): this views the data there.
elfm_spline_problem spline_problem(const Data &d, const SplineSetup &ss)
{
  elfm_spline_problem sp;
  sp.n = d.n;
  sp.K = ss.ts.size();
  sp.x = d.x.data();
  sp.sig = d.sig.data();
  sp.ts = ss.ts.data();
  sp.sig_ref = ss.sig_ref;
  sp.state_of = ss.state_of.data();
  sp.order = ss.order;
  sp.coef = ss.coef.empty() ? nullptr : ss.coef.data();
  sp.iso = elfm_spline_isotropic(&sp);
  sp.lambda_unit = elfm_spline_lambda_unit(sp.ts, sp.K, sp.order);
  return sp;
}

struct SplineFit {
  double lambda = 1;
  std::vector<double> p;        // K x 3 (centred)
  std::vector<double> z0[3], z1[3], z2[3];
  double chi2 = 0, edf = 0;
  int outliers = 0;
  bool ok = false, polished = false;  // polished: Ceres ran
};

// Robust spline at lambda through Ceres, started from the linear solution.
bool spline_ceres(const Data &d, const SplineSetup &ss, const Loss &loss, double lambda,
                  bool sparse, int max_iter, std::vector<double> &p)
{
  const size_t K = ss.ts.size();
  ceres::Problem::Options po;
  po.loss_function_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  ceres::Problem prob(po);
  std::unique_ptr<ceres::LossFunction> lf(loss.make());
  for (size_t k = 0; k < K; k++) prob.AddParameterBlock(&p[3 * k], 3);
  for (size_t i = 0; i < d.n; i++) {
    auto *r = new PointResidual{{d.x[3 * i], d.x[3 * i + 1], d.x[3 * i + 2]},
                                {1 / d.sig[3 * i], 1 / d.sig[3 * i + 1], 1 / d.sig[3 * i + 2]}};
    prob.AddResidualBlock(new ceres::AutoDiffCostFunction<PointResidual, 3, 3>(r), lf.get(),
                          &p[3 * ss.state_of[i]]);
  }
  const double sl = std::sqrt(lambda);
  const double scale[3] = {sl / ss.sig_ref[0], sl / ss.sig_ref[1], sl / ss.sig_ref[2]};
  for (size_t k = 0; k + (size_t)ss.order < K; k++) {  // states k .. k + order
    const double *c = &ss.coef[4 * k];  // the fit's table (elfm_spline_prior_table)
    if (ss.order == 3)
      prob.AddResidualBlock(new ceres::AutoDiffCostFunction<JerkResidual, 3, 3, 3, 3, 3>(
                                new JerkResidual{{c[0], c[1], c[2], c[3]}, {scale[0], scale[1], scale[2]}}),
                            nullptr, &p[3 * k], &p[3 * (k + 1)], &p[3 * (k + 2)], &p[3 * (k + 3)]);
    else
      prob.AddResidualBlock(new ceres::AutoDiffCostFunction<AccelResidual, 3, 3, 3, 3>(
                                new AccelResidual{c[0], c[1], c[2], {scale[0], scale[1], scale[2]}}),
                            nullptr, &p[3 * k], &p[3 * (k + 1)], &p[3 * (k + 2)]);
  }
  ceres::Solver::Options so;
  solver_options(&so, sparse, max_iter);
  ceres::Solver::Summary sum;
  ceres::Solve(so, &prob, &sum);
  return sum.IsSolutionUsable();
}

// The robust weights at p into w, and where asked (not while reweighting), the robust cost and
// the outliers' count: the Cauchy loss's log1p per point was paid at every reweighting step.
void robust_weights(const Data &d, const SplineSetup &ss, const Loss &loss,
                    const std::vector<double> &p, std::vector<double> &w, double *chi2,
                    int *outliers)
{
  if (chi2) *chi2 = 0;
  if (outliers) *outliers = 0;
  for (size_t i = 0; i < d.n; i++) {
    double s = 0, d2 = 0;
    for (int a = 0; a < 3; a++) {
      const double e = p[3 * ss.state_of[i] + a] - d.x[3 * i + a], r = e / d.sig[3 * i + a];
      s += r * r;
      d2 += a == 2 ? e * e / 16 : e * e;
    }
    w[i] = loss.weight(s);
    if (chi2) *chi2 += loss.rho(s);
    if (outliers) *outliers += loss.outlier(s, d2);
  }
}

// Reweighted linear fits at lambda from p (the robust weights shared by the
// axes, as the loss shares them) until the weights settle: p and w then
// hold the last fit and the weights at it. The loss's minimum (or
// another stationary point): each step lowers the robust cost, as both
// losses are concave in the squared residual.
void spline_irls(const Data &d, const SplineSetup &ss, const elfm_spline_problem &sp,
                 const Loss &loss, double lam, Banded *bd, std::vector<double> &work,
                 std::vector<double> &w, std::vector<double> &p)
{
  double rss = 0;
  std::vector<double> w0(d.n), q(p.size());
  robust_weights(d, ss, loss, p, w, nullptr, nullptr);
  for (int it = 0; it < kIrlsMaxIter; it++) {
    // A step whose weights leave the system singular (nearly every point
    // weighed ~0) keeps the last fit: Ceres goes on from there.
    // No edf (NULL): the states alone, without the band of A^-1, which
    // was a third of each step's work and most of the smoothing's time
    // went to these steps (38 on average, flow 1 s seed 1).
    if (!elfm_spline_linear(&sp, w.data(), lam, &bd->w, work.data(), &rss, nullptr, q.data())) {
      robust_weights(d, ss, loss, p, w, nullptr, nullptr);
      break;
    }
    p.swap(q);
    w0.swap(w);
    robust_weights(d, ss, loss, p, w, nullptr, nullptr);
    double dw = 0;
    for (size_t i = 0; i < d.n; i++) dw = std::max(dw, std::fabs(w[i] - w0[i]));
    if (dw < kIrlsWeightTol) break;
  }
}

bool spline_fit(const Data &d, const SplineSetup &ss, const Loss &loss, double lambda_given,
                double gcv_gamma, bool sparse, int max_iter, SplineFit *f)
{
  const size_t K = ss.ts.size();
  const elfm_spline_problem sp = spline_problem(d, ss);
  std::vector<double> w(d.n, 1.0), work(5 * K + 1);
  // GCV's weight: whole decades, then downhill on the half-decade grid
  // (elfm_spline_gcv_lambda_coarse): 15-16 fits, not the grid's 25, and the
  // same weight in 5159 of 5160 on 162 recordings (docs/tracker.md "The
  // spline's weight in fewer fits").
  double lam = lambda_given > 0 ? lambda_given : elfm_spline_gcv_lambda_coarse(&sp, w.data(), gcv_gamma);
  // Beyond these the banded factorisation loses its digits (condition
  // ~ lambda / (sigma^2 h^(2 order - 1))); the ends are already "interpolate"
  // and "line". In the unit of the states' spacing, as GCV's grid.
  const double lo = 1e-9 * sp.lambda_unit, hi = 1e9 * sp.lambda_unit;
  lam = std::min(std::max(lam, lo), hi);
  Banded bd;
  double rss, edf;
  f->p.assign(3 * K, 0.0);
  if (!elfm_spline_linear(&sp, w.data(), lam, &bd.w, work.data(), &rss, &edf, f->p.data()))
    return false;
  if (loss.kind != ELFM_LOSS_NONE) {
    if (lambda_given <= 0) {
      // Outliers can bias the GCV choice: choose again without them. Their
      // weights come from IRLS at the first weight, not from a first Ceres
      // solve, and the one Ceres solve, at the weight chosen, starts from
      // IRLS there (it started from the unweighted linear fit, Ceres
      // taking 13.4 iterations on worm 0.5 s seed 1; now 1). The same GCV
      // weight in all 223 fits of worm 0.5 s seeds 1-6; the Cauchy loss
      // has more than one minimum, and 22 ended in another, 14 of them
      // lower (by up to 11 %), 8 higher (one by 6.6 %, the rest < 0.1 %).
      spline_irls(d, ss, sp, loss, lam, &bd, work, w, f->p);
      // Whole decades, then the half-decade walk, as the first choice: not
      // a walk from the first choice, which the robust weights' score can
      // have left for another basin (the 640 x 480 sensor seed 15: from
      // 2.7e5 downhill to 1.5e8, where the whole grid's least was at 13).
      lam = std::min(std::max(elfm_spline_gcv_lambda_coarse(&sp, w.data(), gcv_gamma), lo), hi);
    }
    spline_irls(d, ss, sp, loss, lam, &bd, work, w, f->p);
    if (max_iter > 0 && !spline_ceres(d, ss, loss, lam, sparse, max_iter, f->p)) return false;
    f->polished = max_iter > 0;
    robust_weights(d, ss, loss, f->p, w, &f->chi2, &f->outliers);
  } else {
    robust_weights(d, ss, loss, f->p, w, &f->chi2, &f->outliers);
  }
  f->lambda = lam;
  // Posterior band of A^-1 per axis at the final robust weights.
  f->edf = 0;
  std::vector<double> W(K), dummy;
  for (int a = 0; a < 3; a++) {
    std::fill(W.begin(), W.end(), 0.0);
    for (size_t i = 0; i < d.n; i++)
      W[ss.state_of[i]] += w[i] / (d.sig[3 * i + a] * d.sig[3 * i + a]);
    if (!elfm_banded_resize(&bd.w, K)) return false;
    elfm_banded_build_table(&bd.w, W.data(), ss.coef.data(), lam / (ss.sig_ref[a] * ss.sig_ref[a]),
                            ss.order);
    if (!elfm_banded_factor(&bd.w)) return false;
    elfm_banded_inverse(&bd.w);
    f->z0[a].assign(bd.w.z[0], bd.w.z[0] + K + 3);
    f->z1[a].assign(bd.w.z[1], bd.w.z[1] + K + 3);
    f->z2[a].assign(bd.w.z[2], bd.w.z[2] + K + 3);
    for (size_t k = 0; k < K; k++) f->edf += bd.w.z[0][k] * W[k];
  }
  f->ok = true;
  return true;
}

void spline_eval(const SplineFit &f, const SplineSetup &ss, const Data &d, size_t nq,
                 const int64_t *q, double *pos, double *vel, double *psd, double *vsd)
{
  const size_t K = ss.ts.size();
  for (size_t j = 0; j < nq; j++) {
    size_t k = (size_t)(std::lower_bound(ss.ts_abs.begin(), ss.ts_abs.end(), q[j]) -
                        ss.ts_abs.begin());
    if (k >= K) k = K - 1;
    // velocity: central difference inside, one-sided at the ends
    size_t km = k > 0 ? k - 1 : k, kp = k + 1 < K ? k + 1 : k;
    double dt = ss.ts[kp] - ss.ts[km];
    for (int a = 0; a < 3; a++) {
      if (pos) pos[3 * j + a] = f.p[3 * k + a] + d.off[a];
      if (vel) vel[3 * j + a] = (f.p[3 * kp + a] - f.p[3 * km + a]) / dt;
      if (psd) psd[3 * j + a] = std::sqrt(std::max(f.z0[a][k], 0.0));
      if (vsd) {
        // cov(p_kp, p_km): offset 1 or 2 in the band
        size_t off = kp - km;
        double c = off == 2 ? f.z2[a][km] : f.z1[a][km];
        double v = (f.z0[a][kp] + f.z0[a][km] - 2 * c) / (dt * dt);
        vsd[3 * j + a] = std::sqrt(std::max(v, 0.0));
      }
    }
  }
}

elfm_status fit_impl(const elfm_smooth_options *o, size_t n, const int64_t *t_us,
                     const double *xyz, const double *sigma, size_t nq, const int64_t *q,
                     double *pos, double *vel, double *psd, double *vsd, elfm_smooth_info *info,
                     elfm_error *err)
{
  elfm_smooth_info inf;
  std::memset(&inf, 0, sizeof inf);
  for (double &b : inf.bic) b = kNaN;
  // ---- validation
  if (!o || n == 0 || !t_us || !xyz || (nq > 0 && !q))
    return elfm_error_set(err, ELFM_ERR_INVALID, nullptr, -1, "smooth: no data or NULL argument");
  if (!(o->loss_scale > 0) || !std::isfinite(o->loss_scale) || o->max_iterations < 1 ||
      !(o->min_sigma_xy_um > 0) || !(o->min_sigma_z_um > 0) || !std::isfinite(o->spline_weight_ms3) ||
      !(o->gcv_gamma >= 1) || !std::isfinite(o->gcv_gamma) ||
      (o->spline_order != 2 && o->spline_order != 3) ||
      !(o->spline_omega_rad_per_ms >= 0 && o->spline_omega_rad_per_ms <= 1e3) ||
      o->model < ELFM_MODEL_AUTO || o->model > ELFM_MODEL_STATIC ||
      !(o->outlier_min_um >= 0 && o->outlier_min_um <= 1e6))
    return elfm_error_set(err, ELFM_ERR_INVALID, nullptr, -1, "smooth: options out of range");
  for (size_t i = 0; i < n; i++) {
    for (int a = 0; a < 3; a++) {
      if (!std::isfinite(xyz[3 * i + a]))
        return elfm_error_set(err, ELFM_ERR_NUMERIC, nullptr, -1,
                              "smooth: point %zu has a non-finite coordinate", i);
      if (sigma && !(sigma[3 * i + a] > 0 && std::isfinite(sigma[3 * i + a])))
        return elfm_error_set(err, ELFM_ERR_NUMERIC, nullptr, -1,
                              "smooth: point %zu has a sigma that is not finite and > 0", i);
    }
    if (i && t_us[i] < t_us[i - 1])
      return elfm_error_set(err, ELFM_ERR_INVALID, nullptr, -1,
                            "smooth: times decrease at point %zu", i);
  }
  for (size_t k = 1; k < nq; k++)
    if (q[k] < q[k - 1])
      return elfm_error_set(err, ELFM_ERR_INVALID, nullptr, -1, "smooth: query times decrease");
  // a span beyond 2^53 us would lose integer precision in double ms
  if ((double)(t_us[n - 1] - t_us[0]) > 9e15 || (nq && (double)(q[nq - 1] - q[0]) > 9e15))
    return elfm_error_set(err, ELFM_ERR_RANGE, nullptr, -1, "smooth: time span too large");

  // ---- prepare: reference time, centred positions, sigmas
  Data d;
  d.n = n;
  d.t_ref = t_us[0];
  d.t_mid_ms = 0.5 * (double)(t_us[n - 1] - t_us[0]) * 1e-3;
  d.tau.resize(n);
  d.x.resize(3 * n);
  d.sig.resize(3 * n);
  for (size_t i = 0; i < n; i++) d.tau[i] = d.tau_of(t_us[i]);
  for (int a = 0; a < 3; a++) {
    double s = 0;
    for (size_t i = 0; i < n; i++) s += xyz[3 * i + a];
    d.off[a] = s / (double)n;
  }
  for (size_t i = 0; i < n; i++)
    for (int a = 0; a < 3; a++) d.x[3 * i + a] = xyz[3 * i + a] - d.off[a];
  if (sigma) {
    for (size_t i = 0; i < 3 * n; i++) d.sig[i] = sigma[i];
    for (int a = 0; a < 3; a++) {
      std::vector<double> s(n);
      for (size_t i = 0; i < n; i++) s[i] = sigma[3 * i + a];
      std::nth_element(s.begin(), s.begin() + n / 2, s.end());
      inf.sigma_um[a] = s[n / 2];
    }
  } else {
    elfm_status st = elfm_smooth_estimate_noise(o, n, t_us, xyz, inf.sigma_um, err);
    if (st != ELFM_OK) return st;
    for (size_t i = 0; i < n; i++)
      for (int a = 0; a < 3; a++) d.sig[3 * i + a] = inf.sigma_um[a];
  }
  size_t distinct = 1;
  for (size_t i = 1; i < n; i++) distinct += t_us[i] != t_us[i - 1];
  Loss loss{o->loss, o->loss_scale, o->outlier_min_um * o->outlier_min_um};
  const double lnobs = std::log(3.0 * (double)n);

  // ---- static: one time only (or asked for)
  if (distinct == 1 || o->model == ELFM_MODEL_STATIC) {
    double m[3], sw[3];
    for (int a = 0; a < 3; a++) {
      double s = 0, sx = 0;
      for (size_t i = 0; i < n; i++) {
        double w = 1 / (d.sig[3 * i + a] * d.sig[3 * i + a]);
        s += w;
        sx += w * d.x[3 * i + a];
      }
      m[a] = sx / s;
      sw[a] = s;
    }
    for (size_t k = 0; k < nq; k++)
      for (int a = 0; a < 3; a++) {
        if (pos) pos[3 * k + a] = m[a] + d.off[a];
        if (vel) vel[3 * k + a] = distinct == 1 ? 0.0 : 0.0;
        if (psd) psd[3 * k + a] = std::sqrt(1 / sw[a]);
        if (vsd) vsd[3 * k + a] = kNaN;  // undetermined
      }
    inf.model = ELFM_MODEL_STATIC;
    inf.edf = 1;
    if (info) *info = inf;
    return ELFM_OK;
  }

  // ---- candidate models
  elfm_motion_model want = o->model;
  bool try_cv = want == ELFM_MODEL_AUTO || want == ELFM_MODEL_CONST_VELOCITY;
  bool try_ca = (want == ELFM_MODEL_AUTO || want == ELFM_MODEL_CONST_ACCEL) && distinct >= 3;
  // the spline needs more distinct times than its stiff limit has parameters
  bool try_sp = ((want == ELFM_MODEL_AUTO && o->allow_spline) || want == ELFM_MODEL_SPLINE) &&
                distinct >= (size_t)o->spline_order + 2;
  if (!try_ca && !try_sp) try_cv = true;  // what the data allow
  PolyFit cv, ca;
  SplineFit sp;
  SplineSetup ss;
  if (try_cv) poly_fit(d, loss, 1, o->max_iterations, &cv);
  if (try_ca) poly_fit(d, loss, 2, o->max_iterations, &ca);
  if (try_sp) {
    // states: union of data and query times
    std::vector<int64_t> all(t_us, t_us + n);
    all.insert(all.end(), q, q + nq);
    std::sort(all.begin(), all.end());
    all.erase(std::unique(all.begin(), all.end()), all.end());
    ss.ts_abs = all;
    ss.order = o->spline_order;
    ss.ts.resize(all.size());
    for (size_t k = 0; k < all.size(); k++) ss.ts[k] = d.tau_of(all[k]);
    ss.coef.assign(4 * ss.ts.size(), 0.0);
    if (ss.order == 3 && o->spline_omega_rad_per_ms > 0)
      elfm_spline_prior_table_omega(ss.ts.data(), ss.ts.size(), o->spline_omega_rad_per_ms,
                                    ss.coef.data());
    else
      elfm_spline_prior_table(ss.ts.data(), ss.ts.size(), ss.order, ss.coef.data());
    ss.state_of.resize(n);
    for (size_t i = 0; i < n; i++)
      ss.state_of[i] = (size_t)(std::lower_bound(all.begin(), all.end(), t_us[i]) - all.begin());
    for (int a = 0; a < 3; a++) {
      std::vector<double> s(n);
      for (size_t i = 0; i < n; i++) s[i] = d.sig[3 * i + a];
      std::nth_element(s.begin(), s.begin() + n / 2, s.end());
      ss.sig_ref[a] = s[n / 2];
    }
    bool sparse = o->solver == ELFM_SOLVER_SPARSE ||
                  (o->solver == ELFM_SOLVER_AUTO && ss.ts.size() > 30);
    const int iters = o->irls_only ? 0 : o->max_iterations;  // 0: IRLS's fit, no Ceres
    if (spline_fit(d, ss, loss, o->spline_weight_ms3, o->gcv_gamma, sparse, iters, &sp) &&
        sp.ok)
      inf.bic[ELFM_MODEL_SPLINE] = sp.chi2 + sp.edf * lnobs;
  }
  // ---- Ceres polishes each polynomial that could be chosen (its IRLS BIC
  // near the lowest; a polished one may fall under another: that one too).
  // From settled weights Ceres's 6-7 steps left the cost the same to 1e-6,
  // and a curved track's spline lies hundreds of units lower: the solves
  // were for models no track kept (docs/tracker.md "Fewer Ceres solves").
  PolyFit *const poly[2] = {try_cv ? &cv : nullptr, try_ca ? &ca : nullptr};
  const elfm_motion_model poly_model[2] = {ELFM_MODEL_CONST_VELOCITY, ELFM_MODEL_CONST_ACCEL};
  for (bool again = true; again;) {
    for (int j = 0; j < 2; j++)  // 3 (order + 1) parameters
      if (poly[j] && poly[j]->ok) inf.bic[poly_model[j]] = poly[j]->chi2 + 3 * (poly[j]->order + 1) * lnobs;
    double lo = std::numeric_limits<double>::infinity();
    for (double b : inf.bic)
      if (b < lo) lo = b;  // NaN (not fitted) never
    again = false;
    for (int j = 0; j < 2; j++) {
      PolyFit *f = poly[j];
      if (!f || f->polished || o->irls_only) continue;
      const double b = inf.bic[poly_model[j]];
      if (b >= lo + kPolishMargin + (f->irls == 2 ? 1e-4 * std::fabs(lo) : kUnsettledShare * std::fabs(b)))
        continue;
      poly_polish(d, loss, o->max_iterations, f);
      if (!f->ok) inf.bic[poly_model[j]] = kNaN;
      again = true;
    }
  }
  // ---- choose: lowest BIC, ties (within 1e-9 relative) to the simpler
  elfm_motion_model best = ELFM_MODEL_AUTO;
  double bb = std::numeric_limits<double>::infinity();
  for (elfm_motion_model m : {ELFM_MODEL_CONST_VELOCITY, ELFM_MODEL_CONST_ACCEL, ELFM_MODEL_SPLINE}) {
    double b = inf.bic[m];
    if (std::isfinite(b) && (!std::isfinite(bb) || b < bb - 1e-9 * std::fabs(bb))) {
      bb = b;
      best = m;
    }
  }
  if (best == ELFM_MODEL_AUTO)
    return elfm_error_set(err, ELFM_ERR_NUMERIC, nullptr, -1,
                          "smooth: no model could be fitted (%zu points)", n);
  inf.model = best;
  if (best == ELFM_MODEL_SPLINE) {
    spline_eval(sp, ss, d, nq, q, pos, vel, psd, vsd);
    inf.spline_weight_ms3 = sp.lambda;
    inf.edf = sp.edf / 3;
    inf.n_outliers = sp.outliers;
    inf.ceres = sp.polished;
  } else {
    const PolyFit &f = best == ELFM_MODEL_CONST_ACCEL ? ca : cv;
    poly_eval(f, d, nq, q, pos, vel, psd, vsd);
    inf.edf = f.order + 1;
    inf.n_outliers = f.outliers;
    inf.ceres = f.polished;
    if (best == ELFM_MODEL_CONST_ACCEL)
      for (int a = 0; a < 3; a++) inf.accel_um_per_ms2[a] = f.p[2][a];
  }
  if (info) *info = inf;
  return ELFM_OK;
}

}  // namespace

extern "C" {

elfm_status elfm_smooth_fit(const elfm_smooth_options *o, size_t n, const int64_t *t_us,
                            const double *xyz_um, const double *sigma_um, size_t nq,
                            const int64_t *q_t_us, double *pos_um, double *vel_um_per_ms,
                            double *pos_sd_um, double *vel_sd_um_per_ms, elfm_smooth_info *info,
                            elfm_error *err)
{
  try {
    const elfm_status st = fit_impl(o, n, t_us, xyz_um, sigma_um, nq, q_t_us, pos_um, vel_um_per_ms,
                                    pos_sd_um, vel_sd_um_per_ms, info, err);
    // Without sigmas from the caller, uncertainties scaled by the noise
    // floors would claim 0.02 um for a lone point: undetermined instead.
    if (st == ELFM_OK && !sigma_um && !elfm_smooth_noise_known(n, t_us))
      for (size_t i = 0; i < 3 * nq; i++) {
        if (pos_sd_um) pos_sd_um[i] = kNaN;
        if (vel_sd_um_per_ms) vel_sd_um_per_ms[i] = kNaN;
      }
    return st;
  } catch (const std::bad_alloc &) {
    return elfm_error_set(err, ELFM_ERR_NOMEM, nullptr, -1, "smooth: out of memory");
  } catch (...) {
    return elfm_error_set(err, ELFM_ERR_NUMERIC, nullptr, -1, "smooth: solver failed");
  }
}

}  // extern "C"
