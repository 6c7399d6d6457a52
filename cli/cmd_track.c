/* cmd_track.c — eventlfm track: events -> volumes -> detections -> linked,
 * smoothed 3D tracks, streaming (the recon driver calls back per volume in
 * frame order; finished tracks are smoothed and written as they end).
 * Here: the run. The options and their defaults are in cmd_track_opts.c,
 * the per-volume work in cmd_track_volume.c, gap filling in
 * cmd_track_fill.c, summary.json in cmd_track_summary.c. */
#include <errno.h>
#include <inttypes.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#if defined(__GLIBC__)
#include <malloc.h>
#endif
#include <string.h>
#include <sys/stat.h>

#include "cmd_track.h"
#include "cmd_track_again.h"

/* The faint-peaks note (TRACK_HINT_DIM_FACTOR) when it applies and was not
 * given yet; `so_far`: during the run (on a line of its own). Not while
 * --blur-px auto has yet to judge, or has judged the peaks faint and the
 * run waits for the stage test to start again (its message says it). */
static void dim_note(track_ctx *c, int so_far)
{
  const track_opts *o = c->o;
  if (o->blur_auto && (!c->auto_decided || c->blur_restart)) return;
  if (c->dim_noted || o->quiet || o->recon.blur_px != 0 || !(o->peaks.absolute > 0) ||
      c->n_height < TRACK_WIDTH_MIN_PEAKS ||
      (o->recon.framer.repr != ELFM_REPR_EXP && o->recon.framer.repr != ELFM_REPR_LIN))
    return;
  const double h_med = track_peak_height_median(c);
  if (!(h_med < TRACK_HINT_DIM_FACTOR * o->peaks.absolute)) return;
  /* crowded frames: the faint peaks are ghosts (auto_judge) */
  if (track_occupancy_mean(c) > TRACK_CROWD_OCC) return;
  fprintf(stderr, "%seventlfm track: note: the peaks are faint (median height %.0f against the "
                  "threshold %.0f%s): for dim objects, about one event per view per frame, "
                  "--blur-px 1 finds more (README, docs/tracker.md \"Dim objects\")\n",
          so_far ? "\n" : "", h_med, o->peaks.absolute, so_far ? ", so far" : "");
  c->dim_noted = 1;
}

static void progress(const elfm_recon_stats *s, void *user)
{
  track_ctx *c = user;
  char left[64];
  if (c->n_height >= TRACK_HINT_DIM_EARLY_PEAKS) dim_note(c, 1);
  fprintf(stderr, "\reventlfm track: %.3f s of recording%s, %" PRId64 " volumes, %.0f volumes/s, "
                  "%zu live tracks   ",
          s->span_s, cli_progress_left(left, sizeof left, s->done_frac, s->wall_s), s->frames,
          s->volumes_per_s, elfm_link_n_live(c->lk));
}

static int close_file(FILE **f, const char *path, elfm_error *err)
{
  if (!*f) return ELFM_OK;
  int bad = ferror(*f) | (fclose(*f) != 0);
  *f = NULL;
  if (bad) return elfm_error_set(err, ELFM_ERR_IO, path, -1, "write failed: %s", strerror(errno));
  return ELFM_OK;
}

/* The two XML files from the points c->xml holds. */
static elfm_status track_write_xml(track_ctx *c, const char *p_isbi, const char *p_tm,
                                   elfm_error *err)
{
  const elfm_framer_options *fo = &c->o->recon.framer;
  const double stride_ms = 1e-3 * (double)(fo->stride_us ? fo->stride_us : fo->dt_us);
  FILE *f = fopen(p_isbi, "w");
  elfm_status st = ELFM_OK;
  if (!f) st = elfm_error_set(err, ELFM_ERR_IO, p_isbi, -1, "cannot create: %s", strerror(errno));
  else st = elfm_track_xml_write_isbi(c->xml, f, p_isbi, err);
  if (f && st != ELFM_OK) fclose(f);
  else if (f) st = close_file(&f, p_isbi, err);
  if (st != ELFM_OK) return st;
  f = fopen(p_tm, "w");
  if (!f) return elfm_error_set(err, ELFM_ERR_IO, p_tm, -1, "cannot create: %s", strerror(errno));
  st = elfm_track_xml_write_trackmate(c->xml, f, p_tm, stride_ms, err);
  if (st != ELFM_OK) {
    fclose(f);
    return st;
  }
  return close_file(&f, p_tm, err);
}

/* Faint first peaks (median height h) in frames that are not crowded:
 * dim objects, for the blur when it is auto's to choose. Crowded frames'
 * faint peaks are ghosts, not dim objects (auto_judge). */
static int faint_uncrowded(const track_ctx *c, double h)
{
  return c->o->blur_auto && h < TRACK_HINT_DIM_FACTOR * c->o->peaks.absolute &&
         !(track_occupancy_mean(c) > TRACK_CROWD_OCC);
}

/* The first peaks judged for the LED's windows (auto_judge): their
 * height and their tracks' speed, and nothing else to start again for but
 * the blur, for faint peaks in frames that are not crowded, as on the grid:
 * dim blinking beads (blink_moving at a quarter of its flux, seeds 4-6:
 * alpha 0.254 on the LED's windows, 0.375 blurred; "Dim blinking beads"). */
static void judged_for_pulses(track_ctx *c)
{
  const track_opts *o = c->o;
  c->auto_decided = 1;
  c->auto_peaks = c->n_height;
  const double h = c->n_height ? track_peak_height_median(c) : NAN;
  c->auto_ratio = h / o->peaks.absolute;
  c->auto_speed = track_detection_speed_median(c);
  c->auto_miss = track_detection_miss_median(c);
  c->miss_decided = 1;
  c->repr_restart = c->dt_restart = c->few_restart = c->slow_restart = c->stride_restart = 0;
  c->blur_restart = faint_uncrowded(c, h);
}

/* --blur-px auto, the automatic window and representation: judge the
 * first peaks once min_peaks of them are in; 1 when the run is to start
 * again: with the integral (their tracks crawl,
 * TRACK_AUTO_CRAWL_UM_PER_MS), the blur (faint peaks whose tracks do not
 * crawl, TRACK_HINT_DIM_FACTOR), half the window (tracks that move
 * TRACK_DT_AUTO_STEP_UM or more per frame), or the last two; and the same
 * windows twice as often (tracks whose predictions miss by
 * TRACK_STRIDE_AUTO_MISS_UM or more), with the blur or alone. And --motion
 * auto: with --motion stage when the first tracks move as one
 * (track_rigid_judge), which comes first: a stage turns the others off
 * (track_opts_derive), so their restart waits for that judgement.
 * at_end: the run has ended, judge with what there is. */
static int auto_judge(track_ctx *c, int64_t min_peaks, int at_end)
{
  const track_opts *o = c->o;
  if (o->start_auto && !c->auto_decided && track_pulsed(c)) {
    /* Pulsed light (the frames with the trigger's edges hold most of the
     * events): one window per pulse, whatever the objects do, which turns
     * the other choices off (track_opts_derive); judged before the test
     * for a stage, whose beads under pulsed light (blink_moving) track
     * best on --repr lin's windows. Moving objects (their tracks' median
     * speed, once there are enough) get --repr lin when the surface was
     * not given: the default one decays over the next window, where a
     * moving bead whose pulse ended late shows again, in the dark. */
    if (!at_end && c->n_height < min_peaks) return 0; /* the speed of enough peaks */
    const int have_speed = c->n_speed >= TRACK_WIDTH_MIN_PEAKS;
    judged_for_pulses(c);
    c->start_restart = 1;
    c->lin_restart = track_lin_choosable(o) && have_speed && c->auto_speed >= TRACK_HINT_PULSED_MIN_SPEED_UM_PER_MS;
    return 1;
  }
  if (o->lin_auto && track_led_windows(o) && !c->auto_decided) {
    /* The LED's windows given, the surface not: moving objects start
     * again on --repr lin's windows, as under pulsed light found above
     * (blink_moving seeds 1-10 with --start each-trigger: alpha 0.511 on
     * the default surface, docs/tracker.md "Blinking beads on a stage
     * given"). Objects at rest keep it. */
    if (!at_end && c->n_height < min_peaks) return 0;
    judged_for_pulses(c);
    c->lin_restart = c->n_speed >= TRACK_WIDTH_MIN_PEAKS &&
                     c->auto_speed >= TRACK_HINT_PULSED_MIN_SPEED_UM_PER_MS;
    c->start_restart = c->lin_restart || c->blur_restart;
    return c->start_restart;
  }
  if (o->motion == MOTION_STAGE && c->votes.vel && !c->votes.judged &&
      !(track_pulsed_pending(c) && !at_end)) {
    /* --motion stage without a velocity: the frames' shift gives it, and
     * the run starts again with new tracks at it (cmd_track_vote.h); not
     * while pulsed light may yet be found (the LED's run measures it) */
    double s, a, d;
    if (track_votes_judge(&c->votes, at_end, &s, &a, &d) == 1) return 1;
  }
  if (o->motion_auto && track_rigid_judge(c, at_end)) return 1;
  if (!o->blur_auto && !o->dt_auto && !o->repr_auto && !o->start_auto) return 0;
  if (!c->auto_decided) {
    if (at_end && o->repr_auto && c->n_height < TRACK_WIDTH_MIN_PEAKS &&
        c->n_frames >= TRACK_AUTO_FEW_MIN_FRAMES) {
      /* too few to judge over a whole recording: the integral
       * (TRACK_AUTO_FEW_MIN_FRAMES); a stage would have been found above */
      c->auto_decided = 1;
      c->auto_peaks = c->n_height;
      c->auto_ratio = c->auto_speed = c->auto_miss = NAN;
      c->miss_decided = 1;
      c->few_restart = c->repr_restart = 1;
      return 1;
    }
    if (c->n_height < min_peaks) return 0;
    c->auto_decided = 1;
    c->auto_peaks = c->n_height;
    const double h = track_peak_height_median(c);
    c->auto_ratio = h / o->peaks.absolute;
    c->auto_speed = track_detection_speed_median(c);
    const int have_speed = c->n_speed >= TRACK_WIDTH_MIN_PEAKS;
    const int slow = have_speed && c->auto_speed >= TRACK_HINT_MIN_SPEED_UM_PER_MS &&
                     c->auto_speed < TRACK_AUTO_CRAWL_UM_PER_MS;
    c->repr_restart = o->repr_auto && slow;
    /* Faint peaks in crowded frames are ghosts, not dim objects: a dim
     * object fires about one pixel per view per frame, and the blur would
     * spread the crowd's every pixel over nine. Dim flow (a quarter of
     * the flux) fills 0.3 % of the views' pixels, flow with 80-150 beads
     * 3.5-6 %, and 9 of those 16 recordings (100 ms, seeds 1-4) were
     * blurred; flow with 80 beads seed 2, whose first peaks stay faint
     * with the crowded frames' view support too: alpha 0.461 blurred,
     * 0.522 not (docs/tracker.md "Crowded frames"). */
    c->blur_restart = faint_uncrowded(c, h) && !slow;
    const double frame_ms = 1e-3 * (double)o->recon.framer.dt_us;
    c->dt_restart = o->dt_auto && have_speed && c->auto_speed * frame_ms >= TRACK_DT_AUTO_STEP_UM;
    /* slow beads (not cells). Their peaks may look faint too: below
     * TRACK_SLOW_BEADS_WINDOW_OVER_BLUR_UM_PER_MS because they move little
     * in 1 ms, and the longer windows beat the blur (flow at 0.6-1 mm/s:
     * 0.731 blurred, 0.785 at 1.5 ms); above it because they are dim, and
     * the blur stays (random flow at 1-2 mm/s, early 2.27-2.55: 0.509
     * blurred, 0.426 at 1.5 ms) */
    c->slow_restart = o->dt_auto && !o->tau_given && have_speed &&
                      c->auto_speed >= TRACK_AUTO_CRAWL_UM_PER_MS &&
                      c->auto_speed < TRACK_SLOW_BEADS_MAX_UM_PER_MS &&
                      (!c->blur_restart || c->auto_speed < TRACK_SLOW_BEADS_WINDOW_OVER_BLUR_UM_PER_MS);
    if (c->slow_restart) c->blur_restart = 0;
  }
  if (!c->miss_decided) {
    /* Beads that turn beyond prediction: the same windows twice as often
     * (TRACK_STRIDE_AUTO_MISS_UM); not where another window is chosen.
     * The misses need tracks of 5 points, which a crowded field's first
     * peaks do not have yet (40 beads: 200 peaks in 5-6 frames): they are
     * counted on, and the run judged, until TRACK_WIDTH_MIN_PEAKS of them
     * are in (or TRACK_MISS_MAX_FRAMES frames have passed: too few to judge). */
    const int wanted = o->dt_auto && !c->dt_restart && !c->slow_restart && !c->repr_restart;
    if (wanted && !at_end && c->n_miss < TRACK_WIDTH_MIN_PEAKS && c->n_frames < TRACK_MISS_MAX_FRAMES)
      return 0;
    c->miss_decided = 1;
    c->auto_miss = track_detection_miss_median(c);
    c->stride_restart = wanted && c->n_miss >= TRACK_WIDTH_MIN_PEAKS &&
                        c->auto_miss >= TRACK_STRIDE_AUTO_MISS_UM;
  }
  if (o->motion_auto && !c->rigid_decided) return 0;
  return c->repr_restart || c->blur_restart || c->dt_restart || c->slow_restart || c->stride_restart;
}

/* The ordered per-volume callback: track_on_volume, then auto's judgement
 * as soon as TRACK_HINT_DIM_EARLY_PEAKS peaks are in. A run to start again
 * stops here (an error status that track_run knows by c->auto_stopped). */
static elfm_status on_volume(const elfm_volume *v, int slot, void *user, elfm_error *err)
{
  track_ctx *c = user;
  const elfm_status st = track_on_volume(v, slot, user, err);
  if (st == ELFM_OK && c->stage_outrun) {
    c->auto_stopped = 1;
    return elfm_error_set(err, ELFM_ERR_INVALID, NULL, -1, "to start again with 1 ms windows");
  }
  if (st == ELFM_OK && auto_judge(c, TRACK_HINT_DIM_EARLY_PEAKS, 0)) {
    c->auto_stopped = 1;
    return elfm_error_set(err, ELFM_ERR_INVALID, NULL, -1, "to start again with auto's choices");
  }
  return st;
}

/* The run's result when it is to start again (track_run's *again says how). */
#define TRACK_RUN_AGAIN 100


/* --motion stage: the stage's velocity in a line, for the microscopist who
 * checks it (summary.json "stage" has the rest). The pooled velocity, each
 * track weighted by the spread of its times (over its points' scatter,
 * axis by axis: elfm_analysis.h), is the one quoted: on a slow
 * stage the short tracks of beads crossing the field stop's edge are
 * biased (docs/tracker.md "The stage's velocity pooled"). */
static void say_stage(const track_ctx *c, const track_opts *o, double span_ms)
{
  elfm_stage_result sr;
  elfm_error e;
  if (!c->n_info || elfm_analysis_stage_info(c->info, c->n_info, o->has_stage_v ? o->stage_v : NULL,
                                             &sr, &e) != ELFM_OK)
    return;
  const double *v = sr.v_pooled_um_per_ms;
  if (!(isfinite(v[0]) && isfinite(v[1]) && isfinite(v[2]))) return;
  fprintf(stderr, "eventlfm track: the stage moves at (%.4f, %.4f, %.4f) um/ms, %.4f mm/s, over "
                  "%zu tracks (each by the spread of its times over its points' scatter; by points "
                  "%.4f mm/s)",
          v[0], v[1], v[2], sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]), sr.n_tracks,
          sr.speed_um_per_ms);
  if (o->has_stage_v && isfinite(sr.rel_error_pooled))
    fprintf(stderr, "; %.2f %% from the given velocity", 100 * sr.rel_error_pooled);
  /* and its acceleration where the speed changes by 5 % or more over the run */
  const double *a = sr.accel_um_per_ms2, sp = sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
  const double am = sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2]);
  if (isfinite(am) && am * span_ms >= 0.05 * sp)
    fprintf(stderr, "; accelerating at (%.5f, %.5f, %.5f) um/ms^2", a[0], a[1], a[2]);
  fputc('\n', stderr);
}

/* One run with *po: CLI_OK, CLI_FAIL (said), or TRACK_RUN_AGAIN with
 * *again what to start again with. *t0_s: the time the command's first
 * run started (NaN: this one), for the wall time in summary.json. */
static int track_run(const track_opts *po, track_again *again, double *t0_s)
{
  static const char *const C = "track";
  track_opts o = *po;
  again->each_trigger = again->lin = again->stage_back = again->stage_short = again->tau_follows = 0;
  again->prior_only = 0;
  again->stride_us = -1;
  elfm_error err;
  elfm_error_clear(&err);
  elfm_calib calib;
  if (elfm_calib_load(o.calib, &calib, &err) != ELFM_OK) return cli_fail(C, &err);
  if (!cli_apply_planes(C, o.planes_um, o.calib, &calib)) return CLI_USAGE;
  track_plane_step(&o, &calib);
  track_views_step(&o, &calib);
  if (o.smooth.motion_lead_um != 0 || o.smooth.motion_delay_us != 0 || o.smooth.motion_slow_lead_ms != 0) {
    /* The motion bias of a fit over the views (elfm_smooth.h): each view's
     * image moves with the object's lateral motion plus its z motion times
     * the view's disparity. Flow 100 ms, mean alpha over seeds 1-8: 0.7486
     * with the lateral model, 0.7515 with the views' (held-out seeds 9-12
     * +0.003 to +0.004 each); the z error of beads moving at 1-2 um/ms in z,
     * -0.3 um x the sign of v_z, falls to -0.13 (docs/tracker.md). */
    elfm_smooth_options_set_views(&o.smooth, &calib);
  }
  if (!cli_out_fits(C, o.out, "/tracks_trackmate.xml")) return CLI_FAIL; /* the longest name */
  if (cli_mkdir_p(o.out) != 0) /* and its parents: --out results/run1 */
    return cli_message(C, CLI_FAIL, "%s: cannot create directory: %s", o.out, strerror(errno));

  track_ctx c;
  memset(&c, 0, sizeof c);
  c.rigid_dev = c.rigid_speed = c.rigid_abs = NAN;
  c.o = &o;
  c.calib = &calib;
  elfm_frame_times_init(&c.frame_times);
  if (mtx_init(&c.fq_mu, mtx_plain) != thrd_success)
    return cli_message(C, CLI_FAIL, "cannot create a mutex");
  c.fq_mu_ok = 1;
  snprintf(c.p_det, sizeof c.p_det, "%s/detections.csv", o.out);
  snprintf(c.p_tr, sizeof c.p_tr, "%s/tracks.csv", o.out);
  snprintf(c.p_fr, sizeof c.p_fr, "%s/frames.csv", o.out);
  char p_isbi[TRACK_PATH_CHARS], p_tm[TRACK_PATH_CHARS], p_sum[TRACK_PATH_CHARS], p_scratch[TRACK_PATH_CHARS];
  snprintf(p_isbi, sizeof p_isbi, "%s/tracks_isbi.xml", o.out);
  snprintf(p_scratch, sizeof p_scratch, "%s/.tracks_points.tmp", o.out);
  snprintf(p_tm, sizeof p_tm, "%s/tracks_trackmate.xml", o.out);
  snprintf(p_sum, sizeof p_sum, "%s/summary.json", o.out);
  int rc = CLI_FAIL;
  c.fw = o.resolution ? malloc((size_t)o.max_det * sizeof *c.fw) : NULL;
  if (o.resolution && !c.fw) {
    cli_message(C, CLI_FAIL, "out of memory");
    goto done;
  }
  if (track_peaks_setup(&c, &err) != ELFM_OK || track_fill_setup(&c, &err) != ELFM_OK) {
    cli_fail(C, &err);
    goto done;
  }
  o.recon.worker = track_detect_worker;
  o.recon.worker_user = &c;
  o.recon.on_volume_slot = on_volume;
  o.recon.side_work = track_side_work;
  o.recon.side_user = &c;
  c.lk = elfm_link_create(&o.link, &err);
  if (!c.lk) { cli_fail(C, &err); goto done; }
  c.fdet = fopen(c.p_det, "w");
  c.ftr = fopen(c.p_tr, "w");
  c.ffr = fopen(c.p_fr, "w");
  if (!c.fdet || !c.ftr || !c.ffr) {
    cli_message(C, CLI_FAIL, "%s: cannot create: %s",
                !c.fdet ? c.p_det : !c.ftr ? c.p_tr : c.p_fr, strerror(errno));
    goto done;
  }
  /* Each track (or piece of a long one) goes to tracks.csv as it ends and
   * is freed (track_drain); the XML files list a track's points together
   * and TrackMate's by frame, so the points wait in a scratch file in the
   * output directory until the end (elfm_track_xml). */
  c.xml = elfm_track_xml_create(p_scratch, 0, &err);
  if (!c.xml || cli_frames_csv_header(c.ffr, c.p_fr, 1, &err) != ELFM_OK ||
      elfm_detections_write_header(c.fdet, c.p_det, &err) != ELFM_OK ||
      elfm_tracks_write_csv_header(c.ftr, c.p_tr, &err) != ELFM_OK) {
    cli_fail(C, &err);
    goto done;
  }
  if (!o.quiet) {
    o.recon.progress = progress;
    o.recon.progress_user = &c;
  }
  if (!o.quiet && !o.auto_chose) {  /* said once, not again in a second run */
    /* the planes are track's own choice unless given: say which */
    if (o.plane_every > 1)
      fprintf(stderr, "eventlfm track: %d planes %g..%g um, %g um apart: %s %d%s of %s's "
              "(--plane-shift-px 0 for all)\n", elfm_calib_n_planes(&calib), calib.z_min_um,
              calib.z_max_um, calib.z_step_um, o.plane_centred ? "centred, the spacing of every" : "every",
              o.plane_every, o.plane_every == 2 ? "nd" : o.plane_every == 3 ? "rd" : "th", o.calib);
    if (o.views_scaled)
      fprintf(stderr, "eventlfm track: %d views: views that must agree scaled from the 25 views' "
              "defaults to %d (view fit), %d (guided), %d (fill), %d (deep peaks)\n",
              o.views_scaled, o.loc.min_views, o.guided_views, o.fill_views, o.deep_peak_views);
    /* On fewer views than 25 the time surface's ghosts make the first
     * tracks of crawling cells look fast, and nothing measured tells them
     * from slow beads, which the integral loses (docs/tracker.md
     * "Measured, not built (fifty-sixth session)"): a hint, not a choice. */
    if (o.views_scaled > 0 && o.views_scaled < 25 && o.repr_auto)
      fprintf(stderr, "eventlfm track: note: on %d views the time surface's ghosts make crawling "
                      "cells look fast, and the integral is not chosen for them: give --repr "
                      "integral for cells (worm on 9 views: alpha 0.12 -> 0.90; README)\n",
              o.views_scaled);
  }
  o.recon.plan = c.plan; /* one plan for the run (track_peaks_setup) */
  o.recon.bin_px = o.bin_px;
  o.recon.volume_plan = c.vplan; /* --bin-px: the binned volumes' */
  if (isnan(*t0_s)) *t0_s = cli_now_s();
  const double t0 = *t0_s;
  elfm_recon_stats rs;
  memset(&rs, 0, sizeof rs);
  elfm_status st = elfm_recon_run(o.events, &calib, &o.recon, NULL, &c, &rs, &err);
  if (o.few_check && (st == ELFM_OK || rs.input_error) && c.n_det < o.few_first_det) {
    /* the integral found less than the time surface did: back to it */
    again->back_exp = 1; /* the rest as the first run left it */
    if (!o.quiet)
      fprintf(stderr, "\neventlfm track: the integral found %" PRId64 " detections, the time "
                      "surface %" PRId64 ": starting again with --repr exp\n",
              c.n_det, o.few_first_det);
    rc = TRACK_RUN_AGAIN;
    goto done;
  }
  if (c.stage_outrun) {
    /* a slow stage's long windows, outrun: back to the first run's 1 ms */
    again->stage_back = 1;
    if (!o.quiet)
      fprintf(stderr, "\neventlfm track: the stage sped up (median %.2f um/ms, %.1f um per %" PRId64
                      " us window, at frame %" PRId64 "): starting again with --motion stage at 1 ms "
                      "windows\n",
              c.stage_outrun_speed, c.stage_outrun_speed * 1e-3 * (double)o.recon.framer.dt_us,
              o.recon.framer.dt_us, c.n_frames);
    rc = TRACK_RUN_AGAIN;
    goto done;
  }
  if (o.stage_watch && st == ELFM_OK && c.n_frames < TRACK_STAGE_SLOW_MIN_WINDOWS && rs.events > 0 &&
      rs.t_last_us >= rs.t_first_us) {
    /* A slow stage's long windows were chosen when the stage was found,
     * before the recording's end was known: when that came within a few
     * windows, fewer than TRACK_STAGE_SLOW_MIN_WINDOWS of them hold too
     * few points for a track (stage 0.2 mm/s, 30 ms: 4 windows of 10 ms
     * and no track on 13 of seeds 1-40). Again with windows of a tenth of
     * the recording, as a stage judged at its end gets, or at 1 ms when
     * that is under TRACK_STAGE_SLOW_MIN_DT_US. */
    const int64_t cap = (rs.t_last_us - rs.t_first_us) / TRACK_STAGE_SLOW_MIN_WINDOWS / 100 * 100;
    again->stage_short = again->stage = 1; /* --motion stage alone, as the first run chose */
    again->integral = 0;
    again->blur_px = -1;
    again->dt_us = cap >= TRACK_STAGE_SLOW_MIN_DT_US ? cap : -1;
    again->tau_follows = again->dt_us > 0;
    if (!o.quiet)
      fprintf(stderr, "\neventlfm track: the recording (%.1f ms) held only %" PRId64 " windows of %" PRId64
                      " us: starting again with --motion stage at %" PRId64 " us windows\n",
              1e-3 * (double)(rs.t_last_us - rs.t_first_us), c.n_frames, o.recon.framer.dt_us,
              again->dt_us > 0 ? cap : (int64_t)1000);
    rc = TRACK_RUN_AGAIN;
    goto done;
  }
  /* auto's choices: stopped by on_volume, or judged at the end (a short
   * run, fewer than TRACK_HINT_DIM_EARLY_PEAKS); an input error is met
   * again by the second run */
  if (c.auto_stopped || ((st == ELFM_OK || rs.input_error) && auto_judge(&c, TRACK_WIDTH_MIN_PEAKS, 1))) {
    /* a stage: --motion stage alone (it turns the others off) */
    const int others = !c.motion_restart;
    again->stage = c.motion_restart;
    again->blur_px = others && c.blur_restart ? 1 : -1;
    again->integral = others && c.repr_restart;
    again->few = others && c.few_restart;
    again->first_det = c.n_det;
    again->back_exp = 0;
    again->each_trigger = c.start_restart;
    again->lin = c.start_restart && c.lin_restart;
    again->prior_only = o.motion == MOTION_STAGE && c.votes.have_v && !c.motion_restart && !c.start_restart &&
                        !c.lin_restart && !c.blur_restart;
    /* the integral's windows: the worm's 2 ms (500 Hz) unless given; a
     * slow stage's, longer (track_stage_slow_dt_us) */
    again->dt_us = !others ? track_stage_slow_dt_us(&c)
                   : c.dt_restart ? o.recon.framer.dt_us / 2
                   : c.slow_restart ? TRACK_SLOW_BEADS_DT_US
                   : c.repr_restart && o.dt_auto ? 2000 : -1;
    again->tau_follows = again->dt_us > 0 && (!others || c.slow_restart);
    again->stride_us = others && c.stride_restart ? o.recon.framer.dt_us / 2 : -1;
    track_again_judged(again, &c);
    track_again_say(&c, again);
    rc = TRACK_RUN_AGAIN;
    goto done;
  }
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
  if (st == ELFM_OK) st = track_fill_gaps(&c, 1, &err);
  if (st == ELFM_OK) st = elfm_link_finish(c.lk, &err);
  if (st == ELFM_OK) st = track_drain(&c, 1, &err);
  if (st == ELFM_OK) st = track_stage_flush(&c, &err);
  if (st == ELFM_OK) st = track_det_flush_before(&c, INT64_MAX, &err);
  if (st == ELFM_OK) st = close_file(&c.fdet, c.p_det, &err);
  if (st == ELFM_OK) st = close_file(&c.ftr, c.p_tr, &err);
  if (st == ELFM_OK) st = close_file(&c.ffr, c.p_fr, &err);
  if (st == ELFM_OK) st = track_write_xml(&c, p_isbi, p_tm, &err);
  double wall = cli_now_s() - t0;
  c.median_speed_um_per_ms = track_median_speed_um_per_ms(&c);
  if (st == ELFM_OK) st = track_write_summary(&c, &rs, wall, p_sum, input_failed ? &input_err : NULL, &err);
  if (input_failed) {
    cli_fail(C, &input_err);
    if (st != ELFM_OK) cli_fail(C, &err);
    goto done;
  }
  /* no event taken: said, the outputs are valid and empty */
  if (st == ELFM_OK && !o.quiet) cli_note_no_events(C, o.events, o.recon.from_us, o.recon.to_us, rs.events);
  /* no window opened by the triggers asked for: the outputs are written
   * (empty), but such a run is not a success */
  if (st == ELFM_OK && cli_check_trigger_start(C, &o.recon.framer, o.events, c.n_frames, rs.triggers))
    goto done;
  const int pulsed = track_pulsed(&c);
  if (st == ELFM_OK && o.start_auto && pulsed && c.n_info > 0) {
    /* Pulsed light found only now (the first peaks were judged before the
     * frames showed it, or a settled run): one window per pulse (docs/
     * tracker.md "Windows opened by the LED", "The LED's windows by
     * default"). The run's files are written again. */
    again->each_trigger = 1;
    again->lin = track_lin_choosable(&o) && !(c.median_speed_um_per_ms < TRACK_HINT_PULSED_MIN_SPEED_UM_PER_MS);
    again->blur_px = -1; /* as the run had it */
    if (!o.auto_chose) track_again_judged(again, &c); /* the first run's judgement, for summary.json */
    if (!o.quiet)
      fprintf(stderr, "eventlfm track: the recording's %" PRId64 " trigger edges come with its events "
                      "(the frames with an edge hold %.0fx the others', a peak in %.0f %% of them, "
                      "%.0f %% of the others): pulsed light; starting again "
                      "with %s--start each-trigger, one window per pulse (--start first: keep the grid; "
                      "score with --frames run --window-us run; README, blinking objects)\n",
              c.n_triggers, track_pulsed_ratio(&c), track_peaked_pct(&c, 1), track_peaked_pct(&c, 0),
              again->lin ? "--repr lin " : "");
    rc = TRACK_RUN_AGAIN;
    goto done;
  }
  if (st != ELFM_OK) {
    cli_fail(C, &err);
    /* what was found before the error is not lost: the detections gap
     * filling still held (best effort; the file may be what failed) */
    elfm_error e2;
    if (c.fdet) track_det_flush_before(&c, INT64_MAX, &e2);
    /* and the tracks written to tracks.csv so far, to the XML files */
    if (c.xml) track_write_xml(&c, p_isbi, p_tm, &e2);
    goto done;
  }
  if (!o.quiet)
    fprintf(stderr, "eventlfm track: %" PRId64 " volumes, %" PRId64 " detections, %zu tracks "
                    "(%" PRId64 " started) in %.2f s (%.0f volumes/s, realtime factor %.2f) -> %s\n",
            c.n_frames, c.n_det, c.n_info, elfm_link_n_started(c.lk), wall,
            wall > 0 ? (double)c.n_frames / wall : 0.0, wall > 0 ? rs.span_s / wall : 0.0, o.out);
  if (!o.quiet && o.motion == MOTION_STAGE) say_stage(&c, &o, 1e3 * rs.span_s);
  /* crowded frames (TRACK_CROWD_OCC), when a tenth of them or more were:
   * what track did there, and how to fix it instead */
  if (!o.quiet && c.n_frames > 0 && 10 * c.n_crowded >= c.n_frames &&
      (o.view_support_auto || o.rescue_auto || o.gate_auto)) {
    const char *what[3] = {o.view_support_auto ? "a peak needed more of its views" : NULL,
                           o.rescue_auto ? "the linker's rescue reached less far" : NULL,
                           o.gate_auto ? "the linker's gate was narrower" : NULL};
    char list[160] = "";
    for (int k = 0, m = 0; k < 3; k++)
      if (what[k]) {
        strncat(list, m++ ? ", " : "", sizeof list - strlen(list) - 1);
        strncat(list, what[k], sizeof list - strlen(list) - 1);
      }
    fprintf(stderr, "eventlfm track: note: %" PRId64 " of %" PRId64 " frames crowded (over %.0f %% of "
                    "the views' pixels with signal; %.1f %% on average): there %s (--view-support, "
                    "--rescue-factor, --gate-um fix them; README, docs/tracker.md \"Crowded "
                    "frames\")\n",
            c.n_crowded, c.n_frames, 100 * TRACK_CROWD_OCC, 100 * track_occupancy_mean(&c), list);
  }
  /* (not for a slow stage's long windows: chosen for it, "Windows for a
   * slow stage", where the integral tracked worse) */
  if (!o.quiet && !o.stage_watch && o.recon.framer.repr != ELFM_REPR_INTEGRAL &&
      o.recon.framer.polarity == ELFM_POL_ON) {
    const double v = c.median_speed_um_per_ms;
    if (v >= TRACK_HINT_MIN_SPEED_UM_PER_MS && v <= TRACK_HINT_MAX_SPEED_UM_PER_MS)
      fprintf(stderr, "eventlfm track: note: the tracks move slowly (median %.2f um/ms): ON events "
                      "lead such objects along their motion; --repr integral places them where "
                      "they are (README, docs/tracker.md)\n", v);
  }
  const double frame_ms =
      1e-3 * (double)(o.recon.framer.stride_us ? o.recon.framer.stride_us : o.recon.framer.dt_us);
  /* Not under the LED's windows (one per pulse, whatever --dt-us says),
   * nor for a stage whose new tracks start at its velocity, given or
   * found by the frames' shift: its linker follows 8 um a frame (stage
   * at 8 mm/s: error 0.03 %, docs/tracker.md "A stage found by its
   * frames' shift") */
  const double *pv = o.link.prior_velocity_um_per_ms;
  const int stage_prior = o.motion == MOTION_STAGE && (pv[0] != 0 || pv[1] != 0 || pv[2] != 0);
  if (!o.quiet && o.recon.framer.repr != ELFM_REPR_INTEGRAL && !track_led_windows(&o) && !stage_prior &&
      c.median_speed_um_per_ms * frame_ms >= TRACK_HINT_MAX_STEP_UM) {
    const int64_t half_us = o.recon.framer.dt_us / 2;
    fprintf(stderr, "eventlfm track: note: the tracks move fast (median %.2f um/ms, %.1f um per "
                    "frame): beyond ~%.1f um per frame the linker loses objects between frames; "
                    "shorter windows follow them (--dt-us %" PRId64 "; README)\n",
            c.median_speed_um_per_ms, c.median_speed_um_per_ms * frame_ms, TRACK_HINT_MAX_STEP_UM,
            half_us);
  }
  /* the notes for pulsed light when its choices were given (--start,
   * --repr): only where the frames show it (track_pulsed), not for edges
   * that are not the light's, such as a frame clock's */
  if (!o.quiet && pulsed && o.recon.framer.repr == ELFM_REPR_EXP &&
      c.median_speed_um_per_ms >= TRACK_HINT_PULSED_MIN_SPEED_UM_PER_MS)
    fprintf(stderr, "eventlfm track: note: the recording has %" PRId64 " trigger edges and the "
                    "frames with one hold %.0fx the others' events (pulsed light), and its objects "
                    "move (median %.2f um/ms): on the exponential surface a pulse that ends late "
                    "in a window shows again in the next frame; --repr lin keeps each pulse in its "
                    "own (README, blinking objects)\n",
            rs.triggers, track_pulsed_ratio(&c), c.median_speed_um_per_ms);
  if (!o.quiet && pulsed && !track_led_windows(&o) &&
      c.median_speed_um_per_ms < TRACK_HINT_PULSED_MIN_SPEED_UM_PER_MS)
    fprintf(stderr, "eventlfm track: note: the recording has %" PRId64 " trigger edges and the "
                    "frames with one hold %.0fx the others' events (pulsed light): --start "
                    "each-trigger opens a window at each rising edge, one pulse to a frame, which "
                    "a pulse at a random phase against the window grid is not; score such a run "
                    "with --frames run --window-us run (README, blinking objects)\n",
            rs.triggers, track_pulsed_ratio(&c));
  /* a deep window given, where it cannot be (track_opts_derive): said,
   * not an error, since auto's later choices (the LED's windows, the blur)
   * may be what turned it off */
  if (!o.quiet && o.deep_window_us > 0 && o.recon.framer.deep_window_us == 0)
    fprintf(stderr, "eventlfm track: note: --deep-window-us %" PRId64 " was given, but the deep "
                    "window needs the ON time surface on a fixed grid, unblurred, without the "
                    "median and without --agree: it was off in this run (summary.json "
                    "deep_window_us)\n",
            o.deep_window_us);
  dim_note(&c, 0);
  track_views_note(&c);
  rc = CLI_OK;
done:
  track_ctx_free(&c);
  return rc;
}

int cmd_track(int argc, char **argv)
{
  track_opts o;
  int pr = track_opts_parse(argc, argv, &o);
  if (pr != CLI_OK) return pr == TRACK_PARSE_HELP ? CLI_OK : pr;
  /* starting again reads the events again: a file, not a pipe */
  struct stat sb;
  if ((o.blur_auto || o.dt_auto || o.repr_auto || o.motion_auto || o.start_auto || o.lin_auto ||
       track_votes_wanted(&o)) &&
      (stat(o.events, &sb) != 0 || !S_ISREG(sb.st_mode))) {
    o.blur_auto = o.dt_auto = o.repr_auto = o.motion_auto = o.start_auto = o.lin_auto = 0;
    o.shift_judged = 1; /* --motion stage's shift would start again too (cmd_track_vote.h) */
  }
  const int was = (o.blur_auto ? 1 : 0) | (o.dt_auto ? 2 : 0) | (o.repr_auto ? 4 : 0) |
                  (o.motion_auto ? 8 : 0) | (o.start_auto ? 16 : 0) | (o.lin_auto ? 32 : 0);
  track_again again;
  memset(&again, 0, sizeof again);
  double t0_s = NAN;
  int rc = track_run(&o, &again, &t0_s);
  if (rc != TRACK_RUN_AGAIN) return rc;
  /* Each further run is the command with the choices so far given last (so
   * the choices bring their own defaults: the blur's thresholds, the
   * integral's, each-trigger's), and nothing automatic left but the start
   * (a finished run may still find pulsed light). At most: auto's choices,
   * back to the time surface, each-trigger. */
  char dt[32], stride[32];
  int stage_watch = 0;
  char **argv2 = malloc(((size_t)argc + 24) * sizeof *argv2);
  if (!argv2) return cli_message("track", CLI_FAIL, "out of memory");
  int argc2 = 0;
  for (int i = 0; i < argc; i++) argv2[argc2++] = argv[i];
  pr = CLI_OK;
  for (int round = 0; rc == TRACK_RUN_AGAIN && pr == CLI_OK && round < 3; round++) {
#if defined(__GLIBC__)
    /* The run's memory back to the system: glibc's worker-thread arenas
     * kept it, and the second run's peak RSS was 20 MB higher than
     * --blur-px 1 alone (125 against 104 MB on dim flow 400 ms; 105 with). */
    malloc_trim(0);
#endif
    double ratio = again.ratio, speed = again.speed_um_per_ms;
    if (again.each_trigger) {
      argv2[argc2++] = "--start";
      argv2[argc2++] = "each-trigger";
      if (again.lin) {
        argv2[argc2++] = "--repr";
        argv2[argc2++] = "lin";
      }
      if (again.blur_px > 0) {
        argv2[argc2++] = "--blur-px";
        argv2[argc2++] = "1";
      }
    } else if (again.stage_back) {
      /* the slow stage's long windows were outrun: the command as given,
       * then --motion stage, as a stage found at 1 ms runs */
      argc2 = argc;
      argv2[argc2++] = "--motion";
      argv2[argc2++] = "stage";
      stage_watch = 0;
    } else if (again.back_exp) {
      /* the time surface, as the first run had it: the command as given,
       * then --repr exp */
      argc2 = argc;
      argv2[argc2++] = "--repr";
      argv2[argc2++] = "exp";
      ratio = speed = NAN;
    } else {
      if (again.stage_short) {
        /* the slow stage's windows were too long for the recording: the
         * command as given, then --motion stage and the shorter windows
         * (watched), or the first run's 1 ms */
        argc2 = argc;
        stage_watch = 0;
      }
      if (again.stage) {
        argv2[argc2++] = "--motion";
        argv2[argc2++] = "stage";
      }
      if (again.integral) {
        argv2[argc2++] = "--repr";
        argv2[argc2++] = "integral";
      }
      if (again.blur_px > 0) {
        argv2[argc2++] = "--blur-px";
        argv2[argc2++] = "1";
      }
      if (again.dt_us > 0) {
        snprintf(dt, sizeof dt, "%" PRId64, again.dt_us);
        argv2[argc2++] = "--dt-us";
        argv2[argc2++] = dt;
        if (again.tau_follows) { /* the time surface keeps the window's events */
          argv2[argc2++] = "--tau-us";
          argv2[argc2++] = dt;
          stage_watch = again.stage; /* a slow stage's, watched */
        }
      }
      if (again.stride_us > 0) {
        snprintf(stride, sizeof stride, "%" PRId64, again.stride_us);
        argv2[argc2++] = "--stride-us";
        argv2[argc2++] = stride;
      }
    }
    argv2[argc2] = NULL;
    const int few = !again.each_trigger && !again.back_exp && again.few;
    pr = track_opts_parse(argc2, argv2, &o);
    if (pr != CLI_OK) break;
    track_again_settle(&o, was, &again, ratio, speed);
    o.few_check = few;
    o.few_first_det = again.first_det;
    o.stage_watch = stage_watch;
    o.stage_back = again.stage_back;
    o.stage_short = again.stage_short;
    rc = track_run(&o, &again, &t0_s);
  }
  free(argv2);
  if (pr != CLI_OK) return pr == TRACK_PARSE_HELP ? CLI_OK : pr;
  return rc == TRACK_RUN_AGAIN ? CLI_FAIL : rc; /* cannot: nothing is automatic now */
}
