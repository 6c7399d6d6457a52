/* test_link_gate.c — the gate of a track after a missed frame widens with
 * the distance its object can turn away while unseen: gate_um + missed x
 * gate_growth_um_per_frame + speed_gate_frac x speed x the time per frame
 * (elfm_link_options; tracker/link_predict.c track_gate_um). The last term
 * is a distance, so at 500 Hz (2 ms frames) it is twice that at 1 kHz.
 *
 * A bead moving along x at 5 um/ms is seen in frames 0..11, missed in
 * frame 12, and seen once more in frame 13 at a point off its line by d
 * across the motion; then it is gone. With the defaults (gate 6 um, growth
 * 0.05 um per frame, fraction 0.3) the gate in frame 13 is 6.05 + 1.5 =
 * 7.55 um at 1 ms frames and 6.05 + 3.0 = 9.05 um at 2 ms frames. The
 * rescue pass (rescue_gate_factor, a wider second chance for established
 * tracks) is off here, so the gate alone decides whether the point joins
 * the track (13 points) or starts one of its own (the track keeps 12).
 * (Found by a mutation sweep: the time per frame left out of the last
 * term passed the linker's tests, all of which run at 1 ms frames, where
 * it is 1.) */
#include <stdio.h>

#include "check.h"
#include "elfm_tracker.h"
#include "link_test_util.h"

/* The kept track's number of points, frames frame_us apart, the last
 * point off the line by off_um in y; -1 when not exactly one track kept. */
static int run(int64_t frame_us, double off_um)
{
  elfm_error err;
  elfm_error_clear(&err);
  elfm_link_options o;
  elfm_link_options_default(&o);
  o.rescue_gate_factor = 0;
  elfm_linker *l = elfm_link_create(&o, &err);
  CHECK(l != NULL);
  if (!l) return -1;
  const double v_um_per_us = 5e-3;
  for (int f = 0; f < 14 + o.max_gap_frames + 2; f++) {
    const int64_t t_us = 1000 + frame_us * f;
    const double x = -40 + v_um_per_us * (double)(t_us - 1000);
    elfm_detection d = link_test_det_bright(x, f == 13 ? 5 + off_um : 5, 10);
    const int n = f < 12 || f == 13;
    CHECK_OK(elfm_link_step(l, f, t_us, &d, n, &err), &err);
  }
  CHECK_OK(elfm_link_finish(l, &err), &err);
  int kept = 0, len = -1;
  elfm_track *t;
  while ((t = elfm_link_pop_finished(l))) {
    kept++;
    len = (int)t->n;
    elfm_track_free(t);
  }
  elfm_link_free(l);
  return kept == 1 ? len : -1;
}

int main(void)
{
  /* within both gates */
  CHECK_EQ_INT(run(1000, 7.0), 13);
  CHECK_EQ_INT(run(2000, 7.0), 13);
  /* beyond the 1 ms gate, within the 2 ms one */
  CHECK_EQ_INT(run(1000, 8.3), 12);
  CHECK_EQ_INT(run(2000, 8.3), 13);
  /* beyond both */
  CHECK_EQ_INT(run(1000, 9.8), 12);
  CHECK_EQ_INT(run(2000, 9.8), 12);
  return check_report();
}
