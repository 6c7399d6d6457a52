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
 * Where one frame's fit finds nothing, fill_frames kept frames centred on
 * it are fitted together (fill_multi). Memory: fill_max_gap + settle + 2
 * frames of sparse pixels (a frame's nonzero pixels only) and fill_frames
 * whole frames to fit in, not the recording. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "cmd_track.h"

static int settle_points(const track_opts *o)
{
  return o->link.swap_points > 0 ? o->link.swap_points : 4;
}

/* How far in z moves the outer views' images as far as r_um does
 * laterally: r_um / um_per_px over the largest disparity per axis (px per
 * um of z). 0 where no view has a disparity. */
static double retry_z_um(const elfm_calib *cal, double r_um)
{
  double g = 0;
  for (int v = 0; v < cal->n_views; v++)
    g = fmax(g, fmax(fabs(cal->views[v].dx_px_per_um), fabs(cal->views[v].dy_px_per_um)));
  return g > 0 ? r_um / cal->um_per_px / g : 0;
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
  c->fill_retried = malloc((size_t)r->cap);
  c->fill_keep = malloc((size_t)r->cap);
  if (!r->slot || !c->gaps || !c->fill_pts || !c->fill_retried || !c->fill_keep)
    return elfm_error_set(err, ELFM_ERR_NOMEM, NULL, -1, "out of memory (gap filling)");
  for (int k = 0; k < r->cap; k++) r->slot[k].frame = r->slot[k].det_frame = -1;
  c->fill_retry_z_um = retry_z_um(c->calib, o->fill_retry_um);
  return ELFM_OK; /* the plan is track_peaks_setup's, freed with the context */
}

elfm_status track_fill_keep(track_ctx *c, const elfm_frame *f, int64_t frame, elfm_error *err)
{
  frame_ring *r = &c->ring;
  if (!r->cap || !f) return ELFM_OK;
  if (!c->scratch) {
    c->scratch = elfm_frame_create(f->w, f->h, err);
    if (!c->scratch) return err ? err->code : ELFM_ERR_NOMEM;
    for (int j = 0; j < c->o->fill_frames - 1; j++)
      if (!(c->scratch_nbr[j] = elfm_frame_create(f->w, f->h, err))) return err ? err->code : ELFM_ERR_NOMEM;
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
  sl->recent_floor = f->recent_floor;
  return ELFM_OK;
}

/* Kept frame sl made whole in f (its nonzero pixels), and emptied again. */
static void slot_load(elfm_frame *f, const ring_slot *sl)
{
  for (size_t i = 0; i < sl->nnz; i++) f->data[sl->idx[i]] = sl->val[i];
  f->recent_floor = sl->recent_floor;
}

static void slot_clear(elfm_frame *f, const ring_slot *sl)
{
  for (size_t i = 0; i < sl->nnz; i++) f->data[sl->idx[i]] = 0;
}

/* The neighbourhood test of a multi-frame fit at r: the same fit started
 * at four places 4 x half_window px beside it (beyond where a start can
 * walk, 2 x half_window, plus a deep image's width). Three frames of
 * windows gather three frames of clutter as well: where other objects'
 * images crowd the views (a dense sample, or a bead's own ghosts) the fit
 * "agrees" almost anywhere, and so it does beside the bead too. A real
 * dim bead is found where it is and rarely at its neighbours. 1 = passes
 * (fewer than two neighbours succeed). Measured on the fits the test
 * judged (flow seeds 1, 2, 5, 6, 8: within the scoring gate of a bead /
 * not, by how many of the four neighbours succeeded, 0 / 1 / 2 / 3 / 4):
 * flow 50 / 26 / 16 / 5 / 2 against 8 / 17 / 21 / 14 / 10; 40 and 60
 * beads (three scenes) 12 / 23 / 34 / 23 / 25 against 26 / 83 / 158 / 264
 * / 353. */
static int multi_fit_isolated(const track_ctx *c, const elfm_frame *const *use,
                              const double (*off)[3], int n, const elfm_localize_options *lo,
                              const elfm_localize_result *r)
{
  const double d_px = 4.0 * lo->half_window_px;
  int hits = 0;
  for (int k = 0; k < 4; k++) {
    const double ox = k == 0 ? d_px : k == 1 ? -d_px : 0, oy = k == 2 ? d_px : k == 3 ? -d_px : 0;
    elfm_localize_result rc;
    hits += elfm_refocus_localize_frames(c->plan, use, off, n, r->x_vox + ox, r->y_vox + oy,
                                         r->z_vox, lo, &rc);
  }
  return hits < 2;
}

/* The kept frames one gap frame's fits read: sl made whole in c->scratch
 * and, once a multi-frame fit is wanted, its neighbours in
 * c->scratch_nbr with where the gap's ends put the object in each
 * (offsets from sl's). Loaded once for all of the frame's starts
 * (fill_one). */
typedef struct {
  const ring_slot *sl;
  const elfm_link_gap *g;
  int multi_ready;                                  /* neighbours loaded */
  int n;                                            /* frames in use[] */
  const elfm_frame *use[TRACK_FILL_MAX_FRAMES];     /* [0] = c->scratch */
  double off[TRACK_FILL_MAX_FRAMES][3];
  const ring_slot *loaded[TRACK_FILL_MAX_FRAMES - 1];
} fill_view;

static void fill_view_load(track_ctx *c, const ring_slot *sl, const elfm_link_gap *g, fill_view *fv)
{
  memset(fv, 0, sizeof *fv);
  fv->sl = sl;
  fv->g = g;
  fv->use[0] = c->scratch;
  fv->n = 1;
  slot_load(c->scratch, sl);
}

static void fill_view_multi(track_ctx *c, fill_view *fv)
{
  if (fv->multi_ready) return;
  fv->multi_ready = 1;
  const frame_ring *r = &c->ring;
  const elfm_volume *geo = &c->geo;
  const int h = c->o->fill_frames / 2;
  double p0[3];
  elfm_link_gap_predict(fv->g, fv->sl->t_us, p0);
  for (int j = 0; j < 2 * h; j++) {
    const int64_t f = fv->sl->frame + (j % 2 ? 1 : -1) * (j / 2 + 1);
    const ring_slot *nb = f >= 0 ? &r->slot[f % r->cap] : NULL;
    if (!nb || nb->frame != f) continue; /* before the recording, or no longer kept */
    slot_load(c->scratch_nbr[j], nb);
    fv->loaded[j] = nb;
    double p[3];
    elfm_link_gap_predict(fv->g, nb->t_us, p);
    fv->off[fv->n][0] = (p[0] - p0[0]) / geo->um_per_px;
    fv->off[fv->n][1] = (p[1] - p0[1]) / geo->um_per_px;
    fv->off[fv->n][2] = p[2] - p0[2];
    fv->use[fv->n++] = c->scratch_nbr[j];
  }
}

static void fill_view_clear(track_ctx *c, fill_view *fv)
{
  for (int j = 0; j < TRACK_FILL_MAX_FRAMES - 1; j++)
    if (fv->loaded[j]) slot_clear(c->scratch_nbr[j], fv->loaded[j]);
  slot_clear(c->scratch, fv->sl);
}

/* The view fit over fill_frames kept frames centred on the gap frame
 * (fill_view_multi), each window placed where the gap's two ends put the
 * object in that frame (elfm_link_gap_predict) and moved back by that
 * shift (elfm_refocus_localize_frames), started at q. A deep bead leaves
 * a few events per frame, too few in one frame for the views to agree,
 * and three frames hold three times as many: from the true position
 * (bench_localize SCENE 8 1000 3 centred, flow seed 1) it finds 0.80 of
 * the beads at 60-80 um against 0.54 in one frame. The forward guided
 * fit could not use this (its frames are all behind the bead, which has
 * moved on: flow alpha fell, docs/tracker.md "Deep beads"); a settled gap
 * has both ends. */
static int fill_multi(track_ctx *c, fill_view *fv, const double q[3], elfm_localize_options lo,
                      elfm_localize_result *res)
{
  const elfm_volume *geo = &c->geo;
  fill_view_multi(c, fv);
  /* Two more views must agree than in one frame: the windows hold the
   * clutter of all the frames too. Flow 100 ms seeds 1-20, fill_views 4
   * and + 0 / 2 / 4 views: alpha 0.8014 / 0.8014 / 0.8011, F1 0.9529 /
   * 0.9541 / 0.9544 (without the neighbourhood test). */
  lo.min_views += 2;
  int ok = fv->n > 1 &&
           elfm_refocus_localize_frames(c->plan, fv->use, (const double (*)[3])fv->off, fv->n,
                                        elfm_volume_x_vox(geo, q[0]), elfm_volume_y_vox(geo, q[1]),
                                        elfm_volume_z_vox(geo, q[2]), &lo, res);
  if (ok && !multi_fit_isolated(c, fv->use, (const double (*)[3])fv->off, fv->n, &lo, res)) {
    c->n_multi_refused++;
    ok = 0;
  }
  return ok;
}

/* The view fit in the gap frame (fv, loaded), started at s0 (um), and
 * where it fails and `many` is set, the multi-frame fit (fill_frames >
 * 1); 1 and *d filled when at least fill_views views agree within
 * fill_gate_um of q (where the gap's ends put the object) and it has at
 * least min_intensity (in the gap frame itself). */
static int fill_at(track_ctx *c, fill_view *fv, const double q[3], const double s0[3],
                   double min_intensity, int many, elfm_detection *d)
{
  const track_opts *o = c->o;
  const elfm_volume *geo = &c->geo;
  const ring_slot *sl = fv->sl;
  const elfm_frame *s = c->scratch;
  elfm_localize_options lo = track_guided_loc(o);
  lo.min_views = o->fill_views;
  elfm_localize_result res;
  int multi = 0;
  /* the frame's detections near q have their light taken out of the fit's
   * windows (localize_near_um, as the peaks' fits in cmd_track_volume.c):
   * a worm neuron in a gap most often lies beside its partner, whose light
   * pulls the fit. Worm, mean alpha_detections over 200 ms seeds 1-4 / 5-7 / 8-12,
   * 150 and 500 ms: 0.900 / 0.888 / 0.898 / 0.882 / 0.887 -> 0.902 /
   * 0.900 / 0.903 / 0.887 / 0.895, alpha 0.899 / 0.874 / 0.908 / 0.879 /
   * 0.844 -> 0.900 / 0.878 / 0.911 / 0.881 / 0.845. */
  double nb[TRACK_NEAR_MAX][3];
  int k_nb = 0;
  const double rn = o->localize_near_um;
  if (rn > 0 && sl->det_frame == sl->frame)
    k_nb = track_near_add(sl->det, sl->det_n, -1, s0[0], s0[1], rn, geo, nb, 0);
  int ok = elfm_refocus_localize_near(c->plan, s, elfm_volume_x_vox(geo, s0[0]),
                                      elfm_volume_y_vox(geo, s0[1]), elfm_volume_z_vox(geo, s0[2]),
                                      (const double(*)[3])nb, k_nb, &lo, &res);
  if (!ok && o->fill_frames > 1 && many) ok = multi = fill_multi(c, fv, s0, lo, &res);
  if (ok) {
    const int X = (int)lround(res.x_vox), Y = (int)lround(res.y_vox), K = (int)lround(res.z_vox);
    memset(d, 0, sizeof *d);
    d->frame = sl->frame;
    d->t_us = sl->t_us;
    d->view_fit = 1;
    d->x_um = elfm_volume_x_um(geo, res.x_vox);
    d->y_um = elfm_volume_y_um(geo, res.y_vox);
    d->z_um = elfm_volume_z_um(geo, res.z_vox);
    d->fit_sd_px = res.sd_px;
    const double dx = d->x_um - q[0], dy = d->y_um - q[1], dz = (d->z_um - q[2]) / o->link.kz;
    ok = X >= 0 && Y >= 0 && K >= 0 && X < geo->w && Y < geo->h && K < geo->nz &&
         dx * dx + dy * dy + dz * dz < o->fill_gate_um * o->fill_gate_um;
    if (ok) d->intensity = elfm_refocus_value_at(c->plan, s, X, Y, K);
    ok = ok && d->intensity >= min_intensity;
    if (ok && multi) c->n_filled_multi++;
  }
  return ok;
}

/* fill_at from q (with the multi-frame fit), and where it finds nothing,
 * the one-frame fit from fill_retry_um beside q in +-x and +-y, then
 * above and below it in z (retry_z_um), in that order; the first find is
 * kept, judged by the gate from q. Returns 0, 1 (found from q) or 2 (from
 * a start beside it: walk_gap keeps it only where a point of the next or
 * the last frame confirms it). Why: the view fit's 5 x 5 px windows
 * reach about 2 um, and a deep bead's prediction in a gap is often
 * further off (flow seeds 1-8: the starts of the fits that found nothing
 * lay 2.5 / 3.9 / 5.5 um from the bead, quartiles, SPEC's distance),
 * where three frames from its true place find 0.96 of the beads at |z|
 * 60-70 um and the tracks held 0.77. The first find, not the nearest of
 * all six (flow seeds 1-20 alpha 0.8797 against 0.8815, both with the
 * multi-frame fit from every start). One frame only from the starts
 * beside q: the multi-frame fits there cost 4 % of `track`'s wall time
 * (flow 1 s, 2 threads) for +0.0002 / +0.0008 alpha on flow seeds 1-20 /
 * 21-32 and -0.0016 on 1 s seeds 1-12 (with the confirmation below).
 * docs/tracker.md "Fits started beside the prediction". */
static int fill_one(track_ctx *c, const ring_slot *sl, const elfm_link_gap *g, const double q[3],
                    double min_intensity, elfm_detection *d)
{
  fill_view fv;
  fill_view_load(c, sl, g, &fv);
  int found = fill_at(c, &fv, q, q, min_intensity, 1, d);
  const double r = c->o->fill_retry_um;
  if (!found && r > 0) {
    const double rz = c->fill_retry_z_um;
    const double step[6][3] = {{r, 0, 0}, {-r, 0, 0}, {0, r, 0}, {0, -r, 0}, {0, 0, rz}, {0, 0, -rz}};
    for (int k = 0; k < (rz > 0 ? 6 : 4) && !found; k++) {
      const double s0[3] = {q[0] + step[k][0], q[1] + step[k][1], q[2] + step[k][2]};
      if (fill_at(c, &fv, q, s0, min_intensity, 0, d)) found = 2;
    }
  }
  fill_view_clear(c, &fv);
  return found;
}

/* Within FILL_CONFIRM_UM (linker metric, z / link.kz) of a retry's find
 * lies a point of its gap walk in the next or the last frame (another
 * find, or the gap's end; elfm_link_fill_confirmed), or the find is
 * dropped. Why: the finds from a start beside the prediction were on a
 * bead in 0.58-0.68 of cases (flow 100 ms seeds 1-8 and 1 s seeds 9 and
 * 11; 0.92 for the fits from the prediction itself), and 0.84 where such
 * a point lay within 4 um (0.19 where the track had no point in either
 * frame). Kept without the test (and with the multi-frame fit from each
 * start), they put more truth points in tracks of other beads on every
 * one of 12 1 s flow recordings, and alpha fell there 0.7732 -> 0.7684.
 * 4 um: 1 s / flow 1-20 / 21-32 alpha 0.7745 /
 * 0.8814 / 0.8638; 3 um 0.7719 / 0.8807 / 0.8617 (with the multi-frame
 * fit beside q); 5 um 0.7669 / 0.8804 / 0.8646; the points' offsets from
 * the gap's path compared instead (motion taken out), 3 um: 0.7704 /
 * 0.8808 / 0.8630. */
#define FILL_CONFIRM_UM 4.0

/* Look for the gap's object in each kept frame of the gap, into
 * c->fill_pts (returns the count). A closed gap is walked from both ends
 * inwards: each side starts where the two ends' fits put the object, moved
 * by how far that side's last find was from them (the fits drift apart
 * from the bead over a long gap; the bead does not jump). An open one (the
 * frames before a track's birth) only backwards, the one after a finished
 * track's end (open_end) only forwards, and only while the object keeps
 * being found: two misses in a row end it. */
static int walk_gap(track_ctx *c, const elfm_link_gap *g)
{
  const frame_ring *r = &c->ring;
  double off[2][3] = {{0, 0, 0}, {0, 0, 0}}; /* forward side, backward side */
  int m = 0, misses = 0;
  int64_t lo = g->frame0 + 1, hi = g->frame1 - 1;
  const int open = g->open_start || g->open_end;
  const int only = g->open_start ? 1 : 0; /* an open gap's one side; a closed one alternates */
  const double min_i = c->o->fill_min_ratio * g->intensity;
  for (int side = only; lo <= hi; side = open ? only : side ^ 1) {
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
    const int found = fill_one(c, sl, g, q, min_i, &d);
    if (!found) {
      if (open && ++misses >= 2) break;
      continue;
    }
    misses = 0;
    off[side][0] = d.x_um - p[0];
    off[side][1] = d.y_um - p[1];
    off[side][2] = d.z_um - p[2];
    c->fill_retried[m] = found == 2;
    c->fill_pts[m++] = d;
  }
  /* the retries' finds that no neighbouring point confirms are dropped */
  int n = 0;
  for (int j = 0; j < m; j++) {
    const int keep = !c->fill_retried[j] ||
                     elfm_link_fill_confirmed(g, c->fill_pts, m, j, c->o->link.kz, FILL_CONFIRM_UM);
    c->fill_keep[j] = (uint8_t)keep;
  }
  for (int j = 0; j < m; j++) {
    if (!c->fill_keep[j]) continue;
    c->n_filled_retry += c->fill_retried[j];
    c->fill_pts[n++] = c->fill_pts[j];
  }
  c->n_retry_dropped += m - n;
  return n;
}

/* The velocity of gap g's object at t_us (um/ms): between the two ends'
 * fits in proportion to time; an open gap's one end's. */
static void gap_velocity(const elfm_link_gap *g, int64_t t_us, double v[3])
{
  const double span = (double)(g->t1_us - g->t0_us);
  const double w = g->open_start ? 1.0 : g->open_end || !(span > 0) ? 0.0
                                                                     : (double)(t_us - g->t0_us) / span;
  for (int a = 0; a < 3; a++) v[a] = (1 - w) * g->v0_um_per_ms[a] + w * g->v1_um_per_ms[a];
}

/* Points found count as detections of their frames. */
static elfm_status emit_fills(track_ctx *c, const elfm_link_gap *g, int m, elfm_error *err)
{
  elfm_status st = ELFM_OK;
  c->n_filled += m;
  c->n_det += m;
  for (int j = 0; j < m && st == ELFM_OK; j++) {
    double v[3];
    gap_velocity(g, c->fill_pts[j].t_us, v);
    st = track_det_emit(c, c->fill_pts[j].frame, &c->fill_pts[j], g->track_id, v, err);
  }
  return st;
}

/* Fill a gap the linker settled; give the linker what is found. */
static elfm_status fill_gap(track_ctx *c, const elfm_link_gap *g, elfm_error *err)
{
  const int m = walk_gap(c, g);
  if (!m) return ELFM_OK;
  elfm_status st = elfm_link_fill(c->lk, g->track_id, c->fill_pts, m, err); /* any order */
  return st == ELFM_OK ? emit_fills(c, g, m, err) : st;
}

/* Follow finished track t on past its last point through the kept frames
 * (walk_gap of its open end, elfm_link_track_end), before it is smoothed:
 * its points go into t and detections.csv. Why: a deep bead's track ends
 * when it has gone unseen for max_gap frames, but the bead is still in
 * the volume; flow seeds 1, 7, 11, 20 had 66 / 127 / 80 / 37 truth points
 * no detection was near after their track's end, against 19 / 0 / 1 / 0
 * before its birth. With one frame per fit this lost (flow seeds 1-20,
 * the seventh session: alpha 0.7661 -> 0.7636 without the intensity
 * floor, 0.7654 -> 0.7659 with it); with the multi-frame fit (fill_frames)
 * it gains: 0.8000 -> 0.8021, every seed up or the same, F1 0.9536 ->
 * 0.9544. Most of its finds are in the first frames after the end. */
elfm_status track_fill_end(track_ctx *c, elfm_track *t, elfm_error *err)
{
  /* Only tracks of 20 points or more: in a dense sample the tracks of
   * ghosts (other beads' images lining up) end too, and their ends "found"
   * more of the same. 40 and 60 beads (9 scenes), F1 without following /
   * following every track / from 20 / from 40 points: 0.8667 / 0.8643 /
   * 0.8653 / 0.8664; flow seeds 1-20 alpha 0.8000 / 0.8022 / 0.8021 /
   * 0.8017. */
  if (!c->o->fill_ends || !c->ring.cap || !c->scratch || !t || t->n < 20) return ELFM_OK;
  elfm_link_gap g;
  elfm_link_track_end(t, &c->o->link, c->o->fill_max_gap, &g);
  const int m = walk_gap(c, &g);
  elfm_status st = ELFM_OK;
  for (int j = 0; j < m && st == ELFM_OK; j++) st = elfm_track_insert(t, &c->fill_pts[j], err);
  c->n_filled_end += m;
  return st == ELFM_OK ? emit_fills(c, &g, m, err) : st;
}

elfm_status track_fill_gaps(track_ctx *c, int all, elfm_error *err)
{
  if (!c->ring.cap || !c->scratch) return ELFM_OK;
  int ng = 0;
  elfm_status st = elfm_link_settled_gaps(c->lk, settle_points(c->o), all, c->gaps, c->gaps_cap, &ng, err);
  for (int i = 0; st == ELFM_OK && i < ng; i++) st = fill_gap(c, &c->gaps[i], err);
  return st;
}

/* The motion bias (elfm_motion_bias) of n detections on tracks moving at
 * v[3 i ..] (NaN: no track, no bias), into b (may be v), with the model
 * and lead the smoother would use now (cmd_track_finish.c fin_new). Why:
 * a detection made from ON events lies ahead of its object along the
 * motion and shows where it was a little before t_us; the smoother
 * corrects its track's points so, and detections.csv is where each object
 * was, too. Flow 100 ms seeds 1-20, the detections' lateral RMSE 0.509 /
 * 0.518 -> 0.432 / 0.436 um (docs/tracker.md "Moving the detections"). */
static void det_bias(const track_ctx *c, const double *v, double *b, int n)
{
  elfm_smooth_options so = c->o->smooth;
  so.motion_lead_um = track_motion_lead_um(c);
  for (int i = 0; i < n; i++) {
    const double *vi = v + 3 * (size_t)i;
    double *bi = b + 3 * (size_t)i;
    if (isfinite(vi[0]) && isfinite(vi[1]) && isfinite(vi[2])) {
      double w[3] = {vi[0], vi[1], vi[2]};
      elfm_motion_bias(&so, w, bi);
    } else {
      bi[0] = bi[1] = bi[2] = 0;
    }
  }
}

/* Into v, the velocity of the line through t's points around detection d
 * (elfm_link_local_velocity), when d is one of t's points: a later
 * review may have given it to another track. v unchanged otherwise. */
static void det_velocity_on(const elfm_track *t, const elfm_detection *d, double v[3])
{
  for (size_t k = t->n; k-- > 0;) {  /* the held frames are the track's last ones */
    const elfm_detection *p = &t->pts[k];
    if (p->frame < d->frame) return;
    if (p->frame == d->frame) {
      if (p->x_um == d->x_um && p->y_um == d->y_um && p->z_um == d->z_um)
        elfm_link_local_velocity(t, d->frame, TRACK_DET_VELOCITY_HALF_FRAMES, v);
      return;
    }
  }
}

void track_det_velocities(track_ctx *c, const elfm_track *t)
{
  frame_ring *r = &c->ring;
  if (!r->cap || !t || !t->n) return;
  for (int j = 0; j < r->cap; j++) {
    ring_slot *sl = &r->slot[j];
    if (sl->det_frame < t->pts[0].frame || sl->det_frame > t->pts[t->n - 1].frame) continue;
    for (int i = 0; i < sl->det_n; i++)
      if (sl->det_track[i] == t->id) det_velocity_on(t, &sl->det[i], sl->det_vel + 3 * (size_t)i);
  }
}

/* Write a slot's detections and empty it. Why the velocity of a line
 * through +-3 frames, known only now: the linker's, when the detection
 * joined, is its short fit's (a parabola through the last 8 points) at
 * the fit's end, the noisiest point of it, and the bias shrinks as the
 * speed it is given grows. Flow seeds 1-20: moved by it, the detections
 * still led by 0.21-0.24 um along the motion (seeds 1-5), lateral RMSE
 * 0.456 / 0.460 um; by the line's, -0.06 to +0.03 um and 0.432 / 0.436
 * (+-2 frames 0.431 / 0.436, +-5 0.451 / 0.459). */
static elfm_status det_write_slot(track_ctx *c, ring_slot *sl, elfm_error *err)
{
  elfm_status st = ELFM_OK;
  if (sl->det_n > 0) {
    for (int i = 0; i < sl->det_n; i++) {
      const elfm_track *t = sl->det_track[i] >= 0 ? elfm_link_live_track(c->lk, sl->det_track[i]) : NULL;
      if (t) det_velocity_on(t, &sl->det[i], sl->det_vel + 3 * (size_t)i);
    }
    det_bias(c, sl->det_vel, sl->det_vel, sl->det_n);
    st = elfm_detections_write(c->fdet, c->p_det, sl->det, sl->det_vel, sl->det_n, err);
  }
  sl->det_n = 0;
  sl->det_frame = -1;
  return st;
}

elfm_status track_det_emit(track_ctx *c, int64_t frame, const elfm_detection *d, int64_t track_id,
                           const double *v_um_per_ms, elfm_error *err)
{
  frame_ring *r = &c->ring;
  double v[3] = {NAN, NAN, NAN};
  if (v_um_per_ms) memcpy(v, v_um_per_ms, sizeof v);
  if (!r->cap) {
    det_bias(c, v, v, 1);
    return elfm_detections_write(c->fdet, c->p_det, d, v, 1, err);
  }
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
    if (p) sl->det = p;
    double *pv = realloc(sl->det_vel, 3 * (size_t)cap * sizeof *pv);
    if (pv) sl->det_vel = pv;
    int64_t *pt = realloc(sl->det_track, (size_t)cap * sizeof *pt);
    if (pt) sl->det_track = pt;
    if (!p || !pv || !pt) return elfm_error_set(err, ELFM_ERR_NOMEM, NULL, -1, "out of memory (detections)");
    sl->det_cap = cap;
  }
  memcpy(sl->det_vel + 3 * (size_t)sl->det_n, v, sizeof v);
  sl->det_track[sl->det_n] = track_id;
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
    free(r->slot[k].det_vel);
    free(r->slot[k].det_track);
  }
  free(r->slot);
  memset(r, 0, sizeof *r);
  free(c->gaps);
  free(c->fill_pts);
  free(c->fill_retried);
  free(c->fill_keep);
  elfm_frame_free(c->scratch);
  for (int j = 0; j < TRACK_FILL_MAX_FRAMES - 1; j++) elfm_frame_free(c->scratch_nbr[j]);
}
