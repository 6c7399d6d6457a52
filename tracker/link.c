/* link.c — streaming linker (see elfm_link.h): options, life cycle and the
 * per-frame linking, steps 1-4 of elfm_link_step: prediction from each
 * track's fits, the candidates (step 2, in link_candidates.c: the FLANN k-d
 * tree, brute force, the rest hypothesis), optimal assignment per connected
 * group, gap closing, births. Also the scratch and track fits that
 * link_candidates.c and link_repair.c share (link_internal.h); the latter
 * holds the repair steps 5-7 (stitching, swap and encounter review) run at
 * the end of each step. */
#include "elfm_link.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "elfm_score.h"
#include "link_internal.h"

void elfm_link_options_default(elfm_link_options *o)
{
  memset(o, 0, sizeof *o);
  o->gate_um = 6.0;
  o->gate_growth_um_per_frame = 0.05;
  o->kz = 4.0;
  o->max_gap_frames = 50;
  o->min_points = 5;
  o->history = 20;
  o->short_history = 8;
  o->short_gap = 6;
  o->gap_cost = 0.02;
  o->max_candidates = 8;
  o->lag_tau_us = 0;
  o->birth_speed_um_per_ms = 5.0;
  o->speed_gate_frac = 0.3;
  o->rescue_gate_factor = 2.5;
  o->weak_gate_um = 0;
  o->trail_us = 2000;
  o->stitch_points = 0;
  o->stitch_gate_um = 8.0;
  o->stitch_history = 100;
  o->stitch_straight_frac = 0.1;
  o->stitch_late_points = 0;
  o->swap_points = 0;
  o->swap_ratio = 0.5;
  o->encounter_um = 0;
  o->encounter_pad = 1;
  o->encounter_apart = 0;
  o->encounter_ratio = 0.5;
  o->encounter_circle_ratio = 0;
  o->encounter_line_ratio = 0;
  o->review_join_factor = 2;
  o->twin_um = 0;
  o->twin_points = 5;
  o->rest_speed_um_per_ms = 0.5;
  o->circle_points = 0;
  o->circle_after = 2;
  o->straight_gaps = 0;
  o->circle_gap_points = 4;
  o->circle_end_points = 0;
  o->circle_min_arc_rad = 1.0;
  o->circle_max_radius_um = 60;
  o->circle_line_ratio = 0.5;
}

/* The first option out of range, named with its value and what it takes;
 * ELFM_OK when all are good. */
static elfm_status link_options_check(const elfm_link_options *o, elfm_error *err)
{
#define LINK_NEED(ok, name, value, what)                                                   \
  do {                                                                                     \
    if (!(ok))                                                                             \
      return elfm_error_set(err, ELFM_ERR_INVALID, NULL, -1,                               \
                            "link: option %s = %g is out of range (%s)", name, (double)(value), \
                            what);                                                         \
  } while (0)
  LINK_NEED(o->gate_um > 0 && isfinite(o->gate_um), "gate_um", o->gate_um, "> 0");
  LINK_NEED(o->gate_growth_um_per_frame >= 0 && isfinite(o->gate_growth_um_per_frame),
            "gate_growth_um_per_frame", o->gate_growth_um_per_frame, ">= 0");
  LINK_NEED(o->kz > 0, "kz", o->kz, "> 0");
  LINK_NEED(o->max_gap_frames >= 0, "max_gap_frames", o->max_gap_frames, ">= 0");
  LINK_NEED(o->min_points >= 1, "min_points", o->min_points, ">= 1");
  LINK_NEED(o->history >= 2, "history", o->history, ">= 2");
  LINK_NEED(o->short_history >= 4, "short_history", o->short_history, ">= 4");
  LINK_NEED(o->short_gap >= 0, "short_gap", o->short_gap, ">= 0");
  LINK_NEED(o->gap_cost >= 0, "gap_cost", o->gap_cost, ">= 0");
  LINK_NEED(o->max_candidates >= 1 && o->max_candidates <= 1024, "max_candidates", o->max_candidates,
            "1..1024");
  LINK_NEED(o->lag_tau_us >= 0, "lag_tau_us", o->lag_tau_us, ">= 0");
  LINK_NEED(isfinite(o->lead_sigmas), "lead_sigmas", o->lead_sigmas, "finite");
  for (int a = 0; a < 3; a++)
    LINK_NEED(isfinite(o->prior_velocity_um_per_ms[a]), "prior_velocity_um_per_ms",
              o->prior_velocity_um_per_ms[a], "finite");
  LINK_NEED(o->birth_speed_um_per_ms >= 0 && isfinite(o->birth_speed_um_per_ms), "birth_speed_um_per_ms",
            o->birth_speed_um_per_ms, ">= 0");
  LINK_NEED(o->birth_frames >= 0, "birth_frames", o->birth_frames, ">= 0");
  LINK_NEED(o->speed_gate_frac >= 0, "speed_gate_frac", o->speed_gate_frac, ">= 0");
  LINK_NEED(o->rescue_gate_factor >= 0 && isfinite(o->rescue_gate_factor), "rescue_gate_factor",
            o->rescue_gate_factor, ">= 0");
  LINK_NEED(o->weak_gate_um >= 0 && isfinite(o->weak_gate_um), "weak_gate_um", o->weak_gate_um, ">= 0");
  LINK_NEED(o->stitch_points == 0 || o->stitch_points >= 4, "stitch_points", o->stitch_points,
            "0 or >= 4");
  LINK_NEED(o->stitch_gate_um >= 0 && isfinite(o->stitch_gate_um), "stitch_gate_um", o->stitch_gate_um,
            ">= 0");
  LINK_NEED(o->stitch_history >= 1, "stitch_history", o->stitch_history, ">= 1");
  LINK_NEED(o->stitch_straight_frac >= 0 && isfinite(o->stitch_straight_frac), "stitch_straight_frac",
            o->stitch_straight_frac, ">= 0");
  LINK_NEED(o->stitch_late_points >= 0, "stitch_late_points", o->stitch_late_points, ">= 0");
  LINK_NEED(o->swap_points == 0 || o->swap_points >= 4, "swap_points", o->swap_points, "0 or >= 4");
  LINK_NEED(o->swap_ratio > 0 && o->swap_ratio <= 1, "swap_ratio", o->swap_ratio, "> 0 and <= 1");
  LINK_NEED(o->encounter_um >= 0 && isfinite(o->encounter_um), "encounter_um", o->encounter_um, ">= 0");
  LINK_NEED(o->encounter_pad >= 0, "encounter_pad", o->encounter_pad, ">= 0");
  LINK_NEED(o->encounter_apart >= 0, "encounter_apart", o->encounter_apart, ">= 0");
  LINK_NEED(o->encounter_ratio > 0 && o->encounter_ratio <= 1, "encounter_ratio", o->encounter_ratio,
            "> 0 and <= 1");
  LINK_NEED(o->encounter_circle_ratio >= 0 && o->encounter_circle_ratio <= 1, "encounter_circle_ratio",
            o->encounter_circle_ratio, "0..1");
  LINK_NEED(o->encounter_line_ratio >= 0 && o->encounter_line_ratio <= 1, "encounter_line_ratio",
            o->encounter_line_ratio, "0..1");
  LINK_NEED(o->review_join_factor >= 0 && isfinite(o->review_join_factor), "review_join_factor",
            o->review_join_factor, ">= 0");
  LINK_NEED(o->priority_points >= 0, "priority_points", o->priority_points, ">= 0");
  LINK_NEED(o->twin_um >= 0 && isfinite(o->twin_um), "twin_um", o->twin_um, ">= 0");
  LINK_NEED(o->twin_points >= 1 && o->twin_points <= 1000, "twin_points", o->twin_points, "1..1000");
  LINK_NEED(o->short_path_um >= 0 && isfinite(o->short_path_um), "short_path_um", o->short_path_um, ">= 0");
  LINK_NEED(o->trail_us >= 0 && isfinite(o->trail_us), "trail_us", o->trail_us, ">= 0");
  LINK_NEED(o->rest_speed_um_per_ms >= 0 && isfinite(o->rest_speed_um_per_ms), "rest_speed_um_per_ms",
            o->rest_speed_um_per_ms, ">= 0");
  LINK_NEED(o->circle_points == 0 || o->circle_points >= 6, "circle_points", o->circle_points, "0 or >= 6");
  LINK_NEED(o->circle_end_points == 0 || o->circle_end_points >= 6, "circle_end_points",
            o->circle_end_points, "0 or >= 6");
  LINK_NEED(o->circle_next_path_um >= 0 && isfinite(o->circle_next_path_um), "circle_next_path_um",
            o->circle_next_path_um, ">= 0");
  LINK_NEED(o->circle_after >= 1, "circle_after", o->circle_after, ">= 1");
  LINK_NEED(o->straight_gaps >= 0 && o->straight_gaps <= 2, "straight_gaps", o->straight_gaps,
            "0, 1 or 2");
  LINK_NEED(o->circle_min_arc_rad >= 0 && isfinite(o->circle_min_arc_rad), "circle_min_arc_rad",
            o->circle_min_arc_rad, ">= 0");
  LINK_NEED(o->circle_max_radius_um > 0, "circle_max_radius_um", o->circle_max_radius_um, "> 0");
  LINK_NEED(o->circle_line_ratio > 0 && o->circle_line_ratio <= 1, "circle_line_ratio",
            o->circle_line_ratio, "> 0 and <= 1");
#undef LINK_NEED
  return ELFM_OK;
}

elfm_linker *elfm_link_create(const elfm_link_options *o, elfm_error *err)
{
  if (!o) {
    elfm_error_set(err, ELFM_ERR_INVALID, NULL, -1, "link: NULL options");
    return NULL;
  }
  if (link_options_check(o, err) != ELFM_OK) return NULL;
  elfm_linker *l = calloc(1, sizeof *l);
  if (!l) {
    elfm_error_set(err, ELFM_ERR_NOMEM, NULL, -1, "link: out of memory");
    return NULL;
  }
  l->o = *o;
  l->nn_idx = malloc((size_t)o->max_candidates * sizeof *l->nn_idx);
  l->nn_dist = malloc((size_t)o->max_candidates * sizeof *l->nn_dist);
  if (!l->nn_idx || !l->nn_dist ||
      elfm_assign_workspace_create(16, 16, &l->aws, err) != ELFM_OK) {
    elfm_link_free(l);
    elfm_error_set(err, ELFM_ERR_NOMEM, NULL, -1, "link: out of memory");
    return NULL;
  }
  return l;
}

void elfm_link_free(elfm_linker *l)
{
  if (!l) return;
  for (size_t i = 0; i < l->n_live; i++) elfm_track_free(l->live[i].t);
  for (size_t i = 0; i < l->fin_n; i++) elfm_track_free(l->fin[l->fin_head + i]);
  free(l->live);
  free(l->fin);
  free(l->enc);
  free(l->pts);
  free(l->nn_idx);
  free(l->nn_dist);
  free(l->cand);
  free(l->n_cand);
  free(l->uf);
  free(l->comp_of);
  free(l->comp_start);
  free(l->comp_fill);
  free(l->members);
  free(l->track_det);
  free(l->det_track);
  free(l->det_local);
  free(l->det_id);
  free(l->det_vel);
  free(l->cost);
  free(l->row_to_col);
  free(l->rows);
  free(l->xkeys);
  free(l->vel_scratch);
  free(l->cols);
  elfm_assign_workspace_free(l->aws);
  free(l);
}

elfm_status elfm_link_take_piece(elfm_linker *l, size_t piece_points, size_t keep_points,
                                 size_t context_points, elfm_track **out, elfm_error *err)
{
  if (out) *out = NULL;
  if (!l || !out || piece_points < 1 || keep_points < 64 || context_points > keep_points)
    return elfm_error_set(err, ELFM_ERR_INVALID, NULL, -1,
                          "link: pieces need piece_points >= 1, keep_points >= 64, "
                          "context_points <= keep_points");
  for (size_t i = 0; i < l->n_live; i++) {
    live_track *lt = &l->live[i];
    elfm_track *t = lt->t;
    /* its own points: from the previous cut on (all of them before one) */
    size_t own0 = 0;
    if (t->partial)
      while (own0 < t->n && t->pts[own0].frame < t->write_from_frame) own0++;
    if (t->n - own0 < piece_points + keep_points) continue;
    const size_t cut = t->n - keep_points, end = cut + context_points,
                 drop = cut - (cut - own0 < context_points ? cut - own0 : context_points);
    const int64_t cut_frame = t->pts[cut].frame;
    elfm_track *p = elfm_track_create(t->id, err);
    if (!p) return ELFM_ERR_NOMEM;
    p->pts = malloc(end * sizeof *p->pts);
    if (!p->pts) {
      elfm_track_free(p);
      return elfm_error_set(err, ELFM_ERR_NOMEM, NULL, -1, "link: out of memory (track piece)");
    }
    memcpy(p->pts, t->pts, end * sizeof *p->pts);
    p->n = p->cap = end;
    p->partial = 1;
    p->piece = t->piece;
    p->write_from_frame = t->partial ? t->write_from_frame : INT64_MIN;
    p->write_to_frame = cut_frame;
    /* the live track keeps the context before the cut and what follows */
    memmove(t->pts, t->pts + drop, (t->n - drop) * sizeof *t->pts);
    t->n -= drop;
    t->partial = 1;
    t->piece++;
    t->write_from_frame = cut_frame;
    t->write_to_frame = INT64_MAX;
    /* the gap closing under review (tail0 indexes the points) moved too;
     * one that old has long been reviewed */
    if (lt->tail0 >= drop) lt->tail0 -= drop;
    else {
      lt->tail0 = 0;
      lt->review = 0;
    }
    *out = p;
    return ELFM_OK;
  }
  return ELFM_OK;
}

size_t elfm_link_n_live(const elfm_linker *l) { return l ? l->n_live : 0; }

const elfm_track *elfm_link_live_track(const elfm_linker *l, int64_t track_id)
{
  for (size_t i = 0; l && i < l->n_live; i++)
    if (l->live[i].t->id == track_id) return l->live[i].t;
  return NULL;
}

int64_t elfm_link_oldest_frame(const elfm_linker *l)
{
  int64_t f = INT64_MAX;
  for (size_t i = 0; l && i < l->n_live; i++)
    if (l->live[i].t->n && l->live[i].t->pts[0].frame < f) f = l->live[i].t->pts[0].frame;
  for (size_t i = 0; l && i < l->fin_n; i++) {
    const elfm_track *t = l->fin[l->fin_head + i];
    if (t->n && t->pts[0].frame < f) f = t->pts[0].frame;
  }
  return f;
}
int64_t elfm_link_n_started(const elfm_linker *l) { return l ? l->next_id : 0; }
int64_t elfm_link_n_twins(const elfm_linker *l) { return l ? l->n_twins : 0; }
int64_t elfm_link_n_late_stitches(const elfm_linker *l) { return l ? l->n_late_stitches : 0; }

/* Detection j joined no track (or a new one): no velocity. */
static void det_vel_none(elfm_linker *l, size_t j)
{
  double *m = l->det_vel + LINK_DET_VEL * j;
  for (int k = 0; k < LINK_DET_VEL; k++) m[k] = NAN;
  m[6] = 0;
}

int64_t elfm_link_last_track_id(const elfm_linker *l, int i)
{
  if (!l || i < 0 || (size_t)i >= l->cap_det || !l->det_id) return -1;
  return l->det_id[i];
}

static int grow(void **p, size_t n, size_t size)
{
  void *q = realloc(*p, (n ? n : 1) * size);
  if (!q) return 0;
  *p = q;
  return 1;
}

/* Shared with link_repair.c (link_internal.h). */
elfm_status elfm_link_reserve_cost(elfm_linker *l, size_t need, elfm_error *err)
{
  if (need <= l->cap_cost) return ELFM_OK;
  size_t c = need + need / 2;
  if (!grow((void **)&l->cost, c, sizeof(double)))
    return elfm_error_set(err, ELFM_ERR_NOMEM, NULL, -1, "link: out of memory");
  l->cap_cost = c;
  return ELFM_OK;
}

/* Optimal assignment of the nr tracks l->rows to the nc detections l->cols
 * over l->cost (nr x nc, +inf forbidden): each pair found becomes
 * track_det / det_track. */
static elfm_status assign_rows(elfm_linker *l, int nr, int nc, elfm_error *err)
{
  elfm_status st = elfm_assign_hungarian(l->cost, nr, nc, l->row_to_col, NULL, l->aws, err);
  if (st != ELFM_OK) return st;
  for (int r = 0; r < nr; r++) {
    int c = l->row_to_col[r];
    if (c < 0 || !isfinite(l->cost[(size_t)r * nc + c])) continue;
    l->track_det[l->rows[r]] = l->cols[c];
    l->det_track[l->cols[c]] = l->rows[r];
  }
  return ELFM_OK;
}

/* Shared with link_repair.c (link_internal.h). */
elfm_status elfm_link_reserve(elfm_linker *l, size_t n_trk, size_t n_det, elfm_error *err)
{
  size_t mc = (size_t)l->o.max_candidates;
  if (n_det > l->cap_det) {
    size_t c = n_det + n_det / 2 + 16;
    if (!grow((void **)&l->pts, 3 * c, sizeof(float)) ||
        !grow((void **)&l->det_track, c, sizeof(int)) ||
        !grow((void **)&l->det_local, c, sizeof(int)) ||
        !grow((void **)&l->det_id, c, sizeof(int64_t)) ||
        !grow((void **)&l->det_vel, LINK_DET_VEL * c, sizeof(double)))
      return elfm_error_set(err, ELFM_ERR_NOMEM, NULL, -1, "link: out of memory");
    l->cap_det = c;
  }
  if (n_trk > l->cap_trk) {
    size_t c = n_trk + n_trk / 2 + 16;
    if (!grow((void **)&l->cand, c * mc, sizeof(link_cand)) ||
        !grow((void **)&l->n_cand, c, sizeof(int)) ||
        !grow((void **)&l->track_det, c, sizeof(int)) ||
        !grow((void **)&l->rows, c, sizeof(int)) ||
        !grow((void **)&l->xkeys, c, sizeof(link_xkey)) ||
        !grow((void **)&l->row_to_col, c, sizeof(int)))
      return elfm_error_set(err, ELFM_ERR_NOMEM, NULL, -1, "link: out of memory");
    l->cap_trk = c;
  }
  size_t nodes = l->cap_trk + l->cap_det;
  /* union-find and grouping cover tracks + detections */
  if (!grow((void **)&l->uf, nodes, sizeof(int)) || !grow((void **)&l->comp_of, nodes, sizeof(int)) ||
      !grow((void **)&l->comp_start, nodes + 1, sizeof(int)) ||
      !grow((void **)&l->comp_fill, nodes + 1, sizeof(int)) ||
      !grow((void **)&l->members, nodes, sizeof(int)) || !grow((void **)&l->cols, nodes, sizeof(int)))
    return elfm_error_set(err, ELFM_ERR_NOMEM, NULL, -1, "link: out of memory");
  return ELFM_OK;
}

static int uf_find(int *uf, int a)
{
  while (uf[a] != a) {
    uf[a] = uf[uf[a]];  /* path halving */
    a = uf[a];
  }
  return a;
}

static elfm_status end_track(elfm_linker *l, elfm_track *t, elfm_error *err)
{
  if (t->n < (size_t)l->o.min_points) {
    elfm_track_free(t);
    return ELFM_OK;
  }
  if (l->fin_head + l->fin_n == l->fin_cap) {
    if (l->fin_head > 0) {  /* slide the queue down before growing */
      memmove(l->fin, l->fin + l->fin_head, l->fin_n * sizeof *l->fin);
      l->fin_head = 0;
    }
    if (l->fin_n == l->fin_cap) {
      size_t c = l->fin_cap ? 2 * l->fin_cap : 64;
      if (!grow((void **)&l->fin, c, sizeof *l->fin)) {
        elfm_track_free(t);
        return elfm_error_set(err, ELFM_ERR_NOMEM, NULL, -1, "link: out of memory");
      }
      l->fin_cap = c;
    }
  }
  l->fin[l->fin_head + l->fin_n++] = t;
  return ELFM_OK;
}

elfm_track *elfm_link_pop_finished(elfm_linker *l)
{
  if (!l || !l->fin_n) return NULL;
  elfm_track *t = l->fin[l->fin_head++];
  if (--l->fin_n == 0) l->fin_head = 0;
  return t;
}

static elfm_status attach(elfm_linker *l, live_track *lt, elfm_detection *d, elfm_error *err)
{
  if (l->o.lag_tau_us > 0 && lt->t->n >= 2)
    elfm_detection_correct_lag_lead(d, elfm_link_current_velocity(lt)[0],
                                    elfm_link_current_velocity(lt)[1],
                                    elfm_link_current_velocity(lt)[2], l->o.lag_tau_us,
                                    l->o.lead_sigmas);
  if (lt->pred_circ_ok && d->t_us == lt->pred_t_us) elfm_link_score_predictions(&l->o, lt, d);
  elfm_status st = elfm_track_append(lt->t, d, err);
  if (st != ELFM_OK) return st;
  lt->last_frame = d->frame;
  lt->last_t_us = d->t_us;
  lt->last[0] = d->x_um;
  lt->last[1] = d->y_um;
  lt->last[2] = d->z_um;
  elfm_link_fit_velocity(lt, &l->o);
  if (l->o.lag_tau_us > 0 && lt->t->n == 2) {
    /* the first velocity: correct the two points it came from alike, so
     * later fits do not mix corrected and uncorrected points */
    for (int k = 0; k < 2; k++)
      elfm_detection_correct_lag_lead(&lt->t->pts[k], lt->vel_um_per_ms[0],
                                      lt->vel_um_per_ms[1], lt->vel_um_per_ms[2],
                                      l->o.lag_tau_us, l->o.lead_sigmas);
    d->x_um = lt->t->pts[1].x_um;
    d->y_um = lt->t->pts[1].y_um;
    d->z_um = lt->t->pts[1].z_um;
    lt->last[0] = d->x_um;
    lt->last[1] = d->y_um;
    lt->last[2] = d->z_um;
  }
  return ELFM_OK;
}

static elfm_status start_track(elfm_linker *l, elfm_detection *d, int64_t *id_out, elfm_error *err)
{
  if (l->n_live == l->cap_live) {
    size_t c = l->cap_live ? 2 * l->cap_live : 64;
    if (!grow((void **)&l->live, c, sizeof *l->live))
      return elfm_error_set(err, ELFM_ERR_NOMEM, NULL, -1, "link: out of memory");
    l->cap_live = c;
  }
  elfm_track *t = elfm_track_create(l->next_id, err);
  if (!t) return ELFM_ERR_NOMEM;
  live_track *lt = &l->live[l->n_live];
  memset(lt, 0, sizeof *lt);
  lt->t = t;
  elfm_status st = attach(l, lt, d, err);
  if (st != ELFM_OK) {
    elfm_track_free(t);
    return st;
  }
  l->n_live++;
  *id_out = l->next_id++;
  return ELFM_OK;
}

/* Is d in the trail of a detection just matched to a moving track? */
static int in_trail(const elfm_linker *l, size_t nt, const elfm_detection *det,
                    const elfm_detection *d)
{
  const double g = l->o.gate_um, kz = l->o.kz;
  for (size_t i = 0; i < nt; i++) {
    int k = l->track_det[i];
    const live_track *lt = &l->live[i];
    if (k < 0 || lt->t->n < 3) continue;  /* needs a velocity from >= 2 earlier points */
    const double *v = elfm_link_current_velocity(lt);
    double speed = sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
    if (!(speed > 0)) continue;
    double e[3] = {d->x_um - det[k].x_um, d->y_um - det[k].y_um, d->z_um - det[k].z_um};
    double behind = -(e[0] * v[0] + e[1] * v[1] + e[2] * v[2]) / speed;
    if (behind <= 0 || behind > speed * l->o.trail_us * 1e-3 + g) continue;
    double px = e[0] + behind * v[0] / speed, py = e[1] + behind * v[1] / speed,
           pz = (e[2] + behind * v[2] / speed) / kz;
    if (px * px + py * py + pz * pz < g * g) return 1;
  }
  return 0;
}

/* The linker's options become *t when link_options_check (the one that
 * elfm_link_create applies) takes them; else they stay as they were. */
static elfm_status link_set_options(elfm_linker *l, const elfm_link_options *t, elfm_error *err)
{
  elfm_status st = link_options_check(t, err);
  if (st == ELFM_OK) l->o = *t;
  return st;
}

elfm_status elfm_link_set_rescue_gate_factor(elfm_linker *l, double factor, elfm_error *err)
{
  if (!l) return elfm_error_set(err, ELFM_ERR_INVALID, NULL, -1, "link: NULL linker");
  elfm_link_options t = l->o;
  t.rescue_gate_factor = factor;
  return link_set_options(l, &t, err);
}

elfm_status elfm_link_set_gate_um(elfm_linker *l, double gate_um, elfm_error *err)
{
  if (!l) return elfm_error_set(err, ELFM_ERR_INVALID, NULL, -1, "link: NULL linker");
  elfm_link_options t = l->o;
  t.gate_um = gate_um;
  return link_set_options(l, &t, err);
}

elfm_status elfm_link_step(elfm_linker *l, int64_t frame, int64_t t_us, elfm_detection *det, int n,
                           elfm_error *err)
{
  if (!l || n < 0 || (n > 0 && !det))
    return elfm_error_set(err, ELFM_ERR_INVALID, NULL, -1, "link: bad arguments");
  if (l->started && (frame <= l->last_frame || t_us < l->last_t_us))
    return elfm_error_set(err, ELFM_ERR_INVALID, NULL, -1,
                          "link: frame %lld at t = %lld us after frame %lld at t = %lld us "
                          "(frames must increase, times must not decrease)",
                          (long long)frame, (long long)t_us, (long long)l->last_frame,
                          (long long)l->last_t_us);
  for (int j = 0; j < n; j++)
    if (!isfinite(det[j].x_um) || !isfinite(det[j].y_um) || !isfinite(det[j].z_um))
      return elfm_error_set(err, ELFM_ERR_NUMERIC, NULL, -1,
                            "link: detection %d of frame %lld has a non-finite position", j,
                            (long long)frame);
  l->started = 1;
  l->last_frame = frame;
  l->last_t_us = t_us;
  const elfm_link_options *o = &l->o;

  /* 1. End tracks dark for too long (stable compaction keeps the order
   * deterministic), unless a younger twin continues them (step 8);
   * predict the others. */
  if (o->twin_um > 0) {
    elfm_status st = elfm_link_join_twins(l, frame, err);
    if (st != ELFM_OK) return st;
  }
  if (o->stitch_points > 0 && o->stitch_late_points > 0) {
    elfm_status st = elfm_link_stitch_late(l, frame, err);
    if (st != ELFM_OK) return st;
  }
  size_t w = 0;
  const int at_rest = o->rest_speed_um_per_ms > 0 && elfm_link_objects_at_rest(l);
  {
    elfm_status sc = elfm_link_common_velocity(l, frame, err);
    if (sc != ELFM_OK) return sc;
  }
  const double *cv = l->has_common_vel ? l->common_vel : NULL;
  for (size_t i = 0; i < l->n_live; i++) {
    live_track lt = l->live[i];
    lt.missed = (int)(frame - lt.last_frame - 1);
    if (lt.missed > o->max_gap_frames) {
      elfm_status st = end_track(l, lt.t, err);
      if (st != ELFM_OK) return st;
      continue;
    }
    elfm_link_predict_track(o, &lt, t_us, at_rest, cv);
    elfm_link_predict_rest(o, &lt, t_us, at_rest);
    l->live[w++] = lt;
  }
  l->n_live = w;
  const size_t nt = l->n_live, nd = (size_t)n;
  elfm_status st = elfm_link_reserve(l, nt, nd, err);
  if (st != ELFM_OK) return st;
  for (size_t j = 0; j < nd; j++) {
    det[j].frame = frame;
    det[j].t_us = t_us;
    l->det_track[j] = -1;
  }
  for (size_t i = 0; i < nt; i++) {
    l->n_cand[i] = 0;
    l->track_det[i] = -1;
  }

  /* 2. Candidates from the k-d tree over this frame's detections (or all
   * pairs when brute_force is set): link_candidates.c. Each detection's
   * claims, for the user: where two tracks competed for one detection their
   * identities may have been exchanged. */
  if ((st = elfm_link_candidates(l, det, nt, nd, err)) != ELFM_OK) return st;
  for (size_t j = 0; j < nd; j++) det[j].claims = 0;
  for (size_t i = 0; i < nt; i++)
    for (int c = 0; c < l->n_cand[i]; c++) det[l->cand[i * (size_t)o->max_candidates + c].det].claims++;

  /* 3. Connected groups (union-find over tracks 0..nt-1, detections
   * nt..nt+nd-1), each solved optimally. */
  const size_t nodes = nt + nd;
  for (size_t a = 0; a < nodes; a++) l->uf[a] = (int)a;
  for (size_t i = 0; i < nt; i++)
    for (int c = 0; c < l->n_cand[i]; c++) {
      int ra = uf_find(l->uf, (int)i),
          rb = uf_find(l->uf, (int)(nt + (size_t)l->cand[i * (size_t)o->max_candidates + c].det));
      if (ra != rb) l->uf[ra] = rb;
    }
  /* counting sort of nodes by group */
  int ngroups = 0;
  for (size_t a = 0; a < nodes; a++) l->comp_of[a] = -1;
  for (size_t a = 0; a < nodes; a++) {
    int r = uf_find(l->uf, (int)a);
    if (l->comp_of[r] < 0) l->comp_of[r] = ngroups++;
  }
  for (int g = 0; g <= ngroups; g++) l->comp_start[g] = 0;
  for (size_t a = 0; a < nodes; a++) l->comp_start[l->comp_of[uf_find(l->uf, (int)a)] + 1]++;
  for (int g = 0; g < ngroups; g++) l->comp_start[g + 1] += l->comp_start[g];
  for (int g = 0; g < ngroups; g++) l->comp_fill[g] = l->comp_start[g];
  for (size_t a = 0; a < nodes; a++)
    l->members[l->comp_fill[l->comp_of[uf_find(l->uf, (int)a)]]++] = (int)a;

  for (int g = 0; g < ngroups; g++) {
    int nr = 0, nc = 0;
    for (int m = l->comp_start[g]; m < l->comp_start[g + 1]; m++) {
      int a = l->members[m];
      if ((size_t)a < nt) l->rows[nr++] = a;
      else {
        l->det_local[a - (int)nt] = nc;
        l->cols[nc++] = a - (int)nt;
      }
    }
    if (nr == 0 || nc == 0) continue;
    if (nr == 1 && nc == 1) {  /* the common case: one track, one detection */
      l->track_det[l->rows[0]] = l->cols[0];
      l->det_track[l->cols[0]] = l->rows[0];
      continue;
    }
    size_t need = (size_t)nr * (size_t)nc;
    st = elfm_link_reserve_cost(l, need, err);
    if (st != ELFM_OK) return st;
    /* With priority_points: pass 0 the established tracks, pass 1 the
     * rest among the detections pass 0 left (elfm_link_options says why).
     * Flow 100 ms, 20 seeds: mean alpha 0.7846 -> 0.7897 (3 / 5 / 12
     * points: 0.7861 / 0.7883 / 0.7881); held-out seeds 21-24 +0.009;
     * denser flow (40 and 60 beads, 9 runs) 0.605 -> 0.623; stage, blink,
     * blink_moving the same; worm seed 4 -0.006 (docs/tracker.md). */
    for (int pass = o->priority_points > 0 ? 0 : 1; pass < 2; pass++) {
      int any = 0;
      for (size_t k = 0; k < need; k++) l->cost[k] = INFINITY;
      for (int r = 0; r < nr; r++) {
        int i = l->rows[r];
        if (l->track_det[i] >= 0 || (pass == 0 && l->live[i].t->n < (size_t)o->priority_points))
          continue;
        for (int c = 0; c < l->n_cand[i]; c++) {
          const link_cand *lc = &l->cand[(size_t)i * (size_t)o->max_candidates + c];
          if (l->det_track[lc->det] >= 0) continue;  /* taken in pass 0 */
          l->cost[(size_t)r * nc + l->det_local[lc->det]] = lc->cost;
          any = 1;
        }
      }
      if (!any) continue;
      st = assign_rows(l, nr, nc, err);
      if (st != ELFM_OK) return st;
    }
  }

  /* 3b. Rescue: unmatched established tracks against unmatched
   * detections, within a wider gate, one optimal assignment. Also tracks
   * seen in the previous frame: on the flow scene a track whose prediction
   * missed by more than the gate right after a real point let a twin be
   * born on the same bead (flow 100 ms: 40 -> 29 tracks for 20 beads,
   * alpha 0.545 -> 0.562). The cost carries step 2's gap_cost per missed
   * frame: d2 / g2 alone favours the track dark the longest, whose gate is
   * widest, and on flow seed 1 a 5-point track dark for 44 frames took a
   * bead from the track that had lost it 3 frames before (8 flow seeds,
   * mean alpha 0.711 -> 0.719; stage, worm, blink unchanged). */
  if (o->rescue_gate_factor > 0) {
    int nr = 0, nc = 0;
    for (size_t i = 0; i < nt; i++)
      if (l->track_det[i] < 0 && l->live[i].t->n >= 3)
        l->rows[nr++] = (int)i;  /* established tracks only: a 2-point one has no reliable path */
    for (size_t j = 0; j < nd; j++)
      if (l->det_track[j] < 0) l->cols[nc++] = (int)j;
    size_t need = (size_t)nr * (size_t)nc;
    if (nr > 0 && nc > 0 && nr <= 500 && nc <= 500) {
      st = elfm_link_reserve_cost(l, need, err);
      if (st != ELFM_OK) return st;
      int any = 0;
      for (int r = 0; r < nr; r++) {
        const live_track *lt = &l->live[l->rows[r]];
        const double g = o->rescue_gate_factor * lt->gate_um;
        for (int c = 0; c < nc; c++) {
          double cost;
          int ok = link_gated_cost(o, lt->pred, g, lt->missed, &det[l->cols[c]], &cost);
          l->cost[(size_t)r * nc + c] = ok ? cost : INFINITY;
          any |= ok;
        }
      }
      if (any) {
        st = assign_rows(l, nr, nc, err);
        if (st != ELFM_OK) return st;
      }
    }
  }

  /* 4. Attach, then births (after: start_track may move the live array). */
  for (size_t i = 0; i < nt; i++) {
    int j = l->track_det[i];
    if (j < 0) continue;
    /* before attach: the prediction, and whether it came from a track of
     * LINK_MISS_MIN_POINTS points seen in the frame before */
    const int from_seen = l->live[i].missed <= 0 && l->live[i].has_short &&
                          l->live[i].t->n >= LINK_MISS_MIN_POINTS;
    double pred[3];
    memcpy(pred, l->live[i].pred, sizeof pred);
    st = attach(l, &l->live[i], &det[j], err);
    if (st != ELFM_OK) return st;
    if (l->live[i].missed > 0 && l->live[i].t->n >= 5) {
      l->live[i].tail0 = l->live[i].t->n - 1;
      l->live[i].review = 1;
    }
    l->det_id[j] = l->live[i].t->id;
    const double *v = elfm_link_current_velocity(&l->live[i]);
    double *m = l->det_vel + LINK_DET_VEL * (size_t)j;
    memcpy(m, v, 3 * sizeof *m);
    memcpy(m + 3, l->live[i].vel_um_per_ms, 3 * sizeof *m);
    const elfm_track *t = l->live[i].t;
    m[6] = (double)t->n;
    /* the long fit's points: the last `history` (elfm_link_fit_velocity) */
    const size_t k0 = t->n > (size_t)o->history ? t->n - (size_t)o->history : 0;
    m[7] = 1e-3 * (double)(t->pts[t->n - 1].t_us - t->pts[k0].t_us);
    /* the detection as attach left it (its lag taken out) */
    m[8] = from_seen ? elfm_link_miss_um(o, pred, &det[j]) : NAN;
  }
  if (o->swap_points > 0 && o->encounter_um > 0) {
    st = elfm_link_mark_encounters(l, frame, nt, err);
    if (st != ELFM_OK) return st;
  }
  const size_t nt_before_births = nt;
  for (size_t j = 0; j < nd; j++) {
    if (l->det_track[j] >= 0) continue;
    if (det[j].weak) {  /* hysteresis: a weak detection only continues a track */
      l->det_id[j] = -3;
      det_vel_none(l, j);
      continue;
    }
    if (o->trail_us > 0 && in_trail(l, nt_before_births, det, &det[j])) {
      l->det_id[j] = -2;
      det_vel_none(l, j);
      continue;
    }
    st = start_track(l, &det[j], &l->det_id[j], err);
    if (st != ELFM_OK) return st;
    det_vel_none(l, j);
    l->det_vel[LINK_DET_VEL * j + 6] = 1; /* a new track's first point */
  }
  for (size_t j = nd; j < l->cap_det; j++) {
    l->det_id[j] = -1;
    det_vel_none(l, j);
  }
  if (o->stitch_points > 0) {
    st = elfm_link_stitch(l, frame, nd, err);
    if (st != ELFM_OK) return st;
  }
  if (o->swap_points > 0) {
    st = elfm_link_review_swaps(l, nd, err);
    if (st != ELFM_OK || o->encounter_um <= 0) return st;
    return elfm_link_review_encounters(l, frame, nd, err);
  }
  return ELFM_OK;
}

elfm_status elfm_link_predict(const elfm_linker *l, int64_t frame, int64_t t_us, int min_points,
                              double *xyz_um, double *intensity, int cap, int *n_out,
                              elfm_error *err)
{
  if (!l || !n_out || cap < 0 || (cap > 0 && !xyz_um))
    return elfm_error_set(err, ELFM_ERR_INVALID, NULL, -1, "link: bad arguments to predict");
  int n = 0;
  const int at_rest = l->o.rest_speed_um_per_ms > 0 && elfm_link_objects_at_rest(l);
  for (size_t i = 0; i < l->n_live && n < cap; i++) {
    live_track lt = l->live[i];
    lt.missed = (int)(frame - lt.last_frame - 1);
    if (lt.missed < 0 || lt.missed > l->o.max_gap_frames || (int)lt.t->n < min_points) continue;
    elfm_link_predict_track(&l->o, &lt, t_us, at_rest, l->has_common_vel ? l->common_vel : NULL);
    memcpy(xyz_um + 3 * (size_t)n, lt.pred, sizeof lt.pred);
    if (intensity) intensity[n] = elfm_link_mean_intensity(lt.t, lt.t->n > 3 ? lt.t->n - 3 : 0, lt.t->n);
    n++;
  }
  *n_out = n;
  return ELFM_OK;
}

elfm_status elfm_link_finish(elfm_linker *l, elfm_error *err)
{
  if (!l) return elfm_error_set(err, ELFM_ERR_INVALID, NULL, -1, "link: NULL linker");
  for (size_t i = 0; i < l->n_live; i++) {
    elfm_status st = end_track(l, l->live[i].t, err);
    if (st != ELFM_OK) {
      /* end_track freed this one; free the rest so nothing leaks */
      for (size_t k = i + 1; k < l->n_live; k++) elfm_track_free(l->live[k].t);
      l->n_live = 0;
      return st;
    }
  }
  l->n_live = 0;
  return ELFM_OK;
}
