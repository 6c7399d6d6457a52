/* scene.c — scene files: find (built-in name or path), parse and check every
 * field with cJSON, --param overrides, accessors.
 *
 * Every key must be present (a scene file is the full record of what was
 * simulated); each is checked for type, finiteness and range, and errors
 * name the source and the key path ("sensor.refractory_us"). Units follow
 * the names; speeds are given in mm/s (= um/ms, how stages are specified)
 * and converted here to um/us.
 */
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <cjson/cJSON.h>

#include "sim_internal.h"

typedef struct scene_ctx {
  const char *src;
  elfm_error *err;
} scene_ctx;

static elfm_status bad_key(scene_ctx *c, elfm_status code, const char *key, const char *fmt,
                           double v)
{
  char what[200];
  snprintf(what, sizeof what, fmt, v);
  return elfm_error_set(c->err, code, c->src, -1, "key \"%s\": %s", key, what);
}

/* Join a parent path and a child name into buf. */
static const char *kpath(char *buf, size_t n, const char *parent, const char *name)
{
  if (parent && *parent) snprintf(buf, n, "%s.%s", parent, name);
  else snprintf(buf, n, "%s", name);
  return buf;
}

static elfm_status get_item(scene_ctx *c, const cJSON *obj, const char *parent, const char *name,
                            const cJSON **out)
{
  char key[160];
  const cJSON *it = cJSON_GetObjectItemCaseSensitive(obj, name);
  if (!it) return bad_key(c, ELFM_ERR_FORMAT, kpath(key, sizeof key, parent, name), "missing", 0);
  *out = it;
  return ELFM_OK;
}

static elfm_status check_num(scene_ctx *c, const cJSON *it, const char *key, double lo, double hi,
                             double *out)
{
  if (!cJSON_IsNumber(it)) return bad_key(c, ELFM_ERR_FORMAT, key, "not a number", 0);
  double v = it->valuedouble;
  if (!isfinite(v)) return bad_key(c, ELFM_ERR_RANGE, key, "not finite", 0);
  if (v < lo || v > hi) {
    return elfm_error_set(c->err, ELFM_ERR_RANGE, c->src, -1, "key \"%s\": %.17g outside [%g, %g]",
                          key, v, lo, hi);
  }
  *out = v;
  return ELFM_OK;
}

static elfm_status get_num(scene_ctx *c, const cJSON *obj, const char *parent, const char *name,
                           double lo, double hi, double *out)
{
  const cJSON *it = NULL;
  char key[160];
  elfm_status st = get_item(c, obj, parent, name, &it);
  if (st) return st;
  return check_num(c, it, kpath(key, sizeof key, parent, name), lo, hi, out);
}

static elfm_status get_int64(scene_ctx *c, const cJSON *obj, const char *parent, const char *name,
                             double lo, double hi, int64_t *out)
{
  double v = 0;
  char key[160];
  elfm_status st = get_num(c, obj, parent, name, lo, hi, &v);
  if (st) return st;
  if (v != floor(v))
    return bad_key(c, ELFM_ERR_FORMAT, kpath(key, sizeof key, parent, name), "not an integer", 0);
  *out = (int64_t)v;
  return ELFM_OK;
}

static elfm_status get_intv(scene_ctx *c, const cJSON *obj, const char *parent, const char *name,
                            int lo, int hi, int *out)
{
  int64_t v = 0;
  elfm_status st = get_int64(c, obj, parent, name, lo, hi, &v);
  if (!st) *out = (int)v;
  return st;
}

/* [lo, hi] pair, both in [min, max], lo <= hi. */
static elfm_status get_range(scene_ctx *c, const cJSON *obj, const char *parent, const char *name,
                             double min, double max, double *lo, double *hi)
{
  const cJSON *it = NULL;
  char key[160], ek[176];
  elfm_status st = get_item(c, obj, parent, name, &it);
  if (st) return st;
  kpath(key, sizeof key, parent, name);
  if (!cJSON_IsArray(it) || cJSON_GetArraySize(it) != 2)
    return bad_key(c, ELFM_ERR_FORMAT, key, "not an array [min, max]", 0);
  snprintf(ek, sizeof ek, "%s[0]", key);
  if ((st = check_num(c, cJSON_GetArrayItem(it, 0), ek, min, max, lo))) return st;
  snprintf(ek, sizeof ek, "%s[1]", key);
  if ((st = check_num(c, cJSON_GetArrayItem(it, 1), ek, min, max, hi))) return st;
  if (*hi < *lo) return bad_key(c, ELFM_ERR_RANGE, key, "max below min", 0);
  return ELFM_OK;
}

static elfm_status get_obj(scene_ctx *c, const cJSON *obj, const char *name, const cJSON **out)
{
  elfm_status st = get_item(c, obj, NULL, name, out);
  if (st) return st;
  if (!cJSON_IsObject(*out)) return bad_key(c, ELFM_ERR_FORMAT, name, "not an object", 0);
  return ELFM_OK;
}

static elfm_status get_string(scene_ctx *c, const cJSON *obj, const char *parent, const char *name,
                              const char **out)
{
  const cJSON *it = NULL;
  char key[160];
  elfm_status st = get_item(c, obj, parent, name, &it);
  if (st) return st;
  if (!cJSON_IsString(it) || !it->valuestring)
    return bad_key(c, ELFM_ERR_FORMAT, kpath(key, sizeof key, parent, name), "not a string", 0);
  *out = it->valuestring;
  return ELFM_OK;
}

/* mm/s -> um/us: 1 mm/s = 1000 um / 1e6 us. */
#define MM_PER_S_TO_UM_PER_US 1e-3

static elfm_status parse_optics(scene_ctx *c, const cJSON *root, elfm_scene *s)
{
  const cJSON *o = NULL, *sen = NULL;
  elfm_status st;
  elfm_optics op;
  double pixel_um = 0;
  if ((st = get_obj(c, root, "optics", &o))) return st;
  if ((st = get_num(c, o, "optics", "na", 0.01, 1.6, &op.na))) return st;
  if ((st = get_num(c, o, "optics", "n_medium", 1.0, 2.0, &op.n_medium))) return st;
  if (op.na >= op.n_medium) return bad_key(c, ELFM_ERR_RANGE, "optics.na", "must be < n_medium", 0);
  if ((st = get_num(c, o, "optics", "magnification", 0.1, 1000, &op.magnification))) return st;
  if ((st = get_num(c, o, "optics", "f_tube_mm", 1, 1000, &op.f_tube_mm))) return st;
  if ((st = get_num(c, o, "optics", "f_fourier_mm", 1, 1000, &op.f_fourier_mm))) return st;
  if ((st = get_num(c, o, "optics", "f_mla_mm", 0.1, 1000, &op.f_mla_mm))) return st;
  if ((st = get_num(c, o, "optics", "mla_pitch_um", 1, 10000, &op.mla_pitch_um))) return st;
  if ((st = get_num(c, o, "optics", "relay", 0.01, 100, &op.relay))) return st;
  if ((st = get_num(c, o, "optics", "wavelength_um", 0.2, 2.0, &op.wavelength_um))) return st;
  if ((st = get_intv(c, o, "optics", "lenslets_per_side", 1, 9, &op.lenslets_per_side))) return st;
  if (op.lenslets_per_side % 2 == 0)
    return bad_key(c, ELFM_ERR_RANGE, "optics.lenslets_per_side", "must be odd", 0);
  /* optional: a lens array turned against the sensor's rows (elfm_optics) */
  op.mla_rotation_deg = 0.0;
  if (cJSON_GetObjectItemCaseSensitive(o, "mla_rotation_deg") &&
      (st = get_num(c, o, "optics", "mla_rotation_deg", -45, 45, &op.mla_rotation_deg)))
    return st;

  sim_sensor *ss = &s->sensor;
  if ((st = get_obj(c, root, "sensor", &sen))) return st;
  /* 2048: EVT 3.0 addresses 11-bit x and y. */
  if ((st = get_intv(c, sen, "sensor", "width", 16, 2048, &ss->width))) return st;
  if ((st = get_intv(c, sen, "sensor", "height", 16, 2048, &ss->height))) return st;
  if ((st = get_num(c, sen, "sensor", "pixel_um", 0.5, 100, &pixel_um))) return st;
  if ((st = get_num(c, sen, "sensor", "threshold_on", 0.01, 5, &ss->threshold_on))) return st;
  if ((st = get_num(c, sen, "sensor", "threshold_off", 0.01, 5, &ss->threshold_off))) return st;
  if ((st = get_num(c, sen, "sensor", "threshold_sigma", 0, 1, &ss->threshold_sigma))) return st;
  if ((st = get_num(c, sen, "sensor", "refractory_us", 0, 1e5, &ss->refractory_us))) return st;
  if ((st = get_num(c, sen, "sensor", "latency_us", 0, 1e5, &ss->latency_us))) return st;
  if ((st = get_num(c, sen, "sensor", "jitter_us", 0, 1e4, &ss->jitter_us))) return st;
  if ((st = get_num(c, sen, "sensor", "cutoff_hz_at_background", 1, 1e7,
                    &ss->cutoff_hz_at_background)))
    return st;
  if ((st = get_num(c, sen, "sensor", "cutoff_hz_max", 1, 1e7, &ss->cutoff_hz_max))) return st;
  if (ss->cutoff_hz_max < ss->cutoff_hz_at_background)
    return bad_key(c, ELFM_ERR_RANGE, "sensor.cutoff_hz_max", "below cutoff_hz_at_background", 0);
  if ((st = get_num(c, sen, "sensor", "shot_noise_hz", 0, 1000, &ss->shot_noise_hz))) return st;
  if ((st = get_num(c, sen, "sensor", "leak_hz", 0, 1000, &ss->leak_hz))) return st;
  if ((st = get_intv(c, sen, "sensor", "hot_pixels", 0, 64, &ss->hot_pixels))) return st;
  if ((st = get_num(c, sen, "sensor", "hot_pixel_hz", 0, 1e5, &ss->hot_pixel_hz))) return st;

  elfm_error e2;
  elfm_error_clear(&e2);
  if (elfm_calib_from_optics(&op, ss->width, ss->height, pixel_um, &s->calib, &e2))
    return elfm_error_set(c->err, ELFM_ERR_RANGE, c->src, -1, "key \"optics\": %s", e2.message);
  return ELFM_OK;
}

static elfm_status parse_motion(scene_ctx *c, const cJSON *root, elfm_scene *s)
{
  const cJSON *m = NULL, *dir = NULL;
  const char *type = NULL;
  elfm_status st;
  const char *P = "motion";
  if ((st = get_obj(c, root, "motion", &m))) return st;
  if ((st = get_string(c, m, P, "type", &type))) return st;
  if (!strcmp(type, "static")) {
    s->motion = SIM_MOTION_STATIC;
  } else if (!strcmp(type, "stage")) {
    s->motion = SIM_MOTION_STAGE;
  } else if (!strcmp(type, "zsweep")) {
    s->motion = SIM_MOTION_ZSWEEP;
  } else if (!strcmp(type, "helix")) {
    s->motion = SIM_MOTION_HELIX;
  } else if (!strcmp(type, "worm")) {
    s->motion = SIM_MOTION_WORM;
  } else if (!strcmp(type, "random")) {
    s->motion = SIM_MOTION_RANDOM;
  } else {
    return elfm_error_set(c->err, ELFM_ERR_FORMAT, c->src, -1,
                          "key \"motion.type\": unknown \"%s\" (static, stage, zsweep, helix, "
                          "worm, random)",
                          type);
  }
  /* Placement extent: every motion but zsweep places objects at random. */
  if (s->motion != SIM_MOTION_ZSWEEP) {
    /* A stage phantom is a slab (half_width_um, period_um) instead. */
    if (s->motion != SIM_MOTION_STAGE &&
        (st = get_num(c, m, P, "place_radius_um", 0, 1000, &s->place_radius_um)))
      return st;
    if ((st = get_num(c, m, P, "z_min_um", -1000, 1000, &s->z_min_um))) return st;
    if ((st = get_num(c, m, P, "z_max_um", -1000, 1000, &s->z_max_um))) return st;
    if (s->z_max_um < s->z_min_um)
      return bad_key(c, ELFM_ERR_RANGE, "motion.z_max_um", "below z_min_um", 0);
  }
  double a, b;
  switch (s->motion) {
  case SIM_MOTION_STATIC: break;
  case SIM_MOTION_STAGE:
    if ((st = get_item(c, m, P, "direction", &dir))) return st;
    if (!cJSON_IsArray(dir) || cJSON_GetArraySize(dir) != 3)
      return bad_key(c, ELFM_ERR_FORMAT, "motion.direction", "not an array [x, y, z]", 0);
    {
      double n2 = 0;
      for (int k = 0; k < 3; k++) {
        char ek[48];
        snprintf(ek, sizeof ek, "motion.direction[%d]", k);
        if ((st = check_num(c, cJSON_GetArrayItem(dir, k), ek, -1e3, 1e3, &s->stage_dir[k])))
          return st;
        n2 += s->stage_dir[k] * s->stage_dir[k];
      }
      if (n2 < 1e-12) return bad_key(c, ELFM_ERR_RANGE, "motion.direction", "zero vector", 0);
      for (int k = 0; k < 3; k++) s->stage_dir[k] /= sqrt(n2);
    }
    /* 50 mm/s: ten times the fastest stage of the paper. */
    if ((st = get_num(c, m, P, "v0_mm_per_s", 0, 50, &a))) return st;
    s->stage_v0_um_per_us = a * MM_PER_S_TO_UM_PER_US;
    if ((st = get_num(c, m, P, "v1_mm_per_s", 0, 50, &a))) return st;
    s->stage_v1_um_per_us = a * MM_PER_S_TO_UM_PER_US;
    /* mm/s^2 -> um/us^2: 1e3 um / 1e12 us^2. */
    if ((st = get_num(c, m, P, "accel_mm_per_s2", 0, 1e4, &a))) return st;
    s->stage_accel_um_per_us2 = a * 1e-9;
    if (s->stage_v1_um_per_us != s->stage_v0_um_per_us && s->stage_accel_um_per_us2 <= 0)
      return bad_key(c, ELFM_ERR_RANGE, "motion.accel_mm_per_s2",
                     "must be > 0 when v1 differs from v0", 0);
    if (s->stage_v1_um_per_us < s->stage_v0_um_per_us)
      return bad_key(c, ELFM_ERR_RANGE, "motion.v1_mm_per_s", "below v0 (stages accelerate)", 0);
    if ((st = get_num(c, m, P, "period_um", 1, 1e4, &s->stage_period_um))) return st;
    if ((st = get_num(c, m, P, "half_width_um", 0, 1e4, &s->stage_half_width_um))) return st;
    break;
  case SIM_MOTION_ZSWEEP:
    if ((st = get_num(c, m, P, "x_um", -1000, 1000, &s->sweep_x_um))) return st;
    if ((st = get_num(c, m, P, "y_um", -1000, 1000, &s->sweep_y_um))) return st;
    /* optional: the slide tilted about y, its beads (side by side along x)
     * each at its own depth */
    s->sweep_tilt_deg = 0;
    if (cJSON_GetObjectItemCaseSensitive(m, "tilt_deg") &&
        (st = get_num(c, m, P, "tilt_deg", -45, 45, &s->sweep_tilt_deg)))
      return st;
    if ((st = get_num(c, m, P, "z_from_um", -1000, 1000, &s->sweep_z_from_um))) return st;
    if ((st = get_num(c, m, P, "z_to_um", -1000, 1000, &s->sweep_z_to_um))) return st;
    if ((st = get_num(c, m, P, "speed_mm_per_s", 1e-6, 50, &a))) return st;
    s->sweep_speed_um_per_us = a * MM_PER_S_TO_UM_PER_US;
    if (s->sweep_z_to_um == s->sweep_z_from_um)
      return bad_key(c, ELFM_ERR_RANGE, "motion.z_to_um", "equals z_from_um", 0);
    /* optional: the beads scattered at random over a disc of this radius
     * about (x_um, y_um), as on a calibration slide, instead of in a row */
    s->place_radius_um = 0;
    if (cJSON_GetObjectItemCaseSensitive(m, "place_radius_um") &&
        (st = get_num(c, m, P, "place_radius_um", 0, 1000, &s->place_radius_um)))
      return st;
    s->z_min_um = fmin(s->sweep_z_from_um, s->sweep_z_to_um);
    s->z_max_um = fmax(s->sweep_z_from_um, s->sweep_z_to_um);
    break;
  case SIM_MOTION_HELIX:
    if ((st = get_range(c, m, P, "speed_mm_per_s", 1e-3, 50, &a, &b))) return st;
    s->helix_speed_min = a * MM_PER_S_TO_UM_PER_US;
    s->helix_speed_max = b * MM_PER_S_TO_UM_PER_US;
    if ((st = get_range(c, m, P, "radius_um", 0.5, 500, &s->helix_radius_min_um,
                        &s->helix_radius_max_um)))
      return st;
    if ((st = get_num(c, m, P, "axial_amp_um", 0, 500, &s->helix_axial_amp_max_um))) return st;
    if ((st = get_range(c, m, P, "axial_period_ms", 0.1, 1e5, &a, &b))) return st;
    s->helix_axial_period_min_us = a * 1e3;
    s->helix_axial_period_max_us = b * 1e3;
    break;
  case SIM_MOTION_RANDOM:
    if ((st = get_range(c, m, P, "speed_mm_per_s", 1e-3, 50, &a, &b))) return st;
    s->random_speed_min = a * MM_PER_S_TO_UM_PER_US;
    s->random_speed_max = b * MM_PER_S_TO_UM_PER_US;
    if ((st = get_range(c, m, P, "period_ms", 0.1, 1e5, &a, &b))) return st;
    s->random_period_min_us = a * 1e3;
    s->random_period_max_us = b * 1e3;
    if ((st = get_intv(c, m, P, "modes", 1, SIM_RANDOM_MODES_MAX, &s->random_modes))) return st;
    break;
  case SIM_MOTION_WORM:
    if ((st = get_num(c, m, P, "crawl_mm_per_s", 0, 10, &a))) return st;
    s->worm_crawl_um_per_us = a * MM_PER_S_TO_UM_PER_US;
    if ((st = get_num(c, m, P, "wave_amp_um", 0, 200, &s->worm_wave_amp_um))) return st;
    if ((st = get_num(c, m, P, "wavelength_um", 1, 5000, &s->worm_wavelength_um))) return st;
    if ((st = get_num(c, m, P, "z_amp_um", 0, 500, &s->worm_z_amp_um))) return st;
    if ((st = get_num(c, m, P, "z_period_ms", 0.1, 1e6, &a))) return st;
    s->worm_z_period_us = a * 1e3;
    {
      const cJSON *ns = NULL;
      if ((st = get_item(c, m, P, "neuron_s_um", &ns))) return st;
      if (!cJSON_IsArray(ns) || cJSON_GetArraySize(ns) != 4)
        return bad_key(c, ELFM_ERR_FORMAT, "motion.neuron_s_um",
                       "not an array of 4 body positions (2 tail, 2 mid-body)", 0);
      for (int k = 0; k < 4; k++) {
        char ek[48];
        snprintf(ek, sizeof ek, "motion.neuron_s_um[%d]", k);
        if ((st = check_num(c, cJSON_GetArrayItem(ns, k), ek, 0, 1000, &s->worm_neuron_s_um[k])))
          return st;
      }
    }
    if (s->n_objects % 4 != 0)
      return bad_key(c, ELFM_ERR_RANGE, "objects.count", "must be a multiple of 4 (neurons per worm)",
                     0);
    break;
  }
  return ELFM_OK;
}

static elfm_status parse_light(scene_ctx *c, const cJSON *root, elfm_scene *s)
{
  const cJSON *il = NULL, *sp = NULL;
  const char *type = NULL;
  elfm_status st;
  double a, b;
  if ((st = get_obj(c, root, "illumination", &il))) return st;
  if ((st = get_string(c, il, "illumination", "type", &type))) return st;
  if (!strcmp(type, "constant")) {
    s->illum = SIM_ILLUM_CONSTANT;
  } else if (!strcmp(type, "random_pulses")) {
    s->illum = SIM_ILLUM_RANDOM_PULSES;
    if ((st = get_num(c, il, "illumination", "pulse_us", 1, 1e7, &s->illum_pulse_us))) return st;
    if ((st = get_range(c, il, "illumination", "gap_us", 1, 1e8, &s->illum_gap_min_us,
                        &s->illum_gap_max_us)))
      return st;
  } else if (!strcmp(type, "periodic")) {
    s->illum = SIM_ILLUM_PERIODIC;
    if ((st = get_num(c, il, "illumination", "pulse_us", 1, 1e7, &s->illum_pulse_us))) return st;
    if ((st = get_num(c, il, "illumination", "period_us", 2, 1e8, &s->illum_period_us))) return st;
    if (s->illum_period_us <= s->illum_pulse_us)
      return bad_key(c, ELFM_ERR_RANGE, "illumination.period_us", "must exceed pulse_us", 0);
  } else {
    return elfm_error_set(c->err, ELFM_ERR_FORMAT, c->src, -1,
                          "key \"illumination.type\": unknown \"%s\" (constant, random_pulses, periodic)",
                          type);
  }
  /* Pulse times are whole microseconds (the event clock). */
  s->illum_pulse_us = floor(s->illum_pulse_us);

  if ((st = get_item(c, root, NULL, "spikes", &sp))) return st;
  if (cJSON_IsNull(sp)) {
    s->has_spikes = 0;
  } else if (cJSON_IsObject(sp)) {
    s->has_spikes = 1;
    if ((st = get_range(c, sp, "spikes", "pulse_us", 1, 1e7, &a, &b))) return st;
    s->spike_pulse_min_us = a;
    s->spike_pulse_max_us = b;
    if ((st = get_range(c, sp, "spikes", "gap_us", 1, 1e8, &a, &b))) return st;
    s->spike_gap_min_us = a;
    s->spike_gap_max_us = b;
    if ((st = get_num(c, sp, "spikes", "baseline", 0, 1, &s->spike_baseline))) return st;
  } else {
    return bad_key(c, ELFM_ERR_FORMAT, "spikes", "must be null or an object", 0);
  }
  return ELFM_OK;
}

static elfm_status parse_scene(scene_ctx *c, const cJSON *root, elfm_scene *s)
{
  elfm_status st;
  const char *name = NULL, *desc = NULL;
  const cJSON *o = NULL;
  double a;
  if (!cJSON_IsObject(root))
    return elfm_error_set(c->err, ELFM_ERR_FORMAT, c->src, 0, "top level is not a JSON object");
  if ((st = get_string(c, root, NULL, "name", &name))) return st;
  if (!name[0] || strlen(name) >= sizeof s->name)
    return bad_key(c, ELFM_ERR_RANGE, "name", "must have 1..63 characters", 0);
  snprintf(s->name, sizeof s->name, "%s", name);
  if ((st = get_string(c, root, NULL, "description", &desc))) return st;
  int64_t seed = 0;
  /* 2^53: the largest integer a JSON number holds exactly. */
  if ((st = get_int64(c, root, NULL, "seed", 0, 9007199254740992.0, &seed))) return st;
  s->seed = (uint64_t)seed;
  /* 1e12 us = 11.6 days: any real recording offset. */
  if ((st = get_int64(c, root, NULL, "t0_us", 0, 1e12, &s->t0_us))) return st;
  if ((st = get_num(c, root, NULL, "duration_ms", 1e-3, 3.6e6, &a))) return st;
  s->duration_us = (int64_t)llround(a * 1e3);
  if (s->duration_us < 1) s->duration_us = 1;
  if ((st = get_int64(c, root, NULL, "slice_us", 100, 100000, &s->slice_us))) return st;
  /* SPEC §6: truth sampled every <= 100 us. */
  if ((st = get_int64(c, root, NULL, "truth_dt_us", 1, 100, &s->truth_dt_us))) return st;
  if ((st = get_int64(c, root, NULL, "max_step_us", 1, 100000, &s->max_step_us))) return st;
  if (s->max_step_us > s->slice_us)
    return bad_key(c, ELFM_ERR_RANGE, "max_step_us", "exceeds slice_us", 0);

  if ((st = parse_optics(c, root, s))) return st;

  if ((st = get_num(c, root, NULL, "background_hz", 1e-3, 1e9, &s->background_hz))) return st;
  if ((st = get_obj(c, root, "field_stop", &o))) return st;
  if ((st = get_num(c, o, "field_stop", "radius_um", 1, 1e4, &s->field_stop_radius_um))) return st;
  if ((st = get_num(c, o, "field_stop", "taper_um", 0, 100, &s->field_stop_taper_um))) return st;
  if ((st = get_obj(c, root, "haze", &o))) return st;
  if ((st = get_num(c, o, "haze", "fraction", 0, 0.99, &s->haze_fraction))) return st;
  if ((st = get_num(c, o, "haze", "sigma_um", 0.1, 1000, &s->haze_sigma_um))) return st;

  if ((st = get_obj(c, root, "objects", &o))) return st;
  if ((st = get_intv(c, o, "objects", "count", 0, 10000, &s->n_objects))) return st;
  if ((st = get_range(c, o, "objects", "diameter_um", 0, 100, &s->diameter_min_um,
                      &s->diameter_max_um)))
    return st;
  if ((st = get_range(c, o, "objects", "flux_hz", 0, 1e12, &s->flux_min_hz, &s->flux_max_hz)))
    return st;
  if ((st = get_num(c, o, "objects", "min_separation_um", 0, 100, &s->min_separation_um))) return st;

  if ((st = parse_motion(c, root, s))) return st;
  if ((st = parse_light(c, root, s))) return st;
  return ELFM_OK;
}

static void scene_destroy(elfm_scene *s)
{
  if (!s) return;
  sim_layout_free(s);
  free(s->json);
  free(s);
}

void elfm_scene_free(elfm_scene *s) { scene_destroy(s); }

elfm_status elfm_scene_parse(const char *json, size_t len, const char *source, elfm_scene **out,
                             elfm_error *err)
{
  if (!out) return elfm_error_set(err, ELFM_ERR_INVALID, source, -1, "no output pointer");
  *out = NULL;
  if (!json) return elfm_error_set(err, ELFM_ERR_INVALID, source, -1, "no scene text");
  scene_ctx c = {source ? source : "<scene>", err};
  if (len == 0) return elfm_error_set(err, ELFM_ERR_FORMAT, c.src, 0, "empty scene file");
  const char *end = NULL;
  cJSON *root = cJSON_ParseWithLengthOpts(json, len, &end, 0);
  if (!root) {
    return elfm_error_set(err, ELFM_ERR_FORMAT, c.src, end ? (int64_t)(end - json) : -1,
                          "invalid JSON");
  }
  elfm_scene *s = calloc(1, sizeof *s);
  if (!s) {
    cJSON_Delete(root);
    return elfm_error_set(err, ELFM_ERR_NOMEM, c.src, -1, "out of memory");
  }
  snprintf(s->source, sizeof s->source, "%s", c.src);
  elfm_status st = parse_scene(&c, root, s);
  if (st == ELFM_OK) {
    /* Keep the compact JSON: set_param edits it and parses again. */
    s->json = cJSON_PrintUnformatted(root);
    if (!s->json) st = elfm_error_set(err, ELFM_ERR_NOMEM, c.src, -1, "out of memory");
  }
  cJSON_Delete(root);
  if (st == ELFM_OK) st = sim_layout_build(s, err);
  if (st != ELFM_OK) {
    scene_destroy(s);
    return st;
  }
  *out = s;
  return ELFM_OK;
}

const char *elfm_scene_builtin_name(int k)
{
  if (k < 0 || k >= sim_n_builtin_scenes) return NULL;
  return sim_builtin_scenes[k].name;
}

elfm_status elfm_scene_load(const char *name_or_path, elfm_scene **out, elfm_error *err)
{
  if (!out) return elfm_error_set(err, ELFM_ERR_INVALID, NULL, -1, "no output pointer");
  *out = NULL;
  if (!name_or_path || !*name_or_path)
    return elfm_error_set(err, ELFM_ERR_INVALID, NULL, -1, "no scene name");
  /* A built-in name wins unless it looks like a path. */
  if (!strchr(name_or_path, '/') && !strstr(name_or_path, ".json")) {
    for (int k = 0; k < sim_n_builtin_scenes; k++) {
      if (!strcmp(sim_builtin_scenes[k].name, name_or_path)) {
        char src[96];
        snprintf(src, sizeof src, "scene %s", name_or_path);
        return elfm_scene_parse((const char *)sim_builtin_scenes[k].json,
                                sim_builtin_scenes[k].len, src, out, err);
      }
    }
  }
  FILE *f = fopen(name_or_path, "rb");
  if (!f) {
    int e = errno;
    if (!strchr(name_or_path, '/') && !strstr(name_or_path, ".json")) {
      char names[400] = "";
      for (int k = 0; k < sim_n_builtin_scenes; k++) {
        size_t n = strlen(names);
        snprintf(names + n, sizeof names - n, "%s%s", k ? ", " : "", sim_builtin_scenes[k].name);
      }
      return elfm_error_set(err, ELFM_ERR_INVALID, name_or_path, -1,
                            "no such scene (built-in: %s) or file", names);
    }
    return elfm_error_set(err, ELFM_ERR_IO, name_or_path, -1, "cannot open: %s", strerror(e));
  }
  /* 4 MB: a scene is a few kB; this only bounds a mistaken path. */
  const size_t max_bytes = (size_t)4 << 20;
  char *buf = malloc(max_bytes + 1);
  if (!buf) {
    fclose(f);
    return elfm_error_set(err, ELFM_ERR_NOMEM, name_or_path, -1, "out of memory");
  }
  size_t n = fread(buf, 1, max_bytes + 1, f);
  int bad = ferror(f);
  fclose(f);
  elfm_status st;
  if (bad) st = elfm_error_set(err, ELFM_ERR_IO, name_or_path, (int64_t)n, "read failed");
  else if (n > max_bytes)
    st = elfm_error_set(err, ELFM_ERR_FORMAT, name_or_path, (int64_t)max_bytes,
                        "file larger than 4 MB: not a scene");
  else st = elfm_scene_parse(buf, n, name_or_path, out, err);
  free(buf);
  return st;
}

/* Replace s's content by a fresh parse of `json` (same source name). */
static elfm_status scene_reparse(elfm_scene *s, const char *json, uint64_t seed, int keep_seed,
                                 elfm_error *err)
{
  elfm_scene *n = NULL;
  elfm_status st = elfm_scene_parse(json, strlen(json), s->source, &n, err);
  if (st) return st;
  if (keep_seed && n->seed != seed) {
    n->seed = seed;
    sim_layout_free(n);
    if ((st = sim_layout_build(n, err))) {
      scene_destroy(n);
      return st;
    }
  }
  /* Swap contents so the caller's pointer stays valid. */
  elfm_scene tmp = *s;
  *s = *n;
  *n = tmp;
  scene_destroy(n);
  return ELFM_OK;
}

/* Set one "key.path=value" in the scene's JSON tree `root`: only existing
 * keys (catches typos); *seed_param = 1 when it is the scene's own "seed". */
static elfm_status json_set_path(const elfm_scene *s, cJSON *root, const char *kv,
                                 int *seed_param, elfm_error *err)
{
  const char *eq = strchr(kv, '=');
  if (!eq || eq == kv || !eq[1])
    return elfm_error_set(err, ELFM_ERR_INVALID, s->source, -1,
                          "parameter \"%s\" is not key=value", kv);
  char key[256];
  size_t klen = (size_t)(eq - kv);
  if (klen >= sizeof key)
    return elfm_error_set(err, ELFM_ERR_INVALID, s->source, -1, "parameter key too long");
  memcpy(key, kv, klen);
  key[klen] = 0;
  const char *val = eq + 1;
  cJSON *value = cJSON_Parse(val);
  if (!value) value = cJSON_CreateString(val); /* bare words are strings: motion.type=helix */
  if (!value) return elfm_error_set(err, ELFM_ERR_NOMEM, s->source, -1, "out of memory");
  cJSON *parent = root, *item = NULL;
  char *save = NULL, *tok = strtok_r(key, ".", &save);
  const char *last = NULL;
  while (tok) {
    if (!cJSON_IsObject(parent)) {
      item = NULL;
      break;
    }
    item = cJSON_GetObjectItemCaseSensitive(parent, tok);
    last = tok;
    tok = strtok_r(NULL, ".", &save);
    if (!item) break;
    if (tok) parent = item;
  }
  if (!item || !last) {
    cJSON_Delete(value);
    return elfm_error_set(err, ELFM_ERR_INVALID, s->source, -1,
                          "parameter \"%.*s\": no such key in the scene", (int)klen, kv);
  }
  cJSON_ReplaceItemInObjectCaseSensitive(parent, last, value);
  if (!strcmp(last, "seed") && parent == root) *seed_param = 1;
  return ELFM_OK;
}

elfm_status elfm_scene_set_params(elfm_scene *s, const char *const *kvs, int n, elfm_error *err)
{
  if (!s || (n > 0 && !kvs) || n < 0)
    return elfm_error_set(err, ELFM_ERR_INVALID, NULL, -1, "set_params: NULL argument");
  for (int i = 0; i < n; i++)
    if (!kvs[i]) return elfm_error_set(err, ELFM_ERR_INVALID, NULL, -1, "set_params: NULL argument");
  if (n == 0) return ELFM_OK;
  cJSON *root = cJSON_Parse(s->json);
  if (!root) return elfm_error_set(err, ELFM_ERR_NOMEM, s->source, -1, "out of memory");
  /* Every edit first, then one check of the whole scene: fields that must
   * agree (a stage's v0 and v1 without an acceleration, z_min below z_max)
   * can then change together, which one edit at a time cannot. */
  int seed_param = 0;
  elfm_status st = ELFM_OK;
  for (int i = 0; i < n && st == ELFM_OK; i++) st = json_set_path(s, root, kvs[i], &seed_param, err);
  if (st == ELFM_OK) {
    char *text = cJSON_PrintUnformatted(root);
    if (!text) st = elfm_error_set(err, ELFM_ERR_NOMEM, s->source, -1, "out of memory");
    else {
      /* The scene's own "seed" may be a parameter; otherwise keep a seed
       * set earlier through set_seed. */
      st = scene_reparse(s, text, s->seed, !seed_param, err);
      cJSON_free(text);
    }
  }
  cJSON_Delete(root);
  return st;
}

elfm_status elfm_scene_set_param(elfm_scene *s, const char *kv, elfm_error *err)
{
  if (!s || !kv) return elfm_error_set(err, ELFM_ERR_INVALID, NULL, -1, "set_param: NULL argument");
  return elfm_scene_set_params(s, &kv, 1, err);
}

elfm_status elfm_scene_set_seed(elfm_scene *s, uint64_t seed, elfm_error *err)
{
  if (!s) return elfm_error_set(err, ELFM_ERR_INVALID, NULL, -1, "set_seed: NULL scene");
  if (s->seed == seed) return ELFM_OK;
  uint64_t old = s->seed;
  sim_layout_free(s);
  s->seed = seed;
  elfm_status st = sim_layout_build(s, err);
  if (st) {
    /* Leave the scene usable: the old layout built before, so it builds again. */
    sim_layout_free(s);
    s->seed = old;
    sim_layout_build(s, NULL);
  }
  return st;
}

const char *elfm_scene_name(const elfm_scene *s) { return s->name; }
uint64_t elfm_scene_seed(const elfm_scene *s) { return s->seed; }
const elfm_calib *elfm_scene_calib(const elfm_scene *s) { return &s->calib; }
int64_t elfm_scene_t0_us(const elfm_scene *s) { return s->t0_us; }
int64_t elfm_scene_duration_us(const elfm_scene *s) { return s->duration_us; }
int elfm_scene_n_objects(const elfm_scene *s) { return s->n_objects; }
int elfm_scene_has_stimulus(const elfm_scene *s)
{
  return s->illum != SIM_ILLUM_CONSTANT || s->has_spikes;
}
