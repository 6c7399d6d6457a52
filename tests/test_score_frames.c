/* test_score_frames.c — scoring with the run's frame list (frames.csv,
 * elfm_score_options.frames): frames not evenly spaced (windows opened by
 * trigger edges), frames without any row, the window rule over each
 * frame's own window, a window shorter than the truth's sampling, and bad
 * frame lists. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "check.h"
#include "elfm_tracker.h"

static elfm_table *table(const char *name, const char *text)
{
  elfm_error err;
  elfm_table *t = NULL;
  CHECK_OK(elfm_table_parse(text, strlen(text), name, &t, &err), &err);
  return t;
}

/* One object at rest at (1, 2, 3) lit for 1 ms from each of 7830 and 34558
 * (the simulator's 100 us samples: dark at 7800, lit 7900..8800, dark at
 * 8900), as `eventlfm track --start each-trigger` frames it with 1 ms
 * windows from the first edge: [7830, 8830) is the first pulse's, ...,
 * [33830, 34558) a window cut short by the second edge, [34558, 35558) the
 * second pulse's. Only frames 0 and 27 hold a detection. */
static char *truth_text(void)
{
  size_t cap = 1 << 16, n = 0;
  char *s = malloc(cap);
  n += (size_t)snprintf(s + n, cap - n, "id,t_us,x_um,y_um,z_um,brightness\n");
  for (int t = 0; t <= 40000; t += 100) {
    int lit = (t > 7830 && t < 8830) || (t > 34558 && t < 35558);
    n += (size_t)snprintf(s + n, cap - n, "0,%d,1,2,3,%d\n", t, lit);
  }
  return s;
}

static char *frames_text(int n_frames, int64_t edge2, int64_t cut_start)
{
  size_t cap = 1 << 14, n = 0;
  char *s = malloc(cap);
  n += (size_t)snprintf(s + n, cap - n, "frame,t_us,t_start_us,t_end_us,n_events,n_detections\n");
  int64_t t0 = 7830;
  for (int f = 0; f < n_frames; f++) {
    int64_t t1 = t0 + 1000;
    if (t0 < edge2 && t1 > edge2) t1 = edge2;
    if (f == 26) t0 = cut_start, t1 = edge2; /* the cut window */
    n += (size_t)snprintf(s + n, cap - n, "%d,%lld,%lld,%lld,0,0\n", f, (long long)t1,
                          (long long)t0, (long long)t1);
    t0 = t1;
  }
  return s;
}

static void test_uneven_frames(void)
{
  elfm_error err;
  char *tt = truth_text();
  elfm_table *truth = table("truth.csv", tt);
  char *ft = frames_text(32, 34558, 33830);
  elfm_table *frames = table("frames.csv", ft);
  /* frames 0 and 27 at their own times; 27 is the second pulse's */
  elfm_table *dets = table("detections.csv", "frame,t_us,x_um,y_um,z_um,intensity\n"
                                             "0,8830,1.1,2,3,50\n"
                                             "27,35558,1.1,2,3,50\n");
  elfm_score_options o;
  elfm_score_options_default(&o);
  o.frames = frames;
  o.window_frames = 1;
  elfm_score_result r;
  CHECK_OK(elfm_score_tables(truth, NULL, dets, &o, &r, &err), &err);
  /* one truth point per pulse, both matched; every listed frame counts */
  CHECK_EQ_INT(r.n_truth_points, 2);
  CHECK_EQ_INT(r.n_true_positives, 2);
  CHECK_EQ_INT(r.n_frames, 32);
  /* SPEC 7 as written: the cut window's t_us (34558) sits on the edge,
   * where the brightness interpolated between 34500 (dark) and 34600
   * (lit) is above 0: that frame counts too, and nothing is there */
  o.window_frames = 0;
  CHECK_OK(elfm_score_tables(truth, NULL, dets, &o, &r, &err), &err);
  CHECK_EQ_INT(r.n_truth_points, 3);
  CHECK_EQ_INT(r.n_true_positives, 2);
  /* without the list the frames between 0 and 27 are spread evenly, so
   * the score sees 28 frames at the wrong times, not the 32 of the run */
  o.frames = NULL;
  CHECK_OK(elfm_score_tables(truth, NULL, dets, &o, &r, &err), &err);
  CHECK_EQ_INT(r.n_frames, 28);
  /* a pulse frame without any row still counts (a miss): only the list
   * knows it was there */
  elfm_table *dets1 = table("detections.csv", "frame,t_us,x_um,y_um,z_um,intensity\n"
                                              "0,8830,1.1,2,3,50\n");
  o.frames = frames;
  o.window_frames = 1;
  CHECK_OK(elfm_score_tables(truth, NULL, dets1, &o, &r, &err), &err);
  CHECK_EQ_INT(r.n_truth_points, 2);
  CHECK_EQ_INT(r.n_true_positives, 1);
  /* a cut window shorter than the sampling, [34510, 34558): no sample
   * inside; the one before it (34500, dark) holds, not the lit 34600 */
  char *ft2 = frames_text(32, 34558, 34510);
  elfm_table *frames2 = table("frames.csv", ft2);
  o.frames = frames2;
  CHECK_OK(elfm_score_tables(truth, NULL, dets, &o, &r, &err), &err);
  CHECK_EQ_INT(r.n_truth_points, 2);
  /* the window rule over each frame's own window needs the list */
  o.frames = NULL;
  CHECK(elfm_score_tables(truth, NULL, dets, &o, &r, &err) == ELFM_ERR_INVALID);
  elfm_table_free(frames2);
  elfm_table_free(dets1);
  elfm_table_free(dets);
  elfm_table_free(frames);
  elfm_table_free(truth);
  free(ft2);
  free(ft);
  free(tt);
}

/* Bad frame lists and rows that disagree with them: errors naming the
 * file and line, never a score. */
static void test_bad_frames(void)
{
  elfm_error err;
  char *tt = truth_text();
  elfm_table *truth = table("truth.csv", tt);
  elfm_table *dets = table("detections.csv", "frame,t_us,x_um,y_um,z_um,intensity\n"
                                             "0,8830,1.1,2,3,50\n");
  static const struct {
    const char *text, *want;
  } bad[] = {
      {"frame,t_us,t_start_us\n0,8830,7830\n", "t_end_us"},
      {"frame,t_us,t_start_us,t_end_us\n0,8830,7830,8830\n0,9830,8830,9830\n", "frames.csv:3"},
      {"frame,t_us,t_start_us,t_end_us\n0,8830,7830,8830\n1,8830,8830,9830\n", "must increase"},
      {"frame,t_us,t_start_us,t_end_us\n0,8830,7830,8830\n1,9830,9830,9830\n", "inside its window"},
      {"frame,t_us,t_start_us,t_end_us\n0,8830,7830,8830\n1,9999,8830,9830\n", "inside its window"},
      {"frame,t_us,t_start_us,t_end_us\n0,8830,7830,\n", "empty"},
      {"frame,t_us,t_start_us,t_end_us\n0.5,8830,7830,8830\n", "integer"},
      /* the detection's frame 0 has another time here */
      {"frame,t_us,t_start_us,t_end_us\n0,8831,7830,8831\n", "detections.csv:2"},
      /* and here frame 0 is not listed */
      {"frame,t_us,t_start_us,t_end_us\n1,9830,8830,9830\n", "not in the frame list"},
  };
  for (size_t k = 0; k < sizeof bad / sizeof bad[0]; k++) {
    elfm_table *frames = table("frames.csv", bad[k].text);
    elfm_score_options o;
    elfm_score_options_default(&o);
    o.frames = frames;
    elfm_score_result r;
    elfm_status s = elfm_score_tables(truth, NULL, dets, &o, &r, &err);
    CHECK(s == ELFM_ERR_FORMAT);
    char full[1200];
    CHECK_MSG(strstr(elfm_error_format(&err, full, sizeof full), bad[k].want) != NULL,
              "case %zu: '%s' lacks '%s'", k, full, bad[k].want);
    elfm_table_free(frames);
  }
  elfm_table_free(dets);
  elfm_table_free(truth);
  free(tt);
}

int main(void)
{
  test_uneven_frames();
  test_bad_frames();
  return check_report();
}
