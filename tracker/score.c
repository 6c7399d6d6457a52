/* score.c — `eventlfm score`'s entry points (elfm_score.h, which has every
 * definition): options, the per-frame detection matching, the stage
 * velocity and the assembly of the result, plus the small helpers the
 * other parts share. score_io.c reads the inputs, score_isbi.c scores the
 * tracks; score_internal.h describes how the parts fit.
 */
#include "score_internal.h"

#include "elfm_smooth.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

void elfm_score_options_default(elfm_score_options *o)
{
  memset(o, 0, sizeof *o);
  o->eps_um = 4.0; /* SPEC §7 */
  o->kz = 4.0;     /* SPEC §7 */
  o->n_frames_hint = 0;
  o->max_truth_points = 10000000; /* elfm_score.h */
  o->motion_lead_fade_um_per_ms = 0.5; /* the smoother's default */
}

void elfm_score_options_set_calib(elfm_score_options *o, const elfm_calib *c)
{
  /* SPEC §3: voxel X sits at (X - (W-1)/2) * um_per_px, X = 0..W-1. */
  o->have_bounds = 1;
  o->x_half_um = 0.5 * (double)(c->view_w_px - 1) * c->um_per_px;
  o->y_half_um = 0.5 * (double)(c->view_h_px - 1) * c->um_per_px;
  o->z_min_um = c->z_min_um;
  o->z_max_um = c->z_max_um;
  /* the views' disparities, as `track` gives them to its smoother */
  elfm_smooth_options v;
  elfm_smooth_options_default(&v);
  elfm_smooth_options_set_views(&v, c);
  o->motion_n_views = v.motion_n_views;
  memcpy(o->motion_view_g, v.motion_view_g, sizeof o->motion_view_g);
}

/* ---------------------------------------------------------------------- */
/* Small helpers */

elfm_status elfm_score_nomem(elfm_error *err)
{
  return elfm_error_set(err, ELFM_ERR_NOMEM, NULL, -1, "out of memory while scoring");
}

int elfm_score_keyed_cmp(const void *a, const void *b)
{
  const keyed_t *x = a, *y = b;
  if (x->key != y->key) return x->key < y->key ? -1 : 1;
  return x->idx < y->idx ? -1 : x->idx > y->idx;
}

elfm_status elfm_score_reserve_cost(double **cost, size_t *cap, size_t need, elfm_error *err)
{
  if (need <= *cap) return ELFM_OK;
  double *nb = realloc(*cost, need * sizeof *nb);
  if (!nb) return elfm_score_nomem(err);
  *cost = nb;
  *cap = need;
  return ELFM_OK;
}

/* ---------------------------------------------------------------------- */
/* (3) Detections per frame */

/* Speeds must spread at least this much to tell a lead from a delay. */
#define MOTION_MIN_SPEED_SD_UM_PER_MS 0.25

/* Truth velocity (um/ms) at truth point p of object k from its
 * neighbours in frame order: central where both exist, else one-sided.
 * Returns 0 where there is neither. */
static int truth_velocity(const truth_t *tr, const frames_t *fr, int k, int64_t p, double v[3])
{
  const int64_t a = tr->obj_off[k], b = tr->obj_off[k + 1];
  /* neighbours more than 2 frames away (the object was dark or outside the
   * volume between) would average over an unseen stretch */
  int64_t lo = p > a && tr->pt.frame[p] - tr->pt.frame[p - 1] <= 2 ? p - 1 : p;
  int64_t hi = p + 1 < b && tr->pt.frame[p + 1] - tr->pt.frame[p] <= 2 ? p + 1 : p;
  if (lo == hi) return 0;
  double dt_ms = (fr->t_us[tr->pt.frame[hi]] - fr->t_us[tr->pt.frame[lo]]) * 1e-3;
  if (!(dt_ms > 0)) return 0;
  v[0] = (tr->pt.x[hi] - tr->pt.x[lo]) / dt_ms;
  v[1] = (tr->pt.y[hi] - tr->pt.y[lo]) / dt_ms;
  v[2] = (tr->pt.z[hi] - tr->pt.z[lo]) / dt_ms;
  return 1;
}

/* Least-squares sums for the motion bias (elfm_score.h, MOTION BIAS): the
 * lateral error e against the model's lead and delay terms L and M (2D
 * dot products), and the along-motion error and speed for their means. */
typedef struct {
  int64_t n;
  double s, ss, e;            /* speed, speed^2, error along the motion */
  double ll, lm, mm, el, em;  /* L.L, L.M, M.M, e.L, e.M */
} motion_sums;

/* The motion bias's model, split in its two terms: elfm_motion_bias is
 * linear in the lead and the delay, so L(v) is its bias at lead 1 um and
 * delay 0 (lead_only), M(v) minus its bias at delay 1 ms and lead 0
 * (delay_only). Built once per scoring. */
typedef struct {
  elfm_smooth_options lead_only, delay_only;
} motion_model;

static void motion_add(motion_sums *m, const motion_model *mm, const truth_t *tr,
                       const frames_t *fr, const int *obj_of, int64_t p, double dx, double dy)
{
  double v[3], L[3], M[3];
  if (!truth_velocity(tr, fr, obj_of[p], p, v)) return;
  double sp = hypot(v[0], v[1]);
  /* below the fade speed the direction of motion is too uncertain for an
   * error "along" it (elfm_score.h, MOTION BIAS) */
  if (!(sp >= mm->lead_only.motion_lead_fade_um_per_ms)) return;
  elfm_motion_bias(&mm->lead_only, v, L);
  elfm_motion_bias(&mm->delay_only, v, M);
  M[0] = -M[0];
  M[1] = -M[1];
  m->n++;
  m->s += sp;
  m->ss += sp * sp;
  m->e += (dx * v[0] + dy * v[1]) / sp;
  m->ll += L[0] * L[0] + L[1] * L[1];
  m->lm += L[0] * M[0] + L[1] * M[1];
  m->mm += M[0] * M[0] + M[1] * M[1];
  m->el += dx * L[0] + dy * L[1];
  m->em += dx * M[0] + dy * M[1];
}

static void motion_finish(const motion_sums *m, elfm_score_result *out)
{
  out->n_motion_points = m->n;
  out->motion_lead_um = out->motion_delay_us = out->motion_along_mean_um = NAN;
  out->motion_speed_sd_um_per_ms = NAN;
  if (m->n == 0) return;
  double n = (double)m->n, ms = m->s / n;
  double var_s = fmax(m->ss / n - ms * ms, 0.0);
  out->motion_along_mean_um = m->e / n;
  out->motion_speed_sd_um_per_ms = sqrt(var_s);
  if (m->n < 3 || sqrt(var_s) < MOTION_MIN_SPEED_SD_UM_PER_MS) return;
  /* e = lead L - delay_ms M: lead ll - delay lm = el, lead lm - delay mm = em */
  const double det = m->lm * m->lm - m->ll * m->mm;
  if (!(fabs(det) > 1e-12 * m->ll * m->mm)) return;
  out->motion_lead_um = (m->lm * m->em - m->mm * m->el) / det;
  out->motion_delay_us = 1000.0 * (m->ll * m->em - m->lm * m->el) / det;
}

/* elfm_score.h, DETECTIONS: per frame, the truth points and detections
 * joined by gated pairs (d < eps) form components, each solved with the
 * Hungarian solver; the counts, ratios and RMSEs go to out. */
static elfm_status score_detections(const truth_t *tr, const frames_t *fr, const points_t *dp,
                                    const gate_t *g, const motion_model *mm, double band_um,
                                    elfm_score_result *out, elfm_error *err)
{
  /* per depth band (elfm_score.h, BY DEPTH): matched pairs, their squared
   * errors and summed d */
  int64_t b_tp[ELFM_SCORE_MAX_DEPTH_BANDS] = {0};
  double b_sx[ELFM_SCORE_MAX_DEPTH_BANDS] = {0}, b_sy[ELFM_SCORE_MAX_DEPTH_BANDS] = {0};
  double b_sz[ELFM_SCORE_MAX_DEPTH_BANDS] = {0}, b_sd[ELFM_SCORE_MAX_DEPTH_BANDS] = {0};
  /* Group detections per frame, sorted by x. */
  int64_t *off;
  keyed_t *ds;
  elfm_status s = elfm_score_index_by_frame(dp, fr->n, &off, &ds, err);
  if (s != ELFM_OK) return s;
  int max_t = 0, max_d = 0;
  for (int f = 0; f < fr->n; f++) {
    int nt = (int)(tr->fr_off[f + 1] - tr->fr_off[f]), nd = (int)(off[f + 1] - off[f]);
    if (nt > max_t) max_t = nt;
    if (nd > max_d) max_d = nd;
  }
  /* Scratch sized once for the largest frame (nothing allocated per frame). */
  size_t nn = (size_t)max_t + (size_t)max_d + 1;
  int *parent = malloc(nn * sizeof *parent);
  int *head = malloc(nn * sizeof *head);   /* first node of each root's chain, or -1 */
  int *next = malloc(nn * sizeof *next);   /* next node in the same component, or -1 */
  int *rows = malloc(nn * sizeof *rows), *cols = malloc(nn * sizeof *cols);
  int *r2c = malloc(nn * sizeof *r2c);
  /* each truth point's object (for its velocity) */
  int *obj_of = malloc(((size_t)tr->pt.n + 1) * sizeof *obj_of);
  motion_sums ms;
  memset(&ms, 0, sizeof ms);
  double *cost = NULL;
  size_t cost_cap = 0;
  elfm_assign_workspace *ws = NULL;
  if (!parent || !head || !next || !rows || !cols || !r2c || !obj_of) {
    s = elfm_score_nomem(err);
    goto done;
  }
  for (int k = 0; k < tr->n_obj; k++)
    for (int64_t p = tr->obj_off[k]; p < tr->obj_off[k + 1]; p++) obj_of[p] = k;
  if ((s = elfm_assign_workspace_create(0, 0, &ws, err)) != ELFM_OK) goto done;

  int64_t tp = 0;
  double sx = 0, sy = 0, sz = 0, sd = 0, rx = 0, ry = 0, rz = 0; /* rx..: as measured */
  for (int f = 0; f < fr->n; f++) {
    int64_t ta = tr->fr_off[f];
    int nt = (int)(tr->fr_off[f + 1] - ta);
    int64_t da = off[f];
    int nd = (int)(off[f + 1] - da);
    if (nt == 0 || nd == 0) continue;
    for (int q = 0; q < nt + nd; q++) parent[q] = q;
    /* Edges d < eps: for each truth point, detections with |dx| < eps. */
    int any = 0;
    for (int i = 0; i < nt; i++) {
      int64_t p = (int64_t)tr->fr_pt[ta + i].idx;
      int lo = (int)(lower_x(ds, da, da + nd, tr->pt.x[p] - g->eps) - da);
      for (int j = lo; j < nd && ds[da + j].key < tr->pt.x[p] + g->eps; j++) {
        int di = (int)ds[da + j].idx;
        if (dist_aniso(g, dp->x[di] - tr->pt.x[p], dp->y[di] - tr->pt.y[p],
                       dp->z[di] - tr->pt.z[p]) < g->eps) {
          uf_union(parent, i, nt + j);
          any = 1;
        }
      }
    }
    if (!any) continue;
    /* Solve each connected component with >= 2 nodes. Nodes are chained
     * per root (linear time; scanning all nodes per root was quadratic). */
    for (int q = 0; q < nt + nd; q++) head[q] = -1;
    for (int q = nt + nd - 1; q >= 0; q--) {
      int root = uf_find(parent, q);
      next[q] = head[root];
      head[root] = q;
    }
    for (int root = 0; root < nt + nd; root++) {
      if (head[root] < 0 || next[head[root]] < 0) continue;
      int nr = 0, nc = 0;
      for (int q = head[root]; q >= 0; q = next[q]) {
        if (q < nt) rows[nr++] = q;
        else cols[nc++] = q - nt;
      }
      if (nr == 0 || nc == 0) continue;
      size_t need = (size_t)nr * (size_t)nc;
      if ((s = elfm_score_reserve_cost(&cost, &cost_cap, need, err)) != ELFM_OK) goto done;
      for (int a = 0; a < nr; a++) {
        int64_t p = (int64_t)tr->fr_pt[ta + rows[a]].idx;
        for (int b = 0; b < nc; b++) {
          int di = (int)ds[da + cols[b]].idx;
          double d = dist_aniso(g, dp->x[di] - tr->pt.x[p], dp->y[di] - tr->pt.y[p],
                                dp->z[di] - tr->pt.z[p]);
          cost[(size_t)a * (size_t)nc + (size_t)b] = d < g->eps ? d : INFINITY;
        }
      }
      if ((s = elfm_assign_hungarian(cost, nr, nc, r2c, NULL, ws, err)) != ELFM_OK) goto done;
      for (int a = 0; a < nr; a++) {
        if (r2c[a] < 0) continue;
        int64_t p = (int64_t)tr->fr_pt[ta + rows[a]].idx;
        int di = (int)ds[da + cols[r2c[a]]].idx;
        double dx = dp->x[di] - tr->pt.x[p], dy = dp->y[di] - tr->pt.y[p];
        double dz = dp->z[di] - tr->pt.z[p];
        const double d = dist_aniso(g, dx, dy, dz);
        tp++;
        sd += d;
        if (band_um > 0) {
          const int k = depth_band(tr->pt.z[p], band_um);
          b_tp[k]++;
          b_sx[k] += dx * dx;
          b_sy[k] += dy * dy;
          b_sz[k] += dz * dz;
          b_sd[k] += d;
        }
        if (dp->raw_x) { /* the regression is of the bias as measured */
          const double ex = dp->raw_x[di] - tr->pt.x[p], ey = dp->raw_y[di] - tr->pt.y[p],
                       ez = dp->raw_z[di] - tr->pt.z[p];
          motion_add(&ms, mm, tr, fr, obj_of, p, ex, ey);
          rx += ex * ex;
          ry += ey * ey;
          rz += ez * ez;
        } else {
          motion_add(&ms, mm, tr, fr, obj_of, p, dx, dy);
        }
        sx += dx * dx;
        sy += dy * dy;
        sz += dz * dz;
      }
    }
  }
  out->n_truth_points = tr->pt.n;
  out->n_detections = dp->n;
  out->n_true_positives = tp;
  out->recall = tr->pt.n ? (double)tp / (double)tr->pt.n : NAN;
  out->precision = dp->n ? (double)tp / (double)dp->n : NAN;
  out->f1 = (tr->pt.n + dp->n) ? 2.0 * (double)tp / (double)(tr->pt.n + dp->n) : NAN;
  out->rmse_x_um = tp ? sqrt(sx / (double)tp) : NAN;
  out->rmse_y_um = tp ? sqrt(sy / (double)tp) : NAN;
  out->rmse_z_um = tp ? sqrt(sz / (double)tp) : NAN;
  out->rmse_raw_x_um = tp && dp->raw_x ? sqrt(rx / (double)tp) : NAN;
  out->rmse_raw_y_um = tp && dp->raw_x ? sqrt(ry / (double)tp) : NAN;
  out->rmse_raw_z_um = tp && dp->raw_x ? sqrt(rz / (double)tp) : NAN;
  out->alpha_detections =
      tr->pt.n ? 1.0 - (sd + g->eps * (double)(tr->pt.n - tp)) / (g->eps * (double)tr->pt.n)
               : NAN;
  motion_finish(&ms, out);
  for (int k = 0; k < out->n_depth_bands; k++) {
    elfm_score_band *bd = &out->depth_bands[k];
    const double n = (double)bd->n_truth_points, m = (double)b_tp[k];
    bd->n_true_positives = b_tp[k];
    bd->recall = n > 0 ? m / n : NAN;
    bd->rmse_x_um = m > 0 ? sqrt(b_sx[k] / m) : NAN;
    bd->rmse_y_um = m > 0 ? sqrt(b_sy[k] / m) : NAN;
    bd->rmse_z_um = m > 0 ? sqrt(b_sz[k] / m) : NAN;
    bd->alpha_detections = n > 0 ? 1.0 - (b_sd[k] + g->eps * (n - m)) / (g->eps * n) : NAN;
  }
done:
  free(obj_of);
  elfm_assign_workspace_free(ws);
  free(cost);
  free(parent);
  free(head);
  free(next);
  free(rows);
  free(cols);
  free(r2c);
  free(off);
  free(ds);
  return s;
}

/* ---------------------------------------------------------------------- */
/* (5) Stage velocity */

static void score_stage(const elfm_table *t, const int *c, const elfm_score_options *o,
                        elfm_score_result *out)
{
  const char *vn[3] = {"vx_um_per_ms", "vy_um_per_ms", "vz_um_per_ms"};
  int cv[3];
  int have_v = 1;
  for (int a = 0; a < 3; a++) have_v &= (cv[a] = elfm_table_col(t, vn[a])) >= 0;
  double sum[3] = {0, 0, 0};
  int64_t n = 0;
  if (have_v) {
    for (size_t r = 0; r < t->n_rows; r++) {
      if (!isfinite(elfm_table_get(t, r, c[6]))) continue;
      double v[3];
      int ok = 1;
      for (int a = 0; a < 3; a++) ok &= isfinite(v[a] = elfm_table_get(t, r, cv[a]));
      if (!ok) continue;
      for (int a = 0; a < 3; a++) sum[a] += v[a];
      n++;
    }
  } else {
    /* Per track: displacement of the first to the last real row over time,
     * assuming rows of a track are in frame order (checked earlier). */
    for (size_t r = 0; r < t->n_rows; r++) {
      if (!isfinite(elfm_table_get(t, r, c[6]))) continue;
      double id = elfm_table_get(t, r, c[0]);
      int first = 1;
      for (size_t q = 0; q < r; q++)
        if (elfm_table_get(t, q, c[0]) == id && isfinite(elfm_table_get(t, q, c[6]))) { first = 0; break; }
      if (!first) continue;
      size_t last = r;
      for (size_t q = r + 1; q < t->n_rows; q++)
        if (elfm_table_get(t, q, c[0]) == id && isfinite(elfm_table_get(t, q, c[6]))) last = q;
      double dt_ms = (elfm_table_get(t, last, c[2]) - elfm_table_get(t, r, c[2])) / 1000.0;
      if (!(dt_ms > 0)) continue;
      for (int a = 0; a < 3; a++)
        sum[a] += (elfm_table_get(t, last, c[3 + a]) - elfm_table_get(t, r, c[3 + a])) / dt_ms;
      n++;
    }
  }
  if (n == 0) return;
  double e2 = 0, s2 = 0;
  for (int a = 0; a < 3; a++) {
    out->mean_v_um_per_ms[a] = sum[a] / (double)n;
    double d = out->mean_v_um_per_ms[a] - o->stage_v_um_per_ms[a];
    e2 += d * d;
    s2 += o->stage_v_um_per_ms[a] * o->stage_v_um_per_ms[a];
  }
  out->has_stage = 1;
  out->stage_rel_error = s2 > 0 ? sqrt(e2 / s2) : NAN;
}

/* ---------------------------------------------------------------------- */

elfm_status elfm_score_tables(const elfm_table *truth, const elfm_table *tracks,
                              const elfm_table *detections, const elfm_score_options *opt,
                              elfm_score_result *out, elfm_error *err)
{
  memset(out, 0, sizeof *out);
  out->recall = out->precision = out->f1 = NAN;
  out->rmse_x_um = out->rmse_y_um = out->rmse_z_um = NAN;
  out->rmse_raw_x_um = out->rmse_raw_y_um = out->rmse_raw_z_um = NAN;
  out->alpha_detections = NAN;
  out->alpha = out->beta = out->jaccard_tracks = out->jaccard_detections = NAN;
  out->rmse_tracks_um = out->stage_rel_error = NAN;
  out->alpha_identities = out->identity_fragments = out->identity_other_tracks = NAN;
  out->motion_lead_um = out->motion_delay_us = out->motion_along_mean_um = NAN;
  out->motion_speed_sd_um_per_ms = NAN;
  out->alpha_tracks_unplaced_cost = NAN;
  if (!truth || (!tracks && !detections) || !opt)
    return elfm_error_set(err, ELFM_ERR_INVALID, NULL, -1,
                          "scoring needs truth and tracks or detections");
  if (opt->max_truth_points < 1)
    return elfm_error_set(err, ELFM_ERR_INVALID, NULL, -1, "max_truth_points must be >= 1");
  if (!(opt->motion_lead_fade_um_per_ms > 0 && opt->motion_lead_fade_um_per_ms <= 100))
    return elfm_error_set(err, ELFM_ERR_INVALID, NULL, -1,
                          "motion fade speed %g um/ms must be in (0, 100]",
                          opt->motion_lead_fade_um_per_ms);
  if (opt->motion_n_views < 0 || opt->motion_n_views > ELFM_MAX_VIEWS)
    return elfm_error_set(err, ELFM_ERR_INVALID, NULL, -1, "%d views for the motion bias (0-%d)",
                          opt->motion_n_views, ELFM_MAX_VIEWS);
  if (!(opt->eps_um > 0) || !(opt->kz > 0) || !isfinite(opt->eps_um) || !isfinite(opt->kz))
    return elfm_error_set(err, ELFM_ERR_INVALID, NULL, -1,
                          "gate eps %g um and kz %g must be positive", opt->eps_um, opt->kz);
  if (!(opt->depth_band_um >= 0) || !isfinite(opt->depth_band_um))
    return elfm_error_set(err, ELFM_ERR_INVALID, NULL, -1,
                          "depth band %g um must be finite and >= 0", opt->depth_band_um);
  gate_t g = {opt->eps_um, opt->kz};
  const double band_um = opt->depth_band_um;

  int cd[5], ct[9];
  elfm_status s = elfm_score_columns(detections, cd, tracks, ct, err);
  if (s != ELFM_OK) return s;

  frames_t fr = {0, 0, NULL, NULL, NULL};
  truth_t tr;
  memset(&tr, 0, sizeof tr);
  points_t dp, raw;
  memset(&dp, 0, sizeof dp);
  memset(&raw, 0, sizeof raw);
  cands_t cand;
  memset(&cand, 0, sizeof cand);

  if (opt->window_frames && !opt->frames)
    return elfm_error_set(err, ELFM_ERR_INVALID, NULL, -1,
                          "the window rule over each frame's own window needs the frame list");
  s = elfm_score_frames_build(&fr, detections, cd, tracks, ct, opt->n_frames_hint, opt->frames,
                              err);
  if (s != ELFM_OK) goto done;
  if ((s = elfm_score_frames_trim(&fr, truth, &out->n_frames_unscored, err)) != ELFM_OK) goto done;
  out->n_frames = fr.n - out->n_frames_unscored;
  if ((s = elfm_score_truth_build(&tr, truth, &fr, opt, err)) != ELFM_OK) goto done;
  out->n_truth_lit_then_dark = tr.n_lit_then_dark;

  if (detections && (s = elfm_score_detections_load(&dp, detections, cd, &fr, err)) != ELFM_OK)
    goto done;
  if (tracks) {
    s = elfm_score_cands_build(&cand, detections ? NULL : &raw, tracks, ct, &fr, err);
    if (s != ELFM_OK) goto done;
  }
  out->detections_from_tracks = detections ? 0 : 1;
  /* the motion bias's model: the views' when a calibration gave them */
  motion_model mm;
  elfm_smooth_options_default(&mm.lead_only);
  mm.lead_only.motion_n_views = opt->motion_n_views;
  memcpy(mm.lead_only.motion_view_g, opt->motion_view_g, sizeof mm.lead_only.motion_view_g);
  mm.lead_only.motion_lead_fade_um_per_ms = opt->motion_lead_fade_um_per_ms;
  mm.delay_only = mm.lead_only;
  mm.lead_only.motion_lead_um = 1.0;
  mm.lead_only.motion_delay_us = 0.0;
  mm.delay_only.motion_lead_um = 0.0;
  mm.delay_only.motion_delay_us = 1000.0;
  if (band_um > 0) {
    out->n_depth_bands = ELFM_SCORE_MAX_DEPTH_BANDS;
    for (int k = 0; k < ELFM_SCORE_MAX_DEPTH_BANDS; k++) {
      elfm_score_band *bd = &out->depth_bands[k];
      bd->z_lo_um = band_um * k;
      bd->z_hi_um = k < ELFM_SCORE_MAX_DEPTH_BANDS - 1 ? band_um * (k + 1) : INFINITY;
      bd->recall = bd->rmse_x_um = bd->rmse_y_um = bd->rmse_z_um = NAN;
      bd->alpha_detections = bd->alpha_tracks = NAN;
    }
    for (int64_t p = 0; p < tr.pt.n; p++)
      out->depth_bands[depth_band(tr.pt.z[p], band_um)].n_truth_points++;
  }
  s = score_detections(&tr, &fr, detections ? &dp : &raw, &g, &mm, band_um, out, err);
  if (s != ELFM_OK) goto done;
  if (tracks) {
    if ((s = elfm_score_isbi_tracks(&tr, &cand, &g, band_um, out, err)) != ELFM_OK) goto done;
    if ((s = elfm_score_identities(&tr, &cand, &g, out, err)) != ELFM_OK) goto done;
    if (opt->have_stage) score_stage(tracks, ct, opt, out);
  }
  if (fr.n == 0) {
    /* No detection and no track point at all: there is no frame list to
     * sample the truth at, but if the truth shows any object the run missed
     * everything: recall, F1, alpha, beta and the Jaccards are 0 (precision
     * stays undefined). */
    int seen = 0;
    if ((s = elfm_score_truth_ids_seen(truth, opt, &seen, err)) != ELFM_OK) goto done;
    if (seen > 0) {
      out->recall = out->f1 = out->alpha_detections = 0.0;
      if (tracks) {
        out->alpha = out->beta = out->jaccard_tracks = out->jaccard_detections = 0.0;
        out->alpha_identities = 0.0;
        out->n_truth_tracks = out->n_missed_tracks = seen;
      }
    }
  }
done:
  elfm_score_frames_free(&fr);
  elfm_score_truth_free(&tr);
  elfm_score_points_free(&dp);
  elfm_score_points_free(&raw);
  elfm_score_cands_free(&cand);
  return s;
}

elfm_status elfm_score_files(const char *truth_csv, const char *tracks_csv,
                             const char *detections_csv, const elfm_score_options *opt,
                             elfm_score_result *out, elfm_error *err)
{
  elfm_table *truth = NULL, *tracks = NULL, *dets = NULL;
  elfm_status s = elfm_table_load_csv(truth_csv, &truth, err);
  if (s == ELFM_OK && tracks_csv) s = elfm_table_load_csv(tracks_csv, &tracks, err);
  if (s == ELFM_OK && detections_csv) s = elfm_table_load_csv(detections_csv, &dets, err);
  if (s == ELFM_OK) s = elfm_score_tables(truth, tracks, dets, opt, out, err);
  elfm_table_free(truth);
  elfm_table_free(tracks);
  elfm_table_free(dets);
  return s;
}
