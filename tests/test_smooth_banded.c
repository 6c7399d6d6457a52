/* test_smooth_banded.c — the smoothing spline's banded algebra
 * (tracker/smooth_banded.c): for both orders, on uneven state times (gaps)
 * and weights with zeros (gap frames), the LDL^T solve returns x with
 * A x = rhs, and the selected inverse's band equals A^-1 computed column by
 * column through the solve; the prior's rows vanish on a polynomial one
 * degree below the penalised derivative and give its derivative on one of
 * that degree; the linear fit and GCV on a noisy smooth path; a matrix
 * that is not positive definite is refused. */
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "check.h"
#include "smooth_banded.h"

enum { K = 60 };

/* (A x)[k] from the rows the build sums: diag(W) x + mu sum_r c_r (c_r . x). */
static void apply_a(const double *W, const double *ts, double mu, int order, const double *x,
                    double *y)
{
  for (size_t k = 0; k < K; k++) y[k] = W[k] * x[k];
  for (size_t k = 0; k + (size_t)order + 1 <= K; k++) {
    double c[4], dot = 0;
    elfm_spline_prior_coef(ts, order, k, c);
    for (int i = 0; i <= order; i++) dot += c[i] * x[k + i];
    for (int i = 0; i <= order; i++) y[k + i] += mu * c[i] * dot;
  }
}

int main(void)
{
  double ts[K], W[K], rhs[K], x[K], y[K], col[K], e[K];
  for (int k = 0, f = 0; k < K; k++) {
    f += k % 13 == 5 ? 4 : 1; /* gaps of 3 frames */
    ts[k] = 0.5 * f;
    W[k] = k % 7 == 3 ? 0 : 1 + 0.5 * sin(k); /* gap-filled states carry no data */
    rhs[k] = cos(0.3 * k) + 0.01 * k;
  }
  for (int order = 2; order <= 3; order++) {
    /* the prior's rows: zero on a polynomial of degree order - 1, the
     * order-th derivative x sqrt(hbar) on one of degree order */
    double c[4], worst0 = 0, worst1 = 0;
    for (size_t k = 0; k + (size_t)order + 1 <= K; k++) {
      elfm_spline_prior_coef(ts, order, k, c);
      double lo = 0, hi = 0;
      for (int i = 0; i <= order; i++) {
        const double t = ts[k + i];
        lo += c[i] * (order == 2 ? 3 - 2 * t : 1 + t - 0.25 * t * t);
        hi += c[i] * pow(t, order);
      }
      const double hb = (ts[k + order] - ts[k]) / order, fact = order == 2 ? 2 : 6;
      worst0 = fmax(worst0, fabs(lo));
      worst1 = fmax(worst1, fabs(hi / sqrt(hb) - fact));
    }
    CHECK(worst0 < 1e-9);
    CHECK(worst1 < 1e-9);
    for (int im = 0; im < 3; im++) {
      const double mu = im == 0 ? 1e-3 : im == 1 ? 1 : 1e3;
      elfm_banded bd;
      elfm_banded_init(&bd);
      CHECK(elfm_banded_resize(&bd, K));
      elfm_banded_build(&bd, W, ts, mu, order);
      CHECK(elfm_banded_factor(&bd));
      elfm_banded_solve(&bd, rhs, x);
      apply_a(W, ts, mu, order, x, y);
      double res = 0, scale = 0;
      for (int k = 0; k < K; k++) {
        res = fmax(res, fabs(y[k] - rhs[k]));
        scale = fmax(scale, fabs(rhs[k]));
      }
      CHECK(res < 1e-8 * scale);
      /* the band of A^-1 against its columns */
      elfm_banded_inverse(&bd);
      double worst = 0, big = 0;
      for (int q = 0; q < K; q++) {
        memset(e, 0, sizeof e);
        e[q] = 1;
        elfm_banded_solve(&bd, e, col); /* A^-1 e_q: column q */
        for (int d = 0; d <= order && q - d >= 0; d++) {
          worst = fmax(worst, fabs(bd.z[d][q - d] - col[q - d]));
          big = fmax(big, fabs(col[q - d]));
        }
      }
      CHECK(worst < 1e-9 * big);
      elfm_banded_free(&bd);
    }
  }
  /* The linear fit and GCV on noisy points of a smooth path (one per
   * state, sigmas 0.2 um): the fit lies nearer the path than the points,
   * its edf falls as lambda grows, and pricing each effective parameter
   * higher (gamma 5) never chooses a more flexible fit than classical GCV */
  {
    double x3[3 * K], sig[3 * K], w[K], p[3 * K], work[5 * K + 1], sref[3] = {0.2, 0.2, 0.2};
    size_t st[K];
    uint64_t r = 12345;
    double raw = 0;
    for (int k = 0; k < K; k++) {
      st[k] = (size_t)k;
      w[k] = 1;
      for (int a = 0; a < 3; a++) {
        r ^= r << 13; r ^= r >> 7; r ^= r << 17;
        const double u = (double)(r >> 11) / 9007199254740992.0 - 0.5;
        const double truth = a == 0 ? sin(0.1 * ts[k]) : a == 1 ? 0.02 * ts[k] * ts[k] : 1;
        x3[3 * k + a] = truth + 0.2 * 1.7 * u; /* uniform of sd 0.2 x 0.49 */
        sig[3 * k + a] = 0.2;
        raw += (x3[3 * k + a] - truth) * (x3[3 * k + a] - truth);
      }
    }
    for (int order = 2; order <= 3; order++) {
      const elfm_spline_problem sp = {K, K, x3, sig, ts, sref, st, order, NULL, 0, 0};
      const double l1 = elfm_spline_gcv_lambda(&sp, w, 1), l5 = elfm_spline_gcv_lambda(&sp, w, 5);
      CHECK(l5 >= l1);
      /* the prior's rows from a table: the same numbers, so the same bits
       * (the smoother uses the table; without it each build recomputes) */
      {
        static double coef[4 * K];
        elfm_spline_prior_table(ts, K, order, coef);
        elfm_spline_problem spt = sp;
        spt.coef = coef;
        CHECK(elfm_spline_gcv_lambda(&spt, w, 1) == l1);
        /* whole decades, then the walk: the whole grid's weight, for both
         * prices (this path's scores fall steadily to their least) */
        CHECK(elfm_spline_gcv_lambda_coarse(&sp, w, 1) == l1);
        CHECK(elfm_spline_gcv_lambda_coarse(&sp, w, 5) == l5);
        double pa[3 * K], pb[3 * K], ra, rb, ea, eb;
        elfm_banded b1, b2;
        elfm_banded_init(&b1);
        elfm_banded_init(&b2);
        CHECK(elfm_spline_linear(&sp, w, 3.7, &b1, work, &ra, &ea, pa));
        CHECK(elfm_spline_linear(&spt, w, 3.7, &b2, work, &rb, &eb, pb));
        CHECK(ra == rb && ea == eb && memcmp(pa, pb, sizeof pa) == 0);
        CHECK(memcmp(b1.z[0], b2.z[0], K * sizeof *b1.z[0]) == 0);
        /* without edf (reweighting's steps) the same states and RSS, bit
         * for bit, with A^-1 not formed; in a workspace used before for
         * a longer track (nothing of that one's may leak in) */
        double pc[3 * K], rc;
        CHECK(elfm_spline_linear(&spt, w, 3.7, &b1, work, &rc, NULL, pc));
        CHECK(rc == ra && memcmp(pa, pc, sizeof pa) == 0);
        elfm_spline_problem sps = spt;
        sps.K = sps.n = K / 2;
        double pd[3 * K], rd, ec, ed;
        elfm_banded b3;
        elfm_banded_init(&b3);
        CHECK(elfm_spline_linear(&sps, w, 3.7, &b1, work, &rc, &ec, pc));
        CHECK(elfm_spline_linear(&sps, w, 3.7, &b3, work, &rd, &ed, pd));
        CHECK(rc == rd && ec == ed && memcmp(pc, pd, 3 * (K / 2) * sizeof *pc) == 0);
        CHECK(memcmp(b1.z[1], b3.z[1], (K / 2 + 3) * sizeof *b1.z[1]) == 0);
        elfm_banded_free(&b3);
        elfm_banded_free(&b1);
        elfm_banded_free(&b2);
      }
      /* Sigmas one factor per point times one per axis (as the tracker
       * gives them): the axes share one factorisation (iso), and the fit
       * is the one with a matrix per axis, to rounding; with the axes'
       * factors not proportional, elfm_spline_isotropic says so. */
      {
        double sg[3 * K], wv[K], ref[3] = {0.3, 0.45, 1.2};
        for (int k = 0; k < K; k++) {
          const double f = 0.5 + 0.37 * (double)((k * 7) % 11);
          wv[k] = k % 5 == 3 ? 0.05 : 1.0 / (1.0 + 0.1 * (double)(k % 3));
          for (int a = 0; a < 3; a++) sg[3 * k + a] = f * ref[a];
        }
        elfm_spline_problem pa = sp, pi;
        pa.sig = sg;
        pa.sig_ref = ref;
        pi = pa;
        CHECK(elfm_spline_isotropic(&pa) == 1);
        pi.iso = 1;
        double qa[3 * K], qi[3 * K], ra, ri, ea, ei;
        elfm_banded b1;
        elfm_banded_init(&b1);
        for (double lam = 1e-3; lam <= 1e5; lam *= 100) {
          CHECK(elfm_spline_linear(&pa, wv, lam, &b1, work, &ra, &ea, qa));
          CHECK(elfm_spline_linear(&pi, wv, lam, &b1, work, &ri, &ei, qi));
          /* to rounding: the stiff end's condition (~lambda / (sigma^2
           * h^3)) magnifies it, 1e-7 of the path's span at 1e5 here */
          double dmax = 0, span = 0;
          for (int i = 0; i < 3 * K; i++) {
            dmax = fmax(dmax, fabs(qa[i] - qi[i]));
            span = fmax(span, fabs(x3[i]));
          }
          CHECK_MSG(dmax < 1e-6 * span && fabs(ra - ri) <= 1e-7 * ra && fabs(ea - ei) <= 1e-7 * ea,
                    "order %d lambda %g: states %.3g apart, rss %.17g / %.17g, edf %.17g / %.17g",
                    order, lam, dmax, ra, ri, ea, ei);
          double rn;
          CHECK(elfm_spline_linear(&pi, wv, lam, &b1, work, &rn, NULL, qa));
          CHECK(rn == ri && memcmp(qa, qi, sizeof qa) == 0);
        }
        /* three right sides at once: each the one-at-a-time solve's bits,
         * in place (b1 holds the last shared factorisation) */
        {
          double r3[3][K], one[K];
          double *const xs[3] = {r3[0], r3[1], r3[2]};
          for (int a = 0; a < 3; a++)
            for (int k = 0; k < K; k++) r3[a][k] = x3[3 * k + a] * (1.0 + 0.1 * a);
          double want[3][K];
          for (int a = 0; a < 3; a++) {
            memcpy(one, r3[a], sizeof one);
            elfm_banded_solve(&b1, one, want[a]);
          }
          elfm_banded_solve3(&b1, xs);
          CHECK(memcmp(r3, want, sizeof r3) == 0);
        }
        CHECK(elfm_spline_gcv_lambda(&pa, wv, 1) == elfm_spline_gcv_lambda(&pi, wv, 1));
        sg[3 * 4 + 1] *= 1.001; /* one point's y no longer in step */
        CHECK(elfm_spline_isotropic(&pa) == 0);
        sg[3 * 4 + 1] /= 1.001;
        ref[2] = 0; /* no reference: no sharing */
        CHECK(elfm_spline_isotropic(&pa) == 0);
        elfm_banded_free(&b1);
      }
      elfm_banded bd;
      elfm_banded_init(&bd);
      double rss, edf, prev_edf = INFINITY, fit = 0;
      for (double lam = 1e-3; lam <= 1e5; lam *= 10) {
        CHECK(elfm_spline_linear(&sp, w, lam, &bd, work, &rss, &edf, p));
        CHECK(edf < prev_edf && edf > 0 && edf <= 3 * K);
        prev_edf = edf;
      }
      CHECK(elfm_spline_linear(&sp, w, l1, &bd, work, &rss, &edf, p));
      for (int k = 0; k < K; k++)
        for (int a = 0; a < 3; a++) {
          const double truth = a == 0 ? sin(0.1 * ts[k]) : a == 1 ? 0.02 * ts[k] * ts[k] : 1;
          fit += (p[3 * k + a] - truth) * (p[3 * k + a] - truth);
        }
      CHECK(fit < 0.7 * raw);
      /* the weight chosen is GCV's minimum to a sixteenth of a decade, not
       * only the best of the half-decade grid: within 0.1 % of the least
       * score over a scan in 1/32 decades */
      for (int gi = 0; gi < 2; gi++) {
        const double gamma = gi ? 5 : 1, nobs = 3.0 * K, lc = gi ? l5 : l1;
        double smin = INFINITY, sgrid = INFINITY, sc = INFINITY;
        for (int e = -4 * 32; e <= 8 * 32; e++) {
          CHECK(elfm_spline_linear(&sp, w, pow(10.0, e / 32.0), &bd, work, &rss, &edf, NULL));
          const double g = nobs * rss / ((nobs - gamma * edf) * (nobs - gamma * edf));
          if (nobs - gamma * edf >= 0.5 && g < smin) smin = g;
          if (nobs - gamma * edf >= 0.5 && e % 16 == 0 && g < sgrid) sgrid = g;
        }
        CHECK(elfm_spline_linear(&sp, w, lc, &bd, work, &rss, &edf, NULL));
        sc = nobs * rss / ((nobs - gamma * edf) * (nobs - gamma * edf));
        fprintf(stderr, "order %d gamma %g: chosen %.6g, scan min %.6g, half-decade grid min %.6g\n",
                order, gamma, sc, smin, sgrid);
        CHECK_MSG(sc <= smin * 1.001, "order %d gamma %g: GCV %g at the weight chosen, %g at best",
                  order, gamma, sc, smin);
      }
      elfm_banded_free(&bd);
    }
  }
  /* no data and no prior on a state: singular, refused */
  {
    double Wz[K];
    memset(Wz, 0, sizeof Wz);
    elfm_banded bd;
    elfm_banded_init(&bd);
    CHECK(elfm_banded_resize(&bd, K));
    elfm_banded_build(&bd, Wz, ts, 0, 2);
    CHECK(!elfm_banded_factor(&bd));
    elfm_banded_free(&bd);
  }
  /* The turn rate's rows (elfm_spline_prior_table_omega): on a circle
   * sampled every h at omega, in a tilted plane, off the origin and at any
   * phase, every row is 0 (to rounding); the jerk rows are not (they are
   * omega^3 R sqrt(h) x ~1 there); omega 0 gives the jerk table itself. */
  {
    enum { KC = 40 };
    double tc[KC], cj[4 * KC], cw[4 * KC], c0[4 * KC], p[3][KC];
    const double h = 1.0, om = 0.3, R = 12;
    const double e1[3] = {0.8, 0.6, 0}, e2[3] = {-0.36, 0.48, 0.8}, m[3] = {5, -7, 40};
    for (int k = 0; k < KC; k++) {
      tc[k] = 1000.0 + h * k;
      const double a = 0.7 + om * h * k;
      for (int ax = 0; ax < 3; ax++) p[ax][k] = m[ax] + R * (cos(a) * e1[ax] + sin(a) * e2[ax]);
    }
    elfm_spline_prior_table(tc, KC, 3, cj);
    elfm_spline_prior_table_omega(tc, KC, om, cw);
    elfm_spline_prior_table_omega(tc, KC, 0, c0);
    double wmax = 0, d0 = 0;
    for (int k = 0; k + 4 <= KC; k++)
      for (int ax = 0; ax < 3; ax++) {
        double rw = 0;
        for (int i = 0; i < 4; i++) {
          rw += cw[4 * k + i] * p[ax][k + i];
          d0 = fmax(d0, fabs(c0[4 * k + i] - cj[4 * k + i]));
        }
        wmax = fmax(wmax, fabs(rw));
      }
    double jmax = 0;
    for (int k = 0; k + 4 <= KC; k++) {
      double rj = 0;
      for (int i = 0; i < 4; i++) rj += cj[4 * k + i] * p[0][k + i];
      jmax = fmax(jmax, fabs(rj));
    }
    CHECK_MSG(wmax < 1e-9, "circle rows with its turn rate: %g", wmax);
    CHECK_MSG(jmax > 0.1, "jerk rows on the circle: %g", jmax);
    CHECK_MSG(d0 == 0, "omega 0 differs from the jerk table by %g", d0);
  }
  return check_report();
}
