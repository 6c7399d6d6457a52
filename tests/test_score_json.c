/* test_score_json.c — every number of `eventlfm score --json` is the
 * library's own (elfm_score_files on the same files, with the gate, axial
 * divisor and window the JSON reports), key by key, on a scene built so that
 * the measures a swapped key would confuse differ: alpha and beta (a
 * spurious track), the two Jaccards, recall and precision, the three RMSEs
 * (a track off by 1 / 0.5 / 2 um in x / y / z), the identity losses (one
 * object's track broken in two, none on another's object). test_score_cli
 * checks the values by hand on a scene where several of these coincide;
 * its alpha = beta and rmse_y = rmse_z = 0 let a beta written from alpha
 * and an rmse_z from rmse_y pass (found by a mutation sweep). */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cjson/cJSON.h>

#include "check.h"
#include "cli_test_util.h"
#include "elfm_score.h"

static char dir[256];
static const char *exe = ELFM_BINARY_DIR "/eventlfm";

static void write_file(const char *name, const char *text)
{
  CHECK(cli_write_file(dir, name, text) == 0);
}

static double jnum(const cJSON *o, const char *key)
{
  const cJSON *v = cJSON_GetObjectItemCaseSensitive(o, key);
  return cJSON_IsNumber(v) ? v->valuedouble : NAN;
}

/* The JSON's key against the library's value: equal to the last digit
 * cJSON prints (17 significant), NaN only where both are. */
static void same(const cJSON *o, const char *key, double want)
{
  const double got = jnum(o, key);
  CHECK_MSG((isnan(got) && isnan(want)) || fabs(got - want) <= 1e-12 * fmax(1.0, fabs(want)),
            "%s: --json %.17g, library %.17g", key, got, want);
}

/* One row of tracks.csv: smoothed and raw at the same point. */
static size_t track_row(char *k, int id, int f, double x, double y, double z)
{
  return (size_t)sprintf(k, "%d,%d,%d,%.6f,%.6f,%.6f,%.6f,%.6f,%.6f,1,0,0,1\n", id, f,
                         1000 + 1000 * f, x, y, z, x, y, z);
}

int main(void)
{
  if (access(exe, X_OK) != 0) SKIP("%s not built", exe);
  snprintf(dir, sizeof dir, "/tmp/elfm_test_score_json_XXXXXX");
  if (!mkdtemp(dir)) SKIP("no temp dir");

  /* Truth: object 1 moving in +x, object 2 in -x, object 3 at rest,
   * sampled every 500 us over 25 ms. Tracks over frames 0-19 (t = 1 + f
   * ms): 5 on object 1, off by (1, 0.5, 2) um; 6 and 7 on object 2 in two
   * pieces (frames 0-9, 10-19), 0.3 um off in x; 8 far from everything
   * (frames 0-9); object 3 has none. */
  char *t = malloc(1 << 16), *k = malloc(1 << 16);
  CHECK(t && k);
  if (!t || !k) return check_report();
  size_t n = 0, m = 0;
  n += (size_t)sprintf(t + n, "id,t_us,x_um,y_um,z_um,brightness\n");
  for (int us = 0; us <= 25000; us += 500) {
    n += (size_t)sprintf(t + n, "1,%d,%g,-20,5,1\n", us, -10 + 0.001 * us);
    n += (size_t)sprintf(t + n, "2,%d,%g,20,-3,1\n", us, 10 - 0.001 * us);
    n += (size_t)sprintf(t + n, "3,%d,0,0,30,1\n", us);
  }
  m += (size_t)sprintf(k + m, "track_id,frame,t_us,x_um,y_um,z_um,raw_x_um,raw_y_um,"
                              "raw_z_um,vx_um_per_ms,vy_um_per_ms,vz_um_per_ms,intensity\n");
  for (int f = 0; f < 20; f++) {
    const double us = 1000 + 1000 * f;
    m += track_row(k + m, 5, f, -10 + 0.001 * us + 1, -19.5, 7);
    m += track_row(k + m, f < 10 ? 6 : 7, f, 10 - 0.001 * us + 0.3, 20, -3);
    if (f < 10) m += track_row(k + m, 8, f, 50, 50, 0);
  }
  write_file("truth.csv", t);
  write_file("tracks.csv", k);
  free(t);
  free(k);

  char cmd[1024];
  snprintf(cmd, sizeof cmd, "cd '%s' && '%s' score --truth truth.csv --tracks tracks.csv --json "
                            ">out.json 2>err.txt", dir, exe);
  const int st = system(cmd);
  CHECK_EQ_INT(WIFEXITED(st) ? WEXITSTATUS(st) : -1, 0);
  char p[512];
  snprintf(p, sizeof p, "%s/out.json", dir);
  static char out[1 << 16];
  FILE *f = fopen(p, "r");
  const size_t got = f ? fread(out, 1, sizeof out - 1, f) : 0;
  out[got] = '\0';
  if (f) fclose(f);
  cJSON *o = cJSON_Parse(out);
  CHECK_MSG(o != NULL, "stdout is not one JSON object: %s", out);

  elfm_score_options so;
  elfm_score_options_default(&so);
  elfm_score_result r;
  elfm_error err;
  elfm_error_clear(&err);
  char pt[512], pk[512];
  snprintf(pt, sizeof pt, "%s/truth.csv", dir);
  snprintf(pk, sizeof pk, "%s/tracks.csv", dir);
  if (o) {
    /* the options the command says it used */
    so.eps_um = jnum(o, "eps_um");
    so.kz = jnum(o, "kz");
    so.window_us = jnum(o, "window_us");
    CHECK(so.eps_um == 4 && so.kz == 4);
  }
  CHECK_OK(elfm_score_files(pt, pk, NULL, &so, &r, &err), &err);
  if (o) {
    CHECK(r.has_tracks);
    /* the scene parts what a swapped key would confuse */
    CHECK(r.beta < r.alpha - 0.01 && fabs(r.jaccard_tracks - r.jaccard_detections) > 0.01);
    CHECK(r.precision < r.recall - 0.01 || r.precision > r.recall + 0.01);
    CHECK(r.rmse_x_um > r.rmse_y_um + 0.1 && r.rmse_z_um > r.rmse_x_um + 0.1);
    CHECK(r.identity_fragments > r.identity_other_tracks + 0.01);
    same(o, "alpha", r.alpha);
    same(o, "beta", r.beta);
    same(o, "jaccard_tracks", r.jaccard_tracks);
    same(o, "jaccard_detections", r.jaccard_detections);
    same(o, "recall", r.recall);
    same(o, "precision", r.precision);
    same(o, "f1", r.f1);
    same(o, "rmse_x_um", r.rmse_x_um);
    same(o, "rmse_y_um", r.rmse_y_um);
    same(o, "rmse_z_um", r.rmse_z_um);
    same(o, "rmse_raw_x_um", r.rmse_raw_x_um);
    same(o, "rmse_raw_y_um", r.rmse_raw_y_um);
    same(o, "rmse_raw_z_um", r.rmse_raw_z_um);
    same(o, "alpha_detections", r.alpha_detections);
    same(o, "rmse_tracks_um", r.rmse_tracks_um);
    same(o, "alpha_identities", r.alpha_identities);
    same(o, "identity_fragments", r.identity_fragments);
    same(o, "identity_other_tracks", r.identity_other_tracks);
    same(o, "n_frames", r.n_frames);
    same(o, "n_truth_points", (double)r.n_truth_points);
    same(o, "n_detections", (double)r.n_detections);
    same(o, "n_true_positives", (double)r.n_true_positives);
    same(o, "n_truth_tracks", r.n_truth_tracks);
    same(o, "n_candidate_tracks", r.n_candidate_tracks);
    same(o, "n_paired_tracks", r.n_paired_tracks);
    same(o, "n_missed_tracks", r.n_missed_tracks);
    same(o, "n_spurious_tracks", r.n_spurious_tracks);
    /* and the scene's counts, by hand: 3 objects, 4 tracks, 2 paired
     * (object 2 to one of its pieces), 1 missed (object 3), the other
     * piece and track 8 spurious; 20 frames x 3 objects, 50 detections */
    CHECK_EQ_INT(r.n_truth_tracks, 3);
    CHECK_EQ_INT(r.n_candidate_tracks, 4);
    CHECK_EQ_INT(r.n_paired_tracks, 2);
    CHECK_EQ_INT(r.n_missed_tracks, 1);
    CHECK_EQ_INT(r.n_spurious_tracks, 2);
    CHECK_EQ_INT((int)r.n_truth_points, 60);
    CHECK_EQ_INT((int)r.n_detections, 50);
    CHECK_NEAR(r.rmse_x_um, sqrt((20 * 1.0 + 20 * 0.09) / 40), 1e-4);
    CHECK_NEAR(r.rmse_z_um, sqrt(20 * 4.0 / 40), 1e-4);
  }
  cJSON_Delete(o);
  snprintf(cmd, sizeof cmd, "rm -rf '%s'", dir);
  CHECK(system(cmd) == 0);
  return check_report();
}
