/* frames.c — the framer: event chunks -> windowed frames (see elfm_frames.h).
 *
 * State: a FIFO of the events of the windows still open (time, pixel,
 * polarity); COUNT also a per-pixel "listed in this frame" stamp (EXP and
 * LIN keep each pixel's latest event in the frame being built). A window
 * is closed once an event at or after its end has
 * been pushed (times never decrease), or at finish(). Building a frame walks
 * the FIFO entries of its window once, then evaluates each listed pixel once
 * (a table of the decay over integer ages replaces exp() per pixel).
 * INTEGRAL also keeps each pixel's reference level, its time and latest
 * polarity, and a list of the pixels above the floor, so a frame costs
 * O(events + shown pixels), not O(sensor).
 */
#include "elfm_frames.h"

#include "big_alloc.h"

#include <limits.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

/* Decay tables longer than this many microseconds (1 s windows) are not
 * worth 4 MB: such frames are rare, so we fall back to exp(). */
#define ELFM_DECAY_TABLE_MAX_US 1000000

/* INTEGRAL: a pixel's reference is clamped to +-this many steps (start
 * levels too): a hot pixel firing ON at 1 kHz would otherwise climb to rate x
 * tau steps (100 at 100 ms), far above any object, and a stuck one without
 * end. 64 steps of 0.2 is e^12.8. */
#define INTEGRAL_CLAMP_STEPS 64.0f

/* Pixels ahead whose state a framer loop fetches before it needs it. */
#define PREFETCH_AHEAD 16

/* INTEGRAL: one pixel's state (16 bytes, so an event touches one line). */
typedef struct integral_px {
  int64_t t_us;              /* its latest event */
  float sum;                 /* reference level, in ON steps, as of t_us */
  uint8_t pol;               /* latest event 1 ON, 2 OFF, 0 none; 3 none yet, and sum is
                                a start level, held (no leak) until the first event */
  uint8_t shown;             /* listed in act[]: level above the floor */
} integral_px;

struct elfm_framer {
  elfm_framer_options opt;
  int w, h;
  /* FIFO ring of pending events: t and (pixel | polarity << 31). */
  int64_t *q_t;
  uint32_t *q_pix;
  size_t q_head, q_n, q_cap; /* q_cap a power of two */
  /* per pixel */
  uint32_t *stamp;           /* == cur_stamp: listed in the COUNT frame being built */
  uint32_t cur_stamp;
  float *decay;              /* decay[age_us] for age 0..dt, or NULL */
  /* INTEGRAL */
  integral_px *px;           /* per pixel, one cache line's quarter: read once per event */
  uint32_t *act;
  size_t n_act;
  int64_t t_integrated;      /* events before this time are in px[] */
  int64_t origin_us;         /* start of window 0, INT64_MIN until known */
  int64_t next_index;        /* window to emit next */
  int64_t next_t0;           /* its start (valid once origin_us is known) */
  /* ELFM_START_EACH_TRIGGER: rising edges after the windows emitted so far,
   * in time order (a ring; bounded by the edges of one chunk plus the open
   * windows'). */
  int64_t *trig_t;
  size_t trig_head, trig_n, trig_cap; /* trig_cap a power of two, or 0 */
  /* Every start: rising edges not yet counted into a window's end (a ring
   * like trig_t), and the count so far (elfm_frame.n_triggers). */
  int64_t *edge_t;
  size_t edge_head, edge_n, edge_cap;
  int64_t edges_counted;
  int64_t t_seen;            /* latest event time pushed (any polarity), INT64_MIN */
  int64_t t_last_kept;       /* latest event time kept in the FIFO */
  int have_events, finished;
};

elfm_frame *elfm_frame_create(int w, int h, elfm_error *err)
{
  if (w <= 0 || h <= 0 || (int64_t)w * h > (int64_t)1 << 31) {
    elfm_error_set(err, ELFM_ERR_INVALID, NULL, -1, "frame size %d x %d is invalid", w, h);
    return NULL;
  }
  elfm_frame *f = calloc(1, sizeof *f);
  size_t n = (size_t)w * (size_t)h;
  if (f) {
    f->cap = n; /* before the buffers: elfm_frame_free frees them by it */
    f->data = elfm_big_calloc(n, sizeof *f->data);
    f->idx = elfm_big_calloc(n, sizeof *f->idx);
  }
  if (!f || !f->data || !f->idx) {
    elfm_frame_free(f);
    elfm_error_set(err, ELFM_ERR_NOMEM, NULL, -1, "cannot allocate a %d x %d frame", w, h);
    return NULL;
  }
  f->w = w;
  f->h = h;
  return f;
}

void elfm_frame_free(elfm_frame *f)
{
  if (!f) return;
  elfm_big_free(f->data, f->cap, sizeof *f->data);
  elfm_big_free(f->idx, f->cap, sizeof *f->idx);
  free(f);
}

void elfm_frame_clear(elfm_frame *f)
{
  for (size_t i = 0; i < f->nnz; i++) f->data[f->idx[i]] = 0.0f;
  f->nnz = 0;
  f->nnz_recent = 0;
  f->recent_floor = 0.0f;
  f->n_events = 0;
  f->n_triggers = 0;
}

void elfm_frame_set(elfm_frame *f, uint32_t i, float value)
{
  if (i >= f->cap) return;
  if (f->data[i] == 0.0f) {
    size_t k;
    for (k = 0; k < f->nnz; k++)
      if (f->idx[k] == i) break;
    if (k == f->nnz) f->idx[f->nnz++] = i;
    f->nnz_recent = f->nnz; /* the new pixel may be either */
  }
  f->data[i] = value;
}

void elfm_frame_clear_like(elfm_frame *dst, const elfm_frame *src)
{
  elfm_frame_clear(dst);
  dst->t_us = src->t_us;
  dst->t_start_us = src->t_start_us;
  dst->t_end_us = src->t_end_us;
  dst->index = src->index;
  dst->n_events = src->n_events;
  dst->n_triggers = src->n_triggers;
  dst->recent_floor = 0.0f;
}

elfm_status elfm_frame_copy(elfm_frame *dst, const elfm_frame *src, elfm_error *err)
{
  if (dst->w != src->w || dst->h != src->h)
    return elfm_error_set(err, ELFM_ERR_INVALID, NULL, -1, "frame copy: %dx%d into %dx%d",
                          src->w, src->h, dst->w, dst->h);
  elfm_frame_clear_like(dst, src);
  for (size_t i = 0; i < src->nnz; i++) {
    uint32_t p = src->idx[i];
    dst->idx[i] = p;
    dst->data[p] = src->data[p];
  }
  dst->nnz = src->nnz;
  dst->recent_floor = src->recent_floor;
  dst->nnz_recent = src->nnz_recent;
  return ELFM_OK;
}

/* The output pixel of input pixel p (elfm_frame_bin): the row by a
 * multiply, as a division per pixel was ~5 % of `track --bin-px 2` on flow;
 * the double's rounding is off by at most one, then fixed. */
static inline uint32_t bin_pixel(uint32_t p, uint32_t sw, double inv_sw, uint32_t dw, uint32_t f)
{
  uint32_t y = (uint32_t)(p * inv_sw);
  if (y * sw > p) y--;
  else if ((y + 1) * sw <= p) y++;
  const uint32_t x = p - y * sw;
  return f == 2 ? (y >> 1) * dw + (x >> 1) : (y / f) * dw + x / f;
}

elfm_status elfm_frame_bin(elfm_frame *dst, const elfm_frame *src, int factor, elfm_error *err)
{
  if (factor < 1 || dst->w != (src->w + factor - 1) / factor ||
      dst->h != (src->h + factor - 1) / factor)
    return elfm_error_set(err, ELFM_ERR_INVALID, NULL, -1, "frame bin %d: %dx%d into %dx%d",
                          factor, src->w, src->h, dst->w, dst->h);
  elfm_frame_clear_like(dst, src);
  const size_t n = elfm_frame_n_window(src);
  const uint32_t sw = (uint32_t)src->w, dw = (uint32_t)dst->w, f = (uint32_t)factor;
  const double inv_sw = 1.0 / sw;
  for (size_t i = 0; i < n; i++) {
    /* the list is in event order, so its pixels lie all over both frames:
     * fetched ahead, as the framer does (the input's pixel further on than
     * the output's, whose place needs the input's index only) */
    if (i + 16 < n) __builtin_prefetch(src->data + src->idx[i + 16]);
    if (i + 8 < n) __builtin_prefetch(dst->data + bin_pixel(src->idx[i + 8], sw, inv_sw, dw, f), 1);
    const uint32_t p = src->idx[i];
    const float v = src->data[p];
    /* a zero is never stored, so a zero output pixel is an unlisted one */
    if (v == 0.0f || !elfm_frame_in_window(src, v)) continue;
    const uint32_t q = bin_pixel(p, sw, inv_sw, dw, f);
    const float old = dst->data[q];
    if (old == 0.0f) dst->idx[dst->nnz++] = q;
    if (fabsf(v) > fabsf(old)) dst->data[q] = v;
  }
  dst->nnz_recent = dst->nnz;
  return ELFM_OK;
}

void elfm_framer_options_default(elfm_framer_options *o)
{
  memset(o, 0, sizeof *o);
  o->dt_us = 1000;
  o->stride_us = 0;
  o->start = ELFM_START_FIRST_EVENT;
  o->trigger_channel = -1;
  o->repr = ELFM_REPR_EXP;
  o->tau_us = 1000.0;
  o->polarity = ELFM_POL_BOTH;
  o->off_weight = 1.0;
  o->tau_bright_us = 0.0;
}

elfm_status elfm_framer_options_check(const elfm_framer_options *o, elfm_error *err)
{
  /* 50 us: below this the EVK4's own timestamp jitter and refractory
   * period dominate (issue 4). 10 s: a frame per 10 s is no longer a video. */
  if (o->dt_us < 50 || o->dt_us > 10000000)
    return elfm_error_set(err, ELFM_ERR_INVALID, NULL, -1,
                          "dt_us %lld is outside 50..10000000", (long long)o->dt_us);
  if (o->stride_us < 0 || o->stride_us > o->dt_us)
    return elfm_error_set(err, ELFM_ERR_INVALID, NULL, -1,
                          "stride_us %lld must be 0 (= dt) or 1..dt_us (%lld)",
                          (long long)o->stride_us, (long long)o->dt_us);
  if ((o->repr == ELFM_REPR_EXP || o->repr == ELFM_REPR_LIN) &&
      (!isfinite(o->tau_us) || o->tau_us <= 0.0))
    return elfm_error_set(err, ELFM_ERR_INVALID, NULL, -1, "tau_us must be > 0");
  if (o->repr == ELFM_REPR_INTEGRAL) {
    if (!isfinite(o->tau_us) || o->tau_us <= 0.0)
      return elfm_error_set(err, ELFM_ERR_INVALID, NULL, -1, "tau_us (the integral's leak) must be > 0");
    if (!isfinite(o->tau_bright_us) || o->tau_bright_us < 0.0)
      return elfm_error_set(err, ELFM_ERR_INVALID, NULL, -1,
                            "tau_bright_us (the integral's leak above 0) must be >= 0");
    if (!(o->off_weight > 0.0 && o->off_weight <= 100.0))
      return elfm_error_set(err, ELFM_ERR_INVALID, NULL, -1,
                            "off_weight %g is outside (0, 100]", o->off_weight);
    if (o->polarity == ELFM_POL_ON || o->polarity == ELFM_POL_OFF)
      return elfm_error_set(err, ELFM_ERR_INVALID, NULL, -1,
                            "the integral needs both polarities (polarity both or signed)");
  }
  if ((unsigned)o->repr > ELFM_REPR_INTEGRAL)
    return elfm_error_set(err, ELFM_ERR_INVALID, NULL, -1, "unknown representation %d", (int)o->repr);
  if ((unsigned)o->polarity > ELFM_POL_SIGNED)
    return elfm_error_set(err, ELFM_ERR_INVALID, NULL, -1, "unknown polarity %d", (int)o->polarity);
  /* the floor tells older pixels by their smaller values: positive ones */
  if (o->deep_window_us != 0 &&
      (o->repr != ELFM_REPR_EXP || o->polarity == ELFM_POL_SIGNED ||
       o->start == ELFM_START_EACH_TRIGGER || o->deep_window_us <= o->dt_us ||
       o->deep_window_us > 10000000))
    return elfm_error_set(err, ELFM_ERR_INVALID, NULL, -1,
                          "deep_window_us %lld needs the exp surface, unsigned, on a fixed grid, "
                          "and dt_us (%lld) < it <= 10000000 (0 = off)",
                          (long long)o->deep_window_us, (long long)o->dt_us);
  if ((unsigned)o->start > ELFM_START_EACH_TRIGGER)
    return elfm_error_set(err, ELFM_ERR_INVALID, NULL, -1, "unknown start mode %d", (int)o->start);
  if (o->trigger_channel < -1 || o->trigger_channel > 255)
    return elfm_error_set(err, ELFM_ERR_INVALID, NULL, -1,
                          "trigger channel %d is outside -1 (any) .. 255", o->trigger_channel);
  return ELFM_OK;
}

static float framer_decay(const elfm_framer *f, int64_t age_us)
{
  if (f->decay) return f->decay[age_us];
  double a = (double)age_us / f->opt.tau_us;
  if (f->opt.repr == ELFM_REPR_EXP) return (float)(255.0 * exp(-a));
  return a >= 1.0 ? 0.0f : (float)(255.0 * (1.0 - a));
}

elfm_status elfm_framer_create(const elfm_framer_options *o, int width, int height,
                               elfm_framer **out, elfm_error *err)
{
  *out = NULL;
  elfm_status st = elfm_framer_options_check(o, err);
  if (st) return st;
  if (width <= 0 || height <= 0 || width > 32767 || height > 32767)
    return elfm_error_set(err, ELFM_ERR_INVALID, NULL, -1, "sensor size %d x %d is invalid",
                          width, height);
  elfm_framer *f = calloc(1, sizeof *f);
  if (!f) return elfm_error_set(err, ELFM_ERR_NOMEM, NULL, -1, "out of memory (framer)");
  f->opt = *o;
  if (f->opt.stride_us == 0) f->opt.stride_us = f->opt.dt_us;
  f->w = width;
  f->h = height;
  size_t n = (size_t)width * (size_t)height;
  f->q_cap = 1u << 16;
  f->q_t = malloc(f->q_cap * sizeof *f->q_t);
  f->q_pix = malloc(f->q_cap * sizeof *f->q_pix);
  f->stamp = elfm_big_calloc(n, sizeof *f->stamp);
  /* the oldest age a frame shows: the window's, or the deep window's */
  const int64_t max_age_us = o->deep_window_us > o->dt_us ? o->deep_window_us : o->dt_us;
  int table = (o->repr == ELFM_REPR_EXP || o->repr == ELFM_REPR_LIN) &&
              max_age_us <= ELFM_DECAY_TABLE_MAX_US;
  if (table) f->decay = malloc((size_t)(max_age_us + 1) * sizeof *f->decay);
  int integral = o->repr == ELFM_REPR_INTEGRAL;
  if (integral) {
    f->px = calloc(n, sizeof *f->px);
    f->act = malloc(n * sizeof *f->act);
  }
  if (!f->q_t || !f->q_pix || !f->stamp || (table && !f->decay) ||
      (integral && (!f->px || !f->act))) {
    elfm_framer_free(f);
    return elfm_error_set(err, ELFM_ERR_NOMEM, NULL, -1, "out of memory (framer %d x %d)",
                          width, height);
  }
  if (table) {
    float *d = f->decay;
    f->decay = NULL; /* framer_decay computes directly while the table is built */
    for (int64_t a = 0; a <= max_age_us; a++) d[a] = framer_decay(f, a);
    f->decay = d;
  }
  f->cur_stamp = 0;
  f->origin_us = INT64_MIN;
  f->t_seen = INT64_MIN;
  f->t_last_kept = INT64_MIN;
  f->t_integrated = INT64_MIN;
  if (o->start == ELFM_START_AT_TIME) f->origin_us = f->next_t0 = o->start_us;
  *out = f;
  return ELFM_OK;
}

void elfm_framer_free(elfm_framer *f)
{
  if (!f) return;
  free(f->q_t);
  free(f->q_pix);
  elfm_big_free(f->stamp, (size_t)f->w * (size_t)f->h, sizeof *f->stamp);
  free(f->decay);
  free(f->px);
  free(f->act);
  free(f->trig_t);
  free(f->edge_t);
  free(f);
}

int64_t elfm_framer_origin_us(const elfm_framer *f) { return f->origin_us; }

elfm_status elfm_framer_set_levels(elfm_framer *f, const float *level_steps, elfm_error *err)
{
  if (!f || !level_steps || f->opt.repr != ELFM_REPR_INTEGRAL)
    return elfm_error_set(err, ELFM_ERR_INVALID, NULL, -1,
                          "framer: starting levels need the integral representation");
  if (f->t_integrated != INT64_MIN || f->have_events)
    return elfm_error_set(err, ELFM_ERR_INVALID, NULL, -1,
                          "framer: starting levels must be set before the first event");
  const float clamp = INTEGRAL_CLAMP_STEPS, floor = (float)ELFM_INTEGRAL_FLOOR;
  const size_t n = (size_t)f->w * (size_t)f->h;
  f->n_act = 0;
  for (size_t i = 0; i < n; i++) {
    integral_px *p = &f->px[i];
    const float v = level_steps[i];
    if (!(v > 0)) { /* also NaN */
      memset(p, 0, sizeof *p);
      continue;
    }
    p->sum = v > clamp ? clamp : v;
    p->t_us = 0; /* unused while held (pol 3): the first event sets it */
    p->pol = 3;
    p->shown = p->sum > floor;
    if (p->shown) f->act[f->n_act++] = (uint32_t)i;
  }
  return ELFM_OK;
}

elfm_status elfm_levels_create(int width, int height, elfm_levels *out, elfm_error *err)
{
  memset(out, 0, sizeof *out);
  if (width <= 0 || height <= 0 || (int64_t)width * height > (int64_t)1 << 31)
    return elfm_error_set(err, ELFM_ERR_INVALID, NULL, -1, "levels: size %d x %d is invalid", width,
                          height);
  const size_t n = (size_t)width * (size_t)height;
  out->sum = calloc(n, sizeof *out->sum);
  out->min = calloc(n, sizeof *out->min);
  if (!out->sum || !out->min) {
    elfm_levels_free(out);
    return elfm_error_set(err, ELFM_ERR_NOMEM, NULL, -1, "out of memory (levels %d x %d)", width,
                          height);
  }
  out->w = width;
  out->h = height;
  out->t_first_us = INT64_MIN;
  return ELFM_OK;
}

void elfm_levels_free(elfm_levels *l)
{
  if (!l) return;
  free(l->sum);
  free(l->min);
  l->sum = l->min = NULL;
}

size_t elfm_levels_add(elfm_levels *l, const elfm_event_chunk *c, double off_weight, int64_t t_end_us)
{
  const float off = (float)off_weight;
  size_t k = 0;
  for (; k < c->n; k++) {
    const int64_t t = c->t_us[k];
    if (t >= t_end_us) break;
    if (c->x[k] >= l->w || c->y[k] >= l->h) continue; /* the framer reports these */
    if (l->t_first_us == INT64_MIN) l->t_first_us = t;
    const size_t i = (size_t)c->y[k] * (size_t)l->w + c->x[k];
    float v = l->sum[i] + (c->p[k] ? 1.0f : -off);
    l->sum[i] = v;
    if (v < l->min[i]) l->min[i] = v;
  }
  return k;
}

void elfm_levels_result(elfm_levels *l, double off_weight)
{
  /* after an OFF event the pixel is 0..1 step below its reference, half a
   * step on average: the start level is the deepest reference plus that */
  const size_t n = (size_t)l->w * (size_t)l->h;
  const float half = 0.5f * (float)off_weight;
  for (size_t i = 0; i < n; i++) l->sum[i] = l->min[i] < 0 ? -l->min[i] + half : 0.0f;
}

static int framer_grow(elfm_framer *f)
{
  size_t cap = f->q_cap * 2;
  int64_t *t = malloc(cap * sizeof *t);
  uint32_t *p = malloc(cap * sizeof *p);
  if (!t || !p) {
    free(t);
    free(p);
    return 0;
  }
  for (size_t i = 0; i < f->q_n; i++) {
    size_t k = (f->q_head + i) & (f->q_cap - 1);
    t[i] = f->q_t[k];
    p[i] = f->q_pix[k];
  }
  free(f->q_t);
  free(f->q_pix);
  f->q_t = t;
  f->q_pix = p;
  f->q_cap = cap;
  f->q_head = 0;
  return 1;
}

/* Double a ring of int64 times (trig_t, edge_t), its oldest first. */
static int ring_grow(int64_t **ring, size_t *head, size_t n, size_t *cap)
{
  size_t c2 = *cap ? 2 * *cap : 64;
  int64_t *t = malloc(c2 * sizeof *t);
  if (!t) return 0;
  for (size_t i = 0; i < n; i++) t[i] = (*ring)[(*head + i) & (*cap - 1)];
  free(*ring);
  *ring = t;
  *cap = c2;
  *head = 0;
  return 1;
}

elfm_status elfm_framer_push(elfm_framer *f, const elfm_event_chunk *c, elfm_error *err)
{
  const int each = f->opt.start == ELFM_START_EACH_TRIGGER;
  const int ch = f->opt.trigger_channel;
  if (f->origin_us == INT64_MIN && (f->opt.start == ELFM_START_FIRST_TRIGGER || each)) {
    for (size_t i = 0; i < c->n_trig; i++)
      if (c->trig[i].value == 1 && (ch < 0 || c->trig[i].channel == ch)) {
        f->origin_us = f->next_t0 = c->trig[i].t_us;
        break;
      }
  }
  for (size_t i = 0; i < c->n_trig; i++) {
    if (c->trig[i].value != 1 || (ch >= 0 && c->trig[i].channel != ch)) continue;
    if (f->edge_n == f->edge_cap && !ring_grow(&f->edge_t, &f->edge_head, f->edge_n, &f->edge_cap))
      return elfm_error_set(err, ELFM_ERR_NOMEM, NULL, -1, "out of memory counting trigger edges");
    f->edge_t[(f->edge_head + f->edge_n) & (f->edge_cap - 1)] = c->trig[i].t_us;
    f->edge_n++;
  }
  if (each && f->origin_us != INT64_MIN) {
    for (size_t i = 0; i < c->n_trig; i++) {
      const int64_t t = c->trig[i].t_us;
      /* the edge that set the origin opens window 0 already; edges must
       * come in time order, as the events do */
      if (c->trig[i].value != 1 || (ch >= 0 && c->trig[i].channel != ch) || t <= f->origin_us)
        continue;
      if (f->trig_n > 0 && t < f->trig_t[(f->trig_head + f->trig_n - 1) & (f->trig_cap - 1)])
        return elfm_error_set(err, ELFM_ERR_FORMAT, NULL, -1,
                              "trigger edge at %lld us is before the previous edge", (long long)t);
      if (f->trig_n == f->trig_cap && !ring_grow(&f->trig_t, &f->trig_head, f->trig_n, &f->trig_cap))
        return elfm_error_set(err, ELFM_ERR_NOMEM, NULL, -1, "out of memory holding trigger edges");
      f->trig_t[(f->trig_head + f->trig_n) & (f->trig_cap - 1)] = t;
      f->trig_n++;
    }
  }
  for (size_t i = 0; i < c->n; i++) {
    int64_t t = c->t_us[i];
    if (t < f->t_seen)
      return elfm_error_set(err, ELFM_ERR_FORMAT, NULL, -1,
                            "event time %lld us is before the previous event's %lld us",
                            (long long)t, (long long)f->t_seen);
    f->t_seen = t;
    if (c->x[i] >= f->w || c->y[i] >= f->h)
      return elfm_error_set(err, ELFM_ERR_RANGE, NULL, -1,
                            "event at (%u, %u) lies outside the %d x %d sensor",
                            (unsigned)c->x[i], (unsigned)c->y[i], f->w, f->h);
    int p = c->p[i] ? 1 : 0;
    if ((f->opt.polarity == ELFM_POL_ON && !p) || (f->opt.polarity == ELFM_POL_OFF && p))
      continue;
    if (f->origin_us == INT64_MIN) {
      if (f->opt.start != ELFM_START_FIRST_EVENT) continue; /* waiting for the trigger */
      f->origin_us = f->next_t0 = t;
    }
    if (t < f->origin_us) continue;
    if (f->q_n == f->q_cap && !framer_grow(f))
      return elfm_error_set(err, ELFM_ERR_NOMEM, NULL, -1,
                            "out of memory holding %zu events of open windows", f->q_n);
    size_t k = (f->q_head + f->q_n) & (f->q_cap - 1);
    f->q_t[k] = t;
    f->q_pix[k] = ((uint32_t)c->y[i] * (uint32_t)f->w + c->x[i]) | ((uint32_t)p << 31);
    f->q_n++;
    f->t_last_kept = t;
    f->have_events = 1;
  }
  return ELFM_OK;
}

void elfm_framer_finish(elfm_framer *f) { f->finished = 1; }

/* The leak over the time since the pixel's sum was last written: towards
 * 0 from either side, so a pixel below the floor stays below it until its
 * next event. */
static float integral_leak(const elfm_framer *f, const integral_px *p, int64_t t)
{
  if (p->pol == 3) return 1.0f; /* a start level: the object is there until it leaves */
  int64_t age = t - p->t_us;
  /* above 0, an object is there: its level fades with tau_bright_us
   * (elfm_frames.h); a residue below 0 goes with tau_us */
  const double tau = p->sum > 0 && f->opt.tau_bright_us > 0 ? f->opt.tau_bright_us : f->opt.tau_us;
  return age > 0 ? (float)exp(-(double)age / tau) : 1.0f;
}

/* INTEGRAL: add the events before t1 not yet integrated (with stride < dt
 * a window's first events were integrated for the window before), then
 * write the pixels whose level at t1 is above the floor. Returns the
 * number of events in [t0, t1).
 *
 * A pixel's sum is its reference level as of its latest event,
 * and a pixel fires only when its brightness has moved a whole step past
 * it: after an ON event the true level is 0..1 step above the reference,
 * after an OFF event 0..1 below. The reference alone lags on both flanks
 * of a moving object (low on the rising front, high on the falling back),
 * which puts the object's image behind it (0.4 px on test_frames_integral's
 * blob). So the level is the reference plus the expected half step in the
 * direction of the latest event, h = +1/2 after ON, -off_weight/2 after
 * OFF, leaked since that event.
 *
 * Between its events a pixel's level only leaks towards 0, so a pixel
 * below the floor stays there until its next event: only the pixels above
 * it are listed (act[]) and visited per frame, every other one is
 * brought up to date lazily at its next event. A frame costs O(events +
 * shown pixels), and sensor noise (a pixel's lone event every ~0.5 s)
 * costs one update per event, not one per frame for the leak's duration.
 * Frames only read the state: the frame at t1 does not depend on which
 * frames came before it. */
static size_t framer_integrate(elfm_framer *f, int64_t t0, int64_t t1, elfm_frame *out)
{
  /* The frame shows the level above the floor (elfm_frames.h). */
  const float clamp = INTEGRAL_CLAMP_STEPS, floor = (float)ELFM_INTEGRAL_FLOOR,
              gain = 255.0f / 8.0f;
  const float off = (float)f->opt.off_weight;
  /* half[pol]: pol 0 no event yet, 1 latest ON, 2 latest OFF, 3 a held start level */
  const float half[4] = {0.0f, 0.5f, -0.5f * off, 0.0f};
  size_t nev = 0;
  for (size_t i = 0; i < f->q_n; i++) {
    size_t k = (f->q_head + i) & (f->q_cap - 1);
    int64_t t = f->q_t[k];
    if (t >= t1) break;
    if (t >= t0) nev++;
    if (t < f->t_integrated) continue;
    /* the pixel states are 16 B each at random places in 15 MB (an EVK4):
     * fetch the one PREFETCH_AHEAD events on while this one is added */
    if (i + PREFETCH_AHEAD < f->q_n)
      __builtin_prefetch(&f->px[f->q_pix[(k + PREFETCH_AHEAD) & (f->q_cap - 1)] & 0x7fffffffu], 1);
    uint32_t pix = f->q_pix[k] & 0x7fffffffu;
    int on = (int)(f->q_pix[k] >> 31);
    integral_px *p = &f->px[pix];
    float v = p->sum * integral_leak(f, p, t) + (on ? 1.0f : -off);
    p->sum = v > clamp ? clamp : v < -clamp ? -clamp : v;
    p->t_us = t;
    p->pol = on ? 1 : 2;
    if (!p->shown && p->sum + half[p->pol] > floor) {
      p->shown = 1;
      f->act[f->n_act++] = pix;
    }
  }
  f->t_integrated = t1;
  size_t kept = 0;
  for (size_t i = 0; i < f->n_act; i++) {
    if (i + PREFETCH_AHEAD < f->n_act) __builtin_prefetch(&f->px[f->act[i + PREFETCH_AHEAD]], 1);
    uint32_t pix = f->act[i];
    integral_px *p = &f->px[pix];
    float v = (p->sum + half[p->pol]) * integral_leak(f, p, t1);
    if (!(v > floor)) {
      p->shown = 0;
      continue;
    }
    f->act[kept++] = pix;
    out->idx[out->nnz++] = pix;
    out->data[pix] = gain * (v - floor);
  }
  f->n_act = kept;
  return nev;
}

/* EXP, LIN, COUNT: the events of [t0, t1) only, or on a deep window's
 * EXP frame those of [t_from, t1) (t_from < t0). Returns the number in
 * [t0, t1). */
static size_t framer_window(elfm_framer *f, int64_t t_from, int64_t t0, int64_t t1, elfm_frame *out)
{
  const int sign = f->opt.polarity == ELFM_POL_SIGNED;
  size_t nev = 0;
  if (f->opt.repr == ELFM_REPR_COUNT) {
    if (++f->cur_stamp == 0) { /* wrapped after 2^32 frames: forget old stamps */
      memset(f->stamp, 0, (size_t)f->w * (size_t)f->h * sizeof *f->stamp);
      f->cur_stamp = 1;
    }
    const uint32_t stamp = f->cur_stamp;
    for (size_t i = 0; i < f->q_n; i++) {
      size_t k = (f->q_head + i) & (f->q_cap - 1);
      int64_t t = f->q_t[k];
      if (t >= t1) break;
      if (t < t0) continue; /* only when stride < dt left older events queued */
      uint32_t pix = f->q_pix[k] & 0x7fffffffu;
      uint8_t p = (uint8_t)(f->q_pix[k] >> 31);
      nev++;
      if (f->stamp[pix] != stamp) {
        f->stamp[pix] = stamp;
        out->idx[out->nnz++] = pix;
      }
      out->data[pix] += sign && !p ? -1.0f : 1.0f;
    }
    return nev;
  }
  /* EXP, LIN: each pixel's latest event, kept in the frame itself as its
   * age t1 - t (>= 1 us, exact in a float up to 2^24 us: dt is at most
   * 10^7) signed by its polarity, so a pixel is new while its value is 0
   * (the frame is 0 outside its list). One array read per event where a
   * stamp, a time and a polarity per pixel were three (12.9 MB on an EVK4;
   * docs/recon.md "The latest event kept in the frame"). */
  float *d = out->data;
  for (size_t i = 0; i < f->q_n; i++) {
    size_t k = (f->q_head + i) & (f->q_cap - 1);
    int64_t t = f->q_t[k];
    if (t >= t1) break;
    if (t < t_from) continue; /* only when stride < dt left older events queued */
    if (i + PREFETCH_AHEAD < f->q_n)
      __builtin_prefetch(&d[f->q_pix[(k + PREFETCH_AHEAD) & (f->q_cap - 1)] & 0x7fffffffu], 1);
    uint32_t pix = f->q_pix[k] & 0x7fffffffu;
    const float age = (float)(t1 - t);
    nev += t >= t0;
    if (d[pix] == 0.0f) out->idx[out->nnz++] = pix;
    d[pix] = (f->q_pix[k] >> 31) ? age : -age;
  }
  for (size_t i = 0; i < out->nnz; i++) {
    uint32_t pix = out->idx[i];
    const float e = d[pix];
    float v = framer_decay(f, (int64_t)fabsf(e));
    d[pix] = sign && e < 0 ? -v : v;
  }
  if (t_from < t0) {
    /* a deep window's: the window's pixels first (elfm_frame.nnz_recent),
     * so that its readers stop at the older ones (the order is free: the
     * refocus sorts the pixels) */
    const float fl = framer_decay(f, t1 - t0);
    size_t a = 0, b = out->nnz;
    while (a < b) {
      if (d[out->idx[a]] >= fl) {
        a++;
      } else {
        const uint32_t x = out->idx[a];
        out->idx[a] = out->idx[--b];
        out->idx[b] = x;
      }
    }
    out->nnz_recent = a;
  }
  return nev;
}

int elfm_framer_next(elfm_framer *f, elfm_frame *out)
{
  if (f->origin_us == INT64_MIN || out->w != f->w || out->h != f->h) return 0;
  const int64_t t0 = f->next_t0;
  int64_t t1 = t0 + f->opt.dt_us;
  /* ELFM_START_EACH_TRIGGER: an edge inside the window ends it there. Once
   * events up to t1 have been pushed, every edge before t1 has been too
   * (chunks come in time order), so the cut is final when the window closes. */
  while (f->trig_n > 0 && f->trig_t[f->trig_head] <= t0) {
    f->trig_head = (f->trig_head + 1) & (f->trig_cap - 1);
    f->trig_n--;
  }
  const int cut = f->trig_n > 0 && f->trig_t[f->trig_head] < t1;
  if (cut) t1 = f->trig_t[f->trig_head];
  int closed = f->t_seen != INT64_MIN && t1 <= f->t_seen;
  if (!closed && f->finished) closed = f->have_events && t0 <= f->t_last_kept;
  if (!closed) return 0;

  elfm_frame_clear(out);
  /* a deep window's surface reaches back before the window (t0 is never
   * cut on its fixed grid) */
  const int64_t deep_us = f->opt.deep_window_us;
  size_t nev = f->opt.repr == ELFM_REPR_INTEGRAL ? framer_integrate(f, t0, t1, out)
                                                 : framer_window(f, deep_us ? t1 - deep_us : t0, t0, t1, out);
  /* age t1 - t0 is the window's oldest: every age up to it decays to at
   * least this value, every older one (by 1 us or more) below it */
  out->recent_floor = deep_us ? framer_decay(f, t1 - t0) : 0.0f;
  const int count = f->opt.repr == ELFM_REPR_COUNT;
  out->n_events = nev;
  /* edges come in time order, so those before t1 are all pushed by now */
  while (f->edge_n > 0 && f->edge_t[f->edge_head] < t1) {
    f->edge_head = (f->edge_head + 1) & (f->edge_cap - 1);
    f->edge_n--;
    f->edges_counted++;
  }
  out->n_triggers = f->edges_counted;
  out->t_start_us = t0;
  out->t_end_us = t1;
  out->t_us = count ? t0 + (t1 - t0) / 2 : t1;
  out->index = f->next_index;
  f->next_index++;
  /* drop what no later window needs (a deep window: reaching back
   * deep_window_us from the next window's end) */
  const int64_t next_t0 = cut ? t1 : t0 + f->opt.stride_us;
  f->next_t0 = next_t0;
  const int64_t keep_from = deep_us ? next_t0 + f->opt.dt_us - deep_us : next_t0;
  while (f->q_n > 0 && f->q_t[f->q_head] < keep_from) {
    f->q_head = (f->q_head + 1) & (f->q_cap - 1);
    f->q_n--;
  }
  return 1;
}
