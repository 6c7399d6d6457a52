/* link_circle.c — the linker's predictions along arcs: the constant-rate
 * turn of the short fit (after a missed frame), and the circle fit, a
 * track's recent path as an arc travelled at a constant rate (after a long
 * gap, and across a settled gap). link_internal.h says where each is used
 * and why. */
#include "link_internal.h"

#include <math.h>

/* Eigen-decomposition of the symmetric 3x3 a (destroyed) by cyclic Jacobi
 * rotations: eigenvalues into w[], eigenvectors into the columns of v. A
 * few sweeps suffice for 3x3; 50 is a bound, not an expectation. */
static void eigen_sym3(double a[3][3], double w[3], double v[3][3])
{
  for (int i = 0; i < 3; i++)
    for (int j = 0; j < 3; j++) v[i][j] = i == j;
  for (int sweep = 0; sweep < 50; sweep++) {
    const double off = a[0][1] * a[0][1] + a[0][2] * a[0][2] + a[1][2] * a[1][2];
    const double on = a[0][0] * a[0][0] + a[1][1] * a[1][1] + a[2][2] * a[2][2];
    if (!(off > 1e-30 * on) || off == 0) break;
    for (int p = 0; p < 2; p++)
      for (int q = p + 1; q < 3; q++) {
        if (a[p][q] == 0) continue;
        const double th = (a[q][q] - a[p][p]) / (2 * a[p][q]);
        const double t = (th >= 0 ? 1 : -1) / (fabs(th) + sqrt(th * th + 1));
        const double c = 1 / sqrt(t * t + 1), s = t * c;
        for (int k = 0; k < 3; k++) { /* a <- a J */
          const double akp = a[k][p], akq = a[k][q];
          a[k][p] = c * akp - s * akq;
          a[k][q] = s * akp + c * akq;
        }
        for (int k = 0; k < 3; k++) { /* a <- J^T a */
          const double apk = a[p][k], aqk = a[q][k];
          a[p][k] = c * apk - s * aqk;
          a[q][k] = s * apk + c * aqk;
        }
        for (int k = 0; k < 3; k++) {
          const double vkp = v[k][p], vkq = v[k][q];
          v[k][p] = c * vkp - s * vkq;
          v[k][q] = s * vkp + c * vkq;
        }
      }
  }
  for (int i = 0; i < 3; i++) w[i] = a[i][i];
}

int elfm_link_fit_circle(const elfm_link_options *o, const elfm_detection *pts, size_t k0,
                         size_t k1, int64_t tr, elfm_link_circle *c)
{
  const double min_arc_rad = o->circle_min_arc_rad, max_radius_um = o->circle_max_radius_um;
  const double line_ratio = o->circle_line_ratio, kz = o->kz;
  c->ok = 0;
  const size_t n = k1 - k0;
  if (n < 6) return 0;
  /* the plane: through the mean, normal to the direction of least spread */
  double m[3] = {0, 0, 0};
  for (size_t k = k0; k < k1; k++) {
    m[0] += pts[k].x_um;
    m[1] += pts[k].y_um;
    m[2] += pts[k].z_um;
  }
  for (int a = 0; a < 3; a++) m[a] /= (double)n;
  double cov[3][3] = {{0}};
  for (size_t k = k0; k < k1; k++) {
    const double e[3] = {pts[k].x_um - m[0], pts[k].y_um - m[1], pts[k].z_um - m[2]};
    for (int i = 0; i < 3; i++)
      for (int j = 0; j < 3; j++) cov[i][j] += e[i] * e[j];
  }
  double w[3], v[3][3];
  eigen_sym3(cov, w, v);
  int lo = 0;
  for (int i = 1; i < 3; i++)
    if (w[i] < w[lo]) lo = i;
  const int i1 = (lo + 1) % 3, i2 = (lo + 2) % 3;
  for (int a = 0; a < 3; a++) {
    c->m[a] = m[a];
    c->e1[a] = v[a][i1];
    c->e2[a] = v[a][i2];
  }
  /* the circle in the plane: the algebraic (Kasa) fit x^2 + y^2 = 2 cx x +
   * 2 cy y + d, linear in (cx, cy, d) */
  double A[3][3] = {{0}}, b[3] = {0, 0, 0};
  for (size_t k = k0; k < k1; k++) {
    const double e[3] = {pts[k].x_um - m[0], pts[k].y_um - m[1], pts[k].z_um - m[2]};
    const double x = e[0] * c->e1[0] + e[1] * c->e1[1] + e[2] * c->e1[2];
    const double y = e[0] * c->e2[0] + e[1] * c->e2[1] + e[2] * c->e2[2];
    const double row[3] = {x, y, 1}, rhs = x * x + y * y;
    for (int i = 0; i < 3; i++) {
      b[i] += row[i] * rhs;
      for (int j = 0; j < 3; j++) A[i][j] += row[i] * row[j];
    }
  }
  /* near singular (relative to the diagonal's scale): collinear points */
  const double det = link_det3(A);
  if (!(fabs(det) > 1e-12 * (fabs(A[0][0] * A[1][1] * A[2][2]) + 1e-300))) return 0;
  double s[3];
  link_cramer3(A, det, b, s);
  c->cx = s[0] / 2;
  c->cy = s[1] / 2;
  const double r2 = s[2] + c->cx * c->cx + c->cy * c->cy;
  if (!(r2 > 0)) return 0;
  c->r_um = sqrt(r2);
  if (!(c->r_um <= max_radius_um)) return 0; /* a straight path: no turn to keep */
  /* The angle, unwrapped along the track, as a straight line in time. A
   * step is taken as the turn nearest the rate fitted to the points before
   * it, not as the nearest angle: across a gap a flow bead turns by more
   * than half a circle (16 frames at 0.2 rad/ms: 3.2 rad), and the
   * nearest angle would run it backwards. */
  double prev = 0, unwrap = 0, st = 0, stt = 0, sa = 0, sta = 0, t_prev = 0;
  for (size_t k = k0; k < k1; k++) {
    const double e[3] = {pts[k].x_um - m[0], pts[k].y_um - m[1], pts[k].z_um - m[2]};
    const double x = e[0] * c->e1[0] + e[1] * c->e1[1] + e[2] * c->e1[2] - c->cx;
    const double y = e[0] * c->e2[0] + e[1] * c->e2[1] + e[2] * c->e2[2] - c->cy;
    const double ang = atan2(y, x);
    const double tm = (double)(pts[k].t_us - tr) * 1e-3;
    if (k > k0) {
      double d = ang - prev;
      while (d > M_PI) d -= 2 * M_PI;
      while (d < -M_PI) d += 2 * M_PI;
      const double m_done = (double)(k - k0), den_done = m_done * stt - st * st;
      if (m_done >= 2 && den_done > 1e-12) {
        const double expect = (m_done * sta - st * sa) / den_done * (tm - t_prev);
        d += 2 * M_PI * round((expect - d) / (2 * M_PI));
      }
      unwrap += d;
    } else {
      unwrap = ang;
    }
    prev = ang;
    t_prev = tm;
    st += tm;
    stt += tm * tm;
    sa += unwrap;
    sta += tm * unwrap;
  }
  const double den = (double)n * stt - st * st;
  if (!(den > 1e-12)) return 0;
  c->omega_rad_per_ms = ((double)n * sta - st * sa) / den;
  c->angle0 = (sa - c->omega_rad_per_ms * st) / (double)n;
  const double span_ms = (double)(pts[k1 - 1].t_us - pts[k0].t_us) * 1e-3;
  if (!(fabs(c->omega_rad_per_ms) * span_ms >= min_arc_rad)) return 0;
  /* A turn only where the points show one: the circle, travelled at its
   * rate, must fit them better than a straight line travelled at a constant
   * velocity (both in the linker's metric, z / kz) by line_ratio. Noisy
   * depths of a bead moving straight (a stage, blink_moving) bend the plane
   * and fit circles of 15-50 um radius that the points do not follow. */
  double lx[3] = {0, 0, 0}, ltx[3] = {0, 0, 0}; /* the line: the times' sums st, stt, den */
  for (size_t k = k0; k < k1; k++) {
    const double tm = (double)(pts[k].t_us - tr) * 1e-3;
    const double p[3] = {pts[k].x_um, pts[k].y_um, pts[k].z_um};
    for (int a = 0; a < 3; a++) {
      lx[a] += p[a];
      ltx[a] += tm * p[a];
    }
  }
  double e_circ = 0, e_line = 0;
  for (size_t k = k0; k < k1; k++) {
    const double tm = (double)(pts[k].t_us - tr) * 1e-3;
    const double p[3] = {pts[k].x_um, pts[k].y_um, pts[k].z_um};
    double q[3];
    elfm_link_circle_predict(c, tm, q);
    for (int a = 0; a < 3; a++) {
      const double vel = ((double)n * ltx[a] - st * lx[a]) / den;
      const double pos = (lx[a] - vel * st) / (double)n;
      const double w = a == 2 ? 1 / kz : 1;
      const double dc = (p[a] - q[a]) * w, dl = (p[a] - pos - vel * tm) * w;
      e_circ += dc * dc;
      e_line += dl * dl;
    }
  }
  if (!(e_circ < line_ratio * line_ratio * e_line)) return 0;
  c->ok = 1;
  return 1;
}

void elfm_link_circle_predict(const elfm_link_circle *c, double dt_ms, double out[3])
{
  const double a = c->angle0 + c->omega_rad_per_ms * dt_ms;
  const double x = c->cx + c->r_um * cos(a), y = c->cy + c->r_um * sin(a);
  for (int i = 0; i < 3; i++) out[i] = c->m[i] + c->e1[i] * x + c->e2[i] * y;
}

/* Shared with link.c, link_repair.c and link_fill.c; the model and why:
 * link_internal.h. */
void elfm_link_predict_turn(const double p0[3], const double v[3], const double acc[3],
                            double dt_ms, double out[3])
{
  double v2 = v[0] * v[0] + v[1] * v[1] + v[2] * v[2];
  double om[3] = {0, 0, 0};
  if (v2 > 1e-12) {
    om[0] = (v[1] * acc[2] - v[2] * acc[1]) / v2;
    om[1] = (v[2] * acc[0] - v[0] * acc[2]) / v2;
    om[2] = (v[0] * acc[1] - v[1] * acc[0]) / v2;
  }
  double w = sqrt(om[0] * om[0] + om[1] * om[1] + om[2] * om[2]);
  if (!(w * dt_ms > 1e-6)) {  /* no turn: a straight line */
    for (int a = 0; a < 3; a++) out[a] = p0[a] + v[a] * dt_ms;
    return;
  }
  double k[3] = {om[0] / w, om[1] / w, om[2] / w};
  double kv[3] = {k[1] * v[2] - k[2] * v[1], k[2] * v[0] - k[0] * v[2], k[0] * v[1] - k[1] * v[0]};
  double s = sin(w * dt_ms) / w, c = (1 - cos(w * dt_ms)) / w;
  for (int a = 0; a < 3; a++) out[a] = p0[a] + v[a] * s + kv[a] * c;
}
