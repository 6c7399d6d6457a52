/* test_sim.c — the simulator against physics it must obey and contracts it
 * must keep (short scenes, a few seconds in all):
 *   - a static scene gives only noise, at the configured rate (10 %);
 *   - a light step of D in ln intensity gives ~D/C events per pixel;
 *   - every event of a moving bead lies on the bead's SPEC §2 image in some
 *     view, and every view the bead is visible in gets events;
 *   - events.raw decodes to exactly the events handed to a sink, across the
 *     EVT3 16.777216 s timestamp loop;
 *   - same seed, same bytes; another seed, other bytes;
 *   - truth: stage speeds, sweep, helix speeds, everything inside the field.
 */
#include <string.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include "check.h"
#include "elfm_datasets.h"

typedef struct ev_store {
  int64_t *t;
  uint16_t *x, *y;
  uint8_t *p;
  size_t n, cap;
  size_t n_trig;
  int64_t last_t;
  int ordered;
} ev_store;

static elfm_status store_sink(void *user, const elfm_event_chunk *c, elfm_error *err)
{
  (void)err;
  ev_store *s = user;
  if (s->n + c->n > s->cap) {
    size_t nc = s->cap ? s->cap : 4096;
    while (nc < s->n + c->n) nc *= 2;
    s->t = realloc(s->t, nc * sizeof *s->t);
    s->x = realloc(s->x, nc * sizeof *s->x);
    s->y = realloc(s->y, nc * sizeof *s->y);
    s->p = realloc(s->p, nc * sizeof *s->p);
    s->cap = nc;
  }
  for (size_t i = 0; i < c->n; i++) {
    if (c->t_us[i] < s->last_t) s->ordered = 0;
    s->last_t = c->t_us[i];
    s->t[s->n] = c->t_us[i];
    s->x[s->n] = c->x[i];
    s->y[s->n] = c->y[i];
    s->p[s->n] = c->p[i];
    s->n++;
  }
  s->n_trig += c->n_trig;
  return ELFM_OK;
}

static void store_init(ev_store *s)
{
  memset(s, 0, sizeof *s);
  s->ordered = 1;
  s->last_t = INT64_MIN;
}

static void store_free(ev_store *s)
{
  free(s->t);
  free(s->x);
  free(s->y);
  free(s->p);
}

static elfm_scene *load(const char *name, const char *const *params, int n)
{
  elfm_error err;
  elfm_error_clear(&err);
  elfm_scene *s = NULL;
  CHECK_OK(elfm_scene_load(name, &s, &err), &err);
  for (int i = 0; s && i < n; i++) CHECK_OK(elfm_scene_set_param(s, params[i], &err), &err);
  return s;
}

/* Quiet sensor: no noise, no jitter, exact thresholds, no refractory. */
#define QUIET "sensor.shot_noise_hz=0", "sensor.leak_hz=0", "sensor.hot_pixels=0", \
              "sensor.jitter_us=0", "sensor.threshold_sigma=0", "sensor.refractory_us=0"

static void test_static_noise(void)
{
  /* blink beads under constant light: nothing changes, so only noise. */
  const char *p[] = {"illumination={\"type\":\"constant\"}", "duration_ms=100"};
  elfm_scene *s = load("blink", p, 2);
  if (!s) return;
  ev_store st;
  store_init(&st);
  elfm_error err;
  elfm_sim_stats stats;
  CHECK_OK(elfm_sim_run_sink(s, store_sink, &st, NULL, &stats, &err), &err);
  CHECK_EQ_INT(stats.n_signal, 0);
  /* Scene: 2 Hz shot noise + 0.1 Hz leak per pixel, 5 hot pixels at 1 kHz. */
  double expect = 1280.0 * 720.0 * (2.0 + 0.1) + 5 * 1000.0;
  double rate = (double)st.n / 0.1;
  CHECK_MSG(fabs(rate / expect - 1) < 0.10, "noise rate %.0f/s, configured %.0f/s", rate, expect);
  CHECK(st.ordered);
  CHECK_EQ_INT((int64_t)st.n, stats.n_events);
  /* Leak events are ON: ON share = (1 + 0.1) / 2.1 of the non-hot noise. */
  double on_share = (double)stats.n_on / (double)stats.n_events;
  CHECK_MSG(fabs(on_share - 1.1 / 2.1) < 0.02, "ON share %.3f", on_share);
  store_free(&st);
  elfm_scene_free(s);
}

/* A bead at the origin under light that turns off at 20 ms and on at 40 ms:
 * each pixel's ON and OFF counts must follow ln(I_on / I_off) / C. */
static void test_step_response(void)
{
  const char *p[] = {QUIET,
                     "objects.count=1",
                     "objects.flux_hz=[120000,120000]",
                     "motion.place_radius_um=0",
                     "motion.z_min_um=0",
                     "motion.z_max_um=0",
                     "illumination={\"type\":\"periodic\",\"pulse_us\":20000,\"period_us\":40000}",
                     "duration_ms=60"};
  elfm_scene *s = load("blink", p, (int)(sizeof p / sizeof *p));
  if (!s) return;
  const elfm_calib *c = elfm_scene_calib(s);
  ev_store st;
  store_init(&st);
  elfm_error err;
  CHECK_OK(elfm_sim_run_sink(s, store_sink, &st, NULL, NULL, &err), &err);
  CHECK(st.n_trig == 3); /* LED on at 0 (t0), off at 20 ms, on at 40 ms */
  /* Expected per-pixel ln step from the documented PSF: sigma^2 = (0.21
   * lambda / NA_sub)^2 + r^2/5 at z = 0, NA_sub = 0.75 / 10; pixel-integrated. */
  double s0 = 0.21 * 0.52 / 0.075, sig_um = sqrt(s0 * s0 + 1.0 / 5.0);
  double sig = sig_um / c->um_per_px, bg = 1000.0, A = 120000.0, C = 0.2;
  int k0 = -1;
  for (int k = 0; k < c->n_views; k++)
    if (c->views[k].i == 0 && c->views[k].j == 0) k0 = k;
  CHECK(k0 >= 0);
  double u0 = c->views[k0].cx_px, v0 = c->views[k0].cy_px;
  double want_off = 0;
  long got_off = 0, got_on = 0;
  int n_pix = 0;
  for (int y = (int)v0 - 6; y <= (int)v0 + 6; y++) {
    for (int x = (int)u0 - 6; x <= (int)u0 + 6; x++) {
      double gx = 0.5 * (erf((x + 0.5 - u0) / (sig * M_SQRT2)) - erf((x - 0.5 - u0) / (sig * M_SQRT2)));
      double gy = 0.5 * (erf((y + 0.5 - v0) / (sig * M_SQRT2)) - erf((y - 0.5 - v0) / (sig * M_SQRT2)));
      double D = log((bg + A * gx * gy) / bg);
      if (D < 4 * C) continue; /* the bright core only: floor effects small */
      n_pix++;
      /* Start offset uniform in the dead band, floor: D/C - 1/2 on average. */
      want_off += D / C - 0.5;
      for (size_t i = 0; i < st.n; i++) {
        if (st.x[i] != x || st.y[i] != y) continue;
        int64_t t = st.t[i] - elfm_scene_t0_us(s);
        if (t >= 20000 && t < 30000 && !st.p[i]) got_off++;
        if (t >= 40000 && t < 50000 && st.p[i]) got_on++;
      }
    }
  }
  fprintf(stderr, "step: %d px, OFF %ld (expected %.1f), ON %ld\n", n_pix, got_off, want_off, got_on);
  CHECK(n_pix >= 4);
  CHECK_MSG(fabs(got_off / want_off - 1) < 0.10, "OFF events %ld, expected %.1f over %d px", got_off,
            want_off, n_pix);
  /* ON after OFF: the reference sits where the OFF run left it, so the ON
   * run gives back the same count within one event per pixel. */
  CHECK_MSG(labs(got_on - got_off) <= n_pix, "ON %ld vs OFF %ld", got_on, got_off);
  /* No events while nothing changes (first 20 ms: static, light on). */
  size_t early = 0;
  for (size_t i = 0; i < st.n; i++)
    if (st.t[i] - elfm_scene_t0_us(s) < 19000) early++;
  CHECK_EQ_INT(early, 0);
  store_free(&st);
  elfm_scene_free(s);
}

/* The same bead, light off at 20 ms, with one sensor parameter changed:
 * OFF events of the 16 central pixels of view (0,0) -> count, mean delay after the edge,
 * largest count in one pixel. */
typedef struct step_stats {
  long n;
  double mean_delay_us, min_delay_us;
  int max_per_pixel;
  int64_t dropped;
  int64_t min_gap_us; /* least time between two OFF events of one pixel */
} step_stats;

/* The step with sensor settings param and param2 (NULL: none); step_with
 * below takes one. */
static step_stats step_with2(const char *param, const char *param2)
{
  const char *p[] = {QUIET,
                     "objects.count=1",
                     "objects.flux_hz=[120000,120000]",
                     "motion.place_radius_um=0",
                     "motion.z_min_um=0",
                     "motion.z_max_um=0",
                     "illumination={\"type\":\"periodic\",\"pulse_us\":20000,\"period_us\":40000}",
                     "duration_ms=32",
                     param,
                     param2};
  step_stats r = {0, 0, 1e9, 0, 0, INT64_MAX};
  elfm_scene *s = load("blink", p, (int)(sizeof p / sizeof *p) - (param2 ? 0 : 1));
  if (!s) return r;
  ev_store st;
  store_init(&st);
  elfm_error err;
  elfm_sim_stats ss;
  CHECK_OK(elfm_sim_run_sink(s, store_sink, &st, NULL, &ss, &err), &err);
  r.dropped = ss.n_dropped_refractory;
  const elfm_calib *c = elfm_scene_calib(s);
  int u0 = (int)c->views[12].cx_px, v0 = (int)c->views[12].cy_px; /* view (0,0) */
  for (int y = v0 - 1; y <= v0 + 2; y++) {
    for (int x = u0 - 1; x <= u0 + 2; x++) {
      int n = 0;
      int64_t t_prev = INT64_MIN;
      for (size_t i = 0; i < st.n; i++) {
        if (st.x[i] != x || st.y[i] != y || st.p[i]) continue;
        if (t_prev != INT64_MIN && st.t[i] - t_prev < r.min_gap_us) r.min_gap_us = st.t[i] - t_prev;
        t_prev = st.t[i];
        double d = (double)(st.t[i] - elfm_scene_t0_us(s) - 20000);
        r.n++;
        n++;
        r.mean_delay_us += d;
        if (d < r.min_delay_us) r.min_delay_us = d;
      }
      if (n > r.max_per_pixel) r.max_per_pixel = n;
    }
  }
  if (r.n) r.mean_delay_us /= (double)r.n;
  store_free(&st);
  elfm_scene_free(s);
  return r;
}

static step_stats step_with(const char *param) { return step_with2(param, NULL); }

/* Latency, refractory period and photoreceptor bandwidth do what they say. */
static void test_sensor_timing(void)
{
  step_stats fast = step_with("sensor.latency_us=0");
  step_stats late = step_with("sensor.latency_us=300");
  step_stats refr = step_with("sensor.refractory_us=5000");
  step_stats slow = step_with("sensor.cutoff_hz_at_background=100");
  fprintf(stderr, "sensor: delay %.0f us (latency 0), %.0f us (latency 300), %.0f us (cutoff 100 Hz)\n",
          fast.mean_delay_us, late.mean_delay_us, slow.mean_delay_us);
  CHECK(fast.n > 30);
  /* Latency shifts every event by itself (no jitter here). */
  CHECK_NEAR(late.mean_delay_us - fast.mean_delay_us, 300, 2);
  CHECK(late.min_delay_us >= 300);
  /* Refractory 5 ms over the 12 ms after the edge: <= 3 events per pixel. */
  CHECK(refr.max_per_pixel <= 3 && fast.max_per_pixel > 3);
  CHECK(refr.dropped > 0 && fast.dropped == 0);
  /* A pixel fires again after its refractory period and not before: on the
   * slow photoreceptor its OFF events come as the level falls, closer than
   * 400 us without one. */
  step_stats slow_refr = step_with2("sensor.cutoff_hz_at_background=100", "sensor.refractory_us=400");
  CHECK_MSG(slow.min_gap_us < 400, "least gap %lld us", (long long)slow.min_gap_us);
  CHECK_MSG(slow_refr.min_gap_us >= 400 && slow_refr.min_gap_us < 800, "least gap %lld us",
            (long long)slow_refr.min_gap_us);
  /* A 20x slower photoreceptor (tau 1.6 ms at background) spreads the OFF
   * run over milliseconds instead of ~0.1 ms. */
  CHECK(slow.mean_delay_us > 5 * fast.mean_delay_us && slow.mean_delay_us > 500);
}

/* Every event of one moving bead lies near its image in some view. */
static void test_moving_bead_on_path(void)
{
  const char *p[] = {QUIET, "objects.count=1", "sensor.latency_us=0", "duration_ms=20"};
  elfm_scene *s = load("stage", p, (int)(sizeof p / sizeof *p));
  if (!s) return;
  const elfm_calib *c = elfm_scene_calib(s);
  ev_store st;
  store_init(&st);
  elfm_error err;
  CHECK_OK(elfm_sim_run_sink(s, store_sink, &st, NULL, NULL, &err), &err);
  elfm_truth tr;
  elfm_scene_truth(s, 0, elfm_scene_t0_us(s), &tr);
  CHECK(st.n > 100 || tr.brightness == 0);
  int per_view[ELFM_MAX_VIEWS] = {0};
  size_t off_path = 0;
  for (size_t i = 0; i < st.n; i++) {
    elfm_scene_truth(s, 0, st.t[i], &tr);
    /* Defocus widens the image: sigma ~ |z| * 0.075 / 2 um; allow 4 sigma + 3 px. */
    double sig_px = sqrt(1.5 * 1.5 + pow(0.5 * fabs(tr.z_um) * 0.075, 2)) / c->um_per_px;
    double best = 1e9;
    int bv = -1;
    for (int v = 0; v < c->n_views; v++) {
      double u, w;
      elfm_calib_project(c, v, tr.x_um, tr.y_um, tr.z_um, &u, &w);
      double d = hypot(st.x[i] - u, st.y[i] - w);
      if (d < best) { best = d; bv = v; }
    }
    if (best > 4 * sig_px + 3) off_path++;
    else per_view[bv]++;
  }
  CHECK_MSG(off_path == 0, "%zu of %zu events off the bead's images", off_path, st.n);
  /* Each view whose image stays on the sensor the whole time got events. */
  int lit = 0, missing = 0;
  for (int v = 0; v < c->n_views; v++) {
    int inside = 1;
    for (int64_t t = 0; t <= 20000; t += 1000) {
      elfm_scene_truth(s, 0, elfm_scene_t0_us(s) + t, &tr);
      double u, w;
      elfm_calib_project(c, v, tr.x_um, tr.y_um, tr.z_um, &u, &w);
      if (u < 10 || w < 10 || u > c->sensor_width_px - 10 || w > c->sensor_height_px - 10 ||
          tr.brightness < 1)
        inside = 0;
    }
    if (!inside) continue;
    lit++;
    if (per_view[v] < 10) missing++;
  }
  fprintf(stderr, "moving bead: %zu events, %d views fully visible\n", st.n, lit);
  CHECK(lit >= 10);
  CHECK_MSG(missing == 0, "%d of %d visible views without events", missing, lit);
  store_free(&st);
  elfm_scene_free(s);
}

/* Mean offset (px, along the motion, +y) of one in-focus stage bead's ON
 * events from its image in their view at the event's time, over the views
 * wholly on the sensor; `param` sets the time step. */
static double on_event_lead_px(const char *param, size_t *n_used)
{
  const char *p[] = {QUIET, "objects.count=1", "sensor.latency_us=0", "motion.z_min_um=0",
                     "motion.z_max_um=0", "duration_ms=30", param};
  *n_used = 0;
  elfm_scene *s = load("stage", p, (int)(sizeof p / sizeof *p));
  if (!s) return NAN;
  const elfm_calib *c = elfm_scene_calib(s);
  ev_store st;
  store_init(&st);
  elfm_error err;
  CHECK_OK(elfm_sim_run_sink(s, store_sink, &st, NULL, NULL, &err), &err);
  double sum = 0;
  for (size_t i = 0; i < st.n; i++) {
    if (!st.p[i] || st.t[i] < elfm_scene_t0_us(s) + 5000) continue; /* settled pixels only */
    elfm_truth tr;
    elfm_scene_truth(s, 0, st.t[i], &tr);
    double best = 1e9, dy = 0;
    for (int v = 0; v < c->n_views; v++) {
      double u, w;
      elfm_calib_project(c, v, tr.x_um, tr.y_um, tr.z_um, &u, &w);
      if (u < 10 || w < 10 || u > c->sensor_width_px - 10 || w > c->sensor_height_px - 10) continue;
      double d = hypot(st.x[i] - u, st.y[i] - w);
      if (d < best) {
        best = d;
        dy = st.y[i] - w;
      }
    }
    if (best > 6) continue;
    sum += dy;
    (*n_used)++;
  }
  store_free(&st);
  elfm_scene_free(s);
  return *n_used ? sum / (double)*n_used : NAN;
}

/* The time step does not shift the events of a moving bead in time: with
 * the image sampled where the object is at the end of each step (backward
 * Euler's photoreceptor then lags a ramp by its own time constant, for any
 * step), the ON events of steps of up to 250 us lie where those of 10 us
 * steps do. Sampled at the step's middle they lagged by half a step: 0.3 px
 * at 2.5 um/ms here, and on flow a delay ~100 us longer than with fine steps
 * (docs/simulator.md "Time steps"). */
static void test_step_size_timing(void)
{
  size_t n_coarse, n_fine;
  double coarse = on_event_lead_px("max_step_us=250", &n_coarse);
  double fine = on_event_lead_px("max_step_us=10", &n_fine);
  fprintf(stderr, "ON events along the motion: %+.3f px (steps <= 250 us, %zu events), %+.3f px "
          "(10 us, %zu events)\n", coarse, n_coarse, fine, n_fine);
  CHECK(n_coarse > 1000 && n_fine > 1000);
  CHECK(fine > 0); /* the ON events lead the bead (its leading half brightens) */
  CHECK_MSG(fabs(coarse - fine) < 0.08, "coarse steps move the ON events by %+.3f px", coarse - fine);
}

static unsigned char *slurp(const char *path, size_t *n)
{
  FILE *f = fopen(path, "rb");
  if (!f) return NULL;
  fseek(f, 0, SEEK_END);
  long len = ftell(f);
  fseek(f, 0, SEEK_SET);
  unsigned char *b = malloc((size_t)len + 1);
  *n = fread(b, 1, (size_t)len, f);
  b[*n] = 0;
  fclose(f);
  return b;
}

static int same_file(const char *a, const char *b)
{
  size_t na = 0, nb = 0;
  unsigned char *x = slurp(a, &na), *y = slurp(b, &nb);
  int same = x && y && na == nb && memcmp(x, y, na) == 0;
  free(x);
  free(y);
  return same;
}

/* The scene test_roundtrip_and_seed writes to sim_rt_a and test_truth_file
 * reads back: its 12 ms cross the EVT3 timestamp loop at 16777216 us. */
static const char *const rt_settings[] = {"objects.count=4", "duration_ms=12", "t0_us=16771216"};

/* Sink vs file, exactly; the recording crosses the EVT3 timestamp loop. */
static void test_roundtrip_and_seed(void)
{
  elfm_scene *s = load("blink_moving", rt_settings, 3);
  if (!s) return;
  elfm_error err;
  ev_store mem;
  store_init(&mem);
  CHECK_OK(elfm_sim_run_sink(s, store_sink, &mem, NULL, NULL, &err), &err);
  elfm_sim_stats st1;
  CHECK_OK(elfm_sim_run(s, "sim_rt_a", NULL, &st1, &err), &err);
  CHECK_EQ_INT(st1.n_events, (int64_t)mem.n);
  CHECK(mem.n > 1000);
  CHECK(mem.t[0] < 16777216 && mem.t[mem.n - 1] > 16777216);

  elfm_reader *r = NULL;
  CHECK_OK(elfm_reader_open("sim_rt_a/events.raw", NULL, &r, &err), &err);
  if (r) {
    CHECK_EQ_INT(elfm_reader_width(r), 1280);
    CHECK_EQ_INT(elfm_reader_height(r), 720);
    elfm_event_chunk *ch = elfm_chunk_create(10000, &err);
    size_t k = 0, mismatch = 0, n_trig = 0;
    for (;;) {
      CHECK_OK(elfm_reader_read(r, ch, &err), &err);
      if (ch->n == 0 && ch->n_trig == 0) break;
      n_trig += ch->n_trig;
      for (size_t i = 0; i < ch->n; i++, k++) {
        if (k >= mem.n || ch->t_us[i] != mem.t[k] || ch->x[i] != mem.x[k] ||
            ch->y[i] != mem.y[k] || ch->p[i] != mem.p[k])
          mismatch++;
      }
    }
    CHECK_EQ_INT(k, mem.n);
    CHECK_EQ_INT(mismatch, 0);
    CHECK_EQ_INT(n_trig, mem.n_trig);
    CHECK(n_trig >= 7); /* 1 ms pulses every 3 ms over 12 ms: 4 on + 4 off */
    elfm_chunk_free(ch);
    elfm_reader_close(r);
  }
  /* calib.json beside the events is the scene's calibration. */
  elfm_calib cal;
  CHECK_OK(elfm_calib_load("sim_rt_a/calib.json", &cal, &err), &err);
  CHECK(cal.n_views == elfm_scene_calib(s)->n_views &&
        cal.views[3].cx_px == elfm_scene_calib(s)->views[3].cx_px);
  /* stimulus.csv: header then the LED edges. */
  size_t n = 0;
  unsigned char *stim = slurp("sim_rt_a/stimulus.csv", &n);
  CHECK(stim && strncmp((char *)stim, "t_us,channel,value\n", 19) == 0);
  free(stim);

  /* Same seed -> same bytes; another seed -> other bytes. */
  CHECK_OK(elfm_sim_run(s, "sim_rt_b", NULL, NULL, &err), &err);
  CHECK(same_file("sim_rt_a/events.raw", "sim_rt_b/events.raw"));
  CHECK(same_file("sim_rt_a/truth.csv", "sim_rt_b/truth.csv"));
  CHECK_OK(elfm_scene_set_seed(s, 99, &err), &err);
  CHECK_OK(elfm_sim_run(s, "sim_rt_c", NULL, NULL, &err), &err);
  CHECK(!same_file("sim_rt_a/events.raw", "sim_rt_c/events.raw"));
  CHECK(!same_file("sim_rt_a/truth.csv", "sim_rt_c/truth.csv"));
  store_free(&mem);
  elfm_scene_free(s);
}

/* truth.csv: header, every <= 100 us per object, matching the truth query
 * row by row (id, time, each axis, brightness: a z written from y passed
 * every test until a mutation sweep). */
static void test_truth_file(void)
{
  size_t n = 0;
  unsigned char *b = slurp("sim_rt_a/truth.csv", &n);
  CHECK(b != NULL);
  if (!b) return;
  CHECK(strncmp((char *)b, "id,t_us,x_um,y_um,z_um,brightness\n", 34) == 0);
  /* 4 objects, 12 ms at 100 us: 121 samples each. */
  size_t lines = 0;
  for (size_t i = 0; i < n; i++) lines += b[i] == '\n';
  CHECK_EQ_INT(lines, 1 + 4 * 121);
  elfm_scene *s = load("blink_moving", rt_settings, 3); /* as written */
  const char *q = memchr(b, '\n', n);
  int rows = 0, bad = 0, lit = 0;
  for (; s && q && q + 1 < (const char *)b + n; q = strchr(q + 1, '\n'), rows++) {
    long long id, t_us;
    double x, y, z, br;
    if (sscanf(q + 1, "%lld,%lld,%lf,%lf,%lf,%lf", &id, &t_us, &x, &y, &z, &br) != 6) {
      bad++;
      continue;
    }
    elfm_truth tr; /* rows go time by time, the objects in order */
    elfm_scene_truth(s, rows % 4, t_us, &tr);
    bad += id != tr.id || t_us != 16771216 + 100LL * (rows / 4) || fabs(x - tr.x_um) > 1e-4 ||
           fabs(y - tr.y_um) > 1e-4 || fabs(z - tr.z_um) > 1e-4 ||
           fabs(br - tr.brightness) > 1e-3 * fmax(1.0, fabs(tr.brightness));
    lit += br > 0;
  }
  CHECK_EQ_INT(rows, 4 * 121);
  CHECK_EQ_INT(bad, 0);
  CHECK(lit > 0 && lit < rows); /* the LED's pulses: lit and dark rows both */
  elfm_scene_free(s);
  free(b);
}

static void test_truth_motion(void)
{
  elfm_error err;
  for (int k = 0; elfm_scene_builtin_name(k); k++) {
    elfm_scene *s = NULL;
    const char *name = elfm_scene_builtin_name(k);
    CHECK_OK(elfm_scene_load(name, &s, &err), &err);
    if (!s) continue;
    int64_t t0 = elfm_scene_t0_us(s), D = elfm_scene_duration_us(s);
    int n = elfm_scene_n_objects(s), outside = 0;
    for (int o = 0; o < n; o++) {
      for (int64_t t = 0; t <= D; t += 1000) {
        elfm_truth tr;
        elfm_scene_truth(s, o, t0 + t, &tr);
        /* Lit objects inside the 62 um field stop and within +-90 um. */
        if (tr.brightness > 0 && (hypot(tr.x_um, tr.y_um) > 62 || fabs(tr.z_um) > 90)) outside++;
        if (tr.brightness < 0 || tr.brightness > 1) outside++;
      }
    }
    CHECK_MSG(outside == 0, "scene %s: %d samples outside the field", name, outside);
    elfm_scene_free(s);
  }
  elfm_scene *s = load("stage", NULL, 0);
  if (s) {
    /* 2.5 mm/s = 2.5 um/ms along +y, id changes when a bead wraps. */
    int checked = 0;
    for (int o = 0; o < elfm_scene_n_objects(s); o++) {
      elfm_truth a, b;
      elfm_scene_truth(s, o, elfm_scene_t0_us(s) + 100000, &a);
      elfm_scene_truth(s, o, elfm_scene_t0_us(s) + 101000, &b);
      if (a.id != b.id) continue;
      CHECK_NEAR(b.y_um - a.y_um, 2.5, 1e-9);
      CHECK_NEAR(b.x_um - a.x_um, 0.0, 1e-12);
      checked++;
    }
    CHECK(checked >= 8);
    elfm_scene_free(s);
  }
  s = load("stage_accel", NULL, 0);
  if (s) {
    /* v(t) = 0.1 + 2.5 t mm/s until 2.5 mm/s at t = 0.96 s. */
    elfm_truth a, b;
    int64_t t0 = elfm_scene_t0_us(s);
    for (int64_t t = 100000; t <= 1100000; t += 200000) {
      elfm_scene_truth(s, 0, t0 + t, &a);
      elfm_scene_truth(s, 0, t0 + t + 10, &b);
      if (a.id != b.id) continue;
      double v = (b.y_um - a.y_um) / 10.0 * 1000.0; /* um/ms = mm/s */
      double want = fmin(0.1 + 2.5 * (t + 5) * 1e-6, 2.5);
      CHECK_NEAR(v, want, 1e-6);
    }
    elfm_scene_free(s);
  }
  s = load("zsweep", NULL, 0);
  if (s) {
    elfm_truth a;
    elfm_scene_truth(s, 0, elfm_scene_t0_us(s) + 450000, &a);
    CHECK_NEAR(a.z_um, -90 + 0.2 * 450, 1e-9);
    CHECK_NEAR(a.x_um, 0, 1e-12);
    elfm_scene_free(s);
  }
  s = load("flow", NULL, 0);
  if (s) {
    double vmin = 1e9;
    for (int o = 0; o < elfm_scene_n_objects(s); o++) {
      for (int64_t t = 0; t < 1000000; t += 50000) {
        elfm_truth a, b;
        elfm_scene_truth(s, o, t, &a);
        elfm_scene_truth(s, o, t + 10, &b);
        double v = sqrt(pow(b.x_um - a.x_um, 2) + pow(b.y_um - a.y_um, 2) + pow(b.z_um - a.z_um, 2)) * 100;
        vmin = fmin(vmin, v); /* um/ms */
      }
    }
    CHECK_MSG(vmin >= 2.5 * 0.999, "flow: slowest bead %.3f mm/s", vmin);
    elfm_scene_free(s);
  }
}

/* flow_random: each bead's RMS speed is drawn in 2.5-4 mm/s (the sum of
 * its modes' shares), its speed varies along the path (no constant-speed
 * helix), its path is smooth (bounded acceleration) and the same seed
 * gives the same path. A wrong amplitude (|amp| omega off by sqrt 2, say)
 * moves the RMS out of its range. */
static void test_random_motion(void)
{
  elfm_scene *s = load("flow_random", NULL, 0);
  if (!s) return;
  const int n = elfm_scene_n_objects(s);
  CHECK(n == 20);
  int rms_ok = 0, varies = 0, smooth = 0;
  double rms_lo = 1e9, rms_hi = 0;
  for (int o = 0; o < n; o++) {
    /* 20 s, 100 us steps: many periods of 8-30 ms, so the time average is
     * the RMS speed to a few per cent */
    double sum2 = 0, vmin = 1e9, vmax = 0, amax = 0, vprev[3] = {0, 0, 0};
    const int64_t dt = 100, N = 200000;
    elfm_truth a, b;
    elfm_scene_truth(s, o, 0, &a);
    for (int64_t i = 1; i <= N; i++) {
      elfm_scene_truth(s, o, i * dt, &b);
      const double v[3] = {(b.x_um - a.x_um) / dt * 1e3, (b.y_um - a.y_um) / dt * 1e3,
                           (b.z_um - a.z_um) / dt * 1e3}; /* um/ms = mm/s */
      const double sp = sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
      sum2 += sp * sp;
      vmin = fmin(vmin, sp);
      vmax = fmax(vmax, sp);
      if (i > 1) {
        const double acc = sqrt(pow(v[0] - vprev[0], 2) + pow(v[1] - vprev[1], 2) +
                                pow(v[2] - vprev[2], 2)) / (dt * 1e-3); /* um/ms^2 */
        amax = fmax(amax, acc);
      }
      memcpy(vprev, v, sizeof v);
      a = b;
    }
    const double rms = sqrt(sum2 / N);
    rms_lo = fmin(rms_lo, rms);
    rms_hi = fmax(rms_hi, rms);
    rms_ok += rms >= 2.5 * 0.9 && rms <= 4.0 * 1.1;
    varies += vmax > 1.5 * vmin;
    /* a mode of period 8 ms at the fastest share: A omega^2 ~ 2.3 um/ms^2;
     * six of them in line at most ~14 */
    smooth += amax < 15;
  }
  CHECK_MSG(rms_ok == n, "flow_random: RMS speeds %.2f-%.2f mm/s, %d of %d in 2.25-4.4", rms_lo,
            rms_hi, rms_ok, n);
  CHECK_MSG(varies == n, "flow_random: %d of %d beads change speed by > 1.5x", varies, n);
  CHECK_MSG(smooth == n, "flow_random: %d of %d paths with acceleration < 15 um/ms^2", smooth, n);
  /* same seed, same path; another seed, another path */
  elfm_scene *s2 = load("flow_random", NULL, 0);
  const char *seed2[] = {"seed=2"};
  elfm_scene *s3 = load("flow_random", seed2, 1);
  if (s2 && s3) {
    elfm_truth a, b, c;
    elfm_scene_truth(s, 7, 54321, &a);
    elfm_scene_truth(s2, 7, 54321, &b);
    elfm_scene_truth(s3, 7, 54321, &c);
    CHECK(a.x_um == b.x_um && a.y_um == b.y_um && a.z_um == b.z_um);
    CHECK(a.x_um != c.x_um || a.y_um != c.y_um || a.z_um != c.z_um);
  }
  elfm_scene_free(s3);
  elfm_scene_free(s2);
  elfm_scene_free(s);
}

/* A random path too fast for its periods cannot fit the field: a clear
 * error naming the key, not an endless draw. */
static void test_random_motion_too_big(void)
{
  elfm_error err;
  elfm_error_clear(&err);
  elfm_scene *s = NULL;
  CHECK_OK(elfm_scene_load("flow_random", &s, &err), &err);
  if (!s) return;
  elfm_status st = elfm_scene_set_param(s, "motion.speed_mm_per_s=[40,50]", &err);
  CHECK(st != ELFM_OK);
  CHECK_MSG(strstr(err.message, "motion.speed_mm_per_s") != NULL, "message: %s", err.message);
  elfm_scene_free(s);
}

static elfm_status count_sink(void *user, const elfm_event_chunk *c, elfm_error *err)
{
  (void)err;
  *(int64_t *)user += (int64_t)c->n;
  return ELFM_OK;
}

/* Peak RSS (kB) of a child process simulating `stage` for duration_ms. */
static long child_peak_kb(int duration_ms)
{
  pid_t pid = fork();
  if (pid == 0) {
    char kv[64];
    snprintf(kv, sizeof kv, "duration_ms=%d", duration_ms);
    elfm_error err;
    elfm_scene *s = NULL;
    int64_t n = 0;
    if (elfm_scene_load("stage", &s, &err) || elfm_scene_set_param(s, kv, &err) ||
        elfm_sim_run_sink(s, count_sink, &n, NULL, NULL, &err))
      _exit(1);
    elfm_scene_free(s);
    _exit(n > 0 ? 0 : 1);
  }
  int status = 0;
  struct rusage ru;
  if (pid < 0 || wait4(pid, &status, 0, &ru) != pid || !WIFEXITED(status) ||
      WEXITSTATUS(status) != 0)
    return -1;
  return ru.ru_maxrss;
}

/* Memory does not grow with the recording: 10x the duration, same peak. */
static void test_memory_bounded(void)
{
  long short_kb = child_peak_kb(15), long_kb = child_peak_kb(150);
  fprintf(stderr, "memory: peak %ld kB for 15 ms, %ld kB for 150 ms of stage\n", short_kb, long_kb);
  CHECK(short_kb > 0 && long_kb > 0);
  /* A few MB of slack: buffers grow to the busiest slice, which a longer
   * run may meet; the pixel state alone is ~30 MB. */
  CHECK_MSG(long_kb - short_kb < 4096, "peak grew by %ld kB", long_kb - short_kb);
}

/* Build DIR = base + parts x "/abcdefghi" and make every directory but the
 * last; returns its length. */
static size_t long_dir(char *dir, size_t cap, const char *base, int parts)
{
  size_t n = (size_t)snprintf(dir, cap, "%s", base);
  for (int i = 0; i < parts && n + 11 < cap; i++) {
    (void)mkdir(dir, 0777);
    n += (size_t)snprintf(dir + n, cap - n, "/abcdefghi");
  }
  return n;
}

/* Remove what long_dir made below base (and the files sim_run wrote at its
 * end): a chain of 400 directories is more than some tools take (git worktree
 * remove stops at "File name too long" on them). */
static void long_dir_remove(char *dir, const char *base)
{
  static const char *files[] = {"events.raw", "truth.csv", "calib.json", "stimulus.csv"};
  char f[8300];
  for (size_t i = 0; i < sizeof files / sizeof *files; i++) {
    snprintf(f, sizeof f, "%s/%s", dir, files[i]);
    (void)unlink(f);
  }
  const size_t nb = strlen(base);
  for (;;) {
    (void)rmdir(dir);
    char *slash = strrchr(dir, '/');
    if (!slash || (size_t)(slash - dir) < nb) break;
    *slash = '\0';
  }
}

/* Output directories as long as the system takes are written whole; longer
 * ones are refused before the directory is made. Before, anything over 1000
 * characters was refused, and only after its directory had been made. */
static void test_long_out_dir(void)
{
  const char *p[] = {"objects.count=1", "duration_ms=2"};
  elfm_scene *s = load("stage", p, 2);
  if (!s) return;
  elfm_error err;
  static char dir[8192], f[8300];
  size_t n = long_dir(dir, sizeof dir, "sim_long_ok", 120); /* 1211 characters */
  CHECK(n > 1100);
  CHECK_OK(elfm_sim_run(s, dir, NULL, NULL, &err), &err);
  snprintf(f, sizeof f, "%s/stimulus.csv", dir); /* the longest name: none here */
  CHECK(access(f, F_OK) != 0);
  snprintf(f, sizeof f, "%s/truth.csv", dir);
  CHECK(access(f, F_OK) == 0);
  long_dir_remove(dir, "sim_long_ok");
  CHECK(access("sim_long_ok", F_OK) != 0);
  n = long_dir(dir, sizeof dir, "sim_long_no", 408); /* 4091: parents made */
  CHECK(n > 4096 - sizeof "/stimulus.csv");
  elfm_error_clear(&err);
  CHECK(elfm_sim_run(s, dir, NULL, NULL, &err) == ELFM_ERR_INVALID);
  CHECK(strstr(err.message, "too long") != NULL);
  CHECK(access(dir, F_OK) != 0); /* nothing made */
  long_dir_remove(dir, "sim_long_no");
  CHECK(access("sim_long_no", F_OK) != 0);
  elfm_scene_free(s);
}

int main(void)
{
  test_static_noise();
  test_step_response();
  test_sensor_timing();
  test_moving_bead_on_path();
  test_step_size_timing();
  test_roundtrip_and_seed();
  test_truth_file();
  test_long_out_dir();
  test_truth_motion();
  test_random_motion();
  test_random_motion_too_big();
  test_memory_bounded();
  return check_report();
}
