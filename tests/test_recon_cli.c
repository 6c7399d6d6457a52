/* test_recon_cli.c — `eventlfm recon` as a user runs it: outputs
 * (summary.json with counts/parameters/timing, EXR volumes, MIP PNGs),
 * exit codes (0 ok, 1 failure with file named on stderr, 2 usage). */
#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cjson/cJSON.h>

#include "check.h"
#include "cli_test_util.h"
#include "elfm_datasets.h"
#include "elfm_recon.h"
#include "elfm_table.h"

static char dir[] = "/tmp/elfm_recon_cli_XXXXXX";

static int run(const char *args) { return cli_run(dir, args); }
static int file_has(const char *name, const char *text) { return cli_file_has(dir, name, text); }

static int exists(const char *rel)
{
  char path[700];
  snprintf(path, sizeof path, "%s/%s", dir, rel);
  return access(path, R_OK) == 0;
}

/* DIR/<rel>/summary.json parsed (cJSON_Delete it), NULL when unreadable */
static cJSON *summary_json(const char *rel)
{
  char path[800];
  snprintf(path, sizeof path, "%s/%s/summary.json", dir, rel);
  FILE *f = fopen(path, "r");
  char buf[16384];
  size_t n = f ? fread(buf, 1, sizeof buf - 1, f) : 0;
  if (f) fclose(f);
  buf[n] = '\0';
  return cJSON_Parse(buf);
}

/* counts.<key> of DIR/<rel>/summary.json, -1 when missing */
static double summary_count(const char *rel, const char *key)
{
  cJSON *root = summary_json(rel);
  cJSON *c = root ? cJSON_GetObjectItem(root, "counts") : NULL;
  cJSON *k = c ? cJSON_GetObjectItem(c, key) : NULL;
  double v = cJSON_IsNumber(k) ? k->valuedouble : -1;
  cJSON_Delete(root);
  return v;
}

/* The files are written by the run's threads beside the refocusing (the
 * callback queues copies): one thread or two, the same bytes in every
 * file, every volume saved; a file that cannot be written stops the run
 * with exit 1 naming it; a run cut short by its input still writes the
 * volumes it made. */
static void test_saved_files(const char *sim)
{
  char args[3000];
  for (int th = 1; th <= 2; th++) {
    snprintf(args, sizeof args,
             "recon --calib %s/calib.json --events %s/events.raw --out %s/w%d --save-volumes "
             "--save-mips --threads %d --dt-us 1000 --quiet",
             sim, sim, dir, th, th);
    CHECK_EQ_INT(run(args), 0);
  }
  const double nvol = summary_count("w2", "volumes");
  CHECK(nvol >= 6);
  CHECK(summary_count("w1", "volumes") == nvol);
  CHECK(summary_count("w1", "saved_volumes") == nvol && summary_count("w2", "saved_volumes") == nvol);
  CHECK(summary_count("w1", "saved_mips") == nvol && summary_count("w2", "saved_mips") == nvol);
  int differ = 0, misnamed = 0;
  int64_t t_prev_us = INT64_MIN;
  for (int k = 0; k < (int)nvol; k++) {
    char a[800], b[800];
    snprintf(a, sizeof a, "%s/w1/volumes/vol_%06d.exr", dir, k);
    snprintf(b, sizeof b, "%s/w2/volumes/vol_%06d.exr", dir, k);
    differ += !cli_same_file(a, b);
    /* each file holds its own frame: the writer's copies are reused from
     * volume to volume (cmd_recon.c) and must carry the new one's fields */
    elfm_volume *v = NULL;
    elfm_error err;
    elfm_error_clear(&err);
    CHECK_OK(elfm_volume_read_exr(b, &v, &err), &err);
    if (v) {
      misnamed += v->frame != k || v->t_us <= t_prev_us;
      t_prev_us = v->t_us;
      elfm_volume_free(v);
    }
    snprintf(a, sizeof a, "%s/w1/mips/mip_%06d.png", dir, k);
    snprintf(b, sizeof b, "%s/w2/mips/mip_%06d.png", dir, k);
    differ += !cli_same_file(a, b);
  }
  CHECK_EQ_INT(differ, 0);
  CHECK_EQ_INT(misnamed, 0);

  /* volumes/ is a file: no EXR can be written */
  char path[800];
  snprintf(path, sizeof path, "%s/wbad", dir);
  mkdir(path, 0777);
  snprintf(path, sizeof path, "%s/wbad/volumes", dir);
  FILE *f = fopen(path, "w");
  if (f) fclose(f);
  snprintf(args, sizeof args,
           "recon --calib %s/calib.json --events %s/events.raw --out %s/wbad --save-volumes --threads 2 --quiet",
           sim, sim, dir);
  CHECK_EQ_INT(run(args), 1);
  CHECK(file_has("err.txt", "wbad/volumes/vol_000000.exr"));
  CHECK(file_has("wbad/summary.json", "\"input_error\"") && file_has("wbad/summary.json", "vol_000000.exr"));
  CHECK(summary_count("wbad", "saved_volumes") == 0);
  CHECK(exists("wbad/frames.csv"));

  /* cut halfway through the recording, inside a 2-byte word (the
   * header's length sets the parity): the volumes made before the error
   * are all written */
  snprintf(path, sizeof path, "%s/events.raw", sim);
  struct stat sb;
  const long half = stat(path, &sb) == 0 ? (long)sb.st_size / 2 : 60000;
  snprintf(path, sizeof path, "%s/cut2.raw", dir);
  int rc = 0;
  for (long cut = half; cut <= half + 1 && rc == 0; cut++) {
    snprintf(args, sizeof args, "head -c %ld %s/events.raw > %s", cut, sim, path);
    CHECK(system(args) == 0);
    snprintf(args, sizeof args,
             "recon --calib %s/calib.json --events %s --out %s/wcut --save-volumes --threads 2 --quiet",
             sim, path, dir);
    rc = run(args);
  }
  CHECK_EQ_INT(rc, 1);
  CHECK(file_has("err.txt", "cut2.raw: byte"));
  const double made = summary_count("wcut", "volumes");
  CHECK(made >= 1 && summary_count("wcut", "saved_volumes") == made);
  char last[64], after[64];
  snprintf(last, sizeof last, "wcut/volumes/vol_%06d.exr", (int)made - 1);
  snprintf(after, sizeof after, "wcut/volumes/vol_%06d.exr", (int)made);
  CHECK(exists(last) && !exists(after));
}

int main(void)
{
  char bin[600];
  snprintf(bin, sizeof bin, "%s/eventlfm", ELFM_BINARY_DIR);
  if (access(bin, X_OK) != 0) SKIP("%s not built", bin);
  if (!mkdtemp(dir)) SKIP("cannot make a temporary directory");
  elfm_error err;
  elfm_scene *sc = NULL;
  CHECK_OK(elfm_scene_load("stage", &sc, &err), &err);
  CHECK_OK(elfm_scene_set_param(sc, "duration_ms=6", &err), &err);
  char sim[700];
  snprintf(sim, sizeof sim, "%s/sim", dir);
  elfm_sim_options so = {.progress = NULL, .progress_user = NULL, .write_truth = 0};
  CHECK_OK(elfm_sim_run(sc, sim, &so, NULL, &err), &err);
  elfm_scene_free(sc);

  char args[3000];
  snprintf(args, sizeof args,
           "recon --calib %s/calib.json --events %s/events.raw --out %s/r --save-volumes --save-mips "
           "--ghost agree:0.3,mad:3 --threads 2 --dt-us 2000",
           sim, sim, dir);
  CHECK_EQ_INT(run(args), 0);
  CHECK(file_has("err.txt", "volumes/s")); /* final line on stderr */
  CHECK(exists("r/volumes/vol_000000.exr") && exists("r/volumes/vol_000002.exr"));
  CHECK(exists("r/mips/mip_000000.png"));
  char path[700];
  cJSON *root = summary_json("r");
  CHECK(root != NULL);
  if (root) {
    cJSON *c = cJSON_GetObjectItem(root, "counts"), *t = cJSON_GetObjectItem(root, "timing");
    cJSON *p = cJSON_GetObjectItem(root, "parameters");
    CHECK(c && cJSON_GetObjectItem(c, "events") && cJSON_GetObjectItem(c, "events")->valuedouble > 1000);
    /* 6 ms at 2 ms per window, +1 for the sensor latency/jitter tail */
    int nvol = c && cJSON_GetObjectItem(c, "volumes") ? (int)cJSON_GetObjectItem(c, "volumes")->valuedouble : 0;
    CHECK(nvol == 3 || nvol == 4);
    char last[64], after[64];
    snprintf(last, sizeof last, "r/volumes/vol_%06d.exr", nvol - 1);
    snprintf(after, sizeof after, "r/volumes/vol_%06d.exr", nvol);
    CHECK(exists(last) && !exists(after));
    CHECK(cJSON_GetObjectItem(c, "saved_mips")->valuedouble == nvol);
    /* frames.csv: one row per volume, windows of 2 ms end to end */
    elfm_table *ft = NULL;
    snprintf(last, sizeof last, "%s/r/frames.csv", dir);
    CHECK_OK(elfm_table_load_csv(last, &ft, &err), &err);
    if (ft) {
      CHECK_EQ_INT(ft->n_rows, nvol);
      int cf = elfm_table_col(ft, "frame"), ct = elfm_table_col(ft, "t_us"),
          c0 = elfm_table_col(ft, "t_start_us"), c1 = elfm_table_col(ft, "t_end_us");
      CHECK(cf >= 0 && ct >= 0 && c0 >= 0 && c1 >= 0 && elfm_table_col(ft, "n_events") >= 0);
      for (size_t k = 0; cf >= 0 && ct >= 0 && c0 >= 0 && c1 >= 0 && k < ft->n_rows; k++) {
        CHECK(elfm_table_get(ft, k, cf) == (double)k);
        CHECK(elfm_table_get(ft, k, c1) - elfm_table_get(ft, k, c0) == 2000);
        CHECK(elfm_table_get(ft, k, ct) == elfm_table_get(ft, k, c1)); /* exp: the window's end */
        if (k > 0) CHECK(elfm_table_get(ft, k, c0) == elfm_table_get(ft, k - 1, c1));
      }
      elfm_table_free(ft);
    }
    CHECK(t && cJSON_GetObjectItem(t, "events_per_s") && cJSON_GetObjectItem(t, "volumes_per_s") &&
          cJSON_GetObjectItem(t, "realtime_factor") && cJSON_GetObjectItem(t, "peak_rss_mb"));
    CHECK(p && cJSON_GetObjectItem(p, "dt_us")->valuedouble == 2000);
    CHECK(p && !strcmp(cJSON_GetObjectItem(p, "ghost_threshold")->valuestring, "mad"));
    CHECK(p && cJSON_GetObjectItem(p, "ghost_agree_frac")->valuedouble == 0.3);
    cJSON_Delete(root);
  }
  elfm_volume *v = NULL;
  snprintf(path, sizeof path, "%s/r/volumes/vol_000001.exr", dir);
  CHECK_OK(elfm_volume_read_exr(path, &v, &err), &err);
  if (v) {
    CHECK_EQ_INT(v->frame, 1);
    CHECK_EQ_INT(v->nz, 101);
    elfm_volume_free(v);
    v = NULL;
  }

  /* other planes than the calibration's: -40..40 every 4 um, 21 planes in
   * the EXR and the summary */
  snprintf(args, sizeof args,
           "recon --calib %s/calib.json --events %s/events.raw --out %s/rz --save-volumes --quiet "
           "--z-min-um -40 --z-max-um 40 --z-step-um 4",
           sim, sim, dir);
  CHECK_EQ_INT(run(args), 0);
  snprintf(path, sizeof path, "%s/rz/volumes/vol_000001.exr", dir);
  CHECK_OK(elfm_volume_read_exr(path, &v, &err), &err);
  if (v) {
    CHECK_EQ_INT(v->nz, 21);
    CHECK(v->z_min_um == -40 && v->z_step_um == 4);
    /* summary.json's geometry is the volumes': each key its own field (a
     * z_step_um written from um_per_px passed every test until a mutation
     * sweep) */
    cJSON *rs = summary_json("rz");
    cJSON *g = rs ? cJSON_GetObjectItem(rs, "volume") : NULL;
    const char *const key[6] = {"w", "h", "nz", "um_per_px", "z_min_um", "z_step_um"};
    const double want[6] = {v->w, v->h, v->nz, v->um_per_px, v->z_min_um, v->z_step_um};
    for (int k = 0; k < 6; k++) {
      cJSON *e = g ? cJSON_GetObjectItem(g, key[k]) : NULL;
      CHECK_MSG(cJSON_IsNumber(e) && e->valuedouble == want[k], "summary.json volume.%s", key[k]);
    }
    CHECK(v->um_per_px != v->z_step_um);
    cJSON_Delete(rs);
    elfm_volume_free(v);
  }
  CHECK(file_has("rz/summary.json", "\"nz\":\t21"));
  /* usage errors: exit 2 */
  snprintf(args, sizeof args, "recon --calib %s/calib.json --events %s/events.raw --out %s/r --z-min-um 200", sim, sim, dir);
  CHECK_EQ_INT(run(args), 2);
  CHECK(file_has("err.txt", "calib.json's planes") && file_has("err.txt", "z.max_um"));
  CHECK_EQ_INT(run("recon"), 2);
  snprintf(args, sizeof args, "recon --calib %s/calib.json --events %s/events.raw --out %s/r --median 4", sim, sim, dir);
  CHECK_EQ_INT(run(args), 2);
  snprintf(args, sizeof args, "recon --calib %s/calib.json --events %s/events.raw --out %s/r --dt-us 10", sim, sim, dir);
  CHECK_EQ_INT(run(args), 2);
  snprintf(args, sizeof args, "recon --calib %s/calib.json --events %s/events.raw --out %s/r --ghost frac", sim, sim, dir);
  CHECK_EQ_INT(run(args), 2);
  snprintf(args, sizeof args, "recon --calib %s/calib.json --events %s/events.raw --out %s/r --repr dots", sim, sim, dir);
  CHECK_EQ_INT(run(args), 2);
  /* a crop margin out of range is the option's error, not the plan's
   * (exit 1, "crop margin -1 px outside 0..1000", until the sixty-first
   * session) */
  snprintf(args, sizeof args, "recon --calib %s/calib.json --events %s/events.raw --out %s/r --crop-margin-px -1", sim, sim, dir);
  CHECK_EQ_INT(run(args), 2);
  CHECK(file_has("err.txt", "--crop-margin-px must be 0..1000"));
  /* A ring of slots larger than half the machine's memory is refused
   * before any of it is made (exit 1 saying why), not filled until the
   * run is killed: 4096 slots of the stage's 1280 x 720 frames, their
   * medians and 101-plane volumes are ~94 GB (sixty-first session). */
  {
    const double phys_gb = (double)sysconf(_SC_PHYS_PAGES) * (double)sysconf(_SC_PAGESIZE) / 1e9;
    snprintf(args, sizeof args, "recon --calib %s/calib.json --events %s/events.raw --out %s/rb --batch 4096",
             sim, sim, dir);
    if (phys_gb > 0 && phys_gb < 150) {
      CHECK_EQ_INT(run(args), 1);
      CHECK(file_has("err.txt", "4096 frames in flight") && file_has("err.txt", "smaller batch"));
    } else {
      printf("note: %.0f GB of memory: the batch of 4096 is not refused here\n", phys_gb);
    }
  }
  /* failures: exit 1 naming the file */
  snprintf(args, sizeof args, "recon --calib %s/calib.json --events %s/none.raw --out %s/r", sim, sim, dir);
  CHECK_EQ_INT(run(args), 1);
  CHECK(file_has("err.txt", "none.raw"));
  snprintf(args, sizeof args, "recon --calib %s/events.raw --events %s/events.raw --out %s/r", sim, sim, dir);
  CHECK_EQ_INT(run(args), 1);
  CHECK(file_has("err.txt", "events.raw"));
  snprintf(path, sizeof path, "%s/cut.raw", dir);
  snprintf(args, sizeof args, "head -c 30000 %s/events.raw > %s", sim, path);
  CHECK(system(args) == 0);
  snprintf(args, sizeof args, "recon --calib %s/calib.json --events %s --out %s/r2 --quiet", sim, path, dir);
  int rc = run(args);
  CHECK(rc == 0 || (rc == 1 && file_has("err.txt", "cut.raw"))); /* cut on a word boundary is valid */
  /* Cut inside a word (the other parity of 30000 or 30001 bytes): exit 1
   * naming file and byte, and the summary of what was read says the input
   * ended in an error rather than passing for the whole recording. */
  snprintf(args, sizeof args, "head -c %d %s/events.raw > %s", rc == 0 ? 30001 : 30000, sim, path);
  CHECK(system(args) == 0);
  snprintf(args, sizeof args, "recon --calib %s/calib.json --events %s --out %s/r4 --quiet", sim, path, dir);
  CHECK_EQ_INT(run(args), 1);
  CHECK(file_has("err.txt", "cut.raw: byte"));
  {
    char sum[800];
    snprintf(sum, sizeof sum, "%s/r4/summary.json", dir);
    FILE *f = fopen(sum, "rb");
    char text[1 << 14];
    size_t n = f ? fread(text, 1, sizeof text - 1, f) : 0;
    if (f) fclose(f);
    text[n] = '\0';
    CHECK_MSG(strstr(text, "\"input_error\"") && strstr(text, "cut.raw: byte"),
              "summary.json of a truncated input lacks input_error");
  }
  test_saved_files(sim);
  snprintf(args, sizeof args, "recon --calib %s/calib.json --tiff %s/events.raw --out %s/r3 --quiet", sim, sim, dir);
  CHECK_EQ_INT(run(args), 1);
  CHECK(file_has("err.txt", "events.raw"));

  snprintf(args, sizeof args, "rm -rf '%s'", dir);
  if (system(args) != 0) fprintf(stderr, "could not remove %s\n", dir);
  return check_report();
}
