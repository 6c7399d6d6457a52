/* cmd_track.c — eventlfm track: events -> volumes -> detections -> linked,
 * smoothed 3D tracks, streaming (the recon driver calls back per volume in
 * frame order; finished tracks are smoothed and written as they end). */
#include <cjson/cJSON.h>
#include <errno.h>
#include <getopt.h>
#include <inttypes.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "cli.h"
#include "elfm_tracker.h"

enum { MOTION_AUTO = 0, MOTION_STAGE, MOTION_FREE };

typedef struct track_opts {
  const char *calib, *events, *out;
  elfm_recon_options recon;
  elfm_peaks_options peaks;
  elfm_link_options link;
  elfm_smooth_options smooth;
  int motion;
  int has_stage_v;
  double stage_v[3];
  int max_det;
  int lag_correct;
  int resolution;
  int views_rule;  /* threshold x (N/n)^views_exponent where n of N views sample a voxel */
  double views_exponent;
  int quiet;
  double max_outlier_frac;
  double guided_low;  /* track-guided search: min value near a prediction (0 = off) */
  double guided_radius_um;
  int guided_min_points;
  double view_support; /* a peak needs signal in this fraction of the views sampling it (0 = off) */
} track_opts;

/* Speed bins for the resolution figures (um/ms): static, slow, moderate, fast. */
#define N_SPEED_BINS 5
static const double speed_edges[N_SPEED_BINS] = {0, 0.05, 0.2, 0.5, 1e300};

typedef struct fwhm_list {
  size_t n, cap;
  double *xy, *z, *speed;
} fwhm_list;

typedef struct track_ctx {
  const track_opts *o;
  const elfm_calib *calib;
  /* Peak detection runs on the recon driver's worker threads (the worker
   * hook): one detector workspace per thread, one detection buffer per
   * batch slot, read back in frame order by the linking callback. */
  int n_threads, n_slots;
  elfm_peaks **pk;       /* [n_threads] */
  elfm_detection *det;   /* [n_slots][max_det] */
  int *det_n;            /* [n_slots] */
  double *det_s;         /* [n_slots] peak detection CPU time of the slot's volume */
  int *det_rej;          /* [n_slots] peaks dropped by the view-support test */
  double *pred;          /* [max_det][3] track predictions (guided search) */
  int have_first;
  elfm_track **fin;      /* finished tracks being smoothed (drain) */
  elfm_status *fin_st;
  elfm_error *fin_err;
  size_t fin_cap;
  elfm_linker *lk;
  FILE *fdet, *ftr;
  char p_det[1100], p_tr[1100];
  elfm_track_store store;
  int64_t n_support_rejected;
  int64_t n_frames, n_det, n_points_kept, n_rejected, n_rejected_stage, first_frame, last_frame;
  int64_t first_t_us, last_t_us;
  double t_peaks, t_link, t_smooth;
  elfm_fwhm *fw;
  fwhm_list fl;
  int vol_w, vol_h, vol_nz;
  double um_per_px, z_min_um, z_step_um;
} track_ctx;

static void track_defaults(track_opts *o);

static void usage(FILE *f)
{
  track_opts d;
  track_defaults(&d);
  fprintf(f,
    "usage: eventlfm track --calib calib.json --events FILE --out DIR [options]\n"
    "\n"
    "Events -> refocused volumes -> 3D peaks -> linked tracks -> Ceres-smoothed tracks.\n"
    "Writes DIR/detections.csv, tracks.csv (smoothed + raw), tracks_isbi.xml (ISBI 2012),\n"
    "tracks_trackmate.xml (TrackMate) and summary.json. Progress on stderr.\n"
    "\n"
    "recon (the same options as eventlfm recon's):\n");
  cli_recon_options_usage(f, &d.recon);
  fprintf(f,
    "                       (polarity on: OFF events trail moving beads; median 0\n"
    "                       and ghost none: the detector and linker reject ghosts;\n"
    "                       a batch's volumes are searched for peaks in parallel too)\n"
    "detection:\n"
    "  --threshold-k K      k x robust noise sigma (6), --threshold-abs V (50 on time\n"
    "                       surfaces), --threshold-rel F (0.35 of the maximum for counts)\n"
    "  --threshold-depth-um Z  absolute threshold / (1 + (z/Z)^2) (0 = same at all depths)\n"
    "  --threshold-min V    floor of that depth-scaled threshold\n"
    "  --threshold-low V    hysteresis: peaks above V but below the threshold may\n"
    "                       continue a track, never start one (30 with the default\n"
    "                       threshold, 0 = off)\n"
    "  --views-rule on|off  where n of the N views sample a voxel, a peak must exceed\n"
    "                       the threshold x (N/n)^E, --views-exponent E (default on, 0.5)\n"
    "  --view-support F     a peak needs signal in >= F of the views sampling its voxel\n"
    "                       (ghosts: a few views; default 0.3, 0 = off)\n"
    "  --radius-xy-um R, --radius-z-um R   local-maximum box (3, 15)\n"
    "  --min-separation-um D (4), --refine gauss|quad|none, --max-detections N (10000)\n"
    "linking:\n"
    "  --gate-um G (6), --max-gap N frames (50), --min-points N (5)\n"
    "  --lead-sigmas K      with --lag-correct: ON events lead a moving object by ~K x\n"
    "                       its width along the motion; move detections back by that\n"
    "  --link-kz K          axial scale of the linker's distance sqrt(dx2+dy2+(dz/K)2) (1.5)\n"
    "  --rescue-factor F    unmatched tracks retry leftovers within F x gate (2.5; 0 off)\n"
    "  --stitch-points N    a new track of N points continues a dark one when its points\n"
    "                       lie on that one's recent path (5; 0 off; --motion stage: 0)\n"
    "  --stitch-gate-um G   RMS distance to the dark track's path for that (8)\n"
    "  --swap-points N      review a gap closing that does not fit when its new tail\n"
    "                       has N points; exchange tails with a better fit (6; 0 off)\n"
    "  --weak-gate-um D     weak (hysteresis) peaks join a track only within D of its\n"
    "                       prediction (default 5; 0 = the track's gate)\n"
    "  --guided-low V       where a track of >= --guided-min-points N (10) points\n"
    "                       predicts its bead and no peak lies within the weak gate,\n"
    "                       take the local maximum above V within --guided-radius-um\n"
    "                       R (1.5, z x link-kz) as a weak peak (default 0 = off)\n"
    "  --lag-correct on|off  shift detections forward by the time-surface lag (off)\n"
    "smoothing:\n"
    "  --motion auto|stage|free   auto: model chosen per track (BIC) among constant\n"
    "                       velocity, constant acceleration and spline; stage: rigid\n"
    "                       motion (no spline; with a stage velocity, new tracks\n"
    "                       predict with it and tracks far from it are dropped);\n"
    "                       free: smoothing spline for all\n"
    "  --stage-velocity-um-per-ms vx,vy,vz   known stage velocity (summary compares)\n"
    "  --model auto|cv|ca|spline, --loss huber|cauchy|none, --spline-weight-ms3 W\n"
    "  --max-outlier-frac F drop tracks whose robust fit rejects more than F of\n"
    "                       their points (default 1/3)\n"
    "analysis:\n"
    "  --resolution         FWHM of isolated beads (every 10th frame) into summary.json\n"
    "  -q, --quiet          no progress\n"
    "  -h, --help           this text\n");
}

static int parse_vec3(const char *s, double v[3])
{
  char *end;
  for (int a = 0; a < 3; a++) {
    errno = 0;
    v[a] = strtod(s, &end);
    if (end == s || errno || !isfinite(v[a])) return 0;
    if (a < 2) {
      if (*end != ',') return 0;
      s = end + 1;
    }
  }
  return *end == 0;
}

static void progress(const elfm_recon_stats *s, void *user)
{
  const track_ctx *c = user;
  fprintf(stderr, "\reventlfm track: %.3f s of recording, %" PRId64 " volumes, %.0f volumes/s, "
                  "%zu live tracks   ",
          s->span_s, s->frames, s->volumes_per_s, elfm_link_n_live(c->lk));
}

/* Filter a smoothed track (st: its smoothing's status) and write it. */
static elfm_status finish_track(track_ctx *c, elfm_track *t, elfm_status st, elfm_error *err)
{
  /* A track whose points the robust fit mostly rejects is not one object
   * (ghosts joined across gaps: on the stage scene such tracks ran against
   * the stage and biased its velocity by 1 %). */
  if (st == ELFM_OK && (double)t->n_outliers > c->o->max_outlier_frac * (double)t->n) {
    c->n_rejected++;
    elfm_track_free(t);
    return ELFM_OK;
  }
  /* Rigid stage motion with a known velocity: a track moving otherwise
   * (more than 25 % of the stage speed + 0.1 um/ms off) is not part of the
   * sample (ghosts joined across gaps). */
  if (st == ELFM_OK && c->o->motion == MOTION_STAGE && c->o->has_stage_v) {
    double v[3], d2 = 0, s2 = 0;
    elfm_track_mean_velocity(t, v);
    for (int a = 0; a < 3; a++) {
      d2 += (v[a] - c->o->stage_v[a]) * (v[a] - c->o->stage_v[a]);
      s2 += c->o->stage_v[a] * c->o->stage_v[a];
    }
    if (sqrt(d2) > 0.25 * sqrt(s2) + 0.1) {
      c->n_rejected_stage++;
      elfm_track_free(t);
      return ELFM_OK;
    }
  }
  if (st == ELFM_OK) st = elfm_tracks_write_csv(c->ftr, c->p_tr, t, err);
  if (st != ELFM_OK) {
    elfm_track_free(t);
    return st;
  }
  c->n_points_kept += (int64_t)t->n;
  return elfm_track_store_add(&c->store, t, err);
}

/* Smooth, filter and write the tracks the linker has finished. Each track
 * is its own single-threaded Ceres problem, so when several finish at once
 * (most of them at the end of the recording) they are smoothed in parallel;
 * filtering and writing stay in the linker's order, so the output does not
 * depend on the thread count. */
static elfm_status drain(track_ctx *c, elfm_error *err)
{
  size_t n = 0;
  elfm_track *t;
  elfm_status st = ELFM_OK;
  while ((t = elfm_link_pop_finished(c->lk))) {
    if (n == c->fin_cap) {
      size_t cap = c->fin_cap ? 2 * c->fin_cap : 64;
      elfm_track **a = realloc(c->fin, cap * sizeof *a);
      elfm_status *b = realloc(c->fin_st, cap * sizeof *b);
      elfm_error *e = realloc(c->fin_err, cap * sizeof *e);
      if (a) c->fin = a;
      if (b) c->fin_st = b;
      if (e) c->fin_err = e;
      if (!a || !b || !e) {
        elfm_track_free(t);
        st = elfm_error_set(err, ELFM_ERR_NOMEM, NULL, -1, "out of memory (finished tracks)");
        break;
      }
      c->fin_cap = cap;
    }
    c->fin[n++] = t;
  }
  double t0 = cli_now_s();
  const elfm_smooth_options *so = &c->o->smooth;
  const int nt = n > 1 && c->n_threads > 1 ? c->n_threads : 1;
#pragma omp parallel for num_threads(nt) schedule(dynamic, 1) if (nt > 1)
  for (size_t i = 0; i < n; i++) c->fin_st[i] = elfm_track_smooth(c->fin[i], so, &c->fin_err[i]);
  c->t_smooth += cli_now_s() - t0;
  for (size_t i = 0; i < n; i++) {
    if (st == ELFM_OK) {
      if (c->fin_st[i] != ELFM_OK && err) *err = c->fin_err[i];
      st = finish_track(c, c->fin[i], c->fin_st[i], err);
    } else {
      elfm_track_free(c->fin[i]);
    }
  }
  return st;
}

static elfm_status fwhm_push(fwhm_list *l, double xy, double z, double speed, elfm_error *err)
{
  if (l->n == l->cap) {
    size_t cap = l->cap ? 2 * l->cap : 1024;
    double *a = realloc(l->xy, cap * sizeof *a);
    if (a) l->xy = a;
    double *b = realloc(l->z, cap * sizeof *b);
    if (b) l->z = b;
    double *s = realloc(l->speed, cap * sizeof *s);
    if (s) l->speed = s;
    if (!a || !b || !s) return elfm_error_set(err, ELFM_ERR_NOMEM, NULL, -1, "out of memory");
    l->cap = cap;
  }
  l->xy[l->n] = xy;
  l->z[l->n] = z;
  l->speed[l->n] = speed;
  l->n++;
  return ELFM_OK;
}

/* Detectors and buffers for the driver's layout, before the run: the
 * volume geometry comes from a plan of the same calibration and options as
 * the one refocusing. With the views rule, the views sampling each voxel
 * (elfm_peaks_set_view_counts) are counted once and copied to each detector. */
static elfm_status peaks_setup(track_ctx *c, elfm_error *err)
{
  const track_opts *o = c->o;
  elfm_status s = elfm_recon_layout(&o->recon, &c->n_threads, &c->n_slots, err);
  if (s != ELFM_OK) return s;
  c->pk = calloc((size_t)c->n_threads, sizeof *c->pk);
  c->det = malloc((size_t)c->n_slots * (size_t)o->max_det * sizeof *c->det);
  c->det_n = calloc((size_t)c->n_slots, sizeof *c->det_n);
  c->det_s = calloc((size_t)c->n_slots, sizeof *c->det_s);
  c->det_rej = calloc((size_t)c->n_slots, sizeof *c->det_rej);
  c->pred = malloc((size_t)o->max_det * 3 * sizeof *c->pred);
  if (!c->pk || !c->det || !c->det_n || !c->det_s || !c->det_rej || !c->pred)
    return elfm_error_set(err, ELFM_ERR_NOMEM, NULL, -1, "out of memory (detections)");
  elfm_refocus_plan *plan = NULL;
  s = elfm_refocus_plan_create(c->calib, &o->recon.refocus, &plan, err);
  if (s != ELFM_OK) return s;
  elfm_volume *v = elfm_refocus_volume_create(plan, err);
  uint8_t *cnt = NULL;
  if (!v) s = err ? err->code : ELFM_ERR_NOMEM;
  if (s == ELFM_OK && o->views_rule) {
    size_t nvox = (size_t)v->w * v->h * v->nz;
    cnt = malloc(nvox);
    if (!cnt) s = elfm_error_set(err, ELFM_ERR_NOMEM, NULL, -1, "out of memory (view counts)");
    else
      for (int k = 0; k < v->nz; k++)
        for (int Y = 0; Y < v->h; Y++)
          for (int X = 0; X < v->w; X++)
            cnt[((size_t)k * v->h + Y) * v->w + X] = (uint8_t)elfm_refocus_plan_views_at(plan, X, Y, k);
  }
  for (int t = 0; s == ELFM_OK && t < c->n_threads; t++) {
    c->pk[t] = elfm_peaks_create(&o->peaks, v->w, v->h, v->nz, err);
    if (!c->pk[t]) s = err ? err->code : ELFM_ERR_INVALID;
    else if (cnt)
      s = elfm_peaks_set_view_counts(c->pk[t], cnt, c->calib->n_views, o->views_exponent, err);
  }
  free(cnt);
  elfm_volume_free(v);
  elfm_refocus_plan_free(plan);
  return s;
}

/* Worker thread: detect the peaks of the slot's volume into its buffer,
 * then drop the peaks too few views see (the view-support test). */
static elfm_status detect_worker(const elfm_volume *v, const elfm_frame *frame,
                                 const elfm_refocus_plan *plan, int slot, int thread, void *user,
                                 elfm_error *err)
{
  track_ctx *c = user;
  double t0 = cli_now_s();
  elfm_detection *det = c->det + (size_t)slot * c->o->max_det;
  elfm_status st = elfm_peaks_detect(c->pk[thread], v, det, c->o->max_det, &c->det_n[slot], err);
  c->det_rej[slot] = 0;
  if (st == ELFM_OK && c->o->view_support > 0) {
    /* A bead at the peak puts signal in most of the views that sample
     * its voxel; a ghost (other beads' images lining up) in a few. On the
     * flow scene at threshold 20, 91 % of ghost peaks had signal in fewer
     * than 30 % of their views, against 2.7 % of true peaks (13 % of
     * those deeper than 50 um, whose sparse events miss some views):
     * docs/tracker.md "View support". The voxel is the refined position's
     * nearest. */
    int kept = 0;
    for (int i = 0; i < c->det_n[slot]; i++) {
      const int X = (int)lround(elfm_volume_x_vox(v, det[i].x_um));
      const int Y = (int)lround(elfm_volume_y_vox(v, det[i].y_um));
      const int K = (int)lround(elfm_volume_z_vox(v, det[i].z_um));
      int ns = 0;
      const int n = elfm_refocus_view_support(plan, frame, X, Y, K, &ns);
      if ((double)n >= c->o->view_support * ns && n > 0) det[kept++] = det[i];
    }
    c->det_rej[slot] = c->det_n[slot] - kept;
    c->det_n[slot] = kept;
  }
  c->det_s[slot] = cli_now_s() - t0;
  return st;
}

/* Calling thread, frame order: link the slot's detections, write them. */
static elfm_status on_volume(const elfm_volume *v, int slot, void *user, elfm_error *err)
{
  track_ctx *c = user;
  const track_opts *o = c->o;
  if (!c->have_first) {
    c->have_first = 1;
    c->vol_w = v->w;
    c->vol_h = v->h;
    c->vol_nz = v->nz;
    c->um_per_px = v->um_per_px;
    c->z_min_um = v->z_min_um;
    c->z_step_um = v->z_step_um;
    c->first_frame = v->frame;
    c->first_t_us = v->t_us;
  }
  elfm_detection *det = c->det + (size_t)slot * o->max_det;
  int n = c->det_n[slot];
  c->t_peaks += c->det_s[slot];
  c->n_support_rejected += c->det_rej[slot];
  double t1 = cli_now_s();
  if (o->guided_low > 0 && o->link.weak_gate_um > 0) {
    /* Track-guided search: where an established track expects its bead
     * and no peak lies within the weak gate, take the local maximum above
     * guided_low there (weak: it can only continue that track). Deep beads
     * fade below the global threshold (25-55 on the surface, docs). */
    int np = 0;
    elfm_status sp = elfm_link_predict(c->lk, v->frame, v->t_us, o->guided_min_points, c->pred, o->max_det, &np, err);
    if (sp != ELFM_OK) return sp;
    const double g = o->link.weak_gate_um, kz = o->link.kz, gs = o->guided_radius_um;
    for (int k = 0; k < np && n < o->max_det; k++) {
      const double *q = c->pred + 3 * (size_t)k;
      int near = 0;
      for (int j = 0; j < n && !near; j++) {
        double dx = det[j].x_um - q[0], dy = det[j].y_um - q[1], dz = (det[j].z_um - q[2]) / kz;
        near = dx * dx + dy * dy + dz * dz < g * g;
      }
      if (near) continue;
      int found = 0;
      sp = elfm_peaks_find_near(c->pk[0], v, q, gs, gs * kz, o->guided_low, &det[n], &found, err);
      if (sp != ELFM_OK) return sp;
      n += found;
    }
  }
  elfm_status st = elfm_link_step(c->lk, v->frame, v->t_us, det, n, err);
  if (st != ELFM_OK) return st;
  c->t_link += cli_now_s() - t1;
  /* after linking: the lag correction (when on) has moved the detections,
   * and trail peaks (id -2) and weak peaks that joined no track (-3) are
   * left out */
  int kept = 0;
  for (int j = 0; j < n; j++) {
    int64_t id = elfm_link_last_track_id(c->lk, j);
    if (id == -2 || id == -3) continue;  /* trail; weak joining no track */
    st = elfm_detections_write(c->fdet, c->p_det, &det[j], 1, err);
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
  c->n_frames++;
  c->n_det += kept;
  c->last_frame = v->frame;
  c->last_t_us = v->t_us;
  return drain(c, err);
}

static cJSON *vec3(const double v[3])
{
  cJSON *a = cJSON_CreateArray();
  for (int k = 0; k < 3; k++) cJSON_AddItemToArray(a, cJSON_CreateNumber(isfinite(v[k]) ? v[k] : 0));
  return a;
}

static void add_num(cJSON *o, const char *k, double v)
{
  if (isfinite(v)) cJSON_AddNumberToObject(o, k, v);
  else cJSON_AddNullToObject(o, k);
}

static cJSON *fwhm_summary(fwhm_list *l)
{
  cJSON *r = cJSON_CreateObject();
  double *tmp = malloc((l->n ? l->n : 1) * sizeof *tmp);
  if (!tmp) return r;
  double med, spr;
  cJSON_AddNumberToObject(r, "n_beads", (double)l->n);
  memcpy(tmp, l->xy, l->n * sizeof *tmp);
  elfm_analysis_median(tmp, l->n, &med, &spr);
  add_num(r, "fwhm_xy_um_median", med);
  add_num(r, "fwhm_xy_um_spread", spr);
  memcpy(tmp, l->z, l->n * sizeof *tmp);
  elfm_analysis_median(tmp, l->n, &med, &spr);
  add_num(r, "fwhm_z_um_median", med);
  add_num(r, "fwhm_z_um_spread", spr);
  cJSON *bins = cJSON_AddArrayToObject(r, "by_speed");
  for (int b = 0; b + 1 < N_SPEED_BINS; b++) {
    size_t m = 0;
    for (size_t i = 0; i < l->n; i++)
      if (l->speed[i] >= speed_edges[b] && l->speed[i] < speed_edges[b + 1]) tmp[m++] = l->xy[i];
    cJSON *o = cJSON_CreateObject();
    cJSON_AddNumberToObject(o, "speed_min_um_per_ms", speed_edges[b]);
    add_num(o, "speed_max_um_per_ms", b + 2 < N_SPEED_BINS ? speed_edges[b + 1] : NAN);
    cJSON_AddNumberToObject(o, "n_beads", (double)m);
    elfm_analysis_median(tmp, m, &med, &spr);
    add_num(o, "fwhm_xy_um_median", med);
    m = 0;
    for (size_t i = 0; i < l->n; i++)
      if (l->speed[i] >= speed_edges[b] && l->speed[i] < speed_edges[b + 1]) tmp[m++] = l->z[i];
    elfm_analysis_median(tmp, m, &med, &spr);
    add_num(o, "fwhm_z_um_median", med);
    cJSON_AddItemToArray(bins, o);
  }
  free(tmp);
  return r;
}

static int write_summary(track_ctx *c, const elfm_recon_stats *rs, double wall_s, const char *path,
                         const elfm_error *input_err, elfm_error *err)
{
  const track_opts *o = c->o;
  cJSON *j = cJSON_CreateObject();
  cJSON_AddStringToObject(j, "events", o->events);
  cJSON_AddStringToObject(j, "calib", o->calib);
  if (input_err) {
    /* The run stopped at a bad input: the counts are of what was read. */
    char msg[1200];
    cJSON_AddStringToObject(j, "input_error", elfm_error_format(input_err, msg, sizeof msg));
  }
  cJSON *cnt = cJSON_AddObjectToObject(j, "counts");
  cJSON_AddNumberToObject(cnt, "events", (double)rs->events);
  cJSON_AddNumberToObject(cnt, "volumes", (double)c->n_frames);
  cJSON_AddNumberToObject(cnt, "detections", (double)c->n_det);
  cJSON_AddNumberToObject(cnt, "peaks_rejected_view_support", (double)c->n_support_rejected);
  cJSON_AddNumberToObject(cnt, "tracks_started", (double)elfm_link_n_started(c->lk));
  cJSON_AddNumberToObject(cnt, "tracks", (double)c->store.n);
  cJSON_AddNumberToObject(cnt, "tracks_rejected_outliers", (double)c->n_rejected);
  cJSON_AddNumberToObject(cnt, "tracks_rejected_off_stage", (double)c->n_rejected_stage);
  cJSON_AddNumberToObject(cnt, "track_points", (double)c->n_points_kept);
  int nm[5] = {0, 0, 0, 0, 0};
  for (size_t i = 0; i < c->store.n; i++) nm[c->store.tracks[i]->model]++;
  cJSON *models = cJSON_AddObjectToObject(cnt, "models");
  for (int m = 1; m < 5; m++)
    cJSON_AddNumberToObject(models, elfm_motion_model_name((elfm_motion_model)m), nm[m]);

  cJSON *par = cJSON_AddObjectToObject(j, "parameters");
  const elfm_framer_options *fo = &o->recon.framer;
  cJSON_AddNumberToObject(par, "dt_us", (double)fo->dt_us);
  cJSON_AddNumberToObject(par, "stride_us", (double)(fo->stride_us ? fo->stride_us : fo->dt_us));
  cJSON_AddNumberToObject(par, "tau_us", fo->tau_us);
  cJSON_AddStringToObject(par, "repr", cli_repr_name(fo->repr));
  cJSON_AddStringToObject(par, "polarity", cli_polarity_name(fo->polarity));
  cJSON_AddNumberToObject(par, "median", o->recon.median);
  cJSON_AddStringToObject(par, "path", cli_refocus_path_name(o->recon.refocus.path));
  cJSON_AddStringToObject(par, "ghost_threshold", cli_ghost_threshold_name(o->recon.refocus.threshold));
  cJSON_AddNumberToObject(par, "ghost_threshold_value", o->recon.refocus.threshold_value);
  cJSON_AddNumberToObject(par, "ghost_agree_frac", o->recon.refocus.agree_frac);
  cJSON_AddNumberToObject(par, "view_support", o->view_support);
  cJSON_AddNumberToObject(par, "threshold_k_sigma", o->peaks.k_sigma);
  cJSON_AddNumberToObject(par, "threshold_abs", o->peaks.absolute);
  cJSON_AddNumberToObject(par, "threshold_rel", o->peaks.relative);
  cJSON_AddNumberToObject(par, "threshold_depth_um", o->peaks.depth_range_um);
  cJSON_AddNumberToObject(par, "threshold_min", o->peaks.absolute_min);
  cJSON_AddNumberToObject(par, "threshold_low", o->peaks.hysteresis_low);
  cJSON_AddBoolToObject(par, "views_rule", o->views_rule);
  cJSON_AddNumberToObject(par, "views_exponent", o->views_exponent);
  cJSON_AddNumberToObject(par, "rescue_gate_factor", o->link.rescue_gate_factor);
  cJSON_AddNumberToObject(par, "stitch_points", o->link.stitch_points);
  cJSON_AddNumberToObject(par, "stitch_gate_um", o->link.stitch_gate_um);
  cJSON_AddNumberToObject(par, "stitch_history", o->link.stitch_history);
  cJSON_AddNumberToObject(par, "swap_points", o->link.swap_points);
  cJSON_AddNumberToObject(par, "swap_ratio", o->link.swap_ratio);
  cJSON_AddNumberToObject(par, "weak_gate_um", o->link.weak_gate_um);
  cJSON_AddNumberToObject(par, "guided_low", o->guided_low);
  cJSON_AddNumberToObject(par, "guided_radius_um", o->guided_radius_um);
  cJSON_AddNumberToObject(par, "guided_min_points", o->guided_min_points);
  cJSON_AddNumberToObject(par, "lead_sigmas", o->link.lead_sigmas);
  cJSON_AddNumberToObject(par, "link_kz", o->link.kz);
  cJSON_AddNumberToObject(par, "radius_xy_um", o->peaks.radius_xy_um);
  cJSON_AddNumberToObject(par, "radius_z_um", o->peaks.radius_z_um);
  cJSON_AddNumberToObject(par, "min_separation_um", o->peaks.min_separation_um);
  cJSON_AddNumberToObject(par, "gate_um", o->link.gate_um);
  cJSON_AddNumberToObject(par, "max_gap_frames", o->link.max_gap_frames);
  cJSON_AddNumberToObject(par, "min_points", o->link.min_points);
  cJSON_AddNumberToObject(par, "max_outlier_frac", o->max_outlier_frac);
  cJSON_AddBoolToObject(par, "lag_correct", o->lag_correct);
  cJSON_AddStringToObject(par, "motion", o->motion == MOTION_STAGE ? "stage"
                                         : o->motion == MOTION_FREE ? "free" : "auto");
  cJSON_AddStringToObject(par, "model", elfm_motion_model_name(o->smooth.model));
  cJSON_AddStringToObject(par, "loss", o->smooth.loss == ELFM_LOSS_HUBER ? "huber"
                                       : o->smooth.loss == ELFM_LOSS_CAUCHY ? "cauchy" : "none");
  if (o->has_stage_v) cJSON_AddItemToObject(par, "stage_velocity_um_per_ms", vec3(o->stage_v));

  cJSON *tim = cJSON_AddObjectToObject(j, "timing");
  add_num(tim, "wall_s", wall_s);
  add_num(tim, "span_s", rs->span_s);
  add_num(tim, "events_per_s", rs->wall_s > 0 ? (double)rs->events / wall_s : NAN);
  add_num(tim, "volumes_per_s", wall_s > 0 ? (double)c->n_frames / wall_s : NAN);
  add_num(tim, "realtime_factor", wall_s > 0 ? rs->span_s / wall_s : NAN);
  add_num(tim, "peak_rss_mb", cli_peak_rss_mb());
  /* recon_s: the driver without the ordered callback (linking, writing,
   * smoothing); it contains peak detection, which runs on the workers.
   * peaks_s is that detection's time summed over the workers (CPU s). */
  add_num(tim, "recon_s", rs->wall_s - rs->callback_s);
  add_num(tim, "read_s", rs->read_s);
  add_num(tim, "frame_s", rs->frame_s);
  add_num(tim, "parallel_s", rs->refocus_s);
  add_num(tim, "callback_s", rs->callback_s);
  add_num(tim, "peaks_s", c->t_peaks);
  add_num(tim, "link_s", c->t_link);
  add_num(tim, "smooth_s", c->t_smooth);

  if (c->store.n) {
    elfm_stage_result sr;
    if (elfm_analysis_stage(&c->store, o->has_stage_v ? o->stage_v : NULL, &sr, err) == ELFM_OK) {
      cJSON *st = cJSON_AddObjectToObject(j, "stage");
      cJSON_AddItemToObject(st, "velocity_um_per_ms", vec3(sr.v_um_per_ms));
      cJSON_AddItemToObject(st, "velocity_sd_um_per_ms", vec3(sr.v_sd_um_per_ms));
      add_num(st, "speed_um_per_ms", sr.speed_um_per_ms);
      add_num(st, "speed_sd_um_per_ms", sr.speed_sd_um_per_ms);
      add_num(st, "rel_error", sr.rel_error);
      add_num(st, "speed_rel_error", sr.speed_rel_error);
    }
  }
  if (o->resolution) cJSON_AddItemToObject(j, "resolution", fwhm_summary(&c->fl));

  cJSON *tr = cJSON_AddArrayToObject(j, "tracks");
  for (size_t i = 0; i < c->store.n; i++) {
    const elfm_track *t = c->store.tracks[i];
    cJSON *e = cJSON_CreateObject();
    double v[3];
    elfm_track_mean_velocity(t, v);
    cJSON_AddNumberToObject(e, "id", (double)t->id);
    cJSON_AddNumberToObject(e, "first_frame", (double)t->pts[0].frame);
    cJSON_AddNumberToObject(e, "last_frame", (double)t->pts[t->n - 1].frame);
    cJSON_AddNumberToObject(e, "points", (double)t->n);
    cJSON_AddStringToObject(e, "model", elfm_motion_model_name(t->model));
    if (t->model == ELFM_MODEL_SPLINE) cJSON_AddNumberToObject(e, "spline_weight_ms3", t->spline_weight_ms3);
    add_num(e, "edf", t->edf);
    cJSON_AddNumberToObject(e, "outliers", t->n_outliers);
    cJSON_AddItemToObject(e, "mean_velocity_um_per_ms", vec3(v));
    cJSON_AddItemToArray(tr, e);
  }
  char *text = cJSON_Print(j);
  cJSON_Delete(j);
  if (!text) return elfm_error_set(err, ELFM_ERR_NOMEM, path, -1, "cannot build summary.json");
  FILE *f = fopen(path, "w");
  elfm_status st = ELFM_OK;
  if (!f) st = elfm_error_set(err, ELFM_ERR_IO, path, -1, "cannot create: %s", strerror(errno));
  else {
    fputs(text, f);
    fputc('\n', f);
    if (ferror(f) | (fclose(f) != 0))
      st = elfm_error_set(err, ELFM_ERR_IO, path, -1, "write failed: %s", strerror(errno));
  }
  free(text);
  return st;
}

static int close_file(FILE **f, const char *path, elfm_error *err)
{
  if (!*f) return ELFM_OK;
  int bad = ferror(*f) | (fclose(*f) != 0);
  *f = NULL;
  if (bad) return elfm_error_set(err, ELFM_ERR_IO, path, -1, "write failed: %s", strerror(errno));
  return ELFM_OK;
}

enum {
  O_CALIB = 1000, O_EVENTS, O_OUT, O_THK, O_THA, O_THR, O_RXY, O_RZ, O_SEP, O_REFINE, O_MAXDET,
  O_GATE, O_MAXGAP, O_MINPTS, O_LAG, O_MOTION, O_STAGEV, O_MODEL, O_LOSS, O_SPW, O_RES, O_MAXOUT,
  O_THDEPTH, O_THMIN, O_VIEWSRULE, O_RESCUE, O_LEAD, O_LINKKZ, O_VEXP, O_HYST, O_WEAKGATE,
  O_GUIDED, O_GUIDEDR, O_GUIDEDM, O_VSUP, O_STITCHN, O_STITCHG, O_SWAPN
};

/* track's defaults: where they differ from the libraries', why. */
static void track_defaults(track_opts *o)
{
  memset(o, 0, sizeof *o);
  elfm_recon_options_default(&o->recon);
  elfm_peaks_options_default(&o->peaks);
  elfm_link_options_default(&o->link);
  elfm_smooth_options_default(&o->smooth);
  o->max_det = 10000;
  o->max_outlier_frac = 1.0 / 3;
  /* Tracking defaults differ from `recon`'s, measured on the simulated flow
   * scene (docs/tracker.md): ON events only (a moving bead's OFF events form
   * a second peak ~5 um behind it: F1 0.79 -> 0.95), no median (recall
   * 0.86 -> 0.92 at equal precision), and an absolute threshold of 50 on the
   * 0..255 time surface (F1 0.88 at 45, 0.86 at 55, 0.65 at 30; the k-sigma
   * rule alone let ghosts through: precision 0.29). */
  o->recon.framer.polarity = ELFM_POL_ON;
  o->recon.median = 0;
  /* No view-agreement ghost rule (recon's default 0.3): on ON-only frames
   * it removed most deep beads (flow recall 0.79 -> 0.36, F1 0.87 -> 0.53);
   * the detector's threshold and the linker reject the ghosts instead. */
  o->recon.refocus.agree_frac = 0;
  o->views_rule = 1;
  o->views_exponent = 0.5;
  /* Linker distance with z / 1.5, not the scoring's z / 4: the detector
   * localises z ~2.5x worse than x/y (RMSE 1.1 vs 0.44 um on flow), so z/4
   * let tracks jump between beads passing 10-20 um apart in z. Flow 100 ms,
   * seeds 1 / 2: alpha 0.562 -> 0.577 / 0.466 -> 0.544; stage 200 ms 0.626
   * -> 0.625; worm 200 ms 0.325 -> 0.332 (docs/tracker.md). */
  o->link.kz = 1.5;
  /* Weak peaks join a track only within 5 um of its prediction (with the
   * hysteresis threshold 30 below). Flow 100 ms seeds 1 / 2, against 45
   * with the track's own gates: F1 0.886 -> 0.891 / 0.907 -> 0.922, alpha
   * 0.667 -> 0.676 / 0.612 -> 0.635, lateral RMSE <= 0.50 um; stage F1
   * 0.914 -> 0.929; blink unchanged. At 6 um the RMSE passed 0.5 um, at
   * 3-4 um tracks broke (docs/tracker.md "Weak gate"). */
  o->link.weak_gate_um = 5;
  /* guided search (off by default; docs/tracker.md "Track-guided search") */
  o->guided_radius_um = 1.5;
  o->guided_min_points = 10;
  /* View support 0.3 with the absolute threshold 45 (instead of no test at
   * 50): scripts/measure_scenes.sh scenes, F1 flow seeds 1 / 2 0.891 ->
   * 0.897 / 0.922 -> 0.925, stage 0.930 -> 0.945, worm 0.800 -> 0.825;
   * alpha 0.676 -> 0.677 / 0.634 -> 0.646, 0.669 -> 0.716, 0.290 -> 0.327;
   * the cost: flow lateral RMSE 0.46-0.50 -> 0.47-0.51 um (more deep beads),
   * stage speed error 0.09 % -> 0.71 % (docs/tracker.md "View support"). */
  o->view_support = 0.3;
  /* Stitching a new track of 5 points onto a dark track whose recent path
   * its points follow within 8 um RMS (elfm_link.h step 5): flow beads
   * circle and come back onto their own path after gaps no extrapolation
   * bridges. Flow 100 ms seeds 1 / 2: alpha 0.677 -> 0.697 / 0.646 ->
   * 0.691, 7 -> 3 / 6 -> 1 spurious tracks; blink unchanged; worm 0.327 ->
   * 0.326 (docs/tracker.md "Stitching"). Points 4-6 and gates 6-10 um
   * gave the same to +-0.01. Off in --motion stage (below). */
  o->link.stitch_points = 5;
  /* Swap review of gap closings that do not fit, after 6 points of the new
   * tail (elfm_link.h step 6). Flow 100 ms seeds 1, 2, 4-9: alpha 0.697,
   * 0.691 -> 0.714 (seed 2), 0.618 -> 0.691 (seed 7), the other six
   * unchanged; stage, blink, worm unchanged. 5-8 points and ratios 0.4-0.5
   * gave the same; 0.7 swapped wrongly (4 seeds down by 0.01-0.04). */
  o->link.swap_points = 6;
}

int cmd_track(int argc, char **argv)
{
  static const char *const C = "track";
  track_opts o;
  track_defaults(&o);
  int thr_given = 0, low_given = 0, stitch_given = 0;
  static const struct option lo[] = {
      CLI_RECON_LONG_OPTIONS,
      {"calib", required_argument, 0, O_CALIB}, {"events", required_argument, 0, O_EVENTS},
      {"out", required_argument, 0, O_OUT},
      {"threshold-k", required_argument, 0, O_THK}, {"threshold-abs", required_argument, 0, O_THA},
      {"threshold-rel", required_argument, 0, O_THR},
      {"threshold-depth-um", required_argument, 0, O_THDEPTH},
      {"threshold-min", required_argument, 0, O_THMIN},
      {"views-rule", required_argument, 0, O_VIEWSRULE},
      {"rescue-factor", required_argument, 0, O_RESCUE},
      {"stitch-points", required_argument, 0, O_STITCHN},
      {"stitch-gate-um", required_argument, 0, O_STITCHG},
      {"swap-points", required_argument, 0, O_SWAPN},
      {"weak-gate-um", required_argument, 0, O_WEAKGATE},
      {"guided-low", required_argument, 0, O_GUIDED},
      {"view-support", required_argument, 0, O_VSUP},
      {"guided-radius-um", required_argument, 0, O_GUIDEDR},
      {"guided-min-points", required_argument, 0, O_GUIDEDM},
      {"lead-sigmas", required_argument, 0, O_LEAD},
      {"link-kz", required_argument, 0, O_LINKKZ},
      {"views-exponent", required_argument, 0, O_VEXP},
      {"threshold-low", required_argument, 0, O_HYST},
      {"radius-xy-um", required_argument, 0, O_RXY},
      {"radius-z-um", required_argument, 0, O_RZ}, {"min-separation-um", required_argument, 0, O_SEP},
      {"refine", required_argument, 0, O_REFINE}, {"max-detections", required_argument, 0, O_MAXDET},
      {"gate-um", required_argument, 0, O_GATE}, {"max-gap", required_argument, 0, O_MAXGAP},
      {"min-points", required_argument, 0, O_MINPTS}, {"lag-correct", required_argument, 0, O_LAG},
      {"motion", required_argument, 0, O_MOTION},
      {"stage-velocity-um-per-ms", required_argument, 0, O_STAGEV},
      {"model", required_argument, 0, O_MODEL}, {"loss", required_argument, 0, O_LOSS},
      {"spline-weight-ms3", required_argument, 0, O_SPW}, {"resolution", no_argument, 0, O_RES},
      {"max-outlier-frac", required_argument, 0, O_MAXOUT},
      {"quiet", no_argument, 0, 'q'}, {"help", no_argument, 0, 'h'}, {0, 0, 0, 0}};
  cli_recon_parse rp = {&o.recon, 0, 0};
  optind = 1;
  opterr = 0;
  int ch;
  while ((ch = getopt_long(argc, argv, ":hq", lo, NULL)) != -1) {
    const char *a = optarg;
    const int k = cli_parse_recon_option(C, ch, a, &rp);
    if (k == 0) return CLI_USAGE;
    if (k > 0) continue;
    switch (ch) {
    case 'h': usage(stdout); return CLI_OK;
    case 'q': o.quiet = 1; break;
    case O_CALIB: o.calib = a; break;
    case O_EVENTS: o.events = a; break;
    case O_OUT: o.out = a; break;
    case O_THK: thr_given = 1; if (!cli_parse_double(C, "--threshold-k", a, &o.peaks.k_sigma)) return CLI_USAGE; break;
    case O_THA: thr_given = 1; if (!cli_parse_double(C, "--threshold-abs", a, &o.peaks.absolute)) return CLI_USAGE; break;
    case O_THDEPTH: if (!cli_parse_double(C, "--threshold-depth-um", a, &o.peaks.depth_range_um)) return CLI_USAGE; break;
    case O_HYST: low_given = 1; if (!cli_parse_double(C, "--threshold-low", a, &o.peaks.hysteresis_low)) return CLI_USAGE; break;
    case O_VEXP: if (!cli_parse_double(C, "--views-exponent", a, &o.views_exponent)) return CLI_USAGE; break;
    case O_LINKKZ: if (!cli_parse_double(C, "--link-kz", a, &o.link.kz)) return CLI_USAGE; break;
    case O_LEAD: if (!cli_parse_double(C, "--lead-sigmas", a, &o.link.lead_sigmas)) return CLI_USAGE; break;
    case O_GUIDEDR: if (!cli_parse_double(C, "--guided-radius-um", a, &o.guided_radius_um)) return CLI_USAGE; break;
    case O_GUIDEDM: if (!cli_parse_int(C, "--guided-min-points", a, &o.guided_min_points)) return CLI_USAGE; break;
    case O_VSUP:
      if (!cli_parse_double(C, "--view-support", a, &o.view_support)) return CLI_USAGE;
      if (!(o.view_support >= 0 && o.view_support <= 1))
        return cli_message(C, CLI_USAGE, "--view-support must be in 0..1");
      break;
    case O_GUIDED: if (!cli_parse_double(C, "--guided-low", a, &o.guided_low)) return CLI_USAGE; break;
    case O_WEAKGATE: if (!cli_parse_double(C, "--weak-gate-um", a, &o.link.weak_gate_um)) return CLI_USAGE; break;
    case O_RESCUE: if (!cli_parse_double(C, "--rescue-factor", a, &o.link.rescue_gate_factor)) return CLI_USAGE; break;
    case O_STITCHN:
      if (!cli_parse_int(C, "--stitch-points", a, &o.link.stitch_points)) return CLI_USAGE;
      stitch_given = 1;
      break;
    case O_SWAPN: if (!cli_parse_int(C, "--swap-points", a, &o.link.swap_points)) return CLI_USAGE; break;
    case O_STITCHG: if (!cli_parse_double(C, "--stitch-gate-um", a, &o.link.stitch_gate_um)) return CLI_USAGE; break;
    case O_VIEWSRULE:
      if (!strcmp(a, "on")) o.views_rule = 1;
      else if (!strcmp(a, "off")) o.views_rule = 0;
      else return cli_message(C, CLI_USAGE, "--views-rule must be on or off, not '%s'", a);
      break;
    case O_THMIN: if (!cli_parse_double(C, "--threshold-min", a, &o.peaks.absolute_min)) return CLI_USAGE; break;
    case O_THR: thr_given = 1; if (!cli_parse_double(C, "--threshold-rel", a, &o.peaks.relative)) return CLI_USAGE; break;
    case O_RXY: if (!cli_parse_double(C, "--radius-xy-um", a, &o.peaks.radius_xy_um)) return CLI_USAGE; break;
    case O_RZ: if (!cli_parse_double(C, "--radius-z-um", a, &o.peaks.radius_z_um)) return CLI_USAGE; break;
    case O_SEP: if (!cli_parse_double(C, "--min-separation-um", a, &o.peaks.min_separation_um)) return CLI_USAGE; break;
    case O_REFINE:
      if (!strcmp(a, "gauss")) o.peaks.refine = ELFM_REFINE_GAUSSIAN;
      else if (!strcmp(a, "quad")) o.peaks.refine = ELFM_REFINE_QUADRATIC;
      else if (!strcmp(a, "none")) o.peaks.refine = ELFM_REFINE_NONE;
      else return cli_message(C, CLI_USAGE, "--refine must be gauss, quad or none, not '%s'", a);
      break;
    case O_MAXDET:
      if (!cli_parse_int(C, "--max-detections", a, &o.max_det)) return CLI_USAGE;
      if (o.max_det < 1 || o.max_det > 10000000) return cli_message(C, CLI_USAGE, "--max-detections must be 1..1e7");
      break;
    case O_GATE: if (!cli_parse_double(C, "--gate-um", a, &o.link.gate_um)) return CLI_USAGE; break;
    case O_MAXGAP: if (!cli_parse_int(C, "--max-gap", a, &o.link.max_gap_frames)) return CLI_USAGE; break;
    case O_MINPTS: if (!cli_parse_int(C, "--min-points", a, &o.link.min_points)) return CLI_USAGE; break;
    case O_LAG:
      if (!strcmp(a, "on")) o.lag_correct = 1;
      else if (!strcmp(a, "off")) o.lag_correct = 0;
      else return cli_message(C, CLI_USAGE, "--lag-correct must be on or off, not '%s'", a);
      break;
    case O_MOTION:
      if (!strcmp(a, "auto")) o.motion = MOTION_AUTO;
      else if (!strcmp(a, "stage")) o.motion = MOTION_STAGE;
      else if (!strcmp(a, "free")) o.motion = MOTION_FREE;
      else return cli_message(C, CLI_USAGE, "--motion must be auto, stage or free, not '%s'", a);
      break;
    case O_STAGEV:
      if (!parse_vec3(a, o.stage_v))
        return cli_message(C, CLI_USAGE, "--stage-velocity-um-per-ms wants vx,vy,vz, not '%s'", a);
      o.has_stage_v = 1;
      break;
    case O_MODEL:
      if (!strcmp(a, "auto")) o.smooth.model = ELFM_MODEL_AUTO;
      else if (!strcmp(a, "cv")) o.smooth.model = ELFM_MODEL_CONST_VELOCITY;
      else if (!strcmp(a, "ca")) o.smooth.model = ELFM_MODEL_CONST_ACCEL;
      else if (!strcmp(a, "spline")) o.smooth.model = ELFM_MODEL_SPLINE;
      else return cli_message(C, CLI_USAGE, "--model must be auto, cv, ca or spline, not '%s'", a);
      break;
    case O_LOSS:
      if (!strcmp(a, "huber")) o.smooth.loss = ELFM_LOSS_HUBER;
      else if (!strcmp(a, "cauchy")) o.smooth.loss = ELFM_LOSS_CAUCHY;
      else if (!strcmp(a, "none")) o.smooth.loss = ELFM_LOSS_NONE;
      else return cli_message(C, CLI_USAGE, "--loss must be huber, cauchy or none, not '%s'", a);
      break;
    case O_SPW: if (!cli_parse_double(C, "--spline-weight-ms3", a, &o.smooth.spline_weight_ms3)) return CLI_USAGE; break;
    case O_RES: o.resolution = 1; break;
    case O_MAXOUT:
      if (!cli_parse_double(C, "--max-outlier-frac", a, &o.max_outlier_frac)) return CLI_USAGE;
      if (!(o.max_outlier_frac >= 0 && o.max_outlier_frac <= 1))
        return cli_message(C, CLI_USAGE, "--max-outlier-frac must be in 0..1");
      break;
    default: return cli_bad_option(C, ch, argv);
    }
  }
  if (optind < argc) return cli_message(C, CLI_USAGE, "unexpected argument '%s'", argv[optind]);
  if (!o.calib || !o.events || !o.out)
    return cli_message(C, CLI_USAGE, "--calib, --events and --out are required (see --help)");
  if (!cli_check_recon_options(C, &rp)) return CLI_USAGE;
  if (!(o.guided_low >= 0) || !(o.guided_radius_um > 0) || o.guided_min_points < 1)
    return cli_message(C, CLI_USAGE,
                       "--guided-low must be >= 0, --guided-radius-um > 0, --guided-min-points >= 1");
  if (!thr_given) {
    if (o.recon.framer.repr == ELFM_REPR_COUNT) o.peaks.relative = 0.35;  /* counts have no fixed scale */
    else {
      /* 45 with the view-support test (below), 50 without it: the test
       * removes the ghosts a lower threshold lets in (docs/tracker.md
       * "View support"). */
      o.peaks.absolute = o.view_support > 0 ? 45 : 50;
      /* Hysteresis 45: a bead dimmed by defocus keeps its track without
       * letting the ghosts of that brightness start tracks. Flow 100 ms
       * seeds 1 / 2: F1 0.874 -> 0.886 / 0.889 -> 0.907, alpha 0.627 -> 0.667 /
       * 0.566 -> 0.612, lateral RMSE 0.43-0.47 -> 0.44-0.49 um; stage F1 0.898
       * -> 0.914; at 40 the RMSE passed 0.5 um (docs/tracker.md). Now 30:
       * with the 5 um weak gate (above) ghosts of that brightness rarely
       * sit where a track expects its bead; below ~30 the robust-noise
       * rule (median + 6 sigma) sets the floor (25 gave the same peaks). */
      if (!low_given) o.peaks.hysteresis_low = 30;
    }
  }
  if (o.motion == MOTION_STAGE) {
    o.smooth.allow_spline = 0;
    if (o.has_stage_v) memcpy(o.link.prior_velocity_um_per_ms, o.stage_v, sizeof o.stage_v);
    /* Everything translates with the stage, so no object comes back onto a
     * path, while a bead trailing another on the same line (or re-entering
     * the field on it) lies on that path: stitching joined two such
     * beads, the track was rejected for outliers (stage 200 ms alpha 0.717
     * -> 0.677). */
    if (!stitch_given) o.link.stitch_points = 0;
  } else if (o.motion == MOTION_FREE && o.smooth.model == ELFM_MODEL_AUTO) {
    o.smooth.model = ELFM_MODEL_SPLINE;
  }
  if (o.lag_correct) o.link.lag_tau_us = o.recon.framer.tau_us;

  elfm_error err;
  elfm_error_clear(&err);
  elfm_calib calib;
  if (elfm_calib_load(o.calib, &calib, &err) != ELFM_OK) return cli_fail(C, &err);
  if (mkdir(o.out, 0777) != 0 && errno != EEXIST)
    return cli_message(C, CLI_FAIL, "%s: cannot create directory: %s", o.out, strerror(errno));

  track_ctx c;
  memset(&c, 0, sizeof c);
  c.o = &o;
  c.calib = &calib;
  elfm_track_store_init(&c.store);
  snprintf(c.p_det, sizeof c.p_det, "%s/detections.csv", o.out);
  snprintf(c.p_tr, sizeof c.p_tr, "%s/tracks.csv", o.out);
  char p_isbi[1100], p_tm[1100], p_sum[1100];
  snprintf(p_isbi, sizeof p_isbi, "%s/tracks_isbi.xml", o.out);
  snprintf(p_tm, sizeof p_tm, "%s/tracks_trackmate.xml", o.out);
  snprintf(p_sum, sizeof p_sum, "%s/summary.json", o.out);
  int rc = CLI_FAIL;
  FILE *fx = NULL;
  c.fw = o.resolution ? malloc((size_t)o.max_det * sizeof *c.fw) : NULL;
  if (o.resolution && !c.fw) {
    cli_message(C, CLI_FAIL, "out of memory");
    goto done;
  }
  if (peaks_setup(&c, &err) != ELFM_OK) { cli_fail(C, &err); goto done; }
  o.recon.worker = detect_worker;
  o.recon.worker_user = &c;
  o.recon.on_volume_slot = on_volume;
  c.lk = elfm_link_create(&o.link, &err);
  if (!c.lk) { cli_fail(C, &err); goto done; }
  c.fdet = fopen(c.p_det, "w");
  c.ftr = fopen(c.p_tr, "w");
  if (!c.fdet || !c.ftr) {
    cli_message(C, CLI_FAIL, "%s: cannot create: %s", c.fdet ? c.p_tr : c.p_det, strerror(errno));
    goto done;
  }
  if (elfm_detections_write_header(c.fdet, c.p_det, &err) != ELFM_OK ||
      elfm_tracks_write_csv_header(c.ftr, c.p_tr, &err) != ELFM_OK) {
    cli_fail(C, &err);
    goto done;
  }
  if (!o.quiet) {
    o.recon.progress = progress;
    o.recon.progress_user = &c;
  }
  double t0 = cli_now_s();
  elfm_recon_stats rs;
  memset(&rs, 0, sizeof rs);
  elfm_status st = elfm_recon_run(o.events, &calib, &o.recon, NULL, &c, &rs, &err);
  if (!o.quiet) fputc('\n', stderr);
  /* An error in the event file (truncated, corrupt) stops reading, but what
   * was read before it is good: finish the tracks, write every output, and
   * only then report the error and exit 1. Nothing already computed is lost.
   * Errors of our own (outputs, memory) still stop at once. */
  elfm_error input_err;
  elfm_error_clear(&input_err);
  int input_failed = st != ELFM_OK && rs.input_error;
  if (input_failed) {
    input_err = err;
    elfm_error_clear(&err);
    st = ELFM_OK;
  }
  if (st == ELFM_OK) st = elfm_link_finish(c.lk, &err);
  if (st == ELFM_OK) st = drain(&c, &err);
  if (st == ELFM_OK) st = close_file(&c.fdet, c.p_det, &err);
  if (st == ELFM_OK) st = close_file(&c.ftr, c.p_tr, &err);
  if (st == ELFM_OK) {
    fx = fopen(p_isbi, "w");
    if (!fx) st = elfm_error_set(&err, ELFM_ERR_IO, p_isbi, -1, "cannot create: %s", strerror(errno));
    else st = elfm_tracks_write_isbi(fx, p_isbi, &c.store, &err);
    if (st == ELFM_OK) st = close_file(&fx, p_isbi, &err);
  }
  if (st == ELFM_OK) {
    fx = fopen(p_tm, "w");
    double stride_us = (double)(o.recon.framer.stride_us ? o.recon.framer.stride_us : o.recon.framer.dt_us);
    if (!fx) st = elfm_error_set(&err, ELFM_ERR_IO, p_tm, -1, "cannot create: %s", strerror(errno));
    else st = elfm_tracks_write_trackmate(fx, p_tm, &c.store, stride_us * 1e-3, &err);
    if (st == ELFM_OK) st = close_file(&fx, p_tm, &err);
  }
  double wall = cli_now_s() - t0;
  if (st == ELFM_OK) st = write_summary(&c, &rs, wall, p_sum, input_failed ? &input_err : NULL, &err);
  if (input_failed) {
    cli_fail(C, &input_err);
    if (st != ELFM_OK) cli_fail(C, &err);
    goto done;
  }
  if (st != ELFM_OK) {
    cli_fail(C, &err);
    goto done;
  }
  if (!o.quiet)
    fprintf(stderr, "eventlfm track: %" PRId64 " volumes, %" PRId64 " detections, %zu tracks "
                    "(%" PRId64 " started) in %.2f s (%.0f volumes/s, realtime factor %.2f) -> %s\n",
            c.n_frames, c.n_det, c.store.n, elfm_link_n_started(c.lk), wall,
            wall > 0 ? (double)c.n_frames / wall : 0.0, wall > 0 ? rs.span_s / wall : 0.0, o.out);
  rc = CLI_OK;
done:
  if (fx) fclose(fx);
  if (c.fdet) fclose(c.fdet);
  if (c.ftr) fclose(c.ftr);
  elfm_link_free(c.lk);
  for (int t = 0; c.pk && t < c.n_threads; t++) elfm_peaks_free(c.pk[t]);
  free(c.pk);
  free(c.det_n);
  free(c.fin);
  free(c.fin_st);
  free(c.fin_err);
  free(c.det_s);
  free(c.det_rej);
  free(c.pred);
  elfm_track_store_clear(&c.store);
  free(c.det);
  free(c.fw);
  free(c.fl.xy);
  free(c.fl.z);
  free(c.fl.speed);
  return rc;
}
