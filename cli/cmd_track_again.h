/* cmd_track_again.h — what one run of eventlfm track judged and chose
 * for the next (cmd_track.c starts the command again with it): the
 * choices, their messages on stderr, and the settled run's options. */
#ifndef CMD_TRACK_AGAIN_H
#define CMD_TRACK_AGAIN_H

#include <stdint.h>

#include "cmd_track.h"

/* What the first run chose for the second. */
typedef struct track_again {
  int blur_px;     /* -1: as given */
  int64_t dt_us;   /* -1: as given */
  int64_t stride_us; /* -1: as given */
  int integral;    /* 1: --repr integral */
  int stage;       /* 1: --motion stage (and nothing else) */
  int few;         /* 1: the integral because too few peaks were found to judge */
  int tau_follows; /* 1: --tau-us as long as dt_us too (a slow stage's, slow beads') */
  int64_t first_det; /* ... the first run's detections then */
  int back_exp;    /* 1: (from that second run) the time surface found more: --repr exp */
  int stage_back;   /* 1: a slow stage's long windows were outrun (TRACK_STAGE_WATCH_*):
                       the command with --motion stage, at its 1 ms windows */
  int stage_short;  /* 1: ... were too few for the recording (TRACK_STAGE_SLOW_MIN_WINDOWS):
                       the command with --motion stage and dt_us, tau following */
  int each_trigger; /* 1: pulsed light (track_pulsed): --start each-trigger */
  int lin;          /* 1: ... and the objects move: --repr lin too */
  double miss_um;  /* the first run's judged miss (track_detection_miss_median) */
  double ratio, speed_um_per_ms, rigid_dev, rigid_speed_um_per_ms, rigid_abs_um_per_ms;
  int rigid_by_shift;  /* ... judged by the frames' shift (cmd_track_vote.h) */
  int shift_judged;    /* that shift judged (in this run or one before), */
  int shift_agree, shift_pairs; /* ... in so many of its pairs of frames */
  int rigid_v_known;   /* ... it moves them as one, */
  double rigid_v_um_per_ms[3]; /* ... at this velocity */
  int prior_only;      /* 1: --motion stage's run found that velocity, and runs again with it */
} track_again;

/* What a run judged (its first peaks, the motion), for the next run's
 * summary.json (track_again_settle). */
void track_again_judged(track_again *g, const track_ctx *c);
/* Say on stderr what the next run starts again with, and why. */
void track_again_say(const track_ctx *c, const track_again *g);
/* A run after auto's choices: nothing automatic left, and summary.json
 * says what was automatic (was) and what the first run judged. */
void track_again_settle(track_opts *o, int was, const track_again *g, double ratio, double speed);

#endif
