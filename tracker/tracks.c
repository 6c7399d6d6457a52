/* tracks.c — the track type and the store of finished tracks (see
 * elfm_tracks.h). */
#include "elfm_tracks.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

const char *elfm_motion_model_name(elfm_motion_model m)
{
  switch (m) {
  case ELFM_MODEL_AUTO: return "auto";
  case ELFM_MODEL_CONST_VELOCITY: return "constant_velocity";
  case ELFM_MODEL_CONST_ACCEL: return "constant_acceleration";
  case ELFM_MODEL_SPLINE: return "spline";
  case ELFM_MODEL_STATIC: return "static";
  }
  return "unknown";
}

elfm_track *elfm_track_create(int64_t id, elfm_error *err)
{
  elfm_track *t = calloc(1, sizeof *t);
  if (!t) elfm_error_set(err, ELFM_ERR_NOMEM, NULL, -1, "track: out of memory");
  else t->id = id;
  return t;
}

void elfm_track_free(elfm_track *t)
{
  if (!t) return;
  free(t->pts);
  free(t->span_t_us);
  free(t->pos_um);
  free(t->vel_um_per_ms);
  free(t->pos_sd_um);
  free(t->vel_sd_um_per_ms);
  free(t->raw_index);
  free(t);
}

elfm_status elfm_track_append(elfm_track *t, const elfm_detection *d, elfm_error *err)
{
  if (t->n && d->frame <= t->pts[t->n - 1].frame)
    return elfm_error_set(err, ELFM_ERR_INVALID, NULL, -1,
                          "track %lld: frame %lld after frame %lld", (long long)t->id,
                          (long long)d->frame, (long long)t->pts[t->n - 1].frame);
  if (t->n == t->cap) {
    /* doubling: amortised O(1), the track is the one thing allowed to grow */
    size_t cap = t->cap ? 2 * t->cap : 16;
    elfm_detection *p = realloc(t->pts, cap * sizeof *p);
    if (!p) return elfm_error_set(err, ELFM_ERR_NOMEM, NULL, -1, "track: out of memory");
    t->pts = p;
    t->cap = cap;
  }
  t->pts[t->n++] = *d;
  return ELFM_OK;
}

elfm_status elfm_track_insert(elfm_track *t, const elfm_detection *d, elfm_error *err)
{
  /* the first point not before d's frame (binary search: the track is in frame order) */
  size_t lo = 0, hi = t->n;
  while (lo < hi) {
    size_t mid = lo + (hi - lo) / 2;
    if (t->pts[mid].frame < d->frame) lo = mid + 1;
    else hi = mid;
  }
  if (lo < t->n && t->pts[lo].frame == d->frame)
    return elfm_error_set(err, ELFM_ERR_INVALID, NULL, -1, "track %lld: frame %lld already has a point",
                          (long long)t->id, (long long)d->frame);
  if (lo == t->n) return elfm_track_append(t, d, err);
  if (t->n == t->cap) {
    elfm_detection *p = realloc(t->pts, 2 * t->cap * sizeof *p); /* cap >= 1 here: n >= 1 */
    if (!p) return elfm_error_set(err, ELFM_ERR_NOMEM, NULL, -1, "track: out of memory");
    t->pts = p;
    t->cap *= 2;
  }
  memmove(&t->pts[lo + 1], &t->pts[lo], (t->n - lo) * sizeof *t->pts);
  t->n++;
  t->pts[lo] = *d;
  return ELFM_OK;
}

void elfm_track_mean_velocity(const elfm_track *t, double v[3])
{
  v[0] = v[1] = v[2] = 0;
  if (!t || !t->n_span || !t->vel_um_per_ms) return;
  for (size_t k = 0; k < t->n_span; k++)
    for (int a = 0; a < 3; a++) v[a] += t->vel_um_per_ms[3 * k + a];
  for (int a = 0; a < 3; a++) v[a] /= (double)t->n_span;
}

void elfm_track_info_get(const elfm_track *t, elfm_track_info *o)
{
  memset(o, 0, sizeof *o);
  o->id = t->id;
  o->n_pieces = 1;
  for (size_t j = 0; j < t->n; j++) {
    if (!elfm_track_writes_frame(t, t->pts[j].frame)) continue;
    if (!o->n) o->first_frame = t->pts[j].frame;
    o->last_frame = t->pts[j].frame;
    o->n++;
  }
  o->model = t->model;
  o->spline_weight_ms3 = t->spline_weight_ms3;
  o->spline_omega_rad_per_ms = t->spline_omega_rad_per_ms;
  o->edf = t->edf;
  o->model_n = o->n;
  o->n_outliers = t->n_outliers;
  o->mean_lateral_speed_um_per_ms = NAN;
  if (!t->n_span || !t->vel_um_per_ms || !t->n) return;
  /* the same sums, in the same order, as elfm_track_mean_velocity */
  double lat = 0;
  for (size_t k = 0; k < t->n_span; k++) {
    if (!elfm_track_writes_frame(t, t->pts[0].frame + (int64_t)k)) continue;
    for (int a = 0; a < 3; a++) o->mean_vel_um_per_ms[a] += t->vel_um_per_ms[3 * k + a];
    lat += hypot(t->vel_um_per_ms[3 * k], t->vel_um_per_ms[3 * k + 1]);
    o->n_rows++;
  }
  if (!o->n_rows) return;
  o->smoothed = 1;
  if (t->pos_um)
    for (size_t j = 0; j < t->n; j++) {
      const int64_t k = t->pts[j].frame - t->pts[0].frame;
      if (!elfm_track_writes_frame(t, t->pts[j].frame) || k < 0 || (size_t)k >= t->n_span) continue;
      const double r[3] = {t->pts[j].x_um - t->pos_um[3 * k], t->pts[j].y_um - t->pos_um[3 * k + 1],
                           t->pts[j].z_um - t->pos_um[3 * k + 2]};
      if (!(isfinite(r[0]) && isfinite(r[1]) && isfinite(r[2]))) continue;
      for (int a = 0; a < 3; a++) {
        o->s_res_um[a] += r[a];
        o->s_res2_um2[a] += r[a] * r[a];
      }
      o->n_res++;
    }
  for (int a = 0; a < 3; a++) o->mean_vel_um_per_ms[a] /= (double)o->n_rows;
  if (isfinite(lat)) o->mean_lateral_speed_um_per_ms = lat / (double)o->n_rows;
  /* One frame: the smoother's static fit says velocity 0, a model's value,
   * not a measurement (elfm_track_velocity_known) */
  const int vk = elfm_track_velocity_known(t);
  if (!vk) {
    for (int a = 0; a < 3; a++) o->mean_vel_um_per_ms[a] = NAN;
    o->mean_lateral_speed_um_per_ms = NAN;
  }
  if (!t->span_t_us) return;
  /* times from the first row's, so that 1e12 us absolute times lose nothing */
  const int64_t t0 = t->span_t_us[0];
  double st = 0;
  for (size_t k = 0; k < t->n_span; k++)
    if (elfm_track_writes_frame(t, t->pts[0].frame + (int64_t)k)) st += 1e-3 * (double)(t->span_t_us[k] - t0);
  const double mt_ms = st / (double)o->n_rows;
  o->mean_t_us = (double)t0 + 1e3 * mt_ms;
  for (size_t k = 0; k < t->n_span; k++) {
    if (!elfm_track_writes_frame(t, t->pts[0].frame + (int64_t)k)) continue;
    const double dt = 1e-3 * (double)(t->span_t_us[k] - t0) - mt_ms;
    o->s_tt_ms2 += dt * dt;
    if (vk)
      for (int a = 0; a < 3; a++) o->s_tv_um[a] += dt * (t->vel_um_per_ms[3 * k + a] - o->mean_vel_um_per_ms[a]);
  }
}

void elfm_track_info_merge(elfm_track_info *acc, const elfm_track_info *p)
{
  if (!p->n) return;
  if (!acc->n) acc->first_frame = p->first_frame;
  if (p->model_n > acc->model_n) { /* the largest piece speaks for the track's model */
    acc->model = p->model;
    acc->spline_weight_ms3 = p->spline_weight_ms3;
    acc->spline_omega_rad_per_ms = p->spline_omega_rad_per_ms;
    acc->edf = p->edf;
    acc->model_n = p->model_n;
  }
  const double r0 = (double)acc->n_rows, r1 = (double)p->n_rows;
  if (r0 > 0 && r1 > 0) {
    /* the two groups' sums about the joint mean (before the means move) */
    const double dt_ms = 1e-3 * (p->mean_t_us - acc->mean_t_us), f = r0 * r1 / (r0 + r1);
    acc->s_tt_ms2 += p->s_tt_ms2 + f * dt_ms * dt_ms;
    for (int a = 0; a < 3; a++)
      acc->s_tv_um[a] += p->s_tv_um[a] + f * dt_ms * (p->mean_vel_um_per_ms[a] - acc->mean_vel_um_per_ms[a]);
    acc->mean_t_us += r1 / (r0 + r1) * (p->mean_t_us - acc->mean_t_us);
  } else if (r1 > 0) {
    acc->mean_t_us = p->mean_t_us;
    acc->s_tt_ms2 = p->s_tt_ms2;
    for (int a = 0; a < 3; a++) acc->s_tv_um[a] = p->s_tv_um[a];
  }
  if (r0 + r1 > 0) {
    for (int a = 0; a < 3; a++)
      acc->mean_vel_um_per_ms[a] =
          (r0 * acc->mean_vel_um_per_ms[a] + r1 * p->mean_vel_um_per_ms[a]) / (r0 + r1);
    const double l0 = acc->n_rows ? acc->mean_lateral_speed_um_per_ms : 0,
                 l1 = p->n_rows ? p->mean_lateral_speed_um_per_ms : 0;
    acc->mean_lateral_speed_um_per_ms = (r0 * l0 + r1 * l1) / (r0 + r1);
  }
  acc->smoothed |= p->smoothed;
  acc->n_res += p->n_res;
  for (int a = 0; a < 3; a++) {
    acc->s_res_um[a] += p->s_res_um[a];
    acc->s_res2_um2[a] += p->s_res2_um2[a];
  }
  acc->last_frame = p->last_frame;
  acc->n += p->n;
  acc->n_rows += p->n_rows;
  acc->n_outliers += p->n_outliers;
  acc->n_pieces += p->n_pieces;
}

void elfm_track_store_init(elfm_track_store *s) { memset(s, 0, sizeof *s); }

elfm_status elfm_track_store_add(elfm_track_store *s, elfm_track *t, elfm_error *err)
{
  if (s->n == s->cap) {
    size_t cap = s->cap ? 2 * s->cap : 64;
    elfm_track **p = realloc(s->tracks, cap * sizeof *p);
    if (!p) {
      elfm_track_free(t);
      return elfm_error_set(err, ELFM_ERR_NOMEM, NULL, -1, "track store: out of memory");
    }
    s->tracks = p;
    s->cap = cap;
  }
  s->tracks[s->n++] = t;
  return ELFM_OK;
}

void elfm_track_store_clear(elfm_track_store *s)
{
  for (size_t i = 0; i < s->n; i++) elfm_track_free(s->tracks[i]);
  free(s->tracks);
  elfm_track_store_init(s);
}
