/* link_candidates.c — step 2 of elfm_link_step (elfm_link.h): each live
 * track's candidate detections, from a FLANN exact k-d tree over the
 * frame's detections in the anisotropic metric (z / kz), or by brute force
 * over every pair (o.brute_force, the reference the tests compare with).
 * A track dark for more than short_gap frames in a recording at rest is
 * looked for where it was too (the rest hypothesis, link.c predict_rest):
 * a second radius search, merged so that each detection keeps its lower
 * cost. */
#include <flann/flann.h>
#include <math.h>
#include <stdlib.h>

#include "link_internal.h"

/* Add detection j at cost to a track's candidates lc[0 .. *c), kept
 * sorted by cost, at most max of them, each detection once (its lower
 * cost): a detection can be found under both of a track's hypotheses. */
static void cand_add(link_cand *lc, int *c, int max, int j, double cost)
{
  int k = 0;
  while (k < *c && lc[k].det != j) k++;
  if (k < *c) {
    if (cost >= lc[k].cost) return;
  } else if (*c < max) {
    k = (*c)++;
  } else if (cost < lc[*c - 1].cost) {
    k = *c - 1;
  } else {
    return;
  }
  while (k > 0 && lc[k - 1].cost > cost) {
    lc[k] = lc[k - 1];
    k--;
  }
  lc[k] = (link_cand){j, cost};
}

/* The k-d tree's detections within gate_um of c[] (z / kz): their indices
 * in l->nn_idx[0 .. *k), nearest first, at most max_candidates. FLANN's L2
 * works in squared distances, in float. */
static elfm_status radius_search(elfm_linker *l, flann_index_t idx, struct FLANNParameters *fp,
                                 const double c[3], double gate_um, int *k, elfm_error *err)
{
  const int max = l->o.max_candidates;
  float q[3] = {(float)c[0], (float)c[1], (float)(c[2] / l->o.kz)};
  *k = flann_radius_search_float(idx, q, l->nn_idx, l->nn_dist, max, (float)(gate_um * gate_um), fp);
  if (*k < 0) return elfm_error_set(err, ELFM_ERR_INVALID, NULL, -1, "link: FLANN radius search failed");
  if (*k > max) *k = max;
  return ELFM_OK;
}

elfm_status elfm_link_candidates(elfm_linker *l, const elfm_detection *det, size_t nt, size_t nd,
                                 elfm_error *err)
{
  const elfm_link_options *o = &l->o;
  const int max = o->max_candidates;
  if (nt == 0 || nd == 0) return ELFM_OK;
  if (o->brute_force) {
    for (size_t i = 0; i < nt; i++) {
      const live_track *lt = &l->live[i];
      /* keep the max_candidates nearest, as the k-d tree's sorted search */
      link_cand *lc = &l->cand[i * (size_t)max];
      int c = 0;
      double cost;
      for (size_t j = 0; j < nd; j++)
        if (link_gated_cost(o, lt->pred, lt->gate_um, lt->missed, &det[j], &cost))
          cand_add(lc, &c, max, (int)j, cost);
      for (size_t j = 0; lt->has_rest && j < nd; j++)
        if (link_gated_cost(o, lt->rest, lt->rest_gate_um, lt->missed, &det[j], &cost))
          cand_add(lc, &c, max, (int)j, cost);
      l->n_cand[i] = c;
    }
    return ELFM_OK;
  }
  for (size_t j = 0; j < nd; j++) {
    l->pts[3 * j] = (float)det[j].x_um;
    l->pts[3 * j + 1] = (float)det[j].y_um;
    l->pts[3 * j + 2] = (float)(det[j].z_um / o->kz);
  }
  struct FLANNParameters fp = DEFAULT_FLANN_PARAMETERS;
  fp.algorithm = FLANN_INDEX_KDTREE_SINGLE;  /* exact search */
  fp.leaf_max_size = 10;
  fp.checks = FLANN_CHECKS_UNLIMITED;
  fp.sorted = 1;                              /* nearest first when capped */
  fp.max_neighbors = max;
  fp.cores = 1;
  fp.log_level = FLANN_LOG_NONE;
  float speedup = 0;
  flann_index_t idx = flann_build_index_float(l->pts, (int)nd, 3, &speedup, &fp);
  if (!idx) return elfm_error_set(err, ELFM_ERR_NOMEM, NULL, -1, "link: FLANN index build failed");
  elfm_status st = ELFM_OK;
  for (size_t i = 0; i < nt && st == ELFM_OK; i++) {
    const live_track *lt = &l->live[i];
    link_cand *lc = &l->cand[i * (size_t)max];
    int k = 0, c = 0;
    double cost;
    if ((st = radius_search(l, idx, &fp, lt->pred, lt->gate_um, &k, err)) != ELFM_OK) break;
    /* sorted by FLANN's float distance; the cost is the exact double one */
    for (int m = 0; m < k; m++) {
      int j = l->nn_idx[m];
      if (j >= 0 && (size_t)j < nd &&
          link_gated_cost(o, lt->pred, lt->gate_um, lt->missed, &det[j], &cost))
        lc[c++] = (link_cand){j, cost};
    }
    if (lt->has_rest) {  /* the same search around where it was */
      if ((st = radius_search(l, idx, &fp, lt->rest, lt->rest_gate_um, &k, err)) != ELFM_OK) break;
      for (int m = 0; m < k; m++) {
        int j = l->nn_idx[m];
        if (j >= 0 && (size_t)j < nd &&
            link_gated_cost(o, lt->rest, lt->rest_gate_um, lt->missed, &det[j], &cost))
          cand_add(lc, &c, max, j, cost);
      }
    }
    l->n_cand[i] = c;
  }
  flann_free_index_float(idx, &fp);
  return st;
}
