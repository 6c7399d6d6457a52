/* test_link_reach.c — how far stitching (step 5 of the linker,
 * elfm_link_options.stitch_points) lets a young track start from a
 * dormant one's end: stitch_gate_um plus 1.5 x the FASTER of the two
 * tracks' speeds over the time between them (link_repair.c).
 *
 * Bead A circles fast (radius 20 um, 3.5 um/ms) in frames 0-39, is dark
 * for 25 frames, and comes back slowed to 0.2 um/ms on its own path, 14
 * frames' arc (37.6 um) behind where it was last seen: a flow bead braking
 * unseen. The jump is within reach of A's speed (8 + 1.5 x 3.5 x 26 um)
 * but not of the young track's (8 + 1.5 x 0.2 x 26 um): one track of all
 * A's points. Off (stitch_points 0): two tracks. (A bead out of reach of
 * both: test_link, 5g.) */
#include <math.h>

#include "check.h"
#include "elfm_tracker.h"
#include "link_test_util.h"

enum { N_FRAMES = 100, SEEN_END = 40, BACK = 65 };
static const int64_t T0 = 1000000;

/* The track count; *n0 the first finished track's points. `w_rad_per_ms`:
 * A's angular speed before the gap (after it 0.01 rad/ms, 0.2 um/ms). */
static int run(int stitch_points, double w_rad_per_ms, size_t *n0)
{
  elfm_error err;
  elfm_link_options o;
  elfm_link_options_default(&o);
  o.stitch_points = stitch_points;
  o.rescue_gate_factor = 0; /* only stitching may join the two */
  elfm_linker *l = elfm_link_create(&o, &err);
  CHECK(l != NULL);
  if (!l) return -1;
  /* the return: the point A passed 14 frames before it was last seen */
  const double a_back = w_rad_per_ms * (SEEN_END - 1 - 14);
  for (int f = 0; f < N_FRAMES; f++) {
    const int seen = f < SEEN_END || f >= BACK;
    const double a = f < SEEN_END ? w_rad_per_ms * f : a_back + 0.01 * (f - BACK);
    elfm_detection d = link_test_det(20 * cos(a), 20 * sin(a), 5, 50);
    CHECK_OK(elfm_link_step(l, f, T0 + f * 1000, &d, seen, &err), &err);
  }
  CHECK_OK(elfm_link_finish(l, &err), &err);
  int n = 0;
  elfm_track *t;
  while ((t = elfm_link_pop_finished(l))) {
    if (n == 0) *n0 = t->n;
    n++;
    elfm_track_free(t);
  }
  elfm_link_free(l);
  return n;
}

int main(void)
{
  size_t n0 = 0;
  const size_t all = SEEN_END + (N_FRAMES - BACK);
  /* fast before the gap: within reach of A's own speed */
  int nt = run(5, 3.5 / 20, &n0);
  CHECK_MSG(nt == 1 && n0 == all, "fast, then slow: %d tracks, the first of %zu points (%zu)", nt, n0,
            all);
  nt = run(0, 3.5 / 20, &n0);
  CHECK_MSG(nt == 2 && n0 == SEEN_END, "stitching off: %d tracks, the first of %zu points", nt, n0);
  return check_report();
}
