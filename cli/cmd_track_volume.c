/* cmd_track_volume.c — eventlfm track's per-volume work, called back by the
 * recon driver: peak detection on the worker threads, then in frame order
 * linking and writing detections; the tracks that ended go to
 * cmd_track_finish.c (see cmd_track.h). */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "cmd_track.h"

void track_width_add(track_ctx *c, const elfm_detection *d)
{
  if (d->weak || d->view_fit || !(d->width_um > 0) || !(fabs(d->z_um) < TRACK_WIDTH_NEAR_UM)) return;
  long b = lround(d->width_um / TRACK_WIDTH_BIN_UM);
  if (b >= TRACK_WIDTH_BINS) b = TRACK_WIDTH_BINS - 1;
  c->width_near_hist[b]++;
  c->n_width_near++;
  if (!(fabs(d->z_um) < TRACK_WIDTH_FOCUS_UM)) return;
  c->width_hist[b]++;
  c->n_width++;
}

void track_height_add(track_ctx *c, const elfm_detection *d)
{
  if (d->view_fit || !(d->intensity >= 0)) return;
  const double b = floor(d->intensity);
  track_hist_add(c->height_hist, TRACK_HEIGHT_BINS, b);
  c->n_height++;
}

void track_speed_add(track_ctx *c, double v_um_per_ms)
{
  if (!(v_um_per_ms >= 0)) return;  /* NaN: a new track */
  const double b = floor(v_um_per_ms / TRACK_SPEED_BIN_UM_PER_MS);
  track_hist_add(c->speed_hist, TRACK_SPEED_BINS, b);
  c->n_speed++;
}

void track_miss_add(track_ctx *c, const elfm_detection *d, double miss_um)
{
  /* in focus, where the views place a bead best (0.3 um per lateral axis
   * against 0.7-0.8 beyond 60 um, docs/tracker.md "Where the information
   * runs out"): there the miss is the motion's more than the noise's */
  if (!(miss_um >= 0) || d->view_fit || !(fabs(d->z_um) < TRACK_MISS_FOCUS_UM)) return;
  const double b = floor(miss_um / TRACK_MISS_BIN_UM);
  track_hist_add(c->miss_hist, TRACK_MISS_BINS, b);
  c->n_miss++;
}

/* The bin of a histogram's median (n > 0 counts in hist[0 .. bins)). */
int track_hist_median_bin(const int64_t *hist, int bins, int64_t n)
{
  int64_t half = (n + 1) / 2, acc = 0;
  int b = 0;
  while (b < bins - 1 && (acc += hist[b]) < half) b++;
  return b;
}

double track_peak_height_median(const track_ctx *c)
{
  if (c->n_height == 0) return NAN;
  return track_hist_median_bin(c->height_hist, TRACK_HEIGHT_BINS, c->n_height) + 0.5;
}

double track_detection_speed_median(const track_ctx *c)
{
  if (c->n_speed == 0) return NAN;
  return (track_hist_median_bin(c->speed_hist, TRACK_SPEED_BINS, c->n_speed) + 0.5) * TRACK_SPEED_BIN_UM_PER_MS;
}

double track_detection_miss_median(const track_ctx *c)
{
  if (c->n_miss == 0) return NAN;
  return (track_hist_median_bin(c->miss_hist, TRACK_MISS_BINS, c->n_miss) + 0.5) * TRACK_MISS_BIN_UM;
}

/* Which peaks give the width: 1 the in-focus ones, 2 those near focus, 0
 * too few of either (cmd_track.h TRACK_WIDTH_*). */
static int width_source(const track_ctx *c)
{
  if (c->n_width >= TRACK_WIDTH_MIN_PEAKS) return 1;
  if (c->n_width_near >= TRACK_WIDTH_MIN_PEAKS) return 2;
  if (c->n_width >= TRACK_WIDTH_FEW_PEAKS) return 1;
  if (c->n_width_near >= TRACK_WIDTH_FEW_PEAKS) return 2;
  return 0;
}

double track_peak_width_median_um(const track_ctx *c)
{
  const int src = width_source(c);
  if (src == 2)
    return track_hist_median_bin(c->width_near_hist, TRACK_WIDTH_BINS, c->n_width_near) * TRACK_WIDTH_BIN_UM;
  if (c->n_width == 0) return NAN;
  return track_hist_median_bin(c->width_hist, TRACK_WIDTH_BINS, c->n_width) * TRACK_WIDTH_BIN_UM;
}

double track_judged_speed_um_per_ms(const track_ctx *c)
{
  if (c->o->auto_chose) return c->o->auto_speed;
  return c->auto_decided ? c->auto_speed : NAN;
}

/* Whether the lead is the flows' one from the widths (1.80 x width -
 * 0.37), which the two cuts below shorten: not on a stage (its own lead,
 * which a shorter one made worse for both) but under the LED's windows,
 * nor where the lead is given or the widths are too few. */
static int flow_widths_lead(const track_ctx *c)
{
  return c->o->motion_lead_auto && width_source(c) &&
         (c->o->motion != MOTION_STAGE || track_led_windows(c->o));
}

/* A recording whose beads all move fast leads less than its peaks' widths
 * say: flow at 5-6 mm/s, 0.25 um less (docs/tracker.md "The lead of fast
 * flows"). */
double track_motion_lead_fast_um(const track_ctx *c)
{
  const double v = track_judged_speed_um_per_ms(c);
  if (!flow_widths_lead(c) || !isfinite(v)) return 0;
  return c->o->lead_fast_ms * fmax(0.0, v - c->o->lead_fast_um_per_ms);
}

/* The blur (--blur-px, chosen for dim objects) leaves the peaks' widths
 * as they were but the detections 0.3 um further back along the motion
 * (docs/tracker.md "The lead on blurred frames"). */
double track_motion_lead_blur_um(const track_ctx *c)
{
  return flow_widths_lead(c) && c->o->recon.blur_px > 0 ? c->o->lead_blur_um : 0;
}

double track_motion_lead_um(const track_ctx *c)
{
  if (!c->o->motion_lead_auto || !width_source(c)) return c->o->smooth.motion_lead_um;
  const double w_um = track_peak_width_median_um(c);
  if (c->o->motion == MOTION_STAGE && !track_led_windows(c->o)) return TRACK_LEAD_PER_WIDTH_FIRST_PASS * w_um;
  return fmax(0.0, TRACK_LEAD_AT_ZERO_WIDTH_UM + TRACK_LEAD_PER_WIDTH * w_um - track_motion_lead_fast_um(c) -
                       track_motion_lead_blur_um(c));
}

static elfm_status fwhm_push(fwhm_list *l, double xy, double z, double speed, elfm_error *err)
{
  if (l->n == l->cap) {
    size_t cap = l->cap ? 2 * l->cap : 1024;
    struct fwhm_bead *b = realloc(l->b, cap * sizeof *b);
    if (!b) return elfm_error_set(err, ELFM_ERR_NOMEM, NULL, -1, "out of memory");
    l->b = b;
    l->cap = cap;
  }
  l->b[l->n++] = (struct fwhm_bead){{xy, z}, speed};
  return ELFM_OK;
}

/* Detectors and buffers for the driver's layout, before the run, and the
 * run's refocus plan (c->plan: the driver refocuses with it too, and the gap
 * fills fit with it). With the views rule, the views sampling each voxel
 * (elfm_peaks_set_view_counts) are counted once and copied to each detector. */
elfm_status track_peaks_setup(track_ctx *c, elfm_error *err)
{
  const track_opts *o = c->o;
  elfm_status s = elfm_recon_layout(&o->recon, &c->n_threads, &c->n_slots, err);
  if (s != ELFM_OK) return s;
  c->pk = calloc((size_t)c->n_threads, sizeof *c->pk);
  c->det = malloc((size_t)c->n_slots * (size_t)o->max_det * sizeof *c->det);
  c->sp = calloc((size_t)c->n_slots, sizeof *c->sp);
  c->slot_frame = calloc((size_t)c->n_slots, sizeof *c->slot_frame);
  c->slot_plan = calloc((size_t)c->n_slots, sizeof *c->slot_plan);
  if (o->localize_near_um > 0) {
    c->fitok = calloc((size_t)c->n_slots * (size_t)o->max_det, 1);
    c->near_fit = malloc((size_t)c->n_slots * (size_t)o->max_det * 4 * sizeof *c->near_fit);
  }
  if (o->view_support > 0) c->keep = malloc((size_t)c->n_slots * (size_t)o->max_det);
  for (int v = 0; v < c->calib->n_views; v++) {
    const double dx = fabs(c->calib->views[v].dx_px_per_um);
    const double dy = fabs(c->calib->views[v].dy_px_per_um);
    if (dx > c->shift_max_px_per_um) c->shift_max_px_per_um = dx;
    if (dy > c->shift_max_px_per_um) c->shift_max_px_per_um = dy;
  }
  c->pred = malloc((size_t)o->max_det * 3 * sizeof *c->pred);
  c->pred_intensity = malloc((size_t)o->max_det * sizeof *c->pred_intensity);
  if ((o->motion_auto || o->stage_watch) &&
      !(c->rigid_v = malloc((size_t)o->max_det * 4 * sizeof *c->rigid_v)))
    return elfm_error_set(err, ELFM_ERR_NOMEM, NULL, -1, "out of memory (detections)");
  if (track_votes_wanted(o) && !track_votes_init(&c->votes, o->link.kz))
    return elfm_error_set(err, ELFM_ERR_NOMEM, NULL, -1, "out of memory (frames for a stage)");
  if (!c->pk || !c->det || !c->sp || !c->slot_frame || !c->slot_plan ||
      (o->localize_near_um > 0 && (!c->fitok || !c->near_fit)) ||
      (o->view_support > 0 && !c->keep) || !c->pred || !c->pred_intensity)
    return elfm_error_set(err, ELFM_ERR_NOMEM, NULL, -1, "out of memory (detections)");
  s = elfm_refocus_plan_create(c->calib, &o->recon.refocus, &c->plan, err);
  if (s != ELFM_OK) return s;
  memset(&c->geo, 0, sizeof c->geo);
  elfm_refocus_plan_size(c->plan, &c->geo.w, &c->geo.h, &c->geo.nz);
  c->geo.um_per_px = c->calib->um_per_px;
  c->geo.z_min_um = c->calib->z_min_um;
  c->geo.z_step_um = c->calib->z_step_um;
  if (o->bin_px > 1) {
    elfm_calib binned;
    s = elfm_calib_bin(c->calib, o->bin_px, &binned, err);
    if (s == ELFM_OK) s = elfm_refocus_plan_create(&binned, &o->recon.refocus, &c->vplan, err);
    if (s == ELFM_OK) s = track_bin_setup(c, err);
    if (s != ELFM_OK) return s;
  }
  const elfm_refocus_plan *plan = c->vplan ? c->vplan : c->plan;
  int w, h, nz; /* the volumes' size: their plan's */
  elfm_refocus_plan_size(plan, &w, &h, &nz);
  uint8_t *cnt = NULL;
  if (o->views_rule) {
    cnt = malloc((size_t)w * h * nz);
    if (!cnt) return elfm_error_set(err, ELFM_ERR_NOMEM, NULL, -1, "out of memory (view counts)");
    for (int k = 0; k < nz; k++)
      for (int Y = 0; Y < h; Y++)
        for (int X = 0; X < w; X++)
          cnt[((size_t)k * h + Y) * w + X] = (uint8_t)elfm_refocus_plan_views_at(plan, X, Y, k);
  }
  for (int t = 0; s == ELFM_OK && t < c->n_threads; t++) {
    c->pk[t] = elfm_peaks_create(&o->peaks, w, h, nz, err);
    if (!c->pk[t]) s = err ? err->code : ELFM_ERR_INVALID;
    else if (cnt)
      s = elfm_peaks_set_view_counts(c->pk[t], cnt, c->calib->n_views, o->views_exponent, err);
  }
  free(cnt);
  return s;
}

/* cmd_track.h: the neighbours of the peaks', the guided fit's and the gap
 * fills' view fits */
int track_near_add(const elfm_detection *det, int n, int skip, double x_um, double y_um,
                   double near_um, const elfm_volume *geo, double nb[TRACK_NEAR_MAX][3], int k)
{
  for (int j = 0; j < n && k < TRACK_NEAR_MAX; j++) {
    const double dx = det[j].x_um - x_um, dy = det[j].y_um - y_um;
    if (j == skip || dx * dx + dy * dy >= near_um * near_um) continue;
    nb[k][0] = elfm_volume_x_vox(geo, det[j].x_um);
    nb[k][1] = elfm_volume_y_vox(geo, det[j].y_um);
    nb[k][2] = elfm_volume_z_vox(geo, det[j].z_um);
    k++;
  }
  return k;
}

/* The view fit again for each peak it placed that has neighbours within
 * localize_near_um, with their light taken out (elfm_refocus_localize_near).
 * Every second fit starts from, and reads its neighbours at, the first fits'
 * positions (the results are kept aside until all are done), so that the
 * order does not matter. Where the second fit fails, the first stays. */
static void near_refit(track_ctx *c, const elfm_volume *geo, int slot, elfm_detection *det, int n,
                       const elfm_localize_options *deep, int deep_test)
{
  const elfm_frame *frame = c->slot_frame[slot];
  const elfm_refocus_plan *plan = c->slot_plan[slot];
  const unsigned char *ok = c->fitok + (size_t)slot * c->o->max_det;
  double(*fit)[4] = (double(*)[4])(c->near_fit + (size_t)slot * c->o->max_det * 4);
  for (int i = 0; i < n; i++) {
    fit[i][0] = NAN;
    if (!ok[i]) continue;
    double nb[TRACK_NEAR_MAX][3];
    const int k = track_near_add(det, n, i, det[i].x_um, det[i].y_um, c->o->localize_near_um, geo,
                                 nb, 0);
    elfm_localize_result r;
    if (!k || !elfm_refocus_localize_near(plan, frame, elfm_volume_x_vox(geo, det[i].x_um),
                                          elfm_volume_y_vox(geo, det[i].y_um),
                                          elfm_volume_z_vox(geo, det[i].z_um),
                                          (const double(*)[3])nb, k,
                                          deep_test && det[i].deep_only ? deep : &c->o->loc, &r))
      continue;
    fit[i][0] = elfm_volume_x_um(geo, r.x_vox);
    fit[i][1] = elfm_volume_y_um(geo, r.y_vox);
    fit[i][2] = elfm_volume_z_um(geo, r.z_vox);
    fit[i][3] = r.sd_px;
  }
  for (int i = 0; i < n; i++) {
    if (isnan(fit[i][0])) continue;
    det[i].x_um = fit[i][0];
    det[i].y_um = fit[i][1];
    det[i].z_um = fit[i][2];
    det[i].fit_sd_px = fit[i][3];
  }
}

/* The view support of peak i (voxel X, Y, K; n views with signal) without
 * the views a brighter peak's images explain (elfm_refocus_view_support_
 * unexplained): the brightest peaks of the frame over 1 / explain_brighter
 * times as bright whose images can reach it in some view (laterally within
 * the views' largest shift x their depth apart + explain_um), at most
 * TRACK_EXPLAIN_MAX. The views they explain are left out only when they
 * are at least half of the n: a bead beside a brighter one at another
 * depth shares a view or two with it, a ghost (the brighter one's images
 * lining up) nearly all. Why: a bead's images grow with its brightness
 * (its dim wings fire events too), and where a bright bead's images in a
 * column or row of views line up at another depth, 30-50 % of the views
 * have signal, so the plain test passes that ghost; on flow with the beads
 * 5 x brighter (flux 60-80 kHz, seed 2) 1065 of 3117 detections were such
 * ghosts and they made 83 tracks for 20 beads (precision 0.64; 0.96 and
 * 25 tracks with this). Counted only when half or more are explained,
 * because at depth a real bead's sparse images miss views, and any view a
 * brighter neighbour then explains can take it under the test
 * (flow_random seeds 1-8, recall 0.850 -> 0.837 with every explained view
 * left out). docs/tracker.md "Ghosts of bright objects" has the rest. */
static int explained_support(const track_ctx *c, const elfm_volume *geo,
                             const elfm_refocus_plan *plan, const elfm_frame *frame,
                             const elfm_detection *det, int n_peaks, int i, int X, int Y, int K,
                             int n)
{
  const track_opts *o = c->o;
  const double r_px = o->explain_um / geo->um_per_px;
  const double reach_px_per_plane = c->shift_max_px_per_um * geo->z_step_um;
  double others[TRACK_EXPLAIN_MAX][3], bright[TRACK_EXPLAIN_MAX];
  int no = 0;
  for (int j = 0; j < n_peaks; j++) {
    if (j == i || !(det[i].intensity < o->explain_brighter * det[j].intensity)) continue;
    const double xj = elfm_volume_x_vox(geo, det[j].x_um), yj = elfm_volume_y_vox(geo, det[j].y_um),
                 kj = elfm_volume_z_vox(geo, det[j].z_um);
    const double reach = reach_px_per_plane * fabs(kj - K) + r_px + 1;
    if (fabs(xj - X) > reach || fabs(yj - Y) > reach) continue;
    /* keep the TRACK_EXPLAIN_MAX brightest: insertion by intensity */
    int at = no < TRACK_EXPLAIN_MAX ? no++ : TRACK_EXPLAIN_MAX;
    while (at > 0 && bright[at - 1] < det[j].intensity) {
      if (at < TRACK_EXPLAIN_MAX) {
        bright[at] = bright[at - 1];
        memcpy(others[at], others[at - 1], sizeof others[at]);
      }
      at--;
    }
    if (at < TRACK_EXPLAIN_MAX) {
      bright[at] = det[j].intensity;
      others[at][0] = xj;
      others[at][1] = yj;
      others[at][2] = kj;
    }
  }
  if (no == 0) return n;
  int n_expl = 0;
  const int nu = elfm_refocus_view_support_unexplained(plan, frame, X, Y, K,
                                                       (const double(*)[3])others, no, r_px, NULL,
                                                       &n_expl);
  return 2 * n_expl >= n ? nu : n;
}

double track_view_support_need(const track_opts *o, double occupancy)
{
  if (!o->view_support_auto || !(occupancy > TRACK_CROWD_OCC)) return o->view_support;
  /* The ghosts' views are other objects' images met by chance, and the
   * more of the views' pixels have signal, the more views such a chance
   * meeting gathers. Flow 100 ms, seeds 1-4, mean alpha at view support
   * 0.3 / 0.45: 60 beads (3.0 % of the pixels) 0.691 / 0.675, 80 beads
   * (3.8 %) 0.524 / 0.535, 100 beads (4.2 %) 0.392 / 0.466, 120 beads
   * (4.8 %) 0.349 / 0.387 (0.397 at 0.55), 150 beads (5.8 %) 0.266 /
   * 0.283 (0.286 at 0.55); docs/tracker.md "Crowded frames". */
  double need = o->view_support + TRACK_VSUP_PER_OCC * (occupancy - TRACK_CROWD_OCC);
  if (need > TRACK_VSUP_MAX) need = TRACK_VSUP_MAX;
  return need > o->view_support ? need : o->view_support;
}

double track_rescue_factor(const track_opts *o, double occupancy)
{
  const double f = o->link.rescue_gate_factor;
  if (!o->rescue_auto || !(occupancy > TRACK_CROWD_OCC)) return f;
  /* In a crowd the detection a track finds 2.5 gates off its path is
   * another object's more often than its own. Flow 100 ms, 80 and 100
   * beads, seeds 1-2, mean alpha with the crowded frames' view support:
   * --rescue-factor 2.5 / 2 / 1.5 / 0 0.500 / 0.551 / 0.573 / 0.569; at
   * 40 beads 0 lost 0.013. Down to 1.5 or to 1 (no reach beyond the
   * gate), 80-150 beads seeds 1-8: 0.480 / 0.487 (docs/tracker.md
   * "Crowded frames"). */
  const double g = f - TRACK_RESCUE_PER_OCC * (occupancy - TRACK_CROWD_OCC);
  return g > TRACK_RESCUE_MIN ? g : TRACK_RESCUE_MIN;
}

double track_occupancy_mean(const track_ctx *c)
{
  return c->n_frames > 0 ? c->occupancy_sum / (double)c->n_frames : 0.0;
}

double track_gate_um(const track_opts *o, double occupancy)
{
  const double g = o->link.gate_um;
  if (!o->gate_auto || !(occupancy > TRACK_CROWD_OCC)) return g;
  /* The gate, too, meets other objects in a crowd. Flow 100 ms, seeds
   * 1-8, mean alpha with the crowded frames' view support and rescue,
   * gate 6 um -> 6 - 200 x (occupancy - 0.03) um, at least 4: 60 beads
   * 0.694 -> 0.692, 80 beads 0.560 -> 0.579, 100 beads 0.529 -> 0.548,
   * 120 beads 0.477 -> 0.497, 150 beads 0.381 -> 0.399; twice as steep
   * (4 um from 3.5 %) 0.689 / 0.587 / 0.549 / 0.497 / 0.399
   * (docs/tracker.md "Crowded frames"). */
  const double h = g - TRACK_GATE_PER_OCC_UM * (occupancy - TRACK_CROWD_OCC);
  return h > TRACK_GATE_MIN_UM ? h : TRACK_GATE_MIN_UM;
}

/* Worker thread: detect the peaks of the slot's volume into its buffer,
 * drop the peaks too few views see (the view-support test), then place
 * each from its images in the views (the view fit). */
elfm_status track_detect_worker(const elfm_volume *v, const elfm_frame *frame,
                                const elfm_refocus_plan *plan, int slot, int thread, void *user,
                                elfm_error *err)
{
  track_ctx *c = user;
  /* v's voxels may be coarser (--bin-px); the view fits' are c->geo's */
  const elfm_volume *g = &c->geo;
  double t0 = cli_now_s();
  elfm_detection *det = c->det + (size_t)slot * c->o->max_det;
  elfm_status st = elfm_peaks_detect(c->pk[thread], v, det, c->o->max_det, &c->sp[slot].n, err);
  c->sp[slot].rej = 0;
  c->sp[slot].explained = 0;
  c->sp[slot].loc = 0;
  c->sp[slot].deep_dropped = 0;
  memset(c->sp[slot].view_miss, 0, TRACK_VIEW_SUMS * (size_t)c->calib->n_views * sizeof *c->sp[slot].view_miss);
  c->sp[slot].fits = c->sp[slot].tries = 0;
  c->sp[slot].occupancy = 0;
  c->sp[slot].need = 0;
  c->slot_frame[slot] = frame;
  c->slot_plan[slot] = plan;
  /* how crowded the frame is: for the view support, the rescue and the
   * blur's judgement */
  if (st == ELFM_OK &&
      (c->o->view_support_auto || c->o->blur_auto || c->o->rescue_auto || c->o->gate_auto))
    c->sp[slot].occupancy = elfm_refocus_occupancy(plan, frame);
  if (st == ELFM_OK && c->o->view_support > 0) {
    /* A bead at the peak puts signal in most of the views that sample
     * its voxel; a ghost (other beads' images lining up) in a few. On the
     * flow scene at threshold 20, 91 % of ghost peaks had signal in fewer
     * than 30 % of their views, against 2.7 % of true peaks (13 % of
     * those deeper than 50 um, whose sparse events miss some views):
     * docs/tracker.md "View support". The voxel is the refined position's
     * nearest. In a crowded frame more views see other objects' images
     * by chance, and a peak needs more (track_view_support_need). */
    const double share = track_view_support_need(c->o, c->sp[slot].occupancy);
    c->sp[slot].need = share;
    const int n_peaks = c->sp[slot].n;
    unsigned char *keep = c->keep + (size_t)slot * c->o->max_det;
    for (int i = 0; i < n_peaks; i++) {
      const int X = (int)lround(elfm_volume_x_vox(g, det[i].x_um));
      const int Y = (int)lround(elfm_volume_y_vox(g, det[i].y_um));
      const int K = (int)lround(elfm_volume_z_vox(g, det[i].z_um));
      int ns = 0;
      int n = elfm_refocus_view_support(plan, frame, X, Y, K, &ns);
      const double need = share * ns;
      if ((double)n >= need && n > 0 && c->o->explain_brighter > 0) {
        const int nu = explained_support(c, g, plan, frame, det, n_peaks, i, X, Y, K, n);
        if (!((double)nu >= need && nu > 0)) c->sp[slot].explained++;
        n = nu;
      }
      keep[i] = (double)n >= need && n > 0;
    }
    /* after: the tests above read every peak of the frame */
    int kept = 0;
    for (int i = 0; i < n_peaks; i++)
      if (keep[i]) det[kept++] = det[i];
    c->sp[slot].rej = n_peaks - kept;
    c->sp[slot].n = kept;
  }
  /* --bin-px: after the view support, which leaves some 70 % of a binned
   * flow's peaks out (their own voxels are enough to judge them) */
  if (st == ELFM_OK && c->vplan) track_bin_refine(c, plan, frame, thread, det, c->sp[slot].n);
  if (st == ELFM_OK && c->o->localize_views) {
    /* The peak fit reads three voxels per axis of a volume that averages
     * the views; the view fit measures the object's image in each view
     * and solves for the one (x, y, z) they all imply (recon/localize.c).
     * With the guided view fit: lateral RMSE blink 0.58 -> 0.17 um (beads
     * at rest), stage x 0.44 -> 0.29 um and speed error 0.71 % -> 0.50 %,
     * flow (8 seeds) x 0.46 -> 0.41 um and z 1.18 -> 0.99 um, alpha 0.702
     * -> 0.733 (docs/tracker.md "View fit"). Where the fit fails (too few
     * views agree), the peak fit stays; but a peak only the depth-scaled
     * threshold let in needs deep_peak_views views agreeing or goes: the
     * ghosts of deep beads' overlapping images sit at that level too, and
     * few views agree on them (docs/tracker.md "Deep peaks"). */
    elfm_localize_options deep = c->o->loc;
    const int deep_test = c->o->deep_peak_views > 0;
    if (deep_test) deep.min_views = c->o->deep_peak_views;
    int n = 0;
    unsigned char *fitok = c->fitok ? c->fitok + (size_t)slot * c->o->max_det : NULL;
    double miss[2 * ELFM_MAX_VIEWS], wt[ELFM_MAX_VIEWS];
    for (int i = 0; i < c->sp[slot].n; i++) {
      elfm_localize_result r;
      const int is_deep = deep_test && det[i].deep_only;
      /* the plain view fit, which also says where each view's image lay:
       * the views' check (cmd_track_views.c) */
      c->sp[slot].tries++;
      if (!elfm_refocus_localize_misses(plan, frame, elfm_volume_x_vox(g, det[i].x_um),
                                        elfm_volume_y_vox(g, det[i].y_um),
                                        elfm_volume_z_vox(g, det[i].z_um), is_deep ? &deep : &c->o->loc,
                                        &r, miss, wt)) {
        if (is_deep) {
          c->sp[slot].deep_dropped++;
        } else {
          if (fitok) fitok[n] = 0; /* kept at its peak fit */
          det[n++] = det[i];
        }
        continue;
      }
      det[n] = det[i];
      det[n].x_um = elfm_volume_x_um(g, r.x_vox);
      det[n].y_um = elfm_volume_y_um(g, r.y_vox);
      det[n].z_um = elfm_volume_z_um(g, r.z_vox);
      det[n].fit_sd_px = r.sd_px;
      if (fitok) fitok[n] = 1;
      n++;
      c->sp[slot].loc++;
      const double at_um[3] = {det[n - 1].x_um, det[n - 1].y_um, det[n - 1].z_um};
      track_views_add(&c->sp[slot], c->calib, at_um, miss, wt);
    }
    c->sp[slot].n = n;
    if (c->o->localize_near_um > 0) near_refit(c, g, slot, det, n, &deep, deep_test);
  }
  c->sp[slot].s = cli_now_s() - t0;
  return st;
}

/* Each detection's distance to the nearest other one of its frame, in the
 * linker's metric (dz / kz), into nearest_um (0 when alone): sorted by x,
 * each scans outwards while |dx| can still beat its best. Why: where two
 * objects come close, tracks may exchange them, and a user without ground
 * truth needs to know where. With the linker's claims and the gap frames
 * it points at 92-98 % of the exchanges of beads between tracks in 40-52 %
 * of the tracks' stretches (flow, flow_random; docs/tracker.md "Where
 * identities are uncertain"). */
typedef struct xkey {
  double x;
  int i;
} xkey;

static int cmp_xkey_x(const void *a, const void *b)
{
  const double xa = ((const xkey *)a)->x, xb = ((const xkey *)b)->x;
  return (xa > xb) - (xa < xb);
}

static elfm_status track_nearest(elfm_detection *det, int n, double kz, elfm_error *err)
{
  for (int i = 0; i < n; i++) det[i].nearest_um = 0;
  if (n < 2) return ELFM_OK;
  xkey *k = malloc((size_t)n * sizeof *k);
  if (!k) return elfm_error_set(err, ELFM_ERR_NOMEM, NULL, -1, "out of memory (nearest)");
  for (int i = 0; i < n; i++) k[i] = (xkey){det[i].x_um, i};
  qsort(k, (size_t)n, sizeof *k, cmp_xkey_x);
  for (int a = 0; a < n; a++) {
    const elfm_detection *p = &det[k[a].i];
    double best2 = INFINITY;
    for (int dir = -1; dir <= 1; dir += 2)
      for (int b = a + dir; b >= 0 && b < n; b += dir) {
        const double dx = k[b].x - k[a].x;
        if (dx * dx >= best2) break;
        const elfm_detection *q = &det[k[b].i];
        const double dy = q->y_um - p->y_um, dz = (q->z_um - p->z_um) / kz;
        const double d2 = dx * dx + dy * dy + dz * dz;
        if (d2 < best2) best2 = d2;
      }
    /* a twin at the same place: a hair above 0, which means "measured" */
    det[k[a].i].nearest_um = isfinite(best2) ? fmax(sqrt(best2), 1e-6) : 0;
  }
  free(k);
  return ELFM_OK;
}

/* Calling thread, frame order: link the slot's detections, write them. */
elfm_status track_on_volume(const elfm_volume *v, int slot, void *user, elfm_error *err)
{
  track_ctx *c = user;
  const track_opts *o = c->o;
  if (!c->have_first) {
    c->have_first = 1;
    c->first_frame = v->frame;
    c->first_t_us = v->t_us;
  }
  /* lit: an edge in this frame or the one before (a 1 ms pulse starting
   * late in a window ends in the next) */
  const int edge = v->n_triggers > c->n_triggers;
  c->cur_lit = edge || c->prev_had_edge;
  if (c->cur_lit) {
    c->n_lit_frames++;
    c->lit_events += (double)v->n_events;
    c->lit_events2 += (double)v->n_events * (double)v->n_events;
  } else {
    c->n_dark_frames++;
    c->dark_events += (double)v->n_events;
    c->dark_events2 += (double)v->n_events * (double)v->n_events;
  }
  c->prev_had_edge = edge;
  c->n_triggers = v->n_triggers;
  elfm_detection *det = c->det + (size_t)slot * o->max_det;
  int n = c->sp[slot].n;
  c->t_peaks += c->sp[slot].s;
  c->n_support_rejected += c->sp[slot].rej;
  c->n_explained += c->sp[slot].explained;
  c->n_localized += c->sp[slot].loc;
  track_views_merge(c, slot);
  c->n_deep_dropped += c->sp[slot].deep_dropped;
  c->occupancy_sum += c->sp[slot].occupancy;
  if (c->sp[slot].occupancy > TRACK_CROWD_OCC) c->n_crowded++;
  if (c->sp[slot].need > c->o->view_support) c->n_need_raised++;
  if (c->sp[slot].need > c->need_max) c->need_max = c->sp[slot].need;
  if (c->votes.vel && !c->votes.judged) { /* the detector's peaks, before any search by tracks */
    for (int j = 0; j < n; j++) track_votes_point(&c->votes, &det[j]);
    track_votes_end_frame(&c->votes, v->t_us);
  }
  double t1 = cli_now_s();
  elfm_status st = track_guided_search(c, v, slot, det, &n, err);
  if (st != ELFM_OK) return st;
  st = track_nearest(det, n, o->link.kz, err);
  if (st != ELFM_OK) return st;
  if (o->rescue_auto &&
      (st = elfm_link_set_rescue_gate_factor(c->lk, track_rescue_factor(o, c->sp[slot].occupancy), err)) !=
          ELFM_OK)
    return st;
  if (o->gate_auto &&
      (st = elfm_link_set_gate_um(c->lk, track_gate_um(o, c->sp[slot].occupancy), err)) != ELFM_OK)
    return st;
  st = track_fill_keep(c, c->slot_frame[slot], v->frame, err);
  if (st != ELFM_OK) return st;
  st = elfm_link_step(c->lk, v->frame, v->t_us, det, n, err);
  if (st != ELFM_OK) return st;
  st = track_fill_gaps(c, 0, err);
  /* frames no longer kept take no more fills: write their detections */
  if (st == ELFM_OK && c->ring.cap) st = track_det_flush_before(c, v->frame - c->ring.cap + 1, err);
  if (st != ELFM_OK) return st;
  c->t_link += cli_now_s() - t1;
  /* after linking: the lag correction (when on) has moved the detections,
   * and trail peaks (id -2) and weak peaks that joined no track (-3) are
   * left out */
  int kept = 0, n_rigid = 0, n_watch = 0;
  double vnow[3], span_ms;
  for (int j = 0; j < n; j++) {
    int64_t id = elfm_link_last_track_id(c->lk, j);
    if (id == -2 || id == -3) continue;  /* trail; weak joining no track */
    if (o->stage_watch) { /* a settled run: no test for a stage uses rigid_v */
      const double sp = elfm_link_last_speed(c->lk, j);
      if (isfinite(sp)) c->rigid_v[n_watch++] = sp;
    }
    track_width_add(c, &det[j]);
    track_height_add(c, &det[j]);
    /* the first peaks' speed: for auto's choices, and for --repr lin under
     * the LED's windows, found (start_auto) or given */
    if ((o->blur_auto || o->dt_auto || o->repr_auto ||
         (track_lin_choosable(o) && (o->start_auto || track_led_windows(o))))) {
      if (!c->auto_decided) track_speed_add(c, elfm_link_last_speed(c->lk, j));
      if (!c->miss_decided) track_miss_add(c, &det[j], elfm_link_last_miss_um(c->lk, j));
    }
    if (o->motion_auto && !c->rigid_decided &&
        elfm_link_last_velocity(c->lk, j, vnow, c->rigid_v + 3 * (size_t)n_rigid, &span_ms) >=
            (track_led_windows(o) ? TRACK_RIGID_LED_MIN_POINTS : TRACK_RIGID_MIN_POINTS) &&
        span_ms >= TRACK_RIGID_MIN_SPAN_MS && isfinite(c->rigid_v[3 * n_rigid]) &&
        isfinite(c->rigid_v[3 * n_rigid + 1]) && isfinite(c->rigid_v[3 * n_rigid + 2]))
      n_rigid++;
    double vj[3];  /* the velocity of the track it joined: its motion bias */
    const size_t np = elfm_link_last_velocity(c->lk, j, vj, NULL, NULL);
    st = track_det_emit(c, v->frame, &det[j], id, np >= 2 ? vj : NULL, err);
    if (st != ELFM_OK) return st;
    kept++;
  }
  if (o->resolution && v->frame % 10 == 0 && n > 0) {
    int m = 0;
    /* isolation 3 x the paper's lateral FWHM of 3.9 um */
    st = elfm_analysis_fwhm(v, det, n, 12.0, c->fw, o->max_det, &m, err);
    if (st != ELFM_OK) return st;
    for (int k = 0; k < m; k++) {
      /* the speed of the track the bead belongs to: find its detection */
      double speed = NAN;
      for (int j = 0; j < n; j++)
        if (det[j].x_um == c->fw[k].x_um && det[j].y_um == c->fw[k].y_um &&
            det[j].z_um == c->fw[k].z_um) {
          speed = elfm_link_last_speed(c->lk, j);
          break;
        }
      if (c->fl.n < 1000000) {  /* a million samples is plenty for a median */
        st = fwhm_push(&c->fl, c->fw[k].fwhm_xy_um, c->fw[k].fwhm_z_um, speed, err);
        if (st != ELFM_OK) return st;
      }
    }
  }
  /* frames.csv: every frame's window, also those without a detection, so
   * that `score --frames` knows when each frame was (windows opened by
   * trigger edges are not evenly spaced) */
  if ((st = cli_frames_csv_row(c->ffr, c->p_fr, v, kept, err)) != ELFM_OK) return st;
  if ((st = elfm_frame_times_add(&c->frame_times, v->frame, v->t_us, err)) != ELFM_OK) return st;
  if (o->motion_auto) track_rigid_add_frame(c, c->rigid_v, n_rigid);
  if (o->stage_watch) track_stage_watch_frame(c, c->rigid_v, n_watch);
  c->n_frames++;
  c->n_det += kept;
  if (kept > 0) *(c->cur_lit ? &c->n_lit_peaked : &c->n_dark_peaked) += 1;
  c->last_frame = v->frame;
  c->last_t_us = v->t_us;
  if ((st = track_drain(c, 0, err)) != ELFM_OK) return st;
  /* Frame times no track can still ask for: before the earliest point the
   * linker holds, and before what gap filling may yet add (the kept
   * frames, and a new track's open start a whole gap before them). */
  int64_t keep = elfm_link_oldest_frame(c->lk);
  const int64_t back = v->frame - (int64_t)c->ring.cap - c->o->link.max_gap_frames - 1;
  elfm_frame_times_forget_before(&c->frame_times, back < keep ? back : keep);
  return ELFM_OK;
}

void track_ctx_free(track_ctx *c)
{
  elfm_track_store_clear(&c->stage_pending);
  elfm_refocus_plan_free(c->plan);
  elfm_refocus_plan_free(c->vplan);
  free(c->bin_piece);
  if (c->fdet) fclose(c->fdet);
  if (c->ftr) fclose(c->ftr);
  if (c->ffr) fclose(c->ffr);
  elfm_frame_times_free(&c->frame_times);
  elfm_link_free(c->lk);
  for (int t = 0; c->pk && t < c->n_threads; t++) elfm_peaks_free(c->pk[t]);
  free(c->pk);
  free(c->sp);
  track_finish_free(c);
  free(c->slot_frame);
  free(c->fitok);
  free(c->keep);
  free(c->near_fit);
  free(c->slot_plan);
  free(c->pred);
  free(c->pred_intensity);
  free(c->rigid_v);
  track_votes_free(&c->votes);
  elfm_track_xml_free(c->xml);
  free(c->info);
  free(c->det);
  free(c->fw);
  free(c->fl.b);
  track_fill_free(c);
}
