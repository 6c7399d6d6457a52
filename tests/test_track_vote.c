/* test_track_vote.c — the frames' shift that finds a stage without tracks
 * (cli/cmd_track_vote.c, compiled in here: the one part of `track`'s
 * internals with a unit test of its own). Frames 2 ms apart (500 Hz), each
 * with 12 bright peaks moved by one stage velocity (5 um/ms: 10 um a frame)
 * and, read first, 10 faint ones placed at random:
 *  - the 16 brightest are kept, so the bright ones' shift carries 12 of
 *    them: a stage at 5 um/ms, its velocity to 1e-9 (keeping the first 16
 *    read, 10 faint and 6 bright, no pair agreed; the shift not divided by
 *    the 2 ms, 10 um/ms);
 *  - weak peaks (the guided fits) take no part: the same frames read as
 *    weak find nothing;
 *  - bright peaks each at its own velocity (a flow) are no stage;
 *  - at the frames' end, 10 pairs are judged, 9 are too few;
 *  - without init the judgement is "not a stage". */
#include <math.h>
#include <string.h>

#include "check.h"
#include "cmd_track.h"

static unsigned rng_state = 12345u;
static double urand(void)
{
  rng_state = rng_state * 1103515245u + 12345u;
  return (double)((rng_state >> 8) % 100001) / 100000.0;
}

/* Feed `frames` frames; bright peak i at base_i + v_i t (v_i the stage's,
 * or its own when `flow`), the faint ones at random, read first. */
static void feed(track_votes *v, int frames, int flow, int weak)
{
  for (int f = 0; f < frames; f++) {
    const double t_ms = 2.0 * f;
    for (int i = 0; i < 10; i++) {
      elfm_detection d;
      memset(&d, 0, sizeof d);
      d.x_um = 200 * urand() - 100;
      d.y_um = 200 * urand() - 100;
      d.z_um = 100 * urand() - 50;
      d.intensity = 50 + urand();
      d.weak = weak;
      track_votes_point(v, &d);
    }
    for (int i = 0; i < 12; i++) {
      elfm_detection d;
      memset(&d, 0, sizeof d);
      const double vx = flow ? 4 * cos(0.5 * i) : 4, vy = flow ? 4 * sin(0.5 * i) : -3;
      d.x_um = -60 + 11 * (i % 4) + vx * t_ms;
      d.y_um = -40 + 13 * (i / 4) + vy * t_ms;
      d.z_um = -20 + 3 * i;
      d.intensity = 200 + i;
      d.weak = weak;
      track_votes_point(v, &d);
    }
    track_votes_end_frame(v, 1000000 + 2000 * (int64_t)f);
  }
}

int main(void)
{
  double speed = NAN, abs_v = NAN, dev = NAN;
  track_votes v;
  /* a stage: judged once 16 pairs are in */
  CHECK(track_votes_init(&v, 1.5));
  feed(&v, 10, 0, 0);
  CHECK_EQ_INT(track_votes_judge(&v, 0, &speed, &abs_v, &dev), -1); /* 9 pairs: wait */
  feed(&v, 10, 0, 0);
  CHECK_EQ_INT(v.n_pairs, TRACK_VOTE_PAIRS);
  CHECK_MSG(v.n_agree == TRACK_VOTE_PAIRS, "%d of %d pairs agree", v.n_agree, v.n_pairs);
  CHECK_EQ_INT(track_votes_judge(&v, 0, &speed, &abs_v, &dev), 1);
  CHECK_NEAR(speed, 5.0, 1e-9);
  CHECK_NEAR(v.v_um_per_ms[0], 4.0, 1e-9);
  CHECK_NEAR(v.v_um_per_ms[1], -3.0, 1e-9);
  CHECK_NEAR(v.v_um_per_ms[2], 0.0, 1e-9);
  CHECK(abs_v < 1e-9 && dev < 1e-9);
  CHECK_EQ_INT(track_votes_judge(&v, 1, &speed, &abs_v, &dev), 1); /* says the same again */
  track_votes_free(&v);

  /* weak peaks only: no frame has the 3 points a pair needs */
  CHECK(track_votes_init(&v, 1.5));
  feed(&v, 20, 0, 1);
  CHECK_EQ_INT(v.n_pairs, 0);
  CHECK_EQ_INT(track_votes_judge(&v, 1, &speed, &abs_v, &dev), 0);
  track_votes_free(&v);

  /* a flow: every bright peak at its own velocity, no shift carries them */
  CHECK(track_votes_init(&v, 1.5));
  feed(&v, 20, 1, 0);
  CHECK_MSG(v.n_agree == 0, "a flow: %d of %d pairs agree", v.n_agree, v.n_pairs);
  CHECK_EQ_INT(track_votes_judge(&v, 0, &speed, &abs_v, &dev), 0);
  track_votes_free(&v);

  /* the frames end after 11 (10 pairs: judged) or 10 (9: not a stage) */
  for (int frames = 10; frames <= 11; frames++) {
    CHECK(track_votes_init(&v, 1.5));
    feed(&v, frames, 0, 0);
    CHECK_EQ_INT(track_votes_judge(&v, 0, &speed, &abs_v, &dev), -1);
    CHECK_EQ_INT(track_votes_judge(&v, 1, &speed, &abs_v, &dev), frames == 11);
    track_votes_free(&v);
  }

  /* never initialised: nothing kept, not a stage */
  memset(&v, 0, sizeof v);
  feed(&v, 20, 0, 0);
  CHECK_EQ_INT(track_votes_judge(&v, 1, &speed, &abs_v, &dev), 0);
  return check_report();
}
