/* refocus_agree.c — the sparse path's view-agreement rule (ghost.c has the
 * dense path's): a voxel is kept when at least need[X] of the views that
 * sample it have a non-zero sample there, and its value is then the dense
 * path's mean, bit for bit.
 *
 * Step 1 (per call): each view's support map, one BIT per crop-box position,
 * from the frame's runs of pixels (agree_support).
 * Step 2 (per plane and row): the number of views whose support bit is set
 * under each voxel, bit-sliced: a row of W voxels is a window of W bits per
 * view, the views are added with carry-save adders into 6 bit planes
 * (counts up to 32 views) and compared with the plan's `need`, also as bit
 * planes: the candidates, a superset of the voxels that pass (the support
 * is a superset of the non-zero samples).
 * Step 3: for the candidates only, the dense path's gather, in its view
 * order and arithmetic, over the views whose support bits are set there
 * (the others have exactly-0 samples), and the exact rule seen >= need[X].
 *
 * The maps were bytes (stride box width + 2 W = 432 B, 1.5 MB for 25
 * views) added 32 voxels at a time: step 2 re-read them for every plane,
 * L2-bound, ~40 % of the sparse time under perf. As packed bits they are
 * 69 kB, and a view's row costs ~14 instructions (window and adders) for
 * its 144 voxels. bench_refocus flow at 21 Mev/s, CPU per volume (1 thread,
 * interleaved runs): 2.0 -> 1.55 ms over the commits that made this file.
 *
 * Two implementations with the same result: AVX2 (256 voxels per register,
 * picked when the CPU has it) and a portable one on 64-bit words, used
 * otherwise or when the workspace's agree_portable is set (tests).
 */
#include "refocus_internal.h"

#include <limits.h>
#include <stddef.h>
#include <string.h>

/* Step 1: each view's support bit map. A pixel at box position (c, y) is a
 * tap of the voxels whose first tap is (c - 1 .. c, y - 1 .. y), so a run of
 * n pixels sets n + 1 bits on two rows. Taking both taps regardless of the
 * plane's weights gives a superset of the views that see signal (a tap of
 * weight 0, fx = 0, adds nothing): the exact count is taken in step 3. */
static void set_bits(uint64_t *w, size_t b, size_t n)
{
  while (n) {
    const size_t o = b & 63, k = 64 - o < n ? 64 - o : n;
    const uint64_t m = k == 64 ? ~(uint64_t)0 : (((uint64_t)1 << k) - 1) << o;
    w[b >> 6] |= m;
    b += k;
    n -= k;
  }
}

void elfm_agree_support(const elfm_refocus_plan *p, elfm_refocus_workspace *ws)
{
  for (int v = 0; v < p->nv; v++) {
    ws->sup_ylo[v] = INT_MAX;
    ws->sup_yhi[v] = 0;
  }
  for (size_t t = 0; t < ws->n_runs; t++) {
    const elfm_refocus_run *run = &ws->runs[t];
    const int v = run->view;
    const elfm_refocus_box *bx = &p->box[v];
    const int bw = bx->x1 - bx->x0;
    const int y = run->row - bx->y0;
    int c = run->c0 - bx->x0 - 1;
    int n = run->n + 1;
    if (c < 0) {
      c = 0;
      n--;
    }
    /* the box's last column is never a first tap (both taps lie in the
     * box): it stays 0 */
    if (c + n > bw - 1) n = bw - 1 - c;
    const size_t at = ws->sup_bit[v] + (size_t)y * ws->sup_stride_bits[v] + (size_t)c;
    if (n > 0) {
      set_bits(ws->sup, at, (size_t)n);
      if (y > 0) set_bits(ws->sup, at - ws->sup_stride_bits[v], (size_t)n);
    }
    const int ya = y > 0 ? y - 1 : 0;
    if (ya < ws->sup_ylo[v]) ws->sup_ylo[v] = ya;
    if (y + 1 > ws->sup_yhi[v]) ws->sup_yhi[v] = y + 1;
  }
}

/* End of call: zero the words holding the map rows this call set. */
void elfm_agree_support_clear(const elfm_refocus_plan *p, elfm_refocus_workspace *ws)
{
  for (int v = 0; v < p->nv; v++) {
    if (ws->sup_ylo[v] >= ws->sup_yhi[v]) continue;
    const size_t b0 = ws->sup_bit[v] + (size_t)ws->sup_ylo[v] * ws->sup_stride_bits[v];
    const size_t b1 = ws->sup_bit[v] + (size_t)ws->sup_yhi[v] * ws->sup_stride_bits[v];
    memset(ws->sup + b0 / 64, 0, ((b1 + 63) / 64 - b0 / 64) * sizeof *ws->sup);
  }
}

/* Bits [lo, hi) of the 64 starting at bit `base`. */
static inline uint64_t range_word(int lo, int hi, int base)
{
  if (lo < base) lo = base;
  if (hi > base + 64) hi = base + 64;
  if (lo >= hi) return 0;
  const uint64_t top = hi - base == 64 ? ~(uint64_t)0 : ((uint64_t)1 << (hi - base)) - 1;
  return top & ~(((uint64_t)1 << (lo - base)) - 1);
}

/* A plane's views with signal on it: where row Y's window starts in the
 * maps, the rows [y0, y1) where the view samples the plane and its map has
 * any signal, the voxels it samples as a lane mask (ws->agree_mask, row a;
 * the window's other lanes hold neighbouring rows' bits) and the weights as
 * the dense path computes them. */
typedef struct agree_view {
  int v, y0, y1, xlo, xhi;
  ptrdiff_t bit0;   /* window of row Y: bit bit0 + Y * stride of ws->sup, >= 0 for Y in [y0, y1) */
  ptrdiff_t stride; /* bits, a multiple of 8 */
  ptrdiff_t tap;    /* first tap of voxel (X, Y): frame pixel Y * sensor width + X + tap */
  float w[4];
} agree_view;

static int agree_views(const elfm_refocus_plan *p, elfm_refocus_workspace *ws, int k,
                       agree_view *av)
{
  const elfm_refocus_shift *sk = p->shift + (size_t)k * p->nv;
  const size_t ld = ws->agree_win_ld;
  const size_t nmw = 4 * (((size_t)p->w + 255) / 256); /* words of a window */
  int na = 0;
  for (int v = 0; v < p->nv; v++) {
    const elfm_refocus_shift *s = sk + v;
    const elfm_refocus_box *bx = &p->box[v];
    if (s->xlo >= s->xhi || ws->sup_ylo[v] >= ws->sup_yhi[v]) continue;
    const int off = bx->y0 - s->iy; /* box row y is volume row y + off */
    int y0 = s->ylo, y1 = s->yhi;
    if (y0 < ws->sup_ylo[v] + off) y0 = ws->sup_ylo[v] + off;
    if (y1 > ws->sup_yhi[v] + off) y1 = ws->sup_yhi[v] + off;
    if (y0 >= y1) continue;
    agree_view *a = &av[na];
    a->v = v;
    a->y0 = y0;
    a->y1 = y1;
    a->xlo = s->xlo;
    a->xhi = s->xhi;
    a->tap = (ptrdiff_t)s->iy * p->sw + s->ix;
    a->stride = (ptrdiff_t)ws->sup_stride_bits[v];
    /* voxel X of row Y has its first tap at box (X + ix - x0, Y - off);
     * ix - x0 > -W and the maps start >= W bits into ws->sup (refocus.c) */
    a->bit0 = (ptrdiff_t)ws->sup_bit[v] - (ptrdiff_t)off * a->stride + (s->ix - bx->x0);
    elfm_refocus_shift_weights(s, a->w);
    uint64_t *m = ws->agree_mask + (size_t)na * ld;
    for (size_t i = 0; i < nmw; i++) m[i] = range_word(s->xlo, s->xhi, 64 * (int)i);
    na++;
  }
  return na;
}

/* Bits [X0, X0 + 8) of a bit array (a[X0 / 64 + 1] must be readable). */
static inline unsigned bits8(const uint64_t *a, int X0)
{
  const int i = X0 >> 6, o = X0 & 63;
  return (unsigned)(((a[i] >> o) | ((a[i + 1] << 1) << (63 - o))) & 0xFFu);
}

/* count >= need for each bit lane, both as bit planes c[0..5] and d[0..5]
 * (weights 1 .. 32; the plan's need_bits): compared from the top bit down. */
#define AGREE_GE(c, d, ge, TYPE, AND, OR, ANDNOT, XOR, ZERO, ONES) \
  do {                                                             \
    TYPE gt_ = ZERO, eq_ = ONES;                                   \
    for (int b_ = 5; b_ >= 0; b_--) {                              \
      gt_ = OR(gt_, AND(eq_, ANDNOT(d[b_], c[b_])));               \
      eq_ = ANDNOT(XOR(c[b_], d[b_]), eq_);                        \
    }                                                              \
    ge = OR(gt_, eq_);                                             \
  } while (0)

/* ---- portable: 64 voxels per word ---------------------------------------- */

static inline uint64_t u64_and(uint64_t a, uint64_t b) { return a & b; }
static inline uint64_t u64_or(uint64_t a, uint64_t b) { return a | b; }
static inline uint64_t u64_andnot(uint64_t a, uint64_t b) { return ~a & b; }
static inline uint64_t u64_xor(uint64_t a, uint64_t b) { return a ^ b; }

/* carry-save adder on words: h:l = a + b + c */
static inline void csa_u64(uint64_t *h, uint64_t *l, uint64_t a, uint64_t b, uint64_t c)
{
  const uint64_t u = a ^ b;
  *h = (a & b) | (u & c);
  *l = u ^ c;
}

/* w (weight 2^b0) into the counter planes c[b0 .. 5], no branch (a ripple
 * that stops when the carry is 0 mispredicted: ~15 % of the portable path) */
static inline void ripple_u64(uint64_t *c, int b0, uint64_t w)
{
  for (int b = b0; b < 6; b++) {
    const uint64_t t = c[b] & w;
    c[b] ^= w;
    w = t;
  }
}

/* Step 2 on one word of n <= 32 view windows (win[j * ld]) against the
 * need planes nb[b * nw]: the AVX2 path's adders on 64 voxels. */
static uint64_t count_ge_u64(const uint64_t *win, size_t ld, int n, const uint64_t *nb, size_t nw)
{
  uint64_t c[6] = {0, 0, 0, 0, 0, 0};
  int j = 0;
#define W_(i) win[(size_t)(j + (i)) * ld]
  for (; j + 4 <= n; j += 4) {
    uint64_t a2, b2, a4;
    csa_u64(&a2, &c[0], c[0], W_(0), W_(1));
    csa_u64(&b2, &c[0], c[0], W_(2), W_(3));
    csa_u64(&a4, &c[1], c[1], a2, b2);
    ripple_u64(c, 2, a4);
  }
  for (; j < n; j++) ripple_u64(c, 0, W_(0));
#undef W_
  uint64_t d[6], ge;
  for (int b = 0; b < 6; b++) d[b] = nb[(size_t)b * nw];
  AGREE_GE(c, d, ge, uint64_t, u64_and, u64_or, u64_andnot, u64_xor, 0, ~(uint64_t)0);
  return ge;
}

static void agree_plane_portable(const elfm_refocus_plan *p, const elfm_frame *frame,
                                 elfm_volume *vol, elfm_refocus_workspace *ws, int k)
{
  const int W = p->w, H = p->h;
  const size_t SW = (size_t)p->sw, nw = ((size_t)W + 63) / 64, ld = ws->agree_win_ld;
  const elfm_refocus_shift *sk = p->shift + (size_t)k * p->nv;
  agree_view av[32];
  const int na = agree_views(p, ws, k, av);
  uint64_t *win = ws->agree_win, *cand = ws->agree_candw;
  int list[32];
  for (int Y = 0; Y < H; Y++) {
    const size_t r = (size_t)k * (size_t)H + (size_t)Y;
    const int T = p->need_row_min[r];
    if (T > p->nv) continue; /* 255: no voxel of the row is sampled */
    int n = 0;
    for (int a = 0; a < na; a++) {
      if (Y < av[a].y0 || Y >= av[a].y1) continue;
      const size_t s0 = (size_t)(av[a].bit0 + (ptrdiff_t)Y * av[a].stride);
      const uint64_t *m = ws->agree_mask + (size_t)a * ld, *sup = ws->sup;
      uint64_t *o = win + (size_t)n * ld;
      for (size_t i = 0; i < nw; i++) {
        const size_t s = s0 + 64 * i, q = s >> 6, sh = s & 63;
        o[i] = ((sup[q] >> sh) | ((sup[q + 1] << 1) << (63 - sh))) & m[i];
      }
      o[nw] = 0;
      list[n++] = a;
    }
    if (n < T) continue;
    const uint64_t *nb = p->need_bits + r * 6 * nw;
    uint64_t any = 0;
    for (size_t i = 0; i < nw; i++) {
      cand[i] = count_ge_u64(win + i, ld, n, nb + i, nw);
      if (64 * (i + 1) > (size_t)W) cand[i] &= ((uint64_t)1 << (W & 63)) - 1; /* X < W */
      any |= cand[i];
    }
    if (!any) continue;
    const uint8_t *need = p->need + r * (size_t)W;
    const uint8_t *count = p->count + r * (size_t)W;
    float *out = vol->data + r * (size_t)W;
    int lo = W, hi = 0;
    for (size_t i = 0; i < nw; i++)
      for (uint64_t b = cand[i]; b; b &= b - 1) {
        const int X = (int)(64 * i) + __builtin_ctzll(b);
        float sum = 0.0f;
        int seen = 0;
        /* views in view order; those without a support bit at X have an
         * exactly-0 sample (and so do views not sampling X: their bit is 0);
         * a mask of them first (testing the bit in the loop mispredicted) */
        uint32_t vm = 0;
        for (int j = 0; j < n; j++) vm |= (uint32_t)((win[(size_t)j * ld + i] >> (X & 63)) & 1) << j;
        for (; vm; vm &= vm - 1) {
          const agree_view *a = &av[list[__builtin_ctz(vm)]];
          const elfm_refocus_shift *s = sk + a->v;
          const float *r0 = frame->data + (size_t)(Y + s->iy) * SW + (ptrdiff_t)(X + s->ix);
          const float *r1 = r0 + SW;
          const float v = a->w[0] * r0[0] + a->w[1] * r0[1] + a->w[2] * r1[0] + a->w[3] * r1[1];
          sum += v;
          seen += v != 0.0f;
        }
        if (seen < need[X]) continue;
        out[X] = sum * p->inv_table[count[X]];
        if (X < lo) lo = X;
        hi = X + 1;
      }
    if (lo < hi) elfm_refocus_mark_row(ws, (uint32_t)r, lo, hi);
  }
}

/* ---- AVX2: 256 voxels per register ----------------------------------------- */
#if defined(__x86_64__) && defined(__GNUC__)
#include <immintrin.h>
#define ELFM_AGREE_AVX2 1

#define M_AND(a, b) _mm256_and_si256(a, b)
#define M_OR(a, b) _mm256_or_si256(a, b)
#define M_ANDNOT(a, b) _mm256_andnot_si256(a, b)
#define M_XOR(a, b) _mm256_xor_si256(a, b)
/* carry-save adder: h:l = a + b + c */
#define CSA(h, l, a, b, c)                                          \
  do {                                                              \
    const __m256i u_ = _mm256_xor_si256(a, b);                      \
    h = _mm256_or_si256(_mm256_and_si256(a, b), _mm256_and_si256(u_, c)); \
    l = _mm256_xor_si256(u_, c);                                    \
  } while (0)

/* A row's listed views, for the windows of one 256-voxel chunk: entry j's
 * window is the 256 bits from bit sh of the 40 bytes at sup8 + at[j],
 * masked to the voxels the view samples (mask[j] + q4). Indexed by list
 * entry, not by view: per view and row the window then costs ~14
 * instructions with its adders, ~19 through the view index. */
typedef struct agree_rowv {
  const uint8_t *sup8;
  const ptrdiff_t *at;
  const __m128i *shr, *shl; /* sh and 64 - sh */
  const uint64_t *const *mask;
  size_t q4;
} agree_rowv;

__attribute__((target("avx2"), always_inline))
static inline __m256i agree_window(const agree_rowv *rv, int j, int narrow)
{
  const uint8_t *src = rv->sup8 + rv->at[j];
  const __m256i lo = _mm256_loadu_si256((const __m256i *)(const void *)src);
  /* lane i takes its top bits from lane i + 1; with W <= 192 the lanes
   * that matter (0 .. 2) have it in the same load */
  const __m256i hi = narrow ? _mm256_permute4x64_epi64(lo, _MM_SHUFFLE(3, 3, 2, 1))
                            : _mm256_loadu_si256((const __m256i *)(const void *)(src + 8));
  const __m256i w = _mm256_or_si256(_mm256_srl_epi64(lo, rv->shr[j]), _mm256_sll_epi64(hi, rv->shl[j]));
  return _mm256_and_si256(w, _mm256_load_si256((const __m256i *)(const void *)(rv->mask[j] + rv->q4)));
}

/* Step 2 on one 256-voxel chunk of the row's n <= 32 views against the
 * need planes nb[b * nw] (4 words each, unaligned: the last ones run into
 * the next plane, lanes the caller drops): Harley-Seal, 8 views per round
 * (7 adders, ~5 ops per view), then pairs, on windows made in registers
 * (storing them for the adders to load back cost more than the count:
 * bench_refocus flow at 21 Mev/s, 0.71 ms of CPU per volume for the
 * windows, stored, 0.27 ms for the adders). */
__attribute__((target("avx2"), always_inline))
static inline __m256i count_ge_avx2(const agree_rowv *rv, int n, const uint64_t *nb, size_t nw,
                                    int narrow)
{
  __m256i c[6];
  for (int b = 0; b < 6; b++) c[b] = _mm256_setzero_si256();
  int j = 0;
#define W_(i) agree_window(rv, j + (i), narrow)
  for (; j + 8 <= n; j += 8) {
    __m256i a2, b2, a4, b4, a8, t;
    CSA(a2, c[0], c[0], W_(0), W_(1));
    CSA(b2, c[0], c[0], W_(2), W_(3));
    CSA(a4, c[1], c[1], a2, b2);
    CSA(a2, c[0], c[0], W_(4), W_(5));
    CSA(b2, c[0], c[0], W_(6), W_(7));
    CSA(b4, c[1], c[1], a2, b2);
    CSA(a8, c[2], c[2], a4, b4);
    /* a8 (weight 8) into c[3..5]: at most 32 views, no carry out of c[5] */
    t = _mm256_and_si256(c[3], a8);
    c[3] = _mm256_xor_si256(c[3], a8);
    c[5] = _mm256_xor_si256(c[5], _mm256_and_si256(c[4], t));
    c[4] = _mm256_xor_si256(c[4], t);
  }
  for (; j + 2 <= n; j += 2) {
    __m256i carry;
    CSA(carry, c[0], c[0], W_(0), W_(1));
    for (int b = 1; b < 6; b++) {
      const __m256i t = _mm256_and_si256(c[b], carry);
      c[b] = _mm256_xor_si256(c[b], carry);
      carry = t;
    }
  }
  if (j < n) {
    __m256i carry = W_(0);
    for (int b = 0; b < 6; b++) {
      const __m256i t = _mm256_and_si256(c[b], carry);
      c[b] = _mm256_xor_si256(c[b], carry);
      carry = t;
    }
  }
#undef W_
  __m256i d[6], ge;
  for (int b = 0; b < 6; b++) d[b] = _mm256_loadu_si256((const __m256i *)(const void *)(nb + (size_t)b * nw));
  AGREE_GE(c, d, ge, __m256i, M_AND, M_OR, M_ANDNOT, M_XOR, _mm256_setzero_si256(), _mm256_set1_epi8(-1));
  return ge;
}

/* Steps 2 and 3 on plane k. Windows: each view's support bits under the
 * row's voxels, 256 at a time, from unaligned loads and a shift, masked to
 * the voxels the view samples (the maps' padding keeps the loads inside,
 * refocus.c).
 * Gather: 8 voxels X0 .. X0 + 7 from each lowest candidate left, summed in
 * registers over the views whose window has a bit in those 8 (in view
 * order), stored with one masked store. Lanes outside a view's [xlo, xhi)
 * are masked loads: 0 and never read, as the view not sampling them does in
 * the dense path. AVX2 has no FMA: the arithmetic is the dense path's, in
 * its order, so the floats are the same. */
__attribute__((target("avx2")))
static void agree_plane_avx2(const elfm_refocus_plan *p, const elfm_frame *frame,
                             elfm_volume *vol, elfm_refocus_workspace *ws, int k)
{
  const int W = p->w, H = p->h;
  const size_t SW = (size_t)p->sw, nch = ((size_t)W + 255) / 256, ld = ws->agree_win_ld;
  agree_view av[32];
  const int na = agree_views(p, ws, k, av);
  if (!na) return;
  uint64_t *cand = ws->agree_candw;
  const uint64_t *valid = ws->agree_mask + 32 * ld; /* X < W */
  /* the row's list of views: list[j] = a, in view order, with its window
   * (byte at[j] of the maps, advanced row by row, shift counts, lane mask)
   * and, for the views under a candidate group 8 entries at a time, the
   * window byte (l_at, per row), the bit in it and the voxels sampled;
   * entries n .. 31 read byte 0 */
  int list[32];
  ptrdiff_t at[32], step[32];
  __m128i shr[32], shl[32];
  const uint64_t *mask[32];
  int32_t l_at[32], l_sh[32], l_xlo[32], l_xhi[32];
  int n = 0, next_change = 0; /* the list holds for rows up to next_change */
  const uint8_t *sup8 = (const uint8_t *)(const void *)ws->sup;
  agree_rowv rv = {sup8, at, shr, shl, mask, 0};
  const __m256i lane = _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7);
  const __m256i bitv = _mm256_setr_epi32(1, 2, 4, 8, 16, 32, 64, 128);
  for (int Y = 0; Y < H; Y++) {
    /* the views sampling the row with signal near it, rebuilt only where
     * a view's rows begin or end (building it on every row was 18 % of
     * the time) */
    if (Y >= next_change) {
      n = 0;
      next_change = H;
      for (int a = 0; a < na; a++) {
        if (Y >= av[a].y0 && Y < av[a].y1) {
          const int sh = (int)(av[a].bit0 & 7); /* the same on every row: strides are whole bytes */
          /* byte of row Y's window: (bit0 + Y stride) / 8 */
          step[n] = av[a].stride / 8;
          at[n] = (av[a].bit0 - sh) / 8 + (ptrdiff_t)Y * step[n];
          shr[n] = _mm_cvtsi32_si128(sh);
          shl[n] = _mm_cvtsi32_si128(64 - sh);
          mask[n] = ws->agree_mask + (size_t)a * ld;
          l_sh[n] = sh;
          l_xlo[n] = av[a].xlo;
          l_xhi[n] = av[a].xhi;
          list[n++] = a;
        }
        if (av[a].y0 > Y && av[a].y0 < next_change) next_change = av[a].y0;
        if (av[a].y1 > Y && av[a].y1 < next_change) next_change = av[a].y1;
      }
      for (int j = n; j < 32; j++) l_sh[j] = l_xlo[j] = l_xhi[j] = 0;
    } else {
      for (int j = 0; j < n; j++) at[j] += step[j];
    }
    const size_t r = (size_t)k * (size_t)H + (size_t)Y;
    const int T = p->need_row_min[r];
    if (T > p->nv) continue; /* 255: no voxel of the row is sampled */
    /* need and count of the row (2 x 2 MB per volume, read only if the row
     * has candidates, so seldom in cache): fetched while the windows are
     * counted */
    for (int X = 0; X < W; X += 64) {
      _mm_prefetch((const char *)(p->need + r * (size_t)W + (size_t)X), _MM_HINT_T0);
      _mm_prefetch((const char *)(p->count + r * (size_t)W + (size_t)X), _MM_HINT_T0);
    }
    if (n < T) continue;
    const uint64_t *nb = p->need_bits + r * 6 * p->need_words;
    /* candidates, X < W only (the windows run on past the row), kept in a
     * register until stored: a 32-byte load of words just written one by
     * one stalls on store forwarding (it was 4 % of the time) */
    __m256i any = _mm256_setzero_si256();
    for (size_t q = 0; q < nch; q++) {
      rv.sup8 = sup8 + 32 * q;
      rv.q4 = 4 * q;
      const __m256i ge = _mm256_and_si256(
          W <= 192 ? count_ge_avx2(&rv, n, nb + 4 * q, p->need_words, 1)
                   : count_ge_avx2(&rv, n, nb + 4 * q, p->need_words, 0),
          _mm256_load_si256((const __m256i *)(const void *)(valid + 4 * q)));
      _mm256_storeu_si256((__m256i *)(void *)(cand + 4 * q), ge);
      any = _mm256_or_si256(any, ge);
    }
    cand[4 * nch] = 0;
    if (_mm256_testz_si256(any, any)) continue;
    const uint8_t *need = p->need + r * (size_t)W;
    const uint8_t *count = p->count + r * (size_t)W;
    float *out = vol->data + r * (size_t)W;
    /* pixel row0 + tap + X: the first tap of X, in the frame for X in [xlo, xhi) */
    const ptrdiff_t row0 = (ptrdiff_t)Y * (ptrdiff_t)SW;
    for (int j = 0; j < 32; j++) l_at[j] = j < n ? (int32_t)at[j] : 0;
    int lo = W, hi = 0;
    size_t i = 0;
    for (;;) {
      while (i < 4 * nch && !cand[i]) i++;
      if (i == 4 * nch) break;
      const int X0 = 64 * (int)i + __builtin_ctzll(cand[i]);
      const unsigned cb = bits8(cand, X0);
      /* the views with support under X0 .. X0 + 7, in view order: 8 bits
       * of each map row (storing the row's windows for this cost more),
       * 8 views per gather (one by one it was ~12 % of agree_plane); byte
       * offsets fit int32: the maps are at most 32 views x (8192 + 2002)^2
       * bits (plan limits), 415 MB */
      uint32_t vm = 0;
      const __m256i x0v = _mm256_set1_epi32(X0), ff = _mm256_set1_epi32(0xFF);
      const __m256i zero = _mm256_setzero_si256();
      for (int j = 0; j < n; j += 8) {
        const __m256i b = _mm256_add_epi32(_mm256_loadu_si256((const __m256i *)(const void *)(l_sh + j)), x0v);
        const __m256i idx = _mm256_add_epi32(_mm256_loadu_si256((const __m256i *)(const void *)(l_at + j)),
                                             _mm256_srli_epi32(b, 3));
        const __m256i g = _mm256_i32gather_epi32((const int *)(const void *)sup8, idx, 1);
        const __m256i bits = _mm256_srlv_epi32(g, _mm256_and_si256(b, _mm256_set1_epi32(7)));
        const __m256i lo_sh = _mm256_max_epi32(
            _mm256_sub_epi32(_mm256_loadu_si256((const __m256i *)(const void *)(l_xlo + j)), x0v), zero);
        const __m256i hi_sh = _mm256_max_epi32(
            _mm256_sub_epi32(_mm256_add_epi32(x0v, _mm256_set1_epi32(8)),
                             _mm256_loadu_si256((const __m256i *)(const void *)(l_xhi + j))), zero);
        const __m256i m = _mm256_and_si256(_mm256_sllv_epi32(ff, lo_sh), _mm256_srlv_epi32(ff, hi_sh));
        const __m256i z = _mm256_cmpeq_epi32(_mm256_and_si256(bits, m), zero);
        vm |= (uint32_t)(~_mm256_movemask_ps(_mm256_castsi256_ps(z)) & 0xFF) << j;
      }
      if (n < 32) vm &= (1u << n) - 1u;
      const __m256i xv = _mm256_add_epi32(_mm256_set1_epi32(X0), lane);
      __m256 sum = _mm256_setzero_ps();
      __m256i seen = _mm256_setzero_si256();
      for (; vm; vm &= vm - 1) {
        const agree_view *a = &av[list[__builtin_ctz(vm)]];
        const float *t0 = frame->data + (row0 + a->tap + X0), *t1 = t0 + SW;
        __m256 a00, a01, a10, a11;
        if (a->xlo <= X0 && X0 + 8 <= a->xhi) { /* all lanes sampled: the usual case */
          a00 = _mm256_loadu_ps(t0);
          a01 = _mm256_loadu_ps(t0 + 1);
          a10 = _mm256_loadu_ps(t1);
          a11 = _mm256_loadu_ps(t1 + 1);
        } else { /* a masked lane's address is never read */
          const __m256i m = _mm256_and_si256(_mm256_cmpgt_epi32(xv, _mm256_set1_epi32(a->xlo - 1)),
                                             _mm256_cmpgt_epi32(_mm256_set1_epi32(a->xhi), xv));
          a00 = _mm256_maskload_ps(t0, m);
          a01 = _mm256_maskload_ps(t0 + 1, m);
          a10 = _mm256_maskload_ps(t1, m);
          a11 = _mm256_maskload_ps(t1 + 1, m);
        }
        __m256 v = _mm256_add_ps(_mm256_mul_ps(_mm256_set1_ps(a->w[0]), a00),
                                 _mm256_mul_ps(_mm256_set1_ps(a->w[1]), a01));
        v = _mm256_add_ps(v, _mm256_mul_ps(_mm256_set1_ps(a->w[2]), a10));
        v = _mm256_add_ps(v, _mm256_mul_ps(_mm256_set1_ps(a->w[3]), a11));
        sum = _mm256_add_ps(sum, v);
        /* v != 0 is all ones (-1) in the lane: subtracting it counts one */
        seen = _mm256_sub_epi32(seen, _mm256_castps_si256(_mm256_cmp_ps(v, _mm256_setzero_ps(), _CMP_NEQ_UQ)));
      }
      /* kept: a candidate lane whose non-zero samples reach need[X]; the
       * value is the mean over the views sampling the voxel, 1 / count[X]
       * from the plan's table (need and count are padded by 32 bytes) */
      const __m256i candv = _mm256_cmpeq_epi32(_mm256_and_si256(_mm256_set1_epi32((int)cb), bitv), bitv);
      const __m256i nd = _mm256_cvtepu8_epi32(_mm_loadl_epi64((const __m128i *)(const void *)(need + X0)));
      const __m256i ci = _mm256_cvtepu8_epi32(_mm_loadl_epi64((const __m128i *)(const void *)(count + X0)));
      const __m256i keep = _mm256_andnot_si256(_mm256_cmpgt_epi32(nd, seen), candv);
      const __m256 val = _mm256_mul_ps(sum, _mm256_i32gather_ps(p->inv_table, ci, 4));
      _mm256_maskstore_ps(out + X0, keep, val);
      const unsigned kb = (unsigned)_mm256_movemask_ps(_mm256_castsi256_ps(keep));
      if (kb) {
        if (X0 + __builtin_ctz(kb) < lo) lo = X0 + __builtin_ctz(kb);
        hi = X0 + 32 - __builtin_clz(kb);
      }
      /* drop the candidates X0 .. X0 + 7 */
      const int o = X0 & 63;
      cand[i] &= ~((uint64_t)0xFF << o);
      if (o > 56) cand[i + 1] &= ~((uint64_t)0xFF >> (64 - o));
    }
    if (lo < hi) elfm_refocus_mark_row(ws, (uint32_t)r, lo, hi);
  }
}
#endif

int elfm_agree_avx2(const elfm_refocus_workspace *ws)
{
#ifdef ELFM_AGREE_AVX2
  return !ws->agree_portable && __builtin_cpu_supports("avx2");
#else
  (void)ws;
  return 0;
#endif
}

void elfm_agree_plane(const elfm_refocus_plan *p, const elfm_frame *frame, elfm_volume *vol,
                      elfm_refocus_workspace *ws, int k, int avx2)
{
#ifdef ELFM_AGREE_AVX2
  if (avx2) {
    agree_plane_avx2(p, frame, vol, ws, k);
    return;
  }
#else
  (void)avx2;
#endif
  agree_plane_portable(p, frame, vol, ws, k);
}
