/* evt3.c — Prophesee EVT 3.0 decoder (16-bit little-endian words).
 *
 * Word types (OpenEB evt3_event_types.h; type in bits 15..12):
 *   0x0 ADDR_Y      y[10:0] (bit 11: master/slave, ignored)
 *   0x2 ADDR_X      x[10:0], polarity bit 11: one CD event at (x, y, t)
 *   0x3 VECT_BASE_X x[10:0], polarity bit 11: base of the next vectors
 *   0x4 VECT_12     valid mask [11:0]: events at base+i; base += 12
 *   0x5 VECT_8      valid mask [7:0];  base += 8
 *   0x6 TIME_LOW    t[11:0]
 *   0x8 TIME_HIGH   t[23:12]; resets TIME_LOW to 0
 *   0xA EXT_TRIGGER value bit 0, channel [11:8]
 *   0x7/0xE/0xF continued/others, 0x9999 padding and reserved: skipped.
 * Timestamps are 24 bits and loop every 2^24 us; a new TIME_HIGH at least
 * 2048 (half the 12-bit range) below the previous one starts a new loop.
 * Words before the first TIME_HIGH are dropped (the camera starts mid-
 * stream), as are events before the first ADDR_Y / VECT_BASE_X.
 *
 * Speed: the state lives in locals (registers) for the whole buffer, the
 * switch compiles to a jump table, and vectors are written branch-free:
 * all 12 (or 8) slots are stored and the count advances by each mask bit,
 * which the reader's "room for 12 events" guarantee makes safe.
 */
#include "events_internal.h"

static elfm_status backward(elfm_reader *r, int64_t off, int64_t t_from, int64_t t_to,
                            elfm_error *err)
{
  if (r->allow_unsorted) {
    r->backward_steps++;
    return ELFM_OK;
  }
  return elfm_error_set(err, ELFM_ERR_FORMAT, r->path, off,
                        "time goes back from %lld to %lld us", (long long)t_from,
                        (long long)t_to);
}

elfm_status elfm_evt3_decode(elfm_reader *r, elfm_event_chunk *c, elfm_error *err)
{
  elfm_evt3_state s = r->st.evt3;
  const uint8_t *b = r->buf;
  size_t pos = r->pos;
  const size_t end = pos + ((r->len - pos) & ~(size_t)1);
  size_t n = c->n;
  /* The caller guarantees room for 12 events at entry. */
  const size_t lim = c->cap - 12;
  int64_t *T = c->t_us;
  uint16_t *X = c->x, *Y = c->y;
  uint8_t *P = c->p;
  const uint32_t xlim = r->x_lim, ylim = r->y_lim;
  elfm_status st = ELFM_OK;

  while (pos < end && n <= lim) {
    const uint32_t w = elfm_le16(b + pos);
    switch (w >> 12) {
    case 0x0: { /* ADDR_Y */
      if (!s.seen_th) break;
      uint32_t y = w & 0x7FF;
      if (y >= ylim) {
        st = elfm_error_set(err, ELFM_ERR_RANGE, r->path, r->buf_off + (int64_t)pos,
                            "EVT3 ADDR_Y y=%u outside the sensor height %u", y, ylim);
        goto out;
      }
      s.y = y;
      s.seen_y = 1;
      break;
    }
    case 0x2: { /* ADDR_X: one event */
      if (!s.seen_y) break;
      uint32_t x = w & 0x7FF;
      if (x >= xlim) {
        st = elfm_error_set(err, ELFM_ERR_RANGE, r->path, r->buf_off + (int64_t)pos,
                            "EVT3 ADDR_X x=%u outside the sensor width %u", x, xlim);
        goto out;
      }
      if (s.t < s.t_emit) {
        st = backward(r, r->buf_off + (int64_t)pos, s.t_emit, s.t, err);
        if (st != ELFM_OK) goto out;
      }
      s.t_emit = s.t;
      T[n] = s.t;
      X[n] = (uint16_t)x;
      Y[n] = (uint16_t)s.y;
      P[n] = (uint8_t)((w >> 11) & 1);
      n++;
      break;
    }
    case 0x3: /* VECT_BASE_X */
      s.vx = w & 0x7FF;
      s.vp = (w >> 11) & 1;
      s.seen_base = 1;
      break;
    case 0x4:   /* VECT_12 */
    case 0x5: { /* VECT_8 */
      const uint32_t nbits = (w >> 12) == 0x4 ? 12 : 8;
      const uint32_t mask = w & ((1u << nbits) - 1);
      const uint32_t x0 = s.vx;
      s.vx += nbits;
      if (!s.seen_y || !s.seen_base || !mask) break;
      /* Highest set bit must land inside the sensor. */
      const uint32_t xhi = x0 + 31 - (uint32_t)__builtin_clz(mask);
      if (xhi >= xlim) {
        st = elfm_error_set(err, ELFM_ERR_RANGE, r->path, r->buf_off + (int64_t)pos,
                            "EVT3 vector runs past the sensor width: x=%u >= %u", xhi, xlim);
        goto out;
      }
      if (s.t < s.t_emit) {
        st = backward(r, r->buf_off + (int64_t)pos, s.t_emit, s.t, err);
        if (st != ELFM_OK) goto out;
      }
      s.t_emit = s.t;
      const int64_t t = s.t;
      const uint16_t y = (uint16_t)s.y;
      const uint8_t p = (uint8_t)s.vp;
      if (nbits == 12) {
        for (uint32_t i = 0; i < 12; i++) {
          T[n] = t;
          X[n] = (uint16_t)(x0 + i);
          Y[n] = y;
          P[n] = p;
          n += (mask >> i) & 1;
        }
      } else {
        for (uint32_t i = 0; i < 8; i++) {
          T[n] = t;
          X[n] = (uint16_t)(x0 + i);
          Y[n] = y;
          P[n] = p;
          n += (mask >> i) & 1;
        }
      }
      break;
    }
    case 0x6: /* TIME_LOW */
      if (!s.seen_th) break;
      s.t = s.t_base | (int64_t)(w & 0xFFF);
      break;
    case 0x8: { /* TIME_HIGH */
      const uint32_t th = w & 0xFFF;
      if (s.seen_th && th + 2048 <= s.prev_th) s.loops++;
      s.prev_th = th;
      s.t_base = (s.loops << 24) | ((int64_t)th << 12);
      s.t = s.t_base;
      if (!s.seen_th) {
        s.seen_th = 1;
        s.t_emit = s.t;
      }
      break;
    }
    case 0xA: /* EXT_TRIGGER */
      if (!s.seen_th || !c->cap_trig) break;
      if (c->n_trig >= c->cap_trig) goto out; /* resume at this word */
      c->trig[c->n_trig].t_us = s.t;
      c->trig[c->n_trig].channel = (uint8_t)((w >> 8) & 0xF);
      c->trig[c->n_trig].value = (uint8_t)(w & 1);
      c->n_trig++;
      break;
    default: /* CONTINUED_4/12, OTHERS, 0x9999 padding, reserved */
      break;
    }
    pos += 2;
  }
out:
  r->need_more = (r->len - pos) < 2;
  r->pos = pos;
  c->n = n;
  r->st.evt3 = s;
  return st;
}
