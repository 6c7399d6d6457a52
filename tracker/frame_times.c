/* frame_times.c — every frame's time, stored as runs of evenly spaced
 * frames (elfm_tracks.h, "Frame times"). */
#include <stdlib.h>
#include <string.h>

#include "elfm_tracks.h"

void elfm_frame_times_init(elfm_frame_times *ft)
{
  ft->n = ft->cap = 0;
  ft->frame = ft->t_us = ft->step_us = NULL;
  ft->last_frame = -1;
}

void elfm_frame_times_free(elfm_frame_times *ft)
{
  free(ft->frame);
  free(ft->t_us);
  free(ft->step_us);
  elfm_frame_times_init(ft);
}

static int grow(elfm_frame_times *ft)
{
  size_t cap = ft->cap ? 2 * ft->cap : 16;
  int64_t *a = realloc(ft->frame, cap * sizeof *a);
  if (!a) return 0;
  ft->frame = a;
  int64_t *b = realloc(ft->t_us, cap * sizeof *b);
  if (!b) return 0;
  ft->t_us = b;
  int64_t *c = realloc(ft->step_us, cap * sizeof *c);
  if (!c) return 0;
  ft->step_us = c;
  ft->cap = cap;
  return 1;
}

elfm_status elfm_frame_times_add(elfm_frame_times *ft, int64_t frame, int64_t t_us,
                                 elfm_error *err)
{
  if (ft->n > 0) {
    const size_t k = ft->n - 1;
    int64_t t_prev = 0;
    elfm_frame_times_get(ft, ft->last_frame, &t_prev);
    if (frame <= ft->last_frame || t_us <= t_prev)
      return elfm_error_set(err, ELFM_ERR_INVALID, NULL, -1,
                            "frame times: frame %lld at %lld us does not follow frame %lld at "
                            "%lld us", (long long)frame, (long long)t_us,
                            (long long)ft->last_frame, (long long)t_prev);
    const int64_t df = frame - ft->frame[k], dt = t_us - ft->t_us[k];
    /* on the current run's line: nothing to store */
    if (ft->step_us[k] > 0 && dt == ft->step_us[k] * df) {
      ft->last_frame = frame;
      return ELFM_OK;
    }
    /* the run's second frame sets its step (when the frames between fit) */
    if (ft->step_us[k] == 0 && ft->last_frame == ft->frame[k] && dt % df == 0) {
      ft->step_us[k] = dt / df;
      ft->last_frame = frame;
      return ELFM_OK;
    }
  }
  if (ft->n == ft->cap && !grow(ft))
    return elfm_error_set(err, ELFM_ERR_NOMEM, NULL, -1, "frame times: out of memory");
  ft->frame[ft->n] = frame;
  ft->t_us[ft->n] = t_us;
  ft->step_us[ft->n] = 0;
  ft->n++;
  ft->last_frame = frame;
  return ELFM_OK;
}

elfm_status elfm_frame_times_copy(elfm_frame_times *dst, const elfm_frame_times *src,
                                  elfm_error *err)
{
  elfm_frame_times_free(dst);
  while (dst->cap < src->n)
    if (!grow(dst)) {
      elfm_frame_times_free(dst);
      return elfm_error_set(err, ELFM_ERR_NOMEM, NULL, -1, "frame times: out of memory");
    }
  if (src->n) {
    memcpy(dst->frame, src->frame, src->n * sizeof *dst->frame);
    memcpy(dst->t_us, src->t_us, src->n * sizeof *dst->t_us);
    memcpy(dst->step_us, src->step_us, src->n * sizeof *dst->step_us);
  }
  dst->n = src->n;
  dst->last_frame = src->last_frame;
  return ELFM_OK;
}

int elfm_frame_times_get(const elfm_frame_times *ft, int64_t frame, int64_t *t_us)
{
  if (ft->n == 0 || frame < ft->frame[0] || frame > ft->last_frame) return 0;
  size_t lo = 0, hi = ft->n; /* the last run starting at or before frame */
  while (hi - lo > 1) {
    size_t mid = lo + (hi - lo) / 2;
    if (ft->frame[mid] <= frame) lo = mid;
    else hi = mid;
  }
  *t_us = ft->t_us[lo] + ft->step_us[lo] * (frame - ft->frame[lo]);
  return 1;
}

void elfm_frame_times_forget_before(elfm_frame_times *ft, int64_t frame)
{
  if (ft->n < 2 || frame <= ft->frame[1]) return;
  size_t lo = 0, hi = ft->n; /* the last run starting at or before frame */
  while (hi - lo > 1) {
    size_t mid = lo + (hi - lo) / 2;
    if (ft->frame[mid] <= frame) lo = mid;
    else hi = mid;
  }
  /* moved only once half the runs can go: O(1) amortised per frame */
  if (2 * lo < ft->n) return;
  const size_t keep = ft->n - lo;
  memmove(ft->frame, ft->frame + lo, keep * sizeof *ft->frame);
  memmove(ft->t_us, ft->t_us + lo, keep * sizeof *ft->t_us);
  memmove(ft->step_us, ft->step_us + lo, keep * sizeof *ft->step_us);
  ft->n = keep;
}
