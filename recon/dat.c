/* dat.c — Prophesee DAT (Event2D) decoder: 8-byte records after the
 * header's type/size bytes: u32 t_us, u32 with x in bits 13..0, y in
 * 27..14 and polarity in bit 28 (little-endian). The 32-bit time wraps
 * every 71.6 minutes; a drop of more than half the range is a wrap. */
#include "events_internal.h"

elfm_status elfm_dat_decode(elfm_reader *r, elfm_event_chunk *c, elfm_error *err)
{
  elfm_dat_state s = r->st.dat;
  const uint8_t *b = r->buf;
  size_t pos = r->pos;
  const size_t end = pos + ((r->len - pos) & ~(size_t)7);
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
  const size_t stop = pos + 8 * ((end - pos) / 8 < cap - n ? (end - pos) / 8 : cap - n);
  while (pos < stop) {
    const uint32_t t32 = elfm_le32(b + pos), d = elfm_le32(b + pos + 4);
    const uint32_t x = d & 0x3FFF, y = (d >> 14) & 0x3FFF;
    int64_t t = s.wrap + t32;
    if ((x >= xlim) | (y >= ylim)) {
      st = elfm_error_set(err, ELFM_ERR_RANGE, r->path, r->buf_off + (int64_t)pos,
                          "DAT event at x=%u y=%u outside the sensor %ux%u", x, y, xlim, ylim);
      goto out;
    }
    if (t < s.t_last) {
      if (s.t_last - t > ((int64_t)1 << 31)) {
        s.wrap += (int64_t)1 << 32;
        t += (int64_t)1 << 32;
      } else if (!r->allow_unsorted) {
        st = elfm_error_set(err, ELFM_ERR_FORMAT, r->path, r->buf_off + (int64_t)pos,
                            "time goes back from %lld to %lld us", (long long)s.t_last,
                            (long long)t);
        goto out;
      } else {
        r->backward_steps++;
      }
    }
    s.t_last = t;
    T[n] = t;
    X[n] = (uint16_t)x;
    Y[n] = (uint16_t)y;
    P[n] = (uint8_t)((d >> 28) & 1);
    n++;
    pos += 8;
  }
out:
  r->need_more = (r->len - pos) < 8;
  r->pos = pos;
  c->n = n;
  r->st.dat = s;
  return st;
}
