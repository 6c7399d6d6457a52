/* link_predict.c — where each live track is expected in the next frame
 * (step 1 of elfm_link_step, elfm_link.h; also elfm_link_predict for the
 * track-guided searches): the short fit's next point, the slow line, the
 * circle or the turn through a gap, and its gate; whether the recording's
 * objects are at rest, and then the rest hypothesis of a dark track. The
 * fits themselves are link_fit.c's (elfm_link_fit_velocity) and
 * link_circle.c's. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "elfm_analysis.h"
#include "link_internal.h"

/* The gate of a track dark for `missed` frames whose object moves at
 * speed_um_per_ms, frames frame_ms apart. It widens with each missed frame,
 * more for fast objects: an unseen turn moves the object off the
 * extrapolated line by ~ speed x turn angle (speed_gate_frac = 0.3: ~17
 * degrees per frame, flow scene), for at most short_gap frames: beyond, the
 * gate would swallow ghosts (a 50-frame gap at 2.5 um/ms gave a 46 um gate
 * on the stage scene). */
static double track_gate_um(const elfm_link_options *o, int missed, double speed_um_per_ms,
                            double frame_ms)
{
  const int turn_frames = missed < o->short_gap ? missed : o->short_gap;
  return o->gate_um + missed * o->gate_growth_um_per_frame +
         turn_frames * o->speed_gate_frac * speed_um_per_ms * frame_ms;
}

/* The track's last k real points (k >= 4) lie within 2 k frames: an object
 * seen in most frames (a crawling cell), not pulses tens of frames apart (a
 * blinking bead, whose short fit is the better one: blink 200 ms seed 8 lost
 * a pulse with the long straight fit). */
static int seen_densely(const elfm_track *t, int k)
{
  if (k < 4) k = 4;
  if (t->n < (size_t)k) return 0;
  return t->pts[t->n - 1].frame - t->pts[t->n - (size_t)k].frame < 2 * (int64_t)k;
}

/* The next frame's circle (elfm_link_options.circle_next_path_um): points
 * scored before it may predict, and the weight of the newest miss in each
 * mean. Flow 100 ms seeds 1-8, 1 ms / 2 ms frames: the circle preferred
 * at below 0.7 / 1 / 1.3 times the short fit's mean gave alpha 0.8775 /
 * 0.8779 / 0.8781 and 0.7810 / 0.7804 / 0.7815. */
#define CIRCLE_NEXT_MIN_SCORED 3
#define CIRCLE_NEXT_DECAY 0.3

/* Shared with link.c (link_internal.h). */
void elfm_link_score_predictions(const elfm_link_options *o, live_track *lt, const elfm_detection *d)
{
  const double p[3] = {d->x_um, d->y_um, d->z_um};
  double ms = 0, mc = 0;
  for (int a = 0; a < 3; a++) {
    const double s = a == 2 ? 1 / o->kz : 1;
    const double es = (lt->pred_short[a] - p[a]) * s, ec = (lt->pred_circ[a] - p[a]) * s;
    ms += es * es;
    mc += ec * ec;
  }
  if (lt->n_scored == 0) {
    lt->miss2_short = ms;
    lt->miss2_circ = mc;
  } else {
    lt->miss2_short += CIRCLE_NEXT_DECAY * (ms - lt->miss2_short);
    lt->miss2_circ += CIRCLE_NEXT_DECAY * (mc - lt->miss2_circ);
  }
  lt->n_scored++;
}

/* Shared with link.c (link_internal.h). */
void elfm_link_predict_track(const elfm_link_options *o, live_track *lt, int64_t t_us, int at_rest,
                             const double *common_vel)
{
  double dt_ms = (double)(t_us - lt->last_t_us) * 1e-3;
  /* the next frame: the constant-acceleration fit (it keeps the change
   * of speed, e.g. stage_accel); after a miss: the constant-rate turn
   * (flow 100 ms, seeds 1 / 2: alpha 0.589 -> 0.627, 0.552 -> 0.566; with
   * the straight line from short_gap frames on, and the acceleration
   * before, tracks broke where beads turned while unseen) */
  lt->pred_circ_ok = 0;
  if (lt->has_short && lt->missed <= 0) {
    for (int a = 0; a < 3; a++)
      lt->pred[a] = lt->fit_pos[a] + lt->fit_vel[a] * dt_ms + 0.5 * lt->fit_acc[a] * dt_ms * dt_ms;
    if (lt->circ_next.ok) {
      /* both predict; the circle where it has missed less so far
       * (elfm_link_options.circle_next_path_um) */
      memcpy(lt->pred_short, lt->pred, sizeof lt->pred);
      elfm_link_circle_predict(&lt->circ_next, dt_ms, lt->pred_circ);
      lt->pred_circ_ok = 1;
      lt->pred_t_us = t_us;
      if (lt->n_scored >= CIRCLE_NEXT_MIN_SCORED && lt->miss2_circ < lt->miss2_short)
        memcpy(lt->pred, lt->pred_circ, sizeof lt->pred);
    }
  } else if (o->straight_gaps && (common_vel || lt->t->n >= 2)) {
    /* a stage: straight on, at the velocity every object shares where the
     * tracks tell it (a short track's own is mostly its points' noise),
     * else at the track's own (elfm_link_options.straight_gaps) */
    const double *v = common_vel ? common_vel : lt->vel_um_per_ms;
    /* lin_pos: the straight fit's end, the one point itself for n = 1 */
    for (int a = 0; a < 3; a++) lt->pred[a] = lt->lin_pos[a] + v[a] * dt_ms;
  } else if (at_rest && lt->missed >= o->short_gap && seen_densely(lt->t, o->short_history))
    /* Slow objects dark for short_gap frames or more: the long straight
     * fit, not the short one. Over a slow track's 8 points the object
     * moves little more than its placement noise, so the short fit's
     * velocity is mostly the noise of its last points, and over a long gap
     * that noise carries the track off (worm 500 ms seed 3, frames 93-107:
     * two points of a dim neuron pulled 1.2-1.7 um towards its partner 6
     * um away, then 12 dark frames, and its track coasted onto the partner
     * and took it). Predictions of the tracks' own raw points 6 / 15 / 30
     * frames ahead on worm 500 ms seeds 1-3 (2 ms frames), median / p90
     * error in the linker's metric: short fit + turn 1.03 / 2.55, 3.33 /
     * 6.81, 9.08 / 15.52 um; straight line over 20 points 1.08 / 2.17,
     * 2.80 / 4.63, 7.25 / 10.72 um. docs/tracker.md "Slow tracks through
     * long gaps". */
    for (int a = 0; a < 3; a++) lt->pred[a] = lt->lin_pos[a] + lt->vel_um_per_ms[a] * dt_ms;
  else if (lt->circ.ok && lt->missed >= o->circle_after)
    elfm_link_circle_predict(&lt->circ, dt_ms, lt->pred);
  else if (lt->has_short)  /* long gap: keep turning, at constant speed */
    elfm_link_predict_turn(lt->fit_pos, lt->fit_vel, lt->fit_acc, dt_ms, lt->pred);
  else
    for (int a = 0; a < 3; a++) lt->pred[a] = lt->last[a] + lt->vel_um_per_ms[a] * dt_ms;
  const double *cv = lt->has_short ? lt->fit_vel : lt->vel_um_per_ms;
  const double speed = sqrt(cv[0] * cv[0] + cv[1] * cv[1] + cv[2] * cv[2]);
  lt->gate_um = track_gate_um(o, lt->missed, speed, dt_ms / (lt->missed + 1));
  /* a new object's unknown velocity; not where all share one */
  if (lt->t->n == 1 && !(o->straight_gaps && common_vel)) {
    /* over at most birth_frames frame intervals (elfm_link_options) */
    double birth_ms = dt_ms;
    if (o->birth_frames > 0 && lt->missed + 1 > o->birth_frames)
      birth_ms = dt_ms / (lt->missed + 1) * o->birth_frames;
    lt->gate_um += o->birth_speed_um_per_ms * birth_ms;
  }
}

/* Shared with link.c (link_internal.h). */
elfm_status elfm_link_common_velocity(elfm_linker *l, int64_t frame, elfm_error *err)
{
  l->has_common_vel = 0;
  if (l->o.straight_gaps != 1) return ELFM_OK; /* 2: each track its own */
  if (l->n_live > l->cap_vel_scratch) {
    double *p = realloc(l->vel_scratch, l->n_live * sizeof *p);
    if (!p) return elfm_error_set(err, ELFM_ERR_NOMEM, NULL, -1, "link: out of memory");
    l->vel_scratch = p;
    l->cap_vel_scratch = l->n_live;
  }
  for (int a = 0; a < 3; a++) {
    size_t n = 0;
    for (size_t i = 0; i < l->n_live; i++) {
      const live_track *lt = &l->live[i];
      if (lt->t->n >= (size_t)l->o.history && lt->last_frame == frame - 1)
        l->vel_scratch[n++] = lt->vel_um_per_ms[a];
    }
    if (n < 3) return ELFM_OK;
    double spread;
    elfm_analysis_median(l->vel_scratch, n, &l->common_vel[a], &spread);
  }
  l->has_common_vel = 1;
  return ELFM_OK;
}

/* Shared with link.c (link_internal.h). Are the recording's objects at
 * rest, as far as the live tracks tell?
 * Most of those with >= 4 points move slower than rest_speed_um_per_ms by
 * their straight-line fit over up to `history` points, or none has 4 points
 * yet (a blinking recording's first pulses). Not by the short fit: through
 * a static bead's pulses, tight clusters tens of frames apart, its slope at
 * the last point is the clusters' noise (blink seed 8: 0.3-1.4 um/ms, the
 * straight line 0.01-0.03); flow's beads read 2.0 um/ms on the straight
 * line (median; 9.8 % of their track frames below 0.5, seed 1). */
int elfm_link_objects_at_rest(const elfm_linker *l)
{
  const double v2max = l->o.rest_speed_um_per_ms * l->o.rest_speed_um_per_ms;
  size_t n_fit = 0, n_slow = 0;
  for (size_t i = 0; i < l->n_live; i++) {
    const live_track *lt = &l->live[i];
    if (lt->t->n < 4) continue;
    const double *v = lt->vel_um_per_ms;
    n_fit++;
    n_slow += v[0] * v[0] + v[1] * v[1] + v[2] * v[2] < v2max;
  }
  return n_fit == 0 || 2 * n_slow >= n_fit;
}

/* Shared with link.c (link_internal.h). After elfm_link_predict_track. A blinking object's velocity comes from its pulses: a
 * track of 2-3 points has one fitted to points a frame apart, their
 * localisation noise over ~1 ms (0.5-1.5 um/ms for a static bead), and
 * with 4-8 points the short fit's slope and curvature come from tight
 * clusters of points tens of frames apart. Carried over a dark gap of tens
 * of frames either puts the object 13-70 um from where it still is (blink
 * seed 2: the next pulse started new tracks, the first pulses' points were
 * dropped with their short tracks, and two beads were never tracked; seed
 * 8: 10 of 15 beads). Past short_gap frames a track may also have stayed
 * where it was: it is looked for there too, moving with the prior
 * velocity, within the gate less its own speed's term (u-track's
 * undetermined motion, Jaqaman et al. 2008, searches under both
 * hypotheses). Only where the objects are at rest (elfm_link_objects_at_rest): in
 * flow, a dark short track is mostly a ghost's or a deep bead's fragment,
 * and at its old place it took passing beads (ungated, for tracks of 2-3
 * points: flow seeds 1-20 alpha 0.8184 -> 0.8132). */
void elfm_link_predict_rest(const elfm_link_options *o, live_track *lt, int64_t t_us, int at_rest)
{
  lt->has_rest = at_rest && lt->t->n >= 2 && lt->missed > o->short_gap;
  if (!lt->has_rest) return;
  const double dt_ms = (double)(t_us - lt->last_t_us) * 1e-3;
  const double *pv = o->prior_velocity_um_per_ms;
  for (int a = 0; a < 3; a++) lt->rest[a] = lt->last[a] + pv[a] * dt_ms;
  const double pspeed = sqrt(pv[0] * pv[0] + pv[1] * pv[1] + pv[2] * pv[2]);
  lt->rest_gate_um = track_gate_um(o, lt->missed, pspeed, dt_ms / (lt->missed + 1));
}

/* What the last step's detections joined (elfm_link.h): the det_vel rows
 * step 4 of elfm_link_step fills. Detection i's row, or NULL when it has
 * none (out of range, or it joined no track). */
static const double *det_row(const elfm_linker *l, int i)
{
  if (!l || i < 0 || (size_t)i >= l->cap_det || !l->det_vel || l->det_id[i] < 0) return NULL;
  return l->det_vel + LINK_DET_VEL * (size_t)i;
}

double elfm_link_last_speed(const elfm_linker *l, int i)
{
  double v[3];
  if (elfm_link_last_velocity(l, i, v, NULL, NULL) < 2) return NAN;
  return sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
}

double elfm_link_last_miss_um(const elfm_linker *l, int i)
{
  const double *m = det_row(l, i);
  return m ? m[8] : NAN;
}

size_t elfm_link_last_velocity(const elfm_linker *l, int i, double v_um_per_ms[3],
                               double v_long_um_per_ms[3], double *long_span_ms)
{
  for (int a = 0; a < 3; a++) {
    v_um_per_ms[a] = NAN;
    if (v_long_um_per_ms) v_long_um_per_ms[a] = NAN;
  }
  if (long_span_ms) *long_span_ms = NAN;
  const double *m = det_row(l, i);
  if (!m) return 0;
  if (!(m[6] >= 2)) return m[6] >= 1 ? 1 : 0;
  memcpy(v_um_per_ms, m, 3 * sizeof *m);
  if (v_long_um_per_ms) memcpy(v_long_um_per_ms, m + 3, 3 * sizeof *m);
  if (long_span_ms) *long_span_ms = m[7];
  return (size_t)m[6];
}

/* Shared with link.c (link_internal.h). */
double elfm_link_miss_um(const elfm_link_options *o, const double pred[3], const elfm_detection *d)
{
  const double dx = d->x_um - pred[0], dy = d->y_um - pred[1], dz = (d->z_um - pred[2]) / o->kz;
  return sqrt(dx * dx + dy * dy + dz * dz);
}
