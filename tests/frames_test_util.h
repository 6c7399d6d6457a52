/* frames_test_util.h — events for the framer tests (test_frames.c,
 * test_frames_deep.c). */
#ifndef ELFM_TESTS_FRAMES_TEST_UTIL_H
#define ELFM_TESTS_FRAMES_TEST_UTIL_H

#include <stdint.h>

#include "elfm_recon.h"

/* Append one event to c (its capacity is the caller's to respect). */
static inline void add_event(elfm_event_chunk *c, int64_t t, int x, int y, int p)
{
  c->t_us[c->n] = t;
  c->x[c->n] = (uint16_t)x;
  c->y[c->n] = (uint16_t)y;
  c->p[c->n] = (uint8_t)p;
  c->n++;
}

#endif
