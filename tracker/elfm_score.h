/* elfm_score.h — scoring detections and tracks against simulator truth
 * (SPEC §7), and the project's one assignment solver (Hungarian).
 *
 * DISTANCE. Every comparison uses the anisotropic distance
 *     d = sqrt(dx^2 + dy^2 + (dz / kz)^2),  kz = 4,
 * because the refocused PSF is ~5x longer along z than across (SPEC §2:
 * 21.0 um axial vs 3.9 um lateral FWHM), and the gate eps = 4 um (about one
 * lateral FWHM). A pair "matches" when d < eps (strict, as the official ISBI
 * evaluator's `ed < maxDist`).
 *
 * TRUTH. truth.csv rows (id, t_us, x, y, z, brightness) are grouped per id,
 * must be strictly increasing in t_us within an id, and are linearly
 * interpolated (all of x, y, z, brightness) at each frame's t_us. An object
 * counts at a frame only when (a) t_us lies within its first..last sample,
 * (b) its interpolated brightness is > 0 and (c) it lies inside the
 * reconstructed volume when bounds are given: |x|, |y| <= (W-1)/2 * um_per_px
 * and z_min <= z <= z_max (calib.json; without a calibration all count).
 *
 * FRAMES. Integer frame indices and their t_us come from detections.csv and
 * tracks.csv (every row carries both; a frame index seen with two different
 * t_us is an error). Frames missing from both files (no detection, no track
 * point) but lying between known frames get a t_us interpolated linearly
 * between their known neighbours, so that truth there still counts as missed.
 * Frames before the first or after the last row are unknown unless the
 * caller gives the run's frame count (n_frames_hint below).
 * Only frames whose t_us lies within the truth's time range (its first to
 * its last sample, over all ids) are scored; the detections and track points
 * of the others count neither way (n_frames_unscored). Why: the truth is the
 * scored sequence, as an ISBI ground truth's frames are; beyond its end it
 * says nothing, not "nothing is there". A simulated 100 ms flow run has a
 * frame at 100001 us (window ends follow the first event at 1 us) and one
 * more of the pixels' latency stragglers, whose beads are there: counted,
 * they were ~20 false detections and as many extra track points per run
 * (seed 1: 20 and 20). Before the eighth session they were counted: the same runs
 * of flow seeds 1-20 score F1 0.9433 -> 0.9461 and alpha 0.7687 -> 0.7741
 * with this rule alone (docs/bench.md).
 * A run with no row at all has no frame list: if the truth shows any object
 * (bright, inside the volume) it scores recall = F1 = alpha = beta = Jaccard
 * = 0, with n_truth_points = 0 (unknown) and precision undefined (NaN).
 *
 * DETECTIONS (per frame). Truth points and detections are matched one to one
 * with the Hungarian solver below, pairs with d >= eps being forbidden: the
 * matching has the largest number of pairs within the gate and, among those,
 * the smallest summed d. Its pairs are the true positives (TP). recall = TP / truth points, precision = TP /
 * detections, F1 = 2 TP / (truth points + detections); RMSE of x, y and z
 * (um, plain differences, no kz) over the TP pairs (and, where the file has
 * raw_x_um, raw_y_um and raw_z_um, all three, the same pairs' at those:
 * rmse_raw_*). Without detections.csv the
 * real (non-gap-filled) rows of tracks.csv at their raw_* positions are used
 * as the detections.
 * alpha_detections = 1 - (sum of d over the TP pairs + eps x unmatched truth
 * points) / (eps x truth points): the ISBI alpha (below) of the tracks a
 * linker would make from these detections if it put every matched detection,
 * at its detected position, on its own object's track and nothing else. It
 * tells a linker's losses (alpha below it) from the detector's (the bound
 * itself): on simulated flow, 20 seeds, 0.792 against an alpha of 0.766.
 * It is not a strict bound: a track's smoothed positions can lie nearer the
 * truth than its raw detections (that is what smoothing is for), and a
 * matching of fewer pairs can, rarely, have the smaller summed cost.
 *
 * IDENTITIES (not SPEC §7; a diagnostic for linkers). Each real point of
 * the tracks belongs to the truth object nearest to it in its frame within
 * the gate (none beyond). alpha_identities is the ISBI alpha (below) of the
 * tracks made by giving every such point, at its smoothed position, to one
 * track per object (the nearest point when two share a frame), the others
 * staying on their own tracks: what these points would score with no
 * swapped or broken identities. Its distance from alpha is what the
 * linking costs (simulated flow 100 ms, 20 seeds: 0.842 against an alpha
 * of 0.796). Of the truth
 * points, identity_fragments are points of an object in a track other than
 * its best one (the track with most of its points) whose points are mostly
 * that object's, and identity_other_tracks those in tracks that mostly
 * follow another object.
 *
 * TRACKS (ISBI 2012, Chenouard et al., Nat. Methods 11:281 (2014), following
 * the official evaluation software, Chenouard's TrackToTrackDistance /
 * OneToOneMatcher / PerformanceAnalyzer, Feb 2012):
 *  - A candidate track Y is the rows of tracks.csv with one track_id whose
 *    raw_x_um/raw_y_um/raw_z_um are present (gap-closing fills are left out);
 *    its positions are the smoothed x_um, y_um, z_um. Like the official
 *    importer we treat the frames between its first and last real point as
 *    its span S(Y); frames of the span without a real point are "virtual":
 *    they never match and are never counted as spurious detections.
 *    R(Y) is the set of frames where Y has a real point.
 *  - A truth track X is one truth id at every frame where it counts (above);
 *    F(X) is that set of frames.
 *  - d(X, Y) = sum over frames t in F(X) u R(Y) of
 *        d_t      if X and a real point of Y exist at t and d_t < eps,
 *        eps      otherwise (one of them missing, or beyond the gate).
 *    d(X, empty) = eps * |F(X)|;  d(Ybar, empty) = eps * |R(Ybar)|.
 *    A frame where X does not count and Y has only a virtual (gap-filled)
 *    point carries no information and adds nothing: SPEC §7 leaves virtual
 *    rows out. (The official evaluator's truth tracks have a point at every
 *    frame of their span, so there the question never arises; for a blinking
 *    bead, whose truth is dark between pulses, charging eps for every dark
 *    frame of a correctly gap-closed track would pair it with nothing.)
 *    A frame where X counts and Y is virtual still costs eps (a miss).
 *  - Pairing: a pair (X, Y) is feasible if at least one frame matches. Each
 *    truth track is assigned to one feasible candidate or to its own dummy
 *    track (cost d(X, empty)), each candidate to at most one truth track,
 *    minimising sum of d(X, Y) (Hungarian; infeasible pairs forbidden).
 *  - alpha = 1 - sum_pairs d(X, Y) / sum_X d(X, empty)            (0..1)
 *    beta  = (sum_X d(X, empty) - sum_pairs d(X, Y))
 *            / (sum_X d(X, empty) + sum_unpaired Ybar d(Ybar, empty))
 *    (a truth track paired with its dummy contributes d(X, empty) to the
 *    pair sum, i.e. zero to the numerator).
 *  - Track Jaccard = paired / (paired + missed truth tracks + unpaired
 *    candidates). Detection Jaccard = TP / (TP + FN + FP) with TP = matched
 *    frames of the pairs, FN = truth points not matched, FP = real points of
 *    paired candidates not matched plus all real points of unpaired ones.
 *    (The official code also counts virtual points of a candidate that lie
 *    outside its truth track's span as spurious; we count real points only.)
 *  - rmse_tracks_um: RMS of the anisotropic d over the matched frames.
 *
 * MOTION BIAS (a calibration for `track --motion-lead-um/--motion-delay-us`,
 * elfm_smooth.h). For every matched detection whose truth moves laterally
 * at >= motion_lead_fade_um_per_ms (0.5 um/ms by default; truth velocity
 * v: central difference of the object's neighbouring frames that count, or
 * one-sided at its ends), the lateral error e = (detection - truth)_xy is
 * fitted by least squares as lead x L(v) - delay x M(v), where lead x L -
 * delay x M is the lateral part of the bias that elfm_motion_bias gives the
 * smoother for v (linear in lead and delay; the same fade speed): with the
 * views' disparities (motion_n_views > 0, from a calibration) the views'
 * model, without them the lateral model, where L =
 * v_xy / max(|v_xy|, 0.5) and M = v_xy, which is the regression of the error
 * along the motion on the lateral speed. Why the views' model: a bead
 * moving steeply in z has images moving every way in the views, whose
 * leads cancel in the lateral fit, and pooling such beads with the others
 * in the lateral model's regression biased both figures low (flow seeds
 * 1-8: lead 0.83 um and delay 311 us pooled, against 1.23 / 436 for the
 * beads with |v_z| < 0.3 |v_xy| alone; docs/tracker.md). motion_along_mean_um
 * is the mean of e . v / |v|. With the lateral speeds' standard deviation
 * below 0.25 um/ms (a stage at one speed) lead and delay cannot be told
 * apart: they are NaN and only that mean is given (pass it as the lead with
 * delay 0 for that speed).
 *
 * BY DEPTH (not SPEC §7; depth_band_um > 0). A Fourier LFM sees an object
 * less well the further it lies from focus (its 25 images widen and dim),
 * so the measures above are also given per band of the truth point's |z|:
 * band b holds |z| in [b w, (b + 1) w), the last band everything beyond
 * (ELFM_SCORE_MAX_DEPTH_BANDS bands in all). Per band: the truth points,
 * the detections' recall, RMSE x/y/z and alpha_detections over the truth
 * points of the band (the detection matching above, unchanged), and
 * alpha_tracks = 1 - (sum of min(d, eps) over the band's truth points) /
 * (eps x the band's truth points), where d is the distance to the point of
 * the truth track's paired candidate in that frame (eps when the object is
 * unpaired, or its candidate has no real point there or none within the
 * gate): the ISBI alpha's part that the band's points pay. Weighted by
 * their points, the bands' alpha_tracks average to the alpha above plus the
 * frames where only a paired candidate exists (eps each in d(X, Y)), which
 * belong to no truth depth (alpha_tracks_unplaced_cost below). Why: on
 * simulated flow every bead within 45 um of focus is found and nearly every
 * miss lies beyond 55 um (docs/tracker.md "Where the information runs
 * out"); a microscopist needs to know over which depths to trust a track.
 *
 * STAGE. With a stage velocity v_s (um/ms), the mean velocity vector v_m is
 * the mean of the vx/vy/vz_um_per_ms columns of tracks.csv over its real rows
 * (or, without those columns, of per-track displacement over time), and
 * stage_rel_error = |v_m - v_s| / |v_s|.
 *
 * All functions follow elfm_error.h: they fill err and return a status; they
 * never print. Allocation: the result is a plain value; everything else is
 * freed before returning.
 */
#ifndef ELFM_SCORE_H
#define ELFM_SCORE_H

#include <stdint.h>

#include "elfm_recon.h"
#include "elfm_table.h"

#ifdef __cplusplus
extern "C" {
#endif

/* ---------------------------------------------------------------------- */
/* Assignment (Hungarian / Kuhn-Munkres with potentials, O(n^2 m) for an
 * n x m problem with n <= m; rectangular problems of either shape).
 *
 * cost is n_rows x n_cols, row-major. A +INFINITY entry is forbidden (a pair
 * outside a gate). Any other non-finite entry (NaN, -inf) is an error
 * (ELFM_ERR_NUMERIC). The result maximises first the number of assigned
 * (non-forbidden) pairs and then minimises their total cost: forbidden
 * entries are replaced internally by a penalty larger than any difference of
 * finite totals, so precision is that of double sums (costs should not span
 * more than ~1e12 in ratio).
 * row_to_col[r] receives the column of row r, or -1 when unassigned;
 * *total_cost (may be NULL) the sum of the assigned costs.
 * The workspace holds all scratch; it grows (realloc) only when a problem is
 * larger than every earlier one, so a caller that reuses it in a loop stops
 * allocating once it has seen its largest problem. */
typedef struct elfm_assign_workspace elfm_assign_workspace;

/* Create a workspace pre-sized for problems up to max_rows x max_cols (0, 0
 * is fine: it grows on demand). Free with elfm_assign_workspace_free. */
elfm_status elfm_assign_workspace_create(int max_rows, int max_cols,
                                         elfm_assign_workspace **out, elfm_error *err);
void elfm_assign_workspace_free(elfm_assign_workspace *ws); /* NULL: no-op */

elfm_status elfm_assign_hungarian(const double *cost, int n_rows, int n_cols,
                                  int *row_to_col, double *total_cost,
                                  elfm_assign_workspace *ws, elfm_error *err);

/* ---------------------------------------------------------------------- */
/* Scoring. */

typedef struct elfm_score_options {
  double eps_um;           /* gate, 4 um (SPEC §7) */
  double kz;               /* axial weight divisor, 4 (SPEC §7) */
  int have_bounds;         /* 1: objects outside the volume below do not count */
  double x_half_um, y_half_um, z_min_um, z_max_um;
  int have_stage;          /* 1: compute stage_rel_error against stage_v */
  double stage_v_um_per_ms[3];
  /* > 0: the run had frames 0 .. n_frames_hint - 1 (e.g. summary.json's
   * volume count); frames before the first or after the last row of the
   * files then count too, their t_us extrapolated with the mean frame
   * spacing. 0 (default): only the span of frames seen in the files. */
  int64_t n_frames_hint;
  /* The run's frame list (`eventlfm track`'s frames.csv: frame, t_us,
   * t_start_us, t_end_us; borrowed, may be NULL). Every frame it lists
   * counts, with its own t_us, also frames without any row and frames that
   * are not evenly spaced (windows opened by trigger edges, `--start
   * each-trigger`). Rows of detections or tracks at a frame it does not
   * list, or with another t_us, are errors. Frames must increase in index
   * and time, with t_start_us <= t_us <= t_end_us and t_start_us <
   * t_end_us. Supersedes n_frames_hint. */
  const struct elfm_table *frames;
  /* 1 (needs frames): the window rule below over each frame's own window
   * [t_start_us, t_end_us) instead of (t_us - window_us, t_us]. Why: a
   * window cut short by a trigger edge ends where the pulse begins, and
   * its t_us sits on the edge, where the truth's brightness is interpolated
   * between a dark and a lit sample; its own window is dark. */
  int window_frames;
  /* > 0: a frame stands for the window (t_us - window_us, t_us] of events
   * that built it (the accumulation time dt of `eventlfm track`), and an
   * object counts at that frame when it was bright for at least half of that
   * window (by its truth samples), not only at t_us. Why: a time surface's
   * t_us is its window's end (SPEC §5), so a 1 ms LED pulse that lit a window
   * may have ended by t_us, and the literal rule then calls that frame dark
   * (blink, 200 ms: one of each bead's 5 pulses, F1 0.80 against 1.00,
   * docs/bench.md); "any light in the window" would instead also count the next
   * window, which sees only the pulse's OFF edge. With 1 ms pulses and 1 ms
   * windows exactly one frame per pulse counts. Positions are still
   * interpolated at t_us. 0 (default): the literal SPEC §7 rule. */
  double window_us;
  /* Most truth points (objects x frames where each counts) sampled before
   * giving up with ELFM_ERR_RANGE: 10 M by default (~0.5 GB; 20 beads over
   * 500,000 frames). The frame-index span is capped at 5 M frames. */
  int64_t max_truth_points;
  /* The views' disparities (um of image shift per um of z), set by
   * elfm_score_options_set_calib: the motion bias is then regressed on the
   * views' model (MOTION BIAS). 0 views: the lateral model. */
  int motion_n_views;
  double motion_view_g[ELFM_MAX_VIEWS][2];
  /* The model's fade speed (elfm_smooth.h motion_lead_fade_um_per_ms) and
   * the lateral speed below which a point is left out of the regression:
   * 0.5 um/ms by default; lower for slow samples (worm neurons: 0.05). */
  double motion_lead_fade_um_per_ms;
  /* > 0: the measures per band of this many um of |z| as well (BY DEPTH
   * above); 0 (default): none. Must be finite and >= 0. */
  double depth_band_um;
} elfm_score_options;

/* eps 4, kz 4, no bounds, no stage, no frame-count hint, 10 M truth points. */
void elfm_score_options_default(elfm_score_options *o);
/* Volume bounds from a calibration (SPEC §3 voxel grid). */
void elfm_score_options_set_calib(elfm_score_options *o, const elfm_calib *c);

/* One band of |z| (BY DEPTH above). Measures without a point to average
 * over are NaN. */
#define ELFM_SCORE_MAX_DEPTH_BANDS 16
typedef struct elfm_score_band {
  double z_lo_um, z_hi_um;      /* |z| in [z_lo, z_hi); z_hi INFINITY for the last band */
  int64_t n_truth_points, n_true_positives;
  double recall, rmse_x_um, rmse_y_um, rmse_z_um, alpha_detections;
  double alpha_tracks;          /* NaN without tracks */
} elfm_score_band;

typedef struct elfm_score_result {
  int n_frames;                 /* frames scored (known + interpolated) */
  int n_frames_unscored;        /* frames outside the truth's time range (FRAMES) */
  /* Under the literal rule (window_us 0, no window_frames): the
   * object-frames left out as dark at the frame's t_us, inside the volume,
   * although a truth sample since the frame before's t_us was lit. Pulsed
   * light ends before a time surface's window does, so a run on an LED's
   * pulses leaves most of its objects uncounted; the window rule counts
   * them. 0 under a window rule. */
  int64_t n_truth_lit_then_dark;
  /* detections */
  int detections_from_tracks;   /* 1: no detections table, raw track points used */
  int64_t n_truth_points, n_detections, n_true_positives;
  double recall, precision, f1; /* NaN when the denominator is 0 */
  double rmse_x_um, rmse_y_um, rmse_z_um;
  /* the same pairs' RMSE at the detections' raw_x/y/z_um, where
   * detections.csv has them (track's: its x/y/z_um are moved back by their
   * motion bias, the raw columns as measured); NaN otherwise */
  double rmse_raw_x_um, rmse_raw_y_um, rmse_raw_z_um;
  double alpha_detections;      /* DETECTIONS above; NaN without truth points */
  /* tracks (valid when has_tracks) */
  int has_tracks;
  int n_truth_tracks, n_candidate_tracks, n_paired_tracks, n_missed_tracks,
      n_spurious_tracks;
  int64_t n_track_tp, n_track_fn, n_track_fp;
  double alpha, beta, jaccard_tracks, jaccard_detections, rmse_tracks_um;
  /* IDENTITIES above (NaN without tracks or truth points) */
  double alpha_identities, identity_fragments, identity_other_tracks;
  /* motion bias of the detections (MOTION BIAS above); NaN without points */
  int64_t n_motion_points;
  double motion_lead_um, motion_delay_us, motion_along_mean_um, motion_speed_sd_um_per_ms;
  /* stage (valid when have_stage was set and tracks exist) */
  int has_stage;
  double mean_v_um_per_ms[3];
  double stage_rel_error;
  /* BY DEPTH (depth_band_um > 0): n_depth_bands bands, those with no truth
   * point included; alpha_tracks_unplaced_cost is the eps x candidate-only
   * frames of the pairs over eps x all truth points (what alpha loses
   * outside the bands; NaN without tracks) */
  int n_depth_bands;
  elfm_score_band depth_bands[ELFM_SCORE_MAX_DEPTH_BANDS];
  double alpha_tracks_unplaced_cost;
} elfm_score_result;

/* Score loaded tables. truth is required; tracks and detections may each be
 * NULL but not both. Column requirements: truth id,t_us,x_um,y_um,z_um,
 * brightness; detections frame,t_us,x_um,y_um,z_um; tracks track_id,frame,
 * t_us,x_um,y_um,z_um,raw_x_um,raw_y_um,raw_z_um (vx/vy/vz_um_per_ms
 * optional). Errors (missing column, empty/NaN required value, unsorted
 * truth, a duplicate frame in a track, inconsistent frame times, negative
 * brightness) name the table's file and line. */
elfm_status elfm_score_tables(const elfm_table *truth, const elfm_table *tracks,
                              const elfm_table *detections, const elfm_score_options *opt,
                              elfm_score_result *out, elfm_error *err);

/* Load the CSV files (tracks_csv or detections_csv may be NULL, not both)
 * and call elfm_score_tables. */
elfm_status elfm_score_files(const char *truth_csv, const char *tracks_csv,
                             const char *detections_csv, const elfm_score_options *opt,
                             elfm_score_result *out, elfm_error *err);

#ifdef __cplusplus
}
#endif
#endif
