/* cmd_track_again.c — what one run of eventlfm track judged and chose for
 * the next (cmd_track_again.h). */
#include "cmd_track_again.h"

#include <inttypes.h>
#include <math.h>
#include <stdio.h>
#include <string.h>

/* What a run judged (its first peaks, the motion), for the next run's
 * summary.json (track_again_settle). */
void track_again_judged(track_again *g, const track_ctx *c)
{
  /* a settled run that judged no first peaks (the LED's run, which tests
   * only for a stage) passes on what the first run judged */
  if (c->auto_decided || !c->o->auto_chose) {
    g->ratio = c->auto_decided ? c->auto_ratio : NAN;
    g->speed_um_per_ms = c->auto_decided ? c->auto_speed : NAN;
    g->miss_um = c->miss_decided ? c->auto_miss : NAN;
  }
  g->rigid_dev = c->rigid_dev;
  g->rigid_speed_um_per_ms = c->rigid_speed;
  g->rigid_abs_um_per_ms = c->rigid_abs;
  g->rigid_by_shift = c->votes.by_shift;
  if (c->votes.judged) { /* else what a run before judged, if one did */
    g->shift_judged = 1;
    g->shift_agree = c->votes.n_agree;
    g->shift_pairs = c->votes.n_pairs;
    g->rigid_v_known = c->votes.have_v;
    for (int a = 0; a < 3; a++) g->rigid_v_um_per_ms[a] = c->votes.v_um_per_ms[a];
  }
}

void track_again_say(const track_ctx *c, const track_again *g)
{
  const track_opts *o = c->o;
  if (o->quiet) return;
  fputc('\n', stderr);
  if (g->each_trigger && track_led_windows(o))
    fprintf(stderr, "eventlfm track: the LED's windows given, and the tracks move (median %.2f um/ms): "
                    "starting again with --repr lin, which drops each event at its window's end "
                    "(--repr exp: keep the default surface; README, blinking objects that move)\n",
            c->auto_speed);
  else if (g->each_trigger)
    fprintf(stderr, "eventlfm track: %" PRId64 " trigger edges so far, and the frames with an edge "
                    "hold %.0fx the others' events: pulsed light (a peak in %.0f %% of them, %.0f %% "
                    "of the others); starting again with %s--start "
                    "each-trigger, one window per pulse (--start first: keep the grid; score with "
                    "--frames run --window-us run; README, blinking objects)\n",
            c->n_triggers, track_pulsed_ratio(c), track_peaked_pct(c, 1), track_peaked_pct(c, 0),
            g->lin ? "--repr lin " : "");
  if (g->prior_only)
    fprintf(stderr, "eventlfm track: one shift carries each frame's detections onto the next's in %d "
                    "of %d pairs, at (%.2f, %.2f, %.2f) um/ms: the stage's; starting again with new "
                    "tracks at that velocity (--stage-velocity-um-per-ms: a known one; docs/"
                    "tracker.md \"A stage found by its frames' shift\")\n",
            g->shift_agree, g->shift_pairs, g->rigid_v_um_per_ms[0], g->rigid_v_um_per_ms[1],
            g->rigid_v_um_per_ms[2]);
  if (g->stage && g->rigid_by_shift)
    fprintf(stderr, "eventlfm track: no stage by the tracks (too few long ones, or linked across "
                    "beads), but one shift carries each frame's detections onto the next's in %d of "
                    "%d pairs (at %.2f um/ms; their velocities lie a median %.3f um/ms, %.1f %%, from "
                    "the median): a stage; starting again with --motion stage, new tracks starting "
                    "at (%.2f, %.2f, %.2f) um/ms "
                    "(--motion per-track: a model for each track; README, docs/tracker.md \"A "
                    "stage found by its frames' shift\")\n",
            g->shift_agree, g->shift_pairs, c->rigid_speed, c->rigid_abs, 100 * c->rigid_dev,
            g->rigid_v_um_per_ms[0], g->rigid_v_um_per_ms[1], g->rigid_v_um_per_ms[2]);
  else if (g->stage) {
    /* found by its tracks; the shift, when its frames moved as one, gives
     * the stage's new tracks their velocity */
    char shift[160] = "", start[128] = "";
    if (g->rigid_v_known) {
      snprintf(shift, sizeof shift,
               ", and one shift carries each frame's detections onto the next's in %d of %d pairs",
               g->shift_agree, g->shift_pairs);
      snprintf(start, sizeof start, ", new tracks starting at the shift's (%.2f, %.2f, %.2f) um/ms",
               g->rigid_v_um_per_ms[0], g->rigid_v_um_per_ms[1], g->rigid_v_um_per_ms[2]);
    }
    fprintf(stderr, "eventlfm track: the tracks move as one (at %.2f um/ms; their velocities lie a "
                    "median %.3f um/ms, %.1f %%, from each frame's median, over the first %" PRId64
                    " frames)%s: a stage; starting again with --motion stage%s (--motion per-track: a "
                    "model for each track; README, docs/tracker.md \"A stage found by its %s\")\n",
            c->rigid_speed, c->rigid_abs, 100 * c->rigid_dev, c->n_frames, shift, start,
            g->rigid_v_known ? "frames' shift" : "tracks");
  }
  if (g->stage && g->dt_us > 0)
    fprintf(stderr, "eventlfm track: the stage is slow (%.2f um per %" PRId64 " us window): "
                    "--dt-us %" PRId64 " --tau-us %" PRId64 " too, %.1f um per window (back to 1 ms "
                    "if it speeds up; --dt-us %" PRId64 ": keep the window; docs/tracker.md "
                    "\"Windows for a slow stage\")\n",
            c->rigid_speed * 1e-3 * (double)o->recon.framer.dt_us, o->recon.framer.dt_us, g->dt_us,
            g->dt_us, c->rigid_speed * 1e-3 * (double)g->dt_us, o->recon.framer.dt_us);
  if (g->blur_px > 0)
    fprintf(stderr, "eventlfm track: the peaks are faint (median height %.0f against the threshold "
                    "%.0f over the first %" PRId64 "): dim objects; starting again with --blur-px 1 "
                    "(--blur-px 0: no blur; README, docs/tracker.md \"Dim objects\")\n",
            c->auto_ratio * o->peaks.absolute, o->peaks.absolute, c->auto_peaks);
  if (g->integral && c->few_restart) {
    char dt[64] = "";
    if (g->dt_us > 0) snprintf(dt, sizeof dt, " --dt-us %" PRId64, g->dt_us);
    fprintf(stderr, "eventlfm track: %" PRId64 " peaks in %" PRId64 " frames, too few to judge: "
                    "objects too slow (or too faint) for the time surface; starting again with "
                    "--repr integral%s (--repr exp: keep the time surface; docs/tracker.md \"Too "
                    "few peaks to judge\")\n",
            c->auto_peaks, c->n_frames, dt);
  } else if (g->integral) {
    char dt[64] = "";
    if (g->dt_us > 0) snprintf(dt, sizeof dt, " --dt-us %" PRId64, g->dt_us);
    fprintf(stderr, "eventlfm track: the tracks crawl (median %.2f um/ms over the first %" PRId64
                    " peaks): cells, whose ON events lead them; starting again with --repr integral%s "
                    "(--repr exp: keep the time surface; README, docs/tracker.md \"Integral frames\")\n",
            c->auto_speed, c->auto_peaks, dt);
  } else if (g->dt_us > 0 && !g->stage && g->tau_follows)
    fprintf(stderr, "eventlfm track: the tracks move slowly for beads (median %.2f um/ms over the "
                    "first %" PRId64 " peaks): starting again with --dt-us %" PRId64 " --tau-us %" PRId64
                    ", windows that hold more of each bead's events (--dt-us %" PRId64 ": keep the "
                    "window; docs/tracker.md \"Windows for slow beads\")\n",
            c->auto_speed, c->auto_peaks, g->dt_us, g->dt_us, o->recon.framer.dt_us);
  else if (g->stride_us > 0 && !g->stage)
    fprintf(stderr, "eventlfm track: the tracks turn beyond prediction (%" PRId64 " detections lay "
                    "a median %.2f um from where their tracks predicted them): starting again with "
                    "--stride-us %" PRId64 ", the %" PRId64 " us windows twice as often (--stride-us "
                    "%" PRId64 ": keep the rate; docs/tracker.md \"Frames twice as often for turning "
                    "beads\")\n",
            c->n_miss, c->auto_miss, g->stride_us, o->recon.framer.dt_us, o->recon.framer.dt_us);
  else if (g->dt_us > 0 && !g->stage)
    fprintf(stderr, "eventlfm track: the tracks move fast (median %.2f um/ms over the first %" PRId64
                    " peaks, %.1f um per frame): starting again with --dt-us %" PRId64 " (--dt-us %" PRId64
                    ": keep the window; README, docs/tracker.md \"Fast beads\")\n",
            c->auto_speed, c->auto_peaks, c->auto_speed * 1e-3 * (double)o->recon.framer.dt_us, g->dt_us,
            o->recon.framer.dt_us);
}

/* A run after auto's choices: nothing automatic left, and summary.json
 * says what was automatic (was) and what the first run judged. */
void track_again_settle(track_opts *o, int was, const track_again *g, double ratio, double speed)
{
  o->blur_auto = o->dt_auto = o->repr_auto = o->lin_auto = 0;
  /* a run on the LED's windows still tests for a stage, which it could
   * not do before (the grid's run stopped at pulsed light's first peaks) */
  o->motion_auto = o->motion_auto && g->each_trigger && (was & 8);
  o->auto_chose = 1;
  o->auto_was = was;
  o->auto_ratio = ratio;
  o->auto_speed = speed;
  o->auto_miss = isfinite(speed) ? g->miss_um : NAN; /* judged with the speed */
  o->auto_rigid_dev = g->rigid_dev;
  o->auto_rigid_speed = g->rigid_speed_um_per_ms;
  o->auto_rigid_abs = g->rigid_abs_um_per_ms;
  o->auto_rigid_by_shift = g->rigid_by_shift;
  o->shift_judged = g->shift_judged;
  /* A stage found by the frames' shift (cmd_track_vote.h) moves too far
   * between frames for the linker's one-point tracks to find their next
   * point as if at rest: they start with the velocity found (blink_moving
   * at 6 mm/s, seeds 4-6: docs/tracker.md "A stage found by its frames'
   * shift"). Not a given velocity: the stage's tracks are still tested
   * against their own consensus, and summary.json compares with none. */
  if (o->motion == MOTION_STAGE && !o->has_stage_v && g->rigid_v_known)
    memcpy(o->link.prior_velocity_um_per_ms, g->rigid_v_um_per_ms, sizeof o->link.prior_velocity_um_per_ms);
}

