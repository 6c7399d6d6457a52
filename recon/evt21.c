/* evt21.c — Prophesee EVT 2.1 decoder (64-bit words).
 *
 * Layout (OpenEB evt21_event_types.h): the 32-bit "event half" carries the
 * type in 31..28, t[5:0] in 27..22, x (base, aligned to 32) in 21..11 and
 * y in 10..0; the other half is a valid mask (bit i: event at x + i).
 * TIME_HIGH holds t[33:6] in 27..0; EXT_TRIGGER t[5:0], channel 12..8,
 * value bit 0. Standard files (GenX320, "% format EVT21") store the whole
 * word little-endian, so the event half comes second; IMX636 files
 * ("endianness=legacy", or the old "% evt 2.1" header) send the event half
 * first. Words before the first TIME_HIGH are dropped.
 */
#include "events_internal.h"

elfm_status elfm_evt21_decode(elfm_reader *r, elfm_event_chunk *c, elfm_error *err)
{
  elfm_evt2_state s = r->st.evt2;
  const uint8_t *b = r->buf;
  size_t pos = r->pos;
  const size_t end = pos + ((r->len - pos) & ~(size_t)7);
  size_t n = c->n;
  const size_t lim = c->cap - 32; /* room for a full mask guaranteed at entry */
  int64_t *T = c->t_us;
  uint16_t *X = c->x, *Y = c->y;
  uint8_t *P = c->p;
  const uint32_t xlim = r->x_lim, ylim = r->y_lim;
  const size_t ev_off = r->evt21_legacy ? 0 : 4, mask_off = r->evt21_legacy ? 4 : 0;
  elfm_status st = ELFM_OK;

  while (pos < end && n <= lim) {
    const uint32_t w = elfm_le32(b + pos + ev_off);
    const uint32_t type = w >> 28;
    if (type <= 1) {
      uint32_t m = elfm_le32(b + pos + mask_off);
      if (s.seen_th && m) {
        const uint32_t x0 = (w >> 11) & 0x7FF, y = w & 0x7FF;
        const int64_t t = s.t_high | ((w >> 22) & 63);
        const uint32_t xhi = x0 + 31 - (uint32_t)__builtin_clz(m);
        if ((xhi >= xlim) | (y >= ylim)) {
          st = elfm_error_set(err, ELFM_ERR_RANGE, r->path, r->buf_off + (int64_t)pos,
                              "EVT2.1 event at x=%u y=%u outside the sensor %ux%u", xhi, y,
                              xlim, ylim);
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
        while (m) {
          const uint32_t i = (uint32_t)__builtin_ctz(m);
          m &= m - 1;
          T[n] = t;
          X[n] = (uint16_t)(x0 + i);
          Y[n] = (uint16_t)y;
          P[n] = (uint8_t)type;
          n++;
        }
      }
    } else if (type == 0x8) {
      elfm_evt2_time_high(&s, w);
    } else if (type == 0xA) {
      if (!elfm_evt2_trigger(&s, c, w)) goto out;
    }
    pos += 8;
  }
out:
  r->need_more = (r->len - pos) < 8;
  r->pos = pos;
  c->n = n;
  r->st.evt2 = s;
  return st;
}
