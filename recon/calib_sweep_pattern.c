/* calib_sweep_pattern.c — several objects swept through z together, as one.
 *
 * A calibration slide rarely holds one bead alone in the field: beads lie
 * side by side on its glass, and the piezo moves them all. Each view then
 * holds several images, and which is brightest changes from frame to frame
 * and view to view, so the brightest spot (calib_sweep.c) is now one bead's
 * image, now another's: taken for one object they fitted the views 9.8 px
 * off (five beads 10 um apart; docs/recon.md "Several beads swept
 * together").
 *
 * Beads at one depth keep their lateral places relative to each other in
 * every view and frame (all views image at one magnification; a depth moves
 * every image of a view alike, by the view's disparity x z): the view's
 * images are one pattern P moved by
 *
 *   T(v, f) = c(v) + d(v) z(f),
 *
 * the single object's model. So each view's spots in each frame are matched
 * to P by the translation most of them agree on, and T takes the place of
 * the brightest spot; the fit is then calib_sweep.c's. P is read off one
 * view: the frame whose brightest spot is brightest, then all its placed
 * frames' spots about their translations gathered (an object out of that
 * frame's field joins, a noise spot leaves). Beads at several depths (a
 * tilted slide, a gel) lie in view v at b_k + d(v) dz_k from T: their
 * places b_k and depths dz_k against each other are fitted over the views
 * whose own spots hold them, and each view matched to its own pattern
 * (zsweep's five beads on a slide tilted by 20 degrees, 14.6 um of depth
 * from end to end, fitted as well as on a flat one).
 *
 * A translation that as many spots agree on as the best (another object
 * taken for the first: a row of beads with its end out of the field) is
 * no translation: that view's frame tells nothing. Objects that do not
 * move together (two beads swept opposite ways, a flow) match P in few
 * frames; the share of frames with two spots or more that found their
 * translation says so, and the caller refuses under half.
 */
#include "calib_internal.h"

#include <math.h>
#include <stdlib.h>

/* Spots within this many px of where the pattern puts them match it
 * (their centroids scatter ~0.2-0.5 px; beads 1 um apart in depth move
 * apart by ~0.7 px between opposite outer views) */
#define PATTERN_TOL_PX 2.0
/* The pattern's objects: clusters of the reference view's spots about
 * their translations, in at least this share of its placed frames */
#define PATTERN_MIN_SHARE 0.5
/* Placements: by the reference frame's spots, by the objects gathered,
 * then by their depths refitted before each */
#define PATTERN_ROUNDS 5
/* A view's clusters tell the objects' depths from this many frames placed */
#define PATTERN_MIN_FRAMES 10
#define PATTERN_MAX_CLUSTERS 256

/* The spot of S nearest (u, w) within PATTERN_TOL_PX, or -1; order[]
 * lists S's spots by their u, so only those within the tolerance in u are
 * looked at */
static int nearest_spot(const float (*S)[2], const int *order, int ns, double u, double w)
{
  int lo = 0, hi = ns;
  while (lo < hi) {
    const int mid = (lo + hi) / 2;
    if (S[order[mid]][0] < u - PATTERN_TOL_PX)
      lo = mid + 1;
    else
      hi = mid;
  }
  int q = -1;
  double dq = PATTERN_TOL_PX * PATTERN_TOL_PX; /* squared: hypot's cost showed */
  for (int a = lo; a < ns && S[order[a]][0] <= u + PATTERN_TOL_PX; a++) {
    const int l = order[a];
    const double du = S[l][0] - u, dw = S[l][1] - w, d = du * du + dw * dw;
    if (d <= dq) {
      dq = d;
      q = l;
    }
  }
  return q;
}

/* The spot-object differences counted in cells 2 x PATTERN_TOL_PX wide
 * (translate): the cells under a translation's tolerance bound how many
 * objects can agree on it. VOTE_SIDE cells a side cover differences
 * spanning 512 px, a view and a pattern as wide (the paper's views are 144
 * px); wider ones go without the bound. Left all zero between calls. */
#define VOTE_CELL_PX (2 * PATTERN_TOL_PX)
#define VOTE_SIDE 128
typedef struct votes {
  double u0, w0;
  int cols, rows;
  uint16_t n[VOTE_SIDE * VOTE_SIDE];
} votes;

static int vote_cell(double x, double x0, int n)
{
  const int k = (int)floor((x - x0) / VOTE_CELL_PX);
  return k < 0 ? 0 : k >= n ? n - 1 : k;
}

/* Adds (+1) or takes back (-1) every spot-object difference's vote */
static void vote(votes *g, const float (*S)[2], int ns, const double (*P)[2], int np, int add)
{
  for (int i = 0; i < ns; i++)
    for (int j = 0; j < np; j++) {
      const int a = vote_cell(S[i][0] - P[j][0], g->u0, g->cols), b = vote_cell(S[i][1] - P[j][1], g->w0, g->rows);
      g->n[b * VOTE_SIDE + a] = (uint16_t)(g->n[b * VOTE_SIDE + a] + add);
    }
}

/* The votes of the cells under the disc of PATTERN_TOL_PX about (u, w):
 * no more objects can agree on that translation (each agrees through its
 * own spot, one difference within the disc) */
static int vote_bound(const votes *g, double u, double w)
{
  const int a0 = vote_cell(u - PATTERN_TOL_PX, g->u0, g->cols), a1 = vote_cell(u + PATTERN_TOL_PX, g->u0, g->cols);
  const int b0 = vote_cell(w - PATTERN_TOL_PX, g->w0, g->rows), b1 = vote_cell(w + PATTERN_TOL_PX, g->w0, g->rows);
  int n = 0;
  for (int b = b0; b <= b1; b++)
    for (int a = a0; a <= a1; a++) n += g->n[b * VOTE_SIDE + a];
  return n;
}

/* The translation of spots S[0 .. ns) onto the pattern P[0 .. np) that
 * most of P's objects agree on (each matched to a spot within
 * PATTERN_TOL_PX of it moved), averaged over them, into t; the objects
 * matched, or 0 when fewer than two agree, or fewer than half of the
 * spots or of P's objects (whichever are fewer: six beads each moving its
 * own way matched 0.36 of their frames with two enough, none so), or
 * another translation has as many.
 *
 * Each translation tried puts one spot on one object. A slide of 30 beads
 * fills a view with 30 spots, and trying all spot-object pairs, each
 * matching every object against every spot, took minutes (ns^2 np^2), so:
 * the spots are looked up by their u (nearest_spot); a translation is
 * not matched where the differences' votes (g, when not NULL) bound it
 * under the best (or the half needed), and stops being matched once the
 * objects left cannot bring it there. Both bounds are exact, and the
 * pairs are tried in the same order: what it finds is what trying every
 * pair in full found (tests/test_calib_pattern.c). */
static int translate(const float (*S)[2], int ns, const double (*P)[2], int np, double t[2], votes *g)
{
  if (g && ns > 0 && np > 0) {
    /* the differences' extent: S's extremes less P's */
    double ulo = INFINITY, uhi = -INFINITY, wlo = INFINITY, whi = -INFINITY;
    double pulo = INFINITY, puhi = -INFINITY, pwlo = INFINITY, pwhi = -INFINITY;
    for (int j = 0; j < np; j++) {
      pulo = fmin(pulo, P[j][0]);
      puhi = fmax(puhi, P[j][0]);
      pwlo = fmin(pwlo, P[j][1]);
      pwhi = fmax(pwhi, P[j][1]);
    }
    for (int i = 0; i < ns; i++) {
      ulo = fmin(ulo, S[i][0] - puhi);
      uhi = fmax(uhi, S[i][0] - pulo);
      wlo = fmin(wlo, S[i][1] - pwhi);
      whi = fmax(whi, S[i][1] - pwlo);
    }
    /* compared before the casts: a span too wide (or not a number) goes
     * without the votes */
    const double cols = floor((uhi - ulo) / VOTE_CELL_PX) + 1, rows = floor((whi - wlo) / VOTE_CELL_PX) + 1;
    if (cols <= VOTE_SIDE && rows <= VOTE_SIDE) {
      g->u0 = ulo;
      g->w0 = wlo;
      g->cols = (int)cols;
      g->rows = (int)rows;
      vote(g, S, ns, P, np, +1);
    } else {
      g = NULL;
    }
  }
  int order[ELFM_CALIB_SWEEP_MAX_SPOTS];
  for (int i = 0; i < ns; i++) {
    int a = i;
    for (; a > 0 && S[order[a - 1]][0] > S[i][0]; a--) order[a] = order[a - 1];
    order[a] = i;
  }
  const int few = ns < np ? ns : np;
  const int need = (few + 1) / 2 > 2 ? (few + 1) / 2 : 2;
  int best = 0, ambiguous = 0;
  double bt[2] = {0, 0};
  for (int i = 0; i < ns; i++)
    for (int j = 0; j < np; j++) {
      const int floor_m = best > need ? best : need;
      const double cu = S[i][0] - P[j][0], cw = S[i][1] - P[j][1];
      if (g && vote_bound(g, cu, cw) < floor_m) continue;
      int m = 0;
      double su = 0, sw = 0;
      for (int k = 0; k < np && m + (np - k) >= floor_m; k++) {
        const int q = nearest_spot(S, order, ns, P[k][0] + cu, P[k][1] + cw);
        if (q < 0) continue;
        m++;
        su += S[q][0] - P[k][0];
        sw += S[q][1] - P[k][1];
      }
      if (m < floor_m) continue;
      su /= m;
      sw /= m;
      if (m > best) {
        best = m;
        bt[0] = su;
        bt[1] = sw;
        ambiguous = 0;
      } else if (hypot(su - bt[0], sw - bt[1]) > PATTERN_TOL_PX) {
        ambiguous = 1;
      }
    }
  if (g) vote(g, S, ns, P, np, -1);
  if (best < need || ambiguous) return 0;
  t[0] = bt[0];
  t[1] = bt[1];
  return best;
}

int elfm_calib_pattern_translate(const float (*S)[2], int ns, const double (*P)[2], int np, int with_votes,
                                 double t[2])
{
  votes *g = with_votes ? calloc(1, sizeof *g) : NULL;
  const int m = translate(S, ns, P, np, t, g);
  free(g);
  return m;
}

static const float (*spots_at(const float *spots, int nv, size_t f, int v))[2]
{
  return (const float(*)[2])(spots + ((f * (size_t)nv + (size_t)v) * ELFM_CALIB_SWEEP_MAX_SPOTS) * 2);
}

/* The objects: object k's image lies b[k] + d(v) dz[k] from view v's
 * translation (dz: its depth against the others') */
typedef struct pattern {
  int n;
  double b[ELFM_CALIB_SWEEP_MAX_SPOTS][2], dz[ELFM_CALIB_SWEEP_MAX_SPOTS];
} pattern;

static void pattern_in_view(const pattern *p, const elfm_calib *c, int v, double (*P)[2])
{
  for (int k = 0; k < p->n; k++) {
    P[k][0] = p->b[k][0] + c->views[v].dx_px_per_um * p->dz[k];
    P[k][1] = p->b[k][1] + c->views[v].dy_px_per_um * p->dz[k];
  }
}

typedef struct cluster {
  double u, w; /* the running mean */
  size_t n;
} cluster;

static int cmp_cluster(const void *a, const void *b)
{
  const cluster *p = a, *q = b;
  return (p->n < q->n) - (p->n > q->n);
}

/* View v's spots about its translations (pu, pw; NaN: none), gathered in
 * clusters PATTERN_TOL_PX wide, the largest first; the frames placed into
 * *placed */
static int view_clusters(int nv, size_t nf, int v, const uint8_t *n_spots, const float *spots, const float *pu,
                         const float *pw, cluster *cl, size_t *placed)
{
  int ncl = 0;
  *placed = 0;
  for (size_t f = 0; f < nf; f++) {
    const size_t i = f * (size_t)nv + (size_t)v;
    if (isnan(pu[i])) continue;
    (*placed)++;
    const float(*S)[2] = spots_at(spots, nv, f, v);
    for (int l = 0; l < n_spots[i]; l++) {
      const double u = S[l][0] - pu[i], w = S[l][1] - pw[i];
      int k = 0;
      while (k < ncl && (u - cl[k].u) * (u - cl[k].u) + (w - cl[k].w) * (w - cl[k].w) >
                            PATTERN_TOL_PX * PATTERN_TOL_PX)
        k++;
      if (k == ncl) {
        if (ncl == PATTERN_MAX_CLUSTERS) continue;
        cl[ncl++] = (cluster){u, w, 0};
      }
      cl[k].n++;
      cl[k].u += (u - cl[k].u) / (double)cl[k].n;
      cl[k].w += (w - cl[k].w) / (double)cl[k].n;
    }
  }
  qsort(cl, (size_t)ncl, sizeof *cl, cmp_cluster);
  return ncl;
}

/* The objects from view v0's clusters in PATTERN_MIN_SHARE of its placed
 * frames or more, at one depth, the one nearest the translation at 0 */
static void pattern_gather(int nv, size_t nf, int v0, const uint8_t *n_spots, const float *spots, const float *pu,
                           const float *pw, pattern *p)
{
  cluster cl[PATTERN_MAX_CLUSTERS];
  size_t placed;
  const int ncl = view_clusters(nv, nf, v0, n_spots, spots, pu, pw, cl, &placed);
  int o = -1;
  p->n = 0;
  for (int k = 0; k < ncl && (double)cl[k].n >= PATTERN_MIN_SHARE * (double)placed; k++)
    if (o < 0 || hypot(cl[k].u, cl[k].w) < hypot(cl[o].u, cl[o].w)) o = k;
  for (int k = 0; o >= 0 && k < ncl && p->n < ELFM_CALIB_SWEEP_MAX_SPOTS; k++) {
    if ((double)cl[k].n < PATTERN_MIN_SHARE * (double)placed) break;
    p->b[p->n][0] = cl[k].u - cl[o].u;
    p->b[p->n][1] = cl[k].w - cl[o].w;
    p->dz[p->n] = 0;
    p->n++;
  }
}

/* Each object's place and depth against the others (b, dz) by least
 * squares over the views whose own clusters hold it: objects at several
 * depths (a tilted slide, beads in a gel) lie apart by d(v) times their
 * depths' difference, other in every view (10 um of depth: 3.6 px from one
 * outer view to the opposite one); an object kept as it was where fewer
 * than 3 views hold it or their disparities do not tell its depth */
static void pattern_depths(int nv, size_t nf, const elfm_calib *c, const uint8_t *n_spots, const float *spots,
                           const float *pu, const float *pw, pattern *p)
{
  double A[ELFM_CALIB_SWEEP_MAX_SPOTS][6] = {{0}}, r[ELFM_CALIB_SWEEP_MAX_SPOTS][3] = {{0}};
  int views[ELFM_CALIB_SWEEP_MAX_SPOTS] = {0};
  for (int v = 0; v < nv; v++) {
    cluster cl[PATTERN_MAX_CLUSTERS];
    size_t placed;
    const int ncl = view_clusters(nv, nf, v, n_spots, spots, pu, pw, cl, &placed);
    if (placed < PATTERN_MIN_FRAMES) continue;
    double P[ELFM_CALIB_SWEEP_MAX_SPOTS][2];
    pattern_in_view(p, c, v, P);
    const double dx = c->views[v].dx_px_per_um, dy = c->views[v].dy_px_per_um;
    for (int k = 0; k < p->n; k++) {
      int q = -1;
      double dq = PATTERN_TOL_PX;
      for (int l = 0; l < ncl && (double)cl[l].n >= PATTERN_MIN_SHARE * (double)placed; l++) {
        const double d = hypot(cl[l].u - P[k][0], cl[l].w - P[k][1]);
        if (d <= dq) {
          dq = d;
          q = l;
        }
      }
      if (q < 0) continue;
      /* the normal equations of (bu, bw, dz): rows (1, 0, dx) and (0, 1, dy);
       * A holds 11, 13, 22, 23, 33 (and 12 = 0) */
      A[k][0] += 1;
      A[k][2] += dx;
      A[k][3] += 1;
      A[k][4] += dy;
      A[k][5] += dx * dx + dy * dy;
      r[k][0] += cl[q].u;
      r[k][1] += cl[q].w;
      r[k][2] += dx * cl[q].u + dy * cl[q].w;
      views[k]++;
    }
  }
  for (int k = 0; k < p->n; k++) {
    if (views[k] < 3) continue;
    /* dz from the Schur complement of the b block (diagonal, n views each) */
    const double n = A[k][0];
    const double s = A[k][5] - (A[k][2] * A[k][2] + A[k][4] * A[k][4]) / n;
    if (!(s > 1e-6 * A[k][5])) continue;
    const double dz = (r[k][2] - (A[k][2] * r[k][0] + A[k][4] * r[k][1]) / n) / s;
    p->dz[k] = dz;
    p->b[k][0] = (r[k][0] - A[k][2] * dz) / n;
    p->b[k][1] = (r[k][1] - A[k][4] * dz) / n;
  }
}

/* Every view's translations onto the pattern into pu, pw; per view the
 * share of its frames with two spots or more that were placed, into
 * share[] (NaN: none) */
static void pattern_place(int nv, size_t nf, const elfm_calib *c, const uint8_t *n_spots, const float *spots,
                          const pattern *p, float *pu, float *pw, double *share, votes *g)
{
  for (int v = 0; v < nv; v++) {
    double P[ELFM_CALIB_SWEEP_MAX_SPOTS][2];
    pattern_in_view(p, c, v, P);
    size_t two = 0, placed = 0;
    for (size_t f = 0; f < nf; f++) {
      const size_t i = f * (size_t)nv + (size_t)v;
      double t[2];
      pu[i] = pw[i] = NAN;
      if (n_spots[i] < 2) continue;
      two++;
      if (!translate(spots_at(spots, nv, f, v), n_spots[i], (const double(*)[2])P, p->n, t, g)) continue;
      pu[i] = (float)t[0];
      pw[i] = (float)t[1];
      placed++;
    }
    share[v] = two > 0 ? (double)placed / (double)two : NAN;
  }
}

int elfm_calib_sweep_pattern(const elfm_calib *c, size_t nf, const int *tells, const uint8_t *n_spots,
                             const float *strength, const float *spots, float *pu, float *pw, double *share,
                             double *depth_um)
{
  const int nv = c->n_views;
  double shares[ELFM_MAX_VIEWS];
  *share = 0;
  *depth_um = NAN;
  /* the reference: of the views that tell the depth, the frame with two
   * spots or more whose brightest is brightest (the objects nearest focus,
   * where the noise's spots stay under SWEEP_SPOT_FRAC of it; at the
   * sweep's far end, where they are faint and wide, the most spots were
   * half noise) */
  int v0 = -1;
  size_t f0 = 0;
  for (size_t f = 0; f < nf; f++)
    for (int v = 0; v < nv; v++) {
      const size_t i = f * (size_t)nv + (size_t)v;
      if (tells[v] && n_spots[i] >= 2 && (v0 < 0 || strength[i] > strength[f0 * (size_t)nv + (size_t)v0])) {
        v0 = v;
        f0 = f;
      }
    }
  pattern p = {.n = v0 < 0 ? 0 : n_spots[f0 * (size_t)nv + (size_t)v0]};
  const float(*S0)[2] = spots_at(spots, nv, f0, v0 < 0 ? 0 : v0);
  for (int k = 0; k < p.n; k++) {
    p.b[k][0] = S0[k][0] - S0[0][0];
    p.b[k][1] = S0[k][1] - S0[0][1];
    p.dz[k] = 0;
  }
  /* placed by that frame's spots; by the objects gathered from the
   * reference view's placed frames; then by their depths, in turn */
  /* the votes' cells (32 KB; without them the same, only slower) */
  votes *g = calloc(1, sizeof *g);
  for (int round = 0; p.n >= 2 && round < PATTERN_ROUNDS; round++) {
    pattern_place(nv, nf, c, n_spots, spots, &p, pu, pw, shares, g);
    if (round == PATTERN_ROUNDS - 1) break;
    if (round == 0)
      pattern_gather(nv, nf, v0, n_spots, spots, pu, pw, &p);
    else
      pattern_depths(nv, nf, c, n_spots, spots, pu, pw, &p);
  }
  free(g);
  if (p.n < 2) {
    for (size_t i = 0; i < nf * (size_t)nv; i++) pu[i] = pw[i] = NAN;
    return 0;
  }
  double tmp[ELFM_MAX_VIEWS];
  int n = 0;
  /* a view with no frame of two spots holds one object (or none): 0 */
  for (int v = 0; v < nv; v++)
    if (tells[v]) tmp[n++] = isnan(shares[v]) ? 0 : shares[v];
  *share = n == 0 ? 0 : elfm_calib_median(tmp, (size_t)n);
  double lo = p.dz[0], hi = p.dz[0];
  for (int k = 1; k < p.n; k++) {
    lo = fmin(lo, p.dz[k]);
    hi = fmax(hi, p.dz[k]);
  }
  *depth_um = hi - lo;
  return p.n;
}
