/* test_big_alloc.c — recon/big_alloc.c: the frames' and volumes' buffers.
 *
 * What the run relies on: a buffer is zeroed and usable to its last byte at
 * every size (a mapping is rounded up to whole 2 MiB pages, and a wrong
 * rounding would cut off a volume's last planes), zeroed again when made
 * after one was used and freed, refused when n x size overflows; from 2 MiB
 * on (Linux, not under AddressSanitizer) aligned to 2 MiB, or the kernel
 * backs none of it with huge pages. And the machine's memory, which the
 * pipeline's ring is checked against, is told in bytes. */
#include <stdint.h>
#include <string.h>

#include "big_alloc.h"
#include "check.h"

#define MIB ((size_t)1 << 20)

#if defined(__linux__) && !defined(__SANITIZE_ADDRESS__)
#if defined(__has_feature)
#if !__has_feature(address_sanitizer)
#define EXPECT_ALIGNED 1
#endif
#else
#define EXPECT_ALIGNED 1
#endif
#endif

/* Every 4 KiB page's first and last byte, and the buffer's last: zero? */
static int all_zero(const uint8_t *p, size_t bytes)
{
  for (size_t i = 0; i < bytes; i += 4096) {
    if (p[i]) return 0;
    const size_t e = i + 4095 < bytes ? i + 4095 : bytes - 1;
    if (p[e]) return 0;
  }
  return bytes == 0 || p[bytes - 1] == 0;
}

static void test_sizes(void)
{
  /* under, at and over one huge page; a paper-geometry volume (144 x 144
   * x 51 floats, 4.2 MB) and a frame (1280 x 720 floats, 3.7 MB) */
  const size_t sizes[][2] = {{1, 1},           {4096, 1},       {2 * MIB - 1, 1}, {2 * MIB, 1},
                             {2 * MIB + 1, 1}, {3 * MIB + 5, 1}, {144 * 144 * 51, 4},
                             {1280 * 720, 4},  {2 * MIB / 8 + 3, 8}};
  for (size_t k = 0; k < sizeof sizes / sizeof sizes[0]; k++) {
    const size_t n = sizes[k][0], size = sizes[k][1], bytes = n * size;
    for (int round = 0; round < 2; round++) {
      uint8_t *p = elfm_big_calloc(n, size);
      CHECK_MSG(p != NULL, "%zu x %zu bytes", n, size);
      if (!p) continue;
      /* zeroed, the second time too (after the first round's writes) */
      CHECK_MSG(all_zero(p, bytes), "%zu bytes, round %d: not zeroed", bytes, round);
#ifdef EXPECT_ALIGNED
      if (bytes >= 2 * MIB)
        CHECK_MSG((uintptr_t)p % (2 * MIB) == 0, "%zu bytes at %p: not on a 2 MiB boundary", bytes,
                  (void *)p);
#endif
      /* usable to the last byte (a short mapping faults here) */
      memset(p, 0xA5, bytes);
      CHECK(p[0] == 0xA5 && p[bytes - 1] == 0xA5);
      elfm_big_free(p, n, size);
    }
  }
}

static void test_refused(void)
{
  /* n x size beyond SIZE_MAX: NULL, not a short buffer */
  CHECK(elfm_big_calloc(SIZE_MAX / 2, 4) == NULL);
  CHECK(elfm_big_calloc(4, SIZE_MAX / 2) == NULL);
  CHECK(elfm_big_calloc((SIZE_MAX >> 20) + 1, (size_t)1 << 20) == NULL);
  /* freeing nothing is nothing */
  elfm_big_free(NULL, 2 * MIB, 1);
  elfm_big_free(NULL, 0, 0);
}

static void test_volume_kept(void)
{
  elfm_error err;
  elfm_volume *v = elfm_volume_create_kept(144, 144, 51, 0.925, -100.0, 4.0, &err);
  CHECK_OK(v ? ELFM_OK : err.code, &err);
  if (!v) return;
  CHECK_EQ_INT(v->w, 144);
  CHECK_EQ_INT(v->h, 144);
  CHECK_EQ_INT(v->nz, 51);
  CHECK(all_zero((const uint8_t *)v->data, (size_t)144 * 144 * 51 * sizeof *v->data));
  v->data[(size_t)144 * 144 * 51 - 1] = 1.0f; /* the last voxel is there */
  CHECK(v->data[(size_t)144 * 144 * 51 - 1] == 1.0f);
  elfm_volume_free(v);
}

static void test_memory(void)
{
  /* in bytes, not pages: a machine that runs this has more than 256 MB
   * and less than 1 PB */
  const double b = elfm_physical_memory_bytes();
#if defined(__linux__)
  CHECK_MSG(b > 256.0 * MIB && b < 1e15, "physical memory %.0f bytes", b);
#else
  CHECK(b >= 0);
#endif
}

int main(void)
{
  test_sizes();
  test_refused();
  test_volume_kept();
  test_memory();
  return check_report();
}
