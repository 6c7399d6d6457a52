/* sim_step.c — the physics of one time slice: where each object's images
 * fall and how bright they are (Fourier LFM optics), the event pixel model
 * stepped over the pixels whose light changes, and the background activity
 * drawn analytically over the whole sensor. See docs/simulator.md.
 *
 *  1. Each object's images: one box per object and view covering where the
 *     image is during [slice start - one slice, slice end] (the look-back
 *     keeps pixels stepping until their photoreceptor has settled after an
 *     image left). Objects that move or blink are "dynamic"; the others are
 *     part of a static base image of the sensor.
 *  2. Time steps over the slice: short enough that an image moves <= 0.75
 *     sigma per step, split at every light edge (LED, spikes).
 *  3. Per step, band by band: add the dynamic images, then step the pixels
 *     under them and those still settling (v2e / ESIM model): log; first-order
 *     low-pass whose bandwidth rises with the photocurrent; ON/OFF events at
 *     each threshold crossing with linearly interpolated times, reference
 *     reset by whole thresholds, refractory period, latency + jitter.
 *  4. Background activity: shot noise and leak as Poisson processes over the
 *     whole sensor, plus hot pixels; the 0.9 M quiet pixels are never stepped.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "sim_ws.h"

/* Grow *p to hold `need` elements (doubling). 0 on out of memory. Only
 * called when a slice needs more than any before it. */
int sim_grow(void **p, size_t *cap, size_t need, size_t elem)
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

void sim_ws_free(sim_ws *w)
{
  free(w->px); free(w->carry); free(w->carry_next);
  free(w->box); free(w->img); free(w->gbuf); free(w->os); free(w->dyn_obj);
  free(w->ev); free(w->sorted); free(w->counts);
  free(w->steps); free(w->gx); free(w->gy);
  free(w->c_t); free(w->c_x); free(w->c_y); free(w->c_p); free(w->c_trig);
  free(w->stim);
}

elfm_status sim_ws_init(sim_ws *w, const elfm_scene *s, elfm_error *err)
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
    sim_ws_free(w);
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
elfm_status sim_plan_slice(sim_ws *w, int64_t a, int64_t b, elfm_error *err)
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
        if (!sim_grow((void **)&w->box, &w->cap_box, w->n_box + 1, sizeof *w->box))
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
      !sim_grow((void **)&w->ev, &w->cap_ev, w->n_ev + 1, sizeof *w->ev))
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
    if (!sim_grow((void **)&w->gx, &w->cap_gx, need, sizeof *w->gx) ||
        !sim_grow((void **)&w->gy, &w->cap_gy, need, sizeof *w->gy))
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
        !sim_grow((void **)&w->carry_next, &w->cap_carry_next, w->n_carry_next + 1,
              sizeof *w->carry_next))
      return elfm_error_set(err, ELFM_ERR_NOMEM, w->s->source, -1, "out of memory");
    w->carry_next[w->n_carry_next++] = (int32_t)pix;
  }
  return ELFM_OK;
}

/* ---- step 2/3: the time steps of a slice ---- */
elfm_status sim_step_slice(sim_ws *w, int64_t q, int64_t a, int64_t b, elfm_error *err)
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
  if (!sim_grow((void **)&w->gx, &w->cap_gx, gneed + 2, sizeof *w->gx) ||
      !sim_grow((void **)&w->gy, &w->cap_gy, gneed + 2, sizeof *w->gy) ||
      !sim_grow((void **)&w->img, &w->cap_img, w->n_box + 1, sizeof *w->img))
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
  if (!sim_grow((void **)&w->steps, &w->cap_steps, need, sizeof *w->steps))
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
    const double sdt = (double)(tb - ta);
    if (++w->step_id == 0) { /* wrapped after 2^32 steps: forget old marks */
      for (size_t p = 0; p < w->npix; p++) w->px[p].mark = 0;
      w->step_id = 1;
    }
    const uint32_t sid = w->step_id;
    w->st.n_steps++;
    for (size_t k = 0; k < w->n_dyn; k++) {
      int ob = w->dyn_obj[k];
      sim_objslice *o = &w->os[ob];
      /* Where the object is at the step's end, not its middle: the
       * photoreceptor's backward-Euler step below reads its input at the
       * step's end, and so lags a ramp by exactly its time constant at any
       * step length. Read at the middle, the input was half a step old:
       * the events lagged by half a step (~100 us on flow, whose steps are
       * ~200 us; test_sim "step size", docs/simulator.md "Time steps"). The
       * light (amp_hz) is constant over the step: steps split at its edges. */
      sim_object_position(s, ob, (double)tb, o->pos, NULL);
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
        if (!sim_grow((void **)&w->gbuf, &w->cap_gbuf, gpos + nx + ny, sizeof *w->gbuf))
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

elfm_status sim_noise_slice(sim_ws *w, int64_t q, int64_t a, int64_t b, elfm_error *err)
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

