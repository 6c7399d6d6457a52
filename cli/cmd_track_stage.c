/* cmd_track_stage.c — eventlfm track --motion stage: the tracks that do
 * not move with the stage are left out (tracks.csv, the XML files and the
 * stage's velocity in summary.json). With --stage-velocity-um-per-ms,
 * against that velocity; without it, against the tracks' own consensus
 * (docs/tracker.md "The stage's velocity from its tracks"). Also the test
 * for a stage (--motion auto) and a slow stage's windows ("Windows for a
 * slow stage"). */
#include <math.h>
#include <stdlib.h>

#include "cmd_track.h"

/* A track too short to tell its own noise (under 5 points of distinct
 * times, elfm_smooth_noise_known: its uncertainties are NaN) is judged
 * only along the stage's motion, which a drift does not fake: at rest or
 * against the stage (a hot pixel's, a ghost's joined across a dark gap),
 * or far faster. Its velocity across the stage is its noise's: on
 * blink_moving at 1.5 mm/s seeds 1-3, 6 such tracks of 2-4 points, 48-84
 * um deep, 5 at the recording's ends, lay 0.5-4.3 um/ms off in z and were
 * dropped (alpha 0.8839; 0.8872 kept), while blink_moving seed 12 kept
 * 2-point ghosts moving against the stage, one in each pulse, and 2-point
 * tracks at rest across 48 frames: the stage's error by the tracks'
 * points 18.8 %, 0.46 % tested along (docs/tracker.md "Dim blinking
 * beads"). A one-frame track (a bead in one LED pulse) has no velocity
 * at all (elfm_track_velocity_known): its static 0 is the model's. */
static int noise_known(const elfm_track *t)
{
  return !(t->vel_sd_um_per_ms && isnan(t->vel_sd_um_per_ms[0]));
}

/* Along and across the direction of v_ref (|v_ref| = s > 0) */
static void along_across(const double v[3], const double v_ref[3], double s, double *along, double *across)
{
  double a = 0, c2 = 0;
  for (int k = 0; k < 3; k++) a += v[k] * v_ref[k] / s;
  for (int k = 0; k < 3; k++) c2 += (v[k] - a * v_ref[k] / s) * (v[k] - a * v_ref[k] / s);
  *along = a;
  *across = sqrt(c2);
}

/* Rigid stage motion: a track moving otherwise than v_ref (more than 25 %
 * of its speed + 0.1 um/ms off) is not part of the sample (ghosts joined
 * across gaps, a hot pixel's or noise's track at rest); a short one, as
 * off_consensus's. */
static int off_stage(const elfm_track *t, const double v_ref[3])
{
  if (!elfm_track_velocity_known(t)) return 0;
  double v[3], d2 = 0, s2 = 0;
  elfm_track_mean_velocity(t, v);
  for (int a = 0; a < 3; a++) {
    d2 += (v[a] - v_ref[a]) * (v[a] - v_ref[a]);
    s2 += v_ref[a] * v_ref[a];
  }
  const double s = sqrt(s2);
  if (!noise_known(t)) {
    double along, across;
    if (!(s >= 0.05)) return 0;
    along_across(v, v_ref, s, &along, &across);
    return !(along >= 0.25 * s && along <= 4 * s);
  }
  return sqrt(d2) > 0.25 * s + 0.1;
}

/* Against the tracks' own consensus v_c instead of a given velocity: the
 * stage may speed up (stage_accel: 0.1 -> 0.6 um/ms over 200 ms, so tracks
 * of different spans differ by 2x in mean speed, and the rule above
 * dropped 1-5 whole tracks of each run, alpha 0.522 -> 0.439). A track is
 * off when it moves along the stage's direction at under 1/4 or over 4x
 * the consensus speed (at rest, or against it: a hot pixel's track, a
 * ghost's), or, told its noise, across it by more than 25 % of that speed
 * + 0.1 um/ms. A consensus near rest (under 0.05 um/ms) tests nothing. */
static int off_consensus(const elfm_track *t, const double v_c[3], double along_min, double along_max)
{
  const double sc = sqrt(v_c[0] * v_c[0] + v_c[1] * v_c[1] + v_c[2] * v_c[2]);
  if (!(sc >= 0.05) || !elfm_track_velocity_known(t)) return 0;
  double v[3], along, across;
  elfm_track_mean_velocity(t, v);
  along_across(v, v_c, sc, &along, &across);
  return !(along >= along_min * sc && along <= along_max * sc) ||
         (noise_known(t) && across > 0.25 * sc + 0.1);
}

/* The points of a track that joins the consensus: under the LED's
 * windows a point per pulse, and a bead crosses the field in fewer than
 * TRACK_STAGE_MIN_POINTS (blink_moving at 2.5 mm/s: at most 18), so
 * there was no consensus and no track was tested */
static size_t stage_min_points(const track_ctx *c)
{
  return track_led_windows(c->o) ? TRACK_STAGE_LED_MIN_POINTS : TRACK_STAGE_MIN_POINTS;
}

/* The weighted median of the values x[k * stride] (weights w[k * stride]),
 * 0 < n <= TRACK_STAGE_RING. */
static double weighted_median(const double *x, const double *w, int n, int stride)
{
  int idx[TRACK_STAGE_RING];
  double tot = 0;
  for (int k = 0; k < n; k++) {
    idx[k] = k;
    tot += w[k * stride];
  }
  for (int i = 1; i < n; i++) /* insertion sort: a few dozen */
    for (int j = i; j > 0 && x[idx[j - 1] * stride] > x[idx[j] * stride]; j--) {
      int tmp = idx[j];
      idx[j] = idx[j - 1];
      idx[j - 1] = tmp;
    }
  double acc = 0;
  for (int k = 0; k < n; k++)
    if ((acc += w[idx[k] * stride]) >= 0.5 * tot) return x[idx[k] * stride];
  return x[idx[n - 1] * stride];
}

/* t against the consensus: per axis, the weighted median (by points) of
 * the ring's mean velocities. No consensus (no long track yet): not off. */
static int stage_off(const track_ctx *c, const elfm_track *t)
{
  if (c->n_stage_ring == 0) return 0;
  double v[3];
  for (int a = 0; a < 3; a++)
    v[a] = weighted_median(&c->stage_ring[0][a], &c->stage_ring[0][3], c->n_stage_ring, 4);
  /* A slow stage's long windows (o->stage_watch) hold only while the
   * stage stays under TRACK_STAGE_WATCH_STEP_UM per window, 1.6x the
   * TRACK_STAGE_SLOW_STEP_UM it was judged at: its tracks' mean speeds
   * lie within that of each other, and a track at half the stage's speed
   * is a deep bead's image cut by the field stop (stage 0.75 mm/s 200 ms
   * seed 3 at 3.4 ms windows: a bead at z -86 um entering the field at
   * 0.40 um/ms, 12 of 429 points, put the stage's speed 1.2 % low; left
   * out, 0.12 %). */
  if (c->o->stage_watch) return off_consensus(t, v, TRACK_STAGE_WATCH_ALONG_MIN, 1 / TRACK_STAGE_WATCH_ALONG_MIN);
  return off_consensus(t, v, 0.25, 4);
}

static void stage_ring_add(track_ctx *c, const elfm_track *t)
{
  if (t->n < stage_min_points(c)) return;
  double *e = c->stage_ring[c->stage_ring_at];
  elfm_track_mean_velocity(t, e);
  e[3] = (double)t->n;
  c->stage_ring_at = (c->stage_ring_at + 1) % TRACK_STAGE_RING;
  if (c->n_stage_ring < TRACK_STAGE_RING) c->n_stage_ring++;
}

/* A track off the stage: counted, freed. */
static elfm_status stage_drop(track_ctx *c, elfm_track *t)
{
  c->n_rejected_stage++;
  elfm_track_free(t);
  return ELFM_OK;
}

/* The pending tracks, in their order: the consensus from the long ones
 * among them, then each tested and written or dropped. */
static elfm_status stage_release(track_ctx *c, elfm_error *err)
{
  elfm_track_store *s = &c->stage_pending;
  for (size_t i = 0; i < s->n; i++) stage_ring_add(c, s->tracks[i]);
  elfm_status st = ELFM_OK;
  for (size_t i = 0; i < s->n; i++) {
    elfm_track *t = s->tracks[i];
    s->tracks[i] = NULL;  /* each is written or freed here */
    if (st != ELFM_OK) elfm_track_free(t);
    else if (stage_off(c, t)) stage_drop(c, t);
    else st = track_write_track(c, t, err);
  }
  s->n = 0;
  c->n_stage_pending_long = 0;
  return st;
}

/* --motion stage without a given velocity: hold t until there is a
 * consensus; then test it, and a kept long track joins the consensus. */
static elfm_status stage_hold(track_ctx *c, elfm_track *t, elfm_error *err)
{
  if (c->stage_established) {
    if (stage_off(c, t)) return stage_drop(c, t);
    stage_ring_add(c, t);
    return track_write_track(c, t, err);
  }
  const int is_long = t->n >= stage_min_points(c);
  elfm_status st = elfm_track_store_add(&c->stage_pending, t, err);  /* frees t on failure */
  if (st != ELFM_OK) return st;
  c->n_stage_pending_long += is_long;
  if (c->n_stage_pending_long < TRACK_STAGE_MIN_TRACKS && c->stage_pending.n < TRACK_STAGE_MAX_PENDING)
    return ELFM_OK;
  c->stage_established = 1;
  return stage_release(c, err);
}

elfm_status track_stage_flush(track_ctx *c, elfm_error *err)
{
  return stage_release(c, err);
}

elfm_status track_stage_filter(track_ctx *c, elfm_track *t, elfm_error *err)
{
  /* with a known velocity, against it; else against the tracks' own */
  if (!c->o->has_stage_v) return stage_hold(c, t, err);
  if (off_stage(t, c->o->stage_v)) return stage_drop(c, t);
  return track_write_track(c, t, err);
}

/* --motion auto's test for rigid motion (cmd_track.h TRACK_RIGID_*). */

void track_rigid_add_frame(track_ctx *c, double *v, int n)
{
  if (c->rigid_decided || n < TRACK_RIGID_MIN_TRACKS) return;
  /* The median velocity, component by component: a few tracks on ghosts
   * or swapped beads do not move it (a mean would follow them). */
  double m[3], spread, *col = c->rigid_v + 3 * (size_t)c->o->max_det; /* its scratch column */
  for (int a = 0; a < 3; a++) {
    for (int i = 0; i < n; i++) col[i] = v[3 * i + a];
    elfm_analysis_median(col, (size_t)n, &m[a], &spread);
  }
  const double sm = sqrt(m[0] * m[0] + m[1] * m[1] + m[2] * m[2]);
  for (int i = 0; i < n; i++) {
    const double *w = v + 3 * i;
    const double d = sqrt((w[0] - m[0]) * (w[0] - m[0]) + (w[1] - m[1]) * (w[1] - m[1]) +
                          (w[2] - m[2]) * (w[2] - m[2]));
    const double b = sm > 0 ? floor(d / sm / TRACK_RIGID_BIN) : TRACK_RIGID_BINS;
    track_hist_add(c->rigid_hist, TRACK_RIGID_BINS, b);
    const double ba = floor(d / TRACK_RIGID_ABS_BIN_UM_PER_MS);
    track_hist_add(c->rigid_abs_hist, TRACK_RIGID_BINS, ba);
    c->n_rigid++;
  }
  const double b = floor(sm / TRACK_SPEED_BIN_UM_PER_MS);
  track_hist_add(c->rigid_speed_hist, TRACK_SPEED_BINS, b);
  c->n_rigid_frames++;
}

int track_rigid_judge(track_ctx *c, int at_end)
{
  const track_opts *o = c->o;
  if (c->rigid_decided) return c->motion_restart;
  /* under the LED's windows, frames that hold a pulse: the dark ones
   * between pulses add no sample */
  const int64_t frames = track_led_windows(o) ? c->n_lit_frames : c->n_frames;
  const int last = at_end || frames >= TRACK_RIGID_MAX_FRAMES; /* no more frames to wait for */
  const int64_t need = at_end ? TRACK_RIGID_MIN_SAMPLES / 2 : TRACK_RIGID_MIN_SAMPLES;
  if (!c->rigid_tracks_judged && c->n_rigid >= need) {
    c->rigid_tracks_judged = 1;
    c->rigid_dev = (track_hist_median_bin(c->rigid_hist, TRACK_RIGID_BINS, c->n_rigid) + 0.5) * TRACK_RIGID_BIN;
    c->rigid_speed = (track_hist_median_bin(c->rigid_speed_hist, TRACK_SPEED_BINS, c->n_rigid_frames) + 0.5) *
                     TRACK_SPEED_BIN_UM_PER_MS;
    c->rigid_abs = (track_hist_median_bin(c->rigid_abs_hist, TRACK_RIGID_BINS, c->n_rigid) + 0.5) *
                   TRACK_RIGID_ABS_BIN_UM_PER_MS;
    c->motion_restart = (c->rigid_dev < TRACK_RIGID_MAX_DEV || c->rigid_abs < TRACK_RIGID_MAX_ABS_UM_PER_MS) &&
                        c->rigid_speed >= TRACK_RIGID_MIN_SPEED_UM_PER_MS;
  }
  if (!c->rigid_tracks_judged) {
    if (!last) return 0;        /* too few samples yet */
    c->rigid_tracks_judged = 2; /* not judged by the tracks, and no later */
  }
  /* The frames' shift (cmd_track_vote.h), once its pairs are in, where
   * the run takes it (track_votes_wanted; else it says 0 at once): with a
   * stage found by the tracks, its velocity for the stage's run to start
   * new tracks at; with none (or too few tracks to judge), a stage when
   * the frames move as one. Not while pulsed light may yet be found (a
   * trigger seen, the first peaks not judged): one window per pulse comes
   * first, and a stage
   * found here would turn that test off (blink_moving at a quarter of the
   * flux, seed 4: found by the shift on the grid before the LED, alpha
   * 0.390 -> 0.240, the LED and the blur never chosen); the shift is left
   * unjudged for the LED's run to measure. */
  double speed, abs_um_per_ms, dev;
  int by_shift = 0;
  if (!track_pulsed_pending(c)) {
    by_shift = track_votes_judge(&c->votes, last, &speed, &abs_um_per_ms, &dev);
    if (by_shift < 0) return 0;
  }
  c->rigid_decided = 1;
  if (c->motion_restart) return 1;
  if (by_shift) {
    c->votes.by_shift = 1;
    c->rigid_speed = speed;
    c->rigid_abs = abs_um_per_ms;
    c->rigid_dev = dev;
    c->motion_restart = 1;
  }
  return c->motion_restart;
}

int64_t track_stage_slow_dt_us(const track_ctx *c)
{
  const track_opts *o = c->o;
  /* the window and tau are auto's to choose only when neither was given;
   * dt_auto also says the first run is on a time surface's 1 ms grid
   * (track_opts_derive) */
  if (!c->motion_restart || !o->dt_auto || o->tau_given || !(c->rigid_speed > 0)) return -1;
  const double dt_us = 1e3 * TRACK_STAGE_SLOW_STEP_UM / c->rigid_speed;
  if (dt_us < TRACK_STAGE_SLOW_MIN_DT_US) return -1;
  /* in steps of 100 us, for a command line that reads well */
  int64_t dt = (int64_t)fmin(TRACK_STAGE_SLOW_MAX_DT_US, 100.0 * round(dt_us / 100.0));
  /* judged at the end of a short recording (not stopped early): at least
   * TRACK_STAGE_SLOW_MIN_WINDOWS windows in it, or none longer */
  if (!c->auto_stopped) {
    const int64_t cap = c->n_frames * o->recon.framer.dt_us / TRACK_STAGE_SLOW_MIN_WINDOWS / 100 * 100;
    if (dt > cap) dt = cap >= TRACK_STAGE_SLOW_MIN_DT_US ? cap : -1;
  }
  return dt;
}

void track_stage_watch_frame(track_ctx *c, double *s, int n)
{
  if (c->stage_outrun || n < TRACK_RIGID_MIN_TRACKS) return; /* too few to say: the count goes on */
  double med, spread;
  elfm_analysis_median(s, (size_t)n, &med, &spread);
  const double frame_ms = 1e-3 * (double)c->o->recon.framer.dt_us;
  if (!(med * frame_ms >= TRACK_STAGE_WATCH_STEP_UM)) {
    c->stage_fast_frames = 0;
    return;
  }
  if (++c->stage_fast_frames < TRACK_STAGE_WATCH_FRAMES) return;
  c->stage_outrun = 1;
  c->stage_outrun_speed = med;
}
