/* evt2.c — Prophesee EVT 2.0 decoder (32-bit little-endian words).
 *
 * Word types (OpenEB evt2_event_types.h; type in bits 31..28):
 *   0x0 CD_OFF / 0x1 CD_ON  t[5:0] in 27..22, x in 21..11, y in 10..0
 *   0x8 TIME_HIGH           t[33:6] in 27..0
 *   0xA EXT_TRIGGER         t[5:0] in 27..22, channel 12..8, value bit 0
 *   0xE OTHERS, 0xF CONTINUED, reserved: skipped.
 * Times reach 2^34 us (4.8 h); a TIME_HIGH far below the previous one (by
 * half the 28-bit range or more) is counted as a loop, as for EVT3.
 * Words before the first TIME_HIGH are dropped.
 */
#include "events_internal.h"

elfm_status elfm_evt2_decode(elfm_reader *r, elfm_event_chunk *c, elfm_error *err)
{
  elfm_evt2_state s = r->st.evt2;
  const uint8_t *b = r->buf;
  size_t pos = r->pos;
  const size_t end = pos + ((r->len - pos) & ~(size_t)3);
  size_t n = c->n;
  const size_t cap = c->cap;
  /* restrict: the arrays never overlap (keeps the pointers in registers). */
  int64_t *restrict const T = c->t_us;
  uint16_t *restrict const X = c->x;
  uint16_t *restrict const Y = c->y;
  uint8_t *restrict const P = c->p;
  const uint32_t xlim = r->x_lim, ylim = r->y_lim;
  elfm_status st = ELFM_OK;

  /* One event per word at most: bound the loop once, not per word. */
  const size_t stop = pos + 4 * ((end - pos) / 4 < cap - n ? (end - pos) / 4 : cap - n);
  /* Words before the first TIME_HIGH are dropped; after it, events need
   * no check of that. */
  if (!s.seen_th)
    while (pos < stop && (elfm_le32(b + pos) >> 28) != 0x8) pos += 4;
  while (pos < stop) {
    const uint32_t w = elfm_le32(b + pos);
    const uint32_t type = w >> 28;
    if (type <= 1) { /* CD_OFF, CD_ON */
      {
        const uint32_t x = (w >> 11) & 0x7FF, y = w & 0x7FF;
        const int64_t t = s.t_high | ((w >> 22) & 63);
        if ((x >= xlim) | (y >= ylim)) {
          st = elfm_error_set(err, ELFM_ERR_RANGE, r->path, r->buf_off + (int64_t)pos,
                              "EVT2 event at x=%u y=%u outside the sensor %ux%u", x, y, xlim,
                              ylim);
          goto out;
        }
        if (t < s.t_last) {
          if (!r->allow_unsorted) {
            st = elfm_error_set(err, ELFM_ERR_FORMAT, r->path, r->buf_off + (int64_t)pos,
                                "time goes back from %lld to %lld us", (long long)s.t_last,
                                (long long)t);
            goto out;
          }
          r->backward_steps++;
        }
        s.t_last = t;
        T[n] = t;
        X[n] = (uint16_t)x;
        Y[n] = (uint16_t)y;
        P[n] = (uint8_t)type;
        n++;
      }
    } else if (type == 0x8) { /* TIME_HIGH */
      elfm_evt2_time_high(&s, w);
    } else if (type == 0xA) { /* EXT_TRIGGER */
      if (!elfm_evt2_trigger(&s, c, w)) goto out;
    }
    pos += 4;
  }
out:
  r->need_more = (r->len - pos) < 4;
  r->pos = pos;
  c->n = n;
  r->st.evt2 = s;
  return st;
}
