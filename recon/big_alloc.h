/* big_alloc.h — zeroed buffers of a sensor's or a volume's size (internal
 * to recon/: frames.c's frames, the framer's stamps, volume.c's volumes).
 *
 * Why: a frame is 3.7 MB of floats and as many bytes of pixel indices, the
 * framer's stamps 7.4 MB, and a run holds a frame or more per slot in
 * flight. In 4 KiB pages their first touches were thousands of page faults
 * per run and their scattered writes missed the TLB; on 2 MiB pages
 * (Linux's transparent huge pages, asked for with madvise) `eventlfm track`
 * on flow 1 s, 2 threads, took 0.97 of the CPU time, on flow 100 ms 0.75.
 * A buffer made and freed per frame would pay for a fresh mapping each
 * time: what is allocated here is kept for the run (docs/recon.md
 * "Volumes on huge pages"). */
#ifndef ELFM_BIG_ALLOC_H
#define ELFM_BIG_ALLOC_H

#include <stddef.h>

#include "elfm_volume.h"

/* n x size bytes, zeroed, or NULL (out of memory, or n x size overflows).
 * From 2 MiB on, and on Linux, mapped on its own and marked for huge
 * pages; otherwise calloc's. Free with elfm_big_free and the same n, size. */
void *elfm_big_calloc(size_t n, size_t size);
void elfm_big_free(void *p, size_t n, size_t size);

/* elfm_volume_create's, with data from elfm_big_calloc: for the volumes a
 * run makes once and refills every frame (the pipeline's slots,
 * elfm_refocus_volume_create). Not for volumes made and freed one after
 * another (a file read per frame): each would be a fresh mapping, zeroed
 * and faulted in: reading 50 EXR volumes three times took 5.0-6.0 s so,
 * 4.2-4.7 s from calloc (whose freed blocks are reused). */
elfm_volume *elfm_volume_create_kept(int w, int h, int nz, double um_per_px,
                                     double z_min_um, double z_step_um, elfm_error *err);

/* The machine's physical memory in bytes (sysconf), 0 where it does not
 * tell: what the pipeline's ring of slots is checked against. */
double elfm_physical_memory_bytes(void);

#endif
