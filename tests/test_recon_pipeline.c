/* test_recon_pipeline.c — the streaming driver end to end on a synthetic
 * EVT3 recording (a bead moving through the paper's Fourier LFM, events
 * rendered with the SPEC §2 projection, plus isolated noise events):
 * in-order volumes, thread-count independence, time ranges, peak accuracy,
 * errors; EXR round trip, MIP PNG, TIFF stacks (good and corrupt). */
#include <math.h>
#include <png.h>
#include <stdlib.h>
#include <string.h>
#include <tiffio.h>
#include <time.h>
#include <unistd.h>

#include "check.h"
#include "elfm_recon.h"

#define T0_US 5800000 /* real EVT3 files start at 5.8 s (SPEC §1) */
#define DUR_US 30000

static void bead_at(int64_t t, double *x, double *y, double *z)
{
  double s = (double)(t - T0_US) / DUR_US;
  *x = -10.0 + 20.0 * s;
  *y = 8.0 - 10.0 * s;
  *z = -30.0 + 60.0 * s;
}

static int write_events(const char *path, const elfm_calib *c, int64_t *n_written)
{
  elfm_error err;
  elfm_writer *w = NULL;
  if (elfm_writer_open(path, ELFM_FMT_EVT3, c->sensor_width_px, c->sensor_height_px, &w, &err)) return 0;
  elfm_event_chunk *ch = elfm_chunk_create(8192, &err);
  uint32_t s = 42;
  *n_written = 0;
  for (int64_t t = T0_US; t < T0_US + DUR_US; t += 50) {
    ch->n = 0;
    double x, y, z;
    bead_at(t, &x, &y, &z);
    for (int v = 0; v < c->n_views; v++) {
      double u, vv;
      elfm_calib_project(c, v, x, y, z, &u, &vv);
      for (int py = (int)floor(vv) - 2; py <= (int)floor(vv) + 2; py++)
        for (int px = (int)floor(u) - 2; px <= (int)floor(u) + 2; px++) {
          if (px < 0 || py < 0 || px >= c->sensor_width_px || py >= c->sensor_height_px) continue;
          if ((px - u) * (px - u) + (py - vv) * (py - vv) > 2.25) continue;
          ch->t_us[ch->n] = t;
          ch->x[ch->n] = (uint16_t)px;
          ch->y[ch->n] = (uint16_t)py;
          ch->p[ch->n] = 1;
          ch->n++;
        }
    }
    for (int k = 0; k < 20; k++) { /* isolated noise: the median removes it */
      s = s * 1664525u + 1013904223u;
      ch->t_us[ch->n] = t;
      ch->x[ch->n] = (uint16_t)((s >> 8) % (uint32_t)c->sensor_width_px);
      ch->y[ch->n] = (uint16_t)((s >> 20) % (uint32_t)c->sensor_height_px);
      ch->p[ch->n] = (uint8_t)(s >> 31);
      ch->n++;
    }
    *n_written += (int64_t)ch->n;
    if (elfm_writer_write(w, ch, &err)) return 0;
  }
  elfm_chunk_free(ch);
  return elfm_writer_close(w, &err) == ELFM_OK;
}

typedef struct collect {
  int n;
  int64_t frames[256], t_us[256];
  double sum[256];
  int bad_peaks;
  int fail_at; /* return an error at this volume (-1: never) */
  elfm_volume *keep;  /* a copy of volume 15 */
} collect;

static elfm_status on_volume(const elfm_volume *v, void *user, elfm_error *err)
{
  collect *c = user;
  if (c->n == c->fail_at) return elfm_error_set(err, ELFM_ERR_INVALID, NULL, -1, "stop here");
  if (c->n < 256) {
    double sum = 0;
    size_t n = (size_t)v->w * v->h * v->nz, best = 0;
    for (size_t i = 0; i < n; i++) {
      sum += v->data[i] * (1.0 + (double)(i % 7));
      if (v->data[i] > v->data[best]) best = i;
    }
    c->frames[c->n] = v->frame;
    c->t_us[c->n] = v->t_us;
    c->sum[c->n] = sum;
    double x, y, z;
    bead_at(v->t_us, &x, &y, &z);
    int X = (int)(best % (size_t)v->w), Y = (int)(best / (size_t)v->w % (size_t)v->h);
    int k = (int)(best / ((size_t)v->w * v->h));
    double ex = elfm_volume_x_um(v, X) - x, ey = elfm_volume_y_um(v, Y) - y;
    double ez = elfm_volume_z_um(v, k) - z;
    /* one voxel laterally, one plane axially (+ rounding of the voxel grid) */
    if (fabs(ex) > 1.5 * v->um_per_px || fabs(ey) > 1.5 * v->um_per_px || fabs(ez) > 1.5 * v->z_step_um) {
      c->bad_peaks++;
      fprintf(stderr, "frame %lld t %lld: peak error (%.2f, %.2f, %.2f) um\n", (long long)v->frame,
              (long long)v->t_us, ex, ey, ez);
    }
    if (c->n == 15 && c->keep) {
      memcpy(c->keep->data, v->data, n * sizeof *v->data);
      c->keep->t_us = v->t_us;
      c->keep->frame = v->frame;
    }
  }
  c->n++;
  return ELFM_OK;
}

static void test_runs(const char *dir, const elfm_calib *cal)
{
  elfm_error err;
  char path[600];
  snprintf(path, sizeof path, "%s/events.raw", dir);
  int64_t n_written = 0;
  CHECK(write_events(path, cal, &n_written));
  elfm_recon_options o;
  elfm_recon_options_default(&o);
  static collect c1, c2;
  memset(&c1, 0, sizeof c1);
  memset(&c2, 0, sizeof c2);
  c1.fail_at = c2.fail_at = -1;
  c1.keep = elfm_volume_create(cal->view_w_px, cal->view_h_px, elfm_calib_n_planes(cal), 1, 0, 1, &err);
  elfm_recon_stats st;
  o.threads = 1;
  o.chunk_events = 5000; /* many chunks: windows span chunk boundaries */
  CHECK_OK(elfm_recon_run(path, cal, &o, on_volume, &c1, &st, &err), &err);
  CHECK_EQ_INT(st.events, n_written);
  CHECK_EQ_INT(st.frames, DUR_US / 1000);
  CHECK_EQ_INT(c1.n, DUR_US / 1000);
  CHECK(st.frames_sparse == st.frames); /* a few hundred pixels per frame */
  CHECK(st.realtime_factor > 0 && st.volumes_per_s > 0);
  CHECK_NEAR(st.span_s, DUR_US * 1e-6, 1e-9);
  for (int i = 0; i < c1.n && i < 256; i++) {
    CHECK_EQ_INT(c1.frames[i], i);
    CHECK_EQ_INT(c1.t_us[i], T0_US + 1000 * (i + 1));
  }
  CHECK_MSG(c1.bad_peaks == 0, "%d of %d peaks off", c1.bad_peaks, c1.n);
  printf("1 thread: %.0f volumes/s, %.2f x real time\n", st.volumes_per_s, st.realtime_factor);

  /* 2 threads, batches of 3, dense path (first 12 ms: dense is slow
   * under the sanitizers): the same volumes in the same order */
  o.threads = 2;
  o.batch = 3;
  o.refocus.path = ELFM_PATH_DENSE;
  o.to_us = T0_US + 12000;
  CHECK_OK(elfm_recon_run(path, cal, &o, on_volume, &c2, &st, &err), &err);
  CHECK_EQ_INT(c2.n, 12);
  CHECK(st.frames_dense == st.frames);
  for (int i = 0; i < c2.n && i < 256; i++) {
    CHECK_EQ_INT(c2.frames[i], c1.frames[i]);
    CHECK_NEAR(c2.sum[i], c1.sum[i], 1e-4 * fabs(c1.sum[i]));
  }

  /* a time range: windows start at from_us */
  memset(&c2, 0, sizeof c2);
  c2.fail_at = -1;
  o.from_us = T0_US + 10000;
  o.to_us = T0_US + 20000;
  o.refocus.path = ELFM_PATH_AUTO;
  CHECK_OK(elfm_recon_run(path, cal, &o, on_volume, &c2, &st, &err), &err);
  CHECK_EQ_INT(c2.n, 10);
  CHECK_EQ_INT(c2.t_us[0], T0_US + 11000);
  CHECK(st.events < n_written / 2 && st.events > n_written / 4);
  for (int i = 0; i < 10; i++) CHECK_NEAR(c2.sum[i], c1.sum[i + 10], 1e-4 * fabs(c1.sum[i + 10]));

  /* the callback's error stops the run and comes back */
  memset(&c2, 0, sizeof c2);
  c2.fail_at = 4;
  elfm_recon_options_default(&o);
  CHECK(elfm_recon_run(path, cal, &o, on_volume, &c2, &st, &err) == ELFM_ERR_INVALID);
  CHECK(strstr(err.message, "stop here") != NULL);
  CHECK_EQ_INT(c2.n, 4); /* volumes 0..3 delivered, the 5th refused */
  CHECK_EQ_INT(st.input_error, 0); /* the caller's error, not the input's */

  /* bad inputs */
  char missing[700];
  snprintf(missing, sizeof missing, "%s/nothing.raw", dir);
  CHECK(elfm_recon_run(missing, cal, &o, on_volume, &c2, NULL, &err) == ELFM_ERR_IO);
  CHECK(strstr(err.file, "nothing.raw") != NULL);
  elfm_calib small = *cal;
  small.sensor_width_px = 640;
  small.sensor_height_px = 480;
  CHECK(elfm_recon_run(path, &small, &o, on_volume, &c2, NULL, &err) == ELFM_ERR_INVALID);
  CHECK(strstr(err.message, "640") != NULL);
  o.median = 4;
  CHECK(elfm_recon_run(path, cal, &o, on_volume, &c2, NULL, &err) == ELFM_ERR_INVALID);
  elfm_recon_options_default(&o);
  o.blur_px = 3;
  CHECK(elfm_recon_run(path, cal, &o, on_volume, &c2, NULL, &err) == ELFM_ERR_INVALID);
  CHECK(strstr(err.message, "blur 3") != NULL);
  elfm_recon_options_default(&o);
  o.from_us = 10;
  o.to_us = 5;
  CHECK(elfm_recon_run(path, cal, &o, on_volume, &c2, NULL, &err) == ELFM_ERR_INVALID);
  /* A truncated recording: every volume before the damage, then the
   * error. Of two cuts a byte apart one ends on a word boundary (a shorter
   * recording, no error) and the other inside a word: that one must give
   * the same volumes (the events of its last chunk, decoded before the
   * error, framed to the end as the clean cut's), then the error naming
   * file and byte. */
  static collect cc[2];
  elfm_status sc[2];
  elfm_error ec[2];
  elfm_recon_stats stc[2];
  for (int k = 0; k < 2; k++) {
    char cut[700];
    snprintf(cut, sizeof cut, "%s/cut%d.raw", dir, k);
    FILE *in = fopen(path, "rb"), *out = fopen(cut, "wb");
    char buf[4096];
    size_t n, total = 0;
    const size_t want = 200000 + (size_t)k;
    while (in && out && total < want && (n = fread(buf, 1, sizeof buf, in)) > 0) {
      if (n > want - total) n = want - total;
      fwrite(buf, 1, n, out);
      total += n;
    }
    if (in) fclose(in);
    if (out) fclose(out);
    memset(&cc[k], 0, sizeof cc[k]);
    cc[k].fail_at = -1;
    elfm_recon_options_default(&o);
    o.chunk_events = 1 << 20; /* the whole cut in one chunk: the damage is in it */
    elfm_error_clear(&ec[k]);
    sc[k] = elfm_recon_run(cut, cal, &o, on_volume, &cc[k], &stc[k], &ec[k]);
  }
  CHECK_MSG((sc[0] == ELFM_OK) != (sc[1] == ELFM_OK), "cuts a byte apart: %d and %d", sc[0], sc[1]);
  const int bad = sc[0] != ELFM_OK ? 0 : 1, good = 1 - bad;
  CHECK(sc[bad] == ELFM_ERR_FORMAT);
  CHECK(strstr(ec[bad].file, bad ? "cut1.raw" : "cut0.raw") != NULL);
  CHECK(ec[bad].offset > 0);
  /* the run says the error was its input's, so callers may keep what came */
  CHECK_EQ_INT(stc[bad].input_error, 1);
  CHECK_EQ_INT(stc[good].input_error, 0);
  CHECK(cc[good].n > 0 && cc[good].n < c1.n);
  CHECK_EQ_INT(cc[bad].n, cc[good].n);
  CHECK_EQ_INT(stc[bad].events, stc[good].events);
  for (int i = 0; i < cc[good].n && i < 256; i++) {
    CHECK_EQ_INT(cc[bad].frames[i], cc[good].frames[i]);
    CHECK(cc[bad].sum[i] == cc[good].sum[i]);
  }

  /* EXR round trip and MIP of the kept volume */
  char exr[700], png[700];
  snprintf(exr, sizeof exr, "%s/v.exr", dir);
  snprintf(png, sizeof png, "%s/v.png", dir);
  c1.keep->um_per_px = cal->um_per_px;
  c1.keep->z_min_um = cal->z_min_um;
  c1.keep->z_step_um = cal->z_step_um;
  CHECK_OK(elfm_volume_write_exr(c1.keep, exr, &err), &err);
  elfm_volume *back = NULL;
  CHECK_OK(elfm_volume_read_exr(exr, &back, &err), &err);
  if (back) {
    CHECK_EQ_INT(back->w, c1.keep->w);
    CHECK_EQ_INT(back->nz, c1.keep->nz);
    CHECK_EQ_INT(back->t_us, c1.keep->t_us);
    CHECK_EQ_INT(back->frame, 15);
    CHECK_NEAR(back->um_per_px, cal->um_per_px, 0);
    CHECK_NEAR(back->z_min_um, cal->z_min_um, 0);
    CHECK_NEAR(back->z_step_um, cal->z_step_um, 0);
    size_t nv = (size_t)back->w * back->h * back->nz, diff = 0, nonzero = 0;
    for (size_t i = 0; i < nv; i++) {
      diff += back->data[i] != c1.keep->data[i];
      nonzero += back->data[i] != 0.0f;
    }
    CHECK_EQ_INT(diff, 0);
    CHECK(nonzero > 0);
    elfm_volume_free(back);
  }
  CHECK(elfm_volume_read_exr(path, &back, &err) != ELFM_OK && back == NULL); /* not an EXR */
  CHECK(strstr(err.file, "events.raw") != NULL);
  /* a cut EXR: an error naming the file, no crash */
  {
    char cut_exr[700];
    snprintf(cut_exr, sizeof cut_exr, "%s/cut.exr", dir);
    FILE *ie = fopen(exr, "rb"), *oe = fopen(cut_exr, "wb");
    if (ie && oe) {
      fseek(ie, 0, SEEK_END);
      long len = ftell(ie);
      fseek(ie, 0, SEEK_SET);
      for (long i = 0; i < len / 2; i++) fputc(fgetc(ie), oe);
    }
    if (ie) fclose(ie);
    if (oe) fclose(oe);
    elfm_status se = elfm_volume_read_exr(cut_exr, &back, &err);
    CHECK(se != ELFM_OK && back == NULL);
    CHECK(strstr(err.file, "cut.exr") != NULL);
    elfm_volume_free(back);
    back = NULL;
  }
  CHECK_OK(elfm_volume_write_mip_png(c1.keep, png, 0, 1, &err), &err);
  png_image im;
  memset(&im, 0, sizeof im);
  im.version = PNG_IMAGE_VERSION;
  CHECK(png_image_begin_read_from_file(&im, png));
  CHECK_EQ_INT(im.width, (unsigned)(c1.keep->w + c1.keep->nz));
  CHECK_EQ_INT(im.height, (unsigned)(c1.keep->h + c1.keep->nz));
  im.format = PNG_FORMAT_RGB;
  uint8_t *rgb = malloc(PNG_IMAGE_SIZE(im));
  CHECK(png_image_finish_read(&im, NULL, rgb, 0, NULL));
  /* the brightest x-y pixel: full value, coloured by the bead's depth */
  double x, y, z;
  bead_at(c1.keep->t_us, &x, &y, &z);
  int best = 0;
  for (int i = 0; i < (int)(im.width * im.height); i++) {
    int a = rgb[3 * i] + rgb[3 * i + 1] + rgb[3 * i + 2];
    int b = rgb[3 * best] + rgb[3 * best + 1] + rgb[3 * best + 2];
    if (a > b && i % (int)im.width < c1.keep->w && i / (int)im.width < c1.keep->h) best = i;
  }
  int bx = best % (int)im.width, by = best / (int)im.width;
  CHECK(fabs(elfm_volume_x_um(c1.keep, bx) - x) < 3 && fabs(elfm_volume_y_um(c1.keep, by) - y) < 3);
  CHECK(z < 0 ? rgb[3 * best + 2] >= rgb[3 * best] : rgb[3 * best] >= rgb[3 * best + 2]); /* blue low, red high */
  free(rgb);
  char bad_png[700];
  snprintf(bad_png, sizeof bad_png, "%s/no/such/dir/v.png", dir);
  CHECK(elfm_volume_write_mip_png(c1.keep, bad_png, 0, 1, &err) == ELFM_ERR_IO);
  CHECK(elfm_volume_write_exr(c1.keep, bad_png, &err) != ELFM_OK);
  elfm_volume_free(c1.keep);
}

static elfm_status count_tiff(const elfm_volume *v, void *user, elfm_error *err)
{
  (void)err;
  collect *c = user;
  size_t n = (size_t)v->w * v->h * v->nz, best = 0;
  for (size_t i = 0; i < n; i++)
    if (v->data[i] > v->data[best]) best = i;
  if (c->n < 256) {
    c->frames[c->n] = (int64_t)best;
    c->t_us[c->n] = v->t_us;
  }
  c->n++;
  return ELFM_OK;
}

static void test_tiff(const char *dir, const elfm_calib *cal)
{
  elfm_error err;
  char path[600];
  snprintf(path, sizeof path, "%s/lf.tif", dir);
  elfm_frame *f = elfm_frame_create(cal->sensor_width_px, cal->sensor_height_px, &err);
  elfm_tiff_writer *w = NULL;
  CHECK_OK(elfm_tiff_writer_open(path, &w, &err), &err);
  const double zs[3] = {-60, 0, 45};
  for (int p = 0; p < 3; p++) {
    elfm_frame_clear(f);
    for (int i = 0; i < f->w * f->h; i++) { /* camera offset */
      f->data[i] = 100.0f;
      f->idx[i] = (uint32_t)i;
    }
    f->nnz = (size_t)f->w * f->h;
    for (int v = 0; v < cal->n_views; v++) {
      double u, vv;
      elfm_calib_project(cal, v, 12.0, -7.0, zs[p], &u, &vv);
      for (int py = (int)vv - 3; py <= (int)vv + 3; py++)
        for (int px = (int)u - 3; px <= (int)u + 3; px++) {
          if (px < 0 || py < 0 || px >= f->w || py >= f->h) continue;
          double d2 = (px - u) * (px - u) + (py - vv) * (py - vv);
          f->data[py * f->w + px] += (float)(3000.0 * exp(-d2 / 3.0));
        }
    }
    CHECK_OK(elfm_tiff_writer_add(w, f, &err), &err);
  }
  CHECK_OK(elfm_tiff_writer_close(w, &err), &err);
  elfm_recon_options o;
  elfm_recon_options_default(&o);
  o.median = 0;
  o.tiff_frame_us = 10000; /* a 100 Hz sCMOS */
  collect c;
  memset(&c, 0, sizeof c);
  elfm_recon_stats st;
  CHECK_OK(elfm_recon_run_tiff(path, cal, &o, count_tiff, &c, &st, &err), &err);
  CHECK_EQ_INT(c.n, 3);
  CHECK_EQ_INT(st.frames_dense, 3);
  for (int p = 0; p < 3 && p < c.n; p++) {
    int W = cal->view_w_px, H = cal->view_h_px;
    int X = (int)(c.frames[p] % W), Y = (int)(c.frames[p] / W % H), k = (int)(c.frames[p] / ((int64_t)W * H));
    double x = (X - 0.5 * (W - 1)) * cal->um_per_px, y = (Y - 0.5 * (H - 1)) * cal->um_per_px;
    double z = cal->z_min_um + k * cal->z_step_um;
    CHECK_MSG(fabs(x - 12) <= 1.5 * cal->um_per_px && fabs(y + 7) <= 1.5 * cal->um_per_px &&
                  fabs(z - zs[p]) <= 1.5 * cal->z_step_um,
              "TIFF page %d: peak (%.1f, %.1f, %.1f)", p, x, y, z);
    CHECK_EQ_INT(c.t_us[p], 5000 + 10000 * p);
  }
  /* a cut TIFF: error naming the file, no crash */
  char cut[700];
  snprintf(cut, sizeof cut, "%s/cut.tif", dir);
  FILE *in = fopen(path, "rb"), *out = fopen(cut, "wb");
  char buf[4096];
  size_t n, total = 0;
  while ((n = fread(buf, 1, sizeof buf, in)) > 0 && total < 1000000) {
    fwrite(buf, 1, n, out);
    total += n;
  }
  fclose(in);
  fclose(out);
  memset(&c, 0, sizeof c);
  elfm_status s = elfm_recon_run_tiff(cut, cal, &o, count_tiff, &c, NULL, &err);
  CHECK(s != ELFM_OK);
  CHECK(strstr(err.file, "cut.tif") != NULL);
  char junk[700];
  snprintf(junk, sizeof junk, "%s/junk.tif", dir);
  out = fopen(junk, "wb");
  fputs("II*\0 this is not really a tiff", out);
  fclose(out);
  CHECK(elfm_recon_run_tiff(junk, cal, &o, count_tiff, &c, NULL, &err) == ELFM_ERR_FORMAT);
  CHECK(strstr(err.file, "junk.tif") != NULL);
  elfm_frame_free(f);
}

/* A stack whose pages differ in sample size (an 8-bit page 0, then a 32-bit
 * float page of the same size): each page is read into the frame with its
 * values. The reader sized its scanline buffer from page 0 and libtiff wrote
 * the wider page's rows past it (a heap overflow libFuzzer found; under
 * ASan this test fails without the fix). */
static void test_tiff_mixed_depth(const char *dir)
{
  char path[600];
  snprintf(path, sizeof path, "%s/mixed.tif", dir);
  const int W = 37, H = 5;
  TIFF *t = TIFFOpen(path, "w");
  CHECK(t != NULL);
  if (!t) return;
  for (int page = 0; page < 2; page++) {
    const int bits = page ? 32 : 8;
    TIFFSetField(t, TIFFTAG_IMAGEWIDTH, (uint32_t)W);
    TIFFSetField(t, TIFFTAG_IMAGELENGTH, (uint32_t)H);
    TIFFSetField(t, TIFFTAG_SAMPLESPERPIXEL, (uint16_t)1);
    TIFFSetField(t, TIFFTAG_BITSPERSAMPLE, (uint16_t)bits);
    TIFFSetField(t, TIFFTAG_SAMPLEFORMAT, (uint16_t)(page ? SAMPLEFORMAT_IEEEFP : SAMPLEFORMAT_UINT));
    TIFFSetField(t, TIFFTAG_PHOTOMETRIC, (uint16_t)PHOTOMETRIC_MINISBLACK);
    TIFFSetField(t, TIFFTAG_PLANARCONFIG, (uint16_t)PLANARCONFIG_CONTIG);
    TIFFSetField(t, TIFFTAG_ROWSPERSTRIP, (uint32_t)1);
    for (int y = 0; y < H; y++) {
      uint8_t row8[64];
      float rowf[64];
      for (int x = 0; x < W; x++) {
        row8[x] = (uint8_t)(x + y);
        rowf[x] = 1000.5f + (float)(x * y);
      }
      CHECK(TIFFWriteScanline(t, page ? (void *)rowf : (void *)row8, (uint32_t)y, 0) == 1);
    }
    CHECK(TIFFWriteDirectory(t) == 1);
  }
  TIFFClose(t);
  elfm_error err;
  elfm_tiff_stack *s = NULL;
  CHECK_OK(elfm_tiff_open(path, &s, &err), &err);
  if (!s) return;
  elfm_frame *f = elfm_frame_create(W, H, &err);
  int got = 0;
  CHECK_OK(elfm_tiff_read(s, f, &got, &err), &err);
  CHECK_EQ_INT(got, 1);
  CHECK(f->data[3 * W + 7] == 10.0f);
  CHECK_OK(elfm_tiff_read(s, f, &got, &err), &err);
  CHECK_EQ_INT(got, 1);
  CHECK_MSG(f->data[3 * W + 7] == 1021.5f, "page 1 value %g", f->data[3 * W + 7]);
  CHECK_OK(elfm_tiff_read(s, f, &got, &err), &err);
  CHECK_EQ_INT(got, 0);
  elfm_frame_free(f);
  elfm_tiff_close(s);
}

/* The worker hook: called once per volume on a worker thread with the
 * volume's slot; the ordered callback then gets that slot, in frame order.
 * The worker stores a weighted sum and the frame per slot; the ordered side
 * recomputes both from the volume it is handed. */
#define HOOK_SLOTS 3
typedef struct hook_ctx {
  int threads, slots;
  int64_t slot_frame[HOOK_SLOTS];
  double slot_sum[HOOK_SLOTS];
  int bad_args;        /* written by workers: only ever set to 1 */
  int64_t fail_frame;  /* worker refuses this frame (-1: none) */
  int64_t n, next_frame, mismatches;
} hook_ctx;

static double weighted_sum(const elfm_volume *v)
{
  double sum = 0;
  size_t n = (size_t)v->w * v->h * v->nz;
  for (size_t i = 0; i < n; i++) sum += v->data[i] * (1.0 + (double)(i % 7));
  return sum;
}

static elfm_status hook_worker(const elfm_volume *v, const elfm_frame *frame,
                               const elfm_refocus_plan *plan, int slot, int thread, void *user,
                               elfm_error *err)
{
  hook_ctx *h = user;
  /* the frame the volume came from, and the run's plan */
  if (!frame || !plan || frame->t_us != v->t_us || slot < 0 || slot >= h->slots ||
      thread < 0 || thread >= h->threads) {
#pragma omp atomic write
    h->bad_args = 1;
    return elfm_error_set(err, ELFM_ERR_INVALID, NULL, -1, "slot %d thread %d", slot, thread);
  }
  if (v->frame == h->fail_frame)
    return elfm_error_set(err, ELFM_ERR_NUMERIC, NULL, -1, "worker refused frame %lld", (long long)v->frame);
  h->slot_frame[slot] = v->frame;
  h->slot_sum[slot] = weighted_sum(v);
  return ELFM_OK;
}

static elfm_status hook_ordered(const elfm_volume *v, int slot, void *user, elfm_error *err)
{
  (void)err;
  hook_ctx *h = user;
  if (slot < 0 || slot >= HOOK_SLOTS || h->slot_frame[slot] != v->frame ||
      h->slot_sum[slot] != weighted_sum(v) || v->frame != h->next_frame)
    h->mismatches++;
  h->next_frame = v->frame + 1;
  h->n++;
  return ELFM_OK;
}

static elfm_status hook_unused(const elfm_volume *v, void *user, elfm_error *err)
{
  (void)v;
  (void)user;
  return elfm_error_set(err, ELFM_ERR_INVALID, NULL, -1, "on_volume called beside on_volume_slot");
}

/* no_refocus: the same frames, in the same order, with the same times, and
 * volumes that carry the frame's times and the plan's geometry. */
typedef struct frames_only_ctx {
  const elfm_calib *cal;
  int64_t t_us[64], t_end_us[64], n_events[64];
  int64_t slot_frame[HOOK_SLOTS];
  int64_t n, next_frame, mismatches;
  int bad_args;
} frames_only_ctx;

static elfm_status fo_worker(const elfm_volume *v, const elfm_frame *frame,
                             const elfm_refocus_plan *plan, int slot, int thread, void *user,
                             elfm_error *err)
{
  (void)plan, (void)thread, (void)err;
  frames_only_ctx *h = user;
  if (!frame || slot < 0 || slot >= HOOK_SLOTS || frame->t_us != v->t_us ||
      frame->index != v->frame || frame->t_end_us != v->t_end_us ||
      frame->n_events != v->n_events || v->um_per_px != h->cal->um_per_px ||
      v->z_min_um != h->cal->z_min_um || v->z_step_um != h->cal->z_step_um) {
#pragma omp atomic write
    h->bad_args = 1;
    return ELFM_OK;
  }
  h->slot_frame[slot] = v->frame;
  return ELFM_OK;
}

static elfm_status fo_ordered(const elfm_volume *v, int slot, void *user, elfm_error *err)
{
  (void)err;
  frames_only_ctx *h = user;
  if (slot < 0 || slot >= HOOK_SLOTS || h->slot_frame[slot] != v->frame || v->frame != h->next_frame)
    h->mismatches++;
  if (v->frame >= 0 && v->frame < 64) {
    h->t_us[v->frame] = v->t_us;
    h->t_end_us[v->frame] = v->t_end_us;
    h->n_events[v->frame] = v->n_events;
  }
  h->next_frame = v->frame + 1;
  h->n++;
  return ELFM_OK;
}

static void test_no_refocus(const char *dir, const elfm_calib *cal)
{
  elfm_error err;
  char path[600];
  snprintf(path, sizeof path, "%s/events.raw", dir);
  frames_only_ctx run[2];
  for (int k = 0; k < 2; k++) {
    elfm_recon_options o;
    elfm_recon_options_default(&o);
    o.threads = 2;
    o.batch = HOOK_SLOTS;
    o.no_refocus = k;
    o.worker = fo_worker;
    o.worker_user = &run[k];
    o.on_volume_slot = fo_ordered;
    memset(&run[k], 0, sizeof run[k]);
    run[k].cal = cal;
    elfm_recon_stats st;
    CHECK_OK(elfm_recon_run(path, cal, &o, NULL, &run[k], &st, &err), &err);
    CHECK_EQ_INT(run[k].n, DUR_US / 1000);
    /* frames refocused by either path, or (no_refocus) by none */
    CHECK_EQ_INT(st.frames_sparse + st.frames_dense, (k ? 0 : DUR_US / 1000));
    CHECK_EQ_INT(run[k].mismatches, 0);
    CHECK_EQ_INT(run[k].bad_args, 0);
  }
  int same = 1;
  for (int f = 0; f < DUR_US / 1000 && f < 64; f++)
    same &= run[0].t_us[f] == run[1].t_us[f] && run[0].t_end_us[f] == run[1].t_end_us[f] &&
            run[0].n_events[f] == run[1].n_events[f] && run[1].n_events[f] > 0;
  CHECK_MSG(same, "no_refocus: frames differ from the refocusing run's");
}

static void test_worker_hook(const char *dir, const elfm_calib *cal)
{
  elfm_error err;
  char path[600];
  snprintf(path, sizeof path, "%s/events.raw", dir);
  elfm_recon_options o;
  elfm_recon_options_default(&o);
  o.threads = 2;
  o.batch = HOOK_SLOTS; /* 30 volumes: 10 batches of 3 */
  hook_ctx h;
  memset(&h, 0, sizeof h);
  h.fail_frame = -1;
  CHECK_OK(elfm_recon_layout(&o, &h.threads, &h.slots, &err), &err);
  CHECK_EQ_INT(h.threads, 2);
  CHECK_EQ_INT(h.slots, HOOK_SLOTS);
  o.worker = hook_worker;
  o.worker_user = &h;
  o.on_volume_slot = hook_ordered;
  elfm_recon_stats st;
  /* on_volume is ignored when on_volume_slot is set: pass one that fails */
  CHECK_OK(elfm_recon_run(path, cal, &o, hook_unused, &h, &st, &err), &err);
  CHECK_EQ_INT(h.n, DUR_US / 1000);
  CHECK_EQ_INT(st.frames, DUR_US / 1000);
  CHECK_EQ_INT(h.mismatches, 0);
  CHECK_EQ_INT(h.bad_args, 0);

  /* a worker's error stops the run: frames before it are delivered */
  memset(&h, 0, sizeof h);
  h.threads = 2;
  h.slots = HOOK_SLOTS;
  h.fail_frame = 7;
  CHECK(elfm_recon_run(path, cal, &o, NULL, &h, &st, &err) == ELFM_ERR_NUMERIC);
  CHECK(strstr(err.message, "worker refused frame 7") != NULL);
  CHECK_EQ_INT(h.n, 7);
  CHECK_EQ_INT(h.mismatches, 0);

  /* layout errors */
  o.threads = -1;
  CHECK(elfm_recon_layout(&o, &h.threads, &h.slots, &err) == ELFM_ERR_INVALID);
}

/* The pipeline's stages at once. With a slow callback (2 ms a volume) and
 * 2 threads, workers run while a callback does, and yet no two callbacks
 * ever run at once and they come in frame order (the batch pipeline this
 * replaced never ran a worker during a callback: there that count was 0).
 * Side work (elfm_recon_options.side_work): each callback posts 3 units,
 * free threads take them one by one between their other jobs; all are done
 * by the time the run returns (threads look for side work before they
 * leave), and with 2 threads some while a callback runs. */
typedef struct stages_ctx {
  int in_callback;         /* callbacks running now (atomic) */
  int n_overlapping;       /* callbacks that found another running */
  int n_worker_during;     /* worker calls made while a callback ran */
  int posted, done;        /* side units (under omp critical) */
  int n_side_during;       /* units done while a callback ran */
  int threads, bad_thread;
  int64_t n, next_frame, out_of_order;
} stages_ctx;

static int during_callback(stages_ctx *h)
{
  int busy;
#pragma omp atomic read
  busy = h->in_callback;
  return busy;
}

static elfm_status st_worker(const elfm_volume *v, const elfm_frame *frame,
                             const elfm_refocus_plan *plan, int slot, int thread, void *user,
                             elfm_error *err)
{
  (void)v, (void)frame, (void)plan, (void)slot, (void)thread, (void)err;
  stages_ctx *h = user;
  if (during_callback(h)) {
#pragma omp atomic update
    h->n_worker_during++;
  }
  return ELFM_OK;
}

static int st_side(void *user, int thread)
{
  stages_ctx *h = user;
  int took = 0;
  if (thread < 0 || thread >= h->threads) {
#pragma omp atomic write
    h->bad_thread = 1;
  }
#pragma omp critical(side_units)
  if (h->done < h->posted) {
    h->done++;
    took = 1;
  }
  if (!took) return 0;
  if (during_callback(h)) {
#pragma omp atomic update
    h->n_side_during++;
  }
  struct timespec ts = {0, 200000}; /* 0.2 ms of "smoothing" */
  nanosleep(&ts, NULL);
  return 1;
}

static elfm_status st_ordered(const elfm_volume *v, int slot, void *user, elfm_error *err)
{
  (void)slot, (void)err;
  stages_ctx *h = user;
  int was;
#pragma omp atomic capture
  was = h->in_callback++;
  if (was) h->n_overlapping++;
  if (v->frame != h->next_frame) h->out_of_order++;
  h->next_frame = v->frame + 1;
  h->n++;
#pragma omp critical(side_units)
  h->posted += 3;
  struct timespec ts = {0, 2000000};
  nanosleep(&ts, NULL);
#pragma omp atomic update
  h->in_callback--;
  return ELFM_OK;
}

static void test_pipeline_stages(const char *dir, const elfm_calib *cal)
{
  elfm_error err;
  char path[600];
  snprintf(path, sizeof path, "%s/events.raw", dir);
  for (int threads = 1; threads <= 2; threads++) {
    elfm_recon_options o;
    elfm_recon_options_default(&o);
    o.threads = threads;
    o.worker = st_worker;
    o.on_volume_slot = st_ordered;
    o.side_work = st_side;
    stages_ctx h;
    memset(&h, 0, sizeof h);
    h.threads = threads;
    o.worker_user = &h;
    o.side_user = &h;
    elfm_recon_stats st;
    CHECK_OK(elfm_recon_run(path, cal, &o, NULL, &h, &st, &err), &err);
    CHECK_EQ_INT(h.n, DUR_US / 1000);
    CHECK_EQ_INT(h.out_of_order, 0);
    CHECK_EQ_INT(h.n_overlapping, 0);
    CHECK_EQ_INT(h.posted, 3 * DUR_US / 1000);
    CHECK_EQ_INT(h.done, h.posted);
    CHECK_EQ_INT(h.bad_thread, 0);
    if (threads == 1) {
      CHECK_EQ_INT(h.n_worker_during, 0);
      CHECK_EQ_INT(h.n_side_during, 0);
    } else {
      CHECK_MSG(h.n_worker_during > 0, "2 threads: no worker ran during the %lld callbacks",
                (long long)h.n);
      CHECK_MSG(h.n_side_during > 0, "2 threads: no side work beside the %lld callbacks",
                (long long)h.n);
    }
    printf("%d thread%s: %d of %lld worker calls and %d of %d side units during a callback\n",
           threads, threads > 1 ? "s" : "", h.n_worker_during, (long long)h.n, h.n_side_during,
           h.done);
  }
}

int main(void)
{
  elfm_calib cal;
  elfm_optics op;
  elfm_error err;
  elfm_optics_default(&op);
  CHECK_OK(elfm_calib_from_optics(&op, 1280, 720, 4.86, &cal, &err), &err);
  char dir[] = "/tmp/elfm_recon_XXXXXX";
  if (!mkdtemp(dir)) SKIP("cannot make a temporary directory");
  test_runs(dir, &cal);
  test_worker_hook(dir, &cal);
  test_no_refocus(dir, &cal);
  test_pipeline_stages(dir, &cal);
  test_tiff(dir, &cal);
  test_tiff_mixed_depth(dir);
  char cmd[600];
  snprintf(cmd, sizeof cmd, "rm -rf '%s'", dir);
  if (system(cmd) != 0) fprintf(stderr, "could not remove %s\n", dir);
  return check_report();
}
