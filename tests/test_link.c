/* test_link.c — the streaming linker: identities through crossings, optimal
 * (not greedy) assignment, gap closing up to max_gap, births/ends, minimum
 * length, many objects through the k-d tree (bad input and lag correction:
 * test_link_input.c). */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "check.h"
#include "elfm_tracker.h"
#include "link_test_util.h"

static uint64_t rng = 88172645463325252ULL;
static double urand(void)
{
  rng ^= rng << 13; rng ^= rng >> 7; rng ^= rng << 17;
  return (double)(rng >> 11) / 9007199254740992.0;
}

static elfm_detection mk(double x, double y, double z) { return link_test_det(x, y, z, 1); }

/* Collect all finished tracks into a store (after finish). */
static void drain(elfm_linker *l, elfm_track_store *s)
{
  elfm_track *t;
  elfm_error err;
  while ((t = elfm_link_pop_finished(l))) elfm_track_store_add(s, t, &err);
}

int main(void)
{
  elfm_error err;
  elfm_error_clear(&err);
  elfm_link_options o;
  elfm_link_options_default(&o);
  const int64_t T0 = 1000000000000LL;  /* absolute times near 1e12 us */

  /* 1. Two objects crossing in an X at 0.5 um/ms each, 1 kHz, noise 0.1 um.
   * At the crossing frame they are closer than the gate; the constant
   * velocity prediction keeps their identities. */
  {
    elfm_linker *l = elfm_link_create(&o, &err);
    CHECK(l != NULL);
    elfm_detection d[2];
    for (int f = 0; f < 100; f++) {
      double t = f - 50;  /* ms */
      d[0] = mk(0.5 * t + 0.1 * (urand() - 0.5), 0.5 * t, 10);
      d[1] = mk(0.5 * t + 0.1 * (urand() - 0.5), -0.5 * t, 10);
      /* present them in alternating order so the order gives no hint */
      if (f % 2) { elfm_detection tmp = d[0]; d[0] = d[1]; d[1] = tmp; }
      CHECK_OK(elfm_link_step(l, f, T0 + f * 1000, d, 2, &err), &err);
    }
    CHECK_OK(elfm_link_finish(l, &err), &err);
    elfm_track_store s;
    elfm_track_store_init(&s);
    drain(l, &s);
    CHECK_EQ_INT(s.n, 2);
    for (size_t i = 0; i < s.n; i++) {
      const elfm_track *t = s.tracks[i];
      CHECK_EQ_INT(t->n, 100);
      /* one identity: y has one sign of slope all along */
      double sgn = t->pts[99].y_um - t->pts[0].y_um > 0 ? 1 : -1;
      int bad = 0;
      for (size_t k = 0; k < t->n; k++)
        bad += fabs(t->pts[k].y_um - sgn * 0.5 * ((double)k - 50)) > 1e-9;
      CHECK_EQ_INT(bad, 0);
      CHECK(t->pts[0].t_us == T0);
    }
    elfm_track_store_clear(&s);
    elfm_link_free(l);
  }

  /* 2. Optimal, not greedy: static tracks at x = 0 (A) and 1.5 (B); then
   * detections at 1.0 and 3.0. Greedy nearest-first takes B-1.0 (0.5) and
   * leaves A-3.0 (3.0): cost 0.25 + 9; the optimum is, B-3.0: 1 + 2.25. */
  {
    elfm_linker *l = elfm_link_create(&o, &err);
    elfm_detection d[2];
    int64_t ida = -1, idb = -1;
    for (int f = 0; f < 6; f++) {
      d[0] = mk(0, 0, 0);
      d[1] = mk(1.5, 0, 0);
      CHECK_OK(elfm_link_step(l, f, T0 + f * 1000, d, 2, &err), &err);
      if (f == 0) { ida = elfm_link_last_track_id(l, 0); idb = elfm_link_last_track_id(l, 1); }
    }
    CHECK(ida != idb && ida >= 0 && idb >= 0);
    d[0] = mk(3.0, 0, 0);
    d[1] = mk(1.0, 0, 0);
    CHECK_OK(elfm_link_step(l, 6, T0 + 6000, d, 2, &err), &err);
    CHECK_EQ_INT(elfm_link_last_track_id(l, 1), ida);
    CHECK_EQ_INT(elfm_link_last_track_id(l, 0), idb);
    CHECK_EQ_INT(elfm_link_n_live(l), 2);
    CHECK_EQ_INT(elfm_link_last_track_id(l, 5), -1);
    /* each live track by its id, read only: A's last point is the 1.0 */
    const elfm_track *ta = elfm_link_live_track(l, ida);
    CHECK(ta && ta->id == ida && ta->n == 7 && ta->pts[6].x_um == 1.0);
    CHECK(elfm_link_live_track(l, idb) && elfm_link_live_track(l, idb) != ta);
    CHECK(elfm_link_live_track(l, ida + idb + 1) == NULL && elfm_link_live_track(NULL, ida) == NULL);
    elfm_link_free(l);  /* frees live tracks (ASan checks) */
  }

  /* 2b. Established tracks first: track T has moved 1 um per frame along
   * x for 10 frames and expects its bead at (10, 0); a one-point track Y
   * was born at (10.6, -7) a frame before, its gate widened to 11 um for
   * its unknown speed. Detections A = (10.3, 0) (T's bead, 7 um from Y)
   * and B = (11, 5) (inside T's 6 um gate, 12 um from Y). "Most pairs
   * first" gives T -> B and Y -> A; with priority_points T takes A and Y
   * nothing (B starts a track). */
  for (int prio = 0; prio <= 1; prio++) {
    elfm_link_options op = o;
    op.priority_points = prio ? 8 : 0;
    elfm_linker *l = elfm_link_create(&op, &err);
    for (int f = 0; f < 10; f++) {
      elfm_detection d[2] = {mk(f, 0, 0), mk(10.6, -7, 0)};
      CHECK_OK(elfm_link_step(l, f, T0 + f * 1000, d, f == 9 ? 2 : 1, &err), &err);
    }
    CHECK_EQ_INT((int)elfm_link_last_track_id(l, 1), 1);  /* Y was born */
    elfm_detection d[2] = {mk(10.3, 0, 0), mk(11, 5, 0)};
    CHECK_OK(elfm_link_step(l, 10, T0 + 10000, d, 2, &err), &err);
    if (prio) {
      CHECK_MSG(elfm_link_last_track_id(l, 0) == 0, "priority: A went to track %lld",
                (long long)elfm_link_last_track_id(l, 0));
      CHECK_MSG(elfm_link_last_track_id(l, 1) == 2, "priority: B went to track %lld",
                (long long)elfm_link_last_track_id(l, 1));
    } else {  /* the case the option is for: the one-point track takes T's bead */
      CHECK_EQ_INT((int)elfm_link_last_track_id(l, 0), 1);
      CHECK_EQ_INT((int)elfm_link_last_track_id(l, 1), 0);
    }
    elfm_link_free(l);
  }

  /* 3. Gap closing: a bead moving at 0.05 um/ms goes dark for 50 frames
   * (joined) and, later, for 51 frames (a new track). Also a 2-point blip
   * far away is dropped (min_points 5), and finished tracks come out while
   * the stream runs. */
  {
    elfm_linker *l = elfm_link_create(&o, &err);
    int popped_early = 0;
    elfm_track_store s;
    elfm_track_store_init(&s);
    for (int f = 0; f < 300; f++) {
      int dark = (f >= 100 && f < 150) || (f >= 200 && f < 251);
      elfm_detection d[2];
      int n = 0;
      if (!dark) d[n++] = mk(0.05 * f, 3, -20);
      if (f == 10 || f == 11) d[n++] = mk(-40, -40, 0);
      CHECK_OK(elfm_link_step(l, f, T0 + f * 1000, d, n, &err), &err);
      elfm_track *t;
      while ((t = elfm_link_pop_finished(l))) {
        if (f < 299) popped_early++;
        elfm_track_store_add(&s, t, &err);
      }
    }
    CHECK_OK(elfm_link_finish(l, &err), &err);
    drain(l, &s);
    CHECK_EQ_INT(s.n, 2);
    CHECK_EQ_INT(popped_early, 1);  /* the first track ended at frame 251 */
    if (s.n == 2) {
      CHECK_EQ_INT(s.tracks[0]->n, 150);  /* frames 0-99 and 150-199 */
      CHECK_EQ_INT(s.tracks[0]->pts[0].frame, 0);
      CHECK_EQ_INT(s.tracks[0]->pts[149].frame, 199);
      CHECK_EQ_INT(s.tracks[1]->n, 49);   /* frames 251-299 */
    }
    CHECK(elfm_link_n_started(l) == 3);   /* bead, blip, bead again */
    elfm_track_store_clear(&s);
    elfm_link_free(l);
  }

  /* 4. Blinking while moving fast: 1 um/ms, dark 40 frames: the velocity
   * prediction carries it 40 um, far outside a plain gate. */
  {
    elfm_linker *l = elfm_link_create(&o, &err);
    for (int f = 0; f < 120; f++) {
      if (f >= 40 && f < 80) { CHECK_OK(elfm_link_step(l, f, T0 + f * 1000, NULL, 0, &err), &err); continue; }
      elfm_detection d = mk(-50 + 1.0 * f + 0.1 * (urand() - 0.5), 0.2 * f, 0);
      CHECK_OK(elfm_link_step(l, f, T0 + f * 1000, &d, 1, &err), &err);
    }
    CHECK_OK(elfm_link_finish(l, &err), &err);
    elfm_track *t = elfm_link_pop_finished(l);
    CHECK(t && t->n == 80);
    CHECK(elfm_link_pop_finished(l) == NULL);
    elfm_track_free(t);
    elfm_link_free(l);
  }

  /* 4b. Static beads blinking (rest_speed_um_per_ms): three beads at rest,
   * seen in 1 ms pulses at blink seed 2's frames, the first pulse over two
   * frames with localisation errors of up to 0.6 um laterally and 1.5 um
   * in z, so their two-point velocity is ~1-3 um/ms of noise that carries
   * them 30-80 um over the 26 dark frames to the next pulse. Looked for
   * where they were as well, each is one track from frame 7 (7 points);
   * without that (0) the first pulse's points are lost with their 2-point
   * tracks; and while most established tracks move (a fast bead seen
   * every frame) the rest hypothesis is off, as it is in flow.
   * Then blink seed 8's pulses, each over two frames with such errors
   * (-1, +1 in each pair, halved in the later pairs), so that the short
   * fit of a track's 4-8 points, tight pairs tens of frames apart, has a
   * slope and curvature of noise: the straight-line fit tells the beads
   * are at rest, and each is one track of 8 points. */
  for (int sched = 0; sched < 2; sched++) {
    static const int pulses[2][8] = {{7, 8, 34, 75, 93, 100, 127, -1},
                                     {38, 39, 64, 65, 110, 111, 147, 181}};
    static const double errs[2][8] = {{1, -1, 0, 0, 0, 0, 0, 0},
                                      {-1, 1, 0.5, -0.5, -0.5, 0.5, 0, 0}};
    const int *pulse = pulses[sched];
    const int np = sched ? 8 : 7, last = pulse[np - 1];
    static const double bead[3][3] = {{0, 0, 0}, {30, -20, 40}, {-25, 35, -60}};
    /* 0 default, 1 off, 2 default + a fast bead, 3 default by brute force */
    for (int mode = 0; mode < 4; mode++) {
      elfm_link_options ob = o;
      if (mode == 1) ob.rest_speed_um_per_ms = 0;
      if (mode == 3) ob.brute_force = 1;
      elfm_linker *l = elfm_link_create(&ob, &err);
      int k = 0;
      for (int f = 0; f < 190; f++) {
        elfm_detection d[4];
        int n = 0;
        if (k < np && pulse[k] == f) {
          const double e = errs[sched][k];
          for (int b = 0; b < 3; b++)
            d[n++] = mk(bead[b][0] + 0.6 * e, bead[b][1] - 0.5 * e, bead[b][2] + 1.5 * e);
          k++;
        }
        if (mode == 2) d[n++] = mk(-60 + 3.0 * (f % 40), 60, 0); /* fast, restarts every 40 */
        CHECK_OK(elfm_link_step(l, f, T0 + f * 1000, d, n, &err), &err);
      }
      CHECK_OK(elfm_link_finish(l, &err), &err);
      elfm_track_store st;
      elfm_track_store_init(&st);
      drain(l, &st);
      /* whole: a track of all the pulses of one bead (every point within 2
       * um of its first); without the rest hypothesis bead 0's noise
       * velocity carries it onto bead 2 (a track from frame 7 on the wrong
       * bead) */
      int whole = 0;
      for (size_t i = 0; i < st.n; i++) {
        const elfm_track *t = st.tracks[i];
        int same = (int)t->n == np && t->pts[0].frame == pulse[0] && t->pts[np - 1].frame == last;
        for (size_t j = 1; same && j < t->n; j++)
          same = fabs(t->pts[j].x_um - t->pts[0].x_um) < 2 && fabs(t->pts[j].y_um - t->pts[0].y_um) < 2;
        whole += same;
      }
      CHECK_EQ_INT(whole, mode == 0 || mode == 3 ? 3 : 0);
      elfm_track_store_clear(&st);
      elfm_link_free(l);
    }
  }

  /* 5. 2,000 objects drifting with individual velocities (up to 0.3 um/ms)
   * in a 200 x 200 x 200 um box, noise 0.1 um: every track keeps its object. */
  {
    enum { N = 2000, F = 40 };
    double *p0 = malloc(sizeof(double) * 3 * N), *v = malloc(sizeof(double) * 3 * N);
    elfm_detection *d = malloc(sizeof *d * N);
    int *perm = malloc(sizeof(int) * N);
    double *tag = malloc(sizeof(double) * N);
    /* Start positions at least 3 um apart (anisotropic): at birth a track
     * has no velocity yet, and two objects closer than their first step
     * are genuinely ambiguous. Later they cross freely. */
    for (int i = 0; i < N; i++) {
      for (int tries = 0;; tries++) {
        for (int a = 0; a < 3; a++) p0[3 * i + a] = 200 * urand() - 100;
        int ok = 1;
        for (int k = 0; k < i && ok; k++) {
          double dx = p0[3 * i] - p0[3 * k], dy = p0[3 * i + 1] - p0[3 * k + 1],
                 dz = (p0[3 * i + 2] - p0[3 * k + 2]) / 4;
          ok = dx * dx + dy * dy + dz * dz >= 9;
        }
        if (ok || tries > 100) break;
      }
      for (int a = 0; a < 3; a++) v[3 * i + a] = 0.6 * urand() - 0.3;
      perm[i] = i;
    }
    elfm_linker *l = elfm_link_create(&o, &err);
    for (int f = 0; f < F; f++) {
      for (int i = N - 1; i > 0; i--) {  /* shuffle the order every frame */
        int j = (int)(urand() * (i + 1));
        int t = perm[i]; perm[i] = perm[j]; perm[j] = t;
      }
      for (int k = 0; k < N; k++) {
        int i = perm[k];
        d[k] = mk(p0[3 * i] + v[3 * i] * f + 0.1 * (urand() - 0.5),
                  p0[3 * i + 1] + v[3 * i + 1] * f + 0.1 * (urand() - 0.5),
                  p0[3 * i + 2] + v[3 * i + 2] * f + 0.4 * (urand() - 0.5));
        d[k].intensity = i;  /* the truth id rides along */
      }
      CHECK_OK(elfm_link_step(l, f, T0 + f * 1000, d, N, &err), &err);
    }
    CHECK_OK(elfm_link_finish(l, &err), &err);
    elfm_track_store s;
    elfm_track_store_init(&s);
    drain(l, &s);
    size_t mixed = 0, full = 0;
    for (size_t i = 0; i < s.n; i++) {
      const elfm_track *t = s.tracks[i];
      for (size_t k = 1; k < t->n; k++) {
        if (t->pts[k].intensity != t->pts[k - 1].intensity && getenv("LINK_DEBUG"))
          fprintf(stderr, "switch at frame %lld\n", (long long)t->pts[k].frame);
        mixed += t->pts[k].intensity != t->pts[0].intensity;
      }
      full += t->n == F;
    }
    (void)tag;
    CHECK_EQ_INT(s.n, N);
    CHECK_EQ_INT(full, N);
    CHECK_EQ_INT(mixed, 0);
    elfm_track_store_clear(&s);
    elfm_link_free(l);
    /* brute-force candidates give the same tracks as the k-d tree */
    {
      elfm_link_options ob = o;
      ob.brute_force = 1;
      elfm_linker *lb = elfm_link_create(&ob, &err);
      for (int f = 0; f < 10; f++) {
        for (int i = 0; i < N; i++) {
          d[i] = mk(p0[3 * i] + v[3 * i] * f, p0[3 * i + 1] + v[3 * i + 1] * f, p0[3 * i + 2] + v[3 * i + 2] * f);
          d[i].intensity = i;
        }
        CHECK_OK(elfm_link_step(lb, f, T0 + f * 1000, d, N, &err), &err);
      }
      CHECK_OK(elfm_link_finish(lb, &err), &err);
      elfm_track_store_init(&s);
      drain(lb, &s);
      size_t bad = 0;
      for (size_t i = 0; i < s.n; i++)
        for (size_t k = 1; k < s.tracks[i]->n; k++) bad += s.tracks[i]->pts[k].intensity != s.tracks[i]->pts[0].intensity;
      CHECK_EQ_INT(s.n, N);
      CHECK_EQ_INT(bad, 0);
      elfm_track_store_clear(&s);
      elfm_link_free(lb);
    }
    free(p0); free(v); free(d); free(perm); free(tag);
  }

  /* 5b. Rescue: a bead moving at 3 um/ms along x is dark for 10 frames and
   * comes back 15 um to the side of its line (gate after 10 missed frames:
   * 6 + 0.5 + 6 x 0.3 x 3 = 11.9 um; rescue gate 2.5 x that). Without the
   * rescue round it comes back as a second track. */
  for (int rescue = 0; rescue < 2; rescue++) {
    const int n = link_test_rescue_return(&o, rescue ? 2.5 : 0, NAN);
    CHECK_MSG(n == (rescue ? 1 : 2), "rescue %d: %d tracks", rescue, n);
  }

  /* 5b'. Turn model: a bead circling at 3 um/ms (radius 30 um, 5.7 degrees
   * per ms) is dark for 10 frames; a straight extrapolation leaves it ~9 um
   * off, outside the gate once the rescue round is off; the constant-rate
   * turn keeps it on the circle: one track of all 50 points. */
  {
    elfm_link_options orr = o;
    orr.rescue_gate_factor = 0;
    elfm_linker *l = elfm_link_create(&orr, &err);
    for (int f = 0; f < 60; f++) {
      if (f >= 30 && f < 40) { CHECK_OK(elfm_link_step(l, f, T0 + f * 1000, NULL, 0, &err), &err); continue; }
      elfm_detection d = mk(30 * cos(0.1 * f), 30 * sin(0.1 * f), 5);
      CHECK_OK(elfm_link_step(l, f, T0 + f * 1000, &d, 1, &err), &err);
    }
    CHECK_OK(elfm_link_finish(l, &err), &err);
    int n = 0;
    elfm_track *t;
    while ((t = elfm_link_pop_finished(l))) {
      n++;
      CHECK_EQ_INT((int)t->n, 50);
      elfm_track_free(t);
    }
    CHECK_MSG(n == 1, "circling bead after a 10-frame gap: %d tracks", n);
    elfm_link_free(l);
  }

  /* 5c. Rescue without a dark frame: a bead moving at 3 um/ms along x
   * jumps 9 um sideways in one frame (a localisation jump, a sudden turn);
   * the detection is outside the 6 um gate but inside 2.5 x 6 um. The
   * rescue round also takes established tracks that just missed their
   * first frame, so this stays one track (before: a second one was born). */
  {
    elfm_linker *l = elfm_link_create(&o, &err);
    for (int f = 0; f < 40; f++) {
      elfm_detection d = mk(3.0 * f, f >= 20 ? 9.0 : 0.0, 5);
      CHECK_OK(elfm_link_step(l, f, T0 + f * 1000, &d, 1, &err), &err);
    }
    CHECK_OK(elfm_link_finish(l, &err), &err);
    int n = 0;
    elfm_track *t;
    while ((t = elfm_link_pop_finished(l))) {
      n++;
      CHECK_EQ_INT((int)t->n, 40);
      elfm_track_free(t);
    }
    CHECK_MSG(n == 1, "jump without a gap: %d tracks", n);
    elfm_link_free(l);
  }

  /* 5g. Stitching: bead A circles at 3.5 um/ms (radius 20 um) and is dark
   * for 25 frames, during which it runs half an orbit ahead of any
   * extrapolation (a flow bead speeding up unseen): it comes back 40 um from
   * the prediction, beyond the rescue gate, but onto its own earlier path.
   * Bead B circles 60 um away all along. Without stitching A comes back as
   * a new track; with it, one track of A's 75 points and B untouched. Then
   * a bead on a straight line at 2.5 um/ms is lost, and a second bead
   * starts on its path 75 um behind 5 ms later (out of reach at 1.5 x 2.5
   * um/ms): never stitched. From the frame the young track is stitched
   * (its 5th point, frame 69) on, A's detection is reported as joining the
   * track that holds it at the end (the id its motion bias is taken from). */
  for (int stitch = 0; stitch < 2; stitch++) {
    elfm_link_options os = o;
    os.stitch_points = stitch ? 5 : 0;
    elfm_linker *l = elfm_link_create(&os, &err);
    CHECK(l != NULL);
    const double w = 3.5 / 20;  /* rad/ms */
    int64_t id_a[100 - 69];
    for (int f = 0; f < 100; f++) {
      elfm_detection d[2];
      int n = 0;
      double pa = w * f + (f >= 65 ? M_PI : 0), pb = -w * f;
      if (f < 40 || f >= 65) d[n++] = mk(20 * cos(pa) + 0.1 * (urand() - 0.5), 20 * sin(pa), 5);
      d[n++] = mk(60 + 20 * cos(pb), 20 * sin(pb) + 0.1 * (urand() - 0.5), 5);
      CHECK_OK(elfm_link_step(l, f, T0 + f * 1000, d, n, &err), &err);
      if (f >= 69) id_a[f - 69] = elfm_link_last_track_id(l, 0);
    }
    CHECK_OK(elfm_link_finish(l, &err), &err);
    int n = 0, n75 = 0, ids_ok = 0;
    elfm_track *t;
    while ((t = elfm_link_pop_finished(l))) {
      n++;
      if (t->pts[0].x_um < 30 && t->pts[t->n - 1].frame == 99)
        for (int f = 69; f < 100; f++) ids_ok += id_a[f - 69] == t->id;
      if (t->n == 75 && t->pts[0].x_um < 30) n75++;
      if (t->pts[0].x_um > 30) CHECK_EQ_INT((int)t->n, 100);  /* B */
      elfm_track_free(t);
    }
    CHECK_MSG(n == (stitch ? 2 : 3) && n75 == stitch, "stitch %d: %d tracks, %d of A's 75", stitch,
              n, n75);
    CHECK_MSG(ids_ok == 100 - 69, "stitch %d: A's detection named its track in %d of frames 69-99",
              stitch, ids_ok);
    elfm_link_free(l);
    /* out of reach */
    l = elfm_link_create(&os, &err);
    for (int f = 0; f < 60; f++) {
      elfm_detection d;
      if (f < 30) d = mk(0, 2.5 * f, 5);
      else if (f < 35) { CHECK_OK(elfm_link_step(l, f, T0 + f * 1000, NULL, 0, &err), &err); continue; }
      else d = mk(0, 2.5 * (f - 35), 5);
      CHECK_OK(elfm_link_step(l, f, T0 + f * 1000, &d, 1, &err), &err);
    }
    CHECK_OK(elfm_link_finish(l, &err), &err);
    n = 0;
    while ((t = elfm_link_pop_finished(l))) { n++; elfm_track_free(t); }
    CHECK_MSG(n == 2, "stitch %d, trailing bead out of reach: %d tracks", stitch, n);
    elfm_link_free(l);
  }

  /* 5g''. A bead re-entering on the line another has left (a stage phantom):
   * bead A runs straight along +y at 2.5 um/ms for 20 frames and leaves;
   * 30 frames later bead B enters on the same line 42.5 um behind A's end
   * and runs the same way. B lies on A's path and is within reach (8 +
   * 1.5 x 2.5 x 31 um), so the path test alone stitches them, the track
   * jumping back; A ran straight, so B cannot be A coming back
   * (stitch_straight_frac): two tracks. A circling bead (5g) is still
   * stitched at the default. */
  for (int straight = 0; straight < 2; straight++) {
    elfm_link_options os = o;
    os.stitch_points = 5;
    os.stitch_straight_frac = straight ? 0.1 : 0;
    elfm_linker *l = elfm_link_create(&os, &err);
    CHECK(l != NULL);
    for (int f = 0; f < 60; f++) {
      elfm_detection d;
      int n = 0;
      if (f < 20) d = mk(0.1 * (urand() - 0.5), 2.5 * f, 5), n = 1;
      else if (f >= 50) d = mk(0.1 * (urand() - 0.5), 5 + 2.5 * (f - 50), 5), n = 1;
      CHECK_OK(elfm_link_step(l, f, T0 + f * 1000, n ? &d : NULL, n, &err), &err);
    }
    CHECK_OK(elfm_link_finish(l, &err), &err);
    int n = 0;
    elfm_track *t;
    while ((t = elfm_link_pop_finished(l))) {
      n++;
      for (size_t k = 1; k < t->n; k++)  /* never a jump back */
        if (straight) CHECK(t->pts[k].y_um > t->pts[k - 1].y_um - 1);
      elfm_track_free(t);
    }
    CHECK_MSG(n == (straight ? 2 : 1), "straight rule %d: %d tracks", straight, n);
    elfm_link_free(l);
  }
  {
    elfm_link_options bad = o;
    bad.stitch_straight_frac = -0.1;
    CHECK(elfm_link_create(&bad, &err) == NULL);
    bad.stitch_straight_frac = NAN;
    CHECK(elfm_link_create(&bad, &err) == NULL);
  }

  /* 5g'. Stitching a twin: a bead moves along +x at 3 um/ms and turns to +y
   * at frame 30, where a second detection of it (2 um off, towards where it
   * turns) starts a track that then takes the bead (its one-point gate is
   * the wider). The first track goes dark in the frame the twin was born;
   * stitching joins them (gap -1, the overlap frame keeping the first
   * track's point): one track of 60 points; without stitching, 31 + 30. */
  for (int stitch = 0; stitch < 2; stitch++) {
    elfm_link_options os = o;
    os.stitch_points = stitch ? 5 : 0;
    elfm_linker *l = elfm_link_create(&os, &err);
    CHECK(l != NULL);
    for (int f = 0; f < 60; f++) {
      elfm_detection d[2];
      int n = 0;
      d[n++] = f <= 30 ? mk(3.0 * f, 0, 5) : mk(90, 3.0 * (f - 30), 5);
      if (f == 30) d[n++] = mk(90, 2, 5);
      CHECK_OK(elfm_link_step(l, f, T0 + f * 1000, d, n, &err), &err);
    }
    CHECK_OK(elfm_link_finish(l, &err), &err);
    int n = 0;
    size_t first_n = 0;
    elfm_track *t;
    while ((t = elfm_link_pop_finished(l))) {
      if (n++ == 0) first_n = t->n;
      for (size_t k = 1; k < t->n; k++) CHECK(t->pts[k].frame > t->pts[k - 1].frame);
      if (stitch && t->n == 60) CHECK(t->pts[30].x_um == 90 && t->pts[30].y_um == 0);
      elfm_track_free(t);
    }
    CHECK_MSG(stitch ? n == 1 && first_n == 60 : n == 2 && first_n == 31,
              "twin, stitch %d: %d tracks, the first of %zu points", stitch, n, first_n);
    elfm_link_free(l);
  }

  /* 5h. Swap review: P moves along +x at 3 um/ms, Q at 20 degrees to it at
   * the same speed; they meet at frame 30, and while closer than 5 um the
   * detector sees one detection between them (frames 29-31). The linker
   * without the review lets P's track coast and close its gap on Q: the
   * track that started on P ends on Q. With it the junction is revisited 6
   * frames later and the tails are exchanged: each track ends on its own
   * object. */
  for (int review = 0; review < 2; review++) {
    elfm_link_options ow = o;
    ow.swap_points = review ? 6 : 0;
    elfm_linker *l = elfm_link_create(&ow, &err);
    CHECK(l != NULL);
    const double th = 20 * M_PI / 180;
    for (int f = 0; f < 60; f++) {
      double t = f - 30, px = 3 * t, py = 0, qx = 3 * t * cos(th), qy = 3 * t * sin(th);
      elfm_detection d[2];
      int n = 0;
      if (hypot(px - qx, py - qy) < 5) d[n++] = mk(0.5 * (px + qx), 0.5 * (py + qy), 5);
      else {
        d[n++] = mk(px, py, 5);
        d[n++] = mk(qx, qy, 5);
      }
      CHECK_OK(elfm_link_step(l, f, T0 + f * 1000, d, n, &err), &err);
    }
    CHECK_OK(elfm_link_finish(l, &err), &err);
    int n = 0, own = 0;
    elfm_track *t;
    while ((t = elfm_link_pop_finished(l))) {
      n++;
      /* started on P (y = 0) or on Q (y < 0): does it end on the same one? */
      int start_p = fabs(t->pts[0].y_um) < 1, end_p = fabs(t->pts[t->n - 1].y_um) < 1;
      own += start_p == end_p;
      elfm_track_free(t);
    }
    CHECK_MSG(n == 2 && own == (review ? 2 : 0), "swap review %d: %d tracks, %d on their own object",
              review, n, own);
    elfm_link_free(l);
  }

  /* 5i. Encounter review: P and Q as in 5h, but while closer than R um the
   * detector finds both at Q (two detections 0.1 um apart, as a view fit
   * started from two predictions finds one bead twice). No track coasts,
   * so the swap review (5h) has nothing to revisit; both tracks run on
   * Q's line for those frames and, when the objects part, share them out
   * as their bent fits say. With the encounter review each track's head
   * (before the encounter) is joined to the tail it fits. The test runs
   * several geometries and asks that the review ends with every track on
   * its own object where, without it, some track ended on the other. */
  {
    int swapped_off = 0, own_on = 0, cases = 0;
    for (int gi = 0; gi < 6; gi++) {
      const double th = (15 + 10 * gi) * M_PI / 180, R = 3 + (gi % 3);
      for (int enc = 0; enc < 2; enc++) {
        elfm_link_options ow = o;
        ow.swap_points = 6;
        ow.encounter_um = enc ? 5 : 0;
        elfm_linker *l = elfm_link_create(&ow, &err);
        CHECK(l != NULL);
        for (int f = 0; f < 60; f++) {
          double t = f - 30, px = 3 * t, py = 0, qx = 3 * t * cos(th), qy = -3 * t * sin(th);
          elfm_detection d[2];
          if (hypot(px - qx, py - qy) < R) {
            d[0] = mk(qx, qy, 5);
            d[1] = mk(qx + 0.1, qy, 5);
          } else {
            d[0] = mk(px, py, 5);
            d[1] = mk(qx, qy, 5);
          }
          CHECK_OK(elfm_link_step(l, f, T0 + f * 1000, d, 2, &err), &err);
        }
        CHECK_OK(elfm_link_finish(l, &err), &err);
        int n = 0, own = 0;
        elfm_track *t;
        while ((t = elfm_link_pop_finished(l))) {
          n++;
          int start_p = fabs(t->pts[0].y_um) < 0.5, end_p = fabs(t->pts[t->n - 1].y_um) < 0.5;
          own += start_p == end_p;
          elfm_track_free(t);
        }
        if (enc) own_on += n == 2 && own == 2;
        else swapped_off += own < n;
        elfm_link_free(l);
      }
      cases++;
    }
    fprintf(stderr, "encounter review: %d of %d geometries swapped without it, %d of %d right with it\n",
            swapped_off, cases, own_on, cases);
    CHECK_MSG(swapped_off >= 3 && own_on == cases, "encounter review: %d of %d swapped without, %d of %d right with",
              swapped_off, cases, own_on, cases);
  }

  /* 5d. Hysteresis: a weak detection continues a track but never starts
   * one. A bead seen strong for 10 frames, then weak for 20: one track of
   * 30 points. A weak-only object: no track, id -3. */
  {
    elfm_linker *l = elfm_link_create(&o, &err);
    for (int f = 0; f < 30; f++) {
      elfm_detection d[2];
      d[0] = mk(1.0 * f, 0, 0);
      d[0].weak = f >= 10;
      d[1] = mk(-40, 30, 0);
      d[1].weak = 1;
      CHECK_OK(elfm_link_step(l, f, T0 + f * 1000, d, 2, &err), &err);
      CHECK(elfm_link_last_track_id(l, 0) >= 0);
      CHECK(elfm_link_last_track_id(l, 1) == -3);
    }
    CHECK_OK(elfm_link_finish(l, &err), &err);
    int n = 0;
    elfm_track *t;
    while ((t = elfm_link_pop_finished(l))) {
      n++;
      CHECK_EQ_INT((int)t->n, 30);
      elfm_track_free(t);
    }
    CHECK_EQ_INT(n, 1);
    elfm_link_free(l);
  }

  /* 5e. Weak gate: a weak detection joins a track only within weak_gate_um
   * of its prediction, in the main round (4.5 um off, inside the 6 um gate)
   * and in the rescue round (9 um off, inside 2.5 x 6 um); a strong
   * detection at the same place still joins, and without the weak gate the
   * weak one does too. */
  {
    const double off_um[2] = {4.5, 9.0};
    for (int c = 0; c < 2; c++)
      for (int mode = 0; mode < 3; mode++) {  /* 0 weak+gate, 1 strong+gate, 2 weak no gate */
        elfm_link_options ow = o;
        ow.weak_gate_um = mode == 2 ? 0 : 3;
        elfm_linker *l = elfm_link_create(&ow, &err);
        CHECK(l != NULL);
        if (!l) continue;
        for (int f = 0; f < 10; f++) {
          elfm_detection d = mk(1.0 * f, 0, 0);
          CHECK_OK(elfm_link_step(l, f, T0 + f * 1000, &d, 1, &err), &err);
        }
        int64_t id0 = elfm_link_last_track_id(l, 0);
        elfm_detection d = mk(10.0, off_um[c], 0);
        d.weak = mode != 1;
        CHECK_OK(elfm_link_step(l, 10, T0 + 10 * 1000, &d, 1, &err), &err);
        int64_t id = elfm_link_last_track_id(l, 0);
        if (mode == 0) CHECK_MSG(id == -3, "weak %.1f um off joined track %lld", off_um[c], (long long)id);
        else CHECK_MSG(id == id0, "mode %d, %.1f um off: id %lld, want %lld", mode, off_um[c],
                       (long long)id, (long long)id0);
        /* after the miss, a weak detection inside the weak gate joins */
        if (mode != 0) {
          elfm_link_free(l);
          continue;
        }
        elfm_detection d2 = mk(11.0, 0.5, 0);
        d2.weak = 1;
        CHECK_OK(elfm_link_step(l, 11, T0 + 11 * 1000, &d2, 1, &err), &err);
        CHECK(elfm_link_last_track_id(l, 0) == id0);
        elfm_link_free(l);
      }
    elfm_link_options bad = o;
    bad.weak_gate_um = -1;
    CHECK(elfm_link_create(&bad, &err) == NULL);
    bad.weak_gate_um = NAN;
    CHECK(elfm_link_create(&bad, &err) == NULL);
  }

  /* 5f. Predictions for the guided search: a track moving 1 um per frame
   * along x is expected at x = 10 in frame 10 (and 12 after two misses);
   * tracks shorter than min_points are left out; nothing changes. With
   * the intensities: the mean of the last 3 points' (7, 8, 9 -> 8). */
  {
    elfm_linker *l = elfm_link_create(&o, &err);
    for (int f = 0; f < 10; f++) {
      elfm_detection d = mk(1.0 * f, 2.0, -3.0);
      d.intensity = f;
      CHECK_OK(elfm_link_step(l, f, T0 + f * 1000, &d, 1, &err), &err);
    }
    double xyz[6], inten[2] = {-1, -1};
    int np = -1;
    CHECK_OK(elfm_link_predict(l, 10, T0 + 10 * 1000, 3, xyz, inten, 2, &np, &err), &err);
    CHECK_EQ_INT(np, 1);
    CHECK_NEAR(inten[0], 8.0, 1e-12);
    CHECK_NEAR(inten[1], -1.0, 0);
    CHECK_NEAR(xyz[0], 10.0, 1e-6);
    CHECK_NEAR(xyz[1], 2.0, 1e-6);
    CHECK_NEAR(xyz[2], -3.0, 1e-6);
    CHECK_OK(elfm_link_predict(l, 12, T0 + 12 * 1000, 3, xyz, NULL, 2, &np, &err), &err);
    CHECK_EQ_INT(np, 1);
    CHECK_NEAR(xyz[0], 12.0, 1e-6);
    CHECK_OK(elfm_link_predict(l, 10, T0 + 10 * 1000, 11, xyz, NULL, 2, &np, &err), &err);
    CHECK_EQ_INT(np, 0);
    CHECK_EQ_INT(elfm_link_predict(l, 10, T0 + 10 * 1000, 3, NULL, NULL, 2, &np, &err), ELFM_ERR_INVALID);
    /* the step uses the same prediction: a weak detection at it joins */
    elfm_detection d = mk(10.0, 2.0, -3.0);
    d.weak = 1;
    CHECK_OK(elfm_link_step(l, 10, T0 + 10 * 1000, &d, 1, &err), &err);
    CHECK(elfm_link_last_track_id(l, 0) >= 0);
    elfm_link_free(l);
  }

  /* 5g. The short fit's path (short_path_um): a fast bead on a tight
   * circle (radius 10 um, 6 um per frame: 0.6 rad) is predicted from its
   * last 8 points (4.2 rad of the circle) 12.1 um off, from the last 4
   * (the last 20 um of path) 3.5 um off; on a slow line the 8 points span 7 um and
   * both predict the same. A negative or NaN path is an error. */
  {
    double err_pred[2], line_pred[2];
    for (int c = 0; c < 2; c++) {
      elfm_link_options oc = o;
      oc.short_path_um = c ? 20 : 0;
      elfm_linker *l = elfm_link_create(&oc, &err);
      CHECK(l != NULL);
      for (int f = 0; f < 12 && l; f++) {
        elfm_detection d = mk(10 * cos(0.6 * f), 10 * sin(0.6 * f), 0.5 * f);
        CHECK_OK(elfm_link_step(l, f, T0 + f * 1000, &d, 1, &err), &err);
      }
      double xyz[3] = {0, 0, 0};
      int np = 0;
      if (l) CHECK_OK(elfm_link_predict(l, 12, T0 + 12 * 1000, 3, xyz, NULL, 1, &np, &err), &err);
      CHECK_EQ_INT(np, 1);
      err_pred[c] = hypot(xyz[0] - 10 * cos(7.2), xyz[1] - 10 * sin(7.2));
      elfm_link_free(l);
      l = elfm_link_create(&oc, &err);
      for (int f = 0; f < 12 && l; f++) {
        elfm_detection d = mk(1.0 * f, 0.3 * f, 0);
        CHECK_OK(elfm_link_step(l, f, T0 + f * 1000, &d, 1, &err), &err);
      }
      if (l) CHECK_OK(elfm_link_predict(l, 12, T0 + 12 * 1000, 3, xyz, NULL, 1, &np, &err), &err);
      line_pred[c] = xyz[0];
      elfm_link_free(l);
    }
    CHECK_MSG(err_pred[1] < 4 && err_pred[1] < 0.5 * err_pred[0],
              "circle, 6 um per frame: prediction off by %g um from 8 points, %g from 20 um of path",
              err_pred[0], err_pred[1]);
    CHECK_NEAR(line_pred[1], line_pred[0], 1e-9);
    CHECK_NEAR(line_pred[0], 12.0, 1e-6);
    elfm_link_options ob = o;
    ob.short_path_um = -1;
    CHECK(elfm_link_create(&ob, &err) == NULL && err.code == ELFM_ERR_INVALID);
    ob.short_path_um = NAN;
    CHECK(elfm_link_create(&ob, &err) == NULL);
  }

  /* claims: two tracks converging on a point, one detection there and one
   * far away. The shared one lies within both gates (claims 2), the far
   * one within none (0); on the frames before, each track's own detection
   * lies in its gate only (1). */
  {
    elfm_linker *l = elfm_link_create(&o, &err);
    CHECK(l != NULL);
    elfm_detection d[2];
    int ones = 0;
    for (int f = 0; f < 9 && l; f++) { /* 8 um apart or more: each in its own gate */
      d[0] = mk(-20 + 2.0 * f, 0, 0);
      d[1] = mk(20 - 2.0 * f, 0, 0);
      d[0].claims = d[1].claims = 77; /* set by the step */
      CHECK_OK(elfm_link_step(l, f, T0 + f * 1000, d, 2, &err), &err);
      if (f >= 1) ones += d[0].claims == 1 && d[1].claims == 1;
      else CHECK(d[0].claims == 0 && d[1].claims == 0); /* no track yet */
    }
    CHECK_EQ_INT(ones, 8);
    if (l) {
      d[0] = mk(0, 0, 0);    /* 2 um from where each track is expected next */
      d[1] = mk(0, 60, 0);   /* far from both */
      CHECK_OK(elfm_link_step(l, 9, T0 + 9000, d, 2, &err), &err);
      CHECK_EQ_INT(d[0].claims, 2);
      CHECK_EQ_INT(d[1].claims, 0);
    }
    elfm_link_free(l);
  }

  return check_report();
}
