/* test_frames_integral.c — the framer's INTEGRAL representation: each
 * pixel's leaky sum of ON minus OFF events (elfm_frames.h).
 *
 * The point of it is where a moving object shows: an ON time surface
 * shows its leading edge, the integral shows the object. So the central
 * test renders a blob moving across a small sensor, turns it into events
 * with an ideal pixel (a log-brightness step of one threshold per event),
 * and compares the centroid of each frame with the blob's true centre at
 * the frame's time. Then the bookkeeping: the leak, overlapping windows,
 * chunking, the clamp, the active list, the options, the start levels,
 * and the slower leak of levels above 0 (tau_bright_us). */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "check.h"
#include "elfm_recon.h"

enum { SW = 96, SH = 32 };

/* A Gaussian blob (sigma_px) of peak brightness `contrast` x the
 * background, centred at (x0 + v t, SH/2). Events from an ideal pixel:
 * every c_on rise of ln brightness above the pixel's reference is an ON
 * event, every c_off fall an OFF, sampled every step_us. */
typedef struct {
  double sigma_px, contrast, x0_px, v_px_per_us, c_on, c_off;
  int64_t step_us, duration_us;
} blob_scene;

static double blob_logi(const blob_scene *s, int x, int y, double t_us)
{
  double dx = x - (s->x0_px + s->v_px_per_us * t_us), dy = y - SH / 2;
  return log(1.0 + s->contrast * exp(-(dx * dx + dy * dy) / (2 * s->sigma_px * s->sigma_px)));
}

/* All events of the scene into one chunk (caller frees). */
static elfm_event_chunk *blob_events(const blob_scene *s)
{
  elfm_error err;
  size_t cap = 1 << 20;
  elfm_event_chunk *c = elfm_chunk_create(cap, &err);
  double *ref = malloc(sizeof(double) * SW * SH);
  for (int y = 0; y < SH; y++)
    for (int x = 0; x < SW; x++) ref[y * SW + x] = blob_logi(s, x, y, 0);
  for (int64_t t = s->step_us; t <= s->duration_us; t += s->step_us)
    for (int y = 0; y < SH; y++)
      for (int x = 0; x < SW; x++) {
        double l = blob_logi(s, x, y, (double)t), *r = &ref[y * SW + x];
        while (l - *r >= s->c_on && c->n < cap) {
          *r += s->c_on;
          c->t_us[c->n] = t, c->x[c->n] = (uint16_t)x, c->y[c->n] = (uint16_t)y, c->p[c->n++] = 1;
        }
        while (*r - l >= s->c_off && c->n < cap) {
          *r -= s->c_off;
          c->t_us[c->n] = t, c->x[c->n] = (uint16_t)x, c->y[c->n] = (uint16_t)y, c->p[c->n++] = 0;
        }
      }
  free(ref);
  return c;
}

/* Centroid in x of the frame's positive values within +-r px of x_true. */
static double centroid_x(const elfm_frame *f, double x_true, int r)
{
  double sw = 0, sx = 0;
  for (int y = 0; y < f->h; y++)
    for (int x = (int)x_true - r; x <= (int)x_true + r; x++) {
      if (x < 0 || x >= f->w) continue;
      float v = f->data[y * f->w + x];
      if (v > 0) sw += v, sx += v * x;
    }
  return sw > 0 ? sx / sw : NAN;
}

/* Mean signed error (frame centroid - true centre, along the motion) over
 * the frames whose blob lies well inside the sensor and, with t_max_us >
 * 0, that stand for times before t_max_us. With levels (w x h, steps),
 * the framer starts from them. strict: every such frame must
 * show the blob. */
static double mean_error_levels(const blob_scene *s, const elfm_framer_options *o,
                                const float *levels, int64_t t_max_us, int strict, int *n_frames)
{
  elfm_error err;
  elfm_framer *fr = NULL;
  CHECK_OK(elfm_framer_create(o, SW, SH, &fr, &err), &err);
  elfm_event_chunk *c = blob_events(s);
  elfm_frame *f = elfm_frame_create(SW, SH, &err);
  double sum = 0;
  int n = 0;
  if (fr && levels) CHECK_OK(elfm_framer_set_levels(fr, levels, &err), &err);
  if (fr && c && f) {
    CHECK_OK(elfm_framer_push(fr, c, &err), &err);
    elfm_framer_finish(fr);
    while (elfm_framer_next(fr, f)) {
      double xt = s->x0_px + s->v_px_per_us * (double)f->t_us;
      if (xt < 16 || xt > SW - 16 || (t_max_us > 0 && f->t_us >= t_max_us)) continue;
      double xc = centroid_x(f, xt, 10);
      if (strict) CHECK(isfinite(xc)); /* else an object just in view may not show yet */
      if (isfinite(xc)) sum += xc - xt, n++;
    }
  }
  elfm_frame_free(f);
  elfm_chunk_free(c);
  elfm_framer_free(fr);
  *n_frames = n;
  return n ? sum / n : NAN;
}

static double mean_error_px(const blob_scene *s, const elfm_framer_options *o, int *n_frames)
{
  return mean_error_levels(s, o, NULL, 0, 1, n_frames);
}

/* Framer options for the integral, windows from t = 0, leak tau_us. */
static elfm_framer_options integral_options(double tau_us)
{
  elfm_framer_options o;
  elfm_framer_options_default(&o);
  o.start = ELFM_START_AT_TIME;
  o.start_us = 0;
  o.repr = ELFM_REPR_INTEGRAL;
  o.tau_us = tau_us;
  return o;
}

static void test_moving_blob(void)
{
  /* 3 px blob at 10x the background, 2 px/ms: enters from the left, so
   * the sensor's first image is the background alone (what came before
   * the recording is not in its events). */
  blob_scene s = {3.0, 10.0, -12.0, 0.002, 0.2, 0.2, 10, 50000};
  elfm_framer_options o = integral_options(ELFM_INTEGRAL_TAU_US), on = o;
  on.repr = ELFM_REPR_EXP;
  on.tau_us = 1000;
  on.polarity = ELFM_POL_ON;
  int n_exp = 0, n_int = 0;
  double e_exp = mean_error_px(&s, &on, &n_exp);
  double e_int = mean_error_px(&s, &o, &n_int);
  CHECK(n_exp >= 2 && n_int >= 2);
  /* The ON surface leads by well over a pixel; the integral is within a
   * quarter pixel (the residue of quantising to whole thresholds). */
  CHECK_MSG(e_exp > 1.0, "ON time surface error %.3f px: expected a lead", e_exp);
  CHECK_MSG(fabs(e_int) < 0.25, "integral error %.3f px", e_int);

  /* OFF steps 1.5x the ON steps: weighting OFF events by the ratio keeps
   * the object where it is; counting them as ON steps leaves the trail
   * positive (fewer, larger OFF steps undo less) and drags it behind. */
  blob_scene a = s;
  a.c_off = 0.3;
  o.off_weight = 1.5;
  double e_right = mean_error_px(&a, &o, &n_int);
  o.off_weight = 1.0;
  double e_wrong = mean_error_px(&a, &o, &n_int);
  CHECK_MSG(fabs(e_right) < 0.3, "off_weight 1.5 on 0.2/0.3 thresholds: error %.3f px", e_right);
  CHECK_MSG(fabs(e_wrong) > fabs(e_right) + 0.2, "off_weight 1: error %.3f px (right: %.3f)",
            e_wrong, e_right);
}

/* One pixel, five ON events at 0: the frame at t is gain (5.5 e^(-t/tau) - F)
 * (the half step after an ON event: the pixel's level is 0..1 step above
 * its reference; F = ELFM_INTEGRAL_FLOOR). */
static void test_leak_and_active_list(void)
{
  elfm_error err;
  elfm_framer_options o = integral_options(2000);
  elfm_framer *fr = NULL;
  CHECK_OK(elfm_framer_create(&o, SW, SH, &fr, &err), &err);
  elfm_event_chunk *c = elfm_chunk_create(16, &err);
  elfm_frame *f = elfm_frame_create(SW, SH, &err);
  if (!fr || !c || !f) goto out;
  for (int i = 0; i < 5; i++)
    c->t_us[c->n] = 0, c->x[c->n] = 5, c->y[c->n] = 6, c->p[c->n++] = 1;
  c->t_us[c->n] = 20000, c->x[c->n] = 50, c->y[c->n] = 20, c->p[c->n++] = 0; /* closes windows */
  CHECK_OK(elfm_framer_push(fr, c, &err), &err);
  const double gain = 255.0 / 8.0;
  for (int k = 1; k <= 19; k++) {
    CHECK_EQ_INT(elfm_framer_next(fr, f), 1);
    CHECK_EQ_INT(f->t_us, k * 1000); /* the state at the window's end */
    double expect = 5.5 * exp(-k * 1000.0 / o.tau_us);
    float v = f->data[6 * SW + 5];
    if (expect > ELFM_INTEGRAL_FLOOR) {
      CHECK_NEAR(v, gain * (expect - ELFM_INTEGRAL_FLOOR), 1e-3 * gain);
      CHECK_EQ_INT(f->nnz, 1);
    } else {
      /* below the floor: not shown */
      CHECK(v == 0.0f);
      CHECK_EQ_INT(f->nnz, 0);
    }
    CHECK_EQ_INT(f->n_events, k == 1 ? 5 : 0);
  }
out:
  elfm_frame_free(f);
  elfm_chunk_free(c);
  elfm_framer_free(fr);
}

/* Frames for the same window end must not depend on the window length or
 * on how the events were chunked: each event is integrated once. */
static void test_stride_and_chunks(void)
{
  blob_scene s = {2.0, 8.0, 10.0, 0.01, 0.2, 0.2, 20, 4000};
  elfm_event_chunk *all = blob_events(&s);
  elfm_error err;
  elfm_framer_options a = integral_options(3000), b;
  a.polarity = ELFM_POL_SIGNED;
  a.dt_us = 500;
  b = a;
  b.dt_us = 1000; /* overlapping windows: t1 = 1000, 1500, ... */
  b.stride_us = 500;
  elfm_framer *fa = NULL, *fb = NULL;
  CHECK_OK(elfm_framer_create(&a, SW, SH, &fa, &err), &err);
  CHECK_OK(elfm_framer_create(&b, SW, SH, &fb, &err), &err);
  elfm_frame *ga = elfm_frame_create(SW, SH, &err), *gb = elfm_frame_create(SW, SH, &err);
  elfm_event_chunk *piece = elfm_chunk_create(37, &err);
  if (!fa || !fb || !ga || !gb || !piece || !all) goto out;
  CHECK_OK(elfm_framer_push(fa, all, &err), &err);
  for (size_t i = 0; i < all->n; i += 37) { /* b gets 37-event chunks */
    piece->n = 0;
    for (size_t j = i; j < all->n && j < i + 37; j++) {
      piece->t_us[piece->n] = all->t_us[j], piece->x[piece->n] = all->x[j];
      piece->y[piece->n] = all->y[j], piece->p[piece->n++] = all->p[j];
    }
    CHECK_OK(elfm_framer_push(fb, piece, &err), &err);
  }
  elfm_framer_finish(fa);
  elfm_framer_finish(fb);
  CHECK_EQ_INT(elfm_framer_next(fa, ga), 1); /* a's first frame ends at 500: b has none */
  int compared = 0, differ = 0;
  while (elfm_framer_next(fa, ga) && elfm_framer_next(fb, gb)) {
    CHECK_EQ_INT(ga->t_us, gb->t_us);
    /* (the leak is applied in different steps: exp(a) exp(b) in floats) */
    for (int i = 0; i < SW * SH; i++) {
      if (fabsf(ga->data[i] - gb->data[i]) > 1e-2f && differ < 3)
        fprintf(stderr, "t %lld pixel %d: %g vs %g\n", (long long)ga->t_us, i, ga->data[i], gb->data[i]);
      differ += fabsf(ga->data[i] - gb->data[i]) > 1e-2f;
    }
    compared++;
  }
  CHECK(compared >= 6);
  CHECK_EQ_INT(differ, 0);
out:
  elfm_chunk_free(all);
  elfm_chunk_free(piece);
  elfm_frame_free(ga);
  elfm_frame_free(gb);
  elfm_framer_free(fa);
  elfm_framer_free(fb);
}

/* The floor: a lone ON event (sensor noise looks like this) is never
 * shown; a second one on the same pixel is. */
static void test_floor(void)
{
  elfm_error err;
  elfm_framer_options o = integral_options(ELFM_INTEGRAL_TAU_US);
  elfm_framer *fr = NULL;
  CHECK_OK(elfm_framer_create(&o, SW, SH, &fr, &err), &err);
  elfm_event_chunk *c = elfm_chunk_create(64, &err);
  elfm_frame *f = elfm_frame_create(SW, SH, &err);
  if (!fr || !c || !f) goto out;
  for (int i = 0; i < 40; i++) /* lone ON events on 40 pixels */
    c->t_us[c->n] = 100, c->x[c->n] = (uint16_t)(2 * i), c->y[c->n] = 3, c->p[c->n++] = 1;
  c->t_us[c->n] = 1100, c->x[c->n] = 10, c->y[c->n] = 3, c->p[c->n++] = 1; /* pixel 10: a second */
  c->t_us[c->n] = 5000, c->x[c->n] = 0, c->y[c->n] = 0, c->p[c->n++] = 0;
  CHECK_OK(elfm_framer_push(fr, c, &err), &err);
  CHECK_EQ_INT(elfm_framer_next(fr, f), 1); /* [0, 1000) */
  CHECK_EQ_INT(f->nnz, 0);
  CHECK_EQ_INT(f->n_events, 40);
  CHECK_EQ_INT(elfm_framer_next(fr, f), 1); /* [1000, 2000) */
  CHECK_EQ_INT(f->nnz, 1);
  if (f->nnz == 1) CHECK_EQ_INT(f->idx[0], 3 * SW + 10);
  /* the first step leaked 1000 us, then + 1 step + the half step, all
   * leaked 900 us to the window's end, less the floor */
  double level = (exp(-1000.0 / o.tau_us) + 1.0 + 0.5) * exp(-900.0 / o.tau_us);
  CHECK(level > ELFM_INTEGRAL_FLOOR && 1.5 < ELFM_INTEGRAL_FLOOR); /* the test's premise */
  CHECK_NEAR(f->data[3 * SW + 10], 255.0 / 8.0 * (level - ELFM_INTEGRAL_FLOOR), 1e-3);
out:
  elfm_frame_free(f);
  elfm_chunk_free(c);
  elfm_framer_free(fr);
}

/* A hot pixel firing ON at 100 kHz stays finite and bounded (64 steps and
 * the half step, less the floor). */
static void test_clamp(void)
{
  elfm_error err;
  elfm_framer_options o = integral_options(ELFM_INTEGRAL_TAU_US);
  elfm_framer *fr = NULL;
  CHECK_OK(elfm_framer_create(&o, SW, SH, &fr, &err), &err);
  elfm_event_chunk *c = elfm_chunk_create(20001, &err);
  elfm_frame *f = elfm_frame_create(SW, SH, &err);
  if (!fr || !c || !f) goto out;
  for (int i = 0; i <= 20000; i++)
    c->t_us[c->n] = 10 * i, c->x[c->n] = 1, c->y[c->n] = 1, c->p[c->n++] = 1;
  CHECK_OK(elfm_framer_push(fr, c, &err), &err);
  float vmax = 0;
  while (elfm_framer_next(fr, f)) vmax = fmaxf(vmax, f->data[SW + 1]);
  CHECK(isfinite(vmax));
  CHECK(vmax > 255.0f / 8.0f * (float)(60.0 - ELFM_INTEGRAL_FLOOR) &&
        vmax <= 255.0f / 8.0f * (float)(64.5 - ELFM_INTEGRAL_FLOOR) + 1e-3f);
out:
  elfm_frame_free(f);
  elfm_chunk_free(c);
  elfm_framer_free(fr);
}

static void test_options(void)
{
  elfm_error err;
  elfm_framer_options o;
  elfm_framer_options_default(&o);
  CHECK(o.off_weight == 1.0);
  o.repr = ELFM_REPR_INTEGRAL;
  o.tau_us = ELFM_INTEGRAL_TAU_US;
  CHECK_OK(elfm_framer_options_check(&o, &err), &err);
  o.polarity = ELFM_POL_ON; /* half the steps: not a brightness */
  CHECK(elfm_framer_options_check(&o, &err) == ELFM_ERR_INVALID);
  CHECK(strstr(err.message, "both polarities") != NULL);
  o.polarity = ELFM_POL_BOTH;
  const double bad_w[] = {0.0, -1.0, NAN, INFINITY, 101.0};
  for (size_t i = 0; i < sizeof bad_w / sizeof *bad_w; i++) {
    o.off_weight = bad_w[i];
    CHECK(elfm_framer_options_check(&o, &err) == ELFM_ERR_INVALID);
  }
  o.off_weight = 1.0;
  o.tau_us = 0;
  CHECK(elfm_framer_options_check(&o, &err) == ELFM_ERR_INVALID);
  o.tau_us = NAN;
  CHECK(elfm_framer_options_check(&o, &err) == ELFM_ERR_INVALID);
}

/* The start levels (elfm_levels, elfm_framer_set_levels). A blob already
 * in view at the first event and moving slowly (0.2 px/ms: 3 px sigma,
 * so it takes ~30 ms to leave where it started, as a worm neuron does):
 * starting from 0, the integral shows only where it has moved to, well
 * ahead of it; starting from the levels its own later OFF events give,
 * it shows the blob where it is from the first frame. */
static void test_start_levels(void)
{
  elfm_error err;
  blob_scene s = {3.0, 10.0, 30.0, 0.0002, 0.2, 0.2, 10, 100000};
  elfm_framer_options o = integral_options(ELFM_INTEGRAL_TAU_US);
  elfm_levels lv;
  CHECK_OK(elfm_levels_create(SW, SH, &lv, &err), &err);
  elfm_event_chunk *c = blob_events(&s);
  CHECK(elfm_levels_add(&lv, c, o.off_weight, INT64_MAX) == c->n);
  CHECK(lv.t_first_us == c->t_us[0]);
  elfm_levels_result(&lv, o.off_weight);
  int n0 = 0, n1 = 0;
  double e0 = mean_error_levels(&s, &o, NULL, 20000, 0, &n0);
  double e1 = mean_error_levels(&s, &o, lv.sum, 20000, 0, &n1);
  fprintf(stderr, "start levels: first 20 ms, error %.3f px from 0, %.3f px from the levels\n", e0, e1);
  CHECK(n0 >= 10 && n1 >= 10);
  CHECK_MSG(e0 > 1.0, "from 0: error %.3f px, expected a lead", e0);
  CHECK_MSG(fabs(e1) < 0.3, "from the levels: error %.3f px", e1);
  /* the whole recording stays right with them (the levels leak away as
   * the blob's own OFF events undo them) */
  double e2 = mean_error_levels(&s, &o, lv.sum, 0, 0, &n1);
  double e3 = mean_error_levels(&s, &o, NULL, 0, 0, &n0);
  fprintf(stderr, "start levels: all 100 ms, error %.3f px from 0, %.3f px from the levels\n", e3, e2);
  CHECK_MSG(e2 < e3 - 0.5, "all frames: %.3f px from the levels, %.3f from 0", e2, e3);
  elfm_chunk_free(c);
  elfm_levels_free(&lv);

  /* Bookkeeping on single pixels: three OFF steps -> 3.5 (the half step an
   * OFF event leaves); up three and down three -> 0 (a pass, not a start);
   * up only -> 0; events at or after t_end are not taken. */
  CHECK_OK(elfm_levels_create(4, 1, &lv, &err), &err);
  elfm_event_chunk *d = elfm_chunk_create(16, &err);
  const uint8_t pol[] = {0, 0, 0, 1, 1, 1, 0, 0, 0, 1, 1, 0};
  const uint16_t px[] = {0, 0, 0, 1, 1, 1, 1, 1, 1, 2, 2, 3};
  for (int k = 0; k < 12; k++) {
    d->t_us[k] = 100 + 10 * k;
    d->x[k] = px[k];
    d->y[k] = 0;
    d->p[k] = pol[k];
  }
  d->n = 12;
  CHECK(elfm_levels_add(&lv, d, 1.0, 100 + 10 * 11) == 11); /* the last event is at t_end */
  elfm_levels_result(&lv, 1.0);
  CHECK(fabs(lv.sum[0] - 3.5f) < 1e-6f && lv.sum[1] == 0 && lv.sum[2] == 0 && lv.sum[3] == 0);
  CHECK(lv.t_first_us == 100);
  /* set_levels: integral only, and before the first event */
  elfm_framer *fr = NULL;
  elfm_framer_options exp = integral_options(ELFM_INTEGRAL_TAU_US);
  exp.repr = ELFM_REPR_EXP;
  exp.polarity = ELFM_POL_BOTH;
  exp.tau_us = 1000;
  CHECK_OK(elfm_framer_create(&exp, 4, 1, &fr, &err), &err);
  CHECK_EQ_INT(elfm_framer_set_levels(fr, lv.sum, &err), ELFM_ERR_INVALID);
  elfm_framer_free(fr);
  CHECK_OK(elfm_framer_create(&o, 4, 1, &fr, &err), &err);
  CHECK_OK(elfm_framer_push(fr, d, &err), &err);
  CHECK_EQ_INT(elfm_framer_set_levels(fr, lv.sum, &err), ELFM_ERR_INVALID);
  elfm_framer_free(fr);
  elfm_levels_free(&lv);
  /* A start level is held, not leaked, until the pixel's first event (the
   * object is there until it leaves): 5 steps show as 3 above the floor
   * in every frame up to an OFF event at 95 ms, and from there the pixel
   * leaks as any other (5 - 1 - 1/2 steps, then e^(-age/tau)). */
  {
    float lv2[4] = {5, 0, 0, 0};
    const float gain = 255.0f / 8.0f, fl = (float)ELFM_INTEGRAL_FLOOR;
    elfm_framer *h = NULL;
    elfm_event_chunk *e = elfm_chunk_create(4, &err);
    elfm_frame *fr1 = elfm_frame_create(4, 1, &err);
    CHECK_OK(elfm_framer_create(&o, 4, 1, &h, &err), &err);
    CHECK_OK(elfm_framer_set_levels(h, lv2, &err), &err);
    e->t_us[0] = 95000, e->x[0] = 0, e->y[0] = 0, e->p[0] = 0;
    e->t_us[1] = 99500, e->x[1] = 3, e->y[1] = 0, e->p[1] = 1;
    e->n = 2;
    CHECK_OK(elfm_framer_push(h, e, &err), &err);
    elfm_framer_finish(h);
    int held = 0, after = 0, bad = 0;
    while (elfm_framer_next(h, fr1)) {
      const float v = fr1->data[0];
      if (fr1->t_us <= 95000) {
        held++;
        bad += fabsf(v - gain * (5 - fl)) > 1e-3f;
      } else if (fr1->t_us == 96000) {
        after++;
        const float want = gain * (3.5f * expf(-1000.0f / (float)o.tau_us) - fl);
        bad += fabsf(v - want) > 1e-2f;
      }
    }
    CHECK_MSG(held == 95 && after == 1 && bad == 0, "held start level: %d held frames, %d after, %d wrong",
              held, after, bad);
    elfm_frame_free(fr1);
    elfm_chunk_free(e);
    elfm_framer_free(h);
  }
  CHECK_EQ_INT(elfm_levels_create(0, 1, &lv, &err), ELFM_ERR_INVALID);
  CHECK(lv.sum == NULL && lv.min == NULL);
  elfm_chunk_free(d);
}

/* A level above 0 leaks with tau_bright_us, one below 0 with tau_us. Pixel
 * A: 10 ON events at t = 0, shown as 10.5 exp(-t / tau_bright). Pixel B:
 * 10 OFF at 0 (hidden, leaking with tau), 10 ON at 3 ms, then above 0.
 * Then why: an object sits on a pixel for 60 ms (5 ON steps), leaves (5
 * OFF) and a second one arrives 60 ms later (5 ON), as a C. elegans neuron
 * follows its partner along the body. With one leak of 100 ms the pixel
 * shows the second object at 3.76 + 0.5 steps, dimmed by the dark residue
 * the first left; with bright levels leaking at 200 ms, at 4.29 + 0.5. */
static double bright_frame_value(const elfm_framer_options *o, const int *t_ms, const int *on,
                                 const int *n, int k, int64_t t_end_us, int x)
{
  elfm_error err;
  elfm_framer *fr = NULL;
  elfm_event_chunk *c = elfm_chunk_create(64, &err);
  elfm_frame *f = elfm_frame_create(SW, SH, &err);
  double v = -1;
  CHECK_OK(elfm_framer_create(o, SW, SH, &fr, &err), &err);
  if (!fr || !c || !f) goto out;
  for (int j = 0; j < k; j++)
    for (int i = 0; i < n[j]; i++)
      c->t_us[c->n] = (int64_t)t_ms[j] * 1000, c->x[c->n] = (uint16_t)x, c->y[c->n] = 6,
      c->p[c->n++] = (uint8_t)on[j];
  c->t_us[c->n] = t_end_us + 5000, c->x[c->n] = 90, c->y[c->n] = 30, c->p[c->n++] = 0;
  CHECK_OK(elfm_framer_push(fr, c, &err), &err);
  while (elfm_framer_next(fr, f) == 1)
    if (f->t_us == t_end_us) {
      v = f->data[6 * SW + x] / (255.0 / 8.0) + ELFM_INTEGRAL_FLOOR;
      break;
    }
out:
  elfm_frame_free(f);
  elfm_chunk_free(c);
  elfm_framer_free(fr);
  return v;
}

static void test_bright_leak(void)
{
  elfm_framer_options o = integral_options(2000);
  o.tau_bright_us = 6000;
  const int t_a[] = {0}, on_a[] = {1}, n_a[] = {10};
  for (int k = 1; k <= 6; k++)
    CHECK_NEAR(bright_frame_value(&o, t_a, on_a, n_a, 1, k * 1000, 5), 10.5 * exp(-k / 6.0), 1e-3);
  const int t_b[] = {0, 3}, on_b[] = {0, 1}, n_b[] = {10, 10};
  CHECK_NEAR(bright_frame_value(&o, t_b, on_b, n_b, 2, 4000, 7),
             (10.5 - 10 * exp(-1.5)) * exp(-1.0 / 6.0), 1e-3);
  /* the object that follows another */
  elfm_framer_options one = integral_options(100000), two = one;
  two.tau_bright_us = 200000;
  const int t_c[] = {0, 60, 120}, on_c[] = {1, 0, 1}, n_c[] = {5, 5, 5};
  const double v1 = bright_frame_value(&one, t_c, on_c, n_c, 3, 121000, 9);
  const double v2 = bright_frame_value(&two, t_c, on_c, n_c, 3, 121000, 9);
  printf("the second object's level (5.5 without a residue): one leak %.2f, bright levels "
         "leaking at 2 x %.2f steps\n", v1, v2);
  CHECK(v1 > 4.0 && v1 < 4.4 && v2 > 4.6 && v2 < 5.0);
  /* bad values */
  elfm_error err;
  const double bad[] = {-1.0, NAN, INFINITY};
  for (size_t i = 0; i < sizeof bad / sizeof *bad; i++) {
    o.tau_bright_us = bad[i];
    CHECK(elfm_framer_options_check(&o, &err) == ELFM_ERR_INVALID);
  }
}

int main(void)
{
  test_moving_blob();
  test_leak_and_active_list();
  test_stride_and_chunks();
  test_floor();
  test_clamp();
  test_options();
  test_start_levels();
  test_bright_leak();
  return check_report();
}
