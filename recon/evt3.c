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
 * Speed: see the fast path below: per word one store into a little
 * register file indexed by the word type, four stores of a would-be event,
 * and no branch that depends on the word type except vectors'.
 */
#include <string.h>
#if defined(__SSE2__)
#include <emmintrin.h>
#endif

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

/* Set-bit positions (then zeros) and bit counts of every 6-bit value:
 * a VECT_12 mask is two 6-bit halves, and these tables turn each half
 * into the x offsets of its events without a loop over the bits.
 * (Generated: row m lists the i in 0..5 with bit i of m set.) */
static const uint8_t evt3_pos6[64][8] = {
    {0, 0, 0, 0, 0, 0, 0, 0}, {0, 0, 0, 0, 0, 0, 0, 0}, {1, 0, 0, 0, 0, 0, 0, 0}, {0, 1, 0, 0, 0, 0, 0, 0},
    {2, 0, 0, 0, 0, 0, 0, 0}, {0, 2, 0, 0, 0, 0, 0, 0}, {1, 2, 0, 0, 0, 0, 0, 0}, {0, 1, 2, 0, 0, 0, 0, 0},
    {3, 0, 0, 0, 0, 0, 0, 0}, {0, 3, 0, 0, 0, 0, 0, 0}, {1, 3, 0, 0, 0, 0, 0, 0}, {0, 1, 3, 0, 0, 0, 0, 0},
    {2, 3, 0, 0, 0, 0, 0, 0}, {0, 2, 3, 0, 0, 0, 0, 0}, {1, 2, 3, 0, 0, 0, 0, 0}, {0, 1, 2, 3, 0, 0, 0, 0},
    {4, 0, 0, 0, 0, 0, 0, 0}, {0, 4, 0, 0, 0, 0, 0, 0}, {1, 4, 0, 0, 0, 0, 0, 0}, {0, 1, 4, 0, 0, 0, 0, 0},
    {2, 4, 0, 0, 0, 0, 0, 0}, {0, 2, 4, 0, 0, 0, 0, 0}, {1, 2, 4, 0, 0, 0, 0, 0}, {0, 1, 2, 4, 0, 0, 0, 0},
    {3, 4, 0, 0, 0, 0, 0, 0}, {0, 3, 4, 0, 0, 0, 0, 0}, {1, 3, 4, 0, 0, 0, 0, 0}, {0, 1, 3, 4, 0, 0, 0, 0},
    {2, 3, 4, 0, 0, 0, 0, 0}, {0, 2, 3, 4, 0, 0, 0, 0}, {1, 2, 3, 4, 0, 0, 0, 0}, {0, 1, 2, 3, 4, 0, 0, 0},
    {5, 0, 0, 0, 0, 0, 0, 0}, {0, 5, 0, 0, 0, 0, 0, 0}, {1, 5, 0, 0, 0, 0, 0, 0}, {0, 1, 5, 0, 0, 0, 0, 0},
    {2, 5, 0, 0, 0, 0, 0, 0}, {0, 2, 5, 0, 0, 0, 0, 0}, {1, 2, 5, 0, 0, 0, 0, 0}, {0, 1, 2, 5, 0, 0, 0, 0},
    {3, 5, 0, 0, 0, 0, 0, 0}, {0, 3, 5, 0, 0, 0, 0, 0}, {1, 3, 5, 0, 0, 0, 0, 0}, {0, 1, 3, 5, 0, 0, 0, 0},
    {2, 3, 5, 0, 0, 0, 0, 0}, {0, 2, 3, 5, 0, 0, 0, 0}, {1, 2, 3, 5, 0, 0, 0, 0}, {0, 1, 2, 3, 5, 0, 0, 0},
    {4, 5, 0, 0, 0, 0, 0, 0}, {0, 4, 5, 0, 0, 0, 0, 0}, {1, 4, 5, 0, 0, 0, 0, 0}, {0, 1, 4, 5, 0, 0, 0, 0},
    {2, 4, 5, 0, 0, 0, 0, 0}, {0, 2, 4, 5, 0, 0, 0, 0}, {1, 2, 4, 5, 0, 0, 0, 0}, {0, 1, 2, 4, 5, 0, 0, 0},
    {3, 4, 5, 0, 0, 0, 0, 0}, {0, 3, 4, 5, 0, 0, 0, 0}, {1, 3, 4, 5, 0, 0, 0, 0}, {0, 1, 3, 4, 5, 0, 0, 0},
    {2, 3, 4, 5, 0, 0, 0, 0}, {0, 2, 3, 4, 5, 0, 0, 0}, {1, 2, 3, 4, 5, 0, 0, 0}, {0, 1, 2, 3, 4, 5, 0, 0},
};
static const uint8_t evt3_cnt6[64] = {
    0, 1, 1, 2, 1, 2, 2, 3, 1, 2, 2, 3, 2, 3, 3, 4,
    1, 2, 2, 3, 2, 3, 3, 4, 2, 3, 3, 4, 3, 4, 4, 5,
    1, 2, 2, 3, 2, 3, 3, 4, 2, 3, 3, 4, 3, 4, 4, 5,
    2, 3, 3, 4, 3, 4, 4, 5, 3, 4, 4, 5, 4, 5, 5, 6,
};

/* X[0..7] = x0 + pos[0..7]: the x of one 6-bit half of a vector mask.
 * One SSE2 add and store where available (every x86-64), else a loop. */
#if defined(__SSE2__)
static inline void put_x8(uint16_t *X, const uint8_t *pos, uint32_t x0)
{
  const __m128i p = _mm_unpacklo_epi8(_mm_loadl_epi64((const __m128i *)pos), _mm_setzero_si128());
  _mm_storeu_si128((__m128i *)X, _mm_add_epi16(p, _mm_set1_epi16((short)x0)));
}
#else
static inline void put_x8(uint16_t *X, const uint8_t *pos, uint32_t x0)
{
  for (int i = 0; i < 8; i++) X[i] = (uint16_t)(x0 + pos[i]);
}
#endif

/* What the fast loop reads and updates, kept together so it can live in
 * memory next to the stack while the loop keeps its own values in
 * registers. */
typedef struct evt3_fast_state {
  uint32_t regs[16];  /* as elfm_evt3_state.regs */
  uint32_t lims[16];  /* largest valid 11-bit payload + 1, per word type */
  int64_t t_high;
  uint32_t xlim;
} evt3_fast_state;

/* The fast path, for words q..stop (the caller makes sure the chunk has
 * room for 12 events per word plus 4 scratch slots). The word types of a
 * real stream follow no pattern a branch predictor learns, and one
 * mispredicted branch costs more than a whole word (only vectors keep a
 * branch of their own), so a word updates the state by one store into
 * regs[type] and always writes a would-be ADDR_X event that is kept (n
 * advances) only when it is one. Time cannot go back here: a TIME_LOW
 * below the current one stops the loop, so events need no order check.
 * It stops at the first word it does not handle (TIME_HIGH, triggers,
 * anything out of range) without having changed anything for it; the
 * slow path then decodes that word with every check. Kept out of line so
 * that its dozen live values get registers of their own. */
#if defined(__GNUC__)
__attribute__((noinline))
#endif
static const uint8_t *evt3_fast(const uint8_t *q, const uint8_t *stop, elfm_event_chunk *c,
                                size_t *n_io, evt3_fast_state *fs)
{
  /* restrict: the four arrays never overlap, which lets the compiler
   * keep the pointers in registers and vectorise the broadcasts. */
  int64_t *restrict const T = c->t_us;
  uint16_t *restrict const X = c->x;
  uint16_t *restrict const Y = c->y;
  uint8_t *restrict const P = c->p;
  size_t n = *n_io;
  const int64_t t_high = fs->t_high;
  for (; q < stop; q += 2) {
    const uint32_t w = elfm_le16(q);
    const uint32_t type = w >> 12;
    /* ADDR_Y, ADDR_X, VECT_BASE_X, VECT_12, VECT_8, TIME_LOW */
    if (!((0x7Du >> type) & 1)) break;
    const uint32_t pl = w & 0x7FF;
    /* A TIME_LOW below the last: less than regs[TIME_LOW] - 0x6000 only
     * for a TIME_LOW word (others wrap to large values or exceed 0xFFF). */
    if ((pl >= fs->lims[type]) | (w - 0x6000u < fs->regs[0x6] - 0x6000u)) break;
    if (type - 0x4 <= 1) { /* VECT_12, VECT_8 */
      const uint32_t nbits = type == 0x4 ? 12 : 8;
      const uint32_t mask = w & ((1u << nbits) - 1);
      const uint32_t base = fs->regs[0x3];
      const uint32_t x0 = (base & 0x7FF) + (base >> 16);
      const uint32_t xhi = x0 + 31 - (uint32_t)__builtin_clz(mask | 1);
      if (((base >> 12) & 0xF) != 0x3 || (mask && xhi >= fs->xlim)) break;
      /* t, y and p are the same for the whole vector: broadcast them
       * into 12 slots (vectorised stores), then place the x of each set
       * bit; slots past the last set bit are scratch. */
      const int64_t t = t_high | (int64_t)(fs->regs[0x6] & 0xFFF);
      const uint16_t y = (uint16_t)(fs->regs[0x0] & 0x7FF);
      const uint8_t p = (uint8_t)((base >> 11) & 1);
      for (uint32_t i = 0; i < 12; i++) T[n + i] = t;
      for (uint32_t i = 0; i < 12; i++) Y[n + i] = y;
      for (uint32_t i = 0; i < 12; i++) P[n + i] = p;
      /* x of the set bits: 8 slots per 6-bit half (room for 16). */
      const uint8_t *lo = evt3_pos6[mask & 63], *hi = evt3_pos6[mask >> 6];
      put_x8(X + n, lo, x0);
      n += evt3_cnt6[mask & 63];
      put_x8(X + n, hi, x0 + 6);
      n += evt3_cnt6[mask >> 6];
      fs->regs[0x3] = base + (nbits << 16);
      continue;
    }
    fs->regs[type] = w;
    T[n] = t_high | (int64_t)(fs->regs[0x6] & 0xFFF);
    X[n] = (uint16_t)pl;
    Y[n] = (uint16_t)(fs->regs[0x0] & 0x7FF);
    P[n] = (uint8_t)((w >> 11) & 1);
    n += type == 0x2;
  }
  *n_io = n;
  return q;
}

elfm_status elfm_evt3_decode(elfm_reader *r, elfm_event_chunk *c, elfm_error *err)
{
  const uint8_t *b = r->buf;
  size_t pos = r->pos;
  const size_t end = pos + ((r->len - pos) & ~(size_t)1);
  size_t n = c->n;
  const size_t n0 = n;
  /* The caller guarantees room for 16 events at entry (a vector gives 12
   * but the fast path writes 16 slots). */
  const size_t lim = c->cap - 16;
  int64_t *const T = c->t_us;
  uint16_t *const X = c->x, *const Y = c->y;
  uint8_t *const P = c->p;
  const uint32_t xlim = r->x_lim, ylim = r->y_lim;
  elfm_status st = ELFM_OK;
  elfm_evt3_state s = r->st.evt3;
  evt3_fast_state fs;
  memcpy(fs.regs, s.regs, sizeof fs.regs);
  for (int i = 0; i < 16; i++) fs.lims[i] = 0x800;
  fs.lims[0x0] = ylim;
  fs.lims[0x2] = xlim;
  fs.t_high = s.t_high;
  fs.xlim = xlim;
#define T_EMIT() (n > n0 ? T[n - 1] : s.t_emit)
#define T_NOW() (fs.t_high | (int64_t)(fs.regs[0x6] & 0xFFF))
  /* The fast path runs once TIME_HIGH and ADDR_Y were seen and no event
   * is due before the last one's time. */
#define FAST_OK() (s.seen_th && s.seen_y && T_NOW() >= T_EMIT())
  int fast = FAST_OK();

  while (pos < end && n <= lim) {
    if (fast) {
      /* As many words as surely fit: each gives at most 12 events and
       * writes at most 16 slots. */
      size_t words = (end - pos) / 2, fit = (lim - n) / 12 + 1;
      if (words > fit) words = fit;
      const uint8_t *stop = b + pos + 2 * words;
      const uint8_t *q = evt3_fast(b + pos, stop, c, &n, &fs);
      pos = (size_t)(q - b);
      if (q == stop) continue;
    }
    if (pos >= end || n > lim) break;

    /* Slow path: one word with every check; errors name its offset. */
    const uint32_t w = elfm_le16(b + pos);
    const uint32_t type = w >> 12;
    const int64_t off = r->buf_off + (int64_t)pos;
    switch (type) {
    case 0x0: /* ADDR_Y */
      if (!s.seen_th) break;
      if ((w & 0x7FF) >= ylim) {
        st = elfm_error_set(err, ELFM_ERR_RANGE, r->path, off,
                            "EVT3 ADDR_Y y=%u outside the sensor height %u", w & 0x7FF, ylim);
        goto out;
      }
      fs.regs[0x0] = w;
      s.seen_y = 1;
      break;
    case 0x2: { /* ADDR_X: one event */
      if (!s.seen_th || !s.seen_y) break;
      const uint32_t x = w & 0x7FF;
      if (x >= xlim) {
        st = elfm_error_set(err, ELFM_ERR_RANGE, r->path, off,
                            "EVT3 ADDR_X x=%u outside the sensor width %u", x, xlim);
        goto out;
      }
      if (T_NOW() < T_EMIT()) {
        st = backward(r, off, T_EMIT(), T_NOW(), err);
        if (st != ELFM_OK) goto out;
      }
      T[n] = T_NOW();
      X[n] = (uint16_t)x;
      Y[n] = (uint16_t)(fs.regs[0x0] & 0x7FF);
      P[n] = (uint8_t)((w >> 11) & 1);
      n++;
      break;
    }
    case 0x3: /* VECT_BASE_X */
      if (!s.seen_th) break;
      fs.regs[0x3] = w;
      break;
    case 0x4:   /* VECT_12 */
    case 0x5: { /* VECT_8 */
      if (!s.seen_th) break;
      const uint32_t nbits = type == 0x4 ? 12 : 8;
      const uint32_t mask = w & ((1u << nbits) - 1);
      const uint32_t base = fs.regs[0x3];
      const uint32_t x0 = (base & 0x7FF) + (base >> 16);
      fs.regs[0x3] = base + (nbits << 16);
      if (!s.seen_y || ((base >> 12) & 0xF) != 0x3 || !mask) break;
      /* Highest set bit must land inside the sensor. */
      const uint32_t xhi = x0 + 31 - (uint32_t)__builtin_clz(mask);
      if (xhi >= xlim) {
        st = elfm_error_set(err, ELFM_ERR_RANGE, r->path, off,
                            "EVT3 vector runs past the sensor width: x=%u >= %u", xhi, xlim);
        goto out;
      }
      if (T_NOW() < T_EMIT()) {
        st = backward(r, off, T_EMIT(), T_NOW(), err);
        if (st != ELFM_OK) goto out;
      }
      const int64_t t = T_NOW();
      for (uint32_t i = 0; i < nbits; i++) {
        if ((mask >> i) & 1) {
          T[n] = t;
          X[n] = (uint16_t)(x0 + i);
          Y[n] = (uint16_t)(fs.regs[0x0] & 0x7FF);
          P[n] = (uint8_t)((base >> 11) & 1);
          n++;
        }
      }
      break;
    }
    case 0x6: /* TIME_LOW */
      if (!s.seen_th) break;
      fs.regs[0x6] = w;
      break;
    case 0x8: { /* TIME_HIGH: resets TIME_LOW */
      const uint32_t th = w & 0xFFF;
      if (s.seen_th && th + 2048 <= s.prev_th) s.loops++;
      s.prev_th = th;
      fs.t_high = (s.loops << 24) | ((int64_t)th << 12);
      fs.regs[0x6] = 0x6000;
      if (!s.seen_th) {
        s.seen_th = 1;
        s.t_emit = fs.t_high;
      }
      break;
    }
    case 0xA: /* EXT_TRIGGER */
      if (!s.seen_th || !c->cap_trig) break;
      if (c->n_trig >= c->cap_trig) goto out; /* resume at this word */
      c->trig[c->n_trig].t_us = T_NOW();
      c->trig[c->n_trig].channel = (uint8_t)((w >> 8) & 0xF);
      c->trig[c->n_trig].value = (uint8_t)(w & 1);
      c->n_trig++;
      break;
    default: /* CONTINUED_4/12, OTHERS, 0x9999 padding, reserved */
      break;
    }
    pos += 2;
    fast = FAST_OK();
  }
out:
  r->need_more = (r->len - pos) < 2;
  r->pos = pos;
  s.t_emit = T_EMIT();
  c->n = n;
  memcpy(s.regs, fs.regs, sizeof s.regs);
  s.t_high = fs.t_high;
  r->st.evt3 = s;
  return st;
#undef T_EMIT
#undef T_NOW
#undef FAST_OK
}
