/* cmd_track_auto.h — the bars of eventlfm track's automatic choices
 * (auto_judge in cmd_track.c: the blur, the window, its rate, the
 * integral, pulsed light, a slow stage's windows) and of its notes on
 * stderr, each with what it was measured on. Included by cmd_track.h. */
#ifndef ELFM_CMD_TRACK_AUTO_H
#define ELFM_CMD_TRACK_AUTO_H

/* Objects this slow are placed ahead of themselves by the ON time surface
 * and where they are by the integral (docs/tracker.md "Integral frames":
 * worm neurons move 0.1-0.34 um/ms; flow and stage beads 2.5-4, where the
 * integral loses them); static ones (blinking beads) gain nothing from it.
 * Up to 0.5, not 1.0 as before: beads in random flow at 0.5-1 mm/s
 * (flow_random seed 2, median track speed 0.85 um/ms) were found far less
 * with the integral (recall 0.570 -> 0.153; docs/tracker.md "Scenes
 * beyond the built-ins"). */
#define TRACK_HINT_MIN_SPEED_UM_PER_MS 0.03
#define TRACK_HINT_MAX_SPEED_UM_PER_MS 0.5
/* The notes for pulsed light (trigger edges in the file): --repr lin on the
 * exponential surface only when the tracks move, as blink_moving's at 2.5
 * um/ms, beads at rest (blink) doing better with the default; --start
 * each-trigger when they do not (README). */
#define TRACK_HINT_PULSED_MIN_SPEED_UM_PER_MS 0.5
/* Pulsed light (track_opts.start_auto, track_pulsed; the rules and what
 * they were measured on in cmd_track_pulsed.c). Moving objects' tracks
 * (TRACK_HINT_PULSED_MIN_SPEED_UM_PER_MS or more) get --repr lin too. */
#define TRACK_AUTO_TRIGGER_EDGES 4
#define TRACK_AUTO_PULSED_RATIO 3.0
#define TRACK_AUTO_PULSED_DIM_RATIO 1.5
#define TRACK_AUTO_PULSED_MIN_Z 3.0
#define TRACK_AUTO_PULSED_PEAKED 0.3
#define TRACK_AUTO_PULSED_PEAKED_OVER 10.0
/* Objects moving further than this between frames (median track speed x
 * frame interval) are tracked better with shorter windows. Flow at 2.5-8
 * mm/s (seeds 1-4 and 31-33), --dt-us 500 against 1000, by the median track
 * speed at 1 ms frames (with the 20 um path cap, short_path_um): at
 * 2.4-2.7 um per frame alpha -0.073..-0.011 (mean -0.054); at 3.11 / 3.21 /
 * 3.26 -0.049 / +0.021 / -0.049; at 3.49 / 3.59 / 3.72 +0.046 / +0.017 /
 * +0.012; at 4.48 / 4.69 / 4.98 +0.039 / +0.069 / +0.033. (Before the path
 * cap, at 5.0-5.3 um per frame: +0.21 to +0.40.) */
#define TRACK_HINT_MAX_STEP_UM 3.5
/* Peaks this close to the absolute threshold (median height below this x
 * it, over at least TRACK_WIDTH_MIN_PEAKS peaks) are dim objects', which
 * --blur-px 1 finds more of: --blur-px auto (the default) then starts the
 * run again with it, and with --blur-px 0 a note names it. Median peak
 * height over the threshold on time surfaces at the defaults, where the
 * blur gained: dim flow (a quarter of the flux) seeds 1-2 1.14 / 1.09,
 * three times the background 1.25 / 1.26, slow random flow (0.5-1 mm/s)
 * seeds 1-4 1.26-1.95, flow at 3/8 and 1/2 of the flux 1.26-1.36 and
 * 1.52-1.78, flow_random at 1/2 1.40-1.83, blink at 0.3 1.71-2.14; where it
 * did not (or lost): flow, stage, blink, blink_moving, flow_random, haze,
 * noise, 640 x 480 2.3-4.5, flow at 3/4 of the flux 2.49-2.87
 * (docs/tracker.md "Dim objects"). */
#define TRACK_HINT_DIM_FACTOR 2.15
/* ... but objects that crawl (worm neurons, 0.1-0.3 um/ms) look faint on a
 * time surface too, and there the integral is the setting: worm 0.5 s
 * seeds 1-4, alpha 0.362 on the time surface (the default), 0.874 with
 * --repr integral, 0.901 with --repr integral --dt-us 2000 (the README's
 * worm setting); the blur's jittery extra tracks only hid the slow-tracks
 * note (worm 150 ms seed 5: 0.43 -> 0.48 blurred; the median track speed
 * read 0.12 -> 0.56 um/ms). So where the judged peaks' tracks move slower
 * than this (and faster than TRACK_HINT_MIN_SPEED_UM_PER_MS: objects at
 * rest, blinking beads, read 0.01) the run starts again with the integral
 * instead (repr_auto), or keeps the time surface without the blur when
 * that was given. Those early speeds (short tracks, elfm_link_last_speed)
 * read high: at 1 ms frames worm 0.57-1.01 um/ms (seeds 1-32), a slow
 * stage (stage_accel's first 200 ms, 0.1-0.6 um/ms, without --motion
 * stage) 0.51; slow random flow (0.5-1 mm/s, where the integral loses:
 * recall 0.57 -> 0.15) 1.37-1.61 (seeds 1-16), flow and flow_random 3.3-4.3. 1.2 lies
 * between the two. */
#define TRACK_AUTO_CRAWL_UM_PER_MS 1.2
/* A recording of at least TRACK_AUTO_FEW_MIN_FRAMES windows whose time
 * surface gave fewer than TRACK_WIDTH_MIN_PEAKS peaks in all (too few to
 * judge) is run again with the integral too: objects so slow that few of
 * their pixels fire within one window build up in the integral, which
 * holds each pixel's brightness. A stage at 0.05 mm/s (13 beads, 0.43 M
 * events): 1 detection and no track on the time surface, alpha 0.267 and
 * recall 0.29 on the integral's 2 ms windows; noise alone (1.94 Mev/s, 300
 * ms) gives no detection either way. When the integral finds fewer
 * detections than the time surface did (flashing neurons), a third run
 * goes back to the time surface (docs/tracker.md "Too few peaks to judge"). */
#define TRACK_AUTO_FEW_MIN_FRAMES 200
/* The automatic window: the first run's 1 ms frames are halved when the
 * judged peaks' tracks move this far per frame or more (their median
 * early speed x the frame). Beyond the linker's reach between frames
 * (TRACK_HINT_MAX_STEP_UM) half-length windows gain: flow 100 ms seeds
 * 1-2, --dt-us 500 against 1000, at 5-6.5 mm/s alpha 0.751 -> 0.866, at
 * 8-10 mm/s 0.312 -> 0.795; flow_random 0.401 -> 0.559 and 0.288 -> 0.568;
 * at the usual 2.5-4 mm/s they lose (0.06 on seeds 1-4, "Fast beads").
 * Early speeds at 1 ms: the usual flow and flow_random (seeds 1-20 each),
 * 640 x 480, noise, haze, 40 and 60 beads 3.29-4.37 um/ms (blink_moving 2.5);
 * 4-5 mm/s 4.95-5.31, 5-6.5 mm/s 5.49-6.73, 8-10 mm/s 7.49-9.99 (seeds 1-4;
 * 9.99 is the speed histogram's top bin, TRACK_SPEED_BINS). */
#define TRACK_DT_AUTO_STEP_UM 5.0
/* Beads that turn beyond prediction: where the judged peaks' tracks (of 5
 * points or more, seen in the frame before) found them a median of this
 * or more from where they predicted, on a time surface with neither
 * --dt-us nor --stride-us given and no other new window chosen, the run
 * starts again with the same windows twice as often (--stride-us half the
 * window): a bead whose path turns at random leaves a 1 ms prediction by
 * its acceleration, and the linker then takes its neighbour. Counted on
 * peaks within TRACK_MISS_FOCUS_UM of focus (deep and faint beads' noise
 * would read as motion), judged when TRACK_WIDTH_MIN_PEAKS misses are in,
 * at most TRACK_MISS_MAX_FRAMES frames into the run. Judged misses: the
 * helical flow and its variants (40 / 60 beads, haze, noise, 0.5-2x the
 * flux) 0.71-1.77 um, at a quarter of the flux up to 1.85; random flow
 * (100 ms seeds 1-30, 1 s, 40 beads, 0.5-2x the flux) 1.81-3.63. Random
 * flow 100 ms seeds 1-30 alpha 0.625 -> 0.713, 1 s seeds 1-4 0.305 ->
 * 0.484; the helical flow at --stride-us 500 would lose (seeds 1-8 0.887
 * -> 0.860). docs/tracker.md "Frames twice as often for turning beads". */
#define TRACK_STRIDE_AUTO_MISS_UM 1.8
#define TRACK_MISS_MAX_FRAMES 100
#define TRACK_MISS_FOCUS_UM 25.0
/* Slow beads: where the judged peaks' tracks move at or above
 * TRACK_AUTO_CRAWL_UM_PER_MS (not cells) but below this (early speeds at 1
 * ms read ~1.5x the beads' own), on a time surface with neither --dt-us
 * nor --tau-us given, the run starts again with windows and tau of
 * TRACK_SLOW_BEADS_DT_US: a bead at 0.3-2 mm/s fires few of its pixels in
 * 1 ms. Flow at 0.3-0.6 / 0.6-1 / 1-1.5 / 1.5-2 / 2-2.5 mm/s (150 ms, 2-4
 * seeds; early speeds 1.07-1.43 / 1.33-1.53 / 1.61-1.83 / 2.01-2.31 /
 * 2.59-2.77), mean alpha at the defaults against --dt-us 1500 --tau-us
 * 1500: 0.517 / 0.731 / 0.770 / 0.802 / 0.837 against 0.760 / 0.797 /
 * 0.829 / 0.850 / 0.848 (2 ms: 0.763 / 0.790 / 0.853 / 0.848 / 0.843);
 * random flow at 1-2 mm/s (early 2.03-2.19) 0.548 against 0.588 (2 ms:
 * 0.497). At the usual 2.5-4 mm/s (early 3.7-4.2) 1.5 ms loses: flow
 * seeds 1-4 0.886 -> 0.838, flow_random 0.656 -> 0.445 (docs/tracker.md
 * "Windows for slow beads"). */
#define TRACK_SLOW_BEADS_MAX_UM_PER_MS 2.5
#define TRACK_SLOW_BEADS_DT_US 1500
#define TRACK_SLOW_BEADS_WINDOW_OVER_BLUR_UM_PER_MS 2.0
/* A slow stage's windows. A stage found by its tracks (TRACK_RIGID_*),
 * with neither --dt-us nor --tau-us given, so slow that it takes
 * TRACK_STAGE_SLOW_MIN_DT_US or more to move TRACK_STAGE_SLOW_STEP_UM,
 * starts again with windows (and the time surface's tau) that long, at
 * most TRACK_STAGE_SLOW_MAX_DT_US: a bead that moves 0.2 um in a window
 * fires few of its pixels in it (stage 0.2 mm/s, 200 ms seeds 1-2: recall
 * 0.54 / 0.68 at 1 ms). Stage seeds 1-2, alpha by --dt-us and --tau-us
 * both (1 / 1.5 / 2 / 3 / 5 / 8 / 12 ms): 0.1 mm/s 0.28 / 0.51 / 0.53 /
 * 0.55 / 0.60 / 0.77 / 0.79 (20 ms 0.74); 0.2 mm/s 0.59 / 0.60 / 0.60 /
 * 0.76 / 0.81 / 0.85 / 0.86; 0.5 mm/s 0.69 / 0.80 / 0.84 / 0.87 / 0.88 /
 * 0.84 / 0.71; 1 mm/s 0.86 / 0.89 / 0.89 / 0.89 / 0.87 / 0.71 / 0.57;
 * 1.5 mm/s 0.90 / 0.90 / 0.89 / 0.88 / 0.83; 2.5 mm/s 0.87 / 0.89 / 0.86 /
 * 0.85 (its speed 30-45 % off) / 0.59: best near 2.5 um per window, and
 * beyond ~4 um per window the linker loses the beads (docs/tracker.md
 * "Windows for a slow stage"). */
#define TRACK_STAGE_SLOW_STEP_UM 2.5
#define TRACK_STAGE_SLOW_MIN_DT_US 2000
#define TRACK_STAGE_SLOW_MAX_DT_US 10000
/* ... and a recording judged at its end (shorter than the judgement needs)
 * keeps at least this many windows: a track needs 5 points */
#define TRACK_STAGE_SLOW_MIN_WINDOWS 10
/* ... and a stage that speeds up while its windows are long (stage_accel:
 * 0.1 to 2.5 mm/s) would outrun them: that run watches its tracks, and
 * when their median speed moves them TRACK_STAGE_WATCH_STEP_UM or more per
 * window in TRACK_STAGE_WATCH_FRAMES windows in a row, the command starts
 * again with the first run's 1 ms windows (--motion stage, as before). */
#define TRACK_STAGE_WATCH_STEP_UM 4.0
#define TRACK_STAGE_WATCH_FRAMES 3
/* ... and in such a run a track is off the stage (cmd_track_stage.c) when
 * it moves along it at under this or over its inverse x the consensus
 * speed (otherwise 1/4 and 4x: an accelerating stage's tracks differ 2x) */
#define TRACK_STAGE_WATCH_ALONG_MIN 0.6
/* The note comes as soon as this many peaks say so (a long recording's user
 * need not wait for its end), else at the end; --blur-px auto judges the
 * same peaks (on flow, the first 10-40 frames), so that its second run
 * repeats little. */
#define TRACK_HINT_DIM_EARLY_PEAKS 200

#endif
