/* test_calib.c — calibration from the paper's optics (SPEC §2 numbers),
 * projection, calib.json save -> load round trip, and bad files naming the
 * file and the key. */
#include <string.h>

#include "check.h"
#include "elfm_recon.h"

static const elfm_view *find_view(const elfm_calib *c, int i, int j)
{
  for (int k = 0; k < c->n_views; k++)
    if (c->views[k].i == i && c->views[k].j == j) return &c->views[k];
  return NULL;
}

static void write_file(const char *path, const char *text)
{
  FILE *f = fopen(path, "wb");
  if (!f) { perror(path); exit(1); }
  fputs(text, f);
  fclose(f);
}

static char *read_file(const char *path)
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

/* Replace the first occurrence of `from` in `text` by `to`; returns a new string. */
static char *replace(const char *text, const char *from, const char *to)
{
  const char *p = strstr(text, from);
  if (!p) { fprintf(stderr, "replace: '%s' not found\n", from); exit(1); }
  size_t a = (size_t)(p - text), lf = strlen(from), lt = strlen(to), n = strlen(text);
  char *r = malloc(n - lf + lt + 1);
  memcpy(r, text, a);
  memcpy(r + a, to, lt);
  memcpy(r + a + lt, p + lf, n - a - lf + 1);
  return r;
}

/* Loading `text` must fail with `code`, naming the file and `key`. */
static void expect_bad(const char *text, elfm_status code, const char *key)
{
  const char *path = "bad_calib.json";
  elfm_error err;
  elfm_calib c;
  elfm_error_clear(&err);
  write_file(path, text);
  elfm_status s = elfm_calib_load(path, &c, &err);
  char buf[1200];
  elfm_error_format(&err, buf, sizeof buf);
  CHECK_MSG(s == code, "want %s for key %s, got %s (%s)", elfm_status_str(code), key,
            elfm_status_str(s), buf);
  CHECK_MSG(strstr(buf, path) != NULL, "message names no file: %s", buf);
  if (key) CHECK_MSG(strstr(buf, key) != NULL, "message names no key '%s': %s", key, buf);
}

int main(void)
{
  elfm_error err;
  elfm_error_clear(&err);
  elfm_optics o;
  elfm_optics_default(&o);
  elfm_calib c;
  CHECK_OK(elfm_calib_from_optics(&o, 1280, 720, 4.86, &c, &err), &err);

  /* SPEC §2: M_T = 20 * 16.8 * 1.25 / 80 = 5.25; 4.86 / 5.25 = 0.9257 um/px. */
  CHECK_NEAR(c.um_per_px, 4.86 / 5.25, 1e-12);
  CHECK_NEAR(c.um_per_px, 0.926, 0.001);
  /* N = 2 * 0.75 * 80 mm / (20 * 0.6 mm) = 10 lenslets: u = 0.2 i, all 25 views lit. */
  CHECK_EQ_INT(c.n_views, 25);
  const elfm_view *v00 = find_view(&c, 0, 0), *v20 = find_view(&c, 2, 0),
                  *v22 = find_view(&c, 2, 2), *vm1 = find_view(&c, -1, 2);
  CHECK(v00 && v20 && v22 && vm1);
  if (v00 && v20 && v22 && vm1) {
    CHECK_NEAR(v00->dx_px_per_um, 0.0, 1e-15);
    CHECK_NEAR(v00->cx_px, 639.5, 1e-12);
    CHECK_NEAR(v00->cy_px, 359.5, 1e-12);
    /* Outer view (2,0): alpha = 0.75*0.4/sqrt(1 - 0.5625*0.16) = 0.31449;
     * dx = 5.25/4.86 * alpha = 0.33973 px/um. */
    double alpha20 = 0.3 / sqrt(1 - 0.5625 * 0.16);
    CHECK_NEAR(v20->dx_px_per_um, 5.25 / 4.86 * alpha20, 1e-12);
    CHECK(v20->dx_px_per_um > 0.32 && v20->dx_px_per_um < 0.36);
    CHECK_NEAR(v20->dy_px_per_um, 0.0, 1e-15);
    /* Corner (2,2): u^2 = 0.32 -> alpha = 0.3/sqrt(0.82) = 0.33129 (non-paraxial
     * makes it larger than the edge view's). */
    CHECK_NEAR(v22->dx_px_per_um, 5.25 / 4.86 * 0.3 / sqrt(1 - 0.5625 * 0.32), 1e-12);
    CHECK(v22->dx_px_per_um > v20->dx_px_per_um && v22->dx_px_per_um < 0.36);
    CHECK(vm1->dx_px_per_um < 0 && vm1->dy_px_per_um > 0);
    /* View spacing 600 um * 1.25 / 4.86 um = 154.3 px. */
    CHECK_NEAR(v20->cx_px - v00->cx_px, 2 * 600 * 1.25 / 4.86, 1e-9);
    CHECK_NEAR((v20->cx_px - v00->cx_px) / 2, 154.3, 0.1);
    /* Rows j = +-2 overhang the 720-row sensor: kept, their 144-px windows
     * reach past the last row (668.1 + 72 > 720). */
    CHECK(v22->cy_px + c.view_h_px / 2 > 720);
  }
  CHECK_EQ_INT(c.view_w_px, 144);
  CHECK_EQ_INT(elfm_calib_n_planes(&c), 101);

  /* Projection: x moves every view by x/um_per_px; z moves view (2,0) by dx*z. */
  if (v20) {
    int k20 = (int)(v20 - c.views);
    double u, v;
    elfm_calib_project(&c, k20, 9.26, -4.63, 50.0, &u, &v);
    CHECK_NEAR(u, v20->cx_px + 9.26 / c.um_per_px + 50.0 * v20->dx_px_per_um, 1e-9);
    CHECK_NEAR(v, v20->cy_px - 4.63 / c.um_per_px, 1e-9);
    CHECK_NEAR(u - v20->cx_px, 10.0025 + 16.986, 0.01);
  }

  /* NA large enough that the corner views fall outside the pupil: fewer views. */
  elfm_optics o2 = o;
  o2.na = 0.3; /* N = 4: u = 0.5 i; (2,2) has u^2 = 2 -> dark; (2,0) has u = 1 -> dark */
  elfm_calib c2;
  CHECK_OK(elfm_calib_from_optics(&o2, 1280, 720, 4.86, &c2, &err), &err);
  CHECK_EQ_INT(c2.n_views, 9); /* i^2 + j^2 < 4: the 3x3 centre */
  o2 = o;
  o2.na = 1.2; /* >= n_medium 1.0 */
  CHECK(elfm_calib_from_optics(&o2, 1280, 720, 4.86, &c2, &err) == ELFM_ERR_RANGE);

  /* Save -> load round trip is exact. */
  CHECK_OK(elfm_calib_save(&c, "calib_rt.json", &err), &err);
  elfm_calib r;
  CHECK_OK(elfm_calib_load("calib_rt.json", &r, &err), &err);
  CHECK_EQ_INT(r.n_views, c.n_views);
  CHECK_EQ_INT(r.sensor_width_px, 1280);
  CHECK_EQ_INT(r.has_optics, 1);
  CHECK(r.optics.na == o.na && r.optics.lenslets_per_side == 5);
  CHECK(r.um_per_px == c.um_per_px);
  int same = 1;
  for (int k = 0; k < c.n_views; k++) {
    same &= r.views[k].i == c.views[k].i && r.views[k].j == c.views[k].j &&
            r.views[k].cx_px == c.views[k].cx_px && r.views[k].cy_px == c.views[k].cy_px &&
            r.views[k].dx_px_per_um == c.views[k].dx_px_per_um &&
            r.views[k].dy_px_per_um == c.views[k].dy_px_per_um;
  }
  CHECK(same);
  CHECK(r.z_min_um == -100 && r.z_max_um == 100 && r.z_step_um == 2);

  /* Bit-exact even where 15 digits land within an epsilon (fuzz_calib found
   * cJSON's printer rounding 0.9257142857141429). */
  elfm_calib e = c;
  e.um_per_px = 0.9257142857141429;
  e.views[0].cx_px = 330.85802469135799;
  CHECK_OK(elfm_calib_save(&e, "calib_exact.json", &err), &err);
  CHECK_OK(elfm_calib_load("calib_exact.json", &r, &err), &err);
  CHECK(r.um_per_px == e.um_per_px && r.views[0].cx_px == e.views[0].cx_px);

  /* Bad files: each names the file and the key. */
  char *good = read_file("calib_rt.json");
  CHECK(good != NULL);
  if (good) {
    char *t;
    t = replace(good, "\"um_per_px\":", "\"um_per_pix\":");
    expect_bad(t, ELFM_ERR_FORMAT, "um_per_px");
    free(t);
    t = replace(good, "\"width\":\t1280", "\"width\":\t\"1280\"");
    expect_bad(t, ELFM_ERR_FORMAT, "sensor.width");
    free(t);
    t = replace(good, "\"width\":\t1280", "\"width\":\t1280.5");
    expect_bad(t, ELFM_ERR_FORMAT, "sensor.width");
    free(t);
    t = replace(good, "\"pixel_um\":\t4.86", "\"pixel_um\":\t-4.86");
    expect_bad(t, ELFM_ERR_RANGE, "sensor.pixel_um");
    free(t);
    t = replace(good, "\"step_um\":\t2", "\"step_um\":\t0");
    expect_bad(t, ELFM_ERR_RANGE, "z.step_um");
    free(t);
    t = replace(good, "\"step_um\":\t2", "\"step_um\":\t1e999"); /* cJSON: inf */
    expect_bad(t, ELFM_ERR_RANGE, "z.step_um");
    free(t);
    t = replace(good, "\"step_um\":\t2", "\"step_um\":\t0.01"); /* 20,001 planes */
    expect_bad(t, ELFM_ERR_RANGE, "z.step_um");
    free(t);
    t = replace(good, "\"max_um\":\t100", "\"max_um\":\t-200");
    expect_bad(t, ELFM_ERR_RANGE, "z.max_um");
    free(t);
    t = replace(good, "\"i\":\t-2", "\"i\":\t12");
    expect_bad(t, ELFM_ERR_RANGE, "views[0].i");
    free(t);
    t = replace(good, "\"i\":\t-1", "\"i\":\t-2"); /* views[1] becomes a copy of views[0] */
    expect_bad(t, ELFM_ERR_FORMAT, "views[1]");
    free(t);
    t = replace(good, "\"dx_px_per_um\":", "\"dx_px_per_um\": null, \"x\":");
    expect_bad(t, ELFM_ERR_FORMAT, "views[0].dx_px_per_um");
    free(t);
    t = replace(good, "\"na\":\t0.75", "\"na\":\t1.5");
    expect_bad(t, ELFM_ERR_RANGE, "optics.na");
    free(t);
    t = replace(good, "\"views\":", "\"viewz\":");
    expect_bad(t, ELFM_ERR_FORMAT, "views");
    free(t);
    /* Truncated JSON: format error with a byte offset. */
    size_t n = strlen(good);
    good[n / 2] = 0;
    expect_bad(good, ELFM_ERR_FORMAT, NULL);
    elfm_calib_load("bad_calib.json", &r, &err);
    CHECK(err.offset >= 0 && err.offset <= (int64_t)(n / 2));
    free(good);
  }
  expect_bad("", ELFM_ERR_FORMAT, NULL);
  expect_bad("[1,2,3]", ELFM_ERR_FORMAT, NULL);
  expect_bad("{}", ELFM_ERR_FORMAT, "sensor");
  CHECK(elfm_calib_load("no/such/calib.json", &r, &err) == ELFM_ERR_IO);
  CHECK(strstr(err.file, "no/such/calib.json") != NULL);

  /* Other planes than the file's (track / recon --z-*-um): NaN keeps a
   * value; a bad range is refused with the calibration unchanged, by the
   * same rules as the file's z object. */
  {
    elfm_calib p = c;
    CHECK_OK(elfm_calib_set_planes(&p, NAN, NAN, 4, &err), &err);
    CHECK(p.z_min_um == -100 && p.z_max_um == 100 && p.z_step_um == 4);
    CHECK_EQ_INT(elfm_calib_n_planes(&p), 51);
    CHECK_OK(elfm_calib_set_planes(&p, -20, 30, NAN, &err), &err);
    CHECK_EQ_INT(elfm_calib_n_planes(&p), 14); /* -20, -16, .., 32: 50 / 4 rounds up to 13 steps */
    CHECK_OK(elfm_calib_set_planes(&p, 5, 5, 1, &err), &err); /* one plane */
    CHECK_EQ_INT(elfm_calib_n_planes(&p), 1);
    const elfm_calib keep = p;
    CHECK(elfm_calib_set_planes(&p, 10, 0, NAN, &err) == ELFM_ERR_RANGE);
    CHECK(strstr(err.message, "z.max_um") && strstr(err.message, "below"));
    CHECK(elfm_calib_set_planes(&p, NAN, NAN, 0, &err) == ELFM_ERR_RANGE);
    CHECK(strstr(err.message, "z.step_um") != NULL);
    CHECK(elfm_calib_set_planes(&p, -100, 100, 0.01, &err) == ELFM_ERR_RANGE); /* 20,001 planes */
    CHECK(strstr(err.message, "4096") != NULL);
    CHECK(elfm_calib_set_planes(&p, INFINITY, NAN, NAN, &err) == ELFM_ERR_RANGE);
    CHECK(elfm_calib_set_planes(&p, NAN, 2e4, NAN, &err) == ELFM_ERR_RANGE);
    CHECK(elfm_calib_set_planes(&p, NAN, NAN, -1, &err) == ELFM_ERR_RANGE);
    CHECK(p.z_min_um == keep.z_min_um && p.z_max_um == keep.z_max_um && p.z_step_um == keep.z_step_um);
  }

  /* A lens array turned against the sensor's rows (optics.mla_rotation_deg):
   * centres and disparities turn about the sensor's centre, the lit views
   * and the images' scale stay. The file keeps the angle; an aligned
   * array's file has no such key (the bytes it had before). */
  {
    elfm_optics ot = o;
    ot.mla_rotation_deg = 2.0;
    elfm_calib t;
    CHECK_OK(elfm_calib_from_optics(&ot, 1280, 720, 4.86, &t, &err), &err);
    CHECK_EQ_INT(t.n_views, c.n_views);
    CHECK(t.um_per_px == c.um_per_px);
    const double a = 2.0 * 3.14159265358979323846 / 180.0;
    const elfm_view *t20 = find_view(&t, 2, 0), *t02 = find_view(&t, 0, 2), *c20 = find_view(&c, 2, 0);
    CHECK(t20 && t02 && c20);
    if (t20 && t02 && c20) {
      const double s2 = 2 * 600 * 1.25 / 4.86; /* two lenslets' spacing, px */
      CHECK_NEAR(t20->cx_px, 639.5 + s2 * cos(a), 1e-9);
      CHECK_NEAR(t20->cy_px, 359.5 + s2 * sin(a), 1e-9); /* y down: the view moves down */
      CHECK_NEAR(t02->cx_px, 639.5 - s2 * sin(a), 1e-9);
      CHECK_NEAR(t20->dx_px_per_um, c20->dx_px_per_um * cos(a), 1e-12);
      CHECK_NEAR(t20->dy_px_per_um, c20->dx_px_per_um * sin(a), 1e-12);
      CHECK_NEAR(hypot(t02->dx_px_per_um, t02->dy_px_per_um), c20->dx_px_per_um, 1e-12);
    }
    CHECK_OK(elfm_calib_save(&t, "calib_turned.json", &err), &err);
    CHECK_OK(elfm_calib_load("calib_turned.json", &r, &err), &err);
    CHECK(r.optics.mla_rotation_deg == 2.0 && r.views[3].dy_px_per_um == t.views[3].dy_px_per_um);
    char *tt = read_file("calib_turned.json"), *aligned = read_file("calib_rt.json");
    CHECK(tt && strstr(tt, "\"mla_rotation_deg\"") && aligned && !strstr(aligned, "mla_rotation_deg"));
    if (tt) {
      char *b = replace(tt, "\"mla_rotation_deg\":\t2", "\"mla_rotation_deg\":\t50");
      expect_bad(b, ELFM_ERR_RANGE, "optics.mla_rotation_deg");
      free(b);
      b = replace(tt, "\"mla_rotation_deg\":\t2", "\"mla_rotation_deg\":\t\"2\"");
      expect_bad(b, ELFM_ERR_FORMAT, "optics.mla_rotation_deg");
      free(b);
    }
    free(tt);
    free(aligned);
    ot.mla_rotation_deg = 46;
    CHECK(elfm_calib_from_optics(&ot, 1280, 720, 4.86, &t, &err) == ELFM_ERR_RANGE);
    CHECK(strstr(err.message, "mla_rotation_deg") != NULL);
    ot.mla_rotation_deg = NAN;
    CHECK(elfm_calib_from_optics(&ot, 1280, 720, 4.86, &t, &err) == ELFM_ERR_RANGE);
  }

  /* optics is optional: a file without it loads, has_optics = 0. */
  c.has_optics = 0;
  CHECK_OK(elfm_calib_save(&c, "calib_noopt.json", &err), &err);
  CHECK_OK(elfm_calib_load("calib_noopt.json", &r, &err), &err);
  CHECK_EQ_INT(r.has_optics, 0);
  return check_report();
}
