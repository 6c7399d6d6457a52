/* cmd_track_vote.c — the shift between consecutive frames' detections, for
 * a stage: --motion auto's test where the tracks cannot tell, and the
 * velocity the stage's new tracks start at (cmd_track_vote.h). */
#include "cmd_track_vote.h"

#include <math.h>
#include <stdlib.h>

#include "cmd_track.h"

int track_votes_wanted(const struct track_opts *o)
{
  return !o->shift_judged && (o->motion_auto || (o->motion == MOTION_STAGE && !o->has_stage_v));
}

int track_votes_init(track_votes *v, double kz)
{
  v->kz = kz;
  v->n_prev = v->n_cur = v->n_pairs = v->n_agree = v->by_shift = v->judged = v->have_v = 0;
  v->prev_t_us = 0;
  v->vel = malloc(3 * TRACK_VOTE_PAIRS * sizeof *v->vel);
  return v->vel != NULL;
}

void track_votes_free(track_votes *v)
{
  free(v->vel);
  v->vel = NULL;
}

void track_votes_point(track_votes *v, const elfm_detection *d)
{
  if (!v->vel || d->weak || !isfinite(d->x_um) || !isfinite(d->y_um) || !isfinite(d->z_um)) return;
  int k = v->n_cur;
  if (k == TRACK_VOTE_POINTS) { /* full: replace the faintest, if fainter */
    k = 0;
    for (int i = 1; i < TRACK_VOTE_POINTS; i++)
      if (v->cur_intensity[i] < v->cur_intensity[k]) k = i;
    if (!(d->intensity > v->cur_intensity[k])) return;
  } else {
    v->n_cur++;
  }
  v->cur[k][0] = d->x_um;
  v->cur[k][1] = d->y_um;
  v->cur[k][2] = d->z_um;
  v->cur_intensity[k] = d->intensity;
}

/* The pair (prev, cur): agreeing or not (cmd_track_vote.h). */
static void vote_pair(track_votes *v, double dt_ms)
{
  int m = 0;
  double d[3], rms;
  if (elfm_analysis_shift_vote(&v->prev[0][0], v->n_prev, &v->cur[0][0], v->n_cur,
                               TRACK_VOTE_TOL_UM, v->kz, &m, d, &rms, NULL) != ELFM_OK)
    return;
  v->n_pairs++;
  const int n_min = v->n_prev < v->n_cur ? v->n_prev : v->n_cur;
  const double len = sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2] / (v->kz * v->kz));
  if (m < TRACK_VOTE_MIN_POINTS || m < TRACK_VOTE_MIN_SHARE * n_min ||
      !(len >= TRACK_VOTE_MIN_SHIFT_UM) || !(rms <= TRACK_RIGID_MAX_DEV * len))
    return;
  for (int a = 0; a < 3; a++) v->vel[3 * v->n_agree + a] = d[a] / dt_ms;
  v->n_agree++;
}

void track_votes_end_frame(track_votes *v, int64_t t_us)
{
  if (v->n_cur >= TRACK_VOTE_MIN_POINTS) {
    const double dt_ms = 1e-3 * (double)(t_us - v->prev_t_us);
    if (v->n_prev > 0 && dt_ms > 0 && dt_ms <= TRACK_VOTE_MAX_GAP_MS && v->vel &&
        v->n_pairs < TRACK_VOTE_PAIRS)
      vote_pair(v, dt_ms);
    for (int i = 0; i < v->n_cur; i++)
      for (int a = 0; a < 3; a++) v->prev[i][a] = v->cur[i][a];
    v->n_prev = v->n_cur;
    v->prev_t_us = t_us;
  }
  v->n_cur = 0;
}

int track_votes_judge(track_votes *v, int at_end, double *speed, double *abs_um_per_ms,
                      double *dev)
{
  if (!v->vel) return 0;
  if (v->judged) {
    if (!v->have_v) return 0;
    double s2 = 0;
    for (int a = 0; a < 3; a++) s2 += v->v_um_per_ms[a] * v->v_um_per_ms[a];
    *speed = sqrt(s2);
    *abs_um_per_ms = v->abs_um_per_ms;
    *dev = v->abs_um_per_ms / *speed;
    return 1;
  }
  if (v->n_pairs < TRACK_VOTE_PAIRS && !(at_end && v->n_pairs >= TRACK_VOTE_MIN_PAIRS)) {
    if (!at_end) return -1;
    v->judged = 1; /* the frames ended with too few pairs: no stage by them */
    return 0;
  }
  v->judged = 1;
  const int n = v->n_agree;
  if (n < TRACK_VOTE_MIN_SHARE * v->n_pairs) return 0;
  double med[3], spread, col[TRACK_VOTE_PAIRS];
  for (int a = 0; a < 3; a++) {
    for (int i = 0; i < n; i++) col[i] = v->vel[3 * i + a];
    elfm_analysis_median(col, (size_t)n, &med[a], &spread);
  }
  const double s = sqrt(med[0] * med[0] + med[1] * med[1] + med[2] * med[2]);
  for (int i = 0; i < n; i++) {
    const double *w = v->vel + 3 * i;
    col[i] = sqrt((w[0] - med[0]) * (w[0] - med[0]) + (w[1] - med[1]) * (w[1] - med[1]) +
                  (w[2] - med[2]) * (w[2] - med[2]));
  }
  double a_med;
  elfm_analysis_median(col, (size_t)n, &a_med, &spread);
  if (!(s >= TRACK_RIGID_MIN_SPEED_UM_PER_MS) || !(a_med < TRACK_RIGID_MAX_DEV * s)) return 0;
  for (int a = 0; a < 3; a++) v->v_um_per_ms[a] = med[a];
  v->abs_um_per_ms = a_med;
  v->have_v = 1;
  *speed = s;
  *abs_um_per_ms = a_med;
  *dev = a_med / s;
  return 1;
}
