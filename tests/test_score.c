/* test_score.c — scoring against hand-computed answers (elfm_score.h).
 *
 * Scene: two objects, truth sampled every 100 us from t = 0 to 25 ms;
 * 20 frames, frame f at t_us = 1000 + 1000 f (so N = 20 truth points per
 * object and d(X, empty) = 4 * 20 = 80 per object, 160 in all).
 *   A: x = -10 + 0.001 t, y = -20, z = 5
 *   B: x =  10 - 0.001 t, y = +20, z = -10 + 0.0004 t
 * They are 40 um apart: no cross-talk through the 4 um gate.
 * (The scene is in score_test_util.h; bad input: test_score_input.c.)
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "check.h"
#include "elfm_tracker.h"
#include "score_test_util.h"

/* detections.csv with both objects exactly where they are in frames
 * f0..f1, except frames skip_a and skip_b (-1: none). */
static elfm_table *exact_detections(buf_t *b, int f0, int f1, int skip_a, int skip_b)
{
  bprintf(b, "frame,t_us,x_um,y_um,z_um\n");
  for (int f = f0; f <= f1; f++)
    for (int o = 0; o < 2; o++) {
      if (f == skip_a || f == skip_b) continue;
      double x, y, z;
      pos(o, frame_t(f), &x, &y, &z);
      bprintf(b, "%d,%.0f,%.17g,%.17g,%.17g\n", f, frame_t(f), x, y, z);
    }
  return parse(b, "detections.csv");
}

/* Truth where B is lit only during two 980 us pulses, [3010, 3990) and
 * [12010, 12990) us: each lights most of the window of frame 3 (t 4000)
 * or frame 12 (t 13000) but has ended by the frame's t_us, as a 1 ms LED
 * pulse does before a time surface's window end (SPEC §5). */
static double pulsed(int o, int t_us, double unused)
{
  (void)unused;
  return o == 0 || (t_us >= 3010 && t_us < 3990) || (t_us >= 12010 && t_us < 12990);
}
static elfm_table *make_truth_pulsed(void) { return make_truth_with(pulsed, 0); }

static elfm_score_result run(const elfm_table *truth, const elfm_table *tracks,
                             const elfm_table *dets, const elfm_score_options *o)
{
  elfm_score_result r;
  elfm_error err;
  elfm_error_clear(&err);
  elfm_score_options def;
  elfm_score_options_default(&def);
  CHECK_OK(elfm_score_tables(truth, tracks, dets, o ? o : &def, &r, &err), &err);
  return r;
}

int main(void)
{
  const double TOL = 1e-12;
  elfm_table *truth = make_truth(1e9);

  /* 1. Perfect tracks and detections. */
  {
    buf_t b = {0};
    bprintf(&b, "%s", TRACK_HEADER);
    add_track(&b, 1, 0, 0, NF - 1, 0, 0, 0, -1, -1);
    add_track(&b, 2, 1, 0, NF - 1, 0, 0, 0, -1, -1);
    elfm_table *tr = parse(&b, "tracks.csv");
    bprintf(&b, "frame,t_us,x_um,y_um,z_um,intensity\n");
    for (int f = 0; f < NF; f++)
      for (int o = 0; o < 2; o++) {
        double x, y, z;
        pos(o, frame_t(f), &x, &y, &z);
        bprintf(&b, "%d,%.0f,%.17g,%.17g,%.17g,1\n", f, frame_t(f), x, y, z);
      }
    elfm_table *de = parse(&b, "detections.csv");
    elfm_score_result r = run(truth, tr, de, NULL);
    CHECK_EQ_INT(r.n_frames, NF);
    CHECK_EQ_INT(r.n_truth_points, 2 * NF);
    CHECK_NEAR(r.alpha, 1.0, TOL);
    CHECK_NEAR(r.beta, 1.0, TOL);
    CHECK_NEAR(r.f1, 1.0, TOL);
    CHECK_NEAR(r.recall, 1.0, TOL);
    CHECK_NEAR(r.precision, 1.0, TOL);
    CHECK_NEAR(r.jaccard_tracks, 1.0, TOL);
    CHECK_NEAR(r.jaccard_detections, 1.0, TOL);
    CHECK_NEAR(r.rmse_x_um, 0.0, 1e-9);
    CHECK_NEAR(r.rmse_z_um, 0.0, 1e-9);
    CHECK_NEAR(r.alpha_detections, 1.0, TOL);
    CHECK_NEAR(r.alpha_identities, 1.0, TOL);
    CHECK_NEAR(r.identity_fragments, 0.0, TOL);
    CHECK_NEAR(r.identity_other_tracks, 0.0, TOL);
    CHECK_EQ_INT(r.detections_from_tracks, 0);
    CHECK_EQ_INT(r.n_paired_tracks, 2);
    /* detections only (no tracks): detection measures, no track measures */
    r = run(truth, NULL, de, NULL);
    CHECK_NEAR(r.f1, 1.0, TOL);
    CHECK_EQ_INT(r.has_tracks, 0);
    /* a detection missing at frame 5 and at frame 6 (no track rows either):
     * truth there still counts (frame times interpolated), recall 38/40 */
    elfm_table *de2 = exact_detections(&b, 0, NF - 1, 5, 6);
    r = run(truth, NULL, de2, NULL);
    CHECK_EQ_INT(r.n_truth_points, 2 * NF);
    CHECK_NEAR(r.recall, 36.0 / 40.0, TOL);
    CHECK_NEAR(r.precision, 1.0, TOL);
    CHECK_NEAR(r.f1, 2.0 * 36.0 / (40.0 + 36.0), TOL);
    CHECK_NEAR(r.alpha_detections, 36.0 / 40.0, TOL); /* 4 misses at eps each */
    elfm_table_free(de2);
    /* nothing detected in the first 3 and the last 2 frames: without the
     * run's frame count those frames are unknown (16 of 20 scored); with
     * n_frames_hint = 20 they count as missed, times extrapolated */
    elfm_table *de3 = exact_detections(&b, 3, NF - 3, -1, -1);
    r = run(truth, NULL, de3, NULL);
    CHECK_EQ_INT(r.n_frames, 15);
    CHECK_NEAR(r.recall, 1.0, TOL);
    elfm_score_options oh;
    elfm_score_options_default(&oh);
    oh.n_frames_hint = NF;
    r = run(truth, NULL, de3, &oh);
    CHECK_EQ_INT(r.n_frames, NF);
    CHECK_EQ_INT(r.n_truth_points, 2 * NF);
    CHECK_NEAR(r.recall, 30.0 / 40.0, TOL);
    /* a hint beyond the truth's time range adds no truth points */
    oh.n_frames_hint = 1000;
    r = run(truth, NULL, de3, &oh);
    CHECK_EQ_INT(r.n_truth_points, 2 * 25); /* truth ends at 25 ms: frames 0..24 */
    elfm_table_free(de3);
    elfm_table_free(tr);
    elfm_table_free(de);
  }

  /* 1b. Frames beyond the truth's last sample (25 ms) are not scored: tracks
   * and detections run on to frame 29 (t 30 ms), where the truth says
   * nothing. Frames 25..29 are left out (5), and the run is perfect; scored,
   * their 10 detections and 10 track points would have been false. The
   * same with a frame count hint. */
  {
    buf_t b = {0};
    bprintf(&b, "%s", TRACK_HEADER);
    add_track(&b, 1, 0, 0, 29, 0, 0, 0, -1, -1);
    add_track(&b, 2, 1, 0, 29, 0, 0, 0, -1, -1);
    elfm_table *tr = parse(&b, "tracks.csv");
    elfm_table *de = exact_detections(&b, 0, 29, -1, -1);
    elfm_score_result r = run(truth, tr, de, NULL);
    CHECK_EQ_INT(r.n_frames, 25);
    CHECK_EQ_INT(r.n_frames_unscored, 5);
    CHECK_EQ_INT(r.n_truth_points, 50);
    CHECK_EQ_INT(r.n_detections, 50);
    CHECK_NEAR(r.precision, 1.0, TOL);
    CHECK_NEAR(r.f1, 1.0, TOL);
    CHECK_NEAR(r.alpha, 1.0, TOL);
    CHECK_NEAR(r.beta, 1.0, TOL);
    CHECK_NEAR(r.jaccard_detections, 1.0, TOL);
    elfm_score_options oh;
    elfm_score_options_default(&oh);
    oh.n_frames_hint = 40;
    r = run(truth, tr, de, &oh);
    CHECK_EQ_INT(r.n_frames_unscored, 15);
    CHECK_NEAR(r.f1, 1.0, TOL);
    CHECK_NEAR(r.alpha, 1.0, TOL);
    /* a track whose real points all lie beyond the truth is no candidate */
    bprintf(&b, "%s", TRACK_HEADER);
    add_track(&b, 1, 0, 0, NF - 1, 0, 0, 0, -1, -1);
    add_track(&b, 2, 1, 0, NF - 1, 0, 0, 0, -1, -1);
    add_track(&b, 3, 1, 26, 29, 30, 0, 0, -1, -1);
    elfm_table *tr2 = parse(&b, "tracks.csv");
    r = run(truth, tr2, NULL, NULL);
    CHECK_EQ_INT(r.n_candidate_tracks, 2);
    CHECK_EQ_INT(r.n_spurious_tracks, 0);
    elfm_table_free(tr2);
    elfm_table_free(tr);
    elfm_table_free(de);
  }

  /* 2. Constant 1 um offset in x: d = 1 on every frame -> alpha = 1 - 1/4. */
  {
    buf_t b = {0};
    bprintf(&b, "%s", TRACK_HEADER);
    add_track(&b, 1, 0, 0, NF - 1, 1.0, 0, 0, -1, -1);
    add_track(&b, 2, 1, 0, NF - 1, 1.0, 0, 0, -1, -1);
    elfm_table *tr = parse(&b, "tracks.csv");
    elfm_score_result r = run(truth, tr, NULL, NULL);
    CHECK_NEAR(r.alpha, 0.75, TOL);
    CHECK_NEAR(r.beta, 0.75, TOL); /* (160 - 40) / 160 */
    CHECK_NEAR(r.rmse_tracks_um, 1.0, 1e-9);
    /* detections from the raw points: all within the gate */
    CHECK_EQ_INT(r.detections_from_tracks, 1);
    CHECK_NEAR(r.f1, 1.0, TOL);
    CHECK_NEAR(r.rmse_x_um, 1.0, 1e-9);
    CHECK_NEAR(r.rmse_y_um, 0.0, 1e-9);
    /* the detections themselves are 1 um off: the same 0.75 */
    CHECK_NEAR(r.alpha_detections, 0.75, TOL);
    elfm_table_free(tr);
  }

  /* 3. Anisotropic z: dz = 4 um counts as d = 1 (kz = 4) -> alpha 0.75;
   * dz = 15.9 is inside the gate (d = 3.975), dz = 16 is not (d = eps). */
  {
    buf_t b = {0};
    bprintf(&b, "%s", TRACK_HEADER);
    add_track(&b, 1, 0, 0, NF - 1, 0, 0, 4.0, -1, -1);
    add_track(&b, 2, 1, 0, NF - 1, 0, 0, 4.0, -1, -1);
    elfm_table *tr = parse(&b, "tracks.csv");
    elfm_score_result r = run(truth, tr, NULL, NULL);
    CHECK_NEAR(r.alpha, 0.75, TOL);
    CHECK_NEAR(r.rmse_z_um, 4.0, 1e-9);
    CHECK_NEAR(r.rmse_x_um, 0.0, 1e-9);
    elfm_table_free(tr);
    bprintf(&b, "%s", TRACK_HEADER);
    add_track(&b, 1, 0, 0, NF - 1, 0, 0, 15.9, -1, -1);
    add_track(&b, 2, 1, 0, NF - 1, 0, 0, 16.0, -1, -1);
    tr = parse(&b, "tracks.csv");
    r = run(truth, tr, NULL, NULL);
    /* A: 20 * 3.975; B: unmatched -> its track is spurious and B missed */
    CHECK_NEAR(r.alpha, 1.0 - (20 * 3.975 + 80) / 160.0, 1e-9);
    CHECK_EQ_INT(r.n_paired_tracks, 1);
    CHECK_EQ_INT(r.n_spurious_tracks, 1);
    CHECK_NEAR(r.recall, 0.5, TOL);
    /* the same 16 um offset in x instead is far outside: x is not divided */
    elfm_table_free(tr);
  }

  /* 4. A missing track: only A is tracked. */
  {
    buf_t b = {0};
    bprintf(&b, "%s", TRACK_HEADER);
    add_track(&b, 1, 0, 0, NF - 1, 0, 0, 0, -1, -1);
    elfm_table *tr = parse(&b, "tracks.csv");
    elfm_score_result r = run(truth, tr, NULL, NULL);
    CHECK_NEAR(r.alpha, 0.5, TOL);
    CHECK_NEAR(r.beta, 0.5, TOL);
    CHECK_NEAR(r.jaccard_tracks, 0.5, TOL);
    CHECK_NEAR(r.jaccard_detections, 0.5, TOL);
    CHECK_EQ_INT(r.n_missed_tracks, 1);
    CHECK_NEAR(r.recall, 0.5, TOL);
    CHECK_NEAR(r.precision, 1.0, TOL);
    elfm_table_free(tr);
  }

  /* 5. A spurious track (10 frames, far from both): beta drops, alpha not.
   * beta = 160 / (160 + 4 * 10) = 0.8. */
  {
    buf_t b = {0};
    bprintf(&b, "%s", TRACK_HEADER);
    add_track(&b, 1, 0, 0, NF - 1, 0, 0, 0, -1, -1);
    add_track(&b, 2, 1, 0, NF - 1, 0, 0, 0, -1, -1);
    add_track(&b, 3, 0, 5, 14, 0, 30, 0, -1, -1); /* A shifted 30 um in y */
    elfm_table *tr = parse(&b, "tracks.csv");
    elfm_score_result r = run(truth, tr, NULL, NULL);
    CHECK_NEAR(r.alpha, 1.0, TOL);
    CHECK_NEAR(r.beta, 0.8, TOL);
    CHECK_NEAR(r.jaccard_tracks, 2.0 / 3.0, TOL);
    CHECK_NEAR(r.jaccard_detections, 40.0 / 50.0, TOL);
    CHECK_EQ_INT(r.n_spurious_tracks, 1);
    CHECK_NEAR(r.recall, 1.0, TOL);
    CHECK_NEAR(r.precision, 40.0 / 50.0, TOL);
    elfm_table_free(tr);
  }

  /* 6. A split track: A as two halves (frames 0-9, 10-19). One half pairs:
   * d(A, half) = 4 * (20 + 10 - 10) - 4 * 10 = 40; alpha = 1 - 40/160,
   * beta = (160 - 40) / (160 + 40) = 0.6. */
  {
    buf_t b = {0};
    bprintf(&b, "%s", TRACK_HEADER);
    add_track(&b, 1, 0, 0, 9, 0, 0, 0, -1, -1);
    add_track(&b, 4, 0, 10, NF - 1, 0, 0, 0, -1, -1);
    add_track(&b, 2, 1, 0, NF - 1, 0, 0, 0, -1, -1);
    elfm_table *tr = parse(&b, "tracks.csv");
    elfm_score_result r = run(truth, tr, NULL, NULL);
    CHECK_NEAR(r.alpha, 0.75, TOL);
    CHECK_NEAR(r.beta, 0.6, TOL);
    CHECK_NEAR(r.jaccard_tracks, 2.0 / 3.0, TOL);
    CHECK_NEAR(r.f1, 1.0, TOL); /* detection-wise nothing is wrong */
    /* the split is the linker's loss, not the detector's */
    CHECK_NEAR(r.alpha_detections, 1.0, TOL);
    /* with identities mended the halves are one track again; A's second
     * half (10 of the 40 truth points) was a fragment */
    CHECK_NEAR(r.alpha_identities, 1.0, TOL);
    CHECK_NEAR(r.identity_fragments, 10.0 / 40.0, TOL);
    CHECK_NEAR(r.identity_other_tracks, 0.0, TOL);
    elfm_table_free(tr);
  }

  /* 6b. Swapped tracks: track 1 follows A for frames 0-11 and then B, track
   * 2 the other way round. A pairs with track 1: d = 8 x 4 (frames 12-19,
   * where track 1 is on B, 40 um away: min(d, eps) = eps) = 32, likewise B
   * with track 2: alpha = 1 - 64/160 = 0.6. Every point is on an
   * object, exactly: mended, alpha 1; each object has 8 of its 20 points in
   * the track that mostly follows the other (16 of 40). The identity
   * diagnostics do not change the ISBI measures. */
  {
    buf_t b = {0};
    bprintf(&b, "%s", TRACK_HEADER);
    add_track(&b, 1, 0, 0, 11, 0, 0, 0, -1, -1);
    add_track(&b, 1, 1, 12, NF - 1, 0, 0, 0, -1, -1);
    add_track(&b, 2, 1, 0, 11, 0, 0, 0, -1, -1);
    add_track(&b, 2, 0, 12, NF - 1, 0, 0, 0, -1, -1);
    elfm_table *tr = parse(&b, "tracks.csv");
    elfm_score_result r = run(truth, tr, NULL, NULL);
    CHECK_NEAR(r.alpha, 0.6, TOL);
    CHECK_EQ_INT(r.n_paired_tracks, 2);
    CHECK_NEAR(r.alpha_identities, 1.0, TOL);
    CHECK_NEAR(r.identity_fragments, 0.0, TOL);
    CHECK_NEAR(r.identity_other_tracks, 16.0 / 40.0, TOL);
    elfm_table_free(tr);
  }

  /* 7. Gap-closing rows (raw empty, position junk) are left out: A's frames
   * 5-9 are virtual: 5 frames at eps -> alpha = 1 - 20/160 = 0.875, and no
   * spurious detections from the junk. */
  {
    buf_t b = {0};
    bprintf(&b, "%s", TRACK_HEADER);
    add_track(&b, 1, 0, 0, NF - 1, 0, 0, 0, 5, 9);
    add_track(&b, 2, 1, 0, NF - 1, 0, 0, 0, -1, -1);
    elfm_table *tr = parse(&b, "tracks.csv");
    elfm_score_result r = run(truth, tr, NULL, NULL);
    CHECK_NEAR(r.alpha, 0.875, TOL);
    CHECK_NEAR(r.beta, 0.875, TOL);
    CHECK_NEAR(r.precision, 1.0, TOL);
    CHECK_NEAR(r.recall, 35.0 / 40.0, TOL);
    CHECK_EQ_INT(r.n_track_fp, 0);
    elfm_table_free(tr);
  }

  /* 8. Blinking: B dark from 10.5 ms on (frames 10..19 dark, frame 9 at
   * 10 ms bright). A track of B over frames 0-9 is then perfect; B's
   * tracked frames 10-19 would be spurious detections. */
  {
    elfm_table *truth_b = make_truth(10500);
    buf_t b = {0};
    bprintf(&b, "%s", TRACK_HEADER);
    add_track(&b, 1, 0, 0, NF - 1, 0, 0, 0, -1, -1);
    add_track(&b, 2, 1, 0, 9, 0, 0, 0, -1, -1);
    elfm_table *tr = parse(&b, "tracks.csv");
    elfm_score_result r = run(truth_b, tr, NULL, NULL);
    CHECK_EQ_INT(r.n_truth_points, 30);
    /* frame 10 (t 11 ms): B lit at 10.1-10.4 ms, dark at 11 ms */
    CHECK_EQ_INT(r.n_truth_lit_then_dark, 1);
    CHECK_NEAR(r.alpha, 1.0, TOL);
    CHECK_NEAR(r.beta, 1.0, TOL);
    elfm_table_free(tr);
    bprintf(&b, "%s", TRACK_HEADER);
    add_track(&b, 1, 0, 0, NF - 1, 0, 0, 0, -1, -1);
    add_track(&b, 2, 1, 0, NF - 1, 0, 0, 0, -1, -1);
    tr = parse(&b, "tracks.csv");
    r = run(truth_b, tr, NULL, NULL);
    /* d(B, Y) = 4 * (10 + 20 - 10) - 4 * 10 = 40 over d_empty 120 */
    CHECK_NEAR(r.alpha, 1.0 - 40.0 / 120.0, TOL);
    CHECK_NEAR(r.precision, 30.0 / 40.0, TOL);
    elfm_table_free(tr);
    elfm_table_free(truth_b);
  }

  /* 9. Volume bounds: with x within +-8 um, A (x = -9..10) and B
   * (x = 9..-10) count only on frames with |x| <= 8; an untracked part
   * outside does not count as missed. */
  {
    buf_t b = {0};
    bprintf(&b, "%s", TRACK_HEADER);
    add_track(&b, 1, 0, 0, NF - 1, 0, 0, 0, -1, -1);
    add_track(&b, 2, 1, 0, NF - 1, 0, 0, 0, -1, -1);
    elfm_table *tr = parse(&b, "tracks.csv");
    elfm_score_options o;
    elfm_score_options_default(&o);
    elfm_calib cal;
    memset(&cal, 0, sizeof cal);
    cal.view_w_px = 17; /* (17 - 1) / 2 * 1.0 = 8 um */
    cal.view_h_px = 101;
    cal.um_per_px = 1.0;
    cal.z_min_um = -100;
    cal.z_max_um = 100;
    elfm_score_options_set_calib(&o, &cal);
    CHECK_NEAR(o.x_half_um, 8.0, TOL);
    elfm_score_result r = run(truth, tr, NULL, &o);
    /* A: x = -9 + f, |x| <= 8 for f = 1..17 -> 17 points; B: x = 9 - f, likewise */
    CHECK_EQ_INT(r.n_truth_points, 34);
    CHECK_NEAR(r.recall, 1.0, TOL);
    CHECK_NEAR(r.precision, 34.0 / 40.0, TOL);
    elfm_table_free(tr);
  }

  /* 10. Stage velocity: tracks report vx = 0.001 um/ms. */
  {
    buf_t b = {0};
    bprintf(&b, "%s", TRACK_HEADER);
    add_track(&b, 1, 0, 0, NF - 1, 0, 0, 0, -1, -1);
    elfm_table *tr = parse(&b, "tracks.csv");
    elfm_score_options o;
    elfm_score_options_default(&o);
    o.have_stage = 1;
    o.stage_v_um_per_ms[0] = 0.002;
    elfm_score_result r = run(truth, tr, NULL, &o);
    CHECK_EQ_INT(r.has_stage, 1);
    CHECK_NEAR(r.mean_v_um_per_ms[0], 0.001, 1e-15);
    CHECK_NEAR(r.stage_rel_error, 0.5, 1e-12);
    elfm_table_free(tr);
  }

  /* (11, bad input, is test_score_input.c.) */

  /* 12. Many objects in a crowded frame: the scorer must not confuse
   * neighbours 3 um apart (inside the gate of each other). Grid of 10 x 10
   * objects at 3 um spacing, detections exactly on truth -> F1 = 1. */
  {
    buf_t b = {0};
    bprintf(&b, "id,t_us,x_um,y_um,z_um,brightness\n");
    for (int t = 0; t <= 3000; t += 1000)
      for (int k = 0; k < 100; k++)
        bprintf(&b, "%d,%d,%g,%g,0,1\n", k, t, 3.0 * (k % 10), 3.0 * (k / 10));
    elfm_table *gt = parse(&b, "truth.csv");
    bprintf(&b, "frame,t_us,x_um,y_um,z_um\n");
    for (int f = 0; f < 3; f++)
      for (int k = 99; k >= 0; k--) /* reversed order on purpose */
        bprintf(&b, "%d,%d,%g,%g,0.4\n", f, 1000 * (f + 1), 3.0 * (k % 10) + 1.4, 3.0 * (k / 10));
    elfm_table *de = parse(&b, "detections.csv");
    elfm_score_result r = run(gt, NULL, de, NULL);
    CHECK_NEAR(r.f1, 1.0, TOL);
    CHECK_NEAR(r.rmse_x_um, 1.4, 1e-9); /* each matched to its own, not the neighbour 1.6 away */
    CHECK_NEAR(r.rmse_z_um, 0.4, 1e-9);
    elfm_table_free(gt);
    elfm_table_free(de);
  }

  /* 13. Sparse ids (range far beyond the row count: the qsort grouping
   * path), interleaved rows, and track ids likewise. */
  {
    buf_t b = {0};
    bprintf(&b, "id,t_us,x_um,y_um,z_um,brightness\n");
    for (int t = 0; t <= 5000; t += 500) {
      bprintf(&b, "1000000000000,%d,1,1,0,1\n", t);
      bprintf(&b, "-3,%d,20,20,0,1\n", t);
    }
    elfm_table *gt = parse(&b, "truth.csv");
    bprintf(&b, "track_id,frame,t_us,x_um,y_um,z_um,raw_x_um,raw_y_um,raw_z_um\n");
    for (int f = 0; f < 4; f++) {
      bprintf(&b, "99999999999,%d,%d,1.5,1,0,1.5,1,0\n", f, 1000 * (f + 1));
      bprintf(&b, "-7,%d,%d,20,20,0,20,20,0\n", f, 1000 * (f + 1));
    }
    elfm_table *tk = parse(&b, "tracks.csv");
    elfm_score_result r = run(gt, tk, NULL, NULL);
    CHECK_NEAR(r.f1, 1.0, TOL);
    CHECK_NEAR(r.alpha, 1.0 - 4 * 0.5 / 32.0, TOL);
    CHECK_EQ_INT(r.n_paired_tracks, 2);
    elfm_table_free(gt);
    elfm_table_free(tk);
  }

  /* 14. A run that found nothing (header-only tracks.csv): a total miss,
   * not an undefined score. */
  {
    buf_t b = {0};
    bprintf(&b, "%s", TRACK_HEADER);
    elfm_table *tk = parse(&b, "tracks.csv");
    elfm_score_result r = run(truth, tk, NULL, NULL);
    CHECK_NEAR(r.f1, 0.0, TOL);
    CHECK_NEAR(r.recall, 0.0, TOL);
    CHECK_NEAR(r.alpha, 0.0, TOL);
    CHECK_NEAR(r.beta, 0.0, TOL);
    CHECK_NEAR(r.alpha_detections, 0.0, TOL);
    CHECK_EQ_INT(r.n_missed_tracks, 2);
    CHECK(isnan(r.precision));
    elfm_table_free(tk);
  }

  /* Blinking: B seen at frames 3 and 12 only, one track linked across the
   * dark gap (frames 4..11 gap-closed, raw empty). With the window rule the
   * pulses count at the frames whose window they lit, and frames where B is
   * dark and the track only virtual cost nothing: a perfect run scores 1.
   * (Before: every frame was dark at t_us, or the 10-frame span cost 40 >
   * d(X, empty) = 8, so B's track paired with nothing.) */
  {
    elfm_table *pulsed = make_truth_pulsed();
    buf_t b = {0};
    bprintf(&b, "%s", TRACK_HEADER);
    add_track(&b, 1, 0, 0, NF - 1, 0, 0, 0, -1, -1);
    add_track(&b, 2, 1, 3, 12, 0, 0, 0, 4, 11);
    elfm_table *tr = parse(&b, "tracks.csv");
    elfm_score_options o;
    elfm_score_options_default(&o);
    o.window_us = 1000;
    elfm_score_result r = run(pulsed, tr, NULL, &o);
    CHECK_EQ_INT(r.n_truth_points, 22);
    CHECK_EQ_INT(r.n_true_positives, 22);
    CHECK_EQ_INT(r.n_truth_tracks, 2);
    CHECK_EQ_INT(r.n_paired_tracks, 2);
    CHECK_NEAR(r.alpha, 1.0, TOL);
    CHECK_NEAR(r.beta, 1.0, TOL);
    /* The literal rule (window 0): B is dark at every frame time, so only A
     * counts and B's two real points form a spurious track: beta = 80 / 88. */
    o.window_us = 0;
    r = run(pulsed, tr, NULL, &o);
    CHECK_EQ_INT(r.n_truth_tracks, 1);
    CHECK_EQ_INT(r.n_spurious_tracks, 1);
    CHECK_NEAR(r.alpha, 1.0, TOL);
    CHECK_NEAR(r.beta, 80.0 / 88.0, TOL);
    /* ... and counts the two frames B's pulses lit as lit, then dark; the
     * window rule counts none (it counted them as B's points above) */
    CHECK_EQ_INT(r.n_truth_lit_then_dark, 2);
    o.window_us = 1000;
    CHECK_EQ_INT(run(pulsed, tr, NULL, &o).n_truth_lit_then_dark, 0);
    /* Half the window must be lit: a 1900 us window holds 19 samples of
     * which 9 are lit, so B does not count at all ("any light in the
     * window" would count it). */
    o.window_us = 1900;
    r = run(pulsed, tr, NULL, &o);
    CHECK_EQ_INT(r.n_truth_points, 20);
    elfm_table_free(tr);
    elfm_table_free(pulsed);
  }

  /* MOTION BIAS: four objects on straight lines at 1, 2, 3 and 4 um/ms in
   * four directions; every detection lies lead - delay x speed ahead along
   * its motion (0.9 um, 350 us). The regression gives both back. A fifth
   * object moving only in z (0.3 um/ms laterally: below 0.5) is left out. */
  {
    buf_t b = {0};
    bprintf(&b, "id,t_us,x_um,y_um,z_um,brightness\n");
    const double dir[5][2] = {{1, 0}, {0, 1}, {-0.6, 0.8}, {0.8, -0.6}, {1, 0}};
    const double sp[5] = {1, 2, 3, 4, 0.3};
    for (int t = 0; t <= 25000; t += 100)
      for (int k = 0; k < 5; k++)
        bprintf(&b, "%d,%d,%.17g,%.17g,%.17g,1\n", k, t, -30 + 15 * k + sp[k] * dir[k][0] * t * 1e-3,
                -30 + 12 * k + sp[k] * dir[k][1] * t * 1e-3, k == 4 ? -20 + 2.0 * t * 1e-3 : 3.0 * k);
    elfm_table *tm = parse(&b, "truth.csv");
    bprintf(&b, "frame,t_us,x_um,y_um,z_um\n");
    for (int f = 0; f < NF; f++)
      for (int k = 0; k < 5; k++) {
        double t = frame_t(f), e = 0.9 - 0.35 * sp[k];
        bprintf(&b, "%d,%.0f,%.17g,%.17g,%.17g\n", f, t,
                -30 + 15 * k + sp[k] * dir[k][0] * t * 1e-3 + e * dir[k][0],
                -30 + 12 * k + sp[k] * dir[k][1] * t * 1e-3 + e * dir[k][1],
                k == 4 ? -20 + 2.0 * t * 1e-3 : 3.0 * k);
      }
    elfm_table *dm = parse(&b, "detections.csv");
    elfm_score_result r = run(tm, NULL, dm, NULL);
    CHECK_EQ_INT(r.n_true_positives, 5 * NF);
    CHECK_EQ_INT(r.n_motion_points, 4 * NF);
    CHECK_NEAR(r.motion_lead_um, 0.9, 1e-6);
    CHECK_NEAR(r.motion_delay_us, 350, 1e-3);
    CHECK_NEAR(r.motion_along_mean_um, 0.9 - 0.35 * 2.5, 1e-6);
    CHECK(isnan(r.rmse_raw_x_um) && isnan(r.rmse_raw_z_um)); /* no raw columns */
    elfm_table_free(dm);

    /* track's detections.csv: x/y_um moved back onto the objects, the
     * measured positions in raw_x_um / raw_y_um. The RMSE is of the moved
     * positions (0 here), the regression of the raw ones (as above). */
    bprintf(&b, "frame,t_us,x_um,y_um,z_um,raw_x_um,raw_y_um,raw_z_um\n");
    for (int f = 0; f < NF; f++)
      for (int k = 0; k < 5; k++) {
        double t = frame_t(f), e = 0.9 - 0.35 * sp[k];
        double x = -30 + 15 * k + sp[k] * dir[k][0] * t * 1e-3,
               y = -30 + 12 * k + sp[k] * dir[k][1] * t * 1e-3,
               z = k == 4 ? -20 + 2.0 * t * 1e-3 : 3.0 * k;
        bprintf(&b, "%d,%.0f,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g\n", f, t, x, y, z,
                x + e * dir[k][0], y + e * dir[k][1], z);
      }
    elfm_table *dr = parse(&b, "detections.csv");
    r = run(tm, NULL, dr, NULL);
    CHECK_EQ_INT(r.n_true_positives, 5 * NF);
    CHECK_NEAR(r.rmse_x_um, 0, 1e-9);
    CHECK_NEAR(r.rmse_y_um, 0, 1e-9);
    CHECK_NEAR(r.motion_lead_um, 0.9, 1e-6);
    CHECK_NEAR(r.motion_delay_us, 350, 1e-3);
    /* ... and the same pairs' RMSE as measured: the offsets e dir */
    {
      double ex2 = 0, ey2 = 0;
      for (int k = 0; k < 5; k++) {
        const double e = 0.9 - 0.35 * sp[k];
        ex2 += e * dir[k][0] * e * dir[k][0] / 5;
        ey2 += e * dir[k][1] * e * dir[k][1] / 5;
      }
      CHECK_NEAR(r.rmse_raw_x_um, sqrt(ex2), 1e-9);
      CHECK_NEAR(r.rmse_raw_y_um, sqrt(ey2), 1e-9);
      CHECK_NEAR(r.rmse_raw_z_um, 0, 1e-9);
    }
    elfm_table_free(dr);
    /* raw columns but not all three, or a raw value missing: errors
     * naming the file (and the line) */
    {
      elfm_error e1;
      elfm_error_clear(&e1);
      elfm_score_options od;
      elfm_score_options_default(&od);
      bprintf(&b, "frame,t_us,x_um,y_um,z_um,raw_x_um\n0,%.0f,1,1,1,1\n", frame_t(0));
      elfm_table *d2 = parse(&b, "detections.csv");
      CHECK(elfm_score_tables(tm, NULL, d2, &od, &r, &e1) == ELFM_ERR_FORMAT);
      CHECK_MSG(strstr(e1.message, "all three") != NULL && strstr(e1.file, "detections.csv"), "%s: %s",
                e1.file, e1.message);
      elfm_table_free(d2);
      elfm_error_clear(&e1);
      bprintf(&b, "frame,t_us,x_um,y_um,z_um,raw_x_um,raw_y_um,raw_z_um\n0,%.0f,1,1,1,1,1,1\n"
              "1,%.0f,1,1,1,,1,1\n", frame_t(0), frame_t(1));
      d2 = parse(&b, "detections.csv");
      CHECK(elfm_score_tables(tm, NULL, d2, &od, &r, &e1) == ELFM_ERR_FORMAT);
      CHECK_MSG(strstr(e1.message, "raw_x_um") != NULL && e1.line == 3, "%s (line %lld)", e1.message,
                (long long)e1.line);
      elfm_table_free(d2);
    }

    /* One speed (every object at 2 um/ms): no regression, the mean only. */
    bprintf(&b, "frame,t_us,x_um,y_um,z_um\n");
    for (int f = 0; f < NF; f++) {
      double t = frame_t(f);
      bprintf(&b, "%d,%.0f,%.17g,%.17g,3\n", f, t, -15.0 + 0.4, -18 + 2 * t * 1e-3 + 0.25);
    }
    elfm_table *d1 = parse(&b, "detections.csv");
    r = run(tm, NULL, d1, NULL);
    CHECK_EQ_INT(r.n_motion_points, NF);
    CHECK_NEAR(r.motion_along_mean_um, 0.25, 1e-6);
    CHECK(isnan(r.motion_lead_um) && isnan(r.motion_delay_us));
    CHECK_NEAR(r.motion_speed_sd_um_per_ms, 0, 1e-6);
    elfm_table_free(d1);
    elfm_table_free(tm);
  }

  /* MOTION BIAS with the views' model: detections off by exactly the bias
   * elfm_motion_bias gives a 5 x 5 array of views (lead 1.2 um, delay 430
   * us), for four objects moving laterally at 1-4 um/ms and three climbing
   * steeply in z (3 um/ms) while moving 1-2 um/ms laterally. The steep ones'
   * views see images moving every way, whose leads mostly cancel in the
   * lateral fit: with the views' disparities the regression gives lead and
   * delay back, while the lateral model pools them with the others and
   * finds both too small (1.00 um and 370 us; as on flow: docs/tracker.md). */
  {
    enum { NO = 7 };
    const double v[NO][3] = {{1, 0, 0},    {0, 2, 0},     {-1.8, 2.4, 0}, {3.2, -2.4, 0},
                             {1, 0, 3},    {0, -1.5, -3}, {1.2, 1.6, 3}};
    elfm_smooth_options mb;
    elfm_smooth_options_default(&mb);
    mb.motion_lead_um = 1.2;
    mb.motion_delay_us = 430;
    mb.motion_n_views = 25;
    for (int k = 0; k < 25; k++) {
      mb.motion_view_g[k][0] = 0.15 * (k % 5 - 2);
      mb.motion_view_g[k][1] = 0.15 * (k / 5 - 2);
    }
    buf_t b = {0};
    bprintf(&b, "id,t_us,x_um,y_um,z_um,brightness\n");
    for (int t = 0; t <= 25000; t += 100)
      for (int k = 0; k < NO; k++)
        bprintf(&b, "%d,%d,%.17g,%.17g,%.17g,1\n", k, t, -40 + 12 * k + v[k][0] * t * 1e-3,
                -40 + 11 * k + v[k][1] * t * 1e-3, -30 + 8 * k + v[k][2] * t * 1e-3);
    elfm_table *tm = parse(&b, "truth.csv");
    bprintf(&b, "frame,t_us,x_um,y_um,z_um\n");
    for (int f = 0; f < NF; f++)
      for (int k = 0; k < NO; k++) {
        double t = frame_t(f), e[3];
        elfm_motion_bias(&mb, v[k], e);
        bprintf(&b, "%d,%.0f,%.17g,%.17g,%.17g\n", f, t, -40 + 12 * k + v[k][0] * t * 1e-3 + e[0],
                -40 + 11 * k + v[k][1] * t * 1e-3 + e[1], -30 + 8 * k + v[k][2] * t * 1e-3 + e[2]);
      }
    elfm_table *dm = parse(&b, "detections.csv");
    elfm_score_options o;
    elfm_score_options_default(&o);
    o.motion_n_views = 25;
    memcpy(o.motion_view_g, mb.motion_view_g, sizeof o.motion_view_g);
    elfm_score_result r = run(tm, NULL, dm, &o);
    CHECK_EQ_INT(r.n_true_positives, NO * NF);
    CHECK_EQ_INT(r.n_motion_points, NO * NF);
    CHECK_NEAR(r.motion_lead_um, 1.2, 1e-6);
    CHECK_NEAR(r.motion_delay_us, 430, 1e-3);
    /* the lateral model on the same detections */
    o.motion_n_views = 0;
    r = run(tm, NULL, dm, &o);
    CHECK(r.motion_lead_um < 1.1 && r.motion_delay_us < 400);
    /* out-of-range views and fade speeds are errors, not silently ignored */
    elfm_error e2;
    elfm_error_clear(&e2);
    o.motion_n_views = ELFM_MAX_VIEWS + 1;
    CHECK(elfm_score_tables(tm, NULL, dm, &o, &r, &e2) == ELFM_ERR_INVALID);
    CHECK(strstr(e2.message, "views") != NULL);
    o.motion_n_views = 0;
    o.motion_lead_fade_um_per_ms = 0;
    CHECK(elfm_score_tables(tm, NULL, dm, &o, &r, &e2) == ELFM_ERR_INVALID);
    elfm_table_free(dm);
    elfm_table_free(tm);
  }

  elfm_table_free(truth);
  return check_report();
}
