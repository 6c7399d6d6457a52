/* hungarian.c — minimum-cost assignment (see elfm_score.h).
 *
 * Kuhn-Munkres with row/column potentials and shortest augmenting paths
 * (the O(n^2 m) formulation, as in Jonker & Volgenant 1987 without their
 * initialisation heuristics): rows are added one at a time; for each, a
 * Dijkstra-like sweep over the columns with reduced costs
 * c(i,j) - u(i) - v(j) >= 0 finds the cheapest augmenting path, and the
 * potentials are updated so that reduced costs stay non-negative.
 * A problem with more rows than columns is solved on its transpose, so the
 * inner loop always runs over the longer side.
 */
#include "elfm_score.h"

#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

struct elfm_assign_workspace {
  int cap_n, cap_m;   /* capacity: short side, long side */
  double *u;          /* cap_n + 1 row potentials (1-based; [0] unused) */
  double *v;          /* cap_m + 1 column potentials */
  double *minv;       /* cap_m + 1 best reduced cost to each column this sweep */
  int *p;             /* cap_m + 1: row assigned to column j (0 = none); p[0] = row being added */
  int *way;           /* cap_m + 1: previous column on the augmenting path */
  unsigned char *used;/* cap_m + 1: column reached this sweep */
};

static elfm_status ws_reserve(elfm_assign_workspace *ws, int n, int m, elfm_error *err)
{
  if (n <= ws->cap_n && m <= ws->cap_m) return ELFM_OK;
  int cn = n > ws->cap_n ? n : ws->cap_n;
  int cm = m > ws->cap_m ? m : ws->cap_m;
  size_t sn = (size_t)cn + 1, sm = (size_t)cm + 1;
  double *u = realloc(ws->u, sn * sizeof *u);
  if (u) ws->u = u;
  double *v = realloc(ws->v, sm * sizeof *v);
  if (v) ws->v = v;
  double *minv = realloc(ws->minv, sm * sizeof *minv);
  if (minv) ws->minv = minv;
  int *p = realloc(ws->p, sm * sizeof *p);
  if (p) ws->p = p;
  int *way = realloc(ws->way, sm * sizeof *way);
  if (way) ws->way = way;
  unsigned char *used = realloc(ws->used, sm * sizeof *used);
  if (used) ws->used = used;
  if (!u || !v || !minv || !p || !way || !used)
    return elfm_error_set(err, ELFM_ERR_NOMEM, NULL, -1,
                          "out of memory for a %d x %d assignment workspace", n, m);
  ws->cap_n = cn;
  ws->cap_m = cm;
  return ELFM_OK;
}

elfm_status elfm_assign_workspace_create(int max_rows, int max_cols,
                                         elfm_assign_workspace **out, elfm_error *err)
{
  *out = NULL;
  if (max_rows < 0 || max_cols < 0)
    return elfm_error_set(err, ELFM_ERR_INVALID, NULL, -1,
                          "assignment workspace size %d x %d is negative", max_rows, max_cols);
  elfm_assign_workspace *ws = calloc(1, sizeof *ws);
  if (!ws) return elfm_error_set(err, ELFM_ERR_NOMEM, NULL, -1, "out of memory");
  ws->cap_n = ws->cap_m = -1;
  int n = max_rows < max_cols ? max_rows : max_cols;
  int m = max_rows < max_cols ? max_cols : max_rows;
  elfm_status s = ws_reserve(ws, n, m, err);
  if (s != ELFM_OK) {
    elfm_assign_workspace_free(ws);
    return s;
  }
  *out = ws;
  return ELFM_OK;
}

void elfm_assign_workspace_free(elfm_assign_workspace *ws)
{
  if (!ws) return;
  free(ws->u);
  free(ws->v);
  free(ws->minv);
  free(ws->p);
  free(ws->way);
  free(ws->used);
  free(ws);
}

/* The (shifted) cost of short-side index i, long-side index j (0-based). */
static inline double cost_at(const double *cost, int n_cols, int transposed, int i, int j,
                             double shift, double penalty)
{
  double c = transposed ? cost[(size_t)j * (size_t)n_cols + (size_t)i]
                        : cost[(size_t)i * (size_t)n_cols + (size_t)j];
  return c == INFINITY ? penalty : c - shift;
}

elfm_status elfm_assign_hungarian(const double *cost, int n_rows, int n_cols,
                                  int *row_to_col, double *total_cost,
                                  elfm_assign_workspace *ws, elfm_error *err)
{
  if (total_cost) *total_cost = 0.0;
  if (n_rows < 0 || n_cols < 0 || !ws || (!cost && n_rows > 0 && n_cols > 0) ||
      (!row_to_col && n_rows > 0))
    return elfm_error_set(err, ELFM_ERR_INVALID, NULL, -1,
                          "assignment: bad arguments (%d x %d)", n_rows, n_cols);
  for (int r = 0; r < n_rows; r++) row_to_col[r] = -1;
  if (n_rows == 0 || n_cols == 0) return ELFM_OK;

  /* Scan: reject NaN/-inf, find the finite range for the forbidden penalty. */
  double lo = DBL_MAX, hi = -DBL_MAX;
  size_t total = (size_t)n_rows * (size_t)n_cols;
  for (size_t k = 0; k < total; k++) {
    double c = cost[k];
    if (c == INFINITY) continue;
    if (!isfinite(c))
      return elfm_error_set(err, ELFM_ERR_NUMERIC, NULL, -1,
                            "assignment: cost[%zu][%zu] is %s (only finite costs or +inf "
                            "for a forbidden pair)",
                            k / (size_t)n_cols, k % (size_t)n_cols,
                            isnan(c) ? "NaN" : "-inf");
    if (c < lo) lo = c;
    if (c > hi) hi = c;
  }
  if (lo > hi) return ELFM_OK; /* everything forbidden */

  int transposed = n_rows > n_cols;
  int n = transposed ? n_cols : n_rows; /* short side: the "rows" below */
  int m = transposed ? n_rows : n_cols;
  /* Shifted finite costs lie in [0, range]; an assignment's finite part lies
   * in [0, n * range], so one forbidden pair must cost more than that for
   * the solver to prefer any assignment with fewer forbidden pairs. */
  double range = hi - lo;
  double penalty = ((double)n + 1.0) * (range + 1.0);

  elfm_status s = ws_reserve(ws, n, m, err);
  if (s != ELFM_OK) return s;
  double *u = ws->u, *v = ws->v, *minv = ws->minv;
  int *p = ws->p, *way = ws->way;
  unsigned char *used = ws->used;
  for (int i = 0; i <= n; i++) u[i] = 0.0;
  for (int j = 0; j <= m; j++) { v[j] = 0.0; p[j] = 0; way[j] = 0; }

  for (int i = 1; i <= n; i++) {
    p[0] = i;
    int j0 = 0;
    for (int j = 0; j <= m; j++) { minv[j] = INFINITY; used[j] = 0; }
    do {
      used[j0] = 1;
      int i0 = p[j0], j1 = 0;
      double delta = INFINITY;
      for (int j = 1; j <= m; j++) {
        if (used[j]) continue;
        double cur = cost_at(cost, n_cols, transposed, i0 - 1, j - 1, lo, penalty) - u[i0] - v[j];
        if (cur < minv[j]) { minv[j] = cur; way[j] = j0; }
        if (minv[j] < delta) { delta = minv[j]; j1 = j; }
      }
      /* n <= m, so an unused column always exists and delta is finite. */
      for (int j = 0; j <= m; j++) {
        if (used[j]) { u[p[j]] += delta; v[j] -= delta; }
        else minv[j] -= delta;
      }
      j0 = j1;
    } while (p[j0] != 0);
    do { /* flip the augmenting path */
      int j1 = way[j0];
      p[j0] = p[j1];
      j0 = j1;
    } while (j0 != 0);
  }

  double sum = 0.0;
  for (int j = 1; j <= m; j++) {
    if (p[j] == 0) continue;
    int si = p[j] - 1, lj = j - 1;
    int r = transposed ? lj : si, c = transposed ? si : lj;
    double cv = cost[(size_t)r * (size_t)n_cols + (size_t)c];
    if (cv == INFINITY) continue; /* forced onto a forbidden pair: unassigned */
    row_to_col[r] = c;
    sum += cv;
  }
  if (total_cost) *total_cost = sum;
  return ELFM_OK;
}
