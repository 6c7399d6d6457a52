/* big_alloc.h — zeroed buffers of a sensor's size (internal to recon/:
 * frames.c's frames and the framer's stamps).
 *
 * Why: a frame is 3.7 MB of floats and as many bytes of pixel indices, the
 * framer's stamps 7.4 MB, and a run holds a frame or more per slot in
 * flight. In 4 KiB pages their first touches were thousands of page faults
 * per run and their scattered writes missed the TLB; on 2 MiB pages
 * (Linux's transparent huge pages, asked for with madvise) `eventlfm track`
 * on flow 1 s, 2 threads, took 0.97 of the CPU time, on flow 100 ms 0.75.
 * Not for volumes: `recon --save-volumes` copies each volume for its
 * writer, and a mapping per copy took 1.7 x the wall time (docs/recon.md
 * "Huge pages for frames"). */
#ifndef ELFM_BIG_ALLOC_H
#define ELFM_BIG_ALLOC_H

#include <stddef.h>

/* n x size bytes, zeroed, or NULL (out of memory, or n x size overflows).
 * From 2 MiB on, and on Linux, mapped on its own and marked for huge
 * pages; otherwise calloc's. Free with elfm_big_free and the same n, size. */
void *elfm_big_calloc(size_t n, size_t size);
void elfm_big_free(void *p, size_t n, size_t size);

#endif
