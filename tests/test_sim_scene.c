/* test_sim_scene.c — scene files: every built-in loads; a file equals its
 * built-in; bad files (missing key, wrong type, non-finite, out of range,
 * truncated, empty, impossible layouts) fail with the file and the key
 * named; --param overrides check keys and leave the scene intact on error. */
#include <math.h>
#include <string.h>

#include "check.h"
#include "elfm_datasets.h"

static char *slurp(const char *path)
{
  FILE *f = fopen(path, "rb");
  if (!f) return NULL;
  fseek(f, 0, SEEK_END);
  long n = ftell(f);
  fseek(f, 0, SEEK_SET);
  char *b = malloc((size_t)n + 1);
  if (fread(b, 1, (size_t)n, f) != (size_t)n) n = 0;
  b[n] = 0;
  fclose(f);
  return b;
}

static char *replace(const char *text, const char *from, const char *to)
{
  const char *p = strstr(text, from);
  if (!p) {
    fprintf(stderr, "replace: '%s' not in scene text\n", from);
    exit(1);
  }
  size_t a = (size_t)(p - text), lf = strlen(from), lt = strlen(to), n = strlen(text);
  char *r = malloc(n - lf + lt + 1);
  memcpy(r, text, a);
  memcpy(r + a, to, lt);
  memcpy(r + a + lt, p + lf, n - a - lf + 1);
  return r;
}

/* Write text to a file, load it: must fail with code, naming file and key. */
static void expect_bad(const char *text, elfm_status code, const char *key)
{
  const char *path = "bad_scene.json";
  FILE *f = fopen(path, "wb");
  fputs(text, f);
  fclose(f);
  elfm_error err;
  elfm_error_clear(&err);
  elfm_scene *s = (elfm_scene *)&err; /* must come back NULL */
  elfm_status st = elfm_scene_load(path, &s, &err);
  char buf[1200];
  elfm_error_format(&err, buf, sizeof buf);
  CHECK_MSG(st == code, "key %s: want %s, got %s (%s)", key ? key : "-", elfm_status_str(code),
            elfm_status_str(st), buf);
  CHECK(s == NULL);
  CHECK_MSG(strstr(buf, path) != NULL, "no file in: %s", buf);
  if (key) CHECK_MSG(strstr(buf, key) != NULL, "no key '%s' in: %s", key, buf);
  elfm_scene_free(s);
}

/* How many of the stage scene's beads move v um/ms along y over 1 ms from
 * the scene's start (a bead the stage carries past the field's edge
 * wraps, and is not counted). */
static int stage_beads_moved(const elfm_scene *s, double v)
{
  int n = 0;
  const int64_t t0 = elfm_scene_t0_us(s);
  for (int k = 0; k < elfm_scene_n_objects(s); k++) {
    elfm_truth a, b;
    elfm_scene_truth(s, k, t0, &a);
    elfm_scene_truth(s, k, t0 + 1000, &b);
    n += fabs(b.y_um - a.y_um - v) < 0.05 && b.x_um == a.x_um;
  }
  return n;
}

/* Static beads lie uniformly over the placement disc (and in depth): of
 * 1000 placed without a minimum separation, half within R / sqrt(2) of
 * the axis (a radius drawn uniformly, not its square, put 71 % there and
 * the beads' density 1 / r at the centre; only end-to-end tracks noticed,
 * through the scenes' changed layouts), none beyond R. */
static void test_placement_uniform(void)
{
  elfm_error err;
  elfm_scene *s = NULL;
  CHECK_OK(elfm_scene_load("blink", &s, &err), &err);
  if (!s) return;
  /* the separation first: 1000 beads 10 um apart do not fit */
  CHECK_OK(elfm_scene_set_param(s, "objects.min_separation_um=0", &err), &err);
  CHECK_OK(elfm_scene_set_param(s, "objects.count=1000", &err), &err);
  const int n = elfm_scene_n_objects(s);
  CHECK_EQ_INT(n, 1000);
  const double R = 55, z_lo = -80, z_hi = 80; /* blink.json's motion */
  int inner = 0, outside = 0, upper = 0;
  for (int o = 0; o < n; o++) {
    elfm_truth tr;
    elfm_scene_truth(s, o, elfm_scene_t0_us(s), &tr);
    const double r = hypot(tr.x_um, tr.y_um);
    inner += r < R / sqrt(2.0);
    outside += r > R + 1e-9 || tr.z_um < z_lo || tr.z_um > z_hi;
    upper += tr.z_um > 0.5 * (z_lo + z_hi);
  }
  /* binomial(1000, 0.5): sd 16 */
  CHECK_MSG(inner > 450 && inner < 550, "%d of 1000 within R / sqrt(2)", inner);
  CHECK_MSG(upper > 450 && upper < 550, "%d of 1000 in the upper half of the depths", upper);
  CHECK_EQ_INT(outside, 0);
  elfm_scene_free(s);
}

int main(void)
{
  elfm_error err;
  elfm_error_clear(&err);
  int n_builtin = 0;
  for (int k = 0; elfm_scene_builtin_name(k); k++) {
    elfm_scene *s = NULL;
    CHECK_OK(elfm_scene_load(elfm_scene_builtin_name(k), &s, &err), &err);
    CHECK(s && !strcmp(elfm_scene_name(s), elfm_scene_builtin_name(k)));
    elfm_scene_free(s);
    n_builtin++;
  }
  CHECK_EQ_INT(n_builtin, 9);
  const char *names[] = {"stage", "stage_accel", "zsweep", "flow", "flow_random", "blink",
                         "blink_moving", "worm", "slice"};
  for (int i = 0; i < 9; i++) {
    elfm_scene *s = NULL;
    CHECK_OK(elfm_scene_load(names[i], &s, &err), &err);
    elfm_scene_free(s);
  }
  elfm_scene *none = NULL;
  CHECK(elfm_scene_load("no_such_scene", &none, &err) != ELFM_OK && none == NULL);
  CHECK(strstr(err.message, "stage") != NULL); /* lists the built-ins */
  CHECK(elfm_scene_load("no/such/file.json", &none, &err) == ELFM_ERR_IO);
  CHECK(strstr(err.file, "no/such/file.json") != NULL);

  /* The file in datasets/scenes equals the built-in. */
  char *text = slurp(ELFM_SOURCE_DIR "/datasets/scenes/worm.json");
  CHECK(text != NULL);
  if (!text) return check_report();
  elfm_scene *a = NULL, *b = NULL;
  CHECK_OK(elfm_scene_load(ELFM_SOURCE_DIR "/datasets/scenes/worm.json", &a, &err), &err);
  CHECK_OK(elfm_scene_load("worm", &b, &err), &err);
  if (a && b) {
    CHECK_EQ_INT(elfm_scene_n_objects(a), 12);
    elfm_truth ta, tb;
    elfm_scene_truth(a, 5, elfm_scene_t0_us(a) + 123456, &ta);
    elfm_scene_truth(b, 5, elfm_scene_t0_us(b) + 123456, &tb);
    CHECK(ta.x_um == tb.x_um && ta.y_um == tb.y_um && ta.z_um == tb.z_um);
    /* Four neurons per worm share the worm's z. */
    elfm_scene_truth(a, 4, elfm_scene_t0_us(a) + 123456, &tb);
    elfm_scene_truth(a, 7, elfm_scene_t0_us(a) + 123456, &ta);
    CHECK(ta.z_um == tb.z_um);
  }
  elfm_scene_free(a);
  elfm_scene_free(b);

  char *t;
  t = replace(text, "\"slice_us\": 1000,", "");
  expect_bad(t, ELFM_ERR_FORMAT, "slice_us");
  free(t);
  t = replace(text, "\"refractory_us\": 50", "\"refractory_us\": \"50\"");
  expect_bad(t, ELFM_ERR_FORMAT, "sensor.refractory_us");
  free(t);
  t = replace(text, "\"background_hz\": 1000", "\"background_hz\": 1e999");
  expect_bad(t, ELFM_ERR_RANGE, "background_hz");
  free(t);
  t = replace(text, "\"background_hz\": 1000", "\"background_hz\": NaN");
  expect_bad(t, ELFM_ERR_FORMAT, NULL); /* not JSON: the byte offset is named */
  free(t);
  t = replace(text, "\"threshold_on\": 0.2", "\"threshold_on\": -0.2");
  expect_bad(t, ELFM_ERR_RANGE, "sensor.threshold_on");
  free(t);
  t = replace(text, "\"type\": \"worm\"", "\"type\": \"snake\"");
  expect_bad(t, ELFM_ERR_FORMAT, "motion.type");
  free(t);
  t = replace(text, "\"count\": 12", "\"count\": 13");
  expect_bad(t, ELFM_ERR_RANGE, "objects.count");
  free(t);
  t = replace(text, "\"diameter_um\": [\n      4,\n      6\n    ]", "\"diameter_um\": [6, 4]");
  expect_bad(t, ELFM_ERR_RANGE, "objects.diameter_um");
  free(t);
  t = replace(text, "\"neuron_s_um\": [", "\"neuron_s_um\": [1, ");
  expect_bad(t, ELFM_ERR_FORMAT, "motion.neuron_s_um");
  free(t);
  t = replace(text, "\"crawl_mm_per_s\": 0.1", "\"crawl_mm_per_s\": 2");
  expect_bad(t, ELFM_ERR_RANGE, "motion.crawl_mm_per_s"); /* would leave the field */
  free(t);
  t = replace(text, "\"width\": 1280", "\"width\": 4096");
  expect_bad(t, ELFM_ERR_RANGE, "sensor.width");
  free(t);
  t = replace(text, "\"na\": 0.75", "\"na\": 1.2");
  expect_bad(t, ELFM_ERR_RANGE, "optics.na");
  free(t);
  t = replace(text, "\"spikes\": null", "\"spikes\": 3");
  expect_bad(t, ELFM_ERR_FORMAT, "spikes");
  free(t);
  /* Truncated: invalid JSON, with the offset where parsing stopped. */
  size_t n = strlen(text);
  char *trunc = strdup(text);
  trunc[n / 3] = 0;
  expect_bad(trunc, ELFM_ERR_FORMAT, NULL);
  elfm_scene *s = NULL;
  elfm_scene_load("bad_scene.json", &s, &err);
  CHECK(err.offset >= 0 && err.offset <= (int64_t)(n / 3));
  free(trunc);
  expect_bad("", ELFM_ERR_FORMAT, NULL);
  expect_bad("[]", ELFM_ERR_FORMAT, NULL);
  free(text);

  /* Too many objects for the placement volume. */
  text = slurp(ELFM_SOURCE_DIR "/datasets/scenes/blink.json");
  if (text) {
    t = replace(text, "\"count\": 15", "\"count\": 5000");
    expect_bad(t, ELFM_ERR_RANGE, "objects.count");
    free(t);
    free(text);
  }

  /* Overrides that must change together: a stage's v0 and v1 (unequal
   * without an acceleration is refused), set one at a time the first is
   * refused; set at once they go through, and a bad key among several
   * leaves the scene as it was. */
  s = NULL;
  CHECK_OK(elfm_scene_load("stage", &s, &err), &err);
  if (s) {
    CHECK(elfm_scene_set_param(s, "motion.v0_mm_per_s=1", &err) != ELFM_OK);
    CHECK(strstr(err.message, "accel") != NULL);
    const char *both[2] = {"motion.v0_mm_per_s=1", "motion.v1_mm_per_s=1"};
    CHECK_EQ_INT(stage_beads_moved(s, 2.5), elfm_scene_n_objects(s));
    CHECK_OK(elfm_scene_set_params(s, both, 2, &err), &err);
    CHECK_EQ_INT(stage_beads_moved(s, 1.0), elfm_scene_n_objects(s));
    const char *bad[2] = {"motion.v0_mm_per_s=3", "motion.vv=3"};
    CHECK(elfm_scene_set_params(s, bad, 2, &err) == ELFM_ERR_INVALID);
    CHECK(strstr(err.message, "motion.vv") != NULL);
    CHECK_EQ_INT(stage_beads_moved(s, 1.0), elfm_scene_n_objects(s));
    CHECK_OK(elfm_scene_set_params(s, NULL, 0, &err), &err);
    CHECK(elfm_scene_set_params(s, NULL, 1, &err) == ELFM_ERR_INVALID);
    elfm_scene_free(s);
  }

  /* --param overrides. */
  s = NULL;
  CHECK_OK(elfm_scene_load("flow", &s, &err), &err);
  if (s) {
    CHECK_OK(elfm_scene_set_param(s, "objects.count=7", &err), &err);
    CHECK_EQ_INT(elfm_scene_n_objects(s), 7);
    CHECK_OK(elfm_scene_set_param(s, "duration_ms=25", &err), &err);
    CHECK_EQ_INT(elfm_scene_duration_us(s), 25000);
    CHECK_OK(elfm_scene_set_seed(s, 5, &err), &err);
    elfm_truth before, after;
    elfm_scene_truth(s, 3, 1000, &before);
    /* A failed override leaves scene, layout and seed as they were. */
    CHECK(elfm_scene_set_param(s, "sensor.width=5", &err) == ELFM_ERR_RANGE);
    CHECK(strstr(err.message, "sensor.width") != NULL);
    CHECK(elfm_scene_set_param(s, "sensor.widht=640", &err) == ELFM_ERR_INVALID);
    CHECK(strstr(err.message, "sensor.widht") != NULL);
    CHECK(elfm_scene_set_param(s, "sensor.width", &err) == ELFM_ERR_INVALID);
    CHECK(elfm_scene_set_param(s, "motion.speed_mm_per_s=fast", &err) == ELFM_ERR_FORMAT);
    CHECK_EQ_INT(elfm_scene_n_objects(s), 7);
    CHECK_EQ_INT(elfm_scene_calib(s)->sensor_width_px, 1280);
    CHECK_EQ_INT(elfm_scene_seed(s), 5);
    elfm_scene_truth(s, 3, 1000, &after);
    CHECK(before.x_um == after.x_um && before.z_um == after.z_um);
    /* A later override keeps the seed set before it. */
    CHECK_OK(elfm_scene_set_param(s, "sensor.leak_hz=0.5", &err), &err);
    CHECK_EQ_INT(elfm_scene_seed(s), 5);
    elfm_scene_truth(s, 3, 1000, &after);
    CHECK(before.x_um == after.x_um);
    /* Another seed moves the beads. */
    CHECK_OK(elfm_scene_set_seed(s, 6, &err), &err);
    elfm_scene_truth(s, 3, 1000, &after);
    CHECK(before.x_um != after.x_um);
    /* A turned lens array (optics.mla_rotation_deg, 0 in every built-in
     * scene): the scene's calibration turns; beyond 45 degrees it is refused
     * naming the key, the turn already set kept */
    const elfm_view v0 = elfm_scene_calib(s)->views[0];
    CHECK(elfm_scene_calib(s)->optics.mla_rotation_deg == 0.0);
    CHECK_OK(elfm_scene_set_param(s, "optics.mla_rotation_deg=2", &err), &err);
    const elfm_calib *ct = elfm_scene_calib(s);
    CHECK(ct->optics.mla_rotation_deg == 2.0 && ct->views[0].cx_px != v0.cx_px &&
          ct->views[0].dy_px_per_um != v0.dy_px_per_um);
    CHECK_NEAR(hypot(ct->views[0].dx_px_per_um, ct->views[0].dy_px_per_um),
               hypot(v0.dx_px_per_um, v0.dy_px_per_um), 1e-12);
    CHECK(elfm_scene_set_param(s, "optics.mla_rotation_deg=50", &err) == ELFM_ERR_RANGE);
    CHECK(strstr(err.message, "mla_rotation_deg") != NULL);
    CHECK(elfm_scene_calib(s)->optics.mla_rotation_deg == 2.0);
  }
  elfm_scene_free(s);
  elfm_scene_free(NULL);
  /* A z sweep's beads on a tilted slide (motion.tilt_deg, 0 in the
   * built-in): side by side along x, each x tan(tilt) deeper, all moving
   * together; beyond 45 degrees refused naming the key */
  elfm_scene *zs = NULL;
  CHECK_OK(elfm_scene_load("zsweep", &zs, &err), &err);
  if (zs) {
    CHECK_OK(elfm_scene_set_param(zs, "objects.count=5", &err), &err);
    CHECK_OK(elfm_scene_set_param(zs, "motion.tilt_deg=20", &err), &err);
    for (int k = 0; k < 5; k++) {
      elfm_truth t0, t1;
      elfm_scene_truth(zs, k, 0, &t0);
      elfm_scene_truth(zs, k, 100000, &t1);
      CHECK_NEAR(t0.x_um, 10.0 * (k - 2), 1e-9);
      CHECK_NEAR(t0.z_um, -90 + t0.x_um * tan(20 * M_PI / 180), 1e-9);
      CHECK_NEAR(t1.z_um - t0.z_um, 20, 1e-9); /* 0.2 mm/s for 100 ms */
    }
    CHECK(elfm_scene_set_param(zs, "motion.tilt_deg=50", &err) == ELFM_ERR_RANGE);
    CHECK(strstr(err.message, "tilt_deg") != NULL);
    /* scattered over a disc (motion.place_radius_um, 0 in the built-in:
     * the row above), as dried on a slide: 30 beads within 50 um of
     * (x_um, y_um), 10 um apart or more, each still x tan(tilt) deeper,
     * spread over the disc (not all in a row), moving together; too many
     * for the disc refused naming the count */
    CHECK_OK(elfm_scene_set_param(zs, "objects.count=30", &err), &err);
    CHECK_OK(elfm_scene_set_param(zs, "motion.tilt_deg=10", &err), &err);
    CHECK_OK(elfm_scene_set_param(zs, "motion.x_um=5", &err), &err);
    CHECK_OK(elfm_scene_set_param(zs, "motion.place_radius_um=50", &err), &err);
    double ylo = 1e9, yhi = -1e9, closest = 1e9;
    elfm_truth b[30];
    for (int k = 0; k < 30; k++) {
      elfm_truth t1;
      elfm_scene_truth(zs, k, 0, &b[k]);
      elfm_scene_truth(zs, k, 100000, &t1);
      CHECK(hypot(b[k].x_um - 5, b[k].y_um) <= 50 + 1e-9);
      CHECK_NEAR(b[k].z_um, -90 + (b[k].x_um - 5) * tan(10 * M_PI / 180), 1e-9);
      CHECK_NEAR(t1.z_um - b[k].z_um, 20, 1e-9);
      CHECK_NEAR(t1.x_um, b[k].x_um, 1e-9);
      ylo = fmin(ylo, b[k].y_um);
      yhi = fmax(yhi, b[k].y_um);
      for (int q = 0; q < k; q++) {
        const double dz = (b[k].z_um - b[q].z_um) / 4; /* SPEC 7's metric, as the placement's */
        closest = fmin(closest, sqrt(pow(b[k].x_um - b[q].x_um, 2) + pow(b[k].y_um - b[q].y_um, 2) + dz * dz));
      }
    }
    CHECK_MSG(yhi - ylo > 50, "the beads span %.1f um in y", yhi - ylo);
    CHECK_MSG(closest >= 10, "two beads %.2f um apart", closest);
    CHECK(elfm_scene_set_param(zs, "objects.count=200", &err) == ELFM_ERR_RANGE);
    CHECK(strstr(err.message, "objects.count") != NULL && strstr(err.message, "radius 50.0 um") != NULL);
    elfm_scene_free(zs);
  }
  test_placement_uniform();
  return check_report();
}
