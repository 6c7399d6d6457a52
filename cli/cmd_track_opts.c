/* cmd_track_opts.c — eventlfm track's options: its defaults (where they
 * differ from the libraries', and why: each measured on the simulator),
 * --help, and the parsing. The defaults that depend on other options (the
 * representation, the motion, the window start) are in
 * cmd_track_defaults.c; the run is in cmd_track.c. */
#include <errno.h>
#include <getopt.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cmd_track.h"

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
  /* The smoother's robust loss: Cauchy, not the library's Huber. A ghost
   * joined to a track, or a detection of the neighbour at an encounter,
   * lies many sigmas off: Cauchy's weight falls as 1/r^2 and lets go of
   * it, Huber's as 1/r and still pulls. Mean alpha, Huber -> Cauchy (with
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
  /* Stitching a new track of 5 points onto a dark track whose recent path
   * its points follow within 8 um RMS (elfm_link.h step 5): flow beads
   * circle and come back onto their own path after gaps no extrapolation
   * bridges. Flow 100 ms seeds 1 / 2: alpha 0.677 -> 0.697 / 0.646 ->
   * 0.691, 7 -> 3 / 6 -> 1 spurious tracks; blink unchanged; worm 0.327 ->
   * 0.326 (docs/tracker.md "Stitching"). Points 4-6 and gates 6-10 um
   * gave the same to +-0.01. Off in --motion stage (below). */
  o->link.stitch_points = 5;
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
  /* The spline weight by modified GCV (elfm_smooth.h gcv_gamma): the
   * detections' errors are correlated from frame to frame (flow: lag-1
   * autocorrelation 0.54-0.58 laterally, 0.38 in z), which classical GCV
   * takes for motion. Flow 100 ms seeds 1-20: alpha 0.7897 -> 0.7950,
   * every seed up or the same (1.2 / 1.6 / 2: 0.7945 / 0.7938 / 0.7867);
   * held-out 21-24 +0.003 to +0.007; worm (integral) seeds 1-4 +0.001 to
   * +0.004; blink, blink_moving up; stage (no spline) the same. */
  o->smooth.gcv_gamma = 1.4;
  /* The spline penalises the jerk, not the acceleration (elfm_smooth.h
   * spline_order): a flow bead turns at ~0.3 rad/ms, a constant
   * acceleration the acceleration penalty pulls toward a line. Flow 100 ms
   * seeds 1-20: alpha 0.7950 -> 0.7964 (14 up, 5 the same, 1 down), lateral
   * velocity RMSE 0.273 / 0.252 -> 0.264 / 0.236 um/ms; held-out 21-24 +0 to
   * +0.003; 40/60 beads +0.002; blink, blink_moving the same. Not on the
   * integral (below). */
  o->smooth.spline_order = 3;
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
  /* The same floor as gap filling's, for the same reason: a bead that has
   * just gone dark (blinking) still leaves faint ON light in some views,
   * which the view fit finds. blink_moving seeds 1-4: alpha 0.304 / 0.224 /
   * 0.426 / 0.236 -> 0.404 / 0.317 / 0.496 / 0.361; flow seeds 1-20 0.7681 ->
   * 0.7687, flat from 0.15 to 0.4 (docs/tracker.md). */
  o->guided_min_ratio = 0.15;
  o->deep_peak_views = 10;
}

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
    "  --threshold-k K      k x robust noise sigma (6), --threshold-abs V (45 on time\n"
    "                       surfaces, 20 on the integral), --threshold-rel F (0.35 of\n"
    "                       the maximum for counts)\n"
    "  --threshold-depth-um Z  absolute threshold / (1 + (z/Z)^2) (0 = same at all\n"
    "                       depths; default 60 on time surfaces, 0 with --motion stage)\n"
    "  --threshold-min V    floor of that depth-scaled threshold (default 30)\n"
    "  --deep-peak-views N  a peak above the depth-scaled threshold only is kept when\n"
    "                       the view fit from it has >= N views agreeing (10; 0 = no\n"
    "                       test; needs --localize views, the default)\n"
    "  --threshold-low V    hysteresis: peaks above V but below the threshold may\n"
    "                       continue a track, never start one (30 with the default\n"
    "                       threshold, 0 = off; off on the integral)\n"
    "  --views-rule on|off  where n of the N views sample a voxel, a peak must exceed\n"
    "                       the threshold x (N/n)^E, --views-exponent E (default on, 0.5)\n"
    "  --view-support F     a peak needs signal in >= F of the views sampling its voxel\n"
    "                       (ghosts: a few views; default 0.3, 0 = off)\n"
    "  --localize views|peak  views (default): each peak's position from its images\n"
    "                       in the views, fitted together; peak: the sub-voxel fit of\n"
    "                       the refocused peak only\n"
    "  --localize-window-px R  each view's window is (2R+1)^2 px (2)\n"
    "  --localize-power P   pixel weight value^P: higher P follows the newest events,\n"
    "                       at the object's leading edge (3; 2 with --repr integral;\n"
    "                       1 is better for bright objects whose ON events lead\n"
    "                       them, e.g. beads on a stage)\n"
    "  --localize-outlier-px D  views missing the fit by more are dropped (1.5)\n"
    "  --localize-min-views N  fewer views with signal: keep the peak fit (6)\n"
    "  --localize-near-um D the view fit of a peak, or of a track's prediction, takes\n"
    "                       out the light of the frame's other objects within D um\n"
    "                       laterally, read mirrored through their centres (0 = off;\n"
    "                       default 12 with --repr integral, else 0)\n"
    "  --radius-xy-um R, --radius-z-um R   local-maximum box (3, 1.5 with --repr integral;\n"
    "                       15)\n"
    "  --min-separation-um D (4), --refine gauss|quad|none, --max-detections N (10000)\n"
    "linking:\n"
    "  --gate-um G (6), --max-gap N frames (50), --min-points N (5; 3 with --start\n"
    "                       each-trigger, one point per pulse)\n"
    "  --lead-sigmas K      with --lag-correct: ON events lead a moving object by ~K x\n"
    "                       its width along the motion; move detections back by that\n"
    "  --link-kz K          axial scale of the linker's distance sqrt(dx2+dy2+(dz/K)2) (1.5)\n"
    "  --rescue-factor F    unmatched tracks retry leftovers within F x gate (2.5; 0 off)\n"
    "  --stitch-points N    a new track of N points continues a dark one when its points\n"
    "                       lie on that one's recent path (5; 0 off; --motion stage: 0)\n"
    "  --stitch-gate-um G   RMS distance to the dark track's path for that (8)\n"
    "  --swap-points N      review a gap closing that does not fit when its new tail\n"
    "                       has N points; exchange tails with a better fit (8; 0 off)\n"
    "  --encounter-um D     two tracks that came within D (linker metric) are reviewed\n"
    "                       the same way once both have N points after it (5; 0 off)\n"
    "  --encounter-pad N    frames before the encounter left out of the heads (1)\n"
    "  --encounter-apart N  up to N frames apart, then together again, are one\n"
    "                       encounter (4)\n"
    "  --encounter-ratio R  exchange when the other way fits R times better (0.5)\n"
    "  --encounter-circle-ratio R  ... or when the heads' circles (--circle-points)\n"
    "                       meet the tails the other way R times better (0.5; 0 = off)\n"
    "  --encounter-line-ratio R  ... or, while the objects are at rest (see\n"
    "                       --rest-speed-um-per-ms), when straight lines through 20\n"
    "                       points of each head and tail join the other way R times\n"
    "                       better; the review then waits for 20 points (0.5; 0 = off)\n"
    "  --review-join-factor F  the swap and encounter reviews exchange only when the\n"
    "                       new joins lie within F x the gate, RMS (2; 0 no limit)\n"
    "  --rest-speed-um-per-ms V  while most tracks of >= 4 points move slower than V,\n"
    "                       a track dark for over 6 frames is looked for where it\n"
    "                       was too, not only where its velocity carries it (for\n"
    "                       blinking objects at rest that velocity is the noise of\n"
    "                       a few pulses' points) (0.5; 0 off)\n"
    "  --priority-points N  tracks of >= N points choose their detections before\n"
    "                       younger ones (8; 0 = one assignment for all)\n"
    "  --short-path-um L    a track's prediction fits its last 8 points, fewer (>= 4)\n"
    "                       when they span more than L um of path, as fast objects'\n"
    "                       do (20; 0 = always 8; --motion stage, --repr integral: 0)\n"
    "  --circle-points N    a track dark for --circle-after M frames (2) or more is\n"
    "                       predicted along the circle through its last N points,\n"
    "                       when they follow one better than a line (15; 0 off;\n"
    "                       --motion stage, --start each-trigger: 0)\n"
    "  --weak-gate-um D     weak (hysteresis) peaks join a track only within D of its\n"
    "                       prediction (default 5; 0 = the track's gate)\n"
    "  --guided-low V       where a track of >= --guided-min-points N (10; 2 with\n"
    "                       --start each-trigger, one point per pulse) points\n"
    "                       predicts its bead and no peak lies within the weak gate,\n"
    "                       take the local maximum above V within --guided-radius-um\n"
    "                       R (1.5, z x link-kz) as a weak peak (default 0 = off)\n"
    "  --guided-views N     where a track of >= --guided-min-points points predicts\n"
    "                       its bead and no peak lies within the weak gate, fit the\n"
    "                       views from the prediction; a fit with >= N views agreeing\n"
    "                       and at least --guided-min-ratio F (0.15) x the track's\n"
    "                       last intensity becomes a weak peak (default 8; 0 = off;\n"
    "                       the floor keeps it off a blinking bead's faint last light)\n"
    "  --fill-views N       gap filling: once a track has found its object again\n"
    "                       (8 points on), fit the views in each kept frame of the\n"
    "                       gap, and before the track began, from where the gap's\n"
    "                       two ends put the object; a fit with >= N views agreeing,\n"
    "                       within --fill-gate-um G (5) of that and at least\n"
    "                       --fill-min-ratio F (0.15) x the ends' intensity becomes\n"
    "                       a detection of that track (default 4, with --repr\n"
    "                       integral 8; 0 = off: better for blinking objects)\n"
    "  --fill-max-gap N     frames kept for it: gaps up to N are filled (50)\n"
    "  --fill-frames N      where one frame's fit finds nothing, fit N frames centred\n"
    "                       on it, each window where the gap's ends put the object\n"
    "                       then (a dim object's events add up); 2 more views must\n"
    "                       agree, and not at two of four places beside it (odd,\n"
    "                       1..9; default 3, with --repr integral 1 = off)\n"
    "  --fill-ends on|off   follow a finished track of >= 20 points on past its last\n"
    "                       point the same way (default on, with --repr integral off)\n"
    "  --lag-correct on|off  shift detections forward by the time-surface lag (off)\n"
    "smoothing:\n"
    "  --motion auto|stage|free   auto: model chosen per track (BIC) among constant\n"
    "                       velocity, constant acceleration and spline; stage: rigid\n"
    "                       motion (no spline; with a stage velocity, new tracks\n"
    "                       predict with it and tracks far from it are dropped);\n"
    "                       free: smoothing spline for all\n"
    "  --stage-velocity-um-per-ms vx,vy,vz   known stage velocity (summary compares)\n"
    "  --model auto|cv|ca|spline, --spline-weight-ms3 W\n"
    "  --loss L             robust loss of the smoother, scale 3 sigma: cauchy (the\n"
    "                       default), huber or none\n"
    "  --gcv-gamma G        the spline weight (when not given) minimises GCV with G per\n"
    "                       effective parameter: n RSS / (n - G edf)^2 (1.4; integral 5;\n"
    "                       1 classical); a track the robust fit would reject at G is\n"
    "                       smoothed again at 1 and kept or rejected on that fit\n"
    "  --spline-order N     the spline penalises the acceleration (2) or the jerk (3),\n"
    "                       which leaves turns at constant speed alone (3; integral: 2)\n"
    "  --view-fit-sigma F   points the view fit found where no peak stood out (gap\n"
    "                       filling, guided search) count as F x noisier than the\n"
    "                       track's peaks (1.5)\n"
    "  --fit-sd-power P     each point's sigma also x (its view fit's scatter / the\n"
    "                       track's median)^P: points whose views agreed less count\n"
    "                       less (1; integral: 0; 0 = off)\n"
    "  --max-outlier-frac F drop tracks whose robust fit rejects more than F of\n"
    "                       their points (default 1/3)\n"
    "  --piece-points N     long tracks in bounded memory: once a live track has N +\n"
    "                       N/4 points, its oldest N are smoothed (with N/8 points of\n"
    "                       context on each side) and written, and dropped from\n"
    "                       memory (1024; 0 = keep whole tracks). The outlier rule\n"
    "                       then judges each piece\n"
    "  --motion-lead-um A, --motion-delay-us D   each view's image of a moving object\n"
    "                       lies A um ahead of it along the image's motion and shows\n"
    "                       where it was D us before the frame: the smoother moves the\n"
    "                       points back by the bias that gives the view fit (laterally\n"
    "                       A - D x speed along the motion) and fits again. ON time\n"
    "                       surface with the view fit: A 1.80 x the median width of\n"
    "                       the in-focus peaks - 0.37 um (brighter beads lead further;\n"
    "                       --motion stage: 1.52 x the width; 1.25 until 50 peaks),\n"
    "                       D the weighted events' mean age + 150 us\n"
    "                       (431 us at tau 1 ms); integral: A -0.05, D 0 (worm\n"
    "                       neurons); else 0, 0 = off. eventlfm score --calib\n"
    "                       measures A and D on a simulated scene; one given alone\n"
    "                       leaves the other at its default\n"
    "  --motion-fade-um-per-ms F  below this speed the lead fades out (the direction\n"
    "                       of motion is noise): 0.5; integral and --motion stage 0.05\n"
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

/* A view-count option, 0 (off) or 2..255 (--guided-views, --fill-views):
 * 1, or 0 after a usage message. */
static int parse_views_or_off(const char *cmd, const char *opt, const char *a, int *out)
{
  if (!cli_parse_int(cmd, opt, a, out)) return 0;
  if (*out != 0 && (*out < 2 || *out > 255)) {
    cli_message(cmd, CLI_USAGE, "%s must be 0 or 2..255, not '%s'", opt, a);
    return 0;
  }
  return 1;
}

enum {
  O_CALIB = 1000, O_EVENTS, O_OUT, O_THK, O_THA, O_THR, O_RXY, O_RZ, O_SEP, O_REFINE, O_MAXDET,
  O_GATE, O_MAXGAP, O_MINPTS, O_LAG, O_MOTION, O_STAGEV, O_MODEL, O_LOSS, O_SPW, O_RES, O_MAXOUT,
  O_THDEPTH, O_THMIN, O_VIEWSRULE, O_RESCUE, O_LEAD, O_LINKKZ, O_VEXP, O_HYST, O_WEAKGATE,
  O_GUIDED, O_GUIDEDR, O_GUIDEDM, O_VSUP, O_STITCHN, O_STITCHG, O_SWAPN, O_LOC, O_LOCWIN,
  O_LOCPOW, O_LOCOUT, O_LOCMIN, O_LOCNEAR, O_GVIEWS, O_MLEAD, O_MDELAY,
  O_FILLV, O_FILLG, O_FILLN, O_FILLR, O_FILLK, O_FILLE, O_SPATH, O_CIRCN, O_CIRCA, O_VFSIG, O_GRATIO, O_DEEPV, O_PRIO, O_GCVG, O_SPORD, O_FSDP, O_MFADE,
  O_ENCUM, O_ENCPAD, O_ENCAPART, O_ENCR, O_ENCCR, O_ENCLR, O_RJOIN, O_RESTV, O_PIECE
};

/* Parse argv into *out (track defaults first). CLI_OK: run; TRACK_PARSE_HELP:
 * --help was printed; otherwise the usage error already shown. */
int track_opts_parse(int argc, char **argv, track_opts *out)
{
  static const char *const C = "track";
  track_opts o;
  track_defaults(&o);
  track_given g;
  memset(&g, 0, sizeof g);
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
      {"encounter-um", required_argument, 0, O_ENCUM},
      {"encounter-pad", required_argument, 0, O_ENCPAD},
      {"encounter-apart", required_argument, 0, O_ENCAPART},
      {"rest-speed-um-per-ms", required_argument, 0, O_RESTV},
      {"encounter-ratio", required_argument, 0, O_ENCR},
      {"encounter-circle-ratio", required_argument, 0, O_ENCCR},
      {"encounter-line-ratio", required_argument, 0, O_ENCLR},
      {"review-join-factor", required_argument, 0, O_RJOIN},
      {"weak-gate-um", required_argument, 0, O_WEAKGATE},
      {"guided-low", required_argument, 0, O_GUIDED},
      {"view-support", required_argument, 0, O_VSUP},
      {"localize", required_argument, 0, O_LOC},
      {"localize-window-px", required_argument, 0, O_LOCWIN},
      {"localize-power", required_argument, 0, O_LOCPOW},
      {"localize-outlier-px", required_argument, 0, O_LOCOUT},
      {"localize-min-views", required_argument, 0, O_LOCMIN},
      {"localize-near-um", required_argument, 0, O_LOCNEAR},
      {"guided-views", required_argument, 0, O_GVIEWS},
      {"fill-views", required_argument, 0, O_FILLV},
      {"fill-gate-um", required_argument, 0, O_FILLG},
      {"view-fit-sigma", required_argument, 0, O_VFSIG},
      {"guided-min-ratio", required_argument, 0, O_GRATIO},
      {"deep-peak-views", required_argument, 0, O_DEEPV},
      {"priority-points", required_argument, 0, O_PRIO},
      {"gcv-gamma", required_argument, 0, O_GCVG},
      {"spline-order", required_argument, 0, O_SPORD},
      {"fit-sd-power", required_argument, 0, O_FSDP},
      {"motion-fade-um-per-ms", required_argument, 0, O_MFADE},
      {"fill-max-gap", required_argument, 0, O_FILLN},
      {"fill-frames", required_argument, 0, O_FILLK},
      {"fill-ends", required_argument, 0, O_FILLE},
      {"short-path-um", required_argument, 0, O_SPATH},
      {"circle-points", required_argument, 0, O_CIRCN},
      {"circle-after", required_argument, 0, O_CIRCA},
      {"fill-min-ratio", required_argument, 0, O_FILLR},
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
      {"piece-points", required_argument, 0, O_PIECE},
      {"motion-lead-um", required_argument, 0, O_MLEAD},
      {"motion-delay-us", required_argument, 0, O_MDELAY},
      {"quiet", no_argument, 0, 'q'}, {"help", no_argument, 0, 'h'}, {0, 0, 0, 0}};
  cli_recon_parse rp = {.ro = &o.recon};
  optind = 1;
  opterr = 0;
  int ch;
  while ((ch = getopt_long(argc, argv, ":hq", lo, NULL)) != -1) {
    const char *a = optarg;
    const int k = cli_parse_recon_option(C, ch, a, &rp);
    if (k == 0) return CLI_USAGE;
    if (k > 0) continue;
    switch (ch) {
    case 'h': usage(stdout); return TRACK_PARSE_HELP;
    case 'q': o.quiet = 1; break;
    case O_CALIB: o.calib = a; break;
    case O_EVENTS: o.events = a; break;
    case O_OUT: o.out = a; break;
    case O_THK: g.thr = 1; if (!cli_parse_double(C, "--threshold-k", a, &o.peaks.k_sigma)) return CLI_USAGE; break;
    case O_THA: g.thr = 1; if (!cli_parse_double(C, "--threshold-abs", a, &o.peaks.absolute)) return CLI_USAGE; break;
    case O_THDEPTH: g.depth = 1; if (!cli_parse_double(C, "--threshold-depth-um", a, &o.peaks.depth_range_um)) return CLI_USAGE; break;
    case O_HYST: g.low = 1; if (!cli_parse_double(C, "--threshold-low", a, &o.peaks.hysteresis_low)) return CLI_USAGE; break;
    case O_VEXP: if (!cli_parse_double(C, "--views-exponent", a, &o.views_exponent)) return CLI_USAGE; break;
    case O_LINKKZ: if (!cli_parse_double(C, "--link-kz", a, &o.link.kz)) return CLI_USAGE; break;
    case O_LEAD: if (!cli_parse_double(C, "--lead-sigmas", a, &o.link.lead_sigmas)) return CLI_USAGE; break;
    case O_GUIDEDR: if (!cli_parse_double(C, "--guided-radius-um", a, &o.guided_radius_um)) return CLI_USAGE; break;
    case O_GUIDEDM: g.gmp = 1; if (!cli_parse_int(C, "--guided-min-points", a, &o.guided_min_points)) return CLI_USAGE; break;
    case O_VSUP:
      if (!cli_parse_double(C, "--view-support", a, &o.view_support)) return CLI_USAGE;
      if (!(o.view_support >= 0 && o.view_support <= 1))
        return cli_message(C, CLI_USAGE, "--view-support must be in 0..1");
      break;
    case O_LOC:
      if (!strcmp(a, "views")) o.localize_views = 1;
      else if (!strcmp(a, "peak")) o.localize_views = 0;
      else return cli_message(C, CLI_USAGE, "--localize must be views or peak, not '%s'", a);
      break;
    case O_LOCWIN:
      if (!cli_parse_int(C, "--localize-window-px", a, &o.loc.half_window_px)) return CLI_USAGE;
      if (o.loc.half_window_px < 1 || o.loc.half_window_px > 32)
        return cli_message(C, CLI_USAGE, "--localize-window-px must be 1..32, not '%s'", a);
      break;
    case O_LOCPOW:
      g.locpow = 1;
      if (!cli_parse_int(C, "--localize-power", a, &o.loc.power)) return CLI_USAGE;
      if (o.loc.power < 1 || o.loc.power > 8)
        return cli_message(C, CLI_USAGE, "--localize-power must be 1..8, not '%s'", a);
      break;
    case O_LOCNEAR:
      g.near = 1;
      if (!cli_parse_double_in(C, "--localize-near-um", a, 0, 0, 1000, "0..1000",
                               &o.localize_near_um))
        return CLI_USAGE;
      break;
    case O_LOCOUT:
      if (!cli_parse_double(C, "--localize-outlier-px", a, &o.loc.outlier_px)) return CLI_USAGE;
      if (!(o.loc.outlier_px > 0 && o.loc.outlier_px <= 1000))
        return cli_message(C, CLI_USAGE, "--localize-outlier-px must be > 0, not '%s'", a);
      break;
    case O_LOCMIN:
      if (!cli_parse_int(C, "--localize-min-views", a, &o.loc.min_views)) return CLI_USAGE;
      if (o.loc.min_views < 2 || o.loc.min_views > 255)
        return cli_message(C, CLI_USAGE, "--localize-min-views must be 2..255, not '%s'", a);
      break;
    case O_FILLV:
      g.fillv = 1;
      if (!parse_views_or_off(C, "--fill-views", a, &o.fill_views)) return CLI_USAGE;
      break;
    case O_FILLG:
      if (!cli_parse_double_in(C, "--fill-gate-um", a, 0, 1, 100, "> 0 and <= 100", &o.fill_gate_um)) return CLI_USAGE;
      break;
    case O_VFSIG:
      if (!cli_parse_double_in(C, "--view-fit-sigma", a, 0, 1, 1000, "> 0 and <= 1000",
                               &o.smooth.view_fit_sigma_factor))
        return CLI_USAGE;
      break;
    case O_DEEPV:
      if (!parse_views_or_off(C, "--deep-peak-views", a, &o.deep_peak_views)) return CLI_USAGE;
      break;
    case O_PRIO:
      if (!cli_parse_int(C, "--priority-points", a, &o.link.priority_points)) return CLI_USAGE;
      if (o.link.priority_points < 0) {
        cli_message(C, CLI_USAGE, "--priority-points must be >= 0, not '%s'", a);
        return CLI_USAGE;
      }
      break;
    case O_GRATIO:
      if (!cli_parse_double_in(C, "--guided-min-ratio", a, 0, 0, 1, "0..1", &o.guided_min_ratio)) return CLI_USAGE;
      break;
    case O_FILLR:
      if (!cli_parse_double_in(C, "--fill-min-ratio", a, 0, 0, 1, "0..1", &o.fill_min_ratio)) return CLI_USAGE;
      break;
    case O_FILLK:
      g.fillk = 1;
      if (!cli_parse_int(C, "--fill-frames", a, &o.fill_frames)) return CLI_USAGE;
      if (o.fill_frames < 1 || o.fill_frames > TRACK_FILL_MAX_FRAMES || o.fill_frames % 2 == 0)
        return cli_message(C, CLI_USAGE, "--fill-frames must be odd, 1..%d, not '%s'",
                           TRACK_FILL_MAX_FRAMES, a);
      break;
    case O_FILLE:
      g.fille = 1;
      if (!strcmp(a, "on")) o.fill_ends = 1;
      else if (!strcmp(a, "off")) o.fill_ends = 0;
      else return cli_message(C, CLI_USAGE, "--fill-ends must be on or off, not '%s'", a);
      break;
    case O_SPATH:
      g.spath = 1;
      if (!cli_parse_double_in(C, "--short-path-um", a, 0, 0, 1000, "0..1000", &o.link.short_path_um))
        return CLI_USAGE;
      break;
    case O_CIRCN:
      g.circ = 1;
      if (!cli_parse_int(C, "--circle-points", a, &o.link.circle_points)) return CLI_USAGE;
      if (o.link.circle_points != 0 && (o.link.circle_points < 6 || o.link.circle_points > 1000))
        return cli_message(C, CLI_USAGE, "--circle-points must be 0 (off) or 6..1000, not %s", a);
      break;
    case O_CIRCA:
      if (!cli_parse_int_in(C, "--circle-after", a, 1, 1000, "1..1000 frames", &o.link.circle_after))
        return CLI_USAGE;
      break;
    case O_FILLN:
      if (!cli_parse_int(C, "--fill-max-gap", a, &o.fill_max_gap)) return CLI_USAGE;
      if (o.fill_max_gap < 1 || o.fill_max_gap > 1000)
        return cli_message(C, CLI_USAGE, "--fill-max-gap must be 1..1000, not '%s'", a);
      break;
    case O_GVIEWS:
      if (!parse_views_or_off(C, "--guided-views", a, &o.guided_views)) return CLI_USAGE;
      break;
    case O_GUIDED: if (!cli_parse_double(C, "--guided-low", a, &o.guided_low)) return CLI_USAGE; break;
    case O_WEAKGATE: if (!cli_parse_double(C, "--weak-gate-um", a, &o.link.weak_gate_um)) return CLI_USAGE; break;
    case O_RESCUE: if (!cli_parse_double(C, "--rescue-factor", a, &o.link.rescue_gate_factor)) return CLI_USAGE; break;
    case O_STITCHN:
      if (!cli_parse_int(C, "--stitch-points", a, &o.link.stitch_points)) return CLI_USAGE;
      g.stitch = 1;
      break;
    case O_SWAPN: if (!cli_parse_int(C, "--swap-points", a, &o.link.swap_points)) return CLI_USAGE; break;
    case O_ENCUM:
      if (!cli_parse_double_in(C, "--encounter-um", a, 0, 0, 1e6, ">= 0", &o.link.encounter_um)) return CLI_USAGE;
      break;
    case O_ENCCR:
      if (!cli_parse_double_in(C, "--encounter-circle-ratio", a, 0, 0, 1, "0 <= R <= 1",
                               &o.link.encounter_circle_ratio))
        return CLI_USAGE;
      break;
    case O_ENCLR:
      if (!cli_parse_double_in(C, "--encounter-line-ratio", a, 0, 0, 1, "0 <= R <= 1",
                               &o.link.encounter_line_ratio))
        return CLI_USAGE;
      break;
    case O_ENCR:
      if (!cli_parse_double_in(C, "--encounter-ratio", a, 0, 1, 1, "0 < R <= 1", &o.link.encounter_ratio))
        return CLI_USAGE;
      break;
    case O_RJOIN:
      if (!cli_parse_double_in(C, "--review-join-factor", a, 0, 0, 1e6, ">= 0", &o.link.review_join_factor))
        return CLI_USAGE;
      break;
    case O_RESTV:
      if (!cli_parse_double_in(C, "--rest-speed-um-per-ms", a, 0, 0, 1e6, ">= 0",
                               &o.link.rest_speed_um_per_ms))
        return CLI_USAGE;
      break;
    case O_ENCAPART:
      if (!cli_parse_int(C, "--encounter-apart", a, &o.link.encounter_apart)) return CLI_USAGE;
      if (o.link.encounter_apart < 0)
        return cli_message(C, CLI_USAGE, "--encounter-apart must be >= 0, not '%s'", a);
      break;
    case O_ENCPAD:
      if (!cli_parse_int(C, "--encounter-pad", a, &o.link.encounter_pad)) return CLI_USAGE;
      if (o.link.encounter_pad < 0) {
        cli_message(C, CLI_USAGE, "--encounter-pad must be >= 0, not '%s'", a);
        return CLI_USAGE;
      }
      break;
    case O_STITCHG: if (!cli_parse_double(C, "--stitch-gate-um", a, &o.link.stitch_gate_um)) return CLI_USAGE; break;
    case O_VIEWSRULE:
      if (!strcmp(a, "on")) o.views_rule = 1;
      else if (!strcmp(a, "off")) o.views_rule = 0;
      else return cli_message(C, CLI_USAGE, "--views-rule must be on or off, not '%s'", a);
      break;
    case O_THMIN: g.min = 1; if (!cli_parse_double(C, "--threshold-min", a, &o.peaks.absolute_min)) return CLI_USAGE; break;
    case O_THR: g.thr = 1; if (!cli_parse_double(C, "--threshold-rel", a, &o.peaks.relative)) return CLI_USAGE; break;
    case O_RXY:
      if (!cli_parse_double(C, "--radius-xy-um", a, &o.peaks.radius_xy_um)) return CLI_USAGE;
      g.rxy = 1;
      break;
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
    case O_MINPTS: g.minpts = 1; if (!cli_parse_int(C, "--min-points", a, &o.link.min_points)) return CLI_USAGE; break;
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
    case O_GCVG:
      if (!cli_parse_double_in(C, "--gcv-gamma", a, 1, 0, 10, "1..10", &o.smooth.gcv_gamma)) return CLI_USAGE;
      g.gcvg = 1;
      break;
    case O_SPORD:
      if (!cli_parse_int(C, "--spline-order", a, &o.smooth.spline_order)) return CLI_USAGE;
      if (o.smooth.spline_order != 2 && o.smooth.spline_order != 3) {
        cli_message(C, CLI_USAGE, "--spline-order must be 2 or 3, not '%s'", a);
        return CLI_USAGE;
      }
      g.spord = 1;
      break;
    case O_MFADE:
      if (!cli_parse_double_in(C, "--motion-fade-um-per-ms", a, 0, 1, 100, "> 0 and <= 100",
                               &o.smooth.motion_lead_fade_um_per_ms))
        return CLI_USAGE;
      g.fade = 1;
      break;
    case O_FSDP:
      if (!cli_parse_double_in(C, "--fit-sd-power", a, 0, 0, 4, "0..4", &o.smooth.fit_sd_power))
        return CLI_USAGE;
      g.fsdp = 1;
      break;
    case O_RES: o.resolution = 1; break;
    case O_MLEAD:
      if (!cli_parse_double_in(C, "--motion-lead-um", a, -100, 0, 100, "-100..100",
                               &o.smooth.motion_lead_um))
        return CLI_USAGE;
      g.mlead = 1;
      break;
    case O_MDELAY:
      if (!cli_parse_double_in(C, "--motion-delay-us", a, -1e6, 0, 1e6, "-1e6..1e6",
                               &o.smooth.motion_delay_us))
        return CLI_USAGE;
      g.mdelay = 1;
      break;
    case O_MAXOUT:
      if (!cli_parse_double(C, "--max-outlier-frac", a, &o.max_outlier_frac)) return CLI_USAGE;
      if (!(o.max_outlier_frac >= 0 && o.max_outlier_frac <= 1))
        return cli_message(C, CLI_USAGE, "--max-outlier-frac must be in 0..1");
      break;
    case O_PIECE:
      if (!cli_parse_int(C, "--piece-points", a, &o.piece_points)) return CLI_USAGE;
      if (o.piece_points < 0 || (o.piece_points > 0 && o.piece_points < 64))
        return cli_message(C, CLI_USAGE, "--piece-points must be 0 (off) or >= 64, not '%s'", a);
      break;
    default: return cli_bad_option(C, ch, argv);
    }
  }
  if (optind < argc) return cli_message(C, CLI_USAGE, "unexpected argument '%s'", argv[optind]);
  if (!o.calib || !o.events || !o.out)
    return cli_message(C, CLI_USAGE, "--calib, --events and --out are required (see --help)");
  if (!cli_check_recon_options(C, &rp)) return CLI_USAGE;
  cli_recon_planes(&rp, o.planes_um);
  const int rc = track_opts_derive(&o, &g);
  if (rc != CLI_OK) return rc;
  *out = o;
  return CLI_OK;
}
