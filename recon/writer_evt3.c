/* writer_evt3.c — EVT 3.0 encoder (the inverse of evt3.c).
 *
 * Per event: TIME_HIGH/TIME_LOW when the time changes, ADDR_Y when the row
 * changes, then either ADDR_X or, when three or more consecutive events
 * share time, row and polarity and fit within 12 columns, VECT_BASE_X +
 * VECT_12 (a following group that starts within the next 12 columns just
 * adds another VECT_12). Event order is kept exactly.
 *
 * Absolute times: EVT3 carries only 24 bits, and a reader counts a loop
 * when TIME_HIGH drops by >= 2048. So TIME_HIGH never advances by more than
 * 2047 steps of 4096 us (8.4 s) at once: a longer gap, or a file
 * starting at t = 913 s, is bridged by intermediate TIME_HIGH words (one
 * per 8.4 s, ~110 words for 913 s), which any EVT3 reader follows to the
 * right loop count.
 */
#include <stdio.h>

#include "events_internal.h"

#define W_ADDR_Y 0x0000u
#define W_ADDR_X 0x2000u
#define W_VECT_BASE_X 0x3000u
#define W_VECT_12 0x4000u
#define W_TIME_LOW 0x6000u
#define W_TIME_HIGH 0x8000u
#define W_EXT_TRIGGER 0xA000u
/* Largest TIME_HIGH step that cannot be mistaken for a loop (see top). */
#define MAX_TH_STEP 2047

static inline void put16(elfm_writer *w, uint32_t v)
{
  w->buf[w->len++] = (uint8_t)(v & 0xFF);
  w->buf[w->len++] = (uint8_t)(v >> 8);
}

elfm_status elfm_evt3_write_header(elfm_writer *w, elfm_error *err)
{
  int n = snprintf((char *)w->buf, w->cap,
                   "%% evt 3.0\n"
                   "%% format EVT3;height=%d;width=%d\n"
                   "%% geometry %dx%d\n"
                   "%% integrator_name EventLFM\n"
                   "%% end\n",
                   w->height, w->width, w->width, w->height);
  if (n < 0 || (size_t)n >= w->cap)
    return elfm_error_set(err, ELFM_ERR_INVALID, w->path, 0, "header does not fit");
  w->len = (size_t)n;
  return ELFM_OK;
}

/* Emit the time words for t (at most ~2 words unless bridging a gap). */
static elfm_status put_time(elfm_writer *w, int64_t t, elfm_error *err)
{
  elfm_writer_evt3_state *s = &w->evt3;
  const int64_t th = t >> 12;
  if (th != s->th_abs) {
    int64_t cur = s->th_abs;
    if (cur < 0) {
      /* A fresh reader is in loop 0: start at 0 when t is beyond it. */
      cur = th < 4096 ? th : 0;
      if (elfm_writer_reserve(w, 2, err)) return ELFM_ERR_IO;
      put16(w, W_TIME_HIGH | (uint32_t)(cur & 0xFFF));
    }
    while (cur < th) {
      cur = th - cur > MAX_TH_STEP ? cur + MAX_TH_STEP : th;
      if (elfm_writer_reserve(w, 2, err)) return ELFM_ERR_IO;
      put16(w, W_TIME_HIGH | (uint32_t)(cur & 0xFFF));
    }
    s->th_abs = th;
    s->low = -1; /* always restate TIME_LOW after TIME_HIGH */
  }
  const int64_t low = t & 0xFFF;
  if (low != s->low) {
    if (elfm_writer_reserve(w, 2, err)) return ELFM_ERR_IO;
    put16(w, W_TIME_LOW | (uint32_t)low);
    s->low = low;
  }
  return ELFM_OK;
}

elfm_status elfm_evt3_write_events(elfm_writer *w, const elfm_event_chunk *c, elfm_error *err)
{
  elfm_writer_evt3_state *s = &w->evt3;
  size_t i = 0, k = 0;
  const size_t n = c->n;
  /* Vector base left by the last VECT_12 (chaining), -1 when none. */
  int64_t vnext = -1;
  uint32_t vp = 0;
  while (i < n || k < c->n_trig) {
    /* Triggers go before events of the same or a later time. */
    if (k < c->n_trig && (i >= n || c->trig[k].t_us <= c->t_us[i])) {
      if (put_time(w, c->trig[k].t_us, err)) return ELFM_ERR_IO;
      if (elfm_writer_reserve(w, 2, err)) return ELFM_ERR_IO;
      put16(w, W_EXT_TRIGGER | ((uint32_t)(c->trig[k].channel & 0xF) << 8) |
                   (uint32_t)(c->trig[k].value & 1));
      k++;
      continue;
    }
    const int64_t t = c->t_us[i];
    const uint32_t y = c->y[i], p = c->p[i], x0 = c->x[i];
    if (put_time(w, t, err)) return ELFM_ERR_IO;
    /* The most words one step can add: ADDR_Y + VECT_BASE_X + VECT_12. */
    if (elfm_writer_reserve(w, 6, err)) return ELFM_ERR_IO;
    if ((int64_t)y != s->y) {
      put16(w, W_ADDR_Y | y);
      s->y = y;
    }
    /* Can the events from i on continue the previous vector? */
    uint32_t base = x0;
    int chained = vnext >= 0 && p == vp && x0 >= (uint32_t)vnext && x0 < (uint32_t)vnext + 12;
    if (chained) base = (uint32_t)vnext;
    uint32_t mask = 1u << (x0 - base), cnt = 1;
    size_t j = i + 1;
    uint32_t xprev = x0;
    while (j < n && c->t_us[j] == t && c->y[j] == y && c->p[j] == p && c->x[j] > xprev &&
           c->x[j] < base + 12) {
      xprev = c->x[j];
      mask |= 1u << (xprev - base);
      cnt++;
      j++;
    }
    if (chained || cnt >= 3) {
      if (!chained) put16(w, W_VECT_BASE_X | (p << 11) | base);
      put16(w, W_VECT_12 | mask);
      vnext = base + 12;
      vp = p;
      i = j;
    } else {
      put16(w, W_ADDR_X | (p << 11) | x0);
      i++;
    }
  }
  if (n) w->t_last = c->t_us[n - 1];
  if (c->n_trig && c->trig[c->n_trig - 1].t_us > w->t_last) w->t_last = c->trig[c->n_trig - 1].t_us;
  return ELFM_OK;
}
