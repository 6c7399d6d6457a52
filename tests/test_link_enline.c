/* test_link_enline.c — slow encounters judged along straight lines
 * (elfm_link.h encounter_line_ratio; docs/tracker.md "Slow encounters
 * along straight lines"). Two slow objects, as a crawling worm's neurons
 * (2 ms frames, 0.05-0.4 um/ms), cross in z a fraction of a micrometre to
 * 1.5 um apart laterally. While they are within the axial blur the
 * detector finds one spot between them (two detections 0.1 um apart, as
 * the view fit started from two predictions finds one blob twice), for
 * 20-60 frames; both tracks run on it, and when the objects part they
 * share them out as their fits say. Over that span the 8-point quadratic
 * fits of the encounter review (step 7) say little, and straight lines
 * through 20 points of each head and tail say which way each went. Over a
 * grid of speeds, offsets, drifts and merge distances the test asks that
 * the lines mend at least 10 of the swapped geometries (none without
 * them), break none of the right ones, and change nothing where the
 * objects are not at rest (faster than rest_speed_um_per_ms). With the
 * objects seen apart every few frames inside the merge, which splits one
 * meeting into nested encounter records, at least 22 in all are mended
 * (18 when the nested records were reviewed again after an exchange).
 * And with encounter_line_ratio out of range the linker is not created. */
#include <math.h>
#include <stdio.h>

#include "check.h"
#include "elfm_tracker.h"
#include "link_test_util.h"

enum { N_FRAMES = 160, MEET = 70 };
static const double FRAME_MS = 2;


/* Object b in frame f. Object 0 rises in z at g[0] um/ms and drifts along
 * +x at g[3]; object 1 moves in z at g[1] um/ms and drifts along -x at
 * g[3]; at frame MEET they are level in z, 2 * g[2] um apart in y. Both
 * are carried along y at g[5] um/ms (0: at rest; 2: the same encounter,
 * the objects faster than rest_speed_um_per_ms). A fixed jitter of
 * +-0.15 um (0.8 um in z), as the detector's on a bright neuron. */
static void object(int b, int f, const double g[6], double p[3])
{
  const double t_ms = (f - MEET) * FRAME_MS;
  p[0] = (b ? -g[3] : g[3]) * t_ms + 0.15 * sin(2.1 * f + b);
  p[1] = (b ? g[2] : -g[2]) + g[5] * t_ms + 0.15 * cos(1.3 * f + 2 * b);
  p[2] = (b ? g[1] : g[0]) * t_ms + 0.8 * sin(0.7 * f + 3 * b);
}

/* Link the two objects with the track command's linking defaults for the
 * integral (step 7 on, no circles) and line_ratio; returns how many of the
 * tracks end on the object they started on (object 0 ends above object
 * 1), -1 when not two tracks. g[4]: merged within (um, z / 4). */
static int run(const double g[6], double line_ratio, int flicker)
{
  elfm_error err;
  elfm_link_options o;
  link_test_review_options(&o);
  o.circle_points = 0;
  o.encounter_line_ratio = line_ratio;
  elfm_linker *l = elfm_link_create(&o, &err);
  CHECK(l != NULL);
  if (!l) return -1;
  for (int f = 0; f < N_FRAMES; f++) {
    double p[3], q[3];
    object(0, f, g, p);
    object(1, f, g, q);
    /* merged: one spot between them */
    const int merged = hypot(hypot(p[0] - q[0], p[1] - q[1]), (p[2] - q[2]) / 4) < g[4] &&
                       !(flicker && f % flicker == 0);
    link_test_step_pair(l, f, 1000 + (int64_t)(f * FRAME_MS * 1000), p, q, merged, 0.5 * (p[2] + q[2]));
  }
  CHECK_OK(elfm_link_finish(l, &err), &err);
  int n = 0, own = 0;
  elfm_track *t;
  while ((t = elfm_link_pop_finished(l))) {
    n++;
    /* object 0 starts below object 1 and ends above it */
    const double z0 = t->pts[0].z_um, z1 = t->pts[t->n - 1].z_um;
    own += (z0 < 0) == (z1 > 0);
    elfm_track_free(t);
  }
  elfm_link_free(l);
  return n == 2 ? own : -1;
}

int main(void)
{
  /* object 0's rise, object 1's z speed (um/ms), half the lateral offset,
   * the drift (um/ms), merged within (um, z / 4) */
  const double v0s[3] = {0.15, 0.25, 0.35}, v1s[3] = {-0.05, 0, 0.05}, ss[3] = {0.15, 0.4, 0.75};
  const double drifts[2] = {0, 0.05}, ms[2] = {2, 3};
  /* flicker 0: one spot while merged; 3, 4, 6, 8: the two objects seen
   * apart every that many frames, which splits an encounter into nested
   * ones (elfm_link_review_encounters drops those within an exchange) */
  const int flickers[5] = {0, 3, 4, 6, 8};
  int total_flicker_mended = 0;
  for (int fi = 0; fi < 5; fi++) {
    const int fl = flickers[fi];
    int cases = 0, swapped_off = 0, mended = 0, broken = 0, moving_changed = 0;
    for (int i0 = 0; i0 < 3; i0++)
      for (int i1 = 0; i1 < 3; i1++)
        for (int i2 = 0; i2 < 3; i2++)
          for (int i3 = 0; i3 < 2; i3++)
            for (int i4 = 0; i4 < 2; i4++) {
              double g[6] = {v0s[i0], v1s[i1], ss[i2], drifts[i3], ms[i4], 0};
              const int off = run(g, 0, fl), on = run(g, 0.5, fl);
              cases++;
              swapped_off += off != 2;
              mended += off != 2 && on == 2;
              broken += off == 2 && on != 2;
              g[5] = 2; /* the same encounter, not at rest */
              moving_changed += run(g, 0, fl) != run(g, 0.5, fl);
            }
    printf("flicker %d: %d geometries, %d end swapped without the lines; the lines mend %d and break "
           "%d; %d changed when not at rest\n",
           fl, cases, swapped_off, mended, broken, moving_changed);
    /* measured when written: flicker 0: 57 swapped, 12 mended, 0 broken;
     * 3 / 4 / 6 / 8: 51 / 50 / 49 / 49 swapped, 8 / 4 / 7 / 5 mended (6 /
     * 3 / 5 / 4 without the drop of nested encounters), 0 broken; 0
     * changed when not at rest. Without encounter_line_ratio none is
     * mended. */
    CHECK_MSG(swapped_off >= 20, "flicker %d: only %d of %d geometries swapped without the lines",
              fl, swapped_off, cases);
    CHECK_MSG(mended >= (fl ? 4 : 10), "flicker %d: the lines mended only %d of %d swapped geometries",
              fl, mended, swapped_off);
    CHECK_MSG(broken == 0, "flicker %d: the lines broke %d geometries", fl, broken);
    CHECK_MSG(moving_changed == 0, "flicker %d: the lines changed %d geometries not at rest", fl,
              moving_changed);
    total_flicker_mended += fl ? mended : 0;
  }
  CHECK_MSG(total_flicker_mended >= 22,
            "with flicker the lines mended only %d geometries (24 when written, 18 without the drop "
            "of nested encounters)",
            total_flicker_mended);

  elfm_error err;
  elfm_link_options o;
  elfm_link_options_default(&o);
  o.encounter_line_ratio = -0.1;
  CHECK(elfm_link_create(&o, &err) == NULL);
  o.encounter_line_ratio = 1.5;
  CHECK(elfm_link_create(&o, &err) == NULL);
  o.encounter_line_ratio = NAN;
  CHECK(elfm_link_create(&o, &err) == NULL);
  return check_report();
}
