/* volume_test_util.h — comparing refocused volumes (test_refocus.c,
 * test_frames_deep.c): the dense and sparse paths agree to float rounding,
 * not bit for bit, so the tests compare the largest difference with the
 * largest value. */
#ifndef ELFM_TESTS_VOLUME_TEST_UTIL_H
#define ELFM_TESTS_VOLUME_TEST_UTIL_H

#include <math.h>
#include <stddef.h>

#include "elfm_volume.h"

/* The largest |value| of v */
static inline float vmax(const elfm_volume *v)
{
  float m = 0.0f;
  for (size_t i = 0; i < (size_t)v->w * v->h * v->nz; i++) m = fmaxf(m, fabsf(v->data[i]));
  return m;
}

/* The largest |a - b| over two volumes of one size */
static inline float maxdiff(const elfm_volume *a, const elfm_volume *b)
{
  float m = 0.0f;
  for (size_t i = 0; i < (size_t)a->w * a->h * a->nz; i++)
    m = fmaxf(m, fabsf(a->data[i] - b->data[i]));
  return m;
}

#endif
