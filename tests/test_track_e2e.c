/* test_track_e2e.c — end to end on simulated scenes: simulate (datasets),
 * run `eventlfm track`, score against truth (elfm_score.h).
 *   default: flow (50 ms) and stage (30 ms)
 *   argument "slow": flow 100 ms, stage_accel, blink_moving, blink, worm @ 500 Hz,
 *   flow_random 100 ms
 * Thresholds are the figures measured when this was written, a little
 * below (docs/tracker.md); the targets are printed beside them. */
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include <cjson/cJSON.h>

#include "check.h"
#include "cli_test_util.h"
#include "elfm_datasets.h"
#include "elfm_tracker.h"

static char tmpdir[] = "/tmp/elfm_e2e_XXXXXX";

/* stage.acceleration_um_per_ms2[1] of a summary.json; NaN when absent. */
static double summary_stage_accel_y(const char *path)
{
  FILE *f = fopen(path, "rb");
  if (!f) return NAN;
  size_t cap = 1 << 16, n = 0, got;
  char *buf = malloc(cap);
  while (buf && (got = fread(buf + n, 1, cap - n - 1, f)) > 0) {
    n += got;
    if (n + 1 == cap) {
      char *b2 = realloc(buf, cap *= 2);
      if (!b2) { free(buf); buf = NULL; }
      buf = b2;
    }
  }
  fclose(f);
  if (!buf) return NAN;
  buf[n] = 0;
  cJSON *j = cJSON_Parse(buf);
  free(buf);
  const cJSON *st = cJSON_GetObjectItemCaseSensitive(j, "stage");
  const cJSON *acc = cJSON_GetObjectItemCaseSensitive(st, "acceleration_um_per_ms2");
  const cJSON *y = cJSON_GetArrayItem(acc, 1);
  const double a = cJSON_IsNumber(y) ? y->valuedouble : NAN;
  cJSON_Delete(j);
  return a;
}

static int simulate(const char *scene, int duration_ms, const char *dir)
{
  elfm_error err;
  elfm_scene *s = NULL;
  char kv[64];
  snprintf(kv, sizeof kv, "duration_ms=%d", duration_ms);
  if (elfm_scene_load(scene, &s, &err) != ELFM_OK || elfm_scene_set_param(s, kv, &err) != ELFM_OK) {
    char b[1200];
    fprintf(stderr, "scene %s: %s\n", scene, elfm_error_format(&err, b, sizeof b));
    elfm_scene_free(s);
    return 0;
  }
  elfm_sim_options so;
  memset(&so, 0, sizeof so);
  so.write_truth = 1;
  elfm_status st = elfm_sim_run(s, dir, &so, NULL, &err);
  elfm_scene_free(s);
  if (st != ELFM_OK) {
    char b[1200];
    fprintf(stderr, "simulate %s: %s\n", scene, elfm_error_format(&err, b, sizeof b));
    return 0;
  }
  return 1;
}

static int track_to(const char *dir, const char *out, int threads, const char *extra)
{
  char cmd[4096];
  snprintf(cmd, sizeof cmd,
           "'%s/eventlfm' track --calib '%s/calib.json' --events '%s/events.raw' --out '%s/%s' "
           "-q --threads %d %s",
           ELFM_BINARY_DIR, dir, dir, dir, out, threads, extra);
  int rc = system(cmd);
  if (rc != 0) fprintf(stderr, "failed (%d): %s\n", rc, cmd);
  return rc == 0;
}

static int track(const char *dir, const char *extra) { return track_to(dir, "out", 2, extra); }

/* Peaks are detected on the worker threads: the detections and tracks must
 * not depend on the thread count (1, 2 and 3 threads: 3 gives batches of 6
 * slots shared unevenly between 2 cores). */
static void check_thread_independence(const char *dir)
{
  static const char *files[2] = {"detections.csv", "tracks.csv"};
  static const int threads[2] = {1, 3};
  static const char *outs[2] = {"out_t1", "out_t3"};
  for (int k = 0; k < 2; k++) {
    if (!track_to(dir, outs[k], threads[k], "")) {
      CHECK(0);
      continue;
    }
    for (int f = 0; f < 2; f++) {
      char a[1400], b[1400];
      snprintf(a, sizeof a, "%s/out/%s", dir, files[f]);
      snprintf(b, sizeof b, "%s/%s/%s", dir, outs[k], files[f]);
      CHECK_MSG(cli_same_file(a, b), "%s differs between 2 and %d threads", files[f], threads[k]);
    }
  }
}

/* frame_list: score with the run's frames.csv and each frame's own window
 * (blinking objects under --start each-trigger) */
static int score_with(const char *dir, const double *stage_v, int frame_list, elfm_score_result *r);
static int score(const char *dir, const double *stage_v, elfm_score_result *r)
{
  return score_with(dir, stage_v, 0, r);
}

static int score_with(const char *dir, const double *stage_v, int frame_list, elfm_score_result *r)
{
  char truth[1400], tracks[1400], dets[1400], calib[1400];
  snprintf(truth, sizeof truth, "%s/truth.csv", dir);
  snprintf(tracks, sizeof tracks, "%s/out/tracks.csv", dir);
  snprintf(dets, sizeof dets, "%s/out/detections.csv", dir);
  snprintf(calib, sizeof calib, "%s/calib.json", dir);
  elfm_error err;
  elfm_calib c;
  elfm_score_options o;
  elfm_score_options_default(&o);
  if (elfm_calib_load(calib, &c, &err) == ELFM_OK) elfm_score_options_set_calib(&o, &c);
  if (stage_v) {
    o.have_stage = 1;
    memcpy(o.stage_v_um_per_ms, stage_v, 3 * sizeof(double));
  }
  elfm_table *frames = NULL;
  elfm_status st = ELFM_OK;
  if (frame_list) {
    char p[1400];
    snprintf(p, sizeof p, "%s/out/frames.csv", dir);
    st = elfm_table_load_csv(p, &frames, &err);
    o.frames = frames;
    o.window_frames = 1;
  }
  if (st == ELFM_OK) st = elfm_score_files(truth, tracks, dets, &o, r, &err);
  elfm_table_free(frames);
  CHECK_OK(st, &err);
  if (st == ELFM_OK)
    fprintf(stderr,
            "  F1 %.3f (recall %.3f precision %.3f)  RMSE x %.2f y %.2f z %.2f um  "
            "alpha %.3f beta %.3f  tracks %d for %d truth (%d paired)\n",
            r->f1, r->recall, r->precision, r->rmse_x_um, r->rmse_y_um, r->rmse_z_um, r->alpha,
            r->beta, r->n_candidate_tracks, r->n_truth_tracks, r->n_paired_tracks);
  return st == ELFM_OK;
}

static void sub(char *out, size_t n, const char *name)
{
  snprintf(out, n, "%s/%s", tmpdir, name);
  mkdir(out, 0777);
}

/* Per truth id: how many tracks.csv tracks have most of their real points
 * nearest to it (within 4 um, anisotropic). One track per bead = 1. */
static void tracks_per_bead(const char *dir, int *beads, int *beads_one_track, int *max_tracks)
{
  char p[1400];
  elfm_error err;
  elfm_table *tr = NULL, *tt = NULL;
  *beads = *beads_one_track = *max_tracks = 0;
  snprintf(p, sizeof p, "%s/out/tracks.csv", dir);
  if (elfm_table_load_csv(p, &tr, &err) != ELFM_OK) return;
  snprintf(p, sizeof p, "%s/truth.csv", dir);
  if (elfm_table_load_csv(p, &tt, &err) != ELFM_OK) { elfm_table_free(tr); return; }
  int cid = elfm_table_col(tr, "track_id"), ct = elfm_table_col(tr, "t_us"),
      crx = elfm_table_col(tr, "raw_x_um"), cry = elfm_table_col(tr, "raw_y_um"),
      crz = elfm_table_col(tr, "raw_z_um");
  int tid = elfm_table_col(tt, "id"), tt_ = elfm_table_col(tt, "t_us"), tx = elfm_table_col(tt, "x_um"),
      ty = elfm_table_col(tt, "y_um"), tz = elfm_table_col(tt, "z_um");
  enum { MAXID = 256, MAXTR = 4096 };
  static int owner[MAXTR][MAXID];
  memset(owner, 0, sizeof owner);
  for (size_t r = 0; r < tr->n_rows; r++) {
    double x = elfm_table_get(tr, r, crx);
    if (isnan(x)) continue;
    int k = (int)elfm_table_get(tr, r, cid);
    double t = elfm_table_get(tr, r, ct), bd = 16;
    int best = -1;
    /* truth rows nearest in time per id (sampled every <= 100 us) */
    for (size_t q = 0; q < tt->n_rows; q++) {
      if (fabs(elfm_table_get(tt, q, tt_) - t) > 50) continue;
      double dx = elfm_table_get(tt, q, tx) - x, dy = elfm_table_get(tt, q, ty) - elfm_table_get(tr, r, cry),
             dz = (elfm_table_get(tt, q, tz) - elfm_table_get(tr, r, crz)) / 4;
      double d2 = dx * dx + dy * dy + dz * dz;
      if (d2 < bd) { bd = d2; best = (int)elfm_table_get(tt, q, tid); }
    }
    if (best >= 0 && best < MAXID && k >= 0 && k < MAXTR) owner[k][best]++;
  }
  int ntr[MAXID] = {0};
  for (int k = 0; k < MAXTR; k++) {
    int bi = -1, bn = 0;
    for (int i = 0; i < MAXID; i++) if (owner[k][i] > bn) { bn = owner[k][i]; bi = i; }
    if (bi >= 0) ntr[bi]++;
  }
  for (int i = 0; i < MAXID; i++) {
    if (!ntr[i]) continue;
    (*beads)++;
    *beads_one_track += ntr[i] == 1;
    if (ntr[i] > *max_tracks) *max_tracks = ntr[i];
  }
  elfm_table_free(tr);
  elfm_table_free(tt);
}

int main(int argc, char **argv)
{
  int slow = argc > 1 && !strcmp(argv[1], "slow");
  char bin[1024];
  snprintf(bin, sizeof bin, "%s/eventlfm", ELFM_BINARY_DIR);
  if (access(bin, X_OK) != 0) SKIP("%s not built", bin);
  if (!mkdtemp(tmpdir)) SKIP("no temp dir");
  char dir[1200];
  elfm_score_result r;

  /* flow: helical paths at 2.5-4 mm/s (targets: F1 >= 0.95, lateral RMSE
   * <= 0.5 um, axial <= 2 um, alpha >= 0.9) */
  sub(dir, sizeof dir, "flow");
  fprintf(stderr, "flow (%d ms):\n", slow ? 100 : 50);
  if (simulate("flow", slow ? 100 : 50, dir) && track(dir, "") && score(dir, NULL, &r)) {
    CHECK_MSG(r.f1 >= 0.75, "flow F1 %.3f", r.f1);
    /* the detections moved back by their track's motion bias (forty-third
     * session): 100 ms 0.44 / 0.46 um (0.51 / 0.52 as measured), 50 ms
     * 0.51 / 0.52 */
    const double lat_max = slow ? 0.5 : 0.6;
    CHECK_MSG(r.rmse_x_um <= lat_max && r.rmse_y_um <= lat_max, "flow lateral RMSE %.2f %.2f", r.rmse_x_um,
              r.rmse_y_um);
    CHECK_MSG(r.rmse_z_um <= 2.0, "flow axial RMSE %.2f", r.rmse_z_um);
    /* 50 ms: 0.679, 100 ms: 0.627 with the rescue round for fresh misses,
     * the linker's z/1.5 and the turn model (before: 0.615 / 0.525;
     * docs/tracker.md) */
    CHECK_MSG(r.alpha >= (slow ? 0.6 : 0.65), "flow alpha %.3f", r.alpha);
    CHECK_MSG(r.n_paired_tracks >= r.n_truth_tracks - 4, "flow paired %d of %d", r.n_paired_tracks, r.n_truth_tracks);
    if (!slow) check_thread_independence(dir);
  } else CHECK(0);

  /* stage: rigid translation at 2.5 mm/s along +y (target: speed error <= 1 %) */
  sub(dir, sizeof dir, "stage");
  /* 50 ms, not 30: the tracks of a 30 ms run are so short that one deep
   * bead's track breaking in two moved the mean velocity's z by 2 % (4 um
   * planes; 6 seeds at 30 ms, vector error 0.12-2.3 %, at 50 ms
   * 0.17-1.17 %, against 0.10-1.41 % / 0.13-1.16 % on the 2 um planes) */
  fprintf(stderr, "stage (%d ms):\n", slow ? 200 : 50);
  const double sv[3] = {0, 2.5, 0};
  if (simulate("stage", slow ? 200 : 50, dir) &&
      track(dir, "--motion stage --stage-velocity-um-per-ms 0,2.5,0") && score(dir, sv, &r)) {
    CHECK(r.has_stage);
    double speed = sqrt(r.mean_v_um_per_ms[0] * r.mean_v_um_per_ms[0] +
                        r.mean_v_um_per_ms[1] * r.mean_v_um_per_ms[1] +
                        r.mean_v_um_per_ms[2] * r.mean_v_um_per_ms[2]);
    fprintf(stderr, "  stage: mean velocity (%.4f, %.4f, %.4f) um/ms, speed error %.3f %%, vector error %.3f %%\n",
            r.mean_v_um_per_ms[0], r.mean_v_um_per_ms[1], r.mean_v_um_per_ms[2],
            100 * fabs(speed - 2.5) / 2.5, 100 * r.stage_rel_error);
    CHECK_MSG(fabs(speed - 2.5) / 2.5 <= 0.01, "stage speed %.4f", speed);
    CHECK_MSG(r.stage_rel_error <= 0.02, "stage vector error %.4f", r.stage_rel_error);
    CHECK_MSG(r.f1 >= 0.85, "stage F1 %.3f", r.f1);
  } else CHECK(0);

  if (slow) {
    /* stage_accel: 0.1 -> 2.5 mm/s at 2.5 mm/s^2 = 0.0025 um/ms^2 (target: within 5 %) */
    sub(dir, sizeof dir, "stage_accel");
    fprintf(stderr, "stage_accel (300 ms):\n");
    if (simulate("stage_accel", 300, dir) && track(dir, "--motion stage") && score(dir, NULL, &r)) {
      char p[1400];
      snprintf(p, sizeof p, "%s/out/tracks.csv", dir);
      elfm_table *t = NULL;
      elfm_error err;
      CHECK_OK(elfm_table_load_csv(p, &t, &err), &err);
      if (t) {
        /* acceleration = slope of vy over time, pooled over all rows */
        int cy = elfm_table_col(t, "vy_um_per_ms"), ct = elfm_table_col(t, "t_us");
        double st = 0, sv_ = 0, stt = 0, stv = 0, n = 0, t0 = elfm_table_get(t, 0, ct);
        for (size_t q = 0; q < t->n_rows; q++) {
          double tm = (elfm_table_get(t, q, ct) - t0) * 1e-3, v = elfm_table_get(t, q, cy);
          st += tm; sv_ += v; stt += tm * tm; stv += tm * v; n++;
        }
        double a = (n * stv - st * sv_) / (n * stt - st * st);
        fprintf(stderr, "  stage_accel: fitted acceleration %.6f um/ms^2 (truth 0.0025, %.1f %%)\n", a,
                100 * fabs(a - 0.0025) / 0.0025);
        CHECK_MSG(fabs(a - 0.0025) / 0.0025 <= 0.05, "acceleration %.6f", a);
        elfm_table_free(t);
        /* summary.json says the same (its stage section fits the rows
         * before they are rounded for tracks.csv) */
        snprintf(p, sizeof p, "%s/out/summary.json", dir);
        const double as = summary_stage_accel_y(p);
        fprintf(stderr, "  stage_accel: summary.json's acceleration %.6f um/ms^2\n", as);
        CHECK_MSG(fabs(as - a) <= 0.01 * fabs(a), "summary's acceleration %.6f against %.6f", as, a);
      }
    } else CHECK(0);

    /* blink_moving: 1 ms pulses every 3 ms on the moving stage: one track per bead */
    const char *blinks[2] = {"blink_moving", "blink"};
    for (int b = 0; b < 2; b++) {
      sub(dir, sizeof dir, blinks[b]);
      fprintf(stderr, "%s (200 ms):\n", blinks[b]);
      /* The README's settings, windows opened by the LED, scored per
       * frame's own window: blink_moving with the linear surface (measured
       * alpha 0.851, recall 0.956, 37 of 37 beads in one track; with the
       * exponential surface and --motion stage, before, 37 of 37 too),
       * blink (alpha 0.928, 15 of 15) */
      if (simulate(blinks[b], 200, dir) &&
          track(dir, b == 0 ? "--repr lin --start each-trigger" : "--start each-trigger")) {
        score_with(dir, NULL, 1, &r);
        int beads, one, mx;
        tracks_per_bead(dir, &beads, &one, &mx);
        fprintf(stderr, "  %s: %d beads tracked, %d with exactly one track (max %d tracks)\n",
                blinks[b], beads, one, mx);
        CHECK(beads >= 8);
        /* A bead or two of blink_moving's at z 86 um, near the volume's
         * top, comes in two pieces: over seeds 1-12 (200 ms), 5 of 511
         * tracked beads on the calibration's 2 um planes, 8 of 514 on the
         * 4 um planes track takes since the twenty-sixth session, which
         * find a few more of the deep beads (the same 506 in one track);
         * on this seed 1 of 42, then 2 of 41. A broken gap closing would
         * split dozens. */
        CHECK_MSG(one >= beads - 2, "%d of %d beads in one track", one, beads);
        if (b == 0) {
          CHECK_MSG(r.alpha >= 0.8 && r.recall >= 0.93, "blink_moving alpha %.3f recall %.3f",
                    r.alpha, r.recall);
          /* every pulse's beads: also those crossing the field's edge in
           * one or two pulses, a track of one or two points (measured 47
           * of 48 paired; 40 with 3 points per track, before) */
          fprintf(stderr, "  blink_moving: %d of %d beads paired\n", r.n_paired_tracks,
                  r.n_truth_tracks);
          CHECK_MSG(r.n_paired_tracks >= r.n_truth_tracks - 2, "blink_moving paired %d of %d",
                    r.n_paired_tracks, r.n_truth_tracks);
        }
        if (b == 1) {
          CHECK_MSG(r.alpha >= 0.9 && r.recall >= 0.98, "blink alpha %.3f recall %.3f", r.alpha,
                    r.recall);
          CHECK_MSG(beads == 15 && one == 15, "blink: %d of %d beads in one track", one, beads);
        }
      } else CHECK(0);
    }

    /* worm at 500 Hz (target: every visible neuron tracked, alpha >= 0.9),
     * with the integral (README: the setting for slowly moving cells;
     * measured F1 0.917, alpha 0.800, lateral RMSE 0.29 / 0.38 um; the
     * ON time surface gave alpha 0.394, RMSE 1.27 / 1.53 um) */
    sub(dir, sizeof dir, "worm");
    fprintf(stderr, "worm (200 ms, 500 Hz):\n");
    if (simulate("worm", 200, dir) && track(dir, "--dt-us 2000 --repr integral") &&
        score(dir, NULL, &r)) {
      CHECK_MSG(r.n_paired_tracks >= r.n_truth_tracks - 1, "worm paired %d of %d", r.n_paired_tracks,
                r.n_truth_tracks);
      CHECK_MSG(r.rmse_x_um <= 0.6 && r.rmse_y_um <= 0.6, "worm lateral RMSE %.2f %.2f",
                r.rmse_x_um, r.rmse_y_um);
      CHECK_MSG(r.alpha >= 0.7, "worm alpha %.3f", r.alpha);
    } else CHECK(0);

    /* flow_random: the flow's beads in random 3D motion, the shape of path
     * the tracker was not tuned on (measured at the defaults, seed 1: alpha
     * 0.686, F1 0.913, lateral RMSE 0.65 / 0.64 um, axial 1.33 um, 20 of
     * 20 beads paired; seeds 1-20 alpha 0.614, docs/tracker.md "Random
     * motion"). A guard against a tracker that works on helices only.
     * Since the fiftieth session track finds that these beads turn beyond
     * its prediction and runs at twice the rate (--stride-us 500): seed 1
     * alpha 0.750 (0.671 at 1 ms frames), F1 0.932, RMSE 0.60 / 0.59 /
     * 1.35 um (docs/tracker.md "Frames twice as often for turning beads");
     * the bar rose from 0.6 to 0.7 with it. */
    sub(dir, sizeof dir, "flow_random");
    fprintf(stderr, "flow_random (100 ms):\n");
    if (simulate("flow_random", 100, dir) && track(dir, "") && score(dir, NULL, &r)) {
      CHECK_MSG(r.f1 >= 0.85, "flow_random F1 %.3f", r.f1);
      CHECK_MSG(r.rmse_x_um <= 0.9 && r.rmse_y_um <= 0.9, "flow_random lateral RMSE %.2f %.2f",
                r.rmse_x_um, r.rmse_y_um);
      CHECK_MSG(r.rmse_z_um <= 2.0, "flow_random axial RMSE %.2f", r.rmse_z_um);
      CHECK_MSG(r.alpha >= 0.7, "flow_random alpha %.3f", r.alpha);
      CHECK_MSG(r.n_paired_tracks >= r.n_truth_tracks - 2, "flow_random paired %d of %d",
                r.n_paired_tracks, r.n_truth_tracks);
    } else CHECK(0);
  }
  if (!getenv("ELFM_KEEP")) {
    char cmd[1200];
    snprintf(cmd, sizeof cmd, "rm -rf '%s'", tmpdir);
    if (system(cmd) != 0) fprintf(stderr, "could not remove %s\n", tmpdir);
  } else fprintf(stderr, "kept %s\n", tmpdir);
  return check_report();
}
