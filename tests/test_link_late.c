/* test_link_late.c — step 5b of the linker, late stitching
 * (elfm_link_options.stitch_late_points; docs/tracker.md "A young track
 * one frame late").
 *
 * Bead A circles (radius 20 um, 3.5 um/ms) and is seen in frames 0-39.
 * Unseen, it speeds up and comes back half an orbit from where its track
 * would look, on its own earlier path: seen in 4 frames (80-83), dark
 * again, then seen from frame 96 on (a deep bead's few frames at a time).
 * A's track is dark from frame 40 and ends in frame 91, when its young
 * successor has 4 points, one short of stitch_points: step 5 judges the
 * young track only when it reaches 5 points, in frame 96, too late. With
 * late stitching (3 points) A's track goes on as the young one: one track
 * of all A's points, under A's id. Off, or asking for 5 points, two
 * tracks. A young track of 4 points on another path (a circle 60 um away)
 * is never joined, nor one of 2 points when 3 are asked for. */
#include <math.h>

#include "check.h"
#include "elfm_tracker.h"
#include "link_test_util.h"

enum { N_FRAMES = 130, SEEN_END = 40, BACK0 = 80, BACK1 = 84, AGAIN = 96 };
static const int64_t T0 = 1000000;

/* Is A seen in frame f, and where: half an orbit ahead from its return on.
 * `young_points`: frames BACK0 .. BACK0 + young_points - 1 of the return
 * are seen; `cx`: the circle's centre x (another path when far). */
static int bead(int f, int young_points, double cx, double p[3])
{
  const double w = 3.5 / 20; /* rad/ms */
  int seen = f < SEEN_END || (f >= BACK0 && f < BACK0 + young_points) || f >= AGAIN;
  const double a = w * f + (f >= BACK0 ? M_PI : 0);
  const double x0 = f >= BACK0 ? cx : 0;
  p[0] = x0 + 20 * cos(a);
  p[1] = 20 * sin(a);
  p[2] = 5;
  return seen;
}

/* Run the scene; the finished tracks' count, and the first one's id and
 * point count. */
static int run(int late_points, int stitch_points, int young_points, double cx, int64_t *id0,
               size_t *n0, int64_t *late)
{
  elfm_error err;
  elfm_link_options o;
  elfm_link_options_default(&o);
  o.stitch_points = stitch_points;
  o.stitch_late_points = late_points;
  o.rescue_gate_factor = 0; /* its wide gate would take A back in frame 80 */
  elfm_linker *l = elfm_link_create(&o, &err);
  CHECK(l != NULL);
  if (!l) return -1;
  for (int f = 0; f < N_FRAMES; f++) {
    double p[3];
    const int seen = bead(f, young_points, cx, p);
    elfm_detection d = link_test_det(p[0], p[1], p[2], 50);
    CHECK_OK(elfm_link_step(l, f, T0 + f * 1000, &d, seen, &err), &err);
  }
  CHECK_OK(elfm_link_finish(l, &err), &err);
  *late = elfm_link_n_late_stitches(l);
  int n = 0;
  elfm_track *t;
  while ((t = elfm_link_pop_finished(l))) {
    if (n == 0) {
      *id0 = t->id;
      *n0 = t->n;
    }
    for (size_t k = 1; k < t->n; k++) CHECK(t->pts[k].frame > t->pts[k - 1].frame);
    n++;
    elfm_track_free(t);
  }
  elfm_link_free(l);
  return n;
}

int main(void)
{
  int64_t id = -1, late = -1;
  size_t n = 0;
  const size_t all = SEEN_END + (BACK1 - BACK0) + (N_FRAMES - AGAIN);

  /* late stitching: one track, A's id, all its points */
  int nt = run(3, 5, 4, 0, &id, &n, &late);
  CHECK_MSG(nt == 1 && id == 0 && n == all && late == 1,
            "late 3: %d tracks, the first id %lld of %zu points (%zu), %lld late stitches", nt,
            (long long)id, n, all, (long long)late);
  /* off, and asking for as many points as step 5 (nothing left to it) */
  nt = run(0, 5, 4, 0, &id, &n, &late);
  CHECK_MSG(nt == 2 && n == SEEN_END && late == 0, "late off: %d tracks, the first of %zu points",
            nt, n);
  nt = run(5, 5, 4, 0, &id, &n, &late);
  CHECK_MSG(nt == 2 && late == 0, "late 5: %d tracks", nt);
  /* without step 5 there is no late step either */
  nt = run(3, 0, 4, 0, &id, &n, &late);
  CHECK_MSG(nt == 2 && late == 0, "no stitching: %d tracks", nt);
  /* a young track on another path: not joined */
  nt = run(3, 5, 4, 60, &id, &n, &late);
  CHECK_MSG(nt == 2 && late == 0, "another path: %d tracks, %lld late stitches", nt,
            (long long)late);
  /* a young track too short when A ends: its 2 points come before the
   * dark stretch, and it ends too (dark past max_gap_frames) */
  nt = run(3, 5, 2, 0, &id, &n, &late);
  CHECK_MSG(late == 0, "2 young points: %lld late stitches", (long long)late);

  /* the option is checked */
  elfm_link_options o;
  elfm_link_options_default(&o);
  elfm_error err;
  o.stitch_late_points = -1;
  CHECK(elfm_link_create(&o, &err) == NULL);
  return check_report();
}
