/* test_track_pulsed.c — `eventlfm track` finds pulsed light by itself
 * (--start not given; docs/tracker.md "The LED's windows by default").
 *  - Blinking beads that move (blink_moving 100 ms, seed 1: 1 ms pulses
 *    every 3 ms, the LED's edges on the trigger input): the frames with an
 *    edge hold most of the events, so the run starts again with --repr lin
 *    --start each-trigger, the README's setting, byte for byte. Before, the
 *    default read them as a stage on the 1 ms grid (blink_moving 200 ms
 *    seeds 1-8, window rule: alpha 0.509 -> 0.867).
 *  - A trigger that is not the light's: a flow recording (100 ms, seed 2)
 *    with rising and falling edges added every 7 ms, as a camera or stage
 *    controller would put on the input. The edge frames hold no more events
 *    than the others, the objects move: the run keeps the grid, its tracks
 *    and detections are the recording's without the edges byte for byte,
 *    and no note calls the edges pulsed light (before this test, the notes
 *    for --repr lin and each-trigger took any 4 edges for it).
 * Blinking beads at rest: tests/track_trigger.sh. */
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "check.h"
#include "cli_test_util.h"
#include "elfm_datasets.h"
#include "elfm_events.h"

static char tmpdir[] = "/tmp/elfm_pulsed_XXXXXX";

static int simulate(const char *scene, int duration_ms, uint64_t seed, const char *dir)
{
  elfm_error err;
  elfm_scene *s = NULL;
  char kv[64];
  snprintf(kv, sizeof kv, "duration_ms=%d", duration_ms);
  if (elfm_scene_load(scene, &s, &err) != ELFM_OK || elfm_scene_set_param(s, kv, &err) != ELFM_OK ||
      elfm_scene_set_seed(s, seed, &err) != ELFM_OK) {
    elfm_scene_free(s);
    return 0;
  }
  elfm_sim_options so;
  memset(&so, 0, sizeof so);
  so.write_truth = 1;
  const elfm_status st = elfm_sim_run(s, dir, &so, NULL, &err);
  elfm_scene_free(s);
  return st == ELFM_OK;
}

/* in -> out, the same events with edges (rising at 3000 + 7000 k us,
 * falling 500 us later, channel 0) merged in; 1 when written. */
static int add_edges(const char *in, const char *out)
{
  elfm_error err;
  elfm_reader *r = NULL;
  elfm_writer *w = NULL;
  elfm_event_chunk *c = elfm_chunk_create(1 << 16, &err);
  int ok = c && elfm_reader_open(in, NULL, &r, &err) == ELFM_OK &&
           elfm_writer_open(out, ELFM_FMT_EVT3, elfm_reader_width(r), elfm_reader_height(r), &w,
                            &err) == ELFM_OK;
  int64_t next = 3000; /* the next edge: rising at 3000 + 7000 k, falling at + 500 */
  int rising = 1, edges = 0;
  while (ok) {
    if (elfm_reader_read(r, c, &err) != ELFM_OK) ok = 0;
    if (!ok || (c->n == 0 && c->n_trig == 0)) break;
    /* the edges up to this chunk's last event go with it (merged by time) */
    while (c->n > 0 && next <= c->t_us[c->n - 1] && c->n_trig < c->cap_trig) {
      c->trig[c->n_trig++] = (elfm_trigger){.t_us = next, .channel = 0, .value = rising};
      edges += rising;
      next += rising ? 500 : 6500;
      rising = !rising;
    }
    if (elfm_writer_write(w, c, &err) != ELFM_OK) ok = 0;
  }
  if (w && elfm_writer_close(w, &err) != ELFM_OK) ok = 0;
  elfm_reader_close(r);
  elfm_chunk_free(c);
  if (ok) fprintf(stderr, "  %d rising edges added\n", edges);
  return ok && edges >= 10;
}

int main(void)
{
  char bin[1024];
  snprintf(bin, sizeof bin, "%s/eventlfm", ELFM_BINARY_DIR);
  if (access(bin, X_OK) != 0) SKIP("%s not built", bin);
  if (!mkdtemp(tmpdir)) SKIP("no temp dir");
  char dir[1200], args[4096], a[1400], b[1400];

  /* blinking beads that move */
  snprintf(dir, sizeof dir, "%s/bm", tmpdir);
  if (!simulate("blink_moving", 100, 1, dir)) SKIP("simulate blink_moving failed");
  snprintf(args, sizeof args, "track --calib %s/calib.json --events %s/events.raw --out %s/auto --threads 1",
           dir, dir, dir);
  CHECK_EQ_INT(cli_run(dir, args), 0);
  CHECK(cli_file_has(dir, "err.txt", "% of the others); starting again with --repr lin --start each-trigger"));
  snprintf(args, sizeof args,
           "track --calib %s/calib.json --events %s/events.raw --out %s/given --threads 1 -q "
           "--repr lin --start each-trigger", dir, dir, dir);
  CHECK_EQ_INT(cli_run(dir, args), 0);
  static const char *files[3] = {"tracks.csv", "detections.csv", "frames.csv"};
  for (int k = 0; k < 3; k++) {
    snprintf(a, sizeof a, "%s/auto/%s", dir, files[k]);
    snprintf(b, sizeof b, "%s/given/%s", dir, files[k]);
    CHECK_MSG(cli_same_file(a, b), "blink_moving: %s differs from --repr lin --start each-trigger's", files[k]);
  }
  CHECK(cli_file_has(dir, "auto/summary.json", "\"start\":\t\"each-trigger\""));
  CHECK(cli_file_has(dir, "auto/summary.json", "\"repr\":\t\"lin\""));
  CHECK(cli_file_has(dir, "auto/summary.json", "\"start_auto\":\ttrue"));
  /* --start given: the grid, as before (a stage there) */
  snprintf(args, sizeof args,
           "track --calib %s/calib.json --events %s/events.raw --out %s/grid --threads 1 -q --start first",
           dir, dir, dir);
  CHECK_EQ_INT(cli_run(dir, args), 0);
  CHECK(cli_file_has(dir, "grid/summary.json", "\"start\":\t\"first\""));
  CHECK(cli_file_has(dir, "grid/summary.json", "\"start_auto\":\tfalse"));

  /* a trigger that is not the light's */
  snprintf(dir, sizeof dir, "%s/f", tmpdir);
  if (!simulate("flow", 100, 2, dir)) SKIP("simulate flow failed");
  snprintf(a, sizeof a, "%s/events.raw", dir);
  snprintf(b, sizeof b, "%s/sync.raw", dir);
  CHECK(add_edges(a, b));
  snprintf(args, sizeof args, "info %s/sync.raw --json", dir);
  CHECK_EQ_INT(cli_run(dir, args), 0);
  CHECK(cli_file_has(dir, "out.txt", "\"triggers\":28"));
  snprintf(args, sizeof args, "track --calib %s/calib.json --events %s/events.raw --out %s/plain --threads 1 -q",
           dir, dir, dir);
  CHECK_EQ_INT(cli_run(dir, args), 0);
  snprintf(args, sizeof args, "track --calib %s/calib.json --events %s/sync.raw --out %s/sync --threads 1",
           dir, dir, dir);
  CHECK_EQ_INT(cli_run(dir, args), 0);
  CHECK(!cli_file_has(dir, "err.txt", "pulsed light"));
  for (int k = 0; k < 2; k++) {
    snprintf(a, sizeof a, "%s/plain/%s", dir, files[k]);
    snprintf(b, sizeof b, "%s/sync/%s", dir, files[k]);
    CHECK_MSG(cli_same_file(a, b), "flow with a frame clock: %s differs from the recording's", files[k]);
  }
  CHECK(cli_file_has(dir, "sync/summary.json", "\"start\":\t\"first\""));

  snprintf(args, sizeof args, "rm -rf '%s'", tmpdir);
  if (system(args) != 0) fprintf(stderr, "could not remove %s\n", tmpdir);
  return check_report();
}
