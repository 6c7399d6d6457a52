/* cmd_track_guided.c — eventlfm track's searches guided by the tracks: where
 * the established tracks expect their objects in this frame (the linker's
 * predictions), split a peak two meeting tracks share (pair fits), and find
 * the object of a track that has no detection near it: a low local maximum,
 * or the view fit from the prediction itself. Called in frame order, before
 * the frame's detections are linked (cmd_track.h). */
#include <math.h>
#include <string.h>

#include "cmd_track.h"

/* The squared distance of a and b (um) in the linker's metric (dz / kz). */
static double dist2_kz(const double *a, const double *b, double kz)
{
  const double dx = a[0] - b[0], dy = a[1] - b[1], dz = (a[2] - b[2]) / kz;
  return dx * dx + dy * dy + dz * dz;
}

/* Is a detection of det[0 .. n) within the weak gate of prediction q? */
static int any_near(const elfm_detection *det, int n, const double q[3], double gate_um, double kz)
{
  for (int j = 0; j < n; j++) {
    const double p[3] = {det[j].x_um, det[j].y_um, det[j].z_um};
    if (dist2_kz(p, q, kz) < gate_um * gate_um) return 1;
  }
  return 0;
}

/* A point the view fit placed from a track's prediction (r, in the voxels
 * of geo, the full-sampled volume's geometry): weak (it can only go on with
 * a track) and view_fit, its intensity the volume v's at the nearest voxel
 * (v's own, coarser with --bin-px). 0 where that voxel lies outside the
 * volume. */
static int guided_point(const elfm_volume *geo, const elfm_volume *v,
                        const elfm_localize_result *r, elfm_detection *d)
{
  int X = (int)lround(r->x_vox), Y = (int)lround(r->y_vox), K = (int)lround(r->z_vox);
  if (X < 0 || Y < 0 || K < 0 || X >= geo->w || Y >= geo->h || K >= geo->nz) return 0;
  memset(d, 0, sizeof *d);
  d->frame = v->frame;
  d->t_us = v->t_us;
  d->x_um = elfm_volume_x_um(geo, r->x_vox);
  d->y_um = elfm_volume_y_um(geo, r->y_vox);
  d->z_um = elfm_volume_z_um(geo, r->z_vox);
  d->fit_sd_px = r->sd_px;
  if (v->w != geo->w || v->h != geo->h) { /* a binned volume: its voxel at the point */
    X = (int)lround(elfm_volume_x_vox(v, d->x_um));
    Y = (int)lround(elfm_volume_y_vox(v, d->y_um));
    X = X < 0 ? 0 : X >= v->w ? v->w - 1 : X;
    Y = Y < 0 ? 0 : Y >= v->h ? v->h - 1 : Y;
  }
  d->intensity = v->data[((size_t)K * v->h + Y) * v->w + X];
  d->weak = 1;
  d->view_fit = 1;
  return 1;
}

/* Two fits closer than this (um, the linker's metric) found one object
 * twice, not the two the tracks expect. */
#define PAIR_MIN_SEP_UM 0.5

/* Two predicted images are told apart in a view when they lie at least
 * this far apart there (px): about a bead's image width (2.6 px in focus);
 * nearer, the fit's window holds both (and localize.c takes out no
 * neighbour closer than 2 px). */
#define PAIR_VIEW_SEP_PX 3.0

/* Do at least half of the views see the images of objects at a and b (um)
 * PAIR_VIEW_SEP_PX apart? Two objects at one depth and close laterally are
 * one blob in every view, and a fit from each prediction then lands where
 * the predictions were, not where the objects are: the worm's neuron pairs
 * (track_integral.sh's worm, alpha 0.925 -> 0.862 with every merged peak
 * split, 0.920 with this test). */
static int views_part(const elfm_calib *cal, const double *a, const double *b)
{
  const double dx = (a[0] - b[0]) / cal->um_per_px, dy = (a[1] - b[1]) / cal->um_per_px;
  const double dz = a[2] - b[2];
  int n = 0;
  for (int v = 0; v < cal->n_views; v++) {
    const double su = dx + dz * cal->views[v].dx_px_per_um, sv = dy + dz * cal->views[v].dy_px_per_um;
    n += su * su + sv * sv >= PAIR_VIEW_SEP_PX * PAIR_VIEW_SEP_PX;
  }
  return 2 * n >= cal->n_views;
}

/* The view fit from q (um) with the light of an object at `other` taken
 * out of its windows; 0 where it fails or lands outside the volume. */
static int fit_beside(const track_ctx *c, const elfm_volume *v, const elfm_refocus_plan *plan,
                      const elfm_frame *frame, const double q[3], const double other[3],
                      elfm_detection *d)
{
  const elfm_volume *geo = &c->geo;
  const double nb[1][3] = {{elfm_volume_x_vox(geo, other[0]), elfm_volume_y_vox(geo, other[1]),
                            elfm_volume_z_vox(geo, other[2])}};
  elfm_localize_result r;
  const elfm_localize_options lo = track_guided_loc(c->o);
  return elfm_refocus_localize_near(plan, frame, elfm_volume_x_vox(geo, q[0]),
                                    elfm_volume_y_vox(geo, q[1]), elfm_volume_z_vox(geo, q[2]), nb,
                                    1, &lo, &r) &&
         guided_point(geo, v, &r, d);
}

elfm_localize_options track_guided_loc(const track_opts *o)
{
  elfm_localize_options lo = o->loc;
  if (o->recon.framer.deep_window_us > 0) lo.deep_z_um = o->deep_window_um;
  return lo;
}

/* Pair fits (pair_fit_um): where two established tracks' predictions lie
 * within pair_fit_um laterally and a single detection stands within the
 * weak gate of either, the two objects' images have merged into one peak
 * of the volume, which both tracks would claim: one takes it, and the
 * other goes dark or, a frame later, leaves on the wrong object. The views
 * can still tell the two apart: in a Fourier LFM an object's image in view
 * v moves by z dx_v, so two objects dz apart in depth sit up to 0.5 dz px
 * further apart in the corner views (the paper's 5 x 5 array) than in the
 * centre one, while the volume's axial blur (~20 um) merges them. Where
 * half the views part the two predicted images (views_part), each object
 * is fitted from its own track's prediction with the other's light taken
 * out of the views' windows (elfm_refocus_localize_near), then again from
 * the two fits. When both fits succeed, each within the weak gate of its
 * own prediction and the two at least PAIR_MIN_SEP_UM apart, they replace
 * the merged detection as weak view-fit points (each can only go on with a
 * track, never start one). On simulated flows 9 in 10 of the splits put
 * both fits on the beads their tracks had followed. Flow 1 s alpha +0.009
 * +- 0.004 over 60 seeds, random flow 1 s -0.001 +- 0.006 over 44, flow
 * 100 ms -0.001 +- 0.002 over 40 (docs/tracker.md "Two tracks at one
 * peak"). */
static void pair_fits(track_ctx *c, const elfm_volume *v, const elfm_frame *frame,
                      const elfm_refocus_plan *plan, const double *pred, int np,
                      elfm_detection *det, int *n_io)
{
  const track_opts *o = c->o;
  int n = *n_io;
  const double g = o->link.weak_gate_um, kz = o->link.kz, D = o->pair_fit_um;
  for (int k = 0; k < np; k++)
    for (int j = k + 1; j < np && n < o->max_det; j++) {
      const double *a = pred + 3 * (size_t)k, *b = pred + 3 * (size_t)j;
      const double dx = a[0] - b[0], dy = a[1] - b[1];
      if (dx * dx + dy * dy >= D * D) continue;
      int n_in = 0, merged = -1;
      for (int i = 0; i < n; i++)
        if (any_near(&det[i], 1, a, g, kz) || any_near(&det[i], 1, b, g, kz)) {
          n_in++;
          merged = i;
        }
      if (n_in != 1) continue;
      if (!views_part(c->calib, a, b)) continue;
      elfm_detection a0, b0, d[2];
      if (!fit_beside(c, v, plan, frame, a, b, &a0) || !fit_beside(c, v, plan, frame, b, a, &b0))
        continue;
      const double pa[3] = {a0.x_um, a0.y_um, a0.z_um}, pb[3] = {b0.x_um, b0.y_um, b0.z_um};
      if (!fit_beside(c, v, plan, frame, pa, pb, &d[0]) ||
          !fit_beside(c, v, plan, frame, pb, pa, &d[1]))
        continue;
      const double A[3] = {d[0].x_um, d[0].y_um, d[0].z_um}, B[3] = {d[1].x_um, d[1].y_um, d[1].z_um};
      if (dist2_kz(A, a, kz) >= g * g || dist2_kz(B, b, kz) >= g * g ||
          dist2_kz(A, B, kz) < PAIR_MIN_SEP_UM * PAIR_MIN_SEP_UM)
        continue;
      det[merged] = d[0];
      det[n++] = d[1];
      c->n_pair_fits++;
    }
  *n_io = n;
}

/* Track-guided view fit: where an established track expects its bead and
 * no peak lies within the weak gate, run the view fit from the prediction
 * itself. A deep bead's few events often leave no local maximum in the
 * volume (recall 0.3 beyond |z| = 60 um on flow) while its images are still
 * there in most views; a fit that lands within the weak gate with at least
 * guided_views views agreeing (ghosts and noise give a few) becomes a
 * weak peak, which can only continue that track. Flow 100 ms, 8 seeds: F1
 * 0.911 -> 0.929 over the view fit of every peak alone (docs/tracker.md).
 * A fit within guided_apart_um of another detection of the frame (a peak,
 * or a fit made for another track just before) found that object, whose
 * light reached the window (on random flow nine in ten of the weak view
 * fits within 2 um of another detection lay on that detection's bead):
 * kept, two tracks hold one bead, and one may leave on the wrong one.
 * Dropped, the track goes dark for the frame instead.
 * pred[0 .. np) are the linker's predictions for this frame. */
static void guided_view_fit(track_ctx *c, const elfm_volume *v, const elfm_frame *frame,
                            const elfm_refocus_plan *plan, const double *pred, int np,
                            elfm_detection *det, int *n_io)
{
  const track_opts *o = c->o;
  const elfm_volume *geo = &c->geo; /* the view fits' voxels */
  int n = *n_io;
  const double g = o->link.weak_gate_um, kz = o->link.kz;
  elfm_localize_options lo = track_guided_loc(o);
  lo.min_views = o->guided_views;
  for (int k = 0; k < np && n < o->max_det; k++) {
    const double *q = pred + 3 * (size_t)k;
    if (any_near(det, n, q, g, kz)) continue;
    elfm_localize_result r;
    /* the frame's objects near the prediction: its peaks, and where no
     * peak stands, the other tracks' predictions (localize_near_um) */
    double nb[TRACK_NEAR_MAX][3];
    int k_nb = 0;
    if (o->localize_near_um > 0) {
      const double r2 = o->localize_near_um * o->localize_near_um;
      k_nb = track_near_add(det, n, -1, q[0], q[1], o->localize_near_um, geo, nb, 0);
      for (int j = 0; j < np && k_nb < TRACK_NEAR_MAX; j++) {
        const double *qj = pred + 3 * (size_t)j;
        const double dx = qj[0] - q[0], dy = qj[1] - q[1];
        if (j == k || dx * dx + dy * dy >= r2 || any_near(det, n, qj, g, kz)) continue;
        nb[k_nb][0] = elfm_volume_x_vox(geo, qj[0]);
        nb[k_nb][1] = elfm_volume_y_vox(geo, qj[1]);
        nb[k_nb][2] = elfm_volume_z_vox(geo, qj[2]);
        k_nb++;
      }
    }
    if (!elfm_refocus_localize_near(plan, frame, elfm_volume_x_vox(geo, q[0]),
                                    elfm_volume_y_vox(geo, q[1]), elfm_volume_z_vox(geo, q[2]),
                                    (const double(*)[3])nb, k_nb, &lo, &r))
      continue;
    elfm_detection d;
    if (!guided_point(geo, v, &r, &d) || !any_near(&d, 1, q, g, kz)) continue;
    if (d.intensity < o->guided_min_ratio * c->pred_intensity[k]) continue;
    const double pd[3] = {d.x_um, d.y_um, d.z_um};
    if (o->guided_apart_um > 0 && any_near(det, n, pd, o->guided_apart_um, kz)) {
      c->n_guided_beside++;
      continue;
    }
    det[n++] = d;
    c->n_guided_views++;
  }
  *n_io = n;
}

/* cmd_track.h */
elfm_status track_guided_search(track_ctx *c, const elfm_volume *v, int slot, elfm_detection *det,
                                int *n_io, elfm_error *err)
{
  const track_opts *o = c->o;
  const int guided_peak = o->guided_low > 0 && o->link.weak_gate_um > 0;
  const int guided_fit = o->guided_views > 0 && o->link.weak_gate_um > 0;
  const int pair_fit = o->pair_fit_um > 0 && o->link.weak_gate_um > 0;
  if (!guided_peak && !guided_fit && !pair_fit) return ELFM_OK;
  /* the linker's predictions, once, for all three */
  int np = 0, n = *n_io;
  elfm_status st = elfm_link_predict(c->lk, v->frame, v->t_us, o->guided_min_points, c->pred,
                                     c->pred_intensity, o->max_det, &np, err);
  if (st != ELFM_OK) return st;
  /* the frame and plan the worker refocused this volume from (the view
   * fits read the frame's views) */
  const elfm_frame *frame = c->slot_frame[slot];
  const elfm_refocus_plan *plan = c->slot_plan[slot];
  const int have_views = frame && plan;
  if (pair_fit && have_views) pair_fits(c, v, frame, plan, c->pred, np, det, &n);
  if (guided_peak) {
    /* Track-guided search: where an established track expects its bead
     * and no peak lies within the weak gate, take the local maximum above
     * guided_low there (weak: it can only continue that track). Deep beads
     * fade below the global threshold (25-55 on the surface, docs). */
    const double g = o->link.weak_gate_um, kz = o->link.kz, gs = o->guided_radius_um;
    for (int k = 0; k < np && n < o->max_det; k++) {
      const double *q = c->pred + 3 * (size_t)k;
      if (any_near(det, n, q, g, kz)) continue;
      int found = 0;
      st = elfm_peaks_find_near(c->pk[0], v, q, gs, gs * kz, o->guided_low, &det[n], &found, err);
      if (st != ELFM_OK) {
        *n_io = n;
        return st;
      }
      n += found;
    }
  }
  if (guided_fit && have_views) guided_view_fit(c, v, frame, plan, c->pred, np, det, &n);
  *n_io = n;
  return ELFM_OK;
}
