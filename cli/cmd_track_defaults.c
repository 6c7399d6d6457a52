/* cmd_track_defaults.c — eventlfm track's defaults: first the plain ones
 * (track_defaults, where they differ from the libraries'), then those that
 * depend on other options: the representation (the integral's own), the
 * motion (a stage), the window start (windows opened by the LED), the
 * threshold family, and the motion-bias correction the surface implies
 * (track_bias_derive, cmd_track_bias.c). Each of those is taken only when
 * its option was not given (track_given). Each default says what it was
 * measured on. The parsing is in cmd_track_opts.c. */
#include <inttypes.h>
#include <math.h>
#include <string.h>

#include "cmd_track.h"

/* track's defaults: where they differ from the libraries', why. */
void track_defaults(track_opts *o)
{
  memset(o, 0, sizeof *o);
  elfm_recon_options_default(&o->recon);
  elfm_peaks_options_default(&o->peaks);
  elfm_link_options_default(&o->link);
  elfm_smooth_options_default(&o->smooth);
  o->max_det = 10000;
  /* Dim objects, fast objects, crawling cells, a stage, pulsed light: the
   * run judges its first peaks (a stage: its first tracks moving as one)
   * and may start again with --blur-px 1, windows of half the length, the
   * integral, --motion stage or --start each-trigger (track_opts_derive). */
  o->blur_auto = o->dt_auto = o->repr_auto = o->motion_auto = o->start_auto = o->lin_auto = 1;
  /* Planes 4 um apart on the paper's optics, not its 2 um: the peaks' axial
   * sigma is 4.6-6 um, and the view fit, not the plane, places each bead in
   * z. 4 um alone, mean alpha against every plane: flow 100 ms seeds 1-20
   * 0.8505 -> 0.8509 (5 um 0.8513, 6 um 0.8341), but the stage's faint deep
   * beads were lost (recall 0.959 -> 0.949, 11 seeds) and the worm's peak
   * fit spanned +-12 um; with the thresholds and the fit window adjusted
   * (track_plane_step): flow 1-20 0.8511, held-out 21-32 0.8545 -> 0.8421,
   * worm 0.5 s (28 seeds) 0.9214 -> 0.9237, stage 0.8745 -> 0.8670 (speed
   * error the same), and `track` on flow 1 s in 0.68 of the time (RTF 0.22
   * -> 0.31; docs/tracker.md "Planes 4 um apart"). */
  o->plane_shift_px = 1.5;
  o->bin_px = 1;
  o->plane_every = 1;
  o->max_outlier_frac = 1.0 / 3;
  /* A recording whose beads all move fast leads less than its in-focus
   * peaks' widths say (track_motion_lead_um): the lead is 0.13 um shorter
   * per um/ms of the judged speed above 4.5 um/ms. The error along the
   * motion is 0.2-0.3 um below the line at 5-6 mm/s (0.5 and 1 ms windows
   * alike), but not on flow_random's fast stretches, whose recordings
   * judge 3.5-4.4 um/ms: so the recording's speed, not each image's.
   * Mean alpha: flow 5-6 mm/s seeds 1-6 0.8640 -> 0.8803, held-out 7-12
   * 0.8371 -> 0.8525, 4.5-5.5 / 7-8 mm/s 0.8855 -> 0.8908 / 0.8222 ->
   * 0.8934, flow_random 5-6.5 mm/s 0.6406 -> 0.6487 (every run up); the
   * built-in flow, flow_random, stage, blink, worm the same files
   * (docs/tracker.md "The lead of fast flows"). */
  o->lead_fast_ms = 0.13;
  o->lead_fast_um_per_ms = 4.5;
  /* On blurred frames (--blur-px 1, which track chooses for dim beads)
   * the peaks are as wide but the detections lie further back: the lead
   * 0.3 um shorter, flow seeds 1-4 with --blur-px 1 0.8665 -> 0.8910, dim
   * flow (half the flux, blur chosen) seeds 1-8 0.6110 -> 0.6212, held-out
   * seeds 5-12 with --blur-px 1 0.8267 -> 0.8476; a quarter of the flux
   * flat (0.3869 -> 0.3845); a stage with the blur loses (0.9049 -> 0.8925,
   * so not there; docs/tracker.md "The lead on blurred frames"). */
  o->lead_blur_um = 0.3;
  o->smooth.outlier_min_um = 1.5; /* ... of points also 1.5 um off (elfm_smooth.h) */
  /* The smoother's robust loss: Cauchy, not the library's Huber. A ghost
   * joined to a track, or the neighbour's detection at an encounter, lies
   * many sigmas off: Cauchy's weight falls as 1/r^2, Huber's as 1/r and
   * still pulls. Mean alpha, Huber -> Cauchy (with
   * outliers counted alike, beyond twice the scale): flow 100 ms seeds
   * 1-20 0.8391 -> 0.8417 and held-out 21-32 0.8367 -> 0.8400 (all 32
   * seeds up), flow 1 s 1-8 0.7692 -> 0.7715 (all up), stage 0.8685 ->
   * 0.8772, blink 0.9288 -> 0.9308, blink_moving 0.8369 -> 0.8378, worm
   * 0.5 s (20 seeds) 0.9167 -> 0.9199 (16 up, 12 down of 28 with the
   * held-out 25-32: 0.9213 -> 0.9225), worm 200 ms 0.9505 the same
   * (docs/tracker.md "Smoother"). */
  o->smooth.loss = ELFM_LOSS_CAUCHY;
  /* Long tracks in bounded memory: a live track holds at most 1024 + 256
   * points (~0.2 MB with the array's spare room), smoothed in pieces with
   * 128 points of context on each side. Worm 20 s (10,000 frames, 12
   * neurons, Huber loss, --piece-points 512 / 1024 / 4096 / 0): alpha
   * 0.67559 / 0.67579 / 0.67576 / 0.67578, peak RSS 89.0 / 93.7 / 116.4 /
   * 118.3 MB (88.3 / 93.6 / - / 93.2 MB at 5 s); with the Cauchy loss,
   * 1024 / 0: 0.67837 / 0.68033, 91.9 / 116.9 MB. No scene of the tests
   * (<= 1000 frames) reaches 1280 points. */
  o->piece_points = 1024;
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
  o->view_support_auto = 1;
  o->rescue_auto = 1;
  o->gate_auto = 1;
  /* ... and the views a peak twice as bright explains do not count, when
   * they are at least half of the peak's (track_detect_worker says why;
   * docs/tracker.md "Ghosts of bright objects"). */
  o->explain_brighter = 0.5;
  o->explain_um = 3.7;
  /* View fit of every peak, and from the predictions of tracks with no
   * peak near (8 views must agree there): recon/localize.c and
   * docs/tracker.md "View fit". Window 5 x 5 px with weights value^P: the
   * time surface is 255 exp(-age / tau), so P weighs an event by
   * exp(-P age / tau), and the centroid moves from the trail of the
   * object's recent events (P = 1) towards their leading edge. Where the
   * object really is depends on its contrast: along the motion, flow beads
   * come out -0.36 / -0.14 / 0.00 um from the truth at P = 1 / 2 / 3, stage
   * beads +0.37 / +0.57 / +0.71 um. P = 3 is best on flow, whose targets
   * are the strictest (8 seeds: alpha 0.701 / 0.716 / 0.733, lateral RMSE
   * 0.50 / 0.43 / 0.41 um); P = 1 on stage (alpha 0.71-0.79 -> 0.77-0.87)
   * and worm (0.39 -> 0.44): docs/tracker.md. 7 x 7 windows were worse on
   * flow, 3 x 3 on stage and worm. */
  o->localize_views = 1;
  elfm_localize_options_default(&o->loc);
  o->guided_views = 8;
  /* Neighbours within 12 um: their light, read mirrored through their
   * centres, is taken out of each fit's windows (recon/localize.c). Worm
   * pairs 6 um apart pulled each other's fits (thirteenth session, worm
   * 200 ms alpha_detections 0.888 -> 0.900), and so do flow beads passing
   * within a few um (fortieth session: flow 100 ms seeds 1-20 lateral /
   * axial RMSE 0.483 / 1.266 -> 0.471 / 1.199 um, alpha held-out 21-32
   * 0.8638 -> 0.8746, 1 s 0.7599 -> 0.7747, seeds 1-20 0.8814 -> 0.8786;
   * docs/tracker.md "Neighbours taken out on time surfaces too"). */
  o->localize_near_um = 12;
  /* Pair fits (cmd_track_guided.c) for predictions within 4 um laterally,
   * about the paper's lateral FWHM (3.9 um): objects further apart leave
   * two peaks. Where half the views part the two images: flow 1 s alpha
   * +0.009 +- 0.004 over seeds 1-60, random flow 1 s -0.001 +- 0.006 over
   * seeds 1-44, flow 100 ms -0.001 +- 0.002 over seeds 1-40 (docs/tracker.md
   * "Two tracks at one peak"). */
  o->pair_fit_um = 4;
  o->deep_window_us = -1; /* auto */
  o->deep_window_um = TRACK_DEEP_WINDOW_UM;
  /* Stitching a new track of 5 points onto a dark track whose recent path
   * its points follow within 8 um RMS (elfm_link.h step 5): flow beads
   * circle and come back onto their own path after gaps no extrapolation
   * bridges. Flow 100 ms seeds 1 / 2: alpha 0.677 -> 0.697 / 0.646 ->
   * 0.691, 7 -> 3 / 6 -> 1 spurious tracks; blink unchanged; worm 0.327 ->
   * 0.326 (docs/tracker.md "Stitching"). Points 4-6 and gates 6-10 um
   * gave the same to +-0.01. Off in --motion stage (below). */
  o->link.stitch_points = 5;
  /* ... and a track about to end onto a young one of 3 or 4 points on its
   * path (step 5b), which step 5 would judge only after the end: a deep
   * bead seen a few frames at a time (flow 1 s seed 8, a track dark since
   * frame 689 ended in 741, when its bead's new track reached 5 points).
   * Flow 1 s seeds 1-24: alpha 0.7624 -> 0.7631 (6 seeds up, none down);
   * flow_random 1 s seeds 1-16 +0.002 (12 up, 3 down), 100 ms seeds 1-24
   * -0.0002; 44 other recordings of every scene the same bytes
   * (docs/tracker.md "A young track one frame late"). */
  o->link.stitch_late_points = 3;
  /* Swap review of gap closings that do not fit, after 8 points of the new
   * tail (elfm_link.h step 6). Flow 100 ms seeds 1, 2, 4-9 at 6 points:
   * alpha 0.697, 0.691 -> 0.714 (seed 2), 0.618 -> 0.691 (seed 7), the
   * other six unchanged; stage, blink, worm unchanged; 0.7 as the ratio
   * swapped wrongly (4 seeds down by 0.01-0.04). Sixth session, 20 flow
   * seeds, 4 / 6 / 8 / 9 / 10 / 12 points: mean alpha 0.7331 / 0.7355 /
   * 0.7379 / 0.7379 / 0.7372 / 0.7367 (at 8: seed 1 0.700 -> 0.742, the
   * crossing docs/tracker.md describes, seed 11 +0.013, three seeds down by
   * <= 0.006); stage seed 3 0.688 -> 0.707; worm, blink, stage_accel the
   * same. A longer tail shows which way each bead turned. */
  o->link.swap_points = 8;
  /* Encounter review (elfm_link.h step 7): tracks that came within 5 um
   * (the linker's metric, z / 1.5) are revisited like a gap closing.
   * Twelfth session, flow 100 ms seeds 1-20: alpha 0.8061 -> 0.8136 (seeds
   * 2, 7, 12, 16 up by 0.018-0.045, none down); 3 / 4 / 6 / 8 um (before
   * the 2 x gate cap on the exchange's joins): 0.8084 / 0.8120 / 0.8129 /
   * 0.8129. Held-out seeds 21-24 the same; flow 500 ms seed 1 0.744 ->
   * 0.767; stage, worm, blink, blink_moving the same. With the reviews'
   * join limit (elfm_link_options.review_join_factor, 2 x the gate, on
   * step 6 too): 0.8184, held-out 0.8100 (docs/tracker.md "Encounter
   * review"). */
  o->link.encounter_um = 5;
  /* Worm seed 5 (200 ms): neurons 4 and 5 at z -57 um, whose images merge,
   * met at frames 9-11, parted for two frames and crossed at 14-17; the
   * review of frames 9-11 alone kept the swap, and so did the other two
   * pairs' reviews: alpha 0.786 -> 0.828 with 4 (3 or more frames change
   * nothing else measured: worm 200 ms seeds 1-4, 6-12, 150 and 500 ms,
   * flow seeds 1-24, dense flow and stage the same to the last digit). */
  o->link.encounter_apart = 4;
  /* ... and along the heads' circles (elfm_link.h encounter_circle_ratio;
   * off where circle_points is): flow 1 s seeds 1-8 (docs/tracker.md
   * "Encounters along circles"). */
  o->link.encounter_circle_ratio = 0.5;
  /* ... and, while the objects are at rest, along straight lines through
   * 20 points (elfm_link.h encounter_line_ratio): worm 500 ms seeds 1-8
   * and 13-16 alpha 0.9005 -> 0.9116, held-out seeds 17-24 0.8742 ->
   * 0.8908, no seed down; flow, stage, blink and blink_moving tracks.csv
   * byte for byte the same (docs/tracker.md "Slow encounters along
   * straight lines"). */
  o->link.encounter_line_ratio = 0.5;
  /* A track about to end whose last 20 points a younger track, born on
   * them, holds too (within 2 um): one bead in two tracks, and the older
   * goes on as the younger (elfm_link.h step 8). Flow 1 s seeds 1-20 alpha
   * 0.7571 -> 0.7599 (8 up, none down); 100 ms flow, stage, worm, blink the
   * same (docs/tracker.md "Twins at a track's end"). */
  o->link.twin_um = 2;
  o->link.twin_points = 5;
  /* Established tracks (8 points, the short fit's history) are assigned
   * before younger ones (elfm_link.h step 3): flow 100 ms seeds 1-20,
   * alpha 0.7846 -> 0.7897; held-out 21-24 0.774 -> 0.783; 40 and 60
   * beads (9 runs) 0.605 -> 0.623 (docs/tracker.md "Established tracks
   * first"). */
  o->link.priority_points = 8;
  /* The linker's acceleration fit spans at most 20 um of path (elfm_link.h
   * short_path_um): fewer of the 8 points for fast beads, whose 8 frames
   * cover more than a radian of a tight turn. Flow 100 ms seeds 1-20 alpha
   * 0.8021 -> 0.8033 (15 / 25 / 30 um: 0.7893 / 0.8027 / 0.8005), held-out
   * 21-24 0.7955 -> 0.8020, 40/60 beads (9 scenes) 0.6273 -> 0.6534;
   * faster beads (4-8 mm/s, seeds 31-33) 0.4755 -> 0.6390; noise, dim,
   * haze variants (seeds 31, 32) +0.017 to +0.051 each (docs/tracker.md
   * "Fast beads"). Off with --motion stage and on the integral
   * (below). */
  o->link.short_path_um = 20;
  /* A track dark for 2 frames or more is predicted along the circle its
   * last 15 points follow (elfm_link.h circle_points): flow beads circle
   * (radius 8-20 um at 2.5-4 um/ms) and the deep ones go dark for 10-35
   * frames, where the short fit's turn missed them by tens of um. Flow
   * 1 s seeds 1-8 alpha 0.6358 -> 0.7309, held-out 9-12 0.6231 -> 0.6813;
   * 100 ms seeds 1-20 0.8184 -> 0.8315, held-out 21-32 0.7918 -> 0.8211
   * (15 points after 2 frames, chosen among 10-30 points after 1-5 frames
   * on seeds 1-8 and 1-20; docs/tracker.md "Circles through long gaps").
   * Worm (integral), blink, stage and stage_accel: the same or within
   * 0.0001; off with --motion stage and --start each-trigger
   * (cmd_track_defaults.c). With the gaps' own circle
   * (elfm_link_options.circle_gap_points) and the rate-guided unwrap:
   * 1 s 0.7486 / 0.6836, 100 ms 0.8398 / 0.8295. */
  o->link.circle_points = 15;
  o->link.circle_after = 2;
  /* ... and a track seen in the last frame is predicted along the circle
   * through its last 45 um of path where that circle has predicted its
   * points better than the short fit (elfm_link.h circle_next_path_um):
   * flow at 2 ms frames turns 0.55-0.9 rad per frame, past what the short
   * fit's parabola follows. Flow 100 ms seeds 1-8 / 9-20 alpha 0.8763 ->
   * 0.8779 / 0.8374 -> 0.8555, at 2 ms frames 0.737 -> 0.780 / 0.699 ->
   * 0.749; 30 / 60 um: 0.8717 / 0.8775 and 0.789 / 0.769 on seeds 1-8;
   * the circle over the 15 circle points instead: 0.8779 / 0.768.
   * docs/tracker.md "The next frame along a circle". */
  o->link.circle_next_path_um = 45;
  /* ... and gap filling's walks before a track's birth and past its end
   * follow the circle through the 8 points at that end
   * (elfm_link_options.circle_end_points), where the end's quadratic turn
   * left a circling bead within 2-3 frames (docs/tracker.md "The open
   * ends along a circle"). Flow 100 ms seeds 1-20 alpha 0.8643 -> 0.8671,
   * at 2 ms frames (seeds 1-16) 0.7829 -> 0.7957, flow_random 1-12 0.6312
   * -> 0.6337; 15 / 30 points: 0.8670 / 0.8666, 0.7951 / 0.7952, 0.6332 /
   * 0.6332. Off where circle_points is. */
  o->link.circle_end_points = 8;
  /* The spline weight by modified GCV (elfm_smooth.h gcv_gamma): the
   * detections' errors are correlated from frame to frame (flow: lag-1
   * autocorrelation 0.54-0.58 laterally, 0.38 in z), which classical GCV
   * takes for motion. Flow 100 ms seeds 1-20: alpha 0.7897 -> 0.7950,
   * every seed up or the same (1.2 / 1.6 / 2: 0.7945 / 0.7938 / 0.7867);
   * held-out 21-24 +0.003 to +0.007; worm (integral) seeds 1-4 +0.001 to
   * +0.004; blink, blink_moving up; stage (no spline) the same.
   * Twenty-third session, GCV's minimum found to 1/16 decade (it was the
   * best of a half-decade grid), 1.4 -> 1.6: flow 100 ms seeds 1-20
   * 0.8432 -> 0.8444, held-out 21-32 0.8415 -> 0.8426 (31 of 32 seeds
   * up), 1 s seeds 1-8 0.7729 -> 0.7736 (8 of 8), blink 0.9341 ->
   * 0.9351, blink_moving and stage the same (1.2 / 1.8 / 2 / 2.5 on seeds
   * 1-20: 0.8408 / 0.8446 / 0.8441 / 0.8411; 1.8 raised 24 of 32). */
  o->smooth.gcv_gamma = 1.6;
  /* The spline penalises the jerk, not the acceleration (elfm_smooth.h
   * spline_order): a flow bead turns at ~0.3 rad/ms, a constant
   * acceleration the acceleration penalty pulls toward a line. Flow 100 ms
   * seeds 1-20: alpha 0.7950 -> 0.7964 (14 up, 5 the same, 1 down), lateral
   * velocity RMSE 0.273 / 0.252 -> 0.264 / 0.236 um/ms; held-out 21-24 +0 to
   * +0.003; 40/60 beads +0.002; blink, blink_moving the same. Not on the
   * integral (below). */
  o->smooth.spline_order = 3;
  /* ... and once fitted, a spline track is fitted again with a prior that
   * leaves a circle at the track's own turn rate alone, its weight chosen
   * again (elfm_smooth.h spline_turn): a circling bead's turn is no longer
   * pulled in, and GCV takes a stiffer spline. Flow 100 ms seeds 1-20
   * alpha 0.8671 -> 0.8749 (GCV again without the turn: 0.8682; the rate
   * x 0.7 / 0.85 / 1.2: 0.8702 / 0.8715 / 0.8714; a rate per stretch of 9
   * frames: 0.8721), docs/tracker.md "Splines along the turn". Order 2
   * (the integral) has no such prior. */
  o->smooth.spline_turn = 1;
  /* The motion bias along the fitted path (elfm_smooth.h
   * motion_along_path): each view's lead along the motion a delay ago, the
   * way back by the mean velocity. Mean alpha, off -> on: flow_random 100
   * ms seeds 1-30 0.717 -> 0.724 (+0.0071 +- 0.0002, every seed up), flow
   * 100 ms seeds 1-20 0.882 -> 0.884 (+0.0020 +- 0.0001, every seed up);
   * docs/tracker.md "The lead along the path". Without a delay (the
   * integral's) it changes nothing. */
  o->smooth.motion_along_path = 1;
  /* Each point's own view-fit scatter in its sigma (elfm_smooth.h,
   * fit_sd_power): flow 100 ms seeds 1-20 alpha 0.8043 -> 0.8058 (every
   * seed up or the same; power 0.5 / 1.5 / 2: 0.8054 / 0.8057 / 0.8051),
   * held-out seeds 21-24 0.8037 -> 0.8054, stage seeds 1-3 0.769 / 0.837 /
   * 0.750 -> 0.788 / 0.837 / 0.750 (speed error 0.42 / 0.20 / 0.08 % ->
   * 0.38 / 0.15 / 0.06 %), blink and blink_moving up or the same. */
  o->smooth.fit_sd_power = 1;
  /* Gap filling (cmd_track_fill.c): once a track has found its object
   * again and followed it for swap_points frames, the view fit looks for it
   * in each kept frame of the gap, from both ends inwards, starting where
   * the two ends put it, and before the track's first point. Flow 100 ms,
   * seeds 1-20, mean alpha 0.7379 -> 0.7655 (every seed up, by 0.004 to
   * 0.046), F1 0.925 -> 0.943 (held-out seeds 21-24: alpha +0.026 to
   * +0.040), at the cost of the detections'
   * lateral RMSE 0.41 -> 0.46 um (the deep beads it finds are placed to
   * ~1 um). 4 views agreeing, not 6: 0.7634 / 0.7599 (3: 0.7667, more
   * wrong fills); gate 5 um (the weak gate; 3 / 7 / 10 um: 0.7525 /
   * 0.7678 / 0.7684). A fill must reach 0.15 x the intensity at the
   * gap's ends: a blinking bead that is off still shows faintly when it
   * moves (blink_moving's fills had 0.01-0.14 x, flow's 5th percentile
   * 0.17-0.23); without the floor blink_moving's alpha fell 0.317 ->
   * 0.137 (docs/tracker.md "Gap filling"). */
  o->fill_views = 4;
  o->fill_gate_um = 5;
  o->fill_max_gap = 50;
  o->fill_min_ratio = 0.15;
  /* Where one frame's view fit finds nothing in a gap, three frames centred
   * on it, each window where the gap's ends put the bead then: a deep
   * bead's few events add up (cmd_track_fill.c). Flow 100 ms seeds 1-20:
   * alpha 0.7964 -> 0.8000, every seed up or the same, F1 0.9525 -> 0.9536;
   * held-out seeds 21-24 +0.002 to +0.004; 5 frames 0.7984 (without the
   * neighbourhood test, which keeps dense samples' F1). Not on the integral
   * (below). */
  o->fill_frames = 3;
  /* A finished track is followed on past its last point the same way
   * (cmd_track_fill.c, track_fill_end; tracks of 20 points or more):
   * flow 100 ms seeds 1-20 alpha 0.8000 -> 0.8021, every seed up or the
   * same, F1 0.9536 -> 0.9544; 40 / 60 beads alpha 0.6266 -> 0.6273, F1
   * 0.8667 -> 0.8653 (fills in the tracks of ghosts). Not on the integral
   * (below). */
  o->fill_ends = 1;
  /* Where the fit from a gap's prediction finds nothing, the one-frame
   * fit from 1.5 um beside it, each find confirmed by a neighbouring
   * frame's point (cmd_track_fill.c, fill_one): flow 100 ms seeds 1-20
   * alpha 0.8768 -> 0.8814, held-out 21-32 0.8590 -> 0.8638; 40-60 beads
   * precision 0.943 -> 0.925 at the same alpha (docs/tracker.md "Fits
   * started beside the prediction"). */
  o->fill_retry_um = 1.5;
  /* The same floor as gap filling's, for the same reason: a bead that has
   * just gone dark (blinking) still leaves faint ON light in some views,
   * which the view fit finds. blink_moving seeds 1-4: alpha 0.304 / 0.224 /
   * 0.426 / 0.236 -> 0.404 / 0.317 / 0.496 / 0.361; flow seeds 1-20 0.7681 ->
   * 0.7687, flat from 0.15 to 0.4 (docs/tracker.md). */
  o->guided_min_ratio = 0.15;
  /* A guided fit beside another detection most often found that
   * detection's object: of the weak view fits of flow_random 1 s seeds
   * 1-2, 3.8 % lay within 2 um of another detection of their frame, nine
   * in ten on that detection's bead. Kept, two tracks hold one bead, and
   * either may leave on the wrong one. Per-seed alpha against 0:
   * flow_random 1 s seeds 1-32 +0.015 +- 0.005, flow 1 s seeds 1-48
   * +0.006 +- 0.004, flow 100 ms seeds 1-40 +0.003 +- 0.002; 2 and 4 um
   * gave less or the same (docs/tracker.md "A guided fit on another's
   * bead"). */
  o->guided_apart_um = 3;
  o->deep_peak_views = 10;
}

int track_opts_derive(track_opts *o, const track_given *g)
{
  static const char *const C = "track";
  /* neither is changed below */
  const int integral = o->recon.framer.repr == ELFM_REPR_INTEGRAL;
  const int each_trigger = o->recon.framer.start == ELFM_START_EACH_TRIGGER;
  if (integral && !g->rxy) {
    /* The integral has no trail to make side maxima, so a one-voxel box
     * separates neighbours a 3 um box merges: worm neurons come in pairs
     * 6 um apart. Worm 200 ms seeds 1-4, means, box 3 / 2 / 1.5 um: F1
     * 0.887 / 0.911 / 0.912, alpha 0.724 / 0.744 / 0.773. (On flow's time
     * surface 1.5 um loses: alpha 0.733 -> 0.705 over 8 seeds.) */
    o->peaks.radius_xy_um = 1.5;
  }
  if (integral && !g->spord) {
    /* Slowly crawling cells: at 0.1-0.34 um/ms a neuron's acceleration is
     * far below its placement noise, and the jerk penalty's freer fit
     * (a constant acceleration costs nothing) lost: worm 200 ms seeds 1-4,
     * alpha 0.830 / 0.785 / 0.754 / 0.826 -> 0.826 / 0.784 / 0.753 / 0.824. */
    o->smooth.spline_order = 2;
  }
  if (integral && !g->gcvg) {
    /* The integral is a leaky sum over ~100 ms: its frames 2 ms apart share
     * most of their events, so a neuron's placement errors are correlated
     * over many frames, far more than on a 1 ms time surface, and GCV takes
     * them for motion. Each effective parameter is priced higher. Worm
     * (mean alpha, the linker's tracks unchanged; every seed up or the same
     * at 5): 0.5 s seeds 1-8, 13-24 0.9033 -> 0.9167 (G 3 / 4 / 6 / 8:
     * 0.9111 / 0.9145 / 0.9179 / 0.9176), 200 ms seeds 1-12 0.9419 ->
     * 0.9505 (0.9476 / 0.9494 / 0.9504 / 0.9492). Beyond 4 it rests on
     * smooth_track's refit: without it, G 5 dropped a whole neuron's
     * track (200 ms seed 10: 0.948 -> 0.871) and G 6 two (0.5 s). */
    o->smooth.gcv_gamma = 5;
  }
  if (!integral && !g->lscale) {
    /* The robust loss turns at 2 sigma on time surfaces, 3 on the
     * integral. Cauchy, mean alpha at 2 / 3: flow 100 ms seeds 1-20
     * 0.8429 / 0.8417 and 21-32 0.8412 / 0.8400 (30 of 32 seeds up), flow
     * 1 s 0.7726 / 0.7715 (8 of 8), blink 0.9341 / 0.9308 (4 of 4),
     * blink_moving 0.8381 / 0.8378, stage 0.8769 / 0.8772 (speed error
     * as before). The worm would lose at 2 (0.5 s 0.9110 / 0.9199, 200 ms
     * 0.9267 / 0.9505); at 4 it gained on seeds 1-8, 13-24 (0.9215) but
     * not on the held-out 25-32 (0.9225 / 0.9225), so it keeps 3. */
    o->smooth.loss_scale = 2;
  }
  if (integral && !g->fsdp) {
    /* Worm 200 ms seeds 1-4 with it: alpha 0.830 / 0.785 / 0.754 / 0.826
     * -> 0.825 / 0.785 / 0.754 / 0.826. */
    o->smooth.fit_sd_power = 0;
  }
  if (integral && !g->fillv) {
    /* Neurons come in pairs 6 um apart on the integral, and 4 views let a
     * fill land on the partner or on another track's neuron: worm 200 ms
     * seeds 1-4, fills within the scoring gate 64-78 % at 4 views, 95-100 %
     * at 8; F1 0.913 / 0.867 / 0.868 / 0.914 at 4, 0.930 / 0.876 / 0.873 /
     * 0.926 at 8 (0.917 / 0.884 / 0.894 / 0.926 without filling), alpha
     * 0.813 / 0.771 / 0.737 / 0.816 at 8 (0.800 / 0.762 / 0.735 / 0.814). */
    o->fill_views = 8;
  }
  if (integral && !g->fillk) {
    /* The integral already holds every past event (a leaky sum), so its
     * neighbouring frames add no events, only a neighbour's light: worm
     * 200 ms seeds 1-4 with 3 frames, alpha the same, precision 0.933 /
     * 0.896 / 0.892 / 0.941 -> 0.926 / 0.846 / 0.886 / 0.939. */
    o->fill_frames = 1;
  }
  if (integral && !g->locpow) {
    /* The view fit weighs each pixel by value^3 on a time surface, where
     * the newest events are the object; the integral's value is the
     * object's brightness, and its whole image counts alike. Twelfth
     * session, with the start levels, worm 200 ms, power 3 / 2 / 1: seeds
     * 1-4 alpha 0.871 / 0.877 / 0.882 (per seed at 1: 0.885 / 0.828 /
     * 0.841 / 0.929 -> 0.909 / 0.830 / 0.851 / 0.939), held-out seeds 5-7
     * 0.866 / 0.857 / 0.868 (0.825 / 0.930 / 0.842 -> 0.844 / 0.932 /
     * 0.828); lateral RMSE 0.25 -> 0.27 um. Thirteenth session: with
     * the partner's light taken out (localize_near_um), power 2 places
     * better than 1 on every worm set, mean alpha_detections / alpha (200 ms
     * seeds 1-4, 5-7, 8-12, 150 ms, 500 ms): power 1 0.902 / 0.900 / 0.903
     * / 0.887 / 0.895 and 0.900 / 0.878 / 0.911 / 0.881 / 0.845; power 2
     * 0.911 / 0.901 / 0.910 / 0.900 / 0.901 and 0.911 / 0.871 / 0.911 /
     * 0.875 / 0.864; power 3 0.907 / 0.902 / 0.910 / 0.899 / 0.893 and
     * 0.892 / 0.887 / 0.909 / 0.903 / 0.844. Without the partner taken out,
     * its far tail counted for less at power 1. */
    o->loc.power = 2;
  }
  if (integral && !g->spath) {
    /* Crawling neurons cover a few um in 8 frames: the cap binds only
     * where noisy points inflate the path, and fewer points predict worse
     * there (worm 200 ms seeds 1-4 with it: alpha the same, precision
     * 0.933 / 0.896 / 0.892 / 0.941 -> 0.924 / 0.884 / 0.890 / 0.941). */
    o->link.short_path_um = 0;
  }
  if (integral && !g->fille) {
    /* Past a neuron's track's end the fit finds its partner: worm 200 ms
     * seeds 1-4, precision 0.933 / 0.896 / 0.892 / 0.941 -> 0.933 / 0.887 /
     * 0.862 / 0.940, alpha the same or lower (seed 3 0.754 -> 0.752). */
    o->fill_ends = 0;
  }
  if (each_trigger && !g->gmp) {
    /* Windows opened by the LED: one point per pulse, so 10 points take
     * 10 pulses (250 ms at blink's 2-50 ms gaps) before the guided view
     * fit looks for a bead where its track expects it. From 2: blink 200
     * ms seeds 1-12 alpha 0.910 -> 0.935, bead-pulses missed 29 -> 5 of
     * 1245; blink_moving seeds 1-9 0.8460 -> 0.8502 (docs/tracker.md). */
    o->guided_min_points = 2;
  }
  if (each_trigger && !g->circ) {
    /* 15 points of one per pulse span 45 frames or more, and a track that
     * took another bead's pulse on the way fits a circle: blink_moving
     * seeds 1-9 alpha 0.8627 -> 0.8564 with it; blink the same. */
    o->link.circle_points = 0;
  }
  if (each_trigger && !g->circnext) o->link.circle_next_path_um = 0;
  if (each_trigger && !g->fretry) {
    /* Windows opened by the LED: a gap is a dark bead, and more starts
     * find more of its faint last light or of a neighbour (blink seed 3:
     * one fill at z 68 um in a dark gap, alpha 0.937 -> 0.927). */
    o->fill_retry_um = 0;
  }
  if (each_trigger && !g->minpts) {
    /* ... a track of 5 points is 5 pulses (a deep bead that fades after 4
     * had none), and of 3 a bead crossing the field's edge in one or two
     * pulses of blink_moving (7.5 um each) had none: seeds 1-10 missed 41
     * of 471 beads; with 1, 13 (unpaired tracks 4 -> 11), alpha 0.8760 ->
     * 0.8813; blink seeds 1-10 the same (docs/tracker.md "A track for
     * every pulse"). */
    o->link.min_points = 1;
  }
  if (each_trigger) {
    o->link.birth_frames = 3;  /* a dark one-point track: 3 frames' reach */
    o->link.straight_gaps = 2; /* a dark track: straight, not its turn */
  }
  if (!(o->guided_low >= 0) || !(o->guided_radius_um > 0) || o->guided_min_points < 1)
    return cli_message(C, CLI_USAGE,
                       "--guided-low must be >= 0, --guided-radius-um > 0, --guided-min-points >= 1");
  o->thr_defaulted = !g->thr ? 1 | (g->low ? 0 : 2) | (g->min ? 0 : 4) : 0;
  o->views_defaulted = (g->locmin ? 0 : 1) | (g->gviews ? 0 : 2) | (g->fillv ? 0 : 4) | (g->deepv ? 0 : 8);
  if (!g->thr) {
    if (o->recon.framer.repr == ELFM_REPR_COUNT) o->peaks.relative = 0.35;  /* counts have no fixed scale */
    else if (integral) {
      /* The integral's scale is brightness (255 at 8 steps over the
       * floor), not recency: worm 200 ms at 500 Hz seeds 1-4, means, at
       * the floor of 2 steps, threshold 10 / 15: F1 0.893 / 0.905, alpha
       * 0.777 / 0.778 (at a floor of 1.5, threshold 10 / 15 / 20 / 30 /
       * 40: alpha 0.728 / 0.731 / 0.724 / 0.716 / 0.689 with a 3 um box).
       * Twelfth session, with the integral's start levels (brighter first
       * frames, whose ghosts reach 10-30): threshold / hysteresis 15 / 15,
       * 20 / 0, 20 / 15, 25 / 0, 30 / 0: seeds 1-4 F1 0.912 / 0.946 /
       * 0.941 / 0.958 / 0.956, alpha 0.871 / 0.871 / 0.873 / 0.877 /
       * 0.874; held-out seeds 5-7 F1 0.918 / 0.941 / 0.933 / 0.943 / 0.946,
       * alpha 0.862 / 0.866 / 0.856 / 0.845 / 0.826. Thirteenth session:
       * with bright levels leaking at 2 x the leak (tau_bright_us) the
       * images are brighter, and so are their ghosts; threshold 20 / 25 /
       * 30, mean alpha over worm 200 ms seeds 1-4 / 5-7 / 8-12, 150 ms, 500
       * ms: 0.923 / 0.898 / 0.924 / 0.915 / 0.895, 0.927 / 0.919 / 0.927 /
       * 0.909 / 0.907, 0.925 / 0.911 / 0.927 / 0.908 / 0.907; detection
       * precision on seeds 1-12 0.70-0.90, 0.88-0.98, 0.89-1.00. */
      o->peaks.absolute = 25;
      if (!g->low) o->peaks.hysteresis_low = 0;
    } else {
      /* 45 with the view-support test (below), 50 without it: the test
       * removes the ghosts a lower threshold lets in (docs/tracker.md
       * "View support"). */
      o->peaks.absolute = o->view_support > 0 ? 45 : 50;
      /* Hysteresis 45: a bead dimmed by defocus keeps its track without
       * letting the ghosts of that brightness start tracks. Flow 100 ms
       * seeds 1 / 2: F1 0.874 -> 0.886 / 0.889 -> 0.907, alpha 0.627 -> 0.667 /
       * 0.566 -> 0.612, lateral RMSE 0.43-0.47 -> 0.44-0.49 um; stage F1 0.898
       * -> 0.914; at 40 the RMSE passed 0.5 um (docs/tracker.md). Now 30:
       * with the 5 um weak gate (above) ghosts of that brightness rarely
       * sit where a track expects its bead; below ~30 the robust-noise
       * rule (median + 6 sigma) sets the floor (25 gave the same peaks). */
      if (!g->low) o->peaks.hysteresis_low = 30;
      /* Deep beads' peaks fall below 45 (their images are 5-10x dimmer
       * and wider: recall 0.44 at |z| 60-80 um on flow), so the threshold
       * falls with depth to 30 - and a peak only that lowered threshold
       * lets in must have deep_peak_views views agree on it (the view fit,
       * below), which the ghosts at that level rarely have. Flow 100 ms
       * seeds 1-20: F1 0.9461 -> 0.9525, alpha 0.7741 -> 0.7846, recall
       * 0.914 -> 0.926, lateral RMSE 0.456 -> 0.463 um; held-out seeds
       * 21-24 alpha +0.063 / +0.008 / +0.015 / +0.027. Not on a stage:
       * there the deep tracks' noise reached the velocity (speed error
       * 0.41 / 0.18 / 0.06 % -> 0.44 / 0.27 / 0.58 %, seeds 1-3). Without
       * the view test: F1 0.9445, precision 0.982 -> 0.963; 8 / 12 views:
       * F1 0.9511 / 0.9501, alpha 0.7863 / 0.7762 (docs/tracker.md "Deep
       * peaks"). Under the LED's windows on a stage (blinking beads on
       * it) it stays: blink_moving seeds 1-10 with --motion stage, alpha
       * 0.866 -> 0.884 (docs/tracker.md "Blinking beads on a stage
       * given"). */
      if (!g->depth && (o->motion != MOTION_STAGE || each_trigger)) {
        o->peaks.depth_range_um = 60;
        if (!g->min) o->peaks.absolute_min = 30;
      }
      if (o->recon.blur_px > 0) {
        /* --blur-px is for dim objects (about one event per view per
         * frame), whose blurred peaks stay far below 45. Flow with a
         * quarter of the flux (objects.flux_hz=[3000,4000]), 100 ms seeds
         * 1-6, mean alpha / recall / precision: no blur, defaults 0.212 /
         * 0.282 / 0.990; no blur, 8 / 6 / 6 given 0.262 / 0.357 / 0.979;
         * blur 1 with these (x 0.94 at 4 um planes) 0.391 / 0.540 /
         * 0.948; lower (6 / 4 / 4, k 4) did no better. Three times the
         * background (background_hz=3000): 0.323 -> 0.354 -> 0.456
         * (docs/tracker.md "Dim objects"). */
        o->peaks.absolute = 8;
        if (!g->low) o->peaks.hysteresis_low = 6;
        if (!g->min && o->peaks.depth_range_um > 0) o->peaks.absolute_min = 6;
      }
    }
  }
  if (o->motion == MOTION_STAGE) {
    o->smooth.allow_spline = 0;
    if (o->has_stage_v) memcpy(o->link.prior_velocity_um_per_ms, o->stage_v, sizeof o->stage_v);
    /* Everything translates with the stage, so no object comes back onto a
     * path, while a bead trailing another on the same line (or re-entering
     * the field on it) lies on that path: stitching joined two such
     * beads, the track was rejected for outliers (stage 200 ms alpha 0.717
     * -> 0.677). */
    if (!g->stitch) o->link.stitch_points = 0;
    /* A stage translates everything straight: no turn for the path cap to
     * follow, and the longer fit averages more noise (stage seeds 1-3 with
     * it: alpha 0.741 / 0.807 / 0.723 -> 0.736 / 0.806 / 0.715, speed
     * error 0.41 / 0.19 / 0.07 % -> 0.30 / 0.24 / 0.11 %). */
    if (!g->spath) o->link.short_path_um = 0;
    /* ... nor a circle for a dark track to follow (elfm_link.h
     * circle_points): stage 200 ms with it, alpha 0.870 / 0.909 / 0.826
     * -> 0.847 / 0.909 / 0.826 (seeds 1-3). */
    if (!g->circ) o->link.circle_points = 0;
    if (!g->circnext) o->link.circle_next_path_um = 0;
    /* ... nor a turn through a dark gap: straight on at the common
     * velocity (elfm_link.h straight_gaps says why). Stage 200 ms seeds
     * 1-9: alpha 0.8872 -> 0.9055, no track dropped for outliers (5
     * before); docs/tracker.md "Straight gaps on a stage". */
    o->link.straight_gaps = 1;
    /* Rigid motion has one direction, which the tracks' smoothed velocity
     * gives well even at 0.1 um/ms: the lead need not fade below 0.5 um/ms.
     * stage_accel 300 ms (0.1 -> 2.5 um/ms): fitted acceleration 3.6 % ->
     * 2.2 % off, alpha 0.543 -> 0.576; stage seeds 1-3 (2.5 um/ms) the same
     * byte for byte. */
    if (!g->fade) o->smooth.motion_lead_fade_um_per_ms = 0.05;
  } else if (o->motion == MOTION_FREE && o->smooth.model == ELFM_MODEL_AUTO) {
    o->smooth.model = ELFM_MODEL_SPLINE;
  }
  if (o->lag_correct) o->link.lag_tau_us = o->recon.framer.tau_us;
  track_bias_derive(o, g);
  /* --blur-px auto judges the peaks against track's own threshold on a
   * time surface (the integral's dim objects were not measured). Not on a
   * stage: the blur cost its speed, the stage's measure (dim stage, 0.3 of
   * the flux, 200 ms seeds 1-3: alpha 0.381 -> 0.419, but speed error 1.07
   * / 1.57 / 0.15 % -> 1.48 / 1.53 / 1.75 %; at the usual flux 0.17 ->
   * 0.63 % mean, docs/tracker.md "Dim objects"). */
  if (o->blur_auto && (g->thr || !(o->peaks.absolute > 0) || o->motion == MOTION_STAGE ||
                       (o->recon.framer.repr != ELFM_REPR_EXP && o->recon.framer.repr != ELFM_REPR_LIN)))
    o->blur_auto = 0;
  /* The crowded frames' rules were measured on time surfaces (a pixel
   * with signal is one that fired in the window); the blur spreads each
   * pixel over 9 and the integral shows whole objects, which would read as
   * crowded. */
  const int crowd_measured = o->recon.blur_px == 0 && (o->recon.framer.repr == ELFM_REPR_EXP ||
                                                       o->recon.framer.repr == ELFM_REPR_LIN);
  /* ... and each rule lowers its setting only from above its floor */
  if (!crowd_measured || !(o->view_support > 0)) o->view_support_auto = 0;
  if (!crowd_measured || !(o->link.rescue_gate_factor > TRACK_RESCUE_MIN)) o->rescue_auto = 0;
  if (!crowd_measured || !(o->link.gate_um > TRACK_GATE_MIN_UM)) o->gate_auto = 0;
  /* The automatic window on time surfaces with windows on the 1 ms grid:
   * not on the integral (slow cells, 2 ms frames by choice), windows opened
   * by a trigger (one per pulse), nor a stage (its linker predicts with
   * the stage's own motion: 5 mm/s stage speed error 0.10 % at 1 ms). */
  if (o->dt_auto && ((o->recon.framer.repr != ELFM_REPR_EXP && o->recon.framer.repr != ELFM_REPR_LIN) ||
                     o->recon.framer.start == ELFM_START_EACH_TRIGGER || o->motion == MOTION_STAGE ||
                     o->recon.framer.dt_us < 2))
    o->dt_auto = 0;
  /* --repr lin under pulsed light (auto_judge), on a stage too: from the
   * default time surface (track_opts_parse), with thresholds or the blur
   * given too. lin's values are at most exp's (e^-a >= 1 - a), and the
   * LED's windows need lin far more: blink_moving seeds 1-10 with
   * --threshold-abs 45, alpha 0.570 on exp, 0.864 on lin; with --blur-px
   * 1, 0.222 / 0.885. */
  if (o->recon.framer.repr != ELFM_REPR_EXP) o->lin_auto = 0;
  /* The integral for crawling cells, from the default time surface only:
   * not with thresholds given (the integral's scale differs), windows
   * opened by a trigger, or a stage (its own motion model). */
  if (o->repr_auto && (g->thr || o->recon.framer.repr != ELFM_REPR_EXP ||
                       o->recon.framer.start == ELFM_START_EACH_TRIGGER || o->motion == MOTION_STAGE))
    o->repr_auto = 0;
  /* The test for a stage on time surfaces: not on the integral (the
   * worm's cells; a stage's beads are best seen by their ON events,
   * "Integral frames"), nor where a model was given. Also on the windows
   * the LED's pulses open: blinking beads on a stage (docs/tracker.md
   * "A stage under the LED's pulses"). */
  if (o->motion_auto && (o->motion != MOTION_AUTO || o->smooth.model != ELFM_MODEL_AUTO ||
                         (o->recon.framer.repr != ELFM_REPR_EXP && o->recon.framer.repr != ELFM_REPR_LIN)))
    o->motion_auto = 0;
  /* Windows opened by the light's pulses (track_pulsed), from the grid on
   * time surfaces only (cells on the integral are left alone). With a
   * stage given too: blinking beads on a stage are what the user of
   * --motion stage records under an LED, and on the grid's windows they
   * tracked at half the alpha (blink_moving seeds 1-10 with --motion stage:
   * 0.490 on the grid, 0.884 on each pulse's lin window, docs/tracker.md
   * "Blinking beads on a stage given"). */
  if (o->start_auto && (o->recon.framer.start != ELFM_START_FIRST_EVENT ||
                        (o->recon.framer.repr != ELFM_REPR_EXP && o->recon.framer.repr != ELFM_REPR_LIN)))
    o->start_auto = 0;
  /* The deep window (docs/tracker.md "A longer window for deep beads"): a
   * bead beyond |z| ~45 um fires a few ON events per view and window, and
   * the fits a track guides there (track_guided_loc) read the last 2 x dt
   * of events; the volume, its peaks and their own fits keep the window's,
   * so the first run's judgements see the same peaks. Flow 1 s seeds 1-60
   * alpha +0.012, 100 ms seeds 1-40 +0.003, random flow 1 s seeds 1-44
   * -0.001 (alpha_identities +0.005..+0.013 on every set); 1.07 of the
   * time. Only on the ON time surface of a fixed grid, unblurred and
   * unfiltered (the blur and the median would mix the older pixels into
   * the window's), and without the view-agreement rule (--agree, --ghost
   * agree:F), which reads each run of a frame as signal and refuses a
   * deep window's frames: with it, every `track --agree F` ended at its
   * first frame with that refusal (exit 1; tests/track_extremes.sh). */
  const int deep_ok = o->recon.framer.repr == ELFM_REPR_EXP && o->recon.framer.polarity == ELFM_POL_ON &&
                      !each_trigger && o->recon.blur_px == 0 && o->recon.median == 0 &&
                      !(o->recon.refocus.agree_frac > 0) && o->recon.framer.dt_us <= 5000000;
  o->recon.framer.deep_window_us = !deep_ok ? 0
                                   : o->deep_window_us < 0 ? 2 * o->recon.framer.dt_us
                                                           : o->deep_window_us;
  if (o->recon.framer.deep_window_us > 0 && o->recon.framer.deep_window_us <= o->recon.framer.dt_us) {
    cli_message(C, CLI_USAGE, "--deep-window-us %" PRId64 " must be longer than the window (--dt-us %" PRId64
                ") or 0 (off)", o->recon.framer.deep_window_us, o->recon.framer.dt_us);
    return CLI_USAGE;
  }
  return CLI_OK;
}

void track_views_step(track_opts *o, const elfm_calib *cal)
{
  /* The counts were chosen on the paper's 25 views, where a few ghosts'
   * views line up by chance. With fewer views fewer agree on a real
   * object too: flow 100 ms with a 3 x 3 lens array (optics.lenslets_per_side=3),
   * 3 / 3 / 2 / 4 instead of 6 / 8 / 4 / 10: seeds 1-8 mean alpha 0.650 ->
   * 0.684 (6 of 8 up), held-out seeds 9-14 0.685 -> 0.691 (3 of 6 up);
   * recall up on 13 of the 14 (+0.011 to +0.045), precision ~0.013 lower.
   * Above all, no count asks for more views than there are. More views
   * than 25 keep the counts: 7 x 7 (49 views), seeds 1-4, lost with them
   * doubled (0.8875 -> 0.8810, recall 0.973 -> 0.953). */
  o->views_scaled = 0;
  const int n = cal->n_views;
  if (n >= 25 || n < 2) return;
  if (o->views_defaulted & 1) o->loc.min_views = cli_views_scale(o->loc.min_views, n);
  if (o->views_defaulted & 2) o->guided_views = cli_views_scale(o->guided_views, n);
  if (o->views_defaulted & 4) o->fill_views = cli_views_scale(o->fill_views, n);
  if (o->views_defaulted & 8) o->deep_peak_views = cli_views_scale(o->deep_peak_views, n);
  if (o->views_defaulted) o->views_scaled = n;
}

void track_plane_step(track_opts *o, elfm_calib *cal)
{
  o->plane_every = 1;
  o->plane_centred = 0;
  if (!isnan(o->planes_um[2]) || !(o->plane_shift_px > 0)) return;
  double shift = 0; /* px per um, the outermost view */
  for (int v = 0; v < cal->n_views; v++) {
    shift = fmax(shift, fabs(cal->views[v].dx_px_per_um));
    shift = fmax(shift, fabs(cal->views[v].dy_px_per_um));
  }
  const double step = cal->z_step_um;
  const long span = elfm_calib_n_planes(cal) - 1; /* steps from the first plane to the last */
  if (!(shift > 0) || span < 2) return;
  int m = (int)floor(o->plane_shift_px / (shift * step) + 1e-9);
  if (m > span) m = (int)span;
  if (m <= 1) return;
  /* Every m-th plane, the range centred: where m does not divide the
   * span, the remainder (under m calibration planes) is split between
   * the two ends (6 um on -100..100 at 2 um: -99..99). */
  cal->z_step_um = step * m;
  cal->z_min_um += 0.5 * (double)(span % m) * step;
  o->plane_centred = span % m != 0;
  cal->z_max_um = cal->z_min_um + (double)(span / m) * cal->z_step_um;
  o->plane_every = m;
  /* the same axial window in um: +-3 planes of 2 um are +-2 of 4 um */
  o->peaks.fit_half_z = (int)lround((double)o->peaks.fit_half_z / m);
  if (o->peaks.fit_half_z < 1) o->peaks.fit_half_z = 1;
  /* A bead's peak in its nearest plane falls by up to exp(-(h/2)^2 /
   * (2 s^2)) with planes h apart: the defaults were measured at the
   * calibration's planes, so they fall by the ratio (0.94 at 4 um against
   * 2). Interpolating each peak's height between planes instead recovered
   * a third of the stage's lost deep beads (docs/tracker.md "Planes 4 um
   * apart"). Thresholds given on the command line are taken as they are. */
  const double s2 = 2 * TRACK_AXIAL_SIGMA_UM * TRACK_AXIAL_SIGMA_UM;
  const double h0 = step / 2, h1 = cal->z_step_um / 2;
  const double f = exp(-(h1 * h1 - h0 * h0) / s2);
  if (o->thr_defaulted & 1) o->peaks.absolute *= f;
  if (o->thr_defaulted & 2) o->peaks.hysteresis_low *= f;
  if (o->thr_defaulted & 4) o->peaks.absolute_min *= f;
}
