/* test_score_depth.c — the measures per band of |z| (elfm_score.h, BY
 * DEPTH) against hand-computed answers.
 *
 * Scene: frames 0..19 at t_us = 1000 + 1000 f; truth sampled every 100 us
 * over 0-25 ms.
 *   A (id 1): x = -10 + 0.001 t, y = -20, z = 5     (band 0 at 20 um bands)
 *   C (id 2): x = 10, y = 20, z = -50, dark from 15.5 ms on (band 2):
 *             it counts in frames 0..14 only.
 * So the truth has 20 + 15 = 35 points. Detections and tracks:
 *   A: every frame, 0.3 um off in x (d = 0.3);
 *   C: frames 0..9, 0.6 um off in x and 2 um in z (d = sqrt(0.36 + 0.25));
 *      its track also has points at frames 15 and 16, where C is dark:
 *      two candidate-only frames, which ISBI's d(X, Y) counts at eps each.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "check.h"
#include "elfm_tracker.h"
#include "score_test_util.h"

static double ax(double t) { return -10 + 0.001 * t; }

static elfm_table *depth_truth(void)
{
  buf_t b = {0};
  bprintf(&b, "id,t_us,x_um,y_um,z_um,brightness\n");
  for (int t = 0; t <= 25000; t += 100) {
    bprintf(&b, "1,%d,%.17g,-20,5,1\n", t, ax(t));
    bprintf(&b, "2,%d,10,20,-50,%d\n", t, t < 15500 ? 1 : 0);
  }
  return parse(&b, "truth.csv");
}

/* detections.csv (tracks 0) or tracks.csv (tracks 1) of the scene */
static elfm_table *depth_rows(int tracks)
{
  buf_t b = {0};
  bprintf(&b, "%s", tracks ? TRACK_HEADER : "frame,t_us,x_um,y_um,z_um\n");
  for (int f = 0; f < NF; f++) {
    const double t = frame_t(f), x = ax(t) + 0.3;
    if (tracks) bprintf(&b, "1,%d,%.0f,%.17g,-20,5,%.17g,-20,5,0.001,0,0,1\n", f, t, x, x);
    else bprintf(&b, "%d,%.0f,%.17g,-20,5\n", f, t, x);
  }
  for (int f = 0; f < NF; f++) {
    const int kept = f <= 9 || (tracks && (f == 15 || f == 16));
    if (!kept) continue;
    const double t = frame_t(f);
    if (tracks) bprintf(&b, "2,%d,%.0f,10.6,20,-48,10.6,20,-48,0,0,0,1\n", f, t);
    else bprintf(&b, "%d,%.0f,10.6,20,-48\n", f, t);
  }
  return parse(&b, tracks ? "tracks.csv" : "detections.csv");
}

static elfm_status score(const elfm_table *truth, const elfm_table *tracks,
                         const elfm_table *dets, double band_um, elfm_score_result *r,
                         elfm_error *err)
{
  elfm_score_options o;
  elfm_score_options_default(&o);
  o.depth_band_um = band_um;
  elfm_error_clear(err);
  return elfm_score_tables(truth, tracks, dets, &o, r, err);
}

int main(void)
{
  const double TOL = 1e-12, EPS = 4.0;
  const double dc = sqrt(0.36 + 0.25); /* C's distance, z counted / 4 */
  elfm_table *truth = depth_truth(), *dets = depth_rows(0), *tracks = depth_rows(1);
  elfm_score_result r;
  elfm_error err;

  /* 1. Bands of 20 um: A in band 0, C in band 2. */
  CHECK_OK(score(truth, tracks, dets, 20, &r, &err), &err);
  CHECK_EQ_INT(r.n_truth_points, 35);
  CHECK_EQ_INT(r.n_depth_bands, ELFM_SCORE_MAX_DEPTH_BANDS);
  CHECK_NEAR(r.depth_bands[0].z_lo_um, 0, 0);
  CHECK_NEAR(r.depth_bands[0].z_hi_um, 20, 0);
  CHECK_NEAR(r.depth_bands[2].z_lo_um, 40, 0);
  CHECK(isinf(r.depth_bands[ELFM_SCORE_MAX_DEPTH_BANDS - 1].z_hi_um));
  const elfm_score_band *a = &r.depth_bands[0], *c = &r.depth_bands[2];
  CHECK_EQ_INT(a->n_truth_points, 20);
  CHECK_EQ_INT(a->n_true_positives, 20);
  CHECK_NEAR(a->recall, 1.0, TOL);
  CHECK_NEAR(a->rmse_x_um, 0.3, 1e-9);
  CHECK_NEAR(a->rmse_y_um, 0.0, 1e-9);
  CHECK_NEAR(a->rmse_z_um, 0.0, 1e-9);
  CHECK_NEAR(a->alpha_detections, 1.0 - 0.3 / EPS, 1e-9);
  CHECK_NEAR(a->alpha_tracks, 1.0 - 0.3 / EPS, 1e-9);
  CHECK_EQ_INT(c->n_truth_points, 15);
  CHECK_EQ_INT(c->n_true_positives, 10);
  CHECK_NEAR(c->recall, 10.0 / 15.0, TOL);
  CHECK_NEAR(c->rmse_x_um, 0.6, 1e-9);
  CHECK_NEAR(c->rmse_z_um, 2.0, 1e-9);
  /* 10 matched at dc, 5 missed at eps */
  const double c_alpha = 1.0 - (10 * dc + 5 * EPS) / (EPS * 15);
  CHECK_NEAR(c->alpha_detections, c_alpha, 1e-9);
  CHECK_NEAR(c->alpha_tracks, c_alpha, 1e-9);
  /* the bands nothing lies in */
  CHECK_EQ_INT(r.depth_bands[1].n_truth_points, 0);
  CHECK(isnan(r.depth_bands[1].recall) && isnan(r.depth_bands[1].alpha_tracks));
  /* the candidate-only frames 15 and 16: 2 eps of 35 eps */
  CHECK_NEAR(r.alpha_tracks_unplaced_cost, 2.0 / 35.0, 1e-12);
  /* the whole: alpha is the bands' alpha_tracks by their points, less
   * what lies outside them; the detections' measures are the bands' sums */
  CHECK_NEAR(r.alpha, (20 * a->alpha_tracks + 15 * c->alpha_tracks) / 35 -
                          r.alpha_tracks_unplaced_cost, 1e-12);
  CHECK_NEAR(r.alpha, 1.0 - (20 * 0.3 + 10 * dc + 5 * EPS + 2 * EPS) / (EPS * 35), 1e-9);
  CHECK_NEAR(r.alpha_detections, (20 * a->alpha_detections + 15 * c->alpha_detections) / 35,
             1e-12);
  CHECK_NEAR(r.recall, 30.0 / 35.0, TOL);

  /* 2. Bands of 100 um: both in band 0, which then is the whole. */
  CHECK_OK(score(truth, tracks, dets, 100, &r, &err), &err);
  CHECK_EQ_INT(r.depth_bands[0].n_truth_points, 35);
  CHECK_NEAR(r.depth_bands[0].recall, r.recall, TOL);
  CHECK_NEAR(r.depth_bands[0].rmse_x_um, r.rmse_x_um, 1e-12);
  CHECK_NEAR(r.depth_bands[0].alpha_tracks - r.alpha_tracks_unplaced_cost, r.alpha, 1e-12);

  /* 3. Bands of 1 um: C's 50 um lies beyond the 16th band, in the last,
   * open one; A's 5 um in band 5. */
  CHECK_OK(score(truth, tracks, dets, 1, &r, &err), &err);
  CHECK_EQ_INT(r.depth_bands[5].n_truth_points, 20);
  CHECK_EQ_INT(r.depth_bands[ELFM_SCORE_MAX_DEPTH_BANDS - 1].n_truth_points, 15);
  CHECK_NEAR(r.depth_bands[ELFM_SCORE_MAX_DEPTH_BANDS - 1].z_lo_um,
             ELFM_SCORE_MAX_DEPTH_BANDS - 1, 0);

  /* 4. Detections only: the bands' detection measures, no alpha_tracks. */
  CHECK_OK(score(truth, NULL, dets, 20, &r, &err), &err);
  CHECK_NEAR(r.depth_bands[2].recall, 10.0 / 15.0, TOL);
  CHECK(isnan(r.depth_bands[2].alpha_tracks));
  CHECK(isnan(r.alpha_tracks_unplaced_cost));

  /* 5. Off by default: no bands, the same measures. */
  CHECK_OK(score(truth, tracks, dets, 0, &r, &err), &err);
  CHECK_EQ_INT(r.n_depth_bands, 0);
  CHECK_NEAR(r.recall, 30.0 / 35.0, TOL);

  /* 5b. A band's alpha_tracks takes a paired point's own distance up to the
   * gate, and eps beyond it: A's track 3 um off (past half the gate) in
   * frames 0..9 and 5 um off (past the gate) in frames 10..19, the track
   * still paired with A (its 10 close frames save 10 (eps - 3) against
   * the dummy). */
  {
    buf_t b = {0};
    bprintf(&b, "%s", TRACK_HEADER);
    for (int f = 0; f < NF; f++) {
      const double t = frame_t(f), x = ax(t) + (f < 10 ? 3.0 : 5.0);
      bprintf(&b, "1,%d,%.0f,%.17g,-20,5,%.17g,-20,5,0.001,0,0,1\n", f, t, x, x);
    }
    elfm_table *far = parse(&b, "tracks.csv");
    CHECK_OK(score(truth, far, NULL, 20, &r, &err), &err);
    CHECK_EQ_INT(r.n_paired_tracks, 1);
    CHECK_NEAR(r.depth_bands[0].alpha_tracks, 1.0 - (10 * 3.0 + 10 * EPS) / (EPS * 20), 1e-9);
    CHECK_NEAR(r.depth_bands[2].alpha_tracks, 0.0, 1e-12); /* C: no track */
    CHECK_NEAR(r.alpha, 1.0 - (10 * 3.0 + 10 * EPS + 15 * EPS) / (EPS * 35), 1e-9);
    elfm_table_free(far);
  }

  /* 6. A band that is not a width: an error, not a guess. */
  const double bad[3] = {-1, NAN, INFINITY};
  for (int i = 0; i < 3; i++) {
    elfm_status s = score(truth, tracks, dets, bad[i], &r, &err);
    CHECK_MSG(s == ELFM_ERR_INVALID, "band %g: status %d", bad[i], (int)s);
    CHECK(strstr(err.message, "depth band") != NULL);
  }

  elfm_table_free(truth);
  elfm_table_free(dets);
  elfm_table_free(tracks);
  return check_report();
}
