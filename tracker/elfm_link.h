/* elfm_link.h — streaming frame-to-frame linking of detections into tracks.
 *
 * Per frame (elfm_link_step):
 *  1. every live track predicts its position at the frame's time from a
 *     constant-acceleration fit to its last `short_history` real points:
 *     in the next frame with that fit (objects on curved paths: the flow
 *     scene's beads turn ~17 degrees per millisecond), after missed frames
 *     as a constant-rate turn (the fit's velocity rotating at the rate its
 *     normal acceleration gives, at constant speed: it stays on the circle
 *     where an extrapolated acceleration diverges); with circle_points,
 *     a track dark for circle_after frames or more whose last
 *     circle_points points follow a circle better than a line is
 *     predicted along that circle at its fitted rate; tracks of 2-3
 *     points use a constant velocity fitted to their last `history` points,
 *     a track with one point prior_velocity_um_per_ms; while the recording's
 *     objects are at rest (rest_speed_um_per_ms), a track dark for more
 *     than short_gap frames is also looked for where it was;
 *  2. the frame's detections go into a FLANN exact k-d tree
 *     (FLANN_INDEX_KDTREE_SINGLE) in the anisotropic metric (z scaled by
 *     1/kz), and each track asks for the detections within its gate:
 *     gate_um + missed x gate_growth_um_per_frame + min(missed, short_gap)
 *     x speed_gate_frac x speed x frame interval, for a one-point track
 *     + birth_speed_um_per_ms x its missed + 1 frame intervals (at most
 *     birth_frames of them); and, at rest, within that gate of where it
 *     was, each detection at its lower cost;
 *  3. tracks and detections joined by a candidate pair form connected
 *     groups; each group is solved optimally (the Hungarian solver of
 *     elfm_score.h: most pairs, then least total cost; cost = squared
 *     anisotropic distance over the squared gate, plus gap_cost per missed
 *     frame so a continuing track beats one coming back from a gap); with
 *     priority_points, the group's tracks of that many points first, the
 *     younger ones then among the detections left;
 *  3b. a rescue round for established tracks left unmatched (rescue_gate_factor);
 *  4. unmatched detections start tracks (weak ones do not); a track that has missed more
 *     than max_gap_frames consecutive frames ends. Ended tracks with at
 *     least min_points real points become "finished" and can be taken with
 *     elfm_link_pop_finished as soon as they end (shorter ones are dropped).
 *  5. stitching (optional): a track reaching stitch_points points continues a
 *     dark live track whose recent path it follows; 5b (optional), a track
 *     about to end goes on as a younger one, too short for that yet, that
 *     follows its path;
 *  6. swap review (optional): a gap closing that does not fit is revisited
 *     a few frames later and the tails of two tracks exchanged when that fits;
 *  7. encounter review (optional, with 6): two tracks that came within
 *     encounter_um of each other are revisited the same way;
 *  8. twins (optional): a track about to end whose last points another,
 *     younger track held too continues as that track.
 * Memory: live tracks plus finished tracks not yet popped; per-frame
 * scratch is reused (it grows only when a frame has more objects than any
 * earlier one).
 */
#ifndef ELFM_LINK_H
#define ELFM_LINK_H

#include <stdint.h>

#include "elfm_recon.h"
#include "elfm_peaks.h"
#include "elfm_tracks.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct elfm_link_options {
  double gate_um;                  /* default 6 um: measured on the flow scene (4 um, the scoring
                                      gate, broke tracks of beads turning ~17 deg/ms) */
  double gate_growth_um_per_frame; /* default 0.05: +2.5 um after a 50-frame gap */
  double speed_gate_frac;          /* + this x speed x frame interval per missed frame (0.3) */
  double kz;                       /* anisotropy, default 4 (SPEC §7) */
  int max_gap_frames;              /* default 50: blinking beads stay dark <= 50 ms at 1 kHz */
  int min_points;                  /* default 5 real points */
  int history;                     /* default 20 points for the long velocity fit */
  int short_history;               /* default 8 points for the short acceleration fit */
  double short_path_um;            /* and over at most this much path (fewer points, >= 4);
                                      0 = off (default; track: 20 um, off with --motion stage
                                      and --repr integral) */
  int short_gap;                   /* default 6: missed frames the gate widens for turns */
  /* Long gaps on a circling path. The constant-rate turn takes its rate
   * from the short fit, a few um of path whose noise the turn carries
   * on: over a 10-30 frame gap it missed a flow bead by 15-37 um (median,
   * simulated helices with the detector's noise), where a circle through
   * the last 15-40 points misses by 4-7 um. So a track dark for at least
   * circle_after frames (default 2) is predicted on the circle fitted to
   * its last circle_points real points (0 = off, the default; >= 6):
   * their plane of least spread, the circle in it, the angle as a
   * constant rate in time. Only when the points cover at least
   * circle_min_arc_rad of it (1 rad), it is no wider than
   * circle_max_radius_um (60 um), and, travelled at its rate, it fits them
   * better than a straight line at constant velocity by
   * circle_line_ratio (0.5, root mean square in the linker's metric):
   * noisy depths of an object moving straight also fit a circle. */
  int circle_points;
  int circle_after;
  /* Objects that translate rigidly (a moving stage: --motion stage): with
   * straight_gaps = 1, a track that missed frames is predicted straight on
   * at the objects' common velocity, the per-axis median of the long
   * straight fits (`history` points) of the tracks seen in the last frame,
   * from the end of its own straight fit; with fewer than 3 such tracks at
   * its own straight fit's velocity. Not on the short fit's constant-rate
   * turn (default 0). A one-point track's gate then does not widen at
   * birth_speed_um_per_ms either: its velocity is the common one. Why: the
   * turn takes its rate from the short fit's curvature, which on a deep
   * bead's noisy points is noise, and carried over tens of dark frames it
   * went anywhere. Stage 200 ms seed 2: a bead at z 87 um dark for 43 frames
   * was predicted 44 um aside and 55 um shallower than its straight path
   * and took an in-focus bead entering the field there; the joined track,
   * 65 of its 68 points outliers, was dropped with both beads
   * (docs/tracker.md "Straight gaps on a stage").
   * straight_gaps = 2: straight on at the track's own straight fit's
   * velocity, never a common one, for objects that need not share one:
   * track sets it under the LED's windows, where a track has one point per
   * pulse and the short fit's turn is the depths' noise as well
   * (blink_moving: beads were predicted round a circle through a 40-frame
   * gap onto a bead 150 um on; docs/tracker.md "Straight through the
   * LED's dark gaps"). */
  int straight_gaps;
  /* With circle_points, a settled gap (elfm_link_settled_gaps) also gets
   * the circle through circle_gap_points real points on each side of it
   * (default 4; < 3 = none), and elfm_link_gap_predict follows it where the
   * two ends' turns each extrapolated over half the gap. Flow 100 ms seeds
   * 1-20 alpha 0.8315 -> 0.8408 (every seed up), held-out 21-32 0.8211 ->
   * 0.8259; 1 s seeds 1-8 0.7309 -> 0.7373, 9-12 0.6813 -> 0.6820 (3 / 6 /
   * 8 points: 0.8393 / 0.8393 / 0.8392 at 100 ms). With the fit's angle
   * unwrapped by its rate (link_circle.c), which a gap needs: 0.8398,
   * 0.8295, 0.7486, 0.6836. */
  int circle_gap_points;
  /* With circle_points, the open gaps gap filling walks (the frames before
   * a track's first point, elfm_link_settled_gaps, and after a finished
   * track's last, elfm_link_track_end) follow the circle through the
   * circle_end_points real points at that end (0 = off, the default; else
   * >= 6), when they follow one, instead of that end's constant-rate turn:
   * a deep bead lost at a track's end keeps circling. */
  int circle_end_points;
  /* The next frame, too, may be predicted along a circle: with
   * circle_next_path_um > 0, a track seen in the last frame also fits the
   * circle (same tests as above) through its last real points covering up
   * to that much path (at least 6 points, at most 64), and both that
   * circle and the short fit predict the next frame. Each prediction's
   * squared miss of the point the track then takes (linker metric) is
   * kept as a mean decaying by 0.3 per point; once 3 points are scored,
   * the circle predicts wherever its mean is the lower. Why: the short fit
   * is a parabola through ~20 um of path, and a bead turning half a
   * radian or more per frame (flow at 2 ms frames, 0.55-0.9 rad per
   * frame; faster beads) leaves it; a circle through the last turn
   * follows. On straight or irregular paths the circle is not fitted or
   * predicts worse, and the short fit stays. Flow 100 ms seeds 1-8 / 9-20
   * alpha 0.8763 -> 0.8779 / 0.8374 -> 0.8555; at 2 ms frames 0.737 ->
   * 0.780 / 0.699 -> 0.749 (docs/tracker.md "The next frame along a
   * circle"). 0 = off (default; track: 45 um where circle_points is on). */
  double circle_next_path_um;
  double circle_min_arc_rad;
  double circle_max_radius_um;
  double circle_line_ratio;
  double gap_cost;                 /* default 0.02 per missed frame (cost units above) */
  int max_candidates;              /* per track, default 8 */
  /* Time-surface lag correction (elfm_peaks.h): when tau_us > 0, each
   * detection attached to a track with a velocity is moved forward by the
   * surface's lag, in the caller's array too. 0 = off. */
  double lag_tau_us;
  /* With it, the ON leading-edge term (elfm_detection_correct_lag_lead):
   * detections move back by lead_sigmas x their width along the motion.
   * Default 0. */
  double lead_sigmas;
  /* Velocity a new track predicts with until it has two points (um/ms):
   * zero, or the stage velocity when the whole sample moves together. */
  double prior_velocity_um_per_ms[3];
  /* A track with one point has no velocity yet: its gate widens by
   * birth_speed_um_per_ms x the time since that point (default 5 um/ms, a
   * little above the fastest flow scene's 4 mm/s). */
  double birth_speed_um_per_ms;
  /* ... for at most birth_frames frame intervals (0 = no limit, the
   * default; track: 3 under the LED's windows). Past that, a dark one-point
   * track is looked for within those frames' reach of its point, not over
   * all it could have reached: after 30 dark frames that was 150 um, most
   * of the field, and any object in it continued the track (blink_moving,
   * 1 ms pulses every 3 ms: beads seen once at the field's edge took beads
   * entering 100 um away). */
  int birth_frames;
  /* While most live tracks with >= 4 points move slower than this (their
   * straight-line fit; or none has 4 points yet), a track of >= 2 points
   * dark for more than short_gap frames is looked for where it was, too,
   * not only where its velocity carries it: fitted to a few pulses of a
   * blinking object, that velocity can be their noise (static beads, 1 ms
   * pulses tens of frames apart). Default 0.5 um/ms (below it the motion
   * bias fades, elfm_smooth.h); 0 = off. */
  double rest_speed_um_per_ms;
  /* Trail suppression: a moving object's time surface leaves a second,
   * weaker peak behind it. An unmatched detection lying behind a matched one
   * (along its track's velocity, within speed x trail_us + gate_um, and
   * within gate_um of that line) is dropped instead of starting a track;
   * elfm_link_last_track_id returns -2 for it. 0 = off (default 2000 us:
   * twice the default tau of 1000 us). */
  double trail_us;
  /* Candidate search: the FLANN k-d tree (default) or brute force over all
   * pairs (for the benchmark and as a cross-check; same candidates). */
  int brute_force;
  /* Rescue round: tracks that missed frames and detections still unmatched
   * after the main assignment are assigned again (optimally) within
   * rescue_gate_factor x their gate, before any birth: a bead seen again
   * off its extrapolated path continues its track instead of starting a
   * new one (flow: tracks coasted through gaps while a twin was born). 0 = off;
   * default 2.5. Skipped when leftovers exceed 500 x 500. */
  double rescue_gate_factor;
  /* Weak (hysteresis) detections may join a track only within this
   * anisotropic distance of its prediction (and within its gate), in the
   * main and the rescue round: a ghost as bright as a deep bead must then
   * also sit where a track expects one. 0 = off (weak detections use the
   * track's gate, the rescue gate too). */
  double weak_gate_um;
  /* Stitching (step 5): a track reaching stitch_points real points (>= 4)
   * may be joined to a live track dark since before its first point, when
   * its points lie within stitch_gate_um (root mean square, anisotropic)
   * of that track's last stitch_history real points. 0 = off. */
  int stitch_points;
  double stitch_gate_um;  /* default 8 um */
  int stitch_history;     /* default 100 points */
  /* Not when the dormant track ran straight over that history (its points
   * within stitch_straight_frac x its chord of the chord; >= 10 frames and
   * a chord of >= 10 um) and the young one starts behind its end along the
   * chord by more than stitch_gate_um: an object moving straight does not
   * come back behind itself, but the next bead on the same line of a stage
   * phantom does. Default 0.1; 0 = off. */
  double stitch_straight_frac;
  /* Late stitching (step 5b): a track ending (dark for more than
   * max_gap_frames) goes on as a young track of at least this many points
   * and fewer than stitch_points, born after its end and passing step 5's
   * test, so one that would reach stitch_points only after the end is not
   * lost. 0 = off (default). */
  int stitch_late_points;
  /* Swap review (step 6): a gap closing whose junction does not fit (the
   * track's head and new tail, extrapolated to the middle of the gap, more
   * than gate_um apart) is revisited once the tail has swap_points real
   * points (>= 4); if another track seen during the gap fits better with
   * the tails exchanged (summed junction distance swap_ratio times smaller,
   * 0 < swap_ratio <= 1), they are exchanged. 0 = off (default; track: 6). */
  int swap_points;
  double swap_ratio;      /* default 0.5 */
  /* Encounter review (step 7, with swap_points > 0): two tracks whose
   * points in one frame lie within encounter_um (anisotropic) have met;
   * the frames they stay that close, and encounter_pad frames before, are
   * the encounter. Once both have swap_points points after it, their heads
   * (before it) and tails (after it) are joined the other way round when
   * that fits encounter_ratio times better, as in step 6. Why: two beads
   * passing within the axial blur give one or two detections at one spot
   * for a frame or two, both tracks take them without a gap, and each may
   * leave on the other's bead. 0 = off (default). */
  double encounter_um;
  int encounter_pad;      /* default 1 frame */
  /* Frames apart that do not end an encounter: up to this many in a row
   * with the two tracks apart, and then together again, are one encounter
   * (default 0; track: 4). Why: a deep pair whose images merge gives two
   * fits that flicker apart and together for a few frames; the tracks
   * cross in the second spell, which a review of the first alone never
   * sees (worm seed 5: neurons 4 and 5 at z -57 um, frames 9-11 and
   * 14-17). */
  int encounter_apart;
  double encounter_ratio; /* like swap_ratio, for encounters (default 0.5) */
  /* With circle_points, an encounter's heads are also joined to the tails
   * along their circles: the circle through each head's last circle_points
   * points (where one fits, elfm_link_circle), travelled at its rate, is
   * compared with the first swap_points points of each tail (mean squared
   * miss), and the tails are exchanged when the other way misses
   * encounter_circle_ratio times less (root of the summed mean squares;
   * within review_join_factor x gate_um too). 0 = off (default; track:
   * 0.5). Why: two flow beads on their helices that meet and part often
   * look like a straight crossing over the 8 points of the heads' and
   * tails' quadratic fits, while their 15-point circles say which way
   * each turned (flow 1 s: docs/tracker.md "Encounters along circles"). */
  double encounter_circle_ratio;
  /* While the objects are at rest (rest_speed_um_per_ms, as for the slow
   * line of a dark track), step 7 waits until both tracks have `history`
   * points after the encounter, and also exchanges the tails when straight
   * lines through up to `history` points of each head and tail join
   * crosswise encounter_line_ratio times better (root of the summed
   * squares) and within review_join_factor x the gate. 0 (the default)
   * = off; in [0, 1]. Why: two slow objects that stay merged for tens of
   * frames, as worm neurons crossing in z, leave 8-point quadratic fits
   * whose extrapolations over the encounter decide nothing. */
  double encounter_line_ratio;
  /* Steps 6 and 7 exchange tails only when both new joins lie within
   * review_join_factor x gate_um (root mean square): past that neither
   * extrapolation is known. Default 2; 0 = no limit. */
  double review_join_factor;
  /* Established tracks first (step 3): within a group, the tracks of at
   * least priority_points real points are assigned first and the younger
   * ones then among the detections left. Why: "most pairs first" let a
   * one-point track, whose gate is widened for its unknown speed, take an
   * established track's bead whenever that gave one more pair (the
   * established track then took a neighbour's detection, or none, and the
   * two tracks swapped beads). 0 = off: one assignment (default; track: 8). */
  int priority_points;
  /* Twins (step 8, run in step 1): a track about to end (dark for more
   * than max_gap_frames) whose last 4 x twin_points real points include
   * at least twin_points that a younger live track also holds, within
   * twin_um (anisotropic) in the same frame, is that track's twin: the two
   * are one object. The ending track takes the younger one's points after
   * its own last point and goes on with its state (as in step 5); the
   * younger one's identity ends. Why: the gap filling and the view fit
   * find a bead for a track that has lost it while a second track, born
   * on the same bead, holds it; the older one ends and the bead's
   * trajectory is cut in two (flow 1 s: docs/tracker.md "Twins at a
   * track's end"). Not with a younger track that has given pieces
   * (elfm_link_take_piece). 0 = off (default; track: 2 um, 5 points). */
  double twin_um;
  int twin_points;
} elfm_link_options;

void elfm_link_options_default(elfm_link_options *o);

typedef struct elfm_linker elfm_linker;

/* NULL (err filled) on bad options / no memory. Free with elfm_link_free,
 * which also frees live and unpopped finished tracks. */
elfm_linker *elfm_link_create(const elfm_link_options *o, elfm_error *err);
void elfm_link_free(elfm_linker *l);

/* Change the rescue round's rescue_gate_factor from the next elfm_link_step
 * on: a caller that knows how crowded each frame is (more objects near a
 * track's path, more of them another object's) sets it per frame. Checked
 * as elfm_link_create checks it (>= 0, finite); ELFM_ERR_INVALID otherwise,
 * the factor unchanged. */
elfm_status elfm_link_set_rescue_gate_factor(elfm_linker *l, double factor, elfm_error *err);
/* ... and gate_um (> 0, finite), likewise. */
elfm_status elfm_link_set_gate_um(elfm_linker *l, double gate_um, elfm_error *err);

/* Link the detections of one frame. Frames must come in increasing order
 * (gaps in the numbering count as missed frames); t_us must not decrease.
 * det may be modified (lag correction, see options) and its frame/t_us
 * fields are set to `frame`/`t_us`, its `claims` to the number of live
 * tracks that had it within their gate (step 2's candidates, before the
 * rescue). NaN positions are an ELFM_ERR_NUMERIC. */
elfm_status elfm_link_step(elfm_linker *l, int64_t frame, int64_t t_us, elfm_detection *det,
                           int n, elfm_error *err);

/* Where the live tracks of at least min_points real points expect their
 * object in the frame at t_us (the predictions elfm_link_step will use),
 * xyz_um[3 k .. 3 k + 2] for k < *n_out <= cap, in the linker's order, and
 * (intensity, may be NULL) the mean intensity of each one's last 3 real
 * points. Changes nothing. For track-guided detection (cmd_track). */
elfm_status elfm_link_predict(const elfm_linker *l, int64_t frame, int64_t t_us, int min_points,
                              double *xyz_um, double *intensity, int cap, int *n_out,
                              elfm_error *err);

/* A path as an arc of a circle travelled at a constant rate (the circle
 * fit, circle_points above): m + e1 x + e2 y with (x, y) = (cx, cy) + r_um
 * (cos a, sin a), a = angle0 + omega_rad_per_ms x (t - the fit's reference
 * time), in um, ms and radians; ok = 0: no circle. */
typedef struct elfm_link_circle {
  int ok;
  double m[3], e1[3], e2[3];
  double cx, cy, r_um;
  double angle0, omega_rad_per_ms;
} elfm_link_circle;

/* ---- Gap filling (cmd_track's back-fill). A track that coasted through
 * frames where its object left no peak has a gap; once the track has
 * settle_points real points after the gap, the gap is settled (the swap
 * review, at swap_points, has had its say). The caller, who still holds
 * those frames, may then search them near where the two ends put the
 * object and give the linker what it found. Only the track's past
 * changes: its last settle_points points, and so its predictions, do not. */
typedef struct elfm_link_gap {
  int64_t track_id;
  int open_start;               /* 1: the frames before the track's first point (frame1):
                                   frame0 is only how far back to look, p0 v0 a0 are unset */
  int open_end;                 /* 1: the frames after a finished track's last point
                                   (frame0): frame1 is only how far on to look, p1 v1 a1
                                   are unset (elfm_link_track_end) */
  int64_t frame0, frame1;       /* the real points before and after (frame1 > frame0 + 1) */
  int64_t t0_us, t1_us;
  double p0_um[3], v0_um_per_ms[3], a0_um_per_ms2[3]; /* the head's fit at frame0 */
  double p1_um[3], v1_um_per_ms[3], a1_um_per_ms2[3]; /* the tail's fit at frame1 */
  double intensity;             /* mean intensity of up to 3 real points on each side */
  elfm_link_circle circle;      /* with circle_points: the circle through the points on
                                   both sides (reference time t0_us), when they follow one;
                                   an open gap's, with circle_end_points, through the
                                   points at its end (t0_us is that end's time) */
} elfm_link_gap;

/* The gaps the last elfm_link_step settled: of each live track that got a
 * point in that step, the gap before its settle_points-th last point, if
 * any, and when that point is its first, the frames before it back to
 * max_gap_frames (open_start: where the object was before the track began);
 * so each gap is reported once. all != 0 (at the end of a recording,
 * before elfm_link_finish): instead every gap of every live track with
 * fewer than settle_points points after it, the ones never settled. At
 * most cap into out (the rest are dropped); *n_out = count. */
elfm_status elfm_link_settled_gaps(const elfm_linker *l, int settle_points, int all,
                                   elfm_link_gap *out, int cap, int *n_out, elfm_error *err);

/* Where the gap's object was at t_us: on the gap's circle when it has one
 * (circle.ok, open gaps too); else the head's and the tail's constant-rate
 * turns (elfm_link_predict), forward from frame0 and backward from frame1,
 * blended linearly in time (open_start: the tail's; open_end: the head's). */
void elfm_link_gap_predict(const elfm_link_gap *g, int64_t t_us, double xyz_um[3]);

/* The open gap after finished track t's last point (open_end), up to
 * max_gap_frames on, its head fit over the last o->short_history points
 * (and its circle, o->circle_end_points): where the object went after the
 * track lost it. */
void elfm_link_track_end(const elfm_track *t, const elfm_link_options *o, int max_gap_frames,
                         elfm_link_gap *g);

/* Whether a gap walk's find pts[j] (pts[0 .. m): the walk's finds, any
 * order) has a neighbour in the next or the last frame within r_um
 * (lateral, z / kz): another find, or the gap's end there (the head's fit
 * p0_um at frame0 unless open_start, the tail's p1_um at frame1 unless
 * open_end). For finds a walk is less sure of (a fit started beside the
 * prediction): a bead does not jump between frames, and clutter found by
 * chance has no such neighbour. */
int elfm_link_fill_confirmed(const elfm_link_gap *g, const elfm_detection *pts, int m, int j,
                             double kz, double r_um);

/* Give live track `track_id` real points d[0 .. n) in frames with no point
 * yet before its last point (its gaps, or before its first). ELFM_ERR_INVALID
 * when the track is not live or a frame is taken or not before the last. */
elfm_status elfm_link_fill(elfm_linker *l, int64_t track_id, const elfm_detection *d, int n,
                           elfm_error *err);

/* End every live track (end of the recording): they become finished. */
elfm_status elfm_link_finish(elfm_linker *l, elfm_error *err);

/* Take the oldest finished track (caller owns it: elfm_track_free), or NULL. */
elfm_track *elfm_link_pop_finished(elfm_linker *l);

/* ---- Long tracks in bounded memory. A live track keeps its real points
 * until it ends, so one followed for minutes would hold them all. Once a
 * live track has at least piece_points + keep_points points of its own (not
 * yet given in a piece), this gives a piece of it (the caller owns it: a
 * copy, partial = 1, elfm_tracks.h): its own frames run from the previous
 * piece's end up to the frame of the track's keep_points-th last point
 * (the cut), and it also holds the points before them that the live track
 * still has and context_points points after the cut, for the smoother.
 * The live track then drops its points before the context_points ones
 * ahead of the cut, which stay as the next piece's context, and becomes a
 * piece itself (partial, its own frames from the cut on): it ends as the
 * last piece. Its last keep_points points, the ones linking, the reviews
 * (which look back ~100 points) and gap filling (60 frames) use, are
 * untouched. One piece per call into *out, NULL when no live track is
 * due. ELFM_ERR_INVALID with context_points > keep_points, piece_points < 1
 * or keep_points < 64. */
elfm_status elfm_link_take_piece(elfm_linker *l, size_t piece_points, size_t keep_points,
                                 size_t context_points, elfm_track **out, elfm_error *err);

/* Speed (um/ms) of the track detection i of the LAST step joined, from its
 * recent history; NaN for a new track or i out of range. */
double elfm_link_last_speed(const elfm_linker *l, int i);
/* How far detection i of the LAST step lay from the position its track
 * predicted for it (um, the linker's metric: z divided by kz), for a track
 * of 5 points or more that was seen in the frame before; NaN otherwise
 * (a new track, a track back from a gap, i out of range). The miss is the
 * detections' noise plus the motion the predictor cannot follow: helical
 * flow at 1 ms frames misses by ~1-1.5 um, random flow by ~2-3 um
 * (docs/tracker.md "Frames twice as often for turning beads"). */
double elfm_link_last_miss_um(const elfm_linker *l, int i);
/* The same track's velocity (um/ms) into v_um_per_ms, and (each when not
 * NULL) its long constant-velocity fit's over the last `history` points
 * into v_long_um_per_ms and the time those points span into *long_span_ms
 * (NaN for a new track, one point or i out of range); returns its number
 * of points (0: no track). */
size_t elfm_link_last_velocity(const elfm_linker *l, int i, double v_um_per_ms[3],
                               double v_long_um_per_ms[3], double *long_span_ms);

/* The velocity (um/ms) of the line fitted by least squares through t's
 * real points within half_frames frames of frame (by their t_us); returns
 * the number of points, 0 (v unchanged) when fewer than 3 or their times
 * do not differ. */
int elfm_link_local_velocity(const elfm_track *t, int64_t frame, int half_frames,
                             double v_um_per_ms[3]);

/* The live track of that id (read only; valid until the next call that
 * changes the linker), NULL when none is live. */
const elfm_track *elfm_link_live_track(const elfm_linker *l, int64_t track_id);

/* Live tracks right now, and how many tracks were started in total. */
size_t elfm_link_n_live(const elfm_linker *l);
/* The earliest frame of a point the linker still holds (live tracks and
 * finished ones not yet taken), INT64_MAX when none. */
int64_t elfm_link_oldest_frame(const elfm_linker *l);
int64_t elfm_link_n_started(const elfm_linker *l);
/* Tracks that step 8 continued as a younger twin (elfm_link_options.twin_um). */
int64_t elfm_link_n_twins(const elfm_linker *l);
/* Tracks that step 5b continued as a young track (elfm_link_options.stitch_late_points). */
int64_t elfm_link_n_late_stitches(const elfm_linker *l);

/* Id of the track detection i of the LAST step joined (a new track when it
 * matched none), -2 when it was suppressed as a trail, -3 when it was weak
 * (elfm_detection.weak: it may continue a track, never start one) and
 * joined none, -1 when i is out of range. */
int64_t elfm_link_last_track_id(const elfm_linker *l, int i);

#ifdef __cplusplus
}
#endif
#endif
