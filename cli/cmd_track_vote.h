/* cmd_track_vote.h — the shift between consecutive frames' detections,
 * for a stage (cmd_track_vote.c). A stage moves every bead by one vector,
 * which two frames' detections show without tracks
 * (elfm_analysis_shift_vote). Two uses:
 *  - --motion auto's test by tracks (TRACK_RIGID_*, cmd_track.h) needs
 *    tracks of 5-8 points; under an LED's pulses a stage at 5-6 mm/s
 *    carries the beads 15-18 um from one pulse to the next (8 um a 1 ms
 *    frame at 8 mm/s on continuous light), beyond the linker's gate, and
 *    few tracks grow that long, or those that do link other beads: where
 *    the tracks find no stage, the shift may (not
 *    while pulsed light may yet be found, track_rigid_judge);
 *  - the stage's run then starts each new track at the shift's velocity
 *    (the linker's prior_velocity_um_per_ms, as a given stage velocity
 *    does), where it had started one at rest; --motion stage without a
 *    velocity measures the shift first and starts again with it.
 * docs/tracker.md "A stage found by its frames' shift". */
#ifndef CMD_TRACK_VOTE_H
#define CMD_TRACK_VOTE_H

#include <stdint.h>

#include "elfm_tracker.h"

/* A frame's TRACK_VOTE_POINTS brightest peaks (the detector's, not weak:
 * the same in every run on the same windows, whatever the linker does)
 * are kept when they are TRACK_VOTE_MIN_POINTS or more; such a frame and
 * the one kept before it, at most TRACK_VOTE_MAX_GAP_MS earlier, are a
 * pair. The pair agrees when one shift carries TRACK_VOTE_MIN_SHARE of the
 * smaller frame's points (and TRACK_VOTE_MIN_POINTS) to within
 * TRACK_VOTE_TOL_UM (z over the linker's kz) of the other's, the shift is
 * TRACK_VOTE_MIN_SHIFT_UM or longer (shorter, points that did not move
 * match too: slow samples are the tracks' to judge) and the matched
 * points' displacements scatter by at most TRACK_RIGID_MAX_DEV of it (RMS;
 * a flow's beads, whose speeds differ, do not); it gives a velocity, the
 * shift over the time apart. The first TRACK_VOTE_PAIRS pairs are judged
 * (fewer, at least TRACK_VOTE_MIN_PAIRS, when the frames end first): they
 * move as one when TRACK_VOTE_MIN_SHARE of them agree, their velocities
 * within TRACK_RIGID_MAX_DEV of the median by the median, at
 * TRACK_RIGID_MIN_SPEED_UM_PER_MS or more. Measured: blink_moving 200 ms
 * at 5-6 mm/s, 16 of 16 pairs agree, their velocities a median 0.9-2.2 %
 * from the median; flow and random flow under the same pulses, no pair
 * (the rule re-run on their detections by a script). */
#define TRACK_VOTE_POINTS 16
#define TRACK_VOTE_MIN_POINTS 3
#define TRACK_VOTE_MAX_GAP_MS 20.0
#define TRACK_VOTE_TOL_UM 2.0
#define TRACK_VOTE_MIN_SHIFT_UM 4.0
#define TRACK_VOTE_MIN_SHARE 0.5
#define TRACK_VOTE_MIN_PAIRS 10
#define TRACK_VOTE_PAIRS 16

typedef struct track_votes {
  double kz;                                   /* the linker's */
  double prev[TRACK_VOTE_POINTS][3];           /* the frame kept last */
  int n_prev;
  int64_t prev_t_us;
  double cur[TRACK_VOTE_POINTS][3], cur_intensity[TRACK_VOTE_POINTS]; /* the frame being read */
  int n_cur;
  double *vel;          /* [TRACK_VOTE_PAIRS][3]: the agreeing pairs' velocities, um/ms */
  int n_pairs, n_agree; /* pairs so far, those agreeing */
  int judged;           /* track_votes_judge has said 0 or 1 */
  int have_v;           /* ... 1: the pairs move as one, */
  double v_um_per_ms[3]; /* ... at the agreeing pairs' median velocity, */
  double abs_um_per_ms;  /* ... their median distance from it */
  int by_shift;         /* --motion auto found the stage by them (track_rigid_judge) */
} track_votes;

struct track_opts;
/* Whether a run of these options takes the shift: --motion auto, or
 * --motion stage without a velocity; not when a run before this one
 * judged it (o->shift_judged). */
int track_votes_wanted(const struct track_opts *o);
/* Allocate (0: out of memory) and free; without init (vel NULL) the
 * other calls do nothing and the judgement is "not a stage". */
int track_votes_init(track_votes *v, double kz);
void track_votes_free(track_votes *v);
/* One detection of the frame being read: kept when a peak among its
 * brightest. */
void track_votes_point(track_votes *v, const elfm_detection *d);
/* The frame (at t_us) is read: pair it with the frame kept before. */
void track_votes_end_frame(track_votes *v, int64_t t_us);
/* Judge the pairs (at_end: the frames are all in): 1 they move as one,
 * with the agreeing pairs' median speed (um/ms) and their velocities'
 * median distance from the median (um/ms and over the speed) in *speed,
 * *abs_um_per_ms, *dev, and v->have_v, v->v_um_per_ms set; 0 they do not
 * (those left as they are); -1 too few pairs yet. Once it has said 0 or
 * 1, it says the same again. */
int track_votes_judge(track_votes *v, int at_end, double *speed, double *abs_um_per_ms,
                      double *dev);

#endif
