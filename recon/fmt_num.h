/* fmt_num.h — numbers into text for the writers (the tracker's
 * tracks_write.c, the events' writer_csv.c), without printf's machinery: a
 * track run writes ~20 numbers per point, and fprintf's "%.4f" was ~4 % of
 * `eventlfm track`'s time on one thread. Internal to the writers; the text
 * is printf's, byte for byte (tests/test_fmt_num.c compares them on
 * millions of values). */
#ifndef ELFM_FMT_NUM_H
#define ELFM_FMT_NUM_H

#include <stddef.h>
#include <stdint.h>

/* Room that any call below needs at out: DBL_MAX has 309 digits before
 * the point, and 9 decimals follow. */
#define ELFM_FMT_NUM_MAX 330

/* v with `decimals` (0..9) digits after the point, exactly as printf's
 * "%.<decimals>f" writes it in the default rounding mode (ties to even on
 * the double's exact value; "-0.0000" for a negative value that rounds to
 * 0). Values that are not finite or not below 1e9 in magnitude go
 * through snprintf. Writes no terminating NUL; returns the length. */
size_t elfm_fmt_fixed(char *out, double v, int decimals);

/* v in decimal, as "%" PRId64 / "%" PRIu64. Returns the length (no NUL). */
size_t elfm_fmt_i64(char *out, int64_t v);
size_t elfm_fmt_u64(char *out, uint64_t v);

#endif
