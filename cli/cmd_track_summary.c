/* cmd_track_summary.c — eventlfm track's summary.json (see cmd_track.h). */
#include <cjson/cJSON.h>
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cmd_track.h"

/* Speed bins for the resolution figures (um/ms): static, slow, moderate, fast. */
#define N_SPEED_BINS 5
static const double speed_edges[N_SPEED_BINS] = {0, 0.05, 0.2, 0.5, 1e300};

/* A 3-vector; a component that is not finite (not known: a spread over
 * one track) is null, as add_num writes a number that is not. */
static cJSON *vec3(const double v[3])
{
  cJSON *a = cJSON_CreateArray();
  for (int k = 0; k < 3; k++)
    cJSON_AddItemToArray(a, isfinite(v[k]) ? cJSON_CreateNumber(v[k]) : cJSON_CreateNull());
  return a;
}

static void add_num(cJSON *o, const char *k, double v)
{
  if (isfinite(v)) cJSON_AddNumberToObject(o, k, v);
  else cJSON_AddNullToObject(o, k);
}

/* View v's lenslet (i, j) as [i, j]; null for v < 0 (none) */
static cJSON *view_ij(const elfm_calib *cal, int v)
{
  if (v < 0) return cJSON_CreateNull();
  const int ij[2] = {cal->views[v].i, cal->views[v].j};
  return cJSON_CreateIntArray(ij, 2);
}

/* The median and spread of FWHM a (0 lateral, 1 axial) over the beads
 * whose track's speed lies in [lo, hi), or over all beads (those of unknown
 * speed too) when `all`; tmp has room for l->n values. Returns the number
 * of beads. */
static size_t fwhm_median(const fwhm_list *l, int a, int all, double lo, double hi,
                          double *tmp, double *med, double *spr)
{
  size_t m = 0;
  for (size_t i = 0; i < l->n; i++)
    if (all || (l->b[i].speed >= lo && l->b[i].speed < hi)) tmp[m++] = l->b[i].fwhm_um[a];
  elfm_analysis_median(tmp, m, med, spr);
  return m;
}

static cJSON *fwhm_summary(const fwhm_list *l)
{
  cJSON *r = cJSON_CreateObject();
  double *tmp = malloc((l->n ? l->n : 1) * sizeof *tmp);
  if (!tmp) return r;
  /* the same figures for the lateral and the axial FWHM */
  static const char *const median_key[2] = {"fwhm_xy_um_median", "fwhm_z_um_median"};
  static const char *const spread_key[2] = {"fwhm_xy_um_spread", "fwhm_z_um_spread"};
  double med, spr;
  cJSON_AddNumberToObject(r, "n_beads", (double)l->n);
  for (int a = 0; a < 2; a++) {
    fwhm_median(l, a, 1, 0, 0, tmp, &med, &spr);
    add_num(r, median_key[a], med);
    add_num(r, spread_key[a], spr);
  }
  cJSON *bins = cJSON_AddArrayToObject(r, "by_speed");
  for (int b = 0; b + 1 < N_SPEED_BINS; b++) {
    const double lo = speed_edges[b], hi = speed_edges[b + 1];
    cJSON *o = cJSON_CreateObject();
    cJSON_AddNumberToObject(o, "speed_min_um_per_ms", lo);
    add_num(o, "speed_max_um_per_ms", b + 2 < N_SPEED_BINS ? hi : NAN);
    for (int a = 0; a < 2; a++) {
      size_t m = fwhm_median(l, a, 0, lo, hi, tmp, &med, &spr);
      if (a == 0) cJSON_AddNumberToObject(o, "n_beads", (double)m);
      add_num(o, median_key[a], med);
    }
    cJSON_AddItemToArray(bins, o);
  }
  free(tmp);
  return r;
}

double track_median_speed_um_per_ms(const track_ctx *c)
{
  double *v = c->n_info ? malloc(c->n_info * sizeof *v) : NULL;
  size_t m = 0;
  for (size_t i = 0; v && i < c->n_info; i++)
    if (isfinite(c->info[i].mean_lateral_speed_um_per_ms)) v[m++] = c->info[i].mean_lateral_speed_um_per_ms;
  double r = NAN, spread;
  if (m > 0) elfm_analysis_median(v, m, &r, &spread);
  free(v);
  return r;
}

/* The median miss the first peaks' tracks made (track_detection_miss_median),
 * as this run judged it or the first run (auto_chose); NaN: not judged. */
static double judged_miss_um(const track_ctx *c)
{
  if (c->o->auto_chose) return c->o->auto_miss;
  return c->miss_decided ? c->auto_miss : NAN;
}

elfm_status track_write_summary(const track_ctx *c, const elfm_recon_stats *rs, double wall_s,
                                const char *path, const elfm_error *input_err, elfm_error *err)
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
  /* the planes refocused on: the calibration's, or --z-*-um's */
  cJSON *vol = cJSON_AddObjectToObject(j, "volume");
  cJSON_AddNumberToObject(vol, "w", c->calib->view_w_px);
  cJSON_AddNumberToObject(vol, "h", c->calib->view_h_px);
  cJSON_AddNumberToObject(vol, "nz", elfm_calib_n_planes(c->calib));
  cJSON_AddNumberToObject(vol, "um_per_px", c->calib->um_per_px);
  cJSON_AddNumberToObject(vol, "z_min_um", c->calib->z_min_um);
  cJSON_AddNumberToObject(vol, "z_step_um", c->calib->z_step_um);
  /* every m-th of the calibration's planes (--plane-shift-px; 1: all) */
  cJSON_AddNumberToObject(vol, "calib_planes_per_plane", o->plane_every);
  cJSON *cnt = cJSON_AddObjectToObject(j, "counts");
  cJSON_AddNumberToObject(cnt, "events", (double)rs->events);
  cJSON_AddNumberToObject(cnt, "triggers", (double)rs->triggers);
  cJSON_AddNumberToObject(cnt, "volumes", (double)c->n_frames);
  cJSON_AddNumberToObject(cnt, "detections", (double)c->n_det);
  cJSON_AddNumberToObject(cnt, "peaks_rejected_view_support", (double)c->n_support_rejected);
  cJSON_AddNumberToObject(cnt, "peaks_explained_by_brighter", (double)c->n_explained);
  /* view_support_auto: how crowded the frames were, how many needed more
   * views than view_support, the most any needed */
  cJSON_AddNumberToObject(cnt, "frames_view_support_raised", (double)c->n_need_raised);
  cJSON_AddNumberToObject(cnt, "frames_crowded", (double)c->n_crowded);
  cJSON_AddNumberToObject(cnt, "peaks_placed_by_view_fit", (double)c->n_localized);
  cJSON_AddNumberToObject(cnt, "deep_peaks_dropped", (double)c->n_deep_dropped);
  cJSON_AddNumberToObject(cnt, "guided_view_fits", (double)c->n_guided_views);
  cJSON_AddNumberToObject(cnt, "pair_fits", (double)c->n_pair_fits);
  cJSON_AddNumberToObject(cnt, "guided_fits_beside", (double)c->n_guided_beside);
  cJSON_AddNumberToObject(cnt, "gap_fill_tries", (double)c->n_fill_tries);
  cJSON_AddNumberToObject(cnt, "gap_fills", (double)c->n_filled);
  cJSON_AddNumberToObject(cnt, "gap_fills_multi_frame", (double)c->n_filled_multi);
  cJSON_AddNumberToObject(cnt, "end_fills", (double)c->n_filled_end);
  cJSON_AddNumberToObject(cnt, "gap_fills_multi_frame_refused", (double)c->n_multi_refused);
  cJSON_AddNumberToObject(cnt, "gap_fills_retried", (double)c->n_filled_retry);
  cJSON_AddNumberToObject(cnt, "gap_fills_retried_unconfirmed", (double)c->n_retry_dropped);
  cJSON_AddNumberToObject(cnt, "tracks_started", (double)elfm_link_n_started(c->lk));
  cJSON_AddNumberToObject(cnt, "tracks_joined_twins", (double)elfm_link_n_twins(c->lk));
  cJSON_AddNumberToObject(cnt, "tracks_stitched_late", (double)elfm_link_n_late_stitches(c->lk));
  cJSON_AddNumberToObject(cnt, "tracks", (double)c->n_info);
  cJSON_AddNumberToObject(cnt, "tracks_rejected_outliers", (double)c->n_rejected);
  cJSON_AddNumberToObject(cnt, "tracks_rejected_off_stage", (double)c->n_rejected_stage);
  cJSON_AddNumberToObject(cnt, "tracks_refit_classical_gcv", (double)c->n_refit_gcv);
  cJSON_AddNumberToObject(cnt, "track_pieces", (double)c->n_pieces);
  cJSON_AddNumberToObject(cnt, "track_points", (double)c->n_points_kept);
  add_num(cnt, "median_track_speed_um_per_ms", c->median_speed_um_per_ms);
  int nm[5] = {0, 0, 0, 0, 0};
  for (size_t i = 0; i < c->n_info; i++) nm[c->info[i].model]++;
  cJSON *models = cJSON_AddObjectToObject(cnt, "models");
  for (int m = 1; m < 5; m++)
    cJSON_AddNumberToObject(models, elfm_motion_model_name((elfm_motion_model)m), nm[m]);

  cJSON *par = cJSON_AddObjectToObject(j, "parameters");
  cli_recon_options_json(par, &o->recon);
  cJSON_AddNumberToObject(par, "view_support", o->view_support);
  cJSON_AddBoolToObject(par, "view_support_auto", o->view_support_auto);
  cJSON_AddBoolToObject(par, "rescue_auto", o->rescue_auto);
  cJSON_AddBoolToObject(par, "gate_auto", o->gate_auto);
  if (o->view_support_auto) {
    cJSON_AddNumberToObject(par, "view_support_occupancy_mean", track_occupancy_mean(c));
    cJSON_AddNumberToObject(par, "view_support_max", c->need_max > 0 ? c->need_max : o->view_support);
  }
  cJSON_AddNumberToObject(par, "explain_brighter", o->explain_brighter);
  cJSON_AddNumberToObject(par, "explain_um", o->explain_um);
  cJSON_AddStringToObject(par, "localize", o->localize_views ? "views" : "peak");
  cJSON_AddNumberToObject(par, "localize_window_px", o->loc.half_window_px);
  cJSON_AddNumberToObject(par, "localize_power", o->loc.power);
  cJSON_AddNumberToObject(par, "localize_near_um", o->localize_near_um);
  cJSON_AddNumberToObject(par, "localize_outlier_px", o->loc.outlier_px);
  cJSON_AddNumberToObject(par, "localize_min_views", o->loc.min_views);
  cJSON_AddNumberToObject(par, "guided_views", o->guided_views);
  cJSON_AddNumberToObject(par, "guided_min_ratio", o->guided_min_ratio);
  cJSON_AddNumberToObject(par, "guided_apart_um", o->guided_apart_um);
  cJSON_AddNumberToObject(par, "pair_fit_um", o->pair_fit_um);
  cJSON_AddNumberToObject(par, "deep_window_us", (double)o->recon.framer.deep_window_us);
  cJSON_AddNumberToObject(par, "deep_window_um", o->recon.framer.deep_window_us > 0 ? o->deep_window_um : 0);
  cJSON_AddNumberToObject(par, "fill_views", o->fill_views);
  cJSON_AddNumberToObject(par, "fill_gate_um", o->fill_gate_um);
  cJSON_AddNumberToObject(par, "fill_max_gap", o->fill_max_gap);
  cJSON_AddNumberToObject(par, "fill_min_ratio", o->fill_min_ratio);
  cJSON_AddNumberToObject(par, "fill_frames", o->fill_frames);
  cJSON_AddBoolToObject(par, "fill_ends", o->fill_ends);
  cJSON_AddNumberToObject(par, "fill_retry_um", o->fill_retry_um);
  cJSON_AddNumberToObject(par, "threshold_k_sigma", o->peaks.k_sigma);
  cJSON_AddNumberToObject(par, "threshold_abs", o->peaks.absolute);
  cJSON_AddNumberToObject(par, "threshold_rel", o->peaks.relative);
  cJSON_AddNumberToObject(par, "threshold_depth_um", o->peaks.depth_range_um);
  cJSON_AddNumberToObject(par, "threshold_min", o->peaks.absolute_min);
  cJSON_AddNumberToObject(par, "deep_peak_views", o->deep_peak_views);
  cJSON_AddNumberToObject(par, "threshold_low", o->peaks.hysteresis_low);
  cJSON_AddBoolToObject(par, "views_rule", o->views_rule);
  cJSON_AddNumberToObject(par, "views_exponent", o->views_exponent);
  cJSON_AddNumberToObject(par, "plane_shift_px", o->plane_shift_px);
  cJSON_AddNumberToObject(par, "bin_px", o->bin_px);
  cJSON_AddNumberToObject(par, "fit_half_z", o->peaks.fit_half_z);
  cJSON_AddNumberToObject(par, "rescue_gate_factor", o->link.rescue_gate_factor);
  cJSON_AddNumberToObject(par, "stitch_points", o->link.stitch_points);
  cJSON_AddNumberToObject(par, "stitch_gate_um", o->link.stitch_gate_um);
  cJSON_AddNumberToObject(par, "stitch_late_points", o->link.stitch_late_points);
  cJSON_AddNumberToObject(par, "stitch_history", o->link.stitch_history);
  cJSON_AddNumberToObject(par, "swap_points", o->link.swap_points);
  cJSON_AddNumberToObject(par, "swap_ratio", o->link.swap_ratio);
  cJSON_AddNumberToObject(par, "encounter_um", o->link.encounter_um);
  cJSON_AddNumberToObject(par, "encounter_pad", o->link.encounter_pad);
  cJSON_AddNumberToObject(par, "encounter_apart", o->link.encounter_apart);
  cJSON_AddNumberToObject(par, "rest_speed_um_per_ms", o->link.rest_speed_um_per_ms);
  cJSON_AddNumberToObject(par, "encounter_ratio", o->link.encounter_ratio);
  cJSON_AddNumberToObject(par, "encounter_circle_ratio", o->link.encounter_circle_ratio);
  cJSON_AddNumberToObject(par, "encounter_line_ratio", o->link.encounter_line_ratio);
  cJSON_AddNumberToObject(par, "review_join_factor", o->link.review_join_factor);
  cJSON_AddNumberToObject(par, "twin_um", o->link.twin_um);
  cJSON_AddNumberToObject(par, "twin_points", o->link.twin_points);
  cJSON_AddNumberToObject(par, "priority_points", o->link.priority_points);
  cJSON_AddNumberToObject(par, "short_path_um", o->link.short_path_um);
  cJSON_AddNumberToObject(par, "circle_points", o->link.circle_points);
  cJSON_AddNumberToObject(par, "straight_gaps", o->link.straight_gaps);
  cJSON_AddNumberToObject(par, "circle_next_path_um", o->link.circle_next_path_um);
  /* as in effect: the open ends' circle needs circle_points */
  cJSON_AddNumberToObject(par, "circle_end_points",
                          o->link.circle_points > 0 ? o->link.circle_end_points : 0);
  cJSON_AddNumberToObject(par, "circle_after", o->link.circle_after);
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
  cJSON_AddNumberToObject(par, "birth_frames", o->link.birth_frames);
  cJSON_AddNumberToObject(par, "min_points", o->link.min_points);
  cJSON_AddNumberToObject(par, "max_outlier_frac", o->max_outlier_frac);
  cJSON_AddNumberToObject(par, "outlier_min_um", o->smooth.outlier_min_um);
  cJSON_AddNumberToObject(par, "piece_points", o->piece_points);
  cJSON_AddBoolToObject(par, "lag_correct", o->lag_correct);
  /* the lead the last tracks were smoothed with (all widths are in by then) */
  cJSON_AddNumberToObject(par, "motion_lead_um", track_motion_lead_um(c));
  cJSON_AddBoolToObject(par, "motion_lead_auto", o->motion_lead_auto);
  cJSON_AddNumberToObject(par, "motion_fast_lead_ms", o->lead_fast_ms);
  cJSON_AddNumberToObject(par, "motion_fast_um_per_ms", o->lead_fast_um_per_ms);
  cJSON_AddNumberToObject(par, "motion_lead_fast_cut_um", track_motion_lead_fast_um(c));
  cJSON_AddNumberToObject(par, "motion_blur_lead_um", o->lead_blur_um);
  cJSON_AddNumberToObject(par, "motion_lead_blur_cut_um", track_motion_lead_blur_um(c));
  cJSON_AddNumberToObject(par, "peak_widths_in_focus", (double)c->n_width);
  cJSON_AddNumberToObject(par, "peak_widths_near_focus", (double)c->n_width_near);
  add_num(par, "peak_width_median_um", track_peak_width_median_um(c));
  add_num(par, "peak_height_median", track_peak_height_median(c));
  cJSON_AddNumberToObject(par, "views_scaled_for", o->views_scaled);
  /* --blur-px auto, the automatic window and representation: whether
   * each was on, and what the first peaks showed, their median height over
   * the threshold and their tracks' median speed (blur_px, dt_us and repr
   * say what was chosen; auto_again: this run is the second, with those
   * choices) */
  const int was = o->auto_chose ? o->auto_was
                                : (o->blur_auto ? 1 : 0) | (o->dt_auto ? 2 : 0) | (o->repr_auto ? 4 : 0) |
                                      (o->motion_auto ? 8 : 0) | (o->start_auto ? 16 : 0) |
                                      (o->lin_auto ? 32 : 0);
  cJSON_AddBoolToObject(par, "blur_auto", was & 1);
  cJSON_AddBoolToObject(par, "dt_auto", (was & 2) != 0);
  cJSON_AddBoolToObject(par, "repr_auto", (was & 4) != 0);
  cJSON_AddBoolToObject(par, "motion_auto", (was & 8) != 0);
  cJSON_AddBoolToObject(par, "start_auto", (was & 16) != 0);
  cJSON_AddBoolToObject(par, "lin_auto", (was & 32) != 0);
  cJSON_AddBoolToObject(par, "auto_again", o->auto_chose);
  /* a slow stage's windows (dt_us, tau_us): this run's were lengthened, or
   * they were and the stage outran them (this run is back at 1 ms) */
  cJSON_AddBoolToObject(par, "stage_slow_windows", o->stage_watch);
  cJSON_AddBoolToObject(par, "stage_windows_outrun", o->stage_back);
  cJSON_AddBoolToObject(par, "stage_windows_too_few", o->stage_short);
  /* --motion auto: the median distance of the long tracks' velocities from
   * their frame's median velocity, over its length and in um/ms, and the
   * frames' median speed (NaN: not judged; track_rigid_judge): this run's
   * judgement (the LED's run tests too), else the run before's */
  const int rigid_before = o->auto_chose && !isfinite(c->rigid_dev);
  add_num(par, "auto_rigid_dev", rigid_before ? o->auto_rigid_dev : c->rigid_dev);
  add_num(par, "auto_rigid_speed_um_per_ms", rigid_before ? o->auto_rigid_speed : c->rigid_speed);
  add_num(par, "auto_rigid_abs_um_per_ms", rigid_before ? o->auto_rigid_abs : c->rigid_abs);
  /* ... a stage found by the frames' shift, where the tracks found none
   * (too few long ones, or linked across beads; cmd_track_vote.h) */
  cJSON_AddBoolToObject(par, "auto_rigid_by_shift",
                        rigid_before ? o->auto_rigid_by_shift : c->votes.by_shift);
  add_num(par, "auto_height_ratio", o->auto_chose ? o->auto_ratio : c->auto_decided ? c->auto_ratio : NAN);
  add_num(par, "auto_track_speed_um_per_ms", track_judged_speed_um_per_ms(c));
  add_num(par, "auto_prediction_miss_um", judged_miss_um(c));
  cJSON_AddNumberToObject(par, "motion_delay_us", o->smooth.motion_delay_us);
  cJSON_AddNumberToObject(par, "motion_lead_fade_um_per_ms", o->smooth.motion_lead_fade_um_per_ms);
  cJSON_AddNumberToObject(par, "motion_slow_lead_ms", o->smooth.motion_slow_lead_ms);
  cJSON_AddNumberToObject(par, "motion_slow_um_per_ms", o->smooth.motion_slow_um_per_ms);
  cJSON_AddNumberToObject(par, "view_fit_sigma_factor", o->smooth.view_fit_sigma_factor);
  cJSON_AddNumberToObject(par, "fit_sd_power", o->smooth.fit_sd_power);
  cJSON_AddNumberToObject(par, "gcv_gamma", o->smooth.gcv_gamma);
  cJSON_AddNumberToObject(par, "spline_order", o->smooth.spline_order);
  cJSON_AddBoolToObject(par, "spline_turn", o->smooth.spline_turn && o->smooth.spline_order == 3);
  cJSON_AddBoolToObject(par, "motion_along_path", o->smooth.motion_along_path != 0);
  cJSON_AddNumberToObject(par, "spline_weight_ms3", o->smooth.spline_weight_ms3);
  cJSON_AddStringToObject(par, "motion", o->motion == MOTION_STAGE ? "stage"
                                         : o->motion == MOTION_FREE ? "free" : "auto");
  cJSON_AddStringToObject(par, "model", elfm_motion_model_name(o->smooth.model));
  cJSON_AddStringToObject(par, "loss", o->smooth.loss == ELFM_LOSS_HUBER ? "huber"
                                       : o->smooth.loss == ELFM_LOSS_CAUCHY ? "cauchy" : "none");
  cJSON_AddNumberToObject(par, "loss_scale", o->smooth.loss_scale);
  if (o->has_stage_v) cJSON_AddItemToObject(par, "stage_velocity_um_per_ms", vec3(o->stage_v));
  /* the velocity a new track predicts with: the given stage's, or the one
   * the frames' shift found (track_again_settle, cmd_track_vote.h) */
  const double *pv = o->link.prior_velocity_um_per_ms;
  if (pv[0] != 0 || pv[1] != 0 || pv[2] != 0)
    cJSON_AddItemToObject(par, "prior_velocity_um_per_ms", vec3(pv));

  cJSON *tim = cJSON_AddObjectToObject(j, "timing");
  add_num(tim, "wall_s", wall_s);
  add_num(tim, "span_s", rs->span_s);
  add_num(tim, "events_per_s", rs->wall_s > 0 ? (double)rs->events / wall_s : NAN);
  add_num(tim, "volumes_per_s", wall_s > 0 ? (double)c->n_frames / wall_s : NAN);
  add_num(tim, "realtime_factor", wall_s > 0 ? rs->span_s / wall_s : NAN);
  add_num(tim, "peak_rss_mb", cli_peak_rss_mb());
  /* recon_s: the driver's wall time without the ordered callback's
   * (linking, writing); the driver reads, refocuses, delivers and smooths
   * at once (elfm_pipeline.h), so the stages' times overlap. parallel_s
   * (median, refocus and peak detection), peaks_s and smooth_s (every
   * track's smoothing, wherever it ran) are summed over the threads. */
  add_num(tim, "recon_s", rs->wall_s - rs->callback_s);
  add_num(tim, "read_s", rs->read_s);
  add_num(tim, "frame_s", rs->frame_s);
  add_num(tim, "parallel_s", rs->refocus_s);
  add_num(tim, "callback_s", rs->callback_s);
  add_num(tim, "peaks_s", c->t_peaks);
  add_num(tim, "link_s", c->t_link);
  add_num(tim, "smooth_s", c->t_smooth);

  if (c->n_info) {
    elfm_stage_result sr;
    if (elfm_analysis_stage_info(c->info, c->n_info, o->has_stage_v ? o->stage_v : NULL, &sr,
                                 err) == ELFM_OK) {
      cJSON *st = cJSON_AddObjectToObject(j, "stage");
      cJSON_AddItemToObject(st, "velocity_um_per_ms", vec3(sr.v_um_per_ms));
      cJSON_AddItemToObject(st, "velocity_sd_um_per_ms", vec3(sr.v_sd_um_per_ms));
      add_num(st, "speed_um_per_ms", sr.speed_um_per_ms);
      add_num(st, "speed_sd_um_per_ms", sr.speed_sd_um_per_ms);
      add_num(st, "rel_error", sr.rel_error);
      add_num(st, "speed_rel_error", sr.speed_rel_error);
      /* weighted by each track's time spread (elfm_analysis.h): the one to
       * quote on a slow stage, whose short edge tracks are biased */
      cJSON_AddItemToObject(st, "velocity_pooled_um_per_ms", vec3(sr.v_pooled_um_per_ms));
      add_num(st, "rel_error_pooled", sr.rel_error_pooled);
      cJSON_AddItemToObject(st, "acceleration_um_per_ms2", vec3(sr.accel_um_per_ms2));
      cJSON_AddItemToObject(st, "acceleration_sd_um_per_ms2", vec3(sr.accel_sd_um_per_ms2));
    }
  }
  if (o->resolution) cJSON_AddItemToObject(j, "resolution", fwhm_summary(&c->fl));
  {
    /* does the calibration fit? (cmd_track_views.c; null fields: too few fits to judge) */
    track_views_check k;
    track_views_judge(c, &k);
    cJSON *vc = cJSON_AddObjectToObject(j, "views_check");
    cJSON_AddNumberToObject(vc, "view_fits", (double)k.fits);
    cJSON_AddNumberToObject(vc, "view_fits_tried", (double)k.tries);
    cJSON_AddItemToObject(vc, "worst_view", view_ij(c->calib, k.worst));
    add_num(vc, "worst_mean_miss_px", k.worst_miss_px);
    cJSON_AddItemToObject(vc, "least_kept_view", view_ij(c->calib, k.least));
    add_num(vc, "least_kept_share", k.least_share);
    add_num(vc, "median_kept_share", k.median_share);
    cJSON_AddBoolToObject(vc, "views_off", k.off);
    /* every view as judged, for a look at the pattern (a view alone off, the
     * outer ring off together: docs/recon.md "Does the calibration fit?") */
    if (k.judged) {
      cJSON *va = cJSON_AddArrayToObject(vc, "views");
      for (int v = 0; v < c->calib->n_views; v++) {
        cJSON *e = cJSON_CreateObject();
        cJSON_AddItemToObject(e, "view", view_ij(c->calib, v));
        if (isfinite(k.miss_px[v][0]) && isfinite(k.miss_px[v][1]))
          cJSON_AddItemToObject(e, "mean_miss_px", cJSON_CreateDoubleArray(k.miss_px[v], 2));
        else
          cJSON_AddNullToObject(e, "mean_miss_px");
        add_num(e, "kept_share", k.share[v]);
        /* where its images lay: within ELFM_CALIB_STILL_PX of one place,
         * the view's miss is not judged (still: true, mean_miss_px null) */
        add_num(e, "images_spread_px", k.spread_px[v]);
        cJSON_AddBoolToObject(e, "still", k.still[v]);
        cJSON_AddItemToArray(va, e);
      }
    }
  }

  cJSON *tr = cJSON_AddArrayToObject(j, "tracks");
  for (size_t i = 0; i < c->n_info; i++) {
    const elfm_track_info *t = &c->info[i];
    cJSON *e = cJSON_CreateObject();
    cJSON_AddNumberToObject(e, "id", (double)t->id);
    cJSON_AddNumberToObject(e, "first_frame", (double)t->first_frame);
    cJSON_AddNumberToObject(e, "last_frame", (double)t->last_frame);
    cJSON_AddNumberToObject(e, "points", (double)t->n);
    cJSON_AddStringToObject(e, "model", elfm_motion_model_name(t->model));
    if (t->model == ELFM_MODEL_SPLINE) cJSON_AddNumberToObject(e, "spline_weight_ms3", t->spline_weight_ms3);
    if (t->model == ELFM_MODEL_SPLINE && t->spline_omega_rad_per_ms > 0)
      cJSON_AddNumberToObject(e, "spline_turn_rad_per_ms", t->spline_omega_rad_per_ms);
    add_num(e, "edf", t->edf);
    cJSON_AddNumberToObject(e, "outliers", t->n_outliers);
    /* a long track written in pieces (--piece-points): model, weight and
     * edf are its largest piece's */
    if (t->n_pieces > 1) cJSON_AddNumberToObject(e, "pieces", t->n_pieces);
    cJSON_AddItemToObject(e, "mean_velocity_um_per_ms", vec3(t->mean_vel_um_per_ms));
    cJSON_AddItemToArray(tr, e);
  }
  return cli_json_write(j, path, err);
}
