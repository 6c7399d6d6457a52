/* cmd_track.h — what the files of `eventlfm track` share (private to it):
 * the options (cmd_track.c parses them), the run's context, the per-volume
 * work the recon driver calls back (cmd_track_volume.c), the finished
 * tracks' queue (cmd_track_finish.c) and the summary (cmd_track_summary.c). */
#ifndef ELFM_CMD_TRACK_H
#define ELFM_CMD_TRACK_H

#include <limits.h>
#include <stdint.h>
#include <stdio.h>
#include <threads.h>

#include "cli.h"
#include "cmd_track_auto.h"
#include "cmd_track_vote.h"
#include "elfm_tracker.h"

enum { MOTION_AUTO = 0, MOTION_STAGE, MOTION_FREE };

typedef struct track_opts {
  const char *calib, *events, *out;
  elfm_recon_options recon;
  double planes_um[3];  /* --z-min-um, --z-max-um, --z-step-um; NaN: the calibration's */
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
  int piece_points;    /* long tracks: a piece of this many points is smoothed and written
                          once a live track has it and piece_keep_points more (0 = off) */
  double guided_low;  /* track-guided search: min value near a prediction (0 = off) */
  double guided_radius_um;
  int guided_min_points;
  double view_support; /* a peak needs signal in this fraction of the views sampling it (0 = off) */
  int view_support_auto; /* ... or more in a crowded frame (track_view_support_need; on unless
                            --view-support is given, on time surfaces without the blur) */
  int rescue_auto;     /* the linker's rescue reaches less far in a crowded frame
                          (track_rescue_factor; on unless --rescue-factor is given, where
                          view_support_auto may be) */
  int gate_auto;       /* ... and its gate is narrower (track_gate_um; unless --gate-um) */
  double explain_brighter; /* ... not counting views a peak over 1 / this times brighter
                              explains (0 = off; track_detect_worker) */
  double explain_um;   /* ... within this of its image there (sample um) */
  int localize_views;  /* 1: each peak's position from its images in the views, 0: the peak fit */
  elfm_localize_options loc;
  double localize_near_um; /* the view fit takes out the light of other objects of the
                              frame within this lateral distance (0 = off), at most
                              TRACK_NEAR_MAX of them */
  int guided_views;    /* track-guided view fit: views that must agree (0 = off) */
  double guided_min_ratio; /* and its find at least this x the track's last intensity */
  double guided_apart_um;  /* and at least this far from the frame's other detections
                              (the linker's metric; 0 = off): nearer, it found their object */
  double pair_fit_um;  /* pair fits: two established tracks' predictions within this
                          laterally that share one detection get a view fit each
                          (cmd_track_guided.c; 0 = off) */
  int64_t deep_window_us; /* the deep window (elfm_framer_options.deep_window_us): -1
                          auto (default: 2 x dt), 0 off, else its length; on the ON
                          time surface of a fixed grid only (track_opts_derive) */
  double deep_window_um;  /* ... read by the track-guided fits started beyond this |z|
                          (track_guided_loc) */
  int deep_peak_views;  /* a peak above the depth-scaled threshold only is kept when the
                           view fit from it has this many views agreeing (0 = no test) */
  int fill_views;      /* gap filling: views that must agree (0 = off) */
  double fill_gate_um; /* a fill lands within this of where the gap's ends put the object */
  int fill_max_gap;    /* frames kept for it: gaps up to this long are filled */
  double fill_min_ratio; /* a fill is at least this x the intensity at the gap's ends */
  int fill_frames;     /* where the one-frame fit fails, fit this many frames centred on
                          the gap's frame (odd, 1..TRACK_FILL_MAX_FRAMES; 1 = off) */
  int fill_ends;       /* follow a finished track on past its last point the same way */
  double fill_retry_um; /* where the fit from the gap's prediction fails, start it again this
                           far beside it in x and y, and as far in z as moves the outer
                           views' images as much (0 = off) */
  int motion_lead_auto; /* 1: the lead from the in-focus peaks' widths (track_motion_lead_um) */
  double lead_fast_ms;  /* ... less this x (the judged speed - lead_fast_um_per_ms) um where
                           the speed the first peaks' tracks moved at is above that (0 = off) */
  double lead_fast_um_per_ms;
  double lead_blur_um;  /* ... and this much shorter on frames blurred (recon.blur_px > 0) */
  double plane_shift_px; /* without --z-step-um: every m-th of the calibration's planes, the
                            outermost view moving <= this between them (0 = all of them;
                            track_plane_step) */
  int bin_px;           /* --bin-px: peaks found in volumes refocused from the frames binned
                           bin_px x bin_px (elfm_recon_options.bin_px; 1: off); the view
                           fits stay on the full frames */
  int plane_every;      /* the m taken (1: the calibration's planes), for summary.json */
  int plane_centred;    /* m does not divide the calibration's range: centred, off its grid */
  int thr_defaulted;    /* 1 absolute, 2 hysteresis_low, 4 absolute_min: track's own
                           defaults, which coarser planes scale (track_plane_step) */
  int views_scaled;     /* track_views_step scaled them for this many views (0: not) */
  int views_defaulted;  /* 1 localize min_views, 2 guided_views, 4 fill_views, 8
                           deep_peak_views: track's own defaults, which fewer views
                           than 25 scale (track_views_step) */
  int blur_auto;        /* --blur-px auto (the default): the run starts without the blur
                           and starts again with --blur-px 1 when its first peaks are
                           faint (TRACK_HINT_DIM_FACTOR); 0 where it does not apply
                           (track_opts_derive) */
  int dt_auto;          /* the window (--dt-us not given): the run starts at 1 ms and
                           starts again at half of it when the first peaks' tracks
                           move TRACK_DT_AUTO_STEP_UM or more per frame; 0 where it
                           does not apply (track_opts_derive) */
  int repr_auto;        /* the representation (--repr, --tau-us, --polarity, --blur-px
                           not given): when the first peaks' tracks crawl, start
                           again with --repr integral (and 2 ms windows when --dt-us
                           is not given either); 0 where it does not apply */
  int lin_auto;         /* --repr, --tau-us, --polarity not given: under pulsed
                           light (start_auto) or --start each-trigger given, moving
                           objects start again with --repr lin, with a stage,
                           thresholds or the blur given as well */
  int motion_auto;      /* --motion auto (the default): when the first tracks move as
                           one (TRACK_RIGID_*), start again with --motion stage; 0
                           where it does not apply (track_opts_derive) */
  int start_auto;       /* --start not given: a run under pulsed light (track_pulsed)
                           starts again with --start each-trigger (and --repr lin
                           when its objects move); 0 where it does not apply
                           (track_opts_derive) */
  int auto_chose;       /* 1: this run is the second, with auto's choices */
  int auto_was;         /* ... and what was automatic in the first: 1 blur, 2 window,
                           4 representation, 8 motion, 16 start */
  double auto_ratio;    /* what the first run judged: median peak height over the
                           threshold, and the tracks' median speed, um/ms */
  double auto_speed;
  double auto_miss;     /* ... and the median miss of their predictions, um */
  double auto_rigid_dev, auto_rigid_speed, auto_rigid_abs; /* what the first run judged of
                                                              the motion */
  int auto_rigid_by_shift; /* ... by the frames' shift (cmd_track_vote.h) */
  int shift_judged;     /* a run before judged that shift (track_votes_wanted) */
  int few_check;        /* 1: this run is the integral after a time surface with too few
                           peaks to judge; it goes back to the time surface when it finds
                           fewer detections than few_first_det, the time surface's */
  int64_t few_first_det;
  int tau_given;        /* --tau-us was given (a slow stage's windows leave it alone) */
  int stage_watch;      /* 1: this run's windows were lengthened for a slow stage
                           (TRACK_STAGE_SLOW_*): it stops when the stage outruns them
                           (TRACK_STAGE_WATCH_*) */
  int stage_back;       /* 1: this run is back at 1 ms after such a run stopped */
  int stage_short;      /* 1: this run's windows are shorter after such a run held too
                           few (TRACK_STAGE_SLOW_MIN_WINDOWS) */
} track_opts;
#define TRACK_FILL_MAX_FRAMES 9
/* detections.csv's motion bias: the velocity of the line through the
 * track's points within this many frames of the detection (cmd_track_fill.c
 * det_bias) */
#define TRACK_DET_VELOCITY_HALF_FRAMES 3
/* The lead from the peaks' widths (track_motion_lead_um): widths of peaks
 * within TRACK_WIDTH_FOCUS_UM of focus, binned up to 10 um; at least
 * TRACK_WIDTH_MIN_PEAKS of them, else the fixed default. The lead is
 * TRACK_LEAD_AT_ZERO_WIDTH_UM + TRACK_LEAD_PER_WIDTH x their median, at
 * least 0: pixels that objects pass again and again (flows, swimming
 * animals), where the last object's OFF events left each reference above
 * the background. With --motion stage, where most pixels see a bead pass
 * once, TRACK_LEAD_PER_WIDTH_FIRST_PASS x the median (docs/tracker.md
 * "The lead in the sensor's steady state"); not under the LED's windows,
 * whose every pulse ends in OFF events over each bead (track_led_windows).
 * There the delay is TRACK_LED_DELAY_EXTRA_US longer than the surface's
 * mean age says: the pulse's onset fires the bead's pixels at the window's
 * start, older than the even spread of events that age assumes
 * (docs/tracker.md "The lead under the LED's windows"). */
#define TRACK_LED_DELAY_EXTRA_US 25.0
#define TRACK_WIDTH_BIN_UM 0.01
#define TRACK_WIDTH_BINS 1000
#define TRACK_WIDTH_FOCUS_UM 20.0
#define TRACK_WIDTH_MIN_PEAKS 50
/* ... and where fewer than TRACK_WIDTH_MIN_PEAKS lie that close to focus,
 * the peaks within TRACK_WIDTH_NEAR_UM: the median width hardly changes
 * out to 40 um (flow 100 ms seeds 1-2 by 10 um of |z|: 0.84-0.87 /
 * 0.81-0.84 / 0.80 / 0.78-0.79, stage 200 ms seed 4: 1.13 / 1.13 / 1.15),
 * and the 1.25 um default is a flow bead's lead, not a brighter bead's
 * (stage seed 11, its beads 20-90 um from focus: alpha 0.71 with it). */
#define TRACK_WIDTH_NEAR_UM 40.0
/* ... and where fewer than TRACK_WIDTH_MIN_PEAKS lie within either, the
 * in-focus peaks, then those near focus, if TRACK_WIDTH_FEW_PEAKS are in:
 * a slow stage's long windows are few (0.5 mm/s, 150 ms: 30 windows of 5
 * ms), and 5 of seeds 1-40 had 17-42 peaks in focus and 29-45 near it.
 * The flow default they kept, 1.25 um, is 0.5 um short of such a stage's
 * lead (1.52 x ~1.2 um): alpha 0.71-0.79 against 0.85 on average (docs/
 * tracker.md "The lead from fewer peaks"). */
#define TRACK_WIDTH_FEW_PEAKS 20
#define TRACK_HEIGHT_BINS 1024
/* The stage's consensus velocity (track_ctx.stage_*): tracks of at least
 * TRACK_STAGE_MIN_POINTS points (_LED_ under the LED's windows) count,
 * TRACK_STAGE_MIN_TRACKS make a consensus, the newest TRACK_STAGE_RING keep
 * it; a run that has held TRACK_STAGE_MAX_PENDING without one decides. */
#define TRACK_STAGE_MIN_POINTS 20
#define TRACK_STAGE_LED_MIN_POINTS 8
#define TRACK_STAGE_MIN_TRACKS 5
#define TRACK_STAGE_RING 32
#define TRACK_STAGE_MAX_PENDING 256
/* --motion auto's test for rigid motion (track_rigid_*, cmd_track_stage.c):
 * in each frame, the detections whose tracks have TRACK_RIGID_MIN_POINTS
 * points or more and whose long velocity fit (the linker's, over its last
 * 20 points) spans TRACK_RIGID_MIN_SPAN_MS or more, if there are
 * TRACK_RIGID_MIN_TRACKS of them, each give that velocity's distance from
 * the frame's median velocity, in um/ms (bins of
 * TRACK_RIGID_ABS_BIN_UM_PER_MS) and over that median's length (bins of
 * TRACK_RIGID_BIN). Once TRACK_RIGID_MIN_SAMPLES are in, the sample moves
 * as one (a stage) when the frames' median speed is
 * TRACK_RIGID_MIN_SPEED_UM_PER_MS or more and the median distance is
 * below TRACK_RIGID_MAX_DEV of it or below TRACK_RIGID_MAX_ABS_UM_PER_MS
 * (a slow stage's velocities differ by their noise, ~0.02 um/ms); a run
 * that has not gathered that many by frame TRACK_RIGID_MAX_FRAMES (few
 * objects, or objects that come and go) is not judged. Stages: 0.3-8 % or
 * 0.010-0.052 um/ms (0.017-0.024 at 0.15-0.19 um/ms); the nearest worm,
 * which crawls as one body, 30 % and 0.084 um/ms; flows 100 % and more
 * (docs/tracker.md "A stage found by its tracks"). Under the LED's
 * windows a track has a point per pulse: 15 ms hold 6 pulses 3 ms apart,
 * so TRACK_RIGID_LED_MIN_POINTS (one may be missed), and MAX_FRAMES
 * counts the frames that hold a pulse (blink_moving 4 mm/s seed 4: 37
 * samples from 11 frames by frame 200; "A stage under the LED's pulses"). */
#define TRACK_RIGID_MIN_POINTS 8
#define TRACK_RIGID_LED_MIN_POINTS 5
#define TRACK_RIGID_MIN_SPAN_MS 15.0
#define TRACK_RIGID_MIN_TRACKS 3
#define TRACK_RIGID_MIN_SAMPLES 64
#define TRACK_RIGID_MAX_DEV 0.15
#define TRACK_RIGID_MIN_SPEED_UM_PER_MS 0.1
#define TRACK_RIGID_MAX_FRAMES 200
#define TRACK_RIGID_MAX_ABS_UM_PER_MS 0.045
#define TRACK_RIGID_ABS_BIN_UM_PER_MS 0.001
#define TRACK_RIGID_BIN 0.005
#define TRACK_RIGID_BINS 400
#define TRACK_SPEED_BIN_UM_PER_MS 0.02
#define TRACK_SPEED_BINS 500
#define TRACK_MISS_BIN_UM 0.02
#define TRACK_MISS_BINS 500
#define TRACK_LEAD_PER_WIDTH 1.80
#define TRACK_LEAD_AT_ZERO_WIDTH_UM (-0.37)
#define TRACK_LEAD_PER_WIDTH_FIRST_PASS 1.52

/* The options (cmd_track_opts.c): track's defaults, then argv. CLI_OK: run
 * with *o; TRACK_PARSE_HELP: --help was printed (exit 0); otherwise the
 * CLI_USAGE already shown on stderr. */
#define TRACK_PARSE_HELP (-1)
int track_opts_parse(int argc, char **argv, track_opts *o);
/* track --help's text (cmd_track_help.c). */
void track_usage(FILE *f);


/* track's plain defaults, where they differ from the libraries' and why
 * (cmd_track_defaults.c), before argv. */
void track_defaults(track_opts *o);

/* Which of track's options were given on the command line, for the
 * defaults that depend on other options (cmd_track_defaults.c): a default
 * is derived only where its option was not given. */
typedef struct track_given {
  int thr, low, depth, min;          /* --threshold-*, --threshold-low/-depth-um/-min */
  int stitch, rxy, mlead, mdelay;    /* --stitch-points, --radius-xy-um, --motion-lead-um,
                                        --motion-delay-us */
  int fillv, fillk, fille;           /* --fill-views, --fill-frames, --fill-ends */
  int spath, spord, fsdp, fade;      /* --short-path-um, --spline-order, --fit-sd-power,
                                        --motion-fade-um-per-ms */
  int gcvg, lscale;                  /* --gcv-gamma, --loss-scale */
  int mslow, mslows;                 /* --motion-slow-lead-ms, --motion-slow-um-per-ms */
  int locpow;                        /* --localize-power */
  int gmp, minpts;                   /* --guided-min-points, --min-points */
  int circ, circnext;                /* --circle-points, --circle-next-path-um */
  int fretry;                        /* --fill-retry-um */
  int locmin, gviews, deepv;         /* --localize-min-views, --guided-views,
                                        --deep-peak-views */
} track_given;

/* Fill in the derived defaults of a parsed *o (g: what was given) and
 * check the guided search's values: CLI_OK, or a usage error (shown). */
int track_opts_derive(track_opts *o, const track_given *g);
/* ... its motion bias's part (cmd_track_bias.c). */
void track_bias_derive(track_opts *o, const track_given *g);

/* Without --z-step-um: take every m-th of *cal's planes, m the largest
 * whose outermost view moves at most o->plane_shift_px between planes
 * (where m does not divide the planes' span, the range is centred: the
 * first and last plane move in by half the remainder); keep
 * the peak fit's axial window (fit_half_z) as wide in um, and lower the
 * default absolute thresholds by what the wider sampling costs a peak
 * (TRACK_AXIAL_SIGMA_UM). Sets o->plane_every and o->plane_centred. */
void track_plane_step(track_opts *o, elfm_calib *cal);

/* With fewer views than the paper's 25 (a 3 x 3 lens array): track's
 * defaults of the views that must agree, ceil(count x n_views / 25), so that
 * no rule asks for more views than there are (deep_peak_views 10 of 9).
 * Sets o->views_scaled to the number of views when it scaled. */
void track_views_step(track_opts *o, const elfm_calib *cal);

/* The refocused peaks' axial sigma on the paper's optics: the median
 * sigma_z of the peak fits on flow and stage at 2 um planes was 4.6-6 um
 * (stage 200 ms seeds 1-5, by depth). A bead between planes h apart sits
 * up to exp(-(h/2)^2 / (2 s^2)) below its peak's height in the nearest
 * plane. */
#define TRACK_AXIAL_SIGMA_UM 5.0

/* Neighbours per view fit (localize_near_um): a view's window meets a few
 * images. */
#define TRACK_NEAR_MAX 16
/* Brighter peaks that may explain a peak's views (explain_brighter): the
 * brightest of those whose images can reach it. */
#define TRACK_EXPLAIN_MAX 16

/* A crowded frame: more than TRACK_CROWD_OCC of the views' pixels are
 * non-zero (elfm_refocus_occupancy). There (view_support_auto) the share of
 * views a peak needs rises by TRACK_VSUP_PER_OCC per unit of that share, up
 * to TRACK_VSUP_MAX. Chosen on flow 100 ms with 40-150 beads (seeds 1-4);
 * the built-in scenes' frames hold 0.1-1.4 % (flow's 20 beads 1.4 %), 40
 * beads 2.2 %, 60 beads 3.0 %, 80 beads 3.8 %, 100 beads 4.2 %, 150
 * beads 5.8 % (docs/tracker.md "Crowded frames"). */
#define TRACK_CROWD_OCC 0.03
#define TRACK_VSUP_PER_OCC 10.0
#define TRACK_VSUP_MAX 0.55
/* ... and the linker's rescue round (elfm_link_options.rescue_gate_factor)
 * reaches TRACK_RESCUE_PER_OCC x gate less far per unit of the share above
 * TRACK_CROWD_OCC, down to TRACK_RESCUE_MIN x gate (docs/tracker.md
 * "Crowded frames"). */
#define TRACK_RESCUE_PER_OCC 100.0
#define TRACK_RESCUE_MIN 1.0
/* ... and its gate (gate_um) TRACK_GATE_PER_OCC_UM um narrower per unit of
 * that share, down to TRACK_GATE_MIN_UM. */
#define TRACK_GATE_PER_OCC_UM 200.0
#define TRACK_GATE_MIN_UM 4.0

/* The deep window's depth (track_opts.deep_window_um): the fits a track
 * guides that start beyond it read 2 x dt of events. Flow recall falls
 * beyond ~45 um (docs/tracker.md "Where the information runs out"). */
#define TRACK_DEEP_WINDOW_UM 45.0

/* One kept frame of the gap-filling ring (cmd_track_fill.c). */
typedef struct ring_slot {
  int64_t frame;         /* the frame held, -1 none */
  int64_t t_us;
  float recent_floor;    /* the frame's (elfm_frame.recent_floor) */
  size_t nnz, nnz_cap;
  uint32_t *idx;         /* [nnz] pixel y*w + x */
  float *val;            /* [nnz] its value */
  /* the frame's detections, written when it leaves the ring (so that fills
   * join their frame and detections.csv stays in frame order) */
  int64_t det_frame;     /* the frame det holds, -1 none */
  elfm_detection *det;
  double *det_vel;       /* [3 det_cap] the velocity of the track each joined
                            (um/ms), NaN where not known: its motion bias */
  int64_t *det_track;    /* [det_cap] the id of that track, -1 none */
  int det_n, det_cap;
} ring_slot;

/* The last frames' nonzero pixels, frame f in slot[f % cap] (gap filling). */
typedef struct frame_ring {
  int cap;
  ring_slot *slot;       /* [cap] */
} frame_ring;

typedef struct fwhm_list {
  size_t n, cap;
  struct fwhm_bead {
    double fwhm_um[2];   /* lateral, axial */
    double speed;        /* its track's lateral speed, um/ms (NaN: unknown) */
  } *b;
} fwhm_list;

/* The output files' paths: --out DIR and a name, as long as the system
 * takes. Longer directories are refused before anything is made
 * (cli_out_fits): cut to fit, every file's path became the same prefix,
 * and the files overwrote one another (the ISBI writer then read its own
 * scratch file cut short: a bus error). */
#define TRACK_PATH_CHARS PATH_MAX

/* per view in the views' check's sums (cmd_track_views.c) */
#define TRACK_VIEW_SUMS 6
typedef struct track_ctx {
  const track_opts *o;
  const elfm_calib *calib;
  /* Peak detection runs on the recon driver's worker threads (the worker
   * hook): one detector workspace per thread, one detection buffer per
   * ring slot, read back in frame order by the linking callback. */
  int n_threads, n_slots;
  elfm_peaks **pk;       /* [n_threads] */
  elfm_detection *det;   /* [n_slots][max_det] */
  struct slot_peaks {    /* [n_slots] what the worker found in the slot's volume: */
    int n;               /* detections in det */
    double s;            /* peak detection CPU time */
    int rej;             /* peaks dropped by the view-support test */
    int explained;       /* of them, those a brighter peak's images explained */
    int loc;             /* peaks placed by the view fit */
    int deep_dropped;    /* deep-only peaks too few views agreed on (deep_peak_views) */
    double occupancy;    /* the frame's elfm_refocus_occupancy (when a crowd rule, *_auto,
                            is on), else 0 */
    double need;         /* the share of views a peak needed (0: no test) */
    /* the views' check (cmd_track_views.c): per view, the misses of its
     * image off the fitted point summed (u, w, px), the fits that kept it,
     * and where its images lay (u, w from the view's centre, px, summed,
     * and u^2 + w^2 summed); the view fits done */
    double view_miss[TRACK_VIEW_SUMS * ELFM_MAX_VIEWS];
    int fits, tries;
  } *sp;
  /* the frame each slot's volume came from and the plan, for the guided
   * view fit in the ordered callback (the driver keeps a batch's frames
   * until the callback of its last volume has returned); per slot, as each
   * slot is written by the one worker thread that refocused it */
  const elfm_frame **slot_frame;        /* [n_slots] */
  const elfm_refocus_plan **slot_plan;  /* [n_slots] */
  /* localize_near_um > 0 only (else NULL): per slot, which detections the
   * view fit placed, and their second fits (x, y, z um, sd px; x NaN: none) */
  unsigned char *fitok;  /* [n_slots][max_det] */
  double *near_fit;      /* [n_slots][max_det][4] */
  double *pred;          /* [max_det][3] track predictions (guided search) */
  double *pred_intensity; /* [max_det] those tracks' last intensity */
  int have_first;
  /* The finished tracks and pieces to smooth and write, in the linker's
   * order: fq[fq_head .. fq_n), under fq_mu (cmd_track_finish.c,
   * track_drain and track_side_work). */
  struct fin_track **fq;
  size_t fq_head, fq_n, fq_cap;
  mtx_t fq_mu;
  int fq_mu_ok;
  elfm_linker *lk;
  FILE *fdet, *ftr, *ffr;      /* detections.csv, tracks.csv, frames.csv */
  elfm_frame_times frame_times; /* every frame's time, for the smoother's gap frames */
  char p_det[TRACK_PATH_CHARS], p_tr[TRACK_PATH_CHARS], p_fr[TRACK_PATH_CHARS];
  /* What is kept of each written track (summary.json, the stage analysis):
   * 112 bytes, a later piece's folded into its track's. The tracks are
   * freed once written and long ones written in pieces, so memory grows
   * with the number of tracks, not with their points. */
  elfm_track_info *info;
  size_t n_info, info_cap;
  elfm_track_xml *xml;         /* the tracks' points for the two XML files, until the end */
  int64_t n_pieces;            /* pieces taken from long live tracks (elfm_link_take_piece) */
  int64_t n_support_rejected, n_explained, n_localized, n_guided_views, n_deep_dropped;
  /* the views' check: the slots' view_miss summed in frame order, and the
   * view fits (track_views_merge) */
  double view_miss[TRACK_VIEW_SUMS * ELFM_MAX_VIEWS];
  int64_t view_fits, view_tries;
  int64_t n_pair_fits; /* detections split in two by the pair fits */
  int64_t n_guided_beside; /* guided view fits dropped: they found another detection's object */
  /* view_support_auto: the frames' occupancy summed, frames that needed
   * more than view_support, and the most a frame needed */
  double occupancy_sum, need_max;
  int64_t n_need_raised;
  int64_t n_crowded;     /* frames over TRACK_CROWD_OCC (their occupancy measured) */
  unsigned char *keep;   /* [n_slots][max_det] the view-support test's verdicts */
  double shift_max_px_per_um; /* the views' largest shift (explain_brighter) */
  int64_t n_frames, n_det, n_points_kept, n_rejected, n_rejected_stage, n_refit_gcv, first_frame,
      last_frame;
  int64_t first_t_us, last_t_us;
  double t_peaks, t_link, t_smooth;
  elfm_fwhm *fw;
  fwhm_list fl;
  elfm_volume geo;       /* the full-sampled volume's geometry (header only, data NULL), set
                            in track_peaks_setup: the view fits' voxels (c->plan's). With
                            --bin-px the volumes the peaks come from are coarser, so a
                            detection goes between the two by its um (elfm_volume_x_vox) */
  double median_speed_um_per_ms; /* of the finished tracks (summary.json, the note) */
  /* gap filling (cmd_track_fill.c) */
  frame_ring ring;
  elfm_frame *scratch;   /* a kept frame, made whole for the view fit */
  elfm_frame *scratch_nbr[TRACK_FILL_MAX_FRAMES - 1]; /* its neighbours (fill_frames > 1) */
  /* owned: the refocus plan, made once (track_peaks_setup) for the
   * detectors' geometry, the driver (o->recon.plan) and the view fits of
   * the gap fills, which go on after the driver's run */
  elfm_refocus_plan *plan;
  elfm_refocus_plan *vplan; /* owned, with --bin-px: the binned calibration's, the volumes' */
  float *bin_piece;         /* with --bin-px: a piece of full-sampled volume per thread */
  size_t bin_piece_len;     /* floats per thread (cmd_track_bin.c) */
  elfm_link_gap *gaps;
  int gaps_cap;
  elfm_detection *fill_pts; /* [ring.cap] */
  uint8_t *fill_retried, *fill_keep; /* [ring.cap]: fill_pts[j] from a retry; kept */
  double fill_retry_z_um;  /* the z step of those retries (fill_one), once per run */
  int64_t n_fill_tries, n_filled;
  int64_t n_filled_end;  /* of n_filled, after a finished track's end */
  int64_t n_filled_multi, n_multi_refused; /* fills of the multi-frame fit; ones the
                                              neighbourhood test refused */
  int64_t n_filled_retry;  /* of n_filled, found from a start beside the prediction */
  int64_t n_retry_dropped; /* such finds that no neighbouring point confirmed */
  /* the in-focus peaks' widths (elfm_detection.width_um), in bins of
   * TRACK_WIDTH_BIN_UM, for the lead (motion_lead_auto) */
  int64_t width_hist[TRACK_WIDTH_BINS];
  int64_t n_width;
  int64_t width_near_hist[TRACK_WIDTH_BINS]; /* within TRACK_WIDTH_NEAR_UM */
  int64_t n_width_near;
  /* the peaks' heights (elfm_detection.intensity, not view-fit points) in
   * bins of 1, for the dim objects' note (TRACK_HINT_DIM_FACTOR) */
  int64_t height_hist[TRACK_HEIGHT_BINS];
  int64_t n_height;
  int dim_noted;        /* the faint-peaks note was printed (track_dim_note) */
  /* --blur-px auto and the automatic window: the speeds of the tracks the
   * detections joined (elfm_link_last_speed), in bins of
   * TRACK_SPEED_BIN_UM_PER_MS, until the judgement; 10 um/ms and more count
   * in the top bin (a median there reads 9.99: far past any bar it meets) */
  int64_t speed_hist[TRACK_SPEED_BINS];
  int64_t n_speed;
  /* ... and how far they lay from their tracks' predictions
   * (elfm_link_last_miss_um), in bins of TRACK_MISS_BIN_UM; 10 um and
   * more in the top bin */
  int64_t miss_hist[TRACK_MISS_BINS];
  int64_t n_miss;
  /* --motion stage without a given velocity: the stage's velocity from the
   * tracks themselves (track_stage_*, cmd_track_stage.c). Finished tracks
   * wait in stage_pending until TRACK_STAGE_MIN_TRACKS of them with
   * TRACK_STAGE_MIN_POINTS points or more give a consensus; from then on
   * each is tested against the weighted median of the newest
   * TRACK_STAGE_RING such tracks' mean velocities (a stage may speed up). */
  elfm_track_store stage_pending;
  size_t n_stage_pending_long;
  double stage_ring[TRACK_STAGE_RING][4]; /* mean vx, vy, vz (um/ms) and points */
  int n_stage_ring, stage_ring_at, stage_established;
  /* --motion auto (motion_auto): the velocities of one frame's long tracks
   * (rigid_v, [max_det][3], then max_det more for a median), and over the frames their distances from
   * the frame's median (rigid_hist, bins of TRACK_RIGID_BIN) and the
   * median's speed (rigid_speed_hist, bins of TRACK_SPEED_BIN_UM_PER_MS),
   * until the judgement */
  double *rigid_v;
  int64_t rigid_hist[TRACK_RIGID_BINS];
  int64_t rigid_abs_hist[TRACK_RIGID_BINS]; /* the distances themselves, bins of
                                               TRACK_RIGID_ABS_BIN_UM_PER_MS */
  int64_t n_rigid;
  int64_t rigid_speed_hist[TRACK_SPEED_BINS];
  int64_t n_rigid_frames;
  int rigid_decided;    /* judged (or given up: rigid_dev NaN) */
  int rigid_tracks_judged; /* ... by the tracks (then by their shift, track_votes) */
  int motion_restart;   /* ... moving as one: start again with --motion stage */
  double rigid_dev, rigid_speed, rigid_abs; /* the medians judged (NaN: not judged) */
  track_votes votes;    /* ... where the tracks could not judge (cmd_track_vote.h) */
  int auto_stopped;     /* the run stopped to start again (cmd_track's on_volume) */
  int stage_fast_frames; /* stage_watch: windows in a row where the tracks moved
                            TRACK_STAGE_WATCH_STEP_UM or more */
  int stage_outrun;     /* ... TRACK_STAGE_WATCH_FRAMES of them: start again at 1 ms */
  double stage_outrun_speed; /* the median speed then, um/ms */
  int auto_decided;     /* the first peaks have been judged (cmd_track's auto_judge) */
  int blur_restart;     /* ... faint: start again with --blur-px 1 */
  int dt_restart;       /* ... fast: start again with half the window */
  int stride_restart;   /* ... turning beyond prediction: the window twice as often */
  int miss_decided;     /* ... the misses judged (they may wait for more frames) */
  int slow_restart;     /* ... slow beads: start again with TRACK_SLOW_BEADS_DT_US windows and tau */
  int repr_restart;     /* ... crawling: start again with the integral */
  int few_restart;      /* ... too few peaks to judge: the integral too (TRACK_AUTO_FEW_MIN_FRAMES) */
  int start_restart;    /* ... under pulsed light: --start each-trigger */
  int lin_restart;      /* ... and moving: --repr lin too */
  int64_t n_triggers;   /* trigger edges up to the last volume's end (elfm_volume) */
  /* The frames' events by whether a trigger edge fell in the frame or the
   * one before (lit under pulsed light) or not (track_pulsed) */
  int64_t n_lit_frames, n_dark_frames, n_lit_peaked, n_dark_peaked; /* ..., those with a peak */
  double lit_events, dark_events, lit_events2, dark_events2; /* ... and their squares */
  int prev_had_edge, cur_lit;
  int64_t auto_peaks;   /* ... how many they were */
  double auto_ratio;    /* ... their median height over the threshold */
  double auto_speed;    /* ... their tracks' median speed, um/ms (track_detection_speed_median) */
  double auto_miss;     /* ... their median miss, um (track_detection_miss_median) */
} track_ctx;

/* Detectors and buffers for the driver's layout (elfm_recon_layout of
 * c->o->recon), before the run. */
elfm_status track_peaks_setup(track_ctx *c, elfm_error *err);
/* --bin-px (cmd_track_bin.c): the pieces' memory (called by
 * track_peaks_setup), and det[0 .. n), peaks of a binned volume, refined
 * again as the detector would in the full-sampled volume, on voxels made
 * from the frame with the full plan around each */
elfm_status track_bin_setup(track_ctx *c, elfm_error *err);
void track_bin_refine(track_ctx *c, const elfm_refocus_plan *plan, const elfm_frame *frame,
                      int thread, elfm_detection *det, int n);
/* The recon driver's worker hook (elfm_volume_worker_fn; user: the
 * track_ctx): peaks of the slot's volume, on the worker thread. */
elfm_status track_detect_worker(const elfm_volume *v, const elfm_frame *frame,
                                const elfm_refocus_plan *plan, int slot, int thread, void *user,
                                elfm_error *err);
/* The share of the views sampling a peak's voxel that must have signal
 * there, in a frame whose views' pixels are `occupancy` non-zero (0..1):
 * o->view_support, raised in crowded frames when o->view_support_auto. */
double track_view_support_need(const track_opts *o, double occupancy);
/* The linker's rescue_gate_factor for a frame whose views' pixels are
 * `occupancy` non-zero: o->link.rescue_gate_factor, lowered in crowded
 * frames when o->rescue_auto. */
double track_rescue_factor(const track_opts *o, double occupancy);
/* The linker's gate_um for such a frame: o->link.gate_um, narrowed in
 * crowded frames when o->gate_auto. */
double track_gate_um(const track_opts *o, double occupancy);
/* The frames' mean occupancy so far (0 before the first frame, and where
 * none was measured). */
double track_occupancy_mean(const track_ctx *c);
/* The ordered callback (elfm_volume_slot_fn): link the slot's detections,
 * write them, queue the tracks that ended and write those smoothed. */
elfm_status track_on_volume(const elfm_volume *v, int slot, void *user, elfm_error *err);
/* The searches guided by the linker's predictions for this frame, before
 * its detections are linked: pair fits, then a low peak or a view fit for
 * each track with no detection near it; det grows (at most max_det;
 * cmd_track_guided.c). */
elfm_status track_guided_search(track_ctx *c, const elfm_volume *v, int slot, elfm_detection *det,
                                int *n_io, elfm_error *err);
/* The view fit's options for the fits a track guides (its prediction, a
 * pair fit, gap filling): the run's, and with the deep window on, a fit
 * started beyond deep_window_um reads the window's older pixels too
 * (elfm_localize_options.deep_z_um). The peaks' own fits keep the
 * window's pixels. */
elfm_localize_options track_guided_loc(const track_opts *o);
/* Append to nb[k ..] the detections of det[0 .. n) but det[skip] (-1: none)
 * within near_um laterally of (x_um, y_um), in geo's voxels (the view fit's
 * neighbours, localize_near_um); returns the new count, at most
 * TRACK_NEAR_MAX. */
int track_near_add(const elfm_detection *det, int n, int skip, double x_um, double y_um,
                   double near_um, const elfm_volume *geo, double nb[TRACK_NEAR_MAX][3], int k);
/* Queue the tracks the linker has finished; filter and write those at the
 * queue's head that are smoothed. at_end (after the run): smooth all that
 * wait first, all threads at once (cmd_track_finish.c). */
elfm_status track_drain(track_ctx *c, int at_end, elfm_error *err);
/* The driver's side work (elfm_recon_options.side_work; user: the
 * track_ctx): smooth the oldest queued track; 0 when none waits. */
int track_side_work(void *user, int thread);
/* The queue's tracks and its mutex (track_ctx_free; cmd_track_finish.c). */
void track_finish_free(track_ctx *c);
/* Write a kept, smoothed track: tracks.csv, the XML scratch, its info
 * (cmd_track_finish.c). Frees t. */
elfm_status track_write_track(track_ctx *c, elfm_track *t, elfm_error *err);
/* --motion stage (cmd_track_stage.c): write t, or leave it out when it does
 * not move with the stage, or (no velocity given) hold it until the tracks
 * agree on the stage's velocity. Takes t. */
elfm_status track_stage_filter(track_ctx *c, elfm_track *t, elfm_error *err);
/* ... at the end: decide on the tracks still waiting for a consensus and
 * write the kept ones. */
elfm_status track_stage_flush(track_ctx *c, elfm_error *err);
/* The bin of a histogram's median (n > 0 counts in hist[0 .. bins);
 * cmd_track_volume.c). */
int track_hist_median_bin(const int64_t *hist, int bins, int64_t n);
/* Count one in bin b (a value over its bin width, floored, >= 0) of
 * hist[0 .. bins): beyond the last bin (or NaN) in the last. */
static inline void track_hist_add(int64_t *hist, int bins, double b)
{
  hist[b < bins - 1 ? (int)b : bins - 1]++;
}
/* --motion auto: add one frame's velocities v[0 .. 3n) of long tracks
 * (TRACK_RIGID_MIN_POINTS; v is c->rigid_v) to the test for rigid motion
 * (cmd_track_stage.c). */
void track_rigid_add_frame(track_ctx *c, double *v, int n);
/* ... and judge it once it can be (at_end: with what there is, at least
 * TRACK_RIGID_MIN_SAMPLES / 2): sets c->rigid_decided, and returns 1 when
 * the objects move as one (c->motion_restart). */
int track_rigid_judge(track_ctx *c, int at_end);
/* The first run found a stage: the window (and tau) for its second run,
 * us, when it is slow (TRACK_STAGE_SLOW_*); -1: keep the first run's. */
int64_t track_stage_slow_dt_us(const track_ctx *c);
/* o->stage_watch: one window's speeds s[0 .. n) (um/ms, the tracks' that
 * joined it; s is scratch); sets c->stage_outrun once the stage has
 * outrun the windows (TRACK_STAGE_WATCH_*). */
void track_stage_watch_frame(track_ctx *c, double *s, int n);
/* Gap filling (cmd_track_fill.c; off when o->fill_views is 0): the ring
 * and buffers, before the run; keep the frame of each volume (linking
 * callback, frame order); after each linking step (all = 0) and before
 * elfm_link_finish (all = 1), fill the gaps the linker settled and write
 * the points found to detections.csv; free. */
elfm_status track_fill_setup(track_ctx *c, elfm_error *err);
elfm_status track_fill_keep(track_ctx *c, const elfm_frame *f, int64_t frame, elfm_error *err);
elfm_status track_fill_gaps(track_ctx *c, int all, elfm_error *err);
/* Follow finished track t (popped, not yet smoothed) past its last point:
 * what is found goes into t and detections.csv (o->fill_ends). */
elfm_status track_fill_end(track_ctx *c, elfm_track *t, elfm_error *err);
void track_fill_free(track_ctx *c);
/* Write frame `frame`'s detection d to detections.csv: at once without gap
 * filling; with it, held until track_det_flush_before writes the frames
 * before a given one, oldest first (each linking callback: the frames no
 * longer kept; at the end: INT64_MAX, all). track_id, v_um_per_ms: the
 * track d joined (-1: none) and its velocity when d joined (NULL or NaN:
 * none); d is written less the motion bias of its track's velocity (the
 * smoother's model and lead when it is written), as well as raw. That
 * velocity is the line's through the track's points within
 * TRACK_DET_VELOCITY_HALF_FRAMES of d when they are known by then (the
 * track still live, or finished: track_det_velocities), else v_um_per_ms. */
elfm_status track_det_emit(track_ctx *c, int64_t frame, const elfm_detection *d, int64_t track_id,
                           const double *v_um_per_ms, elfm_error *err);
/* Finished track t (popped, its end followed): the velocities of its
 * detections still held, from its points around each (before it is
 * smoothed and freed). */
void track_det_velocities(track_ctx *c, const elfm_track *t);
elfm_status track_det_flush_before(track_ctx *c, int64_t frame, elfm_error *err);
/* Close the context's files, free what it holds (for any state of setup). */
void track_ctx_free(track_ctx *c);
/* Write summary.json: inputs, counts, parameters, timing, the stage
 * velocity, resolution figures and one entry per track. input_err: the
 * error that stopped reading early (the counts are of what was read), or
 * NULL. */
elfm_status track_write_summary(const track_ctx *c, const elfm_recon_stats *rs, double wall_s,
                                const char *path, const elfm_error *input_err, elfm_error *err);
/* Count peak d's width into c's histogram when it is a strong in-focus peak
 * (not weak, not a view-fit point, |z| < TRACK_WIDTH_FOCUS_UM). */
void track_width_add(track_ctx *c, const elfm_detection *d);
/* Count peak d's height (intensity) into c's histogram unless it is a
 * view-fit point; the median of those heights (NAN before the first). */
void track_height_add(track_ctx *c, const elfm_detection *d);
double track_peak_height_median(const track_ctx *c);
/* Count a detection's track speed (NaN: none yet, not counted); the median
 * of those speeds, um/ms (NAN before the first). */
void track_speed_add(track_ctx *c, double v_um_per_ms);
double track_detection_speed_median(const track_ctx *c);
/* Count how far peak d lay from its track's prediction (NaN: not judged,
 * not counted; nor a view-fit point, nor |z| TRACK_MISS_FOCUS_UM or more);
 * the median of those misses, um (NAN before the first). */
void track_miss_add(track_ctx *c, const elfm_detection *d, double miss_um);
double track_detection_miss_median(const track_ctx *c);
/* The median width of those peaks, um; NAN before the first. */
double track_peak_width_median_um(const track_ctx *c);
/* Windows opened by the LED (--start each-trigger, given or chosen): one
 * pulse each, the objects dark between them. */
static inline int track_led_windows(const track_opts *o)
{
  return o->recon.framer.start == ELFM_START_EACH_TRIGGER;
}
/* --repr lin is track's to choose: lin_auto, or a settled run's first's
 * (the grid's blur, say, chosen before pulsed light was found) */
static inline int track_lin_choosable(const track_opts *o)
{
  return o->lin_auto || (o->auto_chose && (o->auto_was & 32));
}
/* The lead to smooth with: with motion_lead_auto and enough widths, from
 * their median (above); else the options' lead. */
double track_motion_lead_um(const track_ctx *c);
/* The speed the first peaks' tracks moved at (track_detection_speed_median)
 * as the run judged it, or the first run (auto_chose); NaN: not judged
 * (the window, representation and blur all given). */
double track_judged_speed_um_per_ms(const track_ctx *c);
/* What track_motion_lead_um takes off the widths' lead for a fast
 * recording (lead_fast_ms), um; 0 where it does not apply. */
double track_motion_lead_fast_um(const track_ctx *c);
/* ... and for blurred frames (lead_blur_um), um; 0 where it does not apply. */
double track_motion_lead_blur_um(const track_ctx *c);
/* The points a live track keeps past a piece's cut, and the context on
 * each side of a cut, for --piece-points N: N / 4 (at least 64, more than
 * the linker's reviews look back) and N / 8 (at least 16, at most that). */
static inline size_t track_piece_keep(int n) { return n / 4 > 64 ? (size_t)(n / 4) : 64; }
static inline size_t track_piece_context(int n)
{
  const size_t c = n / 8 > 16 ? (size_t)(n / 8) : 16, k = track_piece_keep(n);
  return c < k ? c : k;
}
/* The median over the written tracks (c->info) of each smoothed one's mean
 * lateral speed |(vx, vy)| over its span, um/ms; NAN without smoothed tracks. */
double track_median_speed_um_per_ms(const track_ctx *c);
int track_pulsed(const track_ctx *c);
/* 1 while pulsed light may yet be found (--start auto, a trigger, the first peaks not judged) */
int track_pulsed_pending(const track_ctx *c);
/* lit frames' excess of mean events in standard errors (Welch's t); the
 * percentage of the lit (1) or other (0) frames with a peak */
double track_pulsed_z(const track_ctx *c);
double track_peaked_pct(const track_ctx *c, int lit);
/* lit frames' mean events over the others' (those at least 1); NaN before
 * one of each */
double track_pulsed_ratio(const track_ctx *c);

/* ---- the views' check (cmd_track_views.c) ----
 * Whether the calibration fits the recording: every view fit of a peak
 * says where each view's image lay off the fitted point; with the right
 * centres those misses average ~0 and every view takes part in most fits.
 * A view whose images lie off on average, or which takes part in few fits
 * where the others take part in most, is off (a turned lens array, a
 * calibration from the optics alone). */
/* a fit's misses (2 per view) and weights (0: the view left out) into the
 * slot, with where the fitted point (xyz_um) put each view's image (whose
 * spread says a view's images stayed in one place); the worker counts the
 * slot's `tries`, failed fits too */
void track_views_add(struct slot_peaks *sp, const elfm_calib *calib, const double xyz_um[3],
                     const double *miss_px, const double *weight);
/* the slot's sums into the run's, in frame order (the callback) */
void track_views_merge(track_ctx *c, int slot);
typedef struct track_views_check {
  int64_t fits;        /* view fits summed */
  int64_t tries;       /* view fits tried */
  int64_t rejected;    /* peaks the view-support test dropped before */
  int few_placed;      /* 1: the views agreed on almost no peak */
  int worst;           /* the view whose images lay furthest off on average (-1: none judged) */
  double worst_miss_px, worst_u_px, worst_w_px;
  int least;           /* the view kept in the fewest fits (-1: none) */
  double least_share, median_share; /* its share of the fits, the median view's */
  int off;             /* 1: a view is off (the note's rule) */
  int judged;          /* 1: enough fits to judge the views one by one (the arrays below) */
  double miss_px[ELFM_MAX_VIEWS][2]; /* each view's mean miss as judged (gauge out); NaN: too few fits kept it */
  double share[ELFM_MAX_VIEWS];      /* each view's share of the fits */
  double spread_px[ELFM_MAX_VIEWS];  /* RMS distance of its images from their mean, px (NaN: none) */
  int still[ELFM_MAX_VIEWS];         /* 1: its images stayed in one place, its miss not judged */
} track_views_check;
void track_views_judge(const track_ctx *c, track_views_check *out);
/* the note on stderr when a view is off (not with --quiet) */
void track_views_note(const track_ctx *c);

#endif
