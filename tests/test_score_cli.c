/* test_score_cli.c — `eventlfm score` end to end: files on disk, --json
 * parsed back with cJSON, the readable table, exit codes 0/1/2 and error
 * messages naming file:line. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cjson/cJSON.h>

#include "check.h"
#include "cli_test_util.h"

static char dir[256];
static const char *exe = ELFM_BINARY_DIR "/eventlfm";

static void write_file(const char *name, const char *text)
{
  CHECK(cli_write_file(dir, name, text) == 0);
}

/* Run `eventlfm score ARGS` in dir; stdout into out, stderr into errtxt. */
static int run(const char *args, char *out, size_t out_size, char *errtxt, size_t err_size)
{
  char cmd[2048];
  snprintf(cmd, sizeof cmd, "cd '%s' && '%s' score %s >out.txt 2>err.txt", dir, exe, args);
  int st = system(cmd);
  int rc = WIFEXITED(st) ? WEXITSTATUS(st) : -1;
  char p[512];
  const char *names[2] = {"out.txt", "err.txt"};
  char *bufs[2] = {out, errtxt};
  size_t sizes[2] = {out_size, err_size};
  for (int i = 0; i < 2; i++) {
    snprintf(p, sizeof p, "%s/%s", dir, names[i]);
    FILE *f = fopen(p, "r");
    size_t n = f ? fread(bufs[i], 1, sizes[i] - 1, f) : 0;
    bufs[i][n] = '\0';
    if (f) fclose(f);
  }
  return rc;
}

static double jnum(const cJSON *o, const char *key)
{
  const cJSON *v = cJSON_GetObjectItemCaseSensitive(o, key);
  return cJSON_IsNumber(v) ? v->valuedouble : NAN;
}

int main(void)
{
  if (access(exe, X_OK) != 0) SKIP("%s not built", exe);
  snprintf(dir, sizeof dir, "/tmp/elfm_test_score_cli_XXXXXX");
  if (!mkdtemp(dir)) { perror("mkdtemp"); return 1; }

  /* Two objects; one tracked with a 1 um x offset, the other missed:
   * alpha = 1 - (20 * 1 + 20 * 4) / (40 * 4) = 0.375. */
  {
    char *t = malloc(1 << 16), *k = malloc(1 << 16);
    size_t n = 0, m = 0;
    n += (size_t)sprintf(t + n, "id,t_us,x_um,y_um,z_um,brightness\n");
    for (int us = 0; us <= 25000; us += 500) {
      n += (size_t)sprintf(t + n, "1,%d,%g,-20,5,1\n", us, -10 + 0.001 * us);
      n += (size_t)sprintf(t + n, "2,%d,%g,20,-3,1\n", us, 10 - 0.001 * us);
    }
    m += (size_t)sprintf(k + m, "track_id,frame,t_us,x_um,y_um,z_um,raw_x_um,raw_y_um,"
                                "raw_z_um,vx_um_per_ms,vy_um_per_ms,vz_um_per_ms,intensity\n");
    for (int f = 0; f < 20; f++) {
      int us = 1000 + 1000 * f;
      double x = -10 + 0.001 * us + 1;
      m += (size_t)sprintf(k + m, "5,%d,%d,%g,-20,5,%g,-20,5,1,0,0,1\n", f, us, x, x);
    }
    write_file("truth.csv", t);
    write_file("tracks.csv", k);
    free(t);
    free(k);
  }
  write_file("bad_truth.csv", "id,t_us,x_um,y_um,z_um,brightness\n1,0,0,0,0,1\n1,100,0,zero,0,1\n");
  write_file("calib.json", "{ not json");

  static char out[1 << 16], err[1 << 16];
  int rc = run("--truth truth.csv --tracks tracks.csv --json --stage-velocity-um-per-ms 2,0,0",
               out, sizeof out, err, sizeof err);
  CHECK_EQ_INT(rc, 0);
  cJSON *o = cJSON_Parse(out);
  CHECK_MSG(o != NULL, "stdout is not one JSON object: %s", out);
  if (o) {
    CHECK_NEAR(jnum(o, "alpha"), 0.375, 1e-9);
    CHECK_NEAR(jnum(o, "beta"), 0.375, 1e-9);
    CHECK_NEAR(jnum(o, "jaccard_tracks"), 0.5, 1e-12);
    CHECK_NEAR(jnum(o, "jaccard_detections"), 0.5, 1e-12);
    CHECK_NEAR(jnum(o, "recall"), 0.5, 1e-12);
    CHECK_NEAR(jnum(o, "precision"), 1.0, 1e-12);
    CHECK_NEAR(jnum(o, "f1"), 2.0 / 3.0, 1e-12);
    CHECK_NEAR(jnum(o, "rmse_x_um"), 1.0, 1e-9);
    CHECK_NEAR(jnum(o, "rmse_y_um"), 0.0, 1e-9);
    CHECK_NEAR(jnum(o, "rmse_z_um"), 0.0, 1e-9);
    /* 20 detections 1 um off, 20 truth points missed: 1 - (20 + 80) / 160 */
    CHECK_NEAR(jnum(o, "alpha_detections"), 0.375, 1e-9);
    /* one track, already on its object: mending identities changes nothing */
    CHECK_NEAR(jnum(o, "alpha_identities"), 0.375, 1e-9);
    CHECK_NEAR(jnum(o, "identity_fragments"), 0.0, 1e-12);
    CHECK_NEAR(jnum(o, "identity_other_tracks"), 0.0, 1e-12);
    CHECK_NEAR(jnum(o, "stage_velocity_rel_error"), 0.5, 1e-12);
    cJSON_Delete(o);
  }
  /* --n-frames 25: frames 20..24 (21..25 ms, extrapolated) count too: 50
   * truth points, 20 matched */
  rc = run("--truth truth.csv --tracks tracks.csv --json --n-frames 25", out, sizeof out, err,
           sizeof err);
  CHECK_EQ_INT(rc, 0);
  o = cJSON_Parse(out);
  CHECK(o != NULL);
  if (o) {
    CHECK_NEAR(jnum(o, "recall"), 0.4, 1e-12);
    CHECK_NEAR(jnum(o, "n_truth_points"), 50, 0);
    cJSON_Delete(o);
  }
  CHECK_EQ_INT(run("--truth truth.csv --tracks tracks.csv --n-frames 0", out, sizeof out, err,
                   sizeof err), 2);
  /* --by-depth 2: object 1 (|z| 5, tracked 1 um off) in the band 4-6 um,
   * object 2 (|z| 3, missed) in 2-4 um; the empty bands left out */
  rc = run("--truth truth.csv --tracks tracks.csv --json --by-depth 2", out, sizeof out, err,
           sizeof err);
  CHECK_EQ_INT(rc, 0);
  o = cJSON_Parse(out);
  CHECK(o != NULL);
  if (o) {
    const cJSON *bands = cJSON_GetObjectItemCaseSensitive(o, "depth_bands");
    CHECK_EQ_INT(cJSON_GetArraySize(bands), 2);
    const cJSON *b0 = cJSON_GetArrayItem(bands, 0), *b1 = cJSON_GetArrayItem(bands, 1);
    CHECK_NEAR(jnum(b0, "z_lo_um"), 2, 0);
    CHECK_NEAR(jnum(b0, "recall"), 0.0, 1e-12);
    CHECK_NEAR(jnum(b0, "alpha_tracks"), 0.0, 1e-12);
    CHECK_NEAR(jnum(b1, "z_lo_um"), 4, 0);
    CHECK_NEAR(jnum(b1, "n_truth_points"), 20, 0);
    CHECK_NEAR(jnum(b1, "rmse_x_um"), 1.0, 1e-9);
    CHECK_NEAR(jnum(b1, "alpha_tracks"), 0.75, 1e-9);
    CHECK_NEAR(jnum(o, "alpha_tracks_unplaced_cost"), 0.0, 1e-12);
    cJSON_Delete(o);
  }
  rc = run("--truth truth.csv --tracks tracks.csv --by-depth 2", out, sizeof out, err, sizeof err);
  CHECK_EQ_INT(rc, 0);
  CHECK_MSG(strstr(out, "by depth (bands of 2 um") != NULL && strstr(out, "0.7500") != NULL,
            "stdout: %s", out);
  /* without it, no bands in the JSON */
  rc = run("--truth truth.csv --tracks tracks.csv --json", out, sizeof out, err, sizeof err);
  CHECK_MSG(rc == 0 && strstr(out, "depth_bands") == NULL, "stdout: %s", out);
  CHECK_EQ_INT(run("--truth truth.csv --tracks tracks.csv --by-depth 0", out, sizeof out, err,
                   sizeof err), 2);
  CHECK_EQ_INT(run("--truth truth.csv --tracks tracks.csv --by-depth deep", out, sizeof out, err,
                   sizeof err), 2);
  /* the readable table */
  rc = run("--truth truth.csv --tracks tracks.csv", out, sizeof out, err, sizeof err);
  CHECK_EQ_INT(rc, 0);
  CHECK(strstr(out, "alpha") != NULL && strstr(out, "0.3750") != NULL);
  /* --help */
  rc = run("--help", out, sizeof out, err, sizeof err);
  CHECK_EQ_INT(rc, 0);
  CHECK(strstr(out, "usage:") != NULL);
  /* usage errors: exit 2 */
  CHECK_EQ_INT(run("--truth truth.csv", out, sizeof out, err, sizeof err), 2);
  CHECK_EQ_INT(run("--truth truth.csv --tracks tracks.csv --stage-velocity-um-per-ms 1,2", out,
                   sizeof out, err, sizeof err), 2);
  CHECK_EQ_INT(run("--truth truth.csv --tracks tracks.csv --eps-um -1", out, sizeof out, err,
                   sizeof err), 2);
  CHECK_EQ_INT(run("--truth truth.csv --tracks tracks.csv --bogus", out, sizeof out, err,
                   sizeof err), 2);
  /* bad files: exit 1, message names file and line */
  rc = run("--truth bad_truth.csv --tracks tracks.csv", out, sizeof out, err, sizeof err);
  CHECK_EQ_INT(rc, 1);
  CHECK_MSG(strstr(err, "bad_truth.csv:3") != NULL, "stderr: %s", err);
  rc = run("--truth missing.csv --tracks tracks.csv", out, sizeof out, err, sizeof err);
  CHECK_EQ_INT(rc, 1);
  CHECK_MSG(strstr(err, "missing.csv") != NULL, "stderr: %s", err);
  rc = run("--truth truth.csv --tracks tracks.csv --calib calib.json", out, sizeof out, err,
           sizeof err);
  CHECK_EQ_INT(rc, 1);
  CHECK_MSG(strstr(err, "calib.json") != NULL, "stderr: %s", err);

  /* By default the window is 0 (SPEC 7 as written) even with a summary;
   * --window-us run takes it from the run's summary.json beside tracks.csv,
   * however long the summary (it lists every track: this one is > 64 KiB,
   * with the parameters last); without one that is an error. */
  rc = run("--truth truth.csv --tracks tracks.csv --window-us run", out, sizeof out, err, sizeof err);
  CHECK_EQ_INT(rc, 1);
  CHECK_MSG(strstr(err, "summary.json") != NULL, "stderr: %s", err);
  {
    size_t cap = 200000, len = 0;
    char *big = malloc(cap);
    CHECK(big != NULL);
    if (big) {
      len += (size_t)snprintf(big + len, cap - len, "{\"tracks\": [");
      for (int i = 0; i < 3000; i++)
        len += (size_t)snprintf(big + len, cap - len, "%s{\"id\": %d, \"model\": \"spline\"}",
                                i ? ", " : "", i);
      snprintf(big + len, cap - len, "], \"parameters\": {\"dt_us\": 1000}}\n");
      CHECK(strlen(big) > 65536);
      write_file("summary.json", big);
      free(big);
    }
    rc = run("--truth truth.csv --tracks tracks.csv --window-us run", out, sizeof out, err, sizeof err);
    CHECK_EQ_INT(rc, 0);
    CHECK_MSG(strstr(out, "window 1000 us from summary.json") != NULL, "stdout: %s", out);
    rc = run("--truth truth.csv --tracks tracks.csv", out, sizeof out, err, sizeof err);
    CHECK_EQ_INT(rc, 0);
    CHECK_MSG(strstr(out, "window 0 us)") != NULL, "stdout: %s", out);
    rc = run("--truth truth.csv --tracks tracks.csv --window-us run --window-us 500", out,
             sizeof out, err, sizeof err);
    CHECK_EQ_INT(rc, 0);
    CHECK_MSG(strstr(out, "window 500 us)") != NULL, "stdout: %s", out);
    rc = run("--truth truth.csv --tracks tracks.csv --window-us soon", out, sizeof out, err, sizeof err);
    CHECK_EQ_INT(rc, 2);
  }

  /* Pulsed light: object 1 lit 800 us of every ms, dark again at each
   * frame's t_us (1000 + 1000 f, the window's end), object 2 always lit.
   * SPEC 7 as written leaves object 1 out at all 20 frames; score counts
   * them (n_truth_lit_then_dark) and says on stderr what the window rule
   * does. No note where nothing blinks, nor under the window rule. */
  {
    char *t = malloc(1 << 17);
    CHECK(t != NULL);
    if (t) {
      size_t n = (size_t)sprintf(t, "id,t_us,x_um,y_um,z_um,brightness\n");
      for (int us = 0; us <= 25000; us += 100) {
        const int lit = us % 1000 >= 100 && us % 1000 < 900;
        n += (size_t)sprintf(t + n, "1,%d,%g,-20,5,%d\n", us, -10 + 0.001 * us, lit);
        n += (size_t)sprintf(t + n, "2,%d,%g,20,-3,1\n", us, 10 - 0.001 * us);
      }
      write_file("pulsed.csv", t);
      free(t);
    }
    rc = run("--truth pulsed.csv --tracks tracks.csv --json", out, sizeof out, err, sizeof err);
    CHECK_EQ_INT(rc, 0);
    o = cJSON_Parse(out);
    CHECK(o != NULL);
    if (o) {
      CHECK_NEAR(jnum(o, "n_truth_lit_then_dark"), 20, 0);
      CHECK_NEAR(jnum(o, "n_truth_points"), 20, 0); /* object 2's */
      cJSON_Delete(o);
    }
    CHECK_MSG(strstr(err, "note: 20 of 40 object-frames were lit within their frame") != NULL &&
                  strstr(err, "--window-us run") != NULL,
              "stderr: %s", err);
    rc = run("--truth pulsed.csv --tracks tracks.csv", out, sizeof out, err, sizeof err);
    CHECK_MSG(rc == 0 && strstr(out, "20 object-frame(s) lit within their frame") != NULL,
              "stdout: %s", out);
    rc = run("--truth pulsed.csv --tracks tracks.csv --json --window-us 1000", out, sizeof out, err,
             sizeof err);
    CHECK_EQ_INT(rc, 0);
    o = cJSON_Parse(out);
    CHECK(o != NULL);
    if (o) {
      CHECK_NEAR(jnum(o, "n_truth_lit_then_dark"), 0, 0);
      CHECK_NEAR(jnum(o, "n_truth_points"), 40, 0);
      cJSON_Delete(o);
    }
    CHECK_MSG(strstr(err, "lit within") == NULL, "stderr: %s", err);
    rc = run("--truth truth.csv --tracks tracks.csv --json", out, sizeof out, err, sizeof err);
    CHECK_EQ_INT(rc, 0);
    CHECK_MSG(strstr(err, "lit within") == NULL, "stderr: %s", err);
    o = cJSON_Parse(out);
    if (o) CHECK_NEAR(jnum(o, "n_truth_lit_then_dark"), 0, 0);
    cJSON_Delete(o);
  }

  char cmd[600];
  snprintf(cmd, sizeof cmd, "rm -rf '%s'", dir);
  if (system(cmd) != 0) fprintf(stderr, "could not remove %s\n", dir);
  return check_report();
}
