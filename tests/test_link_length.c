/* test_link_length.c — the least track length (elfm_link_options.min_points):
 * a track of min_points points is kept, one of min_points - 1 is not.
 * Two static objects far apart: A seen in frames 0..n_a - 1, B in frames
 * 0..n_b - 1, then nothing until the linker's gap closing gives up on both.
 * (Found by a mutation sweep: a length test one point short passed the
 * linker's other tests, whose short tracks were blips of 1-2 points.) */
#include <stdio.h>

#include "check.h"
#include "elfm_tracker.h"
#include "link_test_util.h"

/* Run with min_points m; returns the lengths of the tracks kept in *len_a,
 * *len_b (0: not kept) and how many tracks were kept. */
static int run(int m, int n_a, int n_b, int *len_a, int *len_b)
{
  elfm_error err;
  elfm_link_options o;
  elfm_link_options_default(&o);
  o.min_points = m;
  elfm_linker *l = elfm_link_create(&o, &err);
  CHECK(l != NULL);
  if (!l) return -1;
  const int frames = (n_a > n_b ? n_a : n_b) + o.max_gap_frames + 5;
  for (int f = 0; f < frames; f++) {
    elfm_detection d[2];
    int n = 0;
    if (f < n_a) d[n++] = link_test_det_bright(-40, -40, 0);
    if (f < n_b) d[n++] = link_test_det_bright(40, 40, 10);
    CHECK_OK(elfm_link_step(l, f, 1000 + 1000 * (int64_t)f, d, n, &err), &err);
  }
  CHECK_OK(elfm_link_finish(l, &err), &err);
  *len_a = *len_b = 0;
  int kept = 0;
  elfm_track *t;
  while ((t = elfm_link_pop_finished(l))) {
    kept++;
    if (t->n && t->pts[0].x_um < 0) *len_a = (int)t->n;
    else if (t->n) *len_b = (int)t->n;
    elfm_track_free(t);
  }
  CHECK_EQ_INT((int)elfm_link_n_started(l), (n_a > 0) + (n_b > 0));
  elfm_link_free(l);
  return kept;
}

int main(void)
{
  int la, lb;
  /* the default, 5: 4 points go, 5 stay */
  CHECK_EQ_INT(run(5, 4, 5, &la, &lb), 1);
  CHECK_EQ_INT(la, 0);
  CHECK_EQ_INT(lb, 5);
  /* 1: a single point is a track */
  CHECK_EQ_INT(run(1, 1, 2, &la, &lb), 2);
  CHECK_EQ_INT(la, 1);
  CHECK_EQ_INT(lb, 2);
  /* 2: the single point goes */
  CHECK_EQ_INT(run(2, 1, 2, &la, &lb), 1);
  CHECK_EQ_INT(la, 0);
  CHECK_EQ_INT(lb, 2);
  return check_report();
}
