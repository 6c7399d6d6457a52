/* big_alloc.c — see big_alloc.h. */
#include "big_alloc.h"

#include <stdint.h>
#include <stdlib.h>
#include <unistd.h>

#if defined(__linux__)
#include <sys/mman.h>
#define ELFM_BIG_MMAP 1
#endif
/* Under AddressSanitizer the buffers stay calloc's, so that its leak check
 * still sees them (it does not track mappings). */
#if defined(__SANITIZE_ADDRESS__)
#undef ELFM_BIG_MMAP
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
#undef ELFM_BIG_MMAP
#endif
#endif

#define HUGE_BYTES ((size_t)2 << 20)

#ifdef ELFM_BIG_MMAP
/* Is a buffer of this size mapped (elfm_big_calloc and elfm_big_free must
 * agree)? */
static int big_mapped(size_t bytes)
{
  return bytes >= HUGE_BYTES && bytes <= SIZE_MAX - 2 * HUGE_BYTES;
}

/* The mapping's length: the bytes rounded up to whole huge pages. */
static size_t big_len(size_t bytes)
{
  return (bytes + HUGE_BYTES - 1) / HUGE_BYTES * HUGE_BYTES;
}
#endif

void *elfm_big_calloc(size_t n, size_t size)
{
  if (size && n > SIZE_MAX / size) return NULL;
#ifdef ELFM_BIG_MMAP
  const size_t bytes = n * size;
  if (big_mapped(bytes)) {
    /* map a huge page more than needed, keep the aligned part: the kernel
     * backs only aligned 2 MiB ranges with huge pages. Anonymous mappings
     * read as zero and are faulted in as touched. */
    const size_t len = big_len(bytes);
    uint8_t *m = mmap(NULL, len + HUGE_BYTES, PROT_READ | PROT_WRITE,
                      MAP_PRIVATE | MAP_ANONYMOUS, -1, 0);
    if (m == MAP_FAILED) return NULL;
    const uintptr_t a = ((uintptr_t)m + HUGE_BYTES - 1) & ~(uintptr_t)(HUGE_BYTES - 1);
    uint8_t *p = (uint8_t *)a;
    if (p > m) munmap(m, (size_t)(p - m));
    if (m + len + HUGE_BYTES > p + len) munmap(p + len, (size_t)(m + len + HUGE_BYTES - (p + len)));
    (void)madvise(p, len, MADV_HUGEPAGE); /* a hint: without it, 4 KiB pages */
    return p;
  }
#endif
  return calloc(n, size);
}

void elfm_big_free(void *p, size_t n, size_t size)
{
  if (!p) return;
#ifdef ELFM_BIG_MMAP
  const size_t bytes = n * size;
  if (big_mapped(bytes)) {
    munmap(p, big_len(bytes));
    return;
  }
#else
  (void)n;
  (void)size;
#endif
  free(p);
}

double elfm_physical_memory_bytes(void)
{
#if defined(_SC_PHYS_PAGES) && defined(_SC_PAGESIZE)
  const long pages = sysconf(_SC_PHYS_PAGES), page = sysconf(_SC_PAGESIZE);
  if (pages > 0 && page > 0) return (double)pages * (double)page;
#endif
  return 0;
}
