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

/* Detection d (index j) as a candidate of track lt under the rest
 * hypothesis, when within its rest gate: its cost from the rest position. */
static void rest_candidate(const elfm_link_options *o, const live_track *lt,
                           const elfm_detection *d, int j, link_cand *lc, int *c)
{
  const double g2 = lt->rest_gate_um * lt->rest_gate_um;
  const double dx = d->x_um - lt->rest[0], dy = d->y_um - lt->rest[1],
               dz = (d->z_um - lt->rest[2]) / o->kz;
  const double d2 = dx * dx + dy * dy + dz * dz;
  if (d2 >= g2 || link_weak_out(o, d, d2)) return;
  cand_add(lc, c, o->max_candidates, j, d2 / g2 + o->gap_cost * lt->missed);
}

elfm_status elfm_link_candidates(elfm_linker *l, const elfm_detection *det, size_t nt, size_t nd,
                                 elfm_error *err)
{
  const elfm_link_options *o = &l->o;
  const double kz = o->kz;
  /* 2. Candidates from the k-d tree over this frame's detections (or all
   * pairs when brute_force is set). */
  if (nt > 0 && nd > 0 && o->brute_force) {
    for (size_t i = 0; i < nt; i++) {
      live_track *lt = &l->live[i];
      double g2 = lt->gate_um * lt->gate_um;
      /* keep the max_candidates nearest, as the k-d tree's sorted search */
      link_cand *lc = &l->cand[i * (size_t)o->max_candidates];
      int c = 0;
      for (size_t j = 0; j < nd; j++) {
        double dx = det[j].x_um - lt->pred[0], dy = det[j].y_um - lt->pred[1],
               dz = (det[j].z_um - lt->pred[2]) / kz;
        double d2 = dx * dx + dy * dy + dz * dz;
        if (d2 >= g2 || link_weak_out(o, &det[j], d2)) continue;
        cand_add(lc, &c, o->max_candidates, (int)j, d2 / g2 + o->gap_cost * lt->missed);
      }
      if (lt->has_rest)
        for (size_t j = 0; j < nd; j++) rest_candidate(o, lt, &det[j], (int)j, lc, &c);
      l->n_cand[i] = c;
    }
  } else if (nt > 0 && nd > 0) {
    for (size_t j = 0; j < nd; j++) {
      l->pts[3 * j] = (float)det[j].x_um;
      l->pts[3 * j + 1] = (float)det[j].y_um;
      l->pts[3 * j + 2] = (float)(det[j].z_um / kz);
    }
    struct FLANNParameters fp = DEFAULT_FLANN_PARAMETERS;
    fp.algorithm = FLANN_INDEX_KDTREE_SINGLE;  /* exact search */
    fp.leaf_max_size = 10;
    fp.checks = FLANN_CHECKS_UNLIMITED;
    fp.sorted = 1;                              /* nearest first when capped */
    fp.max_neighbors = o->max_candidates;
    fp.cores = 1;
    fp.log_level = FLANN_LOG_NONE;
    float speedup = 0;
    flann_index_t idx = flann_build_index_float(l->pts, (int)nd, 3, &speedup, &fp);
    if (!idx) return elfm_error_set(err, ELFM_ERR_NOMEM, NULL, -1, "link: FLANN index build failed");
    for (size_t i = 0; i < nt; i++) {
      live_track *lt = &l->live[i];
      float q[3] = {(float)lt->pred[0], (float)lt->pred[1], (float)(lt->pred[2] / kz)};
      double g2 = lt->gate_um * lt->gate_um;
      /* FLANN's L2 works in squared distances */
      int k = flann_radius_search_float(idx, q, l->nn_idx, l->nn_dist, o->max_candidates,
                                        (float)g2, &fp);
      if (k < 0) {
        flann_free_index_float(idx, &fp);
        return elfm_error_set(err, ELFM_ERR_INVALID, NULL, -1, "link: FLANN radius search failed");
      }
      if (k > o->max_candidates) k = o->max_candidates;
      int c = 0;
      for (int m = 0; m < k; m++) {
        int j = l->nn_idx[m];
        if (j < 0 || (size_t)j >= nd) continue;
        /* exact double distance for the cost (FLANN's is float) */
        double dx = det[j].x_um - lt->pred[0], dy = det[j].y_um - lt->pred[1],
               dz = (det[j].z_um - lt->pred[2]) / kz;
        double d2 = dx * dx + dy * dy + dz * dz;
        if (d2 >= g2 || link_weak_out(o, &det[j], d2)) continue;
        l->cand[i * (size_t)o->max_candidates + (size_t)c++] =
            (link_cand){j, d2 / g2 + o->gap_cost * lt->missed};
      }
      if (lt->has_rest) {  /* the same search around where it was */
        float qr[3] = {(float)lt->rest[0], (float)lt->rest[1], (float)(lt->rest[2] / kz)};
        const double r2 = lt->rest_gate_um * lt->rest_gate_um;
        k = flann_radius_search_float(idx, qr, l->nn_idx, l->nn_dist, o->max_candidates,
                                      (float)r2, &fp);
        if (k < 0) {
          flann_free_index_float(idx, &fp);
          return elfm_error_set(err, ELFM_ERR_INVALID, NULL, -1, "link: FLANN radius search failed");
        }
        if (k > o->max_candidates) k = o->max_candidates;
        for (int m = 0; m < k; m++) {
          int j = l->nn_idx[m];
          if (j < 0 || (size_t)j >= nd) continue;
          rest_candidate(o, lt, &det[j], j, &l->cand[i * (size_t)o->max_candidates], &c);
        }
      }
      l->n_cand[i] = c;
    }
    flann_free_index_float(idx, &fp);
  }

  return ELFM_OK;
}
