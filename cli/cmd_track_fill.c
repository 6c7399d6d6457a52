/* cmd_track_fill.c — eventlfm track's gap filling: the last frames are
 * kept (sparse copies) so that, when the linker settles a gap of a track
 * (elfm_link_settled_gaps: its object found again and followed for a few
 * frames), the view fit can look for the object in each frame of the gap,
 * starting where the two ends of the gap put it (elfm_link_gap_predict).
 *
 * Why: on flow, most of the detections missed inside a track's span are
 * deep beads (|z| 40-80 um) whose few events left no peak, and the
 * forward guided fit, started from where the track's past extrapolates,
 * misses them too; from the true position the view fit finds 0.99 of them
 * at 40-60 um and 0.78 at 60-80 um with 4 views agreeing (bench_localize).
 * Memory: fill_max_gap + settle + 2 frames of sparse pixels (a frame's
 * nonzero pixels only), not the recording. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "cmd_track.h"

static int settle_points(const track_opts *o)
{
  return o->link.swap_points > 0 ? o->link.swap_points : 4;
}

elfm_status track_fill_setup(track_ctx *c, elfm_error *err)
{
  const track_opts *o = c->o;
  if (o->fill_views <= 0) return ELFM_OK;
  frame_ring *r = &c->ring;
  r->cap = o->fill_max_gap + settle_points(o) + 2;
  r->slot = calloc((size_t)r->cap, sizeof *r->slot);
  c->gaps_cap = 1024;
  c->gaps = malloc((size_t)c->gaps_cap * sizeof *c->gaps);
  c->fill_pts = malloc((size_t)r->cap * sizeof *c->fill_pts);
  if (!r->slot || !c->gaps || !c->fill_pts)
    return elfm_error_set(err, ELFM_ERR_NOMEM, NULL, -1, "out of memory (gap filling)");
  for (int k = 0; k < r->cap; k++) r->slot[k].frame = r->slot[k].det_frame = -1;
  /* our own plan (the same calibration and options as the driver's): the
   * last gaps are filled after the driver has freed its own */
  return elfm_refocus_plan_create(c->calib, &o->recon.refocus, &c->fill_plan, err);
}

elfm_status track_fill_keep(track_ctx *c, const elfm_frame *f, int64_t frame, elfm_error *err)
{
  frame_ring *r = &c->ring;
  if (!r->cap || !f) return ELFM_OK;
  if (!c->scratch) {
    c->scratch = elfm_frame_create(f->w, f->h, err);
    if (!c->scratch) return err ? err->code : ELFM_ERR_NOMEM;
  }
  ring_slot *sl = &r->slot[frame % r->cap];
  if (f->nnz > sl->nnz_cap) {
    uint32_t *a = realloc(sl->idx, f->nnz * sizeof *a);
    if (a) sl->idx = a;
    float *b = realloc(sl->val, f->nnz * sizeof *b);
    if (b) sl->val = b;
    if (!a || !b) return elfm_error_set(err, ELFM_ERR_NOMEM, NULL, -1, "out of memory (kept frames)");
    sl->nnz_cap = f->nnz;
  }
  for (size_t i = 0; i < f->nnz; i++) {
    sl->idx[i] = f->idx[i];
    sl->val[i] = f->data[f->idx[i]];
  }
  sl->nnz = f->nnz;
  sl->frame = frame;
  sl->t_us = f->t_us;
  return ELFM_OK;
}

/* The view fit in kept frame sl, started at q (um); 1 and *d filled when
 * at least fill_views views agree within fill_gate_um of q and it has at
 * least min_intensity. */
static int fill_one(track_ctx *c, const ring_slot *sl, const double q[3], double min_intensity,
                    elfm_detection *d)
{
  const track_opts *o = c->o;
  const elfm_volume *geo = &c->geo;
  elfm_frame *s = c->scratch;
  elfm_localize_options lo = o->loc;
  lo.min_views = o->fill_views;
  for (size_t i = 0; i < sl->nnz; i++) s->data[sl->idx[i]] = sl->val[i];
  elfm_localize_result res;
  int ok = elfm_refocus_localize(c->fill_plan, s, elfm_volume_x_vox(geo, q[0]),
                                 elfm_volume_y_vox(geo, q[1]), elfm_volume_z_vox(geo, q[2]), &lo, &res);
  if (ok) {
    const int X = (int)lround(res.x_vox), Y = (int)lround(res.y_vox), K = (int)lround(res.z_vox);
    memset(d, 0, sizeof *d);
    d->frame = sl->frame;
    d->t_us = sl->t_us;
    d->view_fit = 1;
    d->x_um = elfm_volume_x_um(geo, res.x_vox);
    d->y_um = elfm_volume_y_um(geo, res.y_vox);
    d->z_um = elfm_volume_z_um(geo, res.z_vox);
    const double dx = d->x_um - q[0], dy = d->y_um - q[1], dz = (d->z_um - q[2]) / o->link.kz;
    ok = X >= 0 && Y >= 0 && K >= 0 && X < geo->w && Y < geo->h && K < geo->nz &&
         dx * dx + dy * dy + dz * dz < o->fill_gate_um * o->fill_gate_um;
    if (ok) d->intensity = elfm_refocus_value_at(c->fill_plan, s, X, Y, K);
    ok = ok && d->intensity >= min_intensity;
  }
  for (size_t i = 0; i < sl->nnz; i++) s->data[sl->idx[i]] = 0;
  return ok;
}

/* Look for the gap's object in each kept frame of the gap, into
 * c->fill_pts (returns the count). A closed gap is walked from both ends
 * inwards: each side starts where the two ends' fits put the object, moved
 * by how far that side's last find was from them (the fits drift apart
 * from the bead over a long gap; the bead does not jump). An open one (the
 * frames before a track's birth) only backwards, and only while the
 * object keeps being found: two misses in a row end it. Following a
 * finished track on past its end the same way lost alpha (flow, 20 seeds:
 * 0.7661 -> 0.7636): a bead that leaves the volume or fades is better
 * left ended. */
static int walk_gap(track_ctx *c, const elfm_link_gap *g)
{
  const frame_ring *r = &c->ring;
  double off[2][3] = {{0, 0, 0}, {0, 0, 0}}; /* forward side, backward side */
  int m = 0, misses = 0;
  int64_t lo = g->frame0 + 1, hi = g->frame1 - 1;
  const int open = g->open_start;
  const double min_i = c->o->fill_min_ratio * g->intensity;
  for (int side = open; lo <= hi; side = open ? 1 : side ^ 1) {
    const int64_t f = side ? hi-- : lo++;
    const ring_slot *sl = f >= 0 ? &r->slot[f % r->cap] : NULL;
    if (!sl || sl->frame != f) {  /* before the first frame, or no longer kept */
      if (open) break;
      continue;
    }
    c->n_fill_tries++;
    double p[3], q[3];
    elfm_link_gap_predict(g, sl->t_us, p);
    for (int a = 0; a < 3; a++) q[a] = p[a] + off[side][a];
    elfm_detection d;
    if (!fill_one(c, sl, q, min_i, &d)) {
      if (open && ++misses >= 2) break;
      continue;
    }
    misses = 0;
    off[side][0] = d.x_um - p[0];
    off[side][1] = d.y_um - p[1];
    off[side][2] = d.z_um - p[2];
    c->fill_pts[m++] = d;
  }
  return m;
}

/* Points found count as detections of their frames. */
static elfm_status emit_fills(track_ctx *c, int m, elfm_error *err)
{
  elfm_status st = ELFM_OK;
  c->n_filled += m;
  c->n_det += m;
  for (int j = 0; j < m && st == ELFM_OK; j++)
    st = track_det_emit(c, c->fill_pts[j].frame, &c->fill_pts[j], err);
  return st;
}

/* Fill a gap the linker settled; give the linker what is found. */
static elfm_status fill_gap(track_ctx *c, const elfm_link_gap *g, elfm_error *err)
{
  const int m = walk_gap(c, g);
  if (!m) return ELFM_OK;
  elfm_status st = elfm_link_fill(c->lk, g->track_id, c->fill_pts, m, err); /* any order */
  return st == ELFM_OK ? emit_fills(c, m, err) : st;
}

elfm_status track_fill_gaps(track_ctx *c, int all, elfm_error *err)
{
  if (!c->ring.cap || !c->scratch) return ELFM_OK;
  int ng = 0;
  elfm_status st = elfm_link_settled_gaps(c->lk, settle_points(c->o), all, c->gaps, c->gaps_cap, &ng, err);
  for (int i = 0; st == ELFM_OK && i < ng; i++) st = fill_gap(c, &c->gaps[i], err);
  return st;
}

/* Write a slot's detections and empty it. */
static elfm_status det_write_slot(track_ctx *c, ring_slot *sl, elfm_error *err)
{
  elfm_status st = ELFM_OK;
  if (sl->det_n > 0) st = elfm_detections_write(c->fdet, c->p_det, sl->det, sl->det_n, err);
  sl->det_n = 0;
  sl->det_frame = -1;
  return st;
}

elfm_status track_det_emit(track_ctx *c, int64_t frame, const elfm_detection *d, elfm_error *err)
{
  frame_ring *r = &c->ring;
  if (!r->cap) return elfm_detections_write(c->fdet, c->p_det, d, 1, err);
  ring_slot *sl = &r->slot[frame % r->cap];
  if (sl->det_frame != frame) {
    if (sl->det_frame >= 0)  /* track_det_flush_before did not run: a bug */
      return elfm_error_set(err, ELFM_ERR_INVALID, NULL, -1,
                            "detections of frame %lld: frame %lld not yet written",
                            (long long)frame, (long long)sl->det_frame);
    sl->det_frame = frame;
  }
  if (sl->det_n == sl->det_cap) {
    int cap = sl->det_cap ? 2 * sl->det_cap : 64;
    elfm_detection *p = realloc(sl->det, (size_t)cap * sizeof *p);
    if (!p) return elfm_error_set(err, ELFM_ERR_NOMEM, NULL, -1, "out of memory (detections)");
    sl->det = p;
    sl->det_cap = cap;
  }
  sl->det[sl->det_n++] = *d;
  return ELFM_OK;
}

elfm_status track_det_flush_before(track_ctx *c, int64_t frame, elfm_error *err)
{
  frame_ring *r = &c->ring;
  for (;;) {  /* oldest first; at most cap slots */
    ring_slot *old = NULL;
    for (int j = 0; j < r->cap; j++) {
      ring_slot *sl = &r->slot[j];
      if (sl->det_frame >= 0 && sl->det_frame < frame && (!old || sl->det_frame < old->det_frame))
        old = sl;
    }
    if (!old) return ELFM_OK;
    elfm_status st = det_write_slot(c, old, err);
    if (st != ELFM_OK) return st;
  }
}

void track_fill_free(track_ctx *c)
{
  frame_ring *r = &c->ring;
  for (int k = 0; r->slot && k < r->cap; k++) {
    free(r->slot[k].idx);
    free(r->slot[k].val);
    free(r->slot[k].det);
  }
  free(r->slot);
  memset(r, 0, sizeof *r);
  free(c->gaps);
  free(c->fill_pts);
  elfm_frame_free(c->scratch);
  elfm_refocus_plan_free(c->fill_plan);
}
