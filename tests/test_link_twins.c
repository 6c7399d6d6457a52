/* test_link_twins.c — step 8 of the linker, twins at a track's end
 * (elfm_link_options.twin_um; docs/tracker.md "Twins at a track's end").
 *
 * One bead runs along +x for 50 frames, goes unseen for 10 while it turns
 * a corner, and is seen again moving along +y, 40 um from where the first
 * track's straight prediction looks: a second track is born on it. Its
 * walk before its birth (the gap filling, given back with elfm_link_fill)
 * finds the bead where the first track held it in its last frames: the
 * two tracks are one bead's. When the first track ends (dark for more than
 * max_gap_frames), step 8 lets it go on as the second: one finished track,
 * the first one's id, with the second one's points after its own. Off
 * (twin_um 0), two tracks. And when the second track's first points lie
 * elsewhere (it was born on another object and only met the first one's),
 * no join: the tracks stay two. */
#include <math.h>

#include "check.h"
#include "elfm_tracker.h"
#include "link_test_util.h"

enum { N_FRAMES = 120, DARK0 = 50, DARK1 = 60 };
static const int64_t T0 = 1000000;

/* The bead in frame f: +x at 3 um/ms, then +y from the corner at frame DARK0. */
static void bead(int f, double p[3])
{
  p[0] = f < DARK0 ? 3.0 * f : 3.0 * DARK0;
  p[1] = f < DARK0 ? 0.0 : 3.0 * (f - DARK0);
  p[2] = 10.0;
}

/* Run the scene (twin_um, twin_points as given); the second track's walk
 * gives fills from frame fill0 to DARK1 - 1, off_um beside the bead in x,
 * those before frame `far_before` 30 um. Returns
 * the finished tracks' count; ids, first and last frames, point counts of
 * up to two of them in the arrays; *twins = the linker's count. */
static int run(double twin_um, int twin_points, int fill0, int far_before, double off_um,
               int64_t id[2], int64_t first[2], int64_t last[2], size_t n[2], int64_t *twins)
{
  elfm_error err;
  elfm_link_options o;
  elfm_link_options_default(&o);
  o.twin_um = twin_um;
  o.twin_points = twin_points;
  elfm_linker *l = elfm_link_create(&o, &err);
  CHECK(l != NULL);
  int64_t young = -1;
  for (int f = 0; f < N_FRAMES; f++) {
    double p[3];
    bead(f, p);
    elfm_detection d = link_test_det(p[0], p[1], p[2], 100);
    const int seen = f < DARK0 || f >= DARK1;
    CHECK_OK(elfm_link_step(l, f, T0 + 1000 * f, &d, seen, &err), &err);
    if (f == DARK1) young = elfm_link_last_track_id(l, 0);
    if (f == DARK1 + 8) {
      /* the young track's walk before its birth */
      elfm_detection fill[DARK1];
      int m = 0;
      for (int g = fill0; g < DARK1; g++) {
        double q[3];
        bead(g, q);
        fill[m] = link_test_det(q[0] + (g < far_before ? 30.0 : off_um), q[1], q[2], 100);
        fill[m].frame = g;
        fill[m].t_us = T0 + 1000 * g;
        fill[m].view_fit = 1;
        m++;
      }
      CHECK_OK(elfm_link_fill(l, young, fill, m, &err), &err);
    }
  }
  CHECK(young == 1); /* born on the bead seen again, not taken by the first */
  CHECK_OK(elfm_link_finish(l, &err), &err);
  *twins = elfm_link_n_twins(l);
  int k = 0;
  for (elfm_track *t; (t = elfm_link_pop_finished(l)) != NULL; k++) {
    for (size_t j = 1; j < t->n; j++) CHECK(t->pts[j].frame > t->pts[j - 1].frame);
    if (k < 2) {
      id[k] = t->id;
      first[k] = t->pts[0].frame;
      last[k] = t->pts[t->n - 1].frame;
      n[k] = t->n;
    }
    elfm_track_free(t);
  }
  elfm_link_free(l);
  return k;
}

int main(void)
{
  int64_t id[2], first[2], last[2], tw;
  size_t n[2];

  /* 1. Twins joined: one track, the older id, frames 0-49 its own, then
   * the young one's fills (50-59) and detections (60-119). */
  CHECK(run(2.0, 5, 40, 0, 0.2, id, first, last, n, &tw) == 1);
  CHECK(tw == 1);
  CHECK(id[0] == 0 && first[0] == 0 && last[0] == N_FRAMES - 1 && n[0] == N_FRAMES);

  /* 2. Off: the same scene gives two tracks, the first ending at 49. */
  CHECK(run(0.0, 5, 40, 0, 0.2, id, first, last, n, &tw) == 2);
  CHECK(tw == 0);
  CHECK(id[0] == 0 && last[0] == DARK0 - 1 && n[0] == DARK0);
  CHECK(id[1] == 1 && first[1] == 40 && last[1] == N_FRAMES - 1);

  /* 3. The young track's first points elsewhere (its walk 30 um off before
   * frame 40): it met the first track's bead, it was not born on it. */
  CHECK(run(2.0, 5, 20, 40, 0.2, id, first, last, n, &tw) == 2);
  CHECK(tw == 0);

  /* 4. Fewer matching points than twin_points: the overlap is frames
   * 40-49, 10 points, so 11 asked (of the first track's last 44) join
   * nothing; 10 join. */
  CHECK(run(2.0, 11, 40, 0, 0.2, id, first, last, n, &tw) == 2);
  CHECK(tw == 0);
  CHECK(run(2.0, 10, 40, 0, 0.2, id, first, last, n, &tw) == 1);
  CHECK(tw == 1);

  /* ... and fills 2.5 um beside the first track's points are not within
   * 2 um of them; at 1.9 um they are. */
  CHECK(run(2.0, 5, 40, 0, 2.5, id, first, last, n, &tw) == 2);
  CHECK(run(2.0, 5, 40, 0, 1.9, id, first, last, n, &tw) == 1);

  /* 5. Options out of range are refused at create. */
  {
    elfm_error err;
    elfm_link_options o;
    elfm_link_options_default(&o);
    o.twin_um = -1;
    CHECK(elfm_link_create(&o, &err) == NULL);
    o.twin_um = NAN;
    CHECK(elfm_link_create(&o, &err) == NULL);
    o.twin_um = 2;
    o.twin_points = 0;
    CHECK(elfm_link_create(&o, &err) == NULL);
  }
  return check_report();
}
