/* fuzz_score.c — libFuzzer target for the scorer's reading of its three
 * tables (score_io.c: columns, sorted truth, frame times, duplicate frames)
 * and everything it computes from them (detection matching, the motion-bias
 * regression, ISBI pairing, the stage velocity). The input is truth.csv,
 * then tracks.csv, then detections.csv, then frames.csv (the run's frame
 * list), separated by lines "==="; a missing part is left out (tracks or
 * detections, not both; the frame list may be absent). */
#include <stddef.h>
#include <stdint.h>
#include <string.h>

#include "elfm_tracker.h"

/* Start of the next separator line "===\n" in [p, end) (at p itself or
 * after a newline), or end. */
static const char *next_sep(const char *p, const char *end)
{
  if (end - p >= 4 && memcmp(p, "===\n", 4) == 0) return p;
  for (const char *q = p; q + 5 <= end; q++)
    if (memcmp(q, "\n===\n", 5) == 0) return q + 1;
  return end;
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
  const char *p = (const char *)data, *end = p + size;
  const char *part[4] = {NULL, NULL, NULL, NULL};
  size_t len[4] = {0, 0, 0, 0};
  for (int k = 0; k < 4 && p <= end; k++) {
    const char *s = next_sep(p, end);
    part[k] = p;
    len[k] = (size_t)(s - p);
    p = s < end ? s + 4 : end + 1;
  }
  static const char *const names[4] = {"truth.csv", "tracks.csv", "detections.csv",
                                       "frames.csv"};
  elfm_table *t[4] = {NULL, NULL, NULL, NULL};
  elfm_error err;
  int ok = 1;
  for (int k = 0; k < 4 && ok; k++)
    if (part[k] && len[k] > 0 && elfm_table_parse(part[k], len[k], names[k], &t[k], &err) != ELFM_OK)
      ok = 0;
  if (ok && t[0] && (t[1] || t[2])) {
    elfm_score_options o;
    elfm_score_options_default(&o);
    o.have_stage = 1;
    o.stage_v_um_per_ms[1] = 2.5;
    o.window_us = size % 2 ? 1000 : 0; /* both frame rules */
    o.frames = t[3];
    o.window_frames = t[3] && size % 3 == 0; /* and each frame's own window */
    elfm_score_result r;
    elfm_score_tables(t[0], t[1], t[2], &o, &r, &err);
  }
  for (int k = 0; k < 4; k++) elfm_table_free(t[k]);
  return 0;
}
