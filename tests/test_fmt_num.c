/* test_fmt_num.c — the writers' number text (recon/fmt_num.c) against
 * printf's own, byte for byte: random doubles of every magnitude the
 * tracks hold, exact ties at the last decimal (where rounding to even
 * shows), values next to a tie (one ulp either side), negatives that round
 * to zero, zeros of both signs, the fallback's range (>= 1e9, inf, NaN)
 * and int64's and uint64's whole ranges. */
#include <float.h>
#include <inttypes.h>
#include <math.h>
#include <stdint.h>
#include <string.h>

#include "check.h"
#include "fmt_num.h"

/* xorshift64*: a fixed sequence, the same on every machine */
static uint64_t rnd(uint64_t *s)
{
  *s ^= *s >> 12;
  *s ^= *s << 25;
  *s ^= *s >> 27;
  return *s * 2685821657736338717ULL;
}

static long n_bad;

static void same_fixed(double v, int d)
{
  char want[512], got[ELFM_FMT_NUM_MAX + 1];
  snprintf(want, sizeof want, "%.*f", d, v);
  size_t n = elfm_fmt_fixed(got, v, d);
  got[n] = '\0';
  if (strcmp(want, got) != 0 && n_bad++ < 10)
    fprintf(stderr, "%%.%df of %.17g (%a): printf \"%s\", elfm_fmt_fixed \"%s\"\n", d, v, v, want,
            got);
}

static void same_i64(int64_t v)
{
  char want[32], got[ELFM_FMT_NUM_MAX + 1];
  snprintf(want, sizeof want, "%" PRId64, v);
  size_t n = elfm_fmt_i64(got, v);
  got[n] = '\0';
  if (strcmp(want, got) != 0 && n_bad++ < 10)
    fprintf(stderr, "%%" PRId64 " of %s: elfm_fmt_i64 \"%s\"\n", want, got);
}

int main(void)
{
  uint64_t s = 0x9e3779b97f4a7c15ULL;
  /* the decimals the writers use (3, 4, 5, 6) and the others */
  for (int d = 0; d <= 9; d++) {
    const double fixed[] = {0.0,     -0.0,    1.0,     -1.0,   0.5,     1.5,      2.5,
                            0.03125, 0.09375, -0.03125, 1e-300, -1e-300, 5e-324,  -5e-324,
                            DBL_MIN, 999999999.99999, -999999999.99999, 1e9,  -1e9,
                            1e300,   INFINITY, -INFINITY, NAN,   123.45675, 0.00005, -0.00004};
    for (size_t k = 0; k < sizeof fixed / sizeof fixed[0]; k++) same_fixed(fixed[k], d);
    for (int i = 0; i < 200000; i++) {
      /* magnitudes 1e-12 .. 1e10, both signs */
      const double mant = (double)(rnd(&s) >> 11) / 9007199254740992.0;
      const double e = -12.0 + 22.0 * (double)(rnd(&s) >> 11) / 9007199254740992.0;
      double v = mant * pow(10.0, e);
      if (rnd(&s) & 1) v = -v;
      same_fixed(v, d);
      /* a tie at the last decimal and its neighbours: k / 10^d + 1 / (2 10^d)
       * is exact when it is a dyadic fraction; the ulps either side test the
       * comparison with the half */
      const double t = ((double)(rnd(&s) % 2000000) + 0.5) / pow(10.0, d);
      same_fixed(t, d);
      same_fixed(nextafter(t, 0), d);
      same_fixed(nextafter(t, 1e300), d);
      /* tracker-like numbers: um positions to 0.1 nm, small velocities */
      same_fixed((double)((int64_t)(rnd(&s) % 4000000) - 2000000) / 8192.0, d);
    }
    /* every k / 2^m for small m: exact ties for the decimals' rounding */
    for (int m = 1; m <= 12; m++)
      for (int k = -300; k <= 300; k++) same_fixed(ldexp((double)k, -m), d);
  }
  const int64_t ints[] = {0, 1, -1, 9, 10, -10, INT64_MAX, INT64_MIN, INT64_MIN + 1,
                          1000000000000LL, -999999999999LL};
  for (size_t k = 0; k < sizeof ints / sizeof ints[0]; k++) same_i64(ints[k]);
  for (int i = 0; i < 200000; i++) same_i64((int64_t)rnd(&s) >> (rnd(&s) % 64));
  const uint64_t uints[] = {0, 1, 9, 10, UINT64_MAX, (uint64_t)INT64_MAX + 1};
  for (size_t k = 0; k < sizeof uints / sizeof uints[0]; k++) {
    char want[32], got[ELFM_FMT_NUM_MAX + 1];
    snprintf(want, sizeof want, "%" PRIu64, uints[k]);
    got[elfm_fmt_u64(got, uints[k])] = '\0';
    CHECK_MSG(strcmp(want, got) == 0, "%s written as %s", want, got);
  }
  CHECK_MSG(n_bad == 0, "%ld numbers written unlike printf", n_bad);
  return check_report();
}
