/* layout.c — a scene's random layout (where objects are, how they move and
 * when they light up) and the truth that follows from it.
 *
 * Everything is drawn from splitmix64 streams keyed by (seed, purpose), so a
 * layout depends only on the scene fields and the seed. Positions are pure
 * functions of time: the simulator, truth.csv and elfm_scene_truth all call
 * sim_object_position and agree exactly.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "sim_internal.h"

#define TWO_PI 6.283185307179586
/* Stream ids (arbitrary distinct constants). */
#define STREAM_LAYOUT 0x4c41594f5554ull /* "LAYOUT" */
#define STREAM_ILLUM 0x494c4c554dull    /* "ILLUM" */
#define STREAM_SPIKE 0x5350494b45ull    /* "SPIKE" */
#define STREAM_HOT 0x484f54ull          /* "HOT" */
/* Placement: attempts per object before giving up (the scene asks for more
 * objects than fit at its min_separation), and a budget of distance checks
 * for the whole layout so that an impossible request fails in well under a
 * second instead of trying 10^4 objects x 2000 times. */
#define PLACE_TRIES 2000
#define PLACE_BUDGET 50000000
/* Light pulses per layout: 16 bytes each, so 64 MB; a 1 ms LED pulse every
 * 3 ms for an hour needs 2.4 M. */
#define MAX_PULSE_EDGES 8000000
/* Separation metric: axial distances count 1/4, as in scoring (SPEC §7, kz =
 * 4), because the axial resolution is ~5x worse than the lateral. */
#define SEP_KZ 4.0

void sim_layout_free(elfm_scene *s)
{
  free(s->obj);
  free(s->worms);
  free(s->illum_edges);
  free(s->spike_edges);
  s->obj = NULL;
  s->worms = NULL;
  s->illum_edges = s->spike_edges = NULL;
  s->n_worms = 0;
  s->n_illum_edges = s->n_spike_edges = 0;
}

static double sep_dist(const double a[3], const double b[3])
{
  double dx = a[0] - b[0], dy = a[1] - b[1], dz = (a[2] - b[2]) / SEP_KZ;
  return sqrt(dx * dx + dy * dy + dz * dz);
}

static int far_enough(const elfm_scene *s, int k, const double p[3], int64_t *budget)
{
  *budget -= k;
  for (int q = 0; q < k; q++)
    if (sep_dist(s->obj[q].p0, p) < s->min_separation_um) return 0;
  return 1;
}

/* A point uniform in the disk of radius r. */
static void disk_point(sim_rng *r, double radius, double *x, double *y)
{
  double rho = radius * sqrt(sim_uniform(r)), th = TWO_PI * sim_uniform(r);
  *x = rho * cos(th);
  *y = rho * sin(th);
}

/* Pulse train from t = 0 to t_end (us from t0): first onset uniform in
 * [0, gap_max) so that trains are not in phase, then pulse / gap draws.
 * Appends on/off pairs to *edges (growing it). */
static elfm_status pulse_train(const char *src, sim_rng *r, double pulse_min, double pulse_max, double gap_min,
                               double gap_max, int64_t t_end, int64_t **edges, int64_t *n,
                               int64_t *cap, elfm_error *err)
{
  double t = floor(sim_uniform(r) * gap_max);
  while (t <= (double)t_end) {
    double len = floor(sim_uniform_ab(r, pulse_min, pulse_max) + 0.5);
    if (len < 1) len = 1;
    if (*n + 2 > MAX_PULSE_EDGES)
      return elfm_error_set(err, ELFM_ERR_RANGE, src, -1,
                            "key \"duration_ms\": more than %d light pulse edges; shorten it "
                            "or lengthen the gaps",
                            MAX_PULSE_EDGES);
    if (*n + 2 > *cap) {
      int64_t nc = *cap ? *cap * 2 : 256;
      int64_t *ne = realloc(*edges, (size_t)nc * sizeof *ne);
      if (!ne) return elfm_error_set(err, ELFM_ERR_NOMEM, src, -1, "out of memory (pulse train)");
      *edges = ne;
      *cap = nc;
    }
    (*edges)[(*n)++] = (int64_t)t;
    (*edges)[(*n)++] = (int64_t)(t + len);
    t += len + floor(sim_uniform_ab(r, gap_min, gap_max) + 0.5);
  }
  return ELFM_OK;
}

static void unit_perp(const double a[3], double u[3], double v[3])
{
  /* Any vector not parallel to a, then Gram-Schmidt and a cross product. */
  double h[3] = {1, 0, 0};
  if (fabs(a[0]) > 0.9) { h[0] = 0; h[1] = 1; }
  double d = h[0] * a[0] + h[1] * a[1] + h[2] * a[2];
  for (int k = 0; k < 3; k++) u[k] = h[k] - d * a[k];
  double n = sqrt(u[0] * u[0] + u[1] * u[1] + u[2] * u[2]);
  for (int k = 0; k < 3; k++) u[k] /= n;
  v[0] = a[1] * u[2] - a[2] * u[1];
  v[1] = a[2] * u[0] - a[0] * u[2];
  v[2] = a[0] * u[1] - a[1] * u[0];
}

static elfm_status place_objects(elfm_scene *s, sim_rng *r, elfm_error *err)
{
  const int n = s->n_objects;
  for (int k = 0; k < n; k++) {
    sim_object *o = &s->obj[k];
    o->diameter_um = sim_uniform_ab(r, s->diameter_min_um, s->diameter_max_um);
    o->flux_hz = sim_uniform_ab(r, s->flux_min_hz, s->flux_max_hz);
  }
  /* A z sweep's slide, tilted or not: each bead x tan(tilt) deeper */
  const double slope = tan(s->sweep_tilt_deg * M_PI / 180.0);
  if (s->motion == SIM_MOTION_ZSWEEP && s->place_radius_um <= 0) {
    /* Several sweeping beads sit side by side along x, min_separation apart. */
    for (int k = 0; k < n; k++) {
      const double x = (k - (n - 1) * 0.5) * s->min_separation_um;
      s->obj[k].p0[0] = s->sweep_x_um + x;
      s->obj[k].p0[1] = s->sweep_y_um;
      s->obj[k].p0[2] = s->sweep_z_from_um + x * slope;
    }
    return ELFM_OK;
  }
  if (s->motion == SIM_MOTION_WORM) {
    s->n_worms = n / 4;
    if (s->n_worms == 0) return ELFM_OK;
    s->worms = calloc((size_t)s->n_worms, sizeof *s->worms);
    if (!s->worms) return elfm_error_set(err, ELFM_ERR_NOMEM, s->source, -1, "out of memory");
    /* The path a worm covers: from its tail neuron at t = -slice (the
     * simulator looks one slice back) to its front neuron at the end. */
    double s_lo = s->worm_neuron_s_um[0], s_hi = s->worm_neuron_s_um[0];
    for (int q = 1; q < 4; q++) {
      s_lo = fmin(s_lo, s->worm_neuron_s_um[q]);
      s_hi = fmax(s_hi, s->worm_neuron_s_um[q]);
    }
    s_lo -= s->worm_crawl_um_per_us * (double)s->slice_us;
    s_hi += s->worm_crawl_um_per_us * (double)(s->duration_us + 2 * s->slice_us);
    double half_len = 0.5 * (s_hi - s_lo);
    double room = s->place_radius_um - half_len - s->worm_wave_amp_um;
    if (room < 0) {
      return elfm_error_set(err, ELFM_ERR_RANGE, s->source, -1,
                            "key \"motion.crawl_mm_per_s\": worms crawl %.1f um, more than "
                            "motion.place_radius_um allows; shorten duration_ms or the crawl",
                            2 * half_len);
    }
    double zroom_lo = s->z_min_um + s->worm_z_amp_um, zroom_hi = s->z_max_um - s->worm_z_amp_um;
    if (zroom_hi < zroom_lo)
      return elfm_error_set(err, ELFM_ERR_RANGE, s->source, -1,
                            "key \"motion.z_amp_um\": larger than half of z_max_um - z_min_um");
    for (int w = 0; w < s->n_worms; w++) {
      sim_worm *wm = &s->worms[w];
      double th = TWO_PI * sim_uniform(r), mx, my;
      disk_point(r, room, &mx, &my);
      wm->heading[0] = cos(th);
      wm->heading[1] = sin(th);
      /* origin + p * heading passes through (mx, my) at the path's middle. */
      double pm = 0.5 * (s_lo + s_hi);
      wm->origin[0] = mx - pm * wm->heading[0];
      wm->origin[1] = my - pm * wm->heading[1];
      wm->wave_phase = TWO_PI * sim_uniform(r);
      wm->z0_um = sim_uniform_ab(r, zroom_lo, zroom_hi);
      wm->z_phase = TWO_PI * sim_uniform(r);
    }
    for (int k = 0; k < n; k++) {
      s->obj[k].worm = k / 4;
      s->obj[k].body_s_um = s->worm_neuron_s_um[k % 4];
    }
    return ELFM_OK;
  }
  int64_t budget = PLACE_BUDGET;
  for (int k = 0; k < n; k++) {
    sim_object *o = &s->obj[k];
    int placed = 0, tries = 0, too_big = 0;
    for (; tries < PLACE_TRIES && !placed && budget > 0; tries++) {
      double p[3];
      if (s->motion == SIM_MOTION_STAGE) {
        /* A slab: +-half_width across, one period along the motion. */
        double along = sim_uniform_ab(r, -0.5 * s->stage_period_um, 0.5 * s->stage_period_um);
        p[0] = sim_uniform_ab(r, -s->stage_half_width_um, s->stage_half_width_um);
        p[1] = sim_uniform_ab(r, -s->stage_half_width_um, s->stage_half_width_um);
        p[2] = sim_uniform_ab(r, s->z_min_um, s->z_max_um);
        double d = p[0] * s->stage_dir[0] + p[1] * s->stage_dir[1] + p[2] * s->stage_dir[2];
        for (int q = 0; q < 3; q++) p[q] += (along - d) * s->stage_dir[q];
      } else if (s->motion == SIM_MOTION_HELIX) {
        double rad = sim_uniform_ab(r, s->helix_radius_min_um, s->helix_radius_max_um);
        double amp = s->helix_axial_amp_max_um * sim_uniform(r);
        double extent = rad + amp; /* the whole path lies within this of the centre */
        double lat = s->place_radius_um - extent;
        double zlo = s->z_min_um + extent, zhi = s->z_max_um - extent;
        if (lat < 0 || zhi < zlo) {
          return elfm_error_set(err, ELFM_ERR_RANGE, s->source, -1,
                                "key \"motion.radius_um\": a helix of radius %.1f um with axial "
                                "amplitude %.1f um does not fit the placement volume",
                                rad, amp);
        }
        disk_point(r, lat, &p[0], &p[1]);
        p[2] = sim_uniform_ab(r, zlo, zhi);
        double speed = sim_uniform_ab(r, s->helix_speed_min, s->helix_speed_max);
        o->radius_um = rad;
        o->omega_rad_per_us = speed / rad;
        o->phase = TWO_PI * sim_uniform(r);
        o->axial_amp_um = amp;
        o->axial_omega_rad_per_us =
            TWO_PI / sim_uniform_ab(r, s->helix_axial_period_min_us, s->helix_axial_period_max_us);
        o->axial_phase = TWO_PI * sim_uniform(r);
        /* Axis uniform on the sphere. */
        double cz = sim_uniform_ab(r, -1, 1), ph = TWO_PI * sim_uniform(r);
        double sz = sqrt(1 - cz * cz);
        o->axis[0] = sz * cos(ph);
        o->axis[1] = sz * sin(ph);
        o->axis[2] = cz;
        unit_perp(o->axis, o->u, o->v);
      } else if (s->motion == SIM_MOTION_RANDOM) {
        /* A smooth random path: K sinusoids along random directions with
         * random periods and phases (a spectral draw of a smooth random
         * process), each carrying an equal share of the bead's RMS speed v
         * (|amp_j| omega_j = v sqrt(2 / K)). The speed varies along the
         * path and the path turns at random: no circle or helix for a
         * tracker to lean on. The triangle inequality bounds the path
         * (lateral and axial) by the sum of the modes' extents; a draw
         * that does not fit the placement volume is drawn again. */
        const int K = s->random_modes;
        const double v = sim_uniform_ab(r, s->random_speed_min, s->random_speed_max);
        double ext_lat = 0, ext_z = 0;
        for (int j = 0; j < K; j++) {
          const double w = TWO_PI / sim_uniform_ab(r, s->random_period_min_us, s->random_period_max_us);
          const double A = v * sqrt(2.0 / K) / w;
          double cz = sim_uniform_ab(r, -1, 1), ph = TWO_PI * sim_uniform(r);
          double sz = sqrt(1 - cz * cz);
          o->mode_amp_um[j][0] = A * sz * cos(ph);
          o->mode_amp_um[j][1] = A * sz * sin(ph);
          o->mode_amp_um[j][2] = A * cz;
          o->mode_omega_rad_per_us[j] = w;
          o->mode_phase[j] = TWO_PI * sim_uniform(r);
          ext_lat += A * sz;
          ext_z += A * fabs(cz);
        }
        double lat = s->place_radius_um - ext_lat;
        double zlo = s->z_min_um + ext_z, zhi = s->z_max_um - ext_z;
        if (lat < 0 || zhi < zlo) {
          too_big++;
          continue;
        }
        disk_point(r, lat, &p[0], &p[1]);
        p[2] = sim_uniform_ab(r, zlo, zhi);
      } else if (s->motion == SIM_MOTION_ZSWEEP) {
        /* scattered over a disc, as beads dried on a slide lie (all sweep
         * together, so their distances stay) */
        disk_point(r, s->place_radius_um, &p[0], &p[1]);
        p[2] = s->sweep_z_from_um + p[0] * slope;
        p[0] += s->sweep_x_um;
        p[1] += s->sweep_y_um;
      } else { /* static */
        disk_point(r, s->place_radius_um, &p[0], &p[1]);
        p[2] = sim_uniform_ab(r, s->z_min_um, s->z_max_um);
      }
      if (far_enough(s, k, p, &budget)) {
        memcpy(o->p0, p, sizeof p);
        placed = 1;
      }
    }
    if (!placed && s->motion == SIM_MOTION_ZSWEEP) {
      return elfm_error_set(err, ELFM_ERR_RANGE, s->source, -1,
                            "key \"objects.count\": cannot place %d beads %.1f um apart on a "
                            "disc of radius %.1f um (placed %d)",
                            n, s->min_separation_um, s->place_radius_um, k);
    }
    if (!placed && too_big == tries) {
      return elfm_error_set(err, ELFM_ERR_RANGE, s->source, -1,
                            "key \"motion.speed_mm_per_s\": random paths this fast with periods "
                            "this long do not fit the placement volume (%d draws)",
                            tries);
    }
    if (!placed) {
      return elfm_error_set(err, ELFM_ERR_RANGE, s->source, -1,
                            "key \"objects.count\": cannot place %d objects %.1f um apart in the "
                            "placement volume (placed %d)",
                            n, s->min_separation_um, k);
    }
  }
  return ELFM_OK;
}

elfm_status sim_layout_build(elfm_scene *s, elfm_error *err)
{
  sim_layout_free(s);
  if (s->n_objects > 0) {
    s->obj = calloc((size_t)s->n_objects, sizeof *s->obj);
    if (!s->obj) return elfm_error_set(err, ELFM_ERR_NOMEM, s->source, -1, "out of memory");
  }
  sim_rng r = sim_rng_make(s->seed, STREAM_LAYOUT, 0);
  elfm_status st = place_objects(s, &r, err);
  if (st) return st;

  /* Light schedules reach one slice past the end: the simulator looks at
   * [t - slice, t + slice] around each slice. */
  int64_t t_end = s->duration_us + 2 * s->slice_us;
  if (s->illum == SIM_ILLUM_RANDOM_PULSES) {
    int64_t cap = 0;
    sim_rng ri = sim_rng_make(s->seed, STREAM_ILLUM, 0);
    st = pulse_train(s->source, &ri, s->illum_pulse_us, s->illum_pulse_us, s->illum_gap_min_us,
                     s->illum_gap_max_us, t_end, &s->illum_edges, &s->n_illum_edges, &cap, err);
    if (st) return st;
  }
  if (s->has_spikes) {
    int64_t cap = 0;
    for (int k = 0; k < s->n_objects; k++) {
      sim_rng rs = sim_rng_make(s->seed, STREAM_SPIKE, (uint64_t)k);
      s->obj[k].spike_first = s->n_spike_edges;
      st = pulse_train(s->source, &rs, s->spike_pulse_min_us, s->spike_pulse_max_us, s->spike_gap_min_us,
                       s->spike_gap_max_us, t_end, &s->spike_edges, &s->n_spike_edges, &cap, err);
      if (st) return st;
      s->obj[k].spike_count = s->n_spike_edges - s->obj[k].spike_first;
    }
  }
  for (int h = 0; h < s->sensor.hot_pixels; h++) {
    uint64_t b = sim_hash(s->seed, STREAM_HOT, (uint64_t)h);
    s->hot_x[h] = (int)((b & 0xffffffffu) % (uint64_t)s->sensor.width);
    s->hot_y[h] = (int)((b >> 32) % (uint64_t)s->sensor.height);
  }
  return ELFM_OK;
}

/* Stage displacement along its direction at t_rel (us): v0 until the ramp,
 * accelerating at a to v1, then v1. Before t0 the stage moved at v0. */
static double stage_displacement(const elfm_scene *s, double t)
{
  double v0 = s->stage_v0_um_per_us, v1 = s->stage_v1_um_per_us, a = s->stage_accel_um_per_us2;
  if (t <= 0 || v1 == v0) return v0 * t;
  double t_ramp = (v1 - v0) / a;
  if (t < t_ramp) return v0 * t + 0.5 * a * t * t;
  return v0 * t_ramp + 0.5 * a * t_ramp * t_ramp + v1 * (t - t_ramp);
}

void sim_object_position(const elfm_scene *s, int k, double t, double pos[3], int64_t *pass)
{
  const sim_object *o = &s->obj[k];
  if (pass) *pass = 0;
  switch (s->motion) {
  case SIM_MOTION_STATIC:
    memcpy(pos, o->p0, 3 * sizeof *pos);
    return;
  case SIM_MOTION_STAGE: {
    const double *d = s->stage_dir;
    double P = s->stage_period_um;
    double along0 = o->p0[0] * d[0] + o->p0[1] * d[1] + o->p0[2] * d[2];
    double a = along0 + stage_displacement(s, t);
    double m = floor((a + 0.5 * P) / P);
    double aw = a - m * P;
    for (int q = 0; q < 3; q++) pos[q] = o->p0[q] + (aw - along0) * d[q];
    if (pass) *pass = (int64_t)m;
    return;
  }
  case SIM_MOTION_ZSWEEP: {
    /* Triangle wave: z_from -> z_to -> z_from ... at constant speed. */
    double L = fabs(s->sweep_z_to_um - s->sweep_z_from_um);
    double d = s->sweep_speed_um_per_us * t;
    double m = d - 2 * L * floor(d / (2 * L));
    double tri = m <= L ? m : 2 * L - m;
    double sign = s->sweep_z_to_um > s->sweep_z_from_um ? 1.0 : -1.0;
    pos[0] = o->p0[0];
    pos[1] = o->p0[1];
    pos[2] = o->p0[2] + sign * tri;
    return;
  }
  case SIM_MOTION_HELIX: {
    double th = o->omega_rad_per_us * t + o->phase;
    double c = o->radius_um * cos(th), sn = o->radius_um * sin(th);
    double ax = o->axial_amp_um * sin(o->axial_omega_rad_per_us * t + o->axial_phase);
    for (int q = 0; q < 3; q++) pos[q] = o->p0[q] + c * o->u[q] + sn * o->v[q] + ax * o->axis[q];
    return;
  }
  case SIM_MOTION_RANDOM: {
    memcpy(pos, o->p0, 3 * sizeof *pos);
    for (int j = 0; j < s->random_modes; j++) {
      const double sn = sin(o->mode_omega_rad_per_us[j] * t + o->mode_phase[j]);
      for (int q = 0; q < 3; q++) pos[q] += o->mode_amp_um[j][q] * sn;
    }
    return;
  }
  case SIM_MOTION_WORM: {
    /* Crawling without slip: each body point follows the same sinusoidal
     * track, so a neuron at body position s is at path length s + v t. */
    const sim_worm *w = &s->worms[o->worm];
    double p = o->body_s_um + s->worm_crawl_um_per_us * t;
    double lat = s->worm_wave_amp_um * sin(TWO_PI * p / s->worm_wavelength_um + w->wave_phase);
    pos[0] = w->origin[0] + p * w->heading[0] - lat * w->heading[1];
    pos[1] = w->origin[1] + p * w->heading[1] + lat * w->heading[0];
    pos[2] = w->z0_um + s->worm_z_amp_um * sin(TWO_PI * t / s->worm_z_period_us + w->z_phase);
    return;
  }
  }
}

/* 1 if t lies inside one of the on/off pairs of edges[0..n). */
static int in_pulses(const int64_t *edges, int64_t n, int64_t t)
{
  /* Number of edges <= t: odd means inside a pulse [on, off). */
  int64_t lo = 0, hi = n;
  while (lo < hi) {
    int64_t mid = lo + (hi - lo) / 2;
    if (edges[mid] <= t) lo = mid + 1;
    else hi = mid;
  }
  return (int)(lo & 1);
}

static double illumination(const elfm_scene *s, int64_t t)
{
  switch (s->illum) {
  case SIM_ILLUM_CONSTANT: return 1.0;
  case SIM_ILLUM_RANDOM_PULSES: return in_pulses(s->illum_edges, s->n_illum_edges, t);
  case SIM_ILLUM_PERIODIC: {
    int64_t P = (int64_t)s->illum_period_us;
    int64_t m = t % P;
    if (m < 0) m += P;
    return m < (int64_t)s->illum_pulse_us ? 1.0 : 0.0;
  }
  }
  return 1.0;
}

double sim_object_light(const elfm_scene *s, int k, int64_t t)
{
  double l = illumination(s, t);
  if (s->has_spikes && l > 0) {
    const sim_object *o = &s->obj[k];
    if (!in_pulses(sim_spike_edges(s, o), o->spike_count, t)) l *= s->spike_baseline;
  }
  return l;
}

double sim_field_stop(const elfm_scene *s, double x, double y)
{
  double r = sqrt(x * x + y * y), R = s->field_stop_radius_um, w = s->field_stop_taper_um;
  if (r >= R) return 0.0;
  if (w <= 0 || r <= R - w) return 1.0;
  return (R - r) / w;
}

/* Edges of edges[0..n) in (a, b]. */
static int64_t edges_in(const int64_t *edges, int64_t n, int64_t a, int64_t b, int64_t *out,
                        int64_t cap, int64_t found)
{
  int64_t lo = 0, hi = n;
  while (lo < hi) { /* first edge > a */
    int64_t mid = lo + (hi - lo) / 2;
    if (edges[mid] <= a) lo = mid + 1;
    else hi = mid;
  }
  for (int64_t i = lo; i < n && edges[i] <= b; i++) {
    if (found < cap) out[found] = edges[i];
    found++;
  }
  return found;
}

int64_t sim_light_edges(const elfm_scene *s, int64_t a, int64_t b, int64_t *out, int64_t cap)
{
  int64_t found = 0;
  if (s->illum == SIM_ILLUM_RANDOM_PULSES) {
    found = edges_in(s->illum_edges, s->n_illum_edges, a, b, out, cap, found);
  } else if (s->illum == SIM_ILLUM_PERIODIC) {
    int64_t P = (int64_t)s->illum_period_us, len = (int64_t)s->illum_pulse_us;
    int64_t m0 = (a - len) / P - 1;
    for (int64_t m = m0; m * P <= b; m++) {
      int64_t e[2] = {m * P, m * P + len};
      for (int q = 0; q < 2; q++) {
        if (e[q] > a && e[q] <= b) {
          if (found < cap) out[found] = e[q];
          found++;
        }
      }
    }
  }
  if (s->has_spikes) {
    for (int k = 0; k < s->n_objects; k++) {
      const sim_object *o = &s->obj[k];
      found = edges_in(sim_spike_edges(s, o), o->spike_count, a, b, out, cap, found);
    }
  }
  return found;
}

void elfm_scene_truth(const elfm_scene *s, int k, int64_t t_us, elfm_truth *out)
{
  double pos[3] = {0, 0, 0};
  int64_t pass = 0;
  int64_t t = t_us - s->t0_us;
  sim_object_position(s, k, (double)t, pos, &pass);
  out->id = (int64_t)k + (int64_t)s->n_objects * pass;
  out->x_um = pos[0];
  out->y_um = pos[1];
  out->z_um = pos[2];
  out->brightness = sim_object_light(s, k, t) * sim_field_stop(s, pos[0], pos[1]);
}

int sim_object_light_changes(const elfm_scene *s, int k, int64_t a, int64_t b)
{
  int64_t tmp;
  if (s->illum == SIM_ILLUM_RANDOM_PULSES &&
      edges_in(s->illum_edges, s->n_illum_edges, a, b, &tmp, 0, 0) > 0)
    return 1;
  if (s->illum == SIM_ILLUM_PERIODIC) {
    /* An edge in (a, b] exists when the light differs somewhere; pulses and
     * gaps are >= 1 us, so compare the state at a with each edge time. */
    int64_t P = (int64_t)s->illum_period_us, len = (int64_t)s->illum_pulse_us;
    if (b - a >= P) return 1;
    int64_t m0 = (a - len) / P - 1;
    for (int64_t m = m0; m * P <= b; m++)
      if ((m * P > a && m * P <= b) || (m * P + len > a && m * P + len <= b)) return 1;
  }
  if (s->has_spikes) {
    const sim_object *o = &s->obj[k];
    if (edges_in(sim_spike_edges(s, o), o->spike_count, a, b, &tmp, 0, 0) > 0) return 1;
  }
  return 0;
}
