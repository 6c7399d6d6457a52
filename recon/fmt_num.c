/* fmt_num.c — see fmt_num.h.
 *
 * "%.Nf" of a double x is x's exact binary value rounded to N decimals.
 * With |x| < 1e9, x = m 2^-s exactly (m < 2^53 an integer, s >= 23), so
 * x 10^N = m 10^N / 2^s: the integer product m 10^N (< 2^83) shifted right
 * by s, rounded to nearest with ties to even on the bits shifted out. That
 * is exact, and so is the text; multiplying x by 10^N in floating point
 * would round first and differ where x lies near a half. */
#include "fmt_num.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

static const uint64_t POW10[10] = {1u,      10u,      100u,      1000u,      10000u,
                                   100000u, 1000000u, 10000000u, 100000000u, 1000000000u};

/* u in decimal at out, returns the length */
static size_t put_u64(char *out, uint64_t u)
{
  char tmp[24];
  size_t n = 0;
  do {
    tmp[n++] = (char)('0' + u % 10);
    u /= 10;
  } while (u);
  for (size_t i = 0; i < n; i++) out[i] = tmp[n - 1 - i];
  return n;
}

size_t elfm_fmt_u64(char *out, uint64_t v) { return put_u64(out, v); }

size_t elfm_fmt_i64(char *out, int64_t v)
{
  if (v >= 0) return put_u64(out, (uint64_t)v);
  out[0] = '-';
  return 1 + put_u64(out + 1, (uint64_t)0 - (uint64_t)v); /* INT64_MIN too */
}

size_t elfm_fmt_fixed(char *out, double v, int decimals)
{
#ifdef __SIZEOF_INT128__
  if (!(decimals >= 0 && decimals <= 9) || !isfinite(v) || !(fabs(v) < 1e9)) {
#else /* no 128-bit product: printf for all */
  {
#endif
    char tmp[ELFM_FMT_NUM_MAX + 1];
    const int d = decimals < 0 ? 0 : decimals > 9 ? 9 : decimals;
    const int n = snprintf(tmp, sizeof tmp, "%.*f", d, v);
    const size_t len = n < 0 ? 0 : (size_t)n < sizeof tmp ? (size_t)n : sizeof tmp - 1;
    memcpy(out, tmp, len);
    return len;
  }
#ifdef __SIZEOF_INT128__
  size_t n = 0;
  if (signbit(v)) out[n++] = '-';
  const double a = fabs(v);
  uint64_t q = 0; /* a 10^decimals, rounded */
  if (a > 0) {
    int ex;
    const double f = frexp(a, &ex);              /* a = f 2^ex, f in [0.5, 1) */
    const uint64_t m = (uint64_t)ldexp(f, 53);   /* exact: 53 bits */
    const int s = 53 - ex;                       /* a = m 2^-s; ex <= 30, so s >= 23 */
    if (s < 84) { /* else m 10^N < 2^83 <= half of 2^s: rounds to 0 */
      const unsigned __int128 P = (unsigned __int128)m * POW10[decimals];
      unsigned __int128 w = P >> s;
      const unsigned __int128 rem = P - (w << s), half = (unsigned __int128)1 << (s - 1);
      if (rem > half || (rem == half && (w & 1))) w++;
      q = (uint64_t)w; /* < 1e18 */
    }
  }
  const uint64_t p = POW10[decimals];
  n += put_u64(out + n, q / p);
  if (decimals > 0) {
    out[n++] = '.';
    uint64_t r = q % p;
    for (int k = decimals - 1; k >= 0; k--) {
      out[n + (size_t)k] = (char)('0' + r % 10);
      r /= 10;
    }
    n += (size_t)decimals;
  }
  return n;
#endif
}
