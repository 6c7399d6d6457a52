/* sim.c — the event-camera simulation: light from the scene's objects through
 * the Fourier LFM onto an IMX636-like pixel array, in time slices.
 *
 * Per slice (default 1 ms):
 *  1. Each object's images: one box per object and view covering where the
 *     image is during [slice start - one slice, slice end] (the look-back
 *     keeps pixels stepping until their photoreceptor has settled after an
 *     image left). Boxes of objects that move or blink are "dynamic"; the
 *     union of their pixels is the active set, the only pixels stepped.
 *  2. Time steps over the slice: short enough that an image moves <= 0.4
 *     sigma per step, split at every light edge (LED, spikes).
 *  3. Per step and active pixel (v2e / ESIM model): photocurrent = background
 *     + every image's pixel-integrated Gaussian; log; first-order low-pass
 *     whose bandwidth rises with the photocurrent; ON/OFF events at each
 *     threshold crossing with linearly interpolated times, reference reset
 *     by whole thresholds, refractory period, latency + jitter.
 *  4. Background activity drawn analytically over the whole sensor: shot
 *     noise and leak events as Poisson processes, plus hot pixels; the 0.9 M
 *     quiet pixels are never stepped.
 *  5. Events (this slice's and those delayed from the last) sorted by time
 *     (counting sort, stable), the ones before the slice end handed on;
 *     later ones (latency) wait for the next slice.
 * Memory: full-sensor pixel state (~30 MB for 1280x720) plus per-slice
 * buffers that grow to the busiest slice, never with the duration.
 */
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>

#include "sim_internal.h"

#define TWO_PI 6.283185307179586
#define STREAM_NOISE 0x4e4f495345ull  /* "NOISE" */
#define STREAM_SIGNAL 0x5349474eull   /* "SIGN" */
#define STREAM_THRESH 0x544852ull     /* "THR" */
#define STREAM_FRESH 0x465245ull      /* "FRE" */

/* Gaussian approximation of the Airy core: sigma = 0.21 lambda / NA
 * (Zhang, Zerubia & Olivo-Marin, Appl. Opt. 2007). */
#define AIRY_SIGMA_FACTOR 0.21
/* An image is cut where it adds less than 4 % to the background. ln(1.04)
 * = 0.04 is a fifth of the 0.2 contrast threshold; as an image approaches,
 * a pixel's light rises monotonically anyway, so the cut only moves that
 * pixel's first crossing a little earlier, it adds no events. */
#define BOX_EPS 0.04
/* Samples of each object's path per slice window (bounding boxes, speed). */
#define PATH_SAMPLES 9
/* Step length: an image moves at most this many PSF sigmas per step. ln I
 * of a Gaussian image is quadratic in position, so the chord between two
 * steps deviates from it by at most (0.75 sigma)^2 / (8 sigma^2) = 0.07 ln
 * units, a third of the 0.2 threshold: crossing times interpolated along the
 * chord err by a few us on an image's flanks, where most events are. */
#define STEP_SIGMA_FRACTION 0.75
#define MIN_STEP_US 2
/* Standard normal CDF table on [-8, 8], 64 points per sigma: linear
 * interpolation error < 1e-5. */
#define PHI_LIM 8.0
#define PHI_PER_SIGMA 64
#define PHI_N (2 * 8 * PHI_PER_SIGMA + 2) /* 2 * PHI_LIM * PHI_PER_SIGMA + 2 */

typedef struct sim_event {
  int64_t t_us;
  uint16_t x, y;
  uint8_t p;
} sim_event;

typedef struct sim_box {
  int obj, view, comp;   /* comp 0: core image, 1: scattering haze */
  int dynamic;
  int x0, y0, x1, y1;    /* [x0, x1) x [y0, y1) on the sensor */
  double r_px;           /* how far from the centre the image matters */
} sim_box;

/* Per object, per slice. */
typedef struct sim_objslice {
  int visible, dynamic;
  double amp_max_hz, sigma_max_px, sigma_min_px, speed_px_per_us;
  /* at the current step */
  double amp_hz, sigma_px;
  double pos[3];
  /* the object's contribution to the static base, if any */
  int in_base;
  double base_pos[3], base_amp_hz, base_sigma_px;
} sim_objslice;

typedef struct sim_stim {
  int64_t t_us;
  int channel, value;
} sim_stim;

typedef struct sim_rect {
  int x0, y0, x1, y1;
} sim_rect;

/* One image at one step: its pixels, amplitude, and where its x and y
 * profiles start in gbuf (x then y). */
typedef struct sim_img {
  sim_rect rc;
  double amp;
  size_t g;
} sim_img;

/* Rows per band of the step loop: the pixels touched in a band (~10^4 for
 * 100 beads) fit in a 2 MB L2 cache with their 32-byte records. */
#define SIM_BAND_ROWS 32

/* A pixel's state in one 32-byte record: the step loop touches all of it,
 * and one cache line then holds two pixels instead of seven arrays' worth
 * of lines (the loop is memory-bound). */
typedef struct sim_pixel {
  float ifull;    /* photocurrent accumulated for this step (== base between steps) */
  float base;     /* background + static images */
  float llp;      /* low-passed ln photocurrent */
  float lref;     /* reference level of the last event */
  float con, coff;/* ON / OFF thresholds; con == 0: never initialised */
  uint32_t mark;  /* step that last processed the pixel */
  uint32_t tlast_q; /* last event (crossing) time in quarter us, modulo 2^32 */
} sim_pixel;

/* Event times in the refractory check: quarter microseconds in 32 bits
 * wrap after 1074 s; differences are taken modulo 2^32, so only a pixel
 * silent for more than 537 s could be wrongly held back, once. */
#define TQ_PER_US 4.0

typedef struct sim_ws {
  const elfm_scene *s;
  int W, H;
  size_t npix;
  double umpp, na_sub, dmax, bg;
  double phi[PHI_N];
  /* Full-sensor pixel state. Invariant between steps: ifull == base, the
   * photocurrent of background + static images; a step adds the moving /
   * blinking images into ifull and puts base back as it reads each pixel. */
  sim_pixel *px;
  uint32_t step_id;
  int first_step;  /* the very first step: pixels start settled at the light they see */
  /* pixels still settling (low-pass not yet at its input): stepped until settled */
  int32_t *carry, *carry_next;
  size_t n_carry, n_carry_next, cap_carry, cap_carry_next;
  sim_box *box;
  size_t n_box, cap_box;
  sim_img *img;
  size_t n_img, cap_img;
  double *gbuf;
  size_t cap_gbuf;
  sim_objslice *os;
  int *dyn_obj;
  size_t n_dyn;
  sim_event *ev, *sorted;
  size_t n_ev, cap_ev, cap_sorted;
  uint32_t *counts;
  size_t cap_counts;
  int64_t *steps;
  size_t cap_steps;
  double *gx, *gy;
  size_t cap_gx, cap_gy;
  /* output chunk (our arrays) */
  int64_t *c_t;
  uint16_t *c_x, *c_y;
  uint8_t *c_p;
  size_t cap_ct, cap_cx, cap_cy, cap_cp;
  elfm_trigger *c_trig;
  size_t cap_trig;
  sim_stim *stim;
  size_t n_stim, cap_stim;
  sim_rng rng;     /* this slice's latency jitter */
  elfm_sim_stats st;
} sim_ws;

/* A pixel counts as settled when its low-pass output is within this of its
 * input (ln units): 1/200 of the 0.2 threshold, so what is left of the
 * relaxation cannot cross a threshold except by a hair. */
#define SETTLE_TOL 1e-3f

/* Grow *p to hold `need` elements (doubling). 0 on out of memory. Only
 * called when a slice needs more than any before it. */
static int grow(void **p, size_t *cap, size_t need, size_t elem)
{
  if (need <= *cap) return 1;
  size_t nc = *cap ? *cap : 1024;
  while (nc < need) nc *= 2;
  void *np = realloc(*p, nc * elem);
  if (!np) return 0;
  *p = np;
  *cap = nc;
  return 1;
}

static double phi_exact(double x) { return 0.5 * erfc(-x / sqrt(2.0)); }

static inline double phi_tab(const double *tab, double x)
{
  double f = (x + PHI_LIM) * PHI_PER_SIGMA;
  if (f <= 0) return 0.0;
  if (f >= PHI_N - 2) return 1.0;
  int i = (int)f;
  double w = f - i;
  return tab[i] + w * (tab[i + 1] - tab[i]);
}

static void ws_free(sim_ws *w)
{
  free(w->px); free(w->carry); free(w->carry_next);
  free(w->box); free(w->img); free(w->gbuf); free(w->os); free(w->dyn_obj);
  free(w->ev); free(w->sorted); free(w->counts);
  free(w->steps); free(w->gx); free(w->gy);
  free(w->c_t); free(w->c_x); free(w->c_y); free(w->c_p); free(w->c_trig);
  free(w->stim);
}

static elfm_status ws_init(sim_ws *w, const elfm_scene *s, elfm_error *err)
{
  memset(w, 0, sizeof *w);
  w->s = s;
  w->W = s->sensor.width;
  w->H = s->sensor.height;
  w->npix = (size_t)w->W * (size_t)w->H;
  w->umpp = s->calib.um_per_px;
  const elfm_optics *o = &s->calib.optics;
  /* SPEC §2: N = 2 NA f_fourier / (M d) lenslets across the pupil; each
   * view sees a sub-aperture of NA / N. */
  double n_lens = 2.0 * o->na * o->f_fourier_mm * 1000.0 / (o->magnification * o->mla_pitch_um);
  w->na_sub = o->na / n_lens;
  w->bg = s->background_hz;
  w->first_step = 1;
  for (int v = 0; v < s->calib.n_views; v++) {
    w->dmax = fmax(w->dmax, fabs(s->calib.views[v].dx_px_per_um));
    w->dmax = fmax(w->dmax, fabs(s->calib.views[v].dy_px_per_um));
  }
  for (int i = 0; i < PHI_N; i++) w->phi[i] = phi_exact(-PHI_LIM + (double)i / PHI_PER_SIGMA);
  w->px = calloc(w->npix, sizeof *w->px); /* con 0: never initialised; mark 0: no step */
  w->os = calloc((size_t)(s->n_objects ? s->n_objects : 1), sizeof *w->os);
  w->dyn_obj = calloc((size_t)(s->n_objects ? s->n_objects : 1), sizeof *w->dyn_obj);
  if (!w->px || !w->os || !w->dyn_obj) {
    ws_free(w);
    return elfm_error_set(err, ELFM_ERR_NOMEM, s->source, -1,
                          "out of memory for the %dx%d pixel state", w->W, w->H);
  }
  for (size_t i = 0; i < w->npix; i++) w->px[i].base = w->px[i].ifull = (float)w->bg;
  return ELFM_OK;
}

static double core_sigma_um(const sim_ws *w, double z_um, double diameter_um)
{
  const elfm_scene *s = w->s;
  double s0 = AIRY_SIGMA_FACTOR * s->calib.optics.wavelength_um / w->na_sub;
  /* Geometric defocus: a disc of radius |z| tan(theta), sin(theta) =
   * NA_sub / n; a uniform disc has sigma = radius / 2. */
  double sn = w->na_sub / s->calib.optics.n_medium;
  double geo = 0.5 * fabs(z_um) * sn / sqrt(1.0 - sn * sn);
  /* A uniformly filled sphere projects with per-axis variance r^2 / 5. */
  double r = 0.5 * diameter_um;
  return sqrt(s0 * s0 + geo * geo + r * r / 5.0);
}

static double comp_sigma_px(const sim_ws *w, double core_px, int comp)
{
  if (!comp) return core_px;
  double h = w->s->haze_sigma_um / w->umpp;
  return sqrt(core_px * core_px + h * h);
}

static double comp_amp(const sim_ws *w, double amp, int comp)
{
  return comp ? amp * w->s->haze_fraction : amp * (1.0 - w->s->haze_fraction);
}

/* Radius (px) beyond which an image of amplitude A (photocurrent summed
 * over the image) and width sigma adds < BOX_EPS of the background; 0 when
 * it never does (invisible). */
static double image_radius_px(const sim_ws *w, double A, double sigma_px)
{
  double peak = A / (TWO_PI * sigma_px * sigma_px);
  double ratio = peak / (BOX_EPS * w->bg);
  if (ratio <= 1.0) return 0.0;
  return sigma_px * sqrt(2.0 * log(ratio)) + 1.0;
}

/* Light factor at t (illumination x spikes x field stop) times flux. */
static double object_amp(const elfm_scene *s, int k, int64_t t, const double pos[3])
{
  return s->obj[k].flux_hz * sim_object_light(s, k, t) * sim_field_stop(s, pos[0], pos[1]);
}

/* ---- step 1: objects and boxes of a slice ---- */
static elfm_status plan_slice(sim_ws *w, int64_t a, int64_t b, elfm_error *err)
{
  const elfm_scene *s = w->s;
  const elfm_calib *c = &s->calib;
  const int64_t wa = a - s->slice_us; /* look-back window start */
  w->n_box = 0;
  w->n_dyn = 0;
  for (int k = 0; k < s->n_objects; k++) {
    sim_objslice *o = &w->os[k];
    double P[PATH_SAMPLES][3];
    double amp_max = 0, smax = 0, smin = INFINITY, speed = 0;
    int moving = 0;
    for (int i = 0; i < PATH_SAMPLES; i++) {
      double t = (double)wa + (double)(b - wa) * i / (PATH_SAMPLES - 1);
      sim_object_position(s, k, t, P[i], NULL);
      double sg = core_sigma_um(w, P[i][2], s->obj[k].diameter_um) / w->umpp;
      smax = fmax(smax, sg);
      smin = fmin(smin, sg);
      double fs = sim_field_stop(s, P[i][0], P[i][1]);
      amp_max = fmax(amp_max, s->obj[k].flux_hz * fs);
      if (i > 0) {
        double dx = P[i][0] - P[i - 1][0], dy = P[i][1] - P[i - 1][1],
               dz = fabs(P[i][2] - P[i - 1][2]);
        if (fabs(dx) + fabs(dy) + dz > 1e-9) moving = 1;
        double dt = (double)(b - wa) / (PATH_SAMPLES - 1);
        /* Fastest image: lateral motion plus the outermost view's depth shift. */
        speed = fmax(speed, (sqrt(dx * dx + dy * dy) / w->umpp + dz * w->dmax) / dt);
      }
    }
    int changes = sim_object_light_changes(s, k, wa, b);
    /* Without a light edge in the window the light is what it is at a. */
    double lmax = changes ? 1.0 : sim_object_light(s, k, a);
    amp_max *= lmax;
    o->visible = amp_max > 0;
    o->dynamic = o->visible && (moving || changes);
    o->amp_max_hz = amp_max;
    o->sigma_max_px = smax;
    o->sigma_min_px = smin;
    o->speed_px_per_us = moving ? speed : 0.0;
    if (!o->dynamic) continue;
    w->dyn_obj[w->n_dyn++] = k;
    for (int comp = 0; comp < 2; comp++) {
      if (comp == 1 && s->haze_fraction <= 0) break;
      double A = comp_amp(w, amp_max, comp), sg = comp_sigma_px(w, smax, comp);
      double r = image_radius_px(w, A, sg);
      if (r <= 0) continue;
      for (int v = 0; v < c->n_views; v++) {
        double umin = INFINITY, umax = -INFINITY, vmin = INFINITY, vmax = -INFINITY;
        for (int i = 0; i < PATH_SAMPLES; i++) {
          double u, vv;
          elfm_calib_project(c, v, P[i][0], P[i][1], P[i][2], &u, &vv);
          umin = fmin(umin, u);
          umax = fmax(umax, u);
          vmin = fmin(vmin, vv);
          vmax = fmax(vmax, vv);
        }
        double fx0 = floor(umin - r), fx1 = ceil(umax + r) + 1, fy0 = floor(vmin - r),
               fy1 = ceil(vmax + r) + 1;
        if (fx1 <= 0 || fy1 <= 0 || fx0 >= w->W || fy0 >= w->H) continue;
        if (!grow((void **)&w->box, &w->cap_box, w->n_box + 1, sizeof *w->box))
          return elfm_error_set(err, ELFM_ERR_NOMEM, s->source, -1, "out of memory (boxes)");
        sim_box *bx = &w->box[w->n_box++];
        bx->obj = k;
        bx->view = v;
        bx->comp = comp;
        bx->dynamic = 1;
        bx->x0 = fx0 < 0 ? 0 : (int)fx0;
        bx->y0 = fy0 < 0 ? 0 : (int)fy0;
        bx->x1 = fx1 > w->W ? w->W : (int)fx1;
        bx->y1 = fy1 > w->H ? w->H : (int)fy1;
        bx->r_px = r;
      }
    }
  }
  return ELFM_OK;
}

/* Pixel-integrated Gaussian profile: g[i] for pixels x0 .. x0+n-1 of an
 * image centred at c (pixel centres at integers). */
static void profile(const sim_ws *w, double c, double sigma, int x0, int n, double *g)
{
  double inv = 1.0 / sigma;
  double prev = phi_tab(w->phi, (x0 - 0.5 - c) * inv);
  for (int i = 0; i < n; i++) {
    double nx = phi_tab(w->phi, (x0 + i + 0.5 - c) * inv);
    g[i] = nx - prev;
    prev = nx;
  }
}

/* Add sign * (image of amplitude A, width sigma, centre u,v) over the part
 * of `clip` within r of the centre into ifull (and base if to_base). Returns
 * the rectangle touched (empty: x1 <= x0). */
static sim_rect add_image(sim_ws *w, sim_rect clip, double r, double A, double sigma, double u,
                          double v, int to_base)
{
  sim_rect rc = {(int)floor(u - r), (int)floor(v - r), (int)ceil(u + r) + 1, (int)ceil(v + r) + 1};
  if (rc.x0 < clip.x0) rc.x0 = clip.x0;
  if (rc.y0 < clip.y0) rc.y0 = clip.y0;
  if (rc.x1 > clip.x1) rc.x1 = clip.x1;
  if (rc.y1 > clip.y1) rc.y1 = clip.y1;
  if (rc.x1 <= rc.x0 || rc.y1 <= rc.y0) {
    rc.x1 = rc.x0;
    return rc;
  }
  if (A == 0) return rc; /* dark: nothing to add, but its pixels still step */
  int nx = rc.x1 - rc.x0, ny = rc.y1 - rc.y0;
  profile(w, u, sigma, rc.x0, nx, w->gx);
  profile(w, v, sigma, rc.y0, ny, w->gy);
  for (int j = 0; j < ny; j++) {
    float ay = (float)(A * w->gy[j]);
    size_t off = (size_t)(rc.y0 + j) * w->W + rc.x0;
    sim_pixel *row = w->px + off;
    if (to_base) {
      for (int i = 0; i < nx; i++) {
        float add = ay * (float)w->gx[i];
        row[i].ifull += add;
        row[i].base += add;
      }
    } else {
      for (int i = 0; i < nx; i++) row[i].ifull += ay * (float)w->gx[i];
    }
  }
  return rc;
}

static elfm_status push_event(sim_ws *w, int64_t t, int x, int y, int p, elfm_error *err)
{
  if (w->n_ev == w->cap_ev &&
      !grow((void **)&w->ev, &w->cap_ev, w->n_ev + 1, sizeof *w->ev))
    return elfm_error_set(err, ELFM_ERR_NOMEM, w->s->source, -1, "out of memory (events)");
  sim_event *e = &w->ev[w->n_ev++];
  e->t_us = t;
  e->x = (uint16_t)x;
  e->y = (uint16_t)y;
  e->p = (uint8_t)p;
  return ELFM_OK;
}

/* Threshold of a pixel: mean + sigma * N(0,1), at least a quarter of the
 * mean (v2e clips the same way to keep thresholds positive). */
static float pixel_threshold(const sim_ws *w, size_t pix, int off)
{
  const sim_sensor *ss = &w->s->sensor;
  double mean = off ? ss->threshold_off : ss->threshold_on;
  double n = sim_normal_fast(sim_hash(w->s->seed, STREAM_THRESH, 2 * (uint64_t)pix + (uint64_t)off));
  double c = mean + ss->threshold_sigma * n;
  if (c < 0.25 * mean) c = 0.25 * mean;
  return (float)c;
}

static int cmp_i64(const void *a, const void *b)
{
  int64_t x = *(const int64_t *)a, y = *(const int64_t *)b;
  return (x > y) - (x < y);
}

/* ---- the static base: background + images that do not change ---- */
static void base_image(sim_ws *w, int k, const double pos[3], double amp, double sigma_core,
                       double sign)
{
  const elfm_calib *c = &w->s->calib;
  const sim_rect all = {0, 0, w->W, w->H};
  for (int comp = 0; comp < 2; comp++) {
    if (comp == 1 && w->s->haze_fraction <= 0) break;
    double A = comp_amp(w, amp, comp), sg = comp_sigma_px(w, sigma_core, comp);
    double r = image_radius_px(w, A, sg);
    if (r <= 0) continue;
    size_t need = (size_t)(2 * r + 4);
    if (!grow((void **)&w->gx, &w->cap_gx, need, sizeof *w->gx) ||
        !grow((void **)&w->gy, &w->cap_gy, need, sizeof *w->gy))
      continue; /* out of memory: leave this image out of the base */
    for (int v = 0; v < c->n_views; v++) {
      double u, vv;
      elfm_calib_project(c, v, pos[0], pos[1], pos[2], &u, &vv);
      add_image(w, all, r, sign * A, sg, u, vv, 1);
    }
  }
  (void)k;
}

/* Objects static in this slice are part of the base; objects that move or
 * blink are drawn per step instead. The same float additions are undone
 * when an object leaves the base, so base drifts by rounding only. */
static void update_base(sim_ws *w, int64_t a)
{
  const elfm_scene *s = w->s;
  for (int k = 0; k < s->n_objects; k++) {
    sim_objslice *o = &w->os[k];
    int want = o->visible && !o->dynamic;
    if (o->in_base && !want) {
      base_image(w, k, o->base_pos, o->base_amp_hz, o->base_sigma_px, -1.0);
      o->in_base = 0;
    }
    if (!o->in_base && want) {
      sim_object_position(s, k, (double)a, o->base_pos, NULL);
      o->base_amp_hz = object_amp(s, k, a, o->base_pos);
      o->base_sigma_px = core_sigma_um(w, o->base_pos[2], s->obj[k].diameter_um) / w->umpp;
      base_image(w, k, o->base_pos, o->base_amp_hz, o->base_sigma_px, 1.0);
      o->in_base = 1;
    }
  }
}

/* ---- step 3: one pixel ---- */

/* Events of one pixel in one step (the rare path). */
static elfm_status pixel_events(sim_ws *w, size_t pix, float L0, float L1, double ta, double dt,
                                elfm_error *err)
{
  const sim_sensor *ss = &w->s->sensor;
  const int64_t t0 = w->s->t0_us;
  double ref = w->px[pix].lref;
  double d = (double)L1 - ref;
  int on = d > 0;
  double C = on ? w->px[pix].con : w->px[pix].coff;
  int n = (int)floor(fabs(d) / C);
  if (n > 1000) n = 1000; /* a pixel can't fire faster than its refractory period anyway */
  int x = (int)(pix % (size_t)w->W), y = (int)(pix / (size_t)w->W);
  double slope = (double)L1 - (double)L0;
  for (int m = 1; m <= n; m++) {
    double level = ref + (on ? m * C : -m * C);
    double frac = slope != 0 ? (level - L0) / slope : 1.0;
    if (frac < 0) frac = 0;
    if (frac > 1) frac = 1;
    double tc = ta + frac * dt;
    uint32_t tq = (uint32_t)(uint64_t)(tc * TQ_PER_US);
    if ((double)(uint32_t)(tq - w->px[pix].tlast_q) < ss->refractory_us * TQ_PER_US) {
      w->st.n_dropped_refractory++;
      continue;
    }
    w->px[pix].tlast_q = tq;
    double delay = ss->latency_us + ss->jitter_us * sim_normal_fast(sim_rng_next(&w->rng));
    if (delay < 0) delay = 0;
    elfm_status s = push_event(w, t0 + (int64_t)floor(tc + delay), x, y, on, err);
    if (s) return s;
    w->st.n_signal++;
  }
  w->px[pix].lref = (float)(ref + (on ? n * C : -n * C));
  return ELFM_OK;
}

/* Natural log for the pixel model: ln x = e ln 2 + ln m with m in [1, 2)
 * from the float's bits and ln m = 2 atanh((m-1)/(m+1)) to the t^7 term;
 * absolute error < 2e-5, a ten-thousandth of the 0.2 contrast threshold, at
 * a third of logf's cost in the hot loop. x must be > 0 and finite. */
static inline float fast_lnf(float x)
{
  union {
    float f;
    uint32_t i;
  } v = {x};
  float e = (float)((int32_t)(v.i >> 23) - 127);
  v.i = (v.i & 0x007fffffu) | 0x3f800000u;
  float m = v.f;
  float t = (m - 1.0f) / (m + 1.0f), t2 = t * t;
  float p = 2.0f * t * (1.0f + t2 * (1.0f / 3.0f + t2 * (1.0f / 5.0f + t2 * (1.0f / 7.0f))));
  return e * 0.69314718f + p;
}

/* Step one pixel from ta to ta + dt: read its photocurrent (and restore
 * the base), low-pass, fire; remember it if it has not settled. */
static inline elfm_status pixel_step(sim_ws *w, size_t pix, float k1, float k2, double ta,
                                     double dt, elfm_error *err)
{
  float I = w->px[pix].ifull;
  w->px[pix].ifull = w->px[pix].base;
  w->st.n_pixel_steps++;
  float L = fast_lnf(I);
  if (w->px[pix].con == 0.0f) {
    /* First sight of this pixel. It has been at the base light until now
     * (anything that changed would have stepped it), except at the very
     * start where everything is taken as settled. Its reference lies
     * anywhere in the dead band: the history is unknown. */
    w->px[pix].con = pixel_threshold(w, pix, 0);
    w->px[pix].coff = pixel_threshold(w, pix, 1);
    /* As if its last event were 2^31 quarter us (537 s) ago. */
    w->px[pix].tlast_q = (uint32_t)(uint64_t)(ta * TQ_PER_US) - 0x80000000u;
    float L_start = w->first_step ? L : fast_lnf(w->px[pix].base);
    uint64_t h = sim_hash(w->s->seed, STREAM_FRESH, (uint64_t)pix);
    w->px[pix].llp = L_start;
    w->px[pix].lref = L_start - (float)(sim_u01(h) * (w->px[pix].con + w->px[pix].coff) - w->px[pix].coff);
  }
  /* Photoreceptor: first-order low-pass of ln I with cutoff
   * f = cutoff_at_background * I / background (v2e: bandwidth rises with
   * photocurrent), capped at cutoff_max; implicit Euler, stable for any step. */
  float ka = k1 * I;
  if (ka > k2) ka = k2;
  float L0 = w->px[pix].llp;
  float L1 = (L0 + ka * L) / (1.0f + ka);
  w->px[pix].llp = L1;
  float d = L1 - w->px[pix].lref;
  if (d >= w->px[pix].con || d <= -w->px[pix].coff) {
    elfm_status st = pixel_events(w, pix, L0, L1, ta, dt, err);
    if (st) return st;
  }
  /* Step it again next time if it has not settled, or if a changing image
   * lights it now (it must see that light go). */
  if (fabsf(L1 - L) > SETTLE_TOL || I != w->px[pix].base) {
    if (w->n_carry_next == w->cap_carry_next &&
        !grow((void **)&w->carry_next, &w->cap_carry_next, w->n_carry_next + 1,
              sizeof *w->carry_next))
      return elfm_error_set(err, ELFM_ERR_NOMEM, w->s->source, -1, "out of memory");
    w->carry_next[w->n_carry_next++] = (int32_t)pix;
  }
  return ELFM_OK;
}

/* ---- step 2/3: the time steps of a slice ---- */
static elfm_status step_slice(sim_ws *w, int64_t q, int64_t a, int64_t b, elfm_error *err)
{
  const elfm_scene *s = w->s;
  const elfm_calib *c = &s->calib;
  const sim_sensor *ss = &s->sensor;
  elfm_status st;
  update_base(w, a);
  if (w->n_dyn == 0 && w->n_carry == 0) {
    w->first_step = 0;
    return ELFM_OK;
  }
  size_t gneed = 0;
  for (size_t i = 0; i < w->n_box; i++) {
    size_t m = (size_t)(w->box[i].x1 - w->box[i].x0);
    if ((size_t)(w->box[i].y1 - w->box[i].y0) > m) m = (size_t)(w->box[i].y1 - w->box[i].y0);
    if (m > gneed) gneed = m;
  }
  if (!grow((void **)&w->gx, &w->cap_gx, gneed + 2, sizeof *w->gx) ||
      !grow((void **)&w->gy, &w->cap_gy, gneed + 2, sizeof *w->gy) ||
      !grow((void **)&w->img, &w->cap_img, w->n_box + 1, sizeof *w->img))
    return elfm_error_set(err, ELFM_ERR_NOMEM, s->source, -1, "out of memory");

  /* Time steps: motion-limited length, split at light edges. */
  double dt = (double)s->max_step_us;
  for (size_t i = 0; i < w->n_dyn; i++) {
    const sim_objslice *o = &w->os[w->dyn_obj[i]];
    if (o->speed_px_per_us > 0) dt = fmin(dt, STEP_SIGMA_FRACTION * o->sigma_min_px / o->speed_px_per_us);
  }
  int64_t dti = (int64_t)floor(dt);
  if (dti < MIN_STEP_US) dti = MIN_STEP_US;
  int64_t n_uniform = (b - a + dti - 1) / dti;
  int64_t n_edges = sim_light_edges(s, a, b - 1, NULL, 0);
  size_t need = (size_t)(n_uniform + n_edges + 2);
  if (!grow((void **)&w->steps, &w->cap_steps, need, sizeof *w->steps))
    return elfm_error_set(err, ELFM_ERR_NOMEM, s->source, -1, "out of memory");
  size_t ns = 0;
  for (int64_t t = a; t < b; t += dti) w->steps[ns++] = t;
  ns += (size_t)sim_light_edges(s, a, b - 1, w->steps + ns, n_edges);
  w->steps[ns++] = b;
  qsort(w->steps, ns, sizeof *w->steps, cmp_i64);
  size_t nu = 0; /* unique */
  for (size_t i = 0; i < ns; i++)
    if (nu == 0 || w->steps[i] != w->steps[nu - 1]) w->steps[nu++] = w->steps[i];

  w->rng = sim_rng_make(s->seed, STREAM_SIGNAL, (uint64_t)q);
  const double bg = w->bg;
  for (size_t i = 0; i + 1 < nu; i++) {
    int64_t ta = w->steps[i], tb = w->steps[i + 1];
    double sdt = (double)(tb - ta), tm = (double)ta + 0.5 * sdt;
    if (++w->step_id == 0) { /* wrapped after 2^32 steps: forget old marks */
      for (size_t p = 0; p < w->npix; p++) w->px[p].mark = 0;
      w->step_id = 1;
    }
    const uint32_t sid = w->step_id;
    w->st.n_steps++;
    for (size_t k = 0; k < w->n_dyn; k++) {
      int ob = w->dyn_obj[k];
      sim_objslice *o = &w->os[ob];
      sim_object_position(s, ob, tm, o->pos, NULL);
      o->amp_hz = object_amp(s, ob, ta, o->pos);
      o->sigma_px = core_sigma_um(w, o->pos[2], s->obj[ob].diameter_um) / w->umpp;
    }
    /* This step's images: where, how bright, their pixel profiles. */
    w->n_img = 0;
    size_t gpos = 0;
    for (size_t j = 0; j < w->n_box; j++) {
      const sim_box *bx = &w->box[j];
      const sim_objslice *o = &w->os[bx->obj];
      double u, v;
      elfm_calib_project(c, bx->view, o->pos[0], o->pos[1], o->pos[2], &u, &v);
      double r = bx->r_px;
      sim_rect rc = {(int)floor(u - r), (int)floor(v - r), (int)ceil(u + r) + 1,
                     (int)ceil(v + r) + 1};
      if (rc.x0 < bx->x0) rc.x0 = bx->x0;
      if (rc.y0 < bx->y0) rc.y0 = bx->y0;
      if (rc.x1 > bx->x1) rc.x1 = bx->x1;
      if (rc.y1 > bx->y1) rc.y1 = bx->y1;
      if (rc.x1 <= rc.x0 || rc.y1 <= rc.y0) continue;
      sim_img *im = &w->img[w->n_img++];
      im->rc = rc;
      im->amp = comp_amp(w, o->amp_hz, bx->comp);
      im->g = gpos;
      size_t nx = (size_t)(rc.x1 - rc.x0), ny = (size_t)(rc.y1 - rc.y0);
      if (im->amp != 0) {
        if (!grow((void **)&w->gbuf, &w->cap_gbuf, gpos + nx + ny, sizeof *w->gbuf))
          return elfm_error_set(err, ELFM_ERR_NOMEM, s->source, -1, "out of memory");
        double sg = comp_sigma_px(w, o->sigma_px, bx->comp);
        profile(w, u, sg, rc.x0, (int)nx, w->gbuf + gpos);
        profile(w, v, sg, rc.y0, (int)ny, w->gbuf + gpos + nx);
        gpos += nx + ny;
      }
    }
    const float k1 = (float)(TWO_PI * ss->cutoff_hz_at_background / bg * sdt * 1e-6);
    const float k2 = (float)(TWO_PI * ss->cutoff_hz_max * sdt * 1e-6);
    /* Band by band (SIM_BAND_ROWS rows): add the images, then step the
     * pixels under them and the settling ones of the band, while the band's
     * pixel records are still in cache. The carry list is built in band
     * order, so its entries of a band are contiguous. */
    size_t cc = 0;
    for (int by0 = 0; by0 < w->H; by0 += SIM_BAND_ROWS) {
      int by1 = by0 + SIM_BAND_ROWS < w->H ? by0 + SIM_BAND_ROWS : w->H;
      for (size_t j = 0; j < w->n_img; j++) {
        const sim_img *im = &w->img[j];
        if (im->amp == 0 || im->rc.y1 <= by0 || im->rc.y0 >= by1) continue;
        int y0 = im->rc.y0 > by0 ? im->rc.y0 : by0, y1 = im->rc.y1 < by1 ? im->rc.y1 : by1;
        int nx = im->rc.x1 - im->rc.x0;
        const double *gx = w->gbuf + im->g, *gy = gx + nx;
        for (int y = y0; y < y1; y++) {
          float ay = (float)(im->amp * gy[y - im->rc.y0]);
          sim_pixel *row = w->px + (size_t)y * w->W + im->rc.x0;
          for (int i = 0; i < nx; i++) row[i].ifull += ay * (float)gx[i];
        }
      }
      for (size_t j = 0; j < w->n_img; j++) {
        const sim_img *im = &w->img[j];
        if (im->rc.y1 <= by0 || im->rc.y0 >= by1) continue;
        int y0 = im->rc.y0 > by0 ? im->rc.y0 : by0, y1 = im->rc.y1 < by1 ? im->rc.y1 : by1;
        for (int y = y0; y < y1; y++) {
          size_t pix = (size_t)y * w->W + im->rc.x0;
          for (int x = im->rc.x0; x < im->rc.x1; x++, pix++) {
            if (w->px[pix].mark == sid) continue;
            w->px[pix].mark = sid;
            if ((st = pixel_step(w, pix, k1, k2, (double)ta, sdt, err))) return st;
          }
        }
      }
      const size_t band_end = (size_t)by1 * w->W;
      for (; cc < w->n_carry && (size_t)w->carry[cc] < band_end; cc++) {
        size_t pix = (size_t)w->carry[cc];
        if (w->px[pix].mark == sid) continue;
        w->px[pix].mark = sid;
        if ((st = pixel_step(w, pix, k1, k2, (double)ta, sdt, err))) return st;
      }
    }
    int32_t *tmp = w->carry;
    size_t tcap = w->cap_carry;
    w->carry = w->carry_next;
    w->cap_carry = w->cap_carry_next;
    w->n_carry = w->n_carry_next;
    w->carry_next = tmp;
    w->cap_carry_next = tcap;
    w->n_carry_next = 0;
    w->first_step = 0;
  }
  return ELFM_OK;
}

/* ---- step 4: background activity ---- */
static int64_t poisson(sim_rng *r, double lambda)
{
  if (lambda <= 0) return 0;
  if (lambda < 30) { /* Knuth's product of uniforms */
    double L = exp(-lambda), p = 1.0;
    int64_t k = 0;
    do {
      k++;
      p *= sim_uniform(r);
    } while (p > L);
    return k - 1;
  }
  /* Normal approximation (error of the rate < 1 % for lambda >= 30). */
  double x = floor(lambda + sqrt(lambda) * sim_normal(r) + 0.5);
  return x < 0 ? 0 : (int64_t)x;
}

static elfm_status noise_slice(sim_ws *w, int64_t q, int64_t a, int64_t b, elfm_error *err)
{
  const elfm_scene *s = w->s;
  const sim_sensor *ss = &s->sensor;
  sim_rng r = sim_rng_make(s->seed, STREAM_NOISE, (uint64_t)q);
  double span_s = (double)(b - a) * 1e-6;
  double rate = ss->shot_noise_hz + ss->leak_hz;
  /* Shot noise is ON or OFF alike; leak events are ON (v2e). */
  double p_on = rate > 0 ? (0.5 * ss->shot_noise_hz + ss->leak_hz) / rate : 0.5;
  int64_t n = poisson(&r, rate * (double)w->npix * span_s);
  for (int64_t i = 0; i < n; i++) {
    uint64_t h = sim_rng_next(&r);
    size_t pix = (size_t)((h >> 11) % w->npix);
    int64_t t = a + (int64_t)(sim_uniform(&r) * (double)(b - a));
    int on = sim_uniform(&r) < p_on;
    if (push_event(w, s->t0_us + t, (int)(pix % (size_t)w->W), (int)(pix / (size_t)w->W), on, err))
      return ELFM_ERR_NOMEM;
  }
  w->st.n_noise += n;
  for (int h = 0; h < ss->hot_pixels; h++) {
    int64_t m = poisson(&r, ss->hot_pixel_hz * span_s);
    for (int64_t i = 0; i < m; i++) {
      int64_t t = a + (int64_t)(sim_uniform(&r) * (double)(b - a));
      int on = sim_uniform(&r) < 0.5;
      if (push_event(w, s->t0_us + t, s->hot_x[h], s->hot_y[h], on, err)) return ELFM_ERR_NOMEM;
    }
    w->st.n_noise += m;
  }
  return ELFM_OK;
}

/* ---- step 5: sort, hand on, keep the late ones ---- */
typedef struct sim_out {
  elfm_sim_sink_fn sink;
  void *user;
  FILE *truth, *stim;
  const char *truth_path, *stim_path;
} sim_out;

static elfm_status emit_sorted(sim_ws *w, int64_t t_lo, int64_t t_end, int final,
                               const sim_out *out, elfm_error *err)
{
  const elfm_scene *s = w->s;
  size_t n = w->n_ev;
  size_t n_trig = 0;
  /* LED edges of this slice as trigger events (channel 0), like the
   * camera's trigger input wired to the LED driver. */
  for (size_t i = 0; i < w->n_stim; i++)
    if (w->stim[i].channel == 0) n_trig++;
  if (n == 0 && n_trig == 0) return ELFM_OK;
  int64_t t_hi = t_lo;
  for (size_t i = 0; i < n; i++)
    if (w->ev[i].t_us > t_hi) t_hi = w->ev[i].t_us;
  size_t range = (size_t)(t_hi - t_lo) + 1;
  if (!grow((void **)&w->counts, &w->cap_counts, range + 1, sizeof *w->counts) ||
      !grow((void **)&w->sorted, &w->cap_sorted, n + 1, sizeof *w->sorted))
    return elfm_error_set(err, ELFM_ERR_NOMEM, s->source, -1, "out of memory (sort)");
  memset(w->counts, 0, (range + 1) * sizeof *w->counts);
  for (size_t i = 0; i < n; i++) w->counts[w->ev[i].t_us - t_lo + 1]++;
  for (size_t i = 1; i <= range; i++) w->counts[i] += w->counts[i - 1];
  for (size_t i = 0; i < n; i++) w->sorted[w->counts[w->ev[i].t_us - t_lo]++] = w->ev[i];
  size_t n_out = n;
  if (!final) {
    n_out = 0;
    while (n_out < n && w->sorted[n_out].t_us < t_end) n_out++;
  }
  if (!grow((void **)&w->c_t, &w->cap_ct, n_out + 1, sizeof *w->c_t) ||
      !grow((void **)&w->c_x, &w->cap_cx, n_out + 1, sizeof *w->c_x) ||
      !grow((void **)&w->c_y, &w->cap_cy, n_out + 1, sizeof *w->c_y) ||
      !grow((void **)&w->c_p, &w->cap_cp, n_out + 1, sizeof *w->c_p))
    goto nomem;
  for (size_t i = 0; i < n_out; i++) {
    w->c_t[i] = w->sorted[i].t_us;
    w->c_x[i] = w->sorted[i].x;
    w->c_y[i] = w->sorted[i].y;
    w->c_p[i] = w->sorted[i].p;
    if (w->sorted[i].p) w->st.n_on++;
    else w->st.n_off++;
  }
  if (!grow((void **)&w->c_trig, &w->cap_trig, n_trig + 1, sizeof *w->c_trig)) goto nomem;
  n_trig = 0;
  for (size_t i = 0; i < w->n_stim; i++) {
    if (w->stim[i].channel != 0) continue;
    w->c_trig[n_trig].t_us = w->stim[i].t_us;
    w->c_trig[n_trig].channel = 0;
    w->c_trig[n_trig].value = (uint8_t)w->stim[i].value;
    n_trig++;
  }
  w->st.n_events += (int64_t)n_out;
  if (out->sink && (n_out || n_trig)) {
    elfm_event_chunk ch;
    memset(&ch, 0, sizeof ch);
    ch.t_us = w->c_t;
    ch.x = w->c_x;
    ch.y = w->c_y;
    ch.p = w->c_p;
    ch.n = ch.cap = n_out;
    ch.trig = w->c_trig;
    ch.n_trig = ch.cap_trig = n_trig;
    elfm_status st = out->sink(out->user, &ch, err);
    if (st) return st;
  }
  /* Keep the rest for the next slice. */
  if (n > n_out) memcpy(w->ev, w->sorted + n_out, (n - n_out) * sizeof *w->ev);
  w->n_ev = n - n_out;
  return ELFM_OK;
nomem:
  return elfm_error_set(err, ELFM_ERR_NOMEM, s->source, -1, "out of memory (output chunk)");
}

/* ---- truth.csv and stimulus.csv ---- */
static elfm_status write_truth(sim_ws *w, int64_t a, int64_t b, int last, const sim_out *out,
                               elfm_error *err)
{
  const elfm_scene *s = w->s;
  if (!out->truth) return ELFM_OK;
  int64_t dt = s->truth_dt_us;
  int64_t t = ((a + dt - 1) / dt) * dt;
  for (;; t += dt) {
    if (t >= b) {
      if (!last) break;
      t = b; /* the end of the recording, once */
      last = 0;
    }
    for (int k = 0; k < s->n_objects; k++) {
      elfm_truth tr;
      elfm_scene_truth(s, k, s->t0_us + t, &tr);
      if (fprintf(out->truth, "%lld,%lld,%.4f,%.4f,%.4f,%.4g\n", (long long)tr.id,
                  (long long)(s->t0_us + t), tr.x_um, tr.y_um, tr.z_um, tr.brightness) < 0)
        return elfm_error_set(err, ELFM_ERR_IO, out->truth_path, -1, "write failed: %s",
                              strerror(errno));
      w->st.n_truth_rows++;
    }
  }
  return ELFM_OK;
}

/* Index of the first of edges[0..n) that is >= t (binary search: a long
 * recording has millions of LED edges; a slice must not scan them all). */
static int64_t first_edge_at(const int64_t *edges, int64_t n, int64_t t)
{
  int64_t lo = 0, hi = n;
  while (lo < hi) {
    int64_t mid = lo + (hi - lo) / 2;
    if (edges[mid] < t) lo = mid + 1;
    else hi = mid;
  }
  return lo;
}

static int cmp_stim(const void *pa, const void *pb)
{
  const sim_stim *a = pa, *b = pb;
  if (a->t_us != b->t_us) return (a->t_us > b->t_us) - (a->t_us < b->t_us);
  return a->channel - b->channel;
}

/* Light edges in [a, b): channel 0 the LED, channel k+1 object k's spikes. */
static elfm_status collect_stimulus(sim_ws *w, int64_t a, int64_t b, elfm_error *err)
{
  const elfm_scene *s = w->s;
  w->n_stim = 0;
  if (s->illum == SIM_ILLUM_RANDOM_PULSES || s->illum == SIM_ILLUM_PERIODIC) {
    /* The illumination alone: edges where it switches. */
    if (s->illum == SIM_ILLUM_RANDOM_PULSES) {
      for (int64_t i = first_edge_at(s->illum_edges, s->n_illum_edges, a);
           i < s->n_illum_edges && s->illum_edges[i] < b; i++) {
        int64_t e = s->illum_edges[i];
        if (!grow((void **)&w->stim, &w->cap_stim, w->n_stim + 1, sizeof *w->stim)) goto nomem;
        w->stim[w->n_stim++] = (sim_stim){s->t0_us + e, 0, (int)((i & 1) == 0)};
      }
    } else {
      int64_t P = (int64_t)s->illum_period_us, len = (int64_t)s->illum_pulse_us;
      for (int64_t m = a / P - 1; m * P < b; m++) {
        int64_t e[2] = {m * P, m * P + len};
        for (int k = 0; k < 2; k++) {
          if (e[k] < a || e[k] >= b) continue;
          if (!grow((void **)&w->stim, &w->cap_stim, w->n_stim + 1, sizeof *w->stim)) goto nomem;
          w->stim[w->n_stim++] = (sim_stim){s->t0_us + e[k], 0, k == 0};
        }
      }
    }
  }
  if (s->has_spikes) {
    for (int k = 0; k < s->n_objects; k++) {
      const sim_object *o = &s->obj[k];
      const int64_t *ed = sim_spike_edges(s, o);
      for (int64_t i = first_edge_at(ed, o->spike_count, a); i < o->spike_count && ed[i] < b; i++) {
        if (!grow((void **)&w->stim, &w->cap_stim, w->n_stim + 1, sizeof *w->stim)) goto nomem;
        w->stim[w->n_stim++] = (sim_stim){s->t0_us + ed[i], k + 1, (int)((i & 1) == 0)};
      }
    }
  }
  if (w->n_stim > 1) qsort(w->stim, w->n_stim, sizeof *w->stim, cmp_stim);
  return ELFM_OK;
nomem:
  return elfm_error_set(err, ELFM_ERR_NOMEM, s->source, -1, "out of memory (stimulus)");
}

static elfm_status write_stimulus(sim_ws *w, const sim_out *out, elfm_error *err)
{
  if (!out->stim) return ELFM_OK;
  for (size_t i = 0; i < w->n_stim; i++) {
    if (fprintf(out->stim, "%lld,%d,%d\n", (long long)w->stim[i].t_us, w->stim[i].channel,
                w->stim[i].value) < 0)
      return elfm_error_set(err, ELFM_ERR_IO, out->stim_path, -1, "write failed: %s",
                            strerror(errno));
  }
  return ELFM_OK;
}

static double now_s(void)
{
  struct timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static elfm_status sim_core(const elfm_scene *s, const sim_out *out, const elfm_sim_options *opt,
                            elfm_sim_stats *stats, elfm_error *err)
{
  sim_ws w;
  double t_start = now_s();
  elfm_status st = ws_init(&w, s, err);
  if (st) return st;
  const int64_t D = s->duration_us, S = s->slice_us;
  const int64_t n_slices = (D + S - 1) / S;
  for (int64_t q = 0; q < n_slices && st == ELFM_OK; q++) {
    int64_t a = q * S, b = a + S < D ? a + S : D;
    int last = q == n_slices - 1;
    if ((st = plan_slice(&w, a, b, err))) break;
    if ((st = step_slice(&w, q, a, b, err))) break;
    if ((st = noise_slice(&w, q, a, b, err))) break;
    if ((st = collect_stimulus(&w, a, b, err))) break;
    if ((st = emit_sorted(&w, s->t0_us + a, s->t0_us + b, last, out, err))) break;
    if ((st = write_truth(&w, a, b, last, out, err))) break;
    if ((st = write_stimulus(&w, out, err))) break;
    if (opt && opt->progress && opt->progress(opt->progress_user, b, D)) {
      st = elfm_error_set(err, ELFM_ERR_INVALID, s->source, -1, "simulation cancelled");
      break;
    }
  }
  w.st.duration_us = D;
  w.st.events_per_s = (double)w.st.n_events / ((double)D * 1e-6);
  w.st.wall_s = now_s() - t_start;
  if (stats) *stats = w.st;
  ws_free(&w);
  return st;
}

elfm_status elfm_sim_run_sink(const elfm_scene *s, elfm_sim_sink_fn sink, void *sink_user,
                              const elfm_sim_options *opt, elfm_sim_stats *stats, elfm_error *err)
{
  if (!s) return elfm_error_set(err, ELFM_ERR_INVALID, NULL, -1, "sim_run: NULL scene");
  sim_out out = {sink, sink_user, NULL, NULL, NULL, NULL};
  return sim_core(s, &out, opt, stats, err);
}

static elfm_status writer_sink(void *user, const elfm_event_chunk *chunk, elfm_error *err)
{
  return elfm_writer_write((elfm_writer *)user, chunk, err);
}

static elfm_status open_text(const char *path, const char *header, FILE **f, elfm_error *err)
{
  *f = fopen(path, "wb");
  if (!*f) return elfm_error_set(err, ELFM_ERR_IO, path, -1, "cannot create: %s", strerror(errno));
  if (fputs(header, *f) == EOF) {
    fclose(*f);
    *f = NULL;
    return elfm_error_set(err, ELFM_ERR_IO, path, -1, "write failed: %s", strerror(errno));
  }
  return ELFM_OK;
}

static elfm_status close_text(FILE *f, const char *path, elfm_status st, elfm_error *err)
{
  if (!f) return st;
  int bad = ferror(f);
  /* fclose reports errors of the final write-back (full disk). */
  if (fclose(f) != 0) bad = 1;
  if (bad && st == ELFM_OK)
    return elfm_error_set(err, ELFM_ERR_IO, path, -1, "write failed: %s", strerror(errno));
  return st;
}

elfm_status elfm_sim_run(const elfm_scene *s, const char *out_dir, const elfm_sim_options *opt,
                         elfm_sim_stats *stats, elfm_error *err)
{
  if (!s || !out_dir) return elfm_error_set(err, ELFM_ERR_INVALID, NULL, -1, "sim_run: NULL argument");
  if (mkdir(out_dir, 0777) != 0 && errno != EEXIST)
    return elfm_error_set(err, ELFM_ERR_IO, out_dir, -1, "cannot create directory: %s",
                          strerror(errno));
  char p_ev[1100], p_truth[1100], p_calib[1100], p_stim[1100];
  if (strlen(out_dir) > 1000)
    return elfm_error_set(err, ELFM_ERR_INVALID, out_dir, -1, "output directory name too long");
  snprintf(p_ev, sizeof p_ev, "%s/events.raw", out_dir);
  snprintf(p_truth, sizeof p_truth, "%s/truth.csv", out_dir);
  snprintf(p_calib, sizeof p_calib, "%s/calib.json", out_dir);
  snprintf(p_stim, sizeof p_stim, "%s/stimulus.csv", out_dir);

  elfm_status st = elfm_calib_save(&s->calib, p_calib, err);
  if (st) return st;
  elfm_writer *wr = NULL;
  if ((st = elfm_writer_open(p_ev, ELFM_FMT_EVT3, s->sensor.width, s->sensor.height, &wr, err)))
    return st;
  FILE *ft = NULL, *fs = NULL;
  int want_truth = opt ? opt->write_truth : 1;
  if (want_truth) st = open_text(p_truth, "id,t_us,x_um,y_um,z_um,brightness\n", &ft, err);
  if (!st && elfm_scene_has_stimulus(s)) st = open_text(p_stim, "t_us,channel,value\n", &fs, err);
  if (!st) {
    sim_out out = {writer_sink, wr, ft, fs, p_truth, p_stim};
    st = sim_core(s, &out, opt, stats, err);
  }
  st = close_text(ft, p_truth, st, err);
  st = close_text(fs, p_stim, st, err);
  elfm_status cs = elfm_writer_close(wr, st ? NULL : err);
  return st ? st : cs;
}
