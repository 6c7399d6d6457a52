/* test_score_input.c — the scorer's bad input (elfm_score.h): every table
 * that cannot be scored is an error naming the file and the line, with the
 * status that says what kind (format or range), and nothing is scored.
 * The scene of test_score.c (score_test_util.h). */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "check.h"
#include "elfm_tracker.h"
#include "score_test_util.h"

static void expect_fail(const elfm_table *truth, const elfm_table *tracks, const elfm_table *dets,
                        elfm_status code, const char *file, int64_t line, const char *what)
{
  elfm_score_result r;
  elfm_error err;
  elfm_error_clear(&err);
  elfm_score_options def;
  elfm_score_options_default(&def);
  elfm_status s = elfm_score_tables(truth, tracks, dets, &def, &r, &err);
  CHECK_MSG(s == code, "%s: got %s: %s", what, elfm_status_str(s), err.message);
  CHECK_MSG(strcmp(err.file, file) == 0, "%s: file '%s'", what, err.file);
  CHECK_MSG(err.line == line, "%s: line %lld, expected %lld (%s)", what, (long long)err.line,
            (long long)line, err.message);
}

int main(void)
{
  elfm_table *truth = make_truth(1e9);

  /* Bad input -> error naming file and line (test_score.c's case 11
   * before it moved here). */
  {
    buf_t b = {0};
    bprintf(&b, "%s", TRACK_HEADER);
    add_track(&b, 1, 0, 0, 3, 0, 0, 0, -1, -1);
    elfm_table *good_tracks = parse(&b, "tracks.csv");

    /* One bad table each, scored with good ones in the other places: the
     * file it is named as says which place it takes. */
    static const struct {
      const char *file, *text;
      elfm_status code;
      int64_t line;
      const char *what;
    } bad[] = {
        {"truth.csv", "id,t_us,x_um,y_um,z_um\n1,0,0,0,0\n", ELFM_ERR_FORMAT, 1,
         "missing brightness"},
        {"truth.csv", "id,t_us,x_um,y_um,z_um,brightness\n1,0,0,0,0,1\n1,100,,0,0,1\n",
         ELFM_ERR_FORMAT, 3, "empty x_um"},
        {"truth.csv",
         "id,t_us,x_um,y_um,z_um,brightness\n1,0,0,0,0,1\n2,0,0,0,0,1\n1,200,0,0,0,1\n"
         "2,100,0,0,0,1\n1,100,0,0,0,1\n",
         ELFM_ERR_FORMAT, 6, "unsorted truth"},
        {"truth.csv", "id,t_us,x_um,y_um,z_um,brightness\n1,0,0,0,0,-1\n", ELFM_ERR_RANGE, 2,
         "negative brightness"},
        {"truth.csv", "id,t_us,x_um,y_um,z_um,brightness\n1.5,0,0,0,0,1\n", ELFM_ERR_FORMAT, 2,
         "fractional id"},
        {"tracks.csv", "track_id,frame,t_us,x_um,y_um,z_um,raw_x_um,raw_y_um\n1,0,1000,0,0,0,0,0\n",
         ELFM_ERR_FORMAT, 1, "missing raw_z_um"},
        {"tracks.csv",
         TRACK_HEADER "1,0,1000,0,0,0,0,0,0,0,0,0,1\n1,1,2000,0,0,0,0,0,0,0,0,0,1\n"
                      "1,1,2000,0,0,0,0,0,0,0,0,0,1\n",
         ELFM_ERR_FORMAT, 4, "duplicate frame"},
        {"tracks.csv", TRACK_HEADER "1,0,1000,0,0,0,0,0,0,0,0,0,1\n2,0,1001,0,0,0,0,0,0,0,0,0,1\n",
         ELFM_ERR_FORMAT, 3, "inconsistent frame time"},
        {"tracks.csv", TRACK_HEADER "1,0,1000,0,0,0,0,,0,0,0,0,1\n", ELFM_ERR_FORMAT, 2,
         "partial raw"},
        {"tracks.csv", TRACK_HEADER "1,0,1000,,0,0,0,0,0,0,0,0,1\n", ELFM_ERR_FORMAT, 2,
         "empty x_um"},
        {"tracks.csv", TRACK_HEADER "1,0.5,1000,0,0,0,0,0,0,0,0,0,1\n", ELFM_ERR_FORMAT, 2,
         "fractional frame"},
        {"detections.csv", "frame,t_us,x_um,y_um,z_um\n0,1000,0,0,0\n1,500,0,0,0\n",
         ELFM_ERR_FORMAT, 3, "time goes back"},
    };
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
      bprintf(&b, "%s", bad[i].text);
      elfm_table *t = parse(&b, bad[i].file);
      if (strcmp(bad[i].file, "truth.csv") == 0)
        expect_fail(t, good_tracks, NULL, bad[i].code, bad[i].file, bad[i].line, bad[i].what);
      else if (strcmp(bad[i].file, "tracks.csv") == 0)
        expect_fail(truth, t, NULL, bad[i].code, bad[i].file, bad[i].line, bad[i].what);
      else
        expect_fail(truth, NULL, t, bad[i].code, bad[i].file, bad[i].line, bad[i].what);
      elfm_table_free(t);
    }

    bprintf(&b, "frame,t_us,x_um,y_um,z_um\n0,1000,0,0,0\n50000001,500,0,0,0\n");
    elfm_table *d_span = parse(&b, "detections.csv");
    {
      elfm_score_result r;
      elfm_error err;
      elfm_score_options def;
      elfm_score_options_default(&def);
      CHECK(elfm_score_tables(truth, NULL, d_span, &def, &r, &err) == ELFM_ERR_RANGE);
      CHECK(strcmp(err.file, "detections.csv") == 0);
      /* the cap on truth points (objects x frames where each counts) */
      CHECK_OK(elfm_score_tables(truth, good_tracks, NULL, &def, &r, &err), &err);
      const int64_t npts = r.n_truth_points;
      CHECK(npts > 2);
      def.max_truth_points = npts - 1;
      CHECK(elfm_score_tables(truth, good_tracks, NULL, &def, &r, &err) == ELFM_ERR_RANGE);
      CHECK(strcmp(err.file, "truth.csv") == 0 && strstr(err.message, "object-frames") != NULL);
      def.max_truth_points = npts;
      CHECK_OK(elfm_score_tables(truth, good_tracks, NULL, &def, &r, &err), &err);
      CHECK(r.n_truth_points == npts);
      def.max_truth_points = 0;
      CHECK(elfm_score_tables(truth, good_tracks, NULL, &def, &r, &err) == ELFM_ERR_INVALID);
      def.max_truth_points = 10000000;
      /* neither tracks nor detections */
      CHECK(elfm_score_tables(truth, NULL, NULL, &def, &r, &err) == ELFM_ERR_INVALID);
      def.eps_um = 0;
      CHECK(elfm_score_tables(truth, good_tracks, NULL, &def, &r, &err) == ELFM_ERR_INVALID);
    }
    /* missing file */
    {
      elfm_score_result r;
      elfm_error err;
      elfm_score_options def;
      elfm_score_options_default(&def);
      CHECK(elfm_score_files("/nonexistent/truth.csv", "/nonexistent/tracks.csv", NULL, &def, &r,
                             &err) == ELFM_ERR_IO);
      CHECK(strstr(err.file, "truth.csv") != NULL);
    }
    elfm_table_free(good_tracks);
    elfm_table_free(d_span);
  }
  elfm_table_free(truth);
  return check_report();
}
