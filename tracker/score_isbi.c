/* score_isbi.c — the ISBI 2012 track measures (elfm_score.h, TRACKS;
 * Chenouard et al., Nat. Methods 2014, after the official evaluation
 * software): every candidate's gated matches with the truth objects, the
 * pairing by Hungarian assignment within connected clusters of feasible
 * pairs (truth objects and candidates joined by a pair; as the official
 * evaluator clusters track pairs), each truth track with its own dummy,
 * and alpha, beta, the Jaccards and the track RMSE.
 */
#include "score_internal.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* Object of truth point p (binary search in obj_off). */
static int truth_obj_of(const truth_t *tr, int64_t p)
{
  int lo = 0, hi = tr->n_obj - 1;
  while (lo < hi) {
    int mid = (lo + hi + 1) / 2;
    if (tr->obj_off[mid] <= p) lo = mid;
    else hi = mid - 1;
  }
  return lo;
}

/* 1 if truth object k counts at frame slot f (its points are in frame order). */
static int truth_has(const truth_t *tr, int k, int f)
{
  int64_t lo = tr->obj_off[k], hi = tr->obj_off[k + 1];
  while (lo < hi) {
    int64_t m = lo + (hi - lo) / 2;
    if (tr->pt.frame[m] < f) lo = m + 1;
    else hi = m;
  }
  return lo < tr->obj_off[k + 1] && tr->pt.frame[lo] == f;
}

/* The truth points of frame slot f that can lie within the gate of a point
 * at x: fr_pt[*m0 .. *m1) (|dx| < eps; the x-sorted list). */
static void gate_range(const truth_t *tr, int f, double x, double eps, int64_t *m0, int64_t *m1)
{
  const int64_t fa = tr->fr_off[f], fb = tr->fr_off[f + 1];
  *m0 = lower_x(tr->fr_pt, fa, fb, x - eps);
  *m1 = lower_x(tr->fr_pt, *m0, fb, x + eps);
}

/* Distance from candidate point q to truth point p. */
static double cand_truth_d(const gate_t *g, const cands_t *cd, int64_t q, const truth_t *tr,
                           int64_t p)
{
  return dist_aniso(g, cd->pt.x[q] - tr->pt.x[p], cd->pt.y[q] - tr->pt.y[p],
                    cd->pt.z[q] - tr->pt.z[p]);
}

typedef struct {
  int obj, cand;
  int64_t matched;
  double saving;   /* sum over matched frames of (eps - d) */
  double sum_d2;
  double cost;     /* d(X, Y) */
} pair_t;

/* Each depth band's alpha_tracks (elfm_score.h, BY DEPTH), from the pairs
 * chosen (obj_pair[k]: object k's pair, or -1 for its dummy): every truth
 * point of a paired object costs its distance to the candidate's point of
 * the same frame when that is within the gate, eps otherwise. Both lists
 * are in frame order, so one walk per object. What the pair costs beyond
 * its truth points (the candidate-only frames) goes to
 * alpha_tracks_unplaced_cost. */
static void isbi_depth_bands(const truth_t *tr, const cands_t *cd, const gate_t *g, double band_um,
                             const pair_t *pairs, const int *obj_pair, elfm_score_result *out)
{
  double cost[ELFM_SCORE_MAX_DEPTH_BANDS] = {0}, unplaced = 0;
  int64_t n_all = 0;
  for (int k = 0; k < tr->n_obj; k++) {
    const int64_t p0 = tr->obj_off[k], p1 = tr->obj_off[k + 1];
    n_all += p1 - p0;
    if (obj_pair[k] < 0) {
      for (int64_t p = p0; p < p1; p++) cost[depth_band(tr->pt.z[p], band_um)] += g->eps;
      continue;
    }
    const pair_t *pp = &pairs[obj_pair[k]];
    int q = cd->off[pp->cand];
    const int q1 = cd->off[pp->cand + 1];
    double own = 0;
    for (int64_t p = p0; p < p1; p++) {
      const int f = tr->pt.frame[p];
      while (q < q1 && cd->pt.frame[q] < f) q++;
      double d = g->eps;
      if (q < q1 && cd->pt.frame[q] == f) {
        const double dq = cand_truth_d(g, cd, q, tr, p);
        if (dq < g->eps) d = dq;
      }
      cost[depth_band(tr->pt.z[p], band_um)] += d;
      own += d;
    }
    unplaced += pp->cost - own;
  }
  for (int b = 0; b < out->n_depth_bands; b++) {
    const double n = (double)out->depth_bands[b].n_truth_points;
    out->depth_bands[b].alpha_tracks = n > 0 ? 1.0 - cost[b] / (g->eps * n) : NAN;
  }
  out->alpha_tracks_unplaced_cost = n_all > 0 ? unplaced / (g->eps * (double)n_all) : NAN;
}

elfm_status elfm_score_isbi_tracks(const truth_t *tr, const cands_t *cd, const gate_t *g,
                                   double band_um, elfm_score_result *out, elfm_error *err)
{
  elfm_status s = ELFM_OK;
  int n_obj = tr->n_obj, n_c = cd->n_tracks;
  /* Truth tracks: objects with at least one counted point. */
  int n_truth_tracks = 0;
  for (int k = 0; k < n_obj; k++) n_truth_tracks += tr->obj_off[k + 1] > tr->obj_off[k];

  pair_t *pairs = NULL;
  size_t n_pairs = 0, cap_pairs = 0;
  int64_t *acc_m = calloc((size_t)n_obj + 1, sizeof *acc_m);
  double *acc_s = calloc((size_t)n_obj + 1, sizeof *acc_s);
  double *acc_d2 = calloc((size_t)n_obj + 1, sizeof *acc_d2);
  int *touched = malloc(((size_t)n_obj + 1) * sizeof *touched);
  int *parent = malloc(((size_t)n_obj + (size_t)n_c + 1) * sizeof *parent);
  int *obj_pair = malloc(((size_t)n_obj + 1) * sizeof *obj_pair);  /* chosen pair, -1 dummy */
  unsigned char *cand_used = calloc((size_t)n_c + 1, 1);
  int *rows = malloc(((size_t)n_obj + 1) * sizeof *rows);
  int *cols = malloc(((size_t)n_c + 1) * sizeof *cols);
  int *col_of = malloc(((size_t)n_c + 1) * sizeof *col_of);
  int *r2c = malloc(((size_t)n_obj + 1) * sizeof *r2c);
  double *cost = NULL;
  size_t cost_cap = 0;
  elfm_assign_workspace *ws = NULL;
  if (!acc_m || !acc_s || !acc_d2 || !touched || !parent || !obj_pair || !cand_used || !rows ||
      !cols || !col_of || !r2c) { s = elfm_score_nomem(err); goto done; }

  /* Gated matches of every candidate with every truth object. */
  for (int ci = 0; ci < n_c; ci++) {
    int n_touched = 0;
    int a = cd->off[ci], b = cd->off[ci + 1];
    for (int q = a; q < b; q++) {
      int64_t m0, m1;
      gate_range(tr, cd->pt.frame[q], cd->pt.x[q], g->eps, &m0, &m1);
      for (int64_t m = m0; m < m1; m++) {
        int64_t p = (int64_t)tr->fr_pt[m].idx;
        double d = cand_truth_d(g, cd, q, tr, p);
        if (!(d < g->eps)) continue;
        int k = truth_obj_of(tr, p);
        if (acc_m[k] == 0) touched[n_touched++] = k;
        acc_m[k]++;
        acc_s[k] += g->eps - d;
        acc_d2[k] += d * d;
      }
    }
    int n_real = b - a;
    for (int t = 0; t < n_touched; t++) {
      int k = touched[t];
      int64_t fx = tr->obj_off[k + 1] - tr->obj_off[k];
      /* |F(X) u R(Y)| = |F(X)| + |R(Y)| - |F(X) n R(Y)| (see elfm_score.h) */
      int64_t both = 0;
      for (int q = a; q < b; q++) both += truth_has(tr, k, cd->pt.frame[q]);
      if (n_pairs == cap_pairs) {
        size_t nc = cap_pairs ? 2 * cap_pairs : 256;
        pair_t *np = realloc(pairs, nc * sizeof *np);
        if (!np) { s = elfm_score_nomem(err); goto done; }
        pairs = np;
        cap_pairs = nc;
      }
      pair_t *pp = &pairs[n_pairs++];
      pp->obj = k;
      pp->cand = ci;
      pp->matched = acc_m[k];
      pp->saving = acc_s[k];
      pp->sum_d2 = acc_d2[k];
      pp->cost = g->eps * (double)(fx + n_real - both) - acc_s[k];
      acc_m[k] = 0;
      acc_s[k] = 0;
      acc_d2[k] = 0;
    }
  }

  /* Clusters: truth objects and candidates joined by feasible pairs. */
  for (int q = 0; q < n_obj + n_c; q++) parent[q] = q;
  for (size_t q = 0; q < n_pairs; q++) uf_union(parent, pairs[q].obj, n_obj + pairs[q].cand);
  for (int k = 0; k < n_obj; k++) obj_pair[k] = -1;
  /* Pairs grouped by root: order pairs by root of their object. */
  {
    keyed_t *po = malloc((n_pairs + 1) * sizeof *po);
    pair_t *sorted = malloc((n_pairs + 1) * sizeof *sorted);
    if (!po || !sorted) { free(po); free(sorted); s = elfm_score_nomem(err); goto done; }
    for (size_t q = 0; q < n_pairs; q++) po[q] = (keyed_t){(double)uf_find(parent, pairs[q].obj), q};
    qsort(po, n_pairs, sizeof *po, elfm_score_keyed_cmp);
    for (size_t q = 0; q < n_pairs; q++) sorted[q] = pairs[po[q].idx];
    free(po);
    free(pairs);
    pairs = sorted;
  }
  if ((s = elfm_assign_workspace_create(0, 0, &ws, err)) != ELFM_OK) goto done;
  for (size_t q0 = 0; q0 < n_pairs;) {
    int root = uf_find(parent, pairs[q0].obj);
    size_t q1 = q0;
    while (q1 < n_pairs && uf_find(parent, pairs[q1].obj) == root) q1++;
    /* Rows: objects of the cluster; columns: its candidates, then one
     * dummy per object (only its own dummy is allowed). */
    int nr = 0, nc = 0;
    for (size_t q = q0; q < q1; q++) {
      int k = pairs[q].obj, c = pairs[q].cand;
      if (obj_pair[k] != -2) { obj_pair[k] = -2; rows[nr++] = k; }
      if (!cand_used[c]) { cand_used[c] = 1; col_of[c] = nc; cols[nc++] = c; }
    }
    for (int c = 0; c < nc; c++) cand_used[cols[c]] = 0;
    int ncol = nc + nr;
    size_t need = (size_t)nr * (size_t)ncol;
    if ((s = elfm_score_reserve_cost(&cost, &cost_cap, need, err)) != ELFM_OK) goto done;
    for (size_t e = 0; e < need; e++) cost[e] = INFINITY;
    for (int r = 0; r < nr; r++) {
      int k = rows[r];
      obj_pair[k] = r; /* temporarily: row index of object k */
      cost[(size_t)r * (size_t)ncol + (size_t)(nc + r)] =
          g->eps * (double)(tr->obj_off[k + 1] - tr->obj_off[k]);
    }
    for (size_t q = q0; q < q1; q++)
      cost[(size_t)obj_pair[pairs[q].obj] * (size_t)ncol + (size_t)col_of[pairs[q].cand]] = pairs[q].cost;
    if ((s = elfm_assign_hungarian(cost, nr, ncol, r2c, NULL, ws, err)) != ELFM_OK) goto done;
    /* obj_pair[k] still holds k's row here; turn it into the chosen pair. */
    for (size_t q = q0; q < q1; q++) {
      int k = pairs[q].obj;
      if (obj_pair[k] < 0) continue; /* already resolved */
      int c = r2c[obj_pair[k]];
      if (c >= 0 && c < nc && cols[c] == pairs[q].cand) obj_pair[k] = -3 - (int)q;
    }
    for (int r = 0; r < nr; r++) {
      int k = rows[r];
      obj_pair[k] = obj_pair[k] <= -3 ? -3 - obj_pair[k] : -1;
    }
    q0 = q1;
  }

  /* Measures. */
  {
    double d_empty = 0, d_pairs = 0, d_spur = 0, sum_d2 = 0;
    int64_t tp = 0, fn = 0, fp = 0;
    int paired = 0, missed = 0, spurious = 0;
    memset(cand_used, 0, (size_t)n_c + 1);
    for (int k = 0; k < n_obj; k++) {
      int64_t fx = tr->obj_off[k + 1] - tr->obj_off[k];
      if (fx == 0) continue;
      d_empty += g->eps * (double)fx;
      if (obj_pair[k] >= 0) {
        const pair_t *pp = &pairs[obj_pair[k]];
        d_pairs += pp->cost;
        tp += pp->matched;
        fn += fx - pp->matched;
        fp += (cd->off[pp->cand + 1] - cd->off[pp->cand]) - pp->matched;
        sum_d2 += pp->sum_d2;
        cand_used[pp->cand] = 1;
        paired++;
      } else {
        d_pairs += g->eps * (double)fx;
        fn += fx;
        missed++;
      }
    }
    for (int c = 0; c < n_c; c++) {
      if (cand_used[c]) continue;
      int a = cd->off[c], b = cd->off[c + 1];
      d_spur += g->eps * (double)(b - a);
      fp += b - a;
      spurious++;
    }
    out->has_tracks = 1;
    out->n_truth_tracks = n_truth_tracks;
    out->n_candidate_tracks = n_c;
    out->n_paired_tracks = paired;
    out->n_missed_tracks = missed;
    out->n_spurious_tracks = spurious;
    out->n_track_tp = tp;
    out->n_track_fn = fn;
    out->n_track_fp = fp;
    out->alpha = d_empty > 0 ? 1.0 - d_pairs / d_empty : NAN;
    out->beta = d_empty + d_spur > 0 ? (d_empty - d_pairs) / (d_empty + d_spur) : NAN;
    out->jaccard_tracks = paired + missed + spurious
                              ? (double)paired / (double)(paired + missed + spurious) : NAN;
    out->jaccard_detections = tp + fn + fp ? (double)tp / (double)(tp + fn + fp) : NAN;
    out->rmse_tracks_um = tp ? sqrt(sum_d2 / (double)tp) : NAN;
  }
  if (band_um > 0) isbi_depth_bands(tr, cd, g, band_um, pairs, obj_pair, out);
done:
  elfm_assign_workspace_free(ws);
  free(pairs);
  free(cost);
  free(acc_m);
  free(acc_s);
  free(acc_d2);
  free(touched);
  free(parent);
  free(obj_pair);
  free(cand_used);
  free(rows);
  free(cols);
  free(col_of);
  free(r2c);
  return s;
}

/* ---------------------------------------------------------------------- */
/* (4b) Identities: what the tracks' own points would give with every point
 * on its own object's track (elfm_score.h, IDENTITIES). */

typedef struct {
  int obj, frame, cand;
  int64_t q;     /* candidate point */
  double d;
} owned_t;

static int owned_by_obj_frame_d(const void *a, const void *b)
{
  const owned_t *u = a, *v = b;
  if (u->obj != v->obj) return u->obj < v->obj ? -1 : 1;
  if (u->frame != v->frame) return u->frame < v->frame ? -1 : 1;
  if (u->d != v->d) return u->d < v->d ? -1 : 1;
  return u->q < v->q ? -1 : u->q > v->q;
}

static int owned_by_cand_obj(const void *a, const void *b)
{
  const owned_t *u = a, *v = b;
  if (u->cand != v->cand) return u->cand < v->cand ? -1 : 1;
  if (u->obj != v->obj) return u->obj < v->obj ? -1 : 1;
  return u->q < v->q ? -1 : u->q > v->q;
}

elfm_status elfm_score_identities(const truth_t *tr, const cands_t *cd, const gate_t *g,
                                  elfm_score_result *out, elfm_error *err)
{
  elfm_status s = ELFM_OK;
  const int n_obj = tr->n_obj, n_c = cd->n_tracks;
  const int64_t n_pt = cd->off[n_c];
  owned_t *own = malloc(((size_t)n_pt + 1) * sizeof *own);
  int64_t *owner = malloc(((size_t)n_pt + 1) * sizeof *owner);  /* object or -1 */
  int *maj = malloc(((size_t)n_c + 1) * sizeof *maj);            /* majority object, -1 none */
  int64_t *best = calloc((size_t)n_obj + 1, sizeof *best);       /* points in its best track */
  cands_t rl;
  memset(&rl, 0, sizeof rl);
  elfm_score_result tmp;
  memset(&tmp, 0, sizeof tmp);
  if (!own || !owner || !maj || !best) { s = elfm_score_nomem(err); goto done; }

  /* Each real point's object: the nearest counted truth point of its frame
   * within the gate. */
  int64_t n_own = 0;
  for (int ci = 0; ci < n_c; ci++)
    for (int64_t q = cd->off[ci]; q < cd->off[ci + 1]; q++) {
      int f = cd->pt.frame[q], k_best = -1;
      double d_best = g->eps;
      int64_t m0, m1;
      gate_range(tr, f, cd->pt.x[q], g->eps, &m0, &m1);
      for (int64_t m = m0; m < m1; m++) {
        int64_t p = (int64_t)tr->fr_pt[m].idx;
        double d = cand_truth_d(g, cd, q, tr, p);
        if (d < d_best) {
          d_best = d;
          k_best = truth_obj_of(tr, p);
        }
      }
      owner[q] = k_best;
      if (k_best >= 0) own[n_own++] = (owned_t){k_best, f, ci, q, d_best};
    }

  /* Where each object's points are: its best track (the one with most of
   * them), fragments (other tracks whose points are mostly its own), and
   * tracks that mostly follow another object. */
  qsort(own, (size_t)n_own, sizeof *own, owned_by_cand_obj);
  for (int ci = 0; ci < n_c; ci++) maj[ci] = -1;
  for (int pass = 0; pass < 2; pass++) {
    int64_t n_frag = 0, n_other = 0, top = 0;
    for (int64_t i = 0; i < n_own;) {  /* runs of equal (cand, obj) */
      int64_t j = i;
      while (j < n_own && own[j].cand == own[i].cand && own[j].obj == own[i].obj) j++;
      const int ci = own[i].cand, k = own[i].obj;
      if (pass == 0) {  /* majorities and best counts */
        if (i == 0 || own[i - 1].cand != ci) top = 0;
        if (j - i > top) {
          top = j - i;
          maj[ci] = k;
        }
        if (j - i > best[k]) best[k] = j - i;
      } else if (best[k] == j - i) {
        best[k] = -1;  /* this run is the object's best track: counted once */
      } else if (maj[ci] == k) {
        n_frag += j - i;
      } else {
        n_other += j - i;
      }
      i = j;
    }
    if (pass == 1 && tr->pt.n > 0) {
      out->identity_fragments = (double)n_frag / (double)tr->pt.n;
      out->identity_other_tracks = (double)n_other / (double)tr->pt.n;
    }
  }

  /* The tracks with identities mended: per object its points, the nearest
   * one per frame; the points of no object stay on their own tracks. */
  qsort(own, (size_t)n_own, sizeof *own, owned_by_obj_frame_d);
  rl.off = malloc(((size_t)n_obj + (size_t)n_c + 1) * sizeof *rl.off);
  rl.pt.frame = malloc(((size_t)n_pt + 1) * sizeof *rl.pt.frame);
  rl.pt.x = malloc(((size_t)n_pt + 1) * sizeof *rl.pt.x);
  rl.pt.y = malloc(((size_t)n_pt + 1) * sizeof *rl.pt.y);
  rl.pt.z = malloc(((size_t)n_pt + 1) * sizeof *rl.pt.z);
  if (!rl.off || !rl.pt.frame || !rl.pt.x || !rl.pt.y || !rl.pt.z) { s = elfm_score_nomem(err); goto done; }
  int64_t w = 0;
  int nt = 0;
  for (int64_t i = 0; i < n_own;) {
    rl.off[nt++] = (int)w;
    const int k = own[i].obj;
    for (; i < n_own && own[i].obj == k; i++) {
      if (i > 0 && own[i - 1].obj == k && own[i - 1].frame == own[i].frame) continue;
      const int64_t q = own[i].q;
      rl.pt.frame[w] = cd->pt.frame[q];
      rl.pt.x[w] = cd->pt.x[q];
      rl.pt.y[w] = cd->pt.y[q];
      rl.pt.z[w] = cd->pt.z[q];
      w++;
    }
  }
  for (int ci = 0; ci < n_c; ci++) {
    int64_t w0 = w;
    for (int64_t q = cd->off[ci]; q < cd->off[ci + 1]; q++) {
      if (owner[q] >= 0) continue;
      rl.pt.frame[w] = cd->pt.frame[q];
      rl.pt.x[w] = cd->pt.x[q];
      rl.pt.y[w] = cd->pt.y[q];
      rl.pt.z[w] = cd->pt.z[q];
      w++;
    }
    if (w > w0) rl.off[nt++] = (int)w0;
  }
  rl.off[nt] = (int)w;
  rl.n_tracks = nt;
  rl.pt.n = w;
  if ((s = elfm_score_isbi_tracks(tr, &rl, g, 0, &tmp, err)) != ELFM_OK) goto done;
  out->alpha_identities = tmp.alpha;
done:
  free(own);
  free(owner);
  free(maj);
  free(best);
  elfm_score_cands_free(&rl);
  return s;
}
