/* sim_internal.h — private to datasets/: the scene structure, its random
 * layout, and the counter-based random numbers everything draws from.
 * Not installed; the module's public header is elfm_datasets.h. */
#ifndef ELFM_SIM_INTERNAL_H
#define ELFM_SIM_INTERNAL_H

#include <math.h>
#include <stdint.h>

#include "elfm_datasets.h"

/* ---- random numbers: splitmix64 (Steele, Lea & Flood 2014) ----
 * Counter-based: sim_hash(seed, a, b) is a pure function, so a stream for
 * (slice 17, noise) or a threshold for pixel 12345 is the same whatever was
 * drawn before; this keeps output independent of evaluation order. */
static inline uint64_t sim_mix64(uint64_t z)
{
  z += 0x9e3779b97f4a7c15ull;
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
  return z ^ (z >> 31);
}
static inline uint64_t sim_hash(uint64_t seed, uint64_t a, uint64_t b)
{
  return sim_mix64(sim_mix64(sim_mix64(seed) ^ a) + b);
}
typedef struct sim_rng {
  uint64_t state;
} sim_rng;
static inline sim_rng sim_rng_make(uint64_t seed, uint64_t a, uint64_t b)
{
  sim_rng r = {sim_hash(seed, a, b)};
  return r;
}
static inline uint64_t sim_rng_next(sim_rng *r)
{
  r->state += 0x9e3779b97f4a7c15ull;
  uint64_t z = r->state;
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
  return z ^ (z >> 31);
}
/* Uniform in [0, 1): the top 53 bits. */
static inline double sim_u01(uint64_t bits) { return (double)(bits >> 11) * 0x1.0p-53; }
static inline double sim_uniform(sim_rng *r) { return sim_u01(sim_rng_next(r)); }
static inline double sim_uniform_ab(sim_rng *r, double a, double b)
{
  return a + (b - a) * sim_uniform(r);
}
/* Standard normal by Box-Muller (layout, not hot loops). */
static inline double sim_normal(sim_rng *r)
{
  double u1 = sim_uniform(r), u2 = sim_uniform(r);
  if (u1 < 1e-300) u1 = 1e-300;
  return sqrt(-2.0 * log(u1)) * cos(6.283185307179586 * u2);
}
/* Cheap near-normal from one 64-bit word: the sum of four 16-bit uniforms
 * (Irwin-Hall, n = 4) scaled to unit variance; bounded to +-3.46, which is
 * what a latency jitter needs (no negative delays from the far tail). */
static inline double sim_normal_fast(uint64_t bits)
{
  double s = (double)(bits & 0xffff) + (double)((bits >> 16) & 0xffff) +
             (double)((bits >> 32) & 0xffff) + (double)(bits >> 48);
  return (s / 65536.0 - 2.0) * 1.7320508075688772; /* sqrt(12 / 4) */
}

/* ---- scene ---- */
typedef enum sim_motion_type {
  SIM_MOTION_STATIC = 0,
  SIM_MOTION_STAGE,
  SIM_MOTION_ZSWEEP,
  SIM_MOTION_HELIX,
  SIM_MOTION_WORM,
  SIM_MOTION_RANDOM
} sim_motion_type;

/* random motion: most modes per object (motion.modes) */
#define SIM_RANDOM_MODES_MAX 16

typedef enum sim_illum_type {
  SIM_ILLUM_CONSTANT = 0,
  SIM_ILLUM_RANDOM_PULSES,
  SIM_ILLUM_PERIODIC
} sim_illum_type;

typedef struct sim_sensor {
  int width, height;
  double threshold_on, threshold_off, threshold_sigma; /* ln-intensity units */
  double refractory_us, latency_us, jitter_us;
  double cutoff_hz_at_background, cutoff_hz_max;
  double shot_noise_hz, leak_hz;
  int hot_pixels;
  double hot_pixel_hz;
} sim_sensor;

/* One object of the random layout; which fields matter depends on the motion. */
typedef struct sim_object {
  double p0[3];           /* position at t0 (static, stage), helix centre, worm: unused */
  double diameter_um, flux_hz;
  /* helix: p = c + r (cos(w t + ph) u + sin(w t + ph) v) + A sin(W t + ps) a */
  double axis[3], u[3], v[3];
  double radius_um, omega_rad_per_us, phase, axial_amp_um, axial_omega_rad_per_us, axial_phase;
  /* random: p = c + sum_j amp_j sin(omega_j t + phase_j), amp_j a 3D vector */
  double mode_amp_um[SIM_RANDOM_MODES_MAX][3];
  double mode_omega_rad_per_us[SIM_RANDOM_MODES_MAX], mode_phase[SIM_RANDOM_MODES_MAX];
  /* worm: which worm, and where along its body (um from the tail) */
  int worm;
  double body_s_um;
  /* spikes: [first, first + count) in scene->spike_edges, pairs on/off */
  int64_t spike_first, spike_count;
} sim_object;

typedef struct sim_worm {
  double origin[2];      /* path origin in x, y (um) */
  double heading[2];     /* unit direction of crawling */
  double wave_phase;
  double z0_um, z_phase;
} sim_worm;

struct elfm_scene {
  char name[64];
  char source[512];      /* file path or "scene NAME" for messages */
  char *json;            /* the scene's JSON text (for set_param re-checks) */
  uint64_t seed;
  int64_t t0_us, duration_us, slice_us, truth_dt_us, max_step_us;
  elfm_calib calib;
  sim_sensor sensor;
  double background_hz, field_stop_radius_um, field_stop_taper_um;
  double haze_fraction, haze_sigma_um;

  /* objects (ranges are uniform draws) */
  int n_objects;
  double diameter_min_um, diameter_max_um, flux_min_hz, flux_max_hz, min_separation_um;

  sim_motion_type motion;
  /* stage */
  double stage_dir[3], stage_v0_um_per_us, stage_v1_um_per_us, stage_accel_um_per_us2;
  double stage_period_um, stage_half_width_um;
  /* common extent of random placement */
  double place_radius_um, z_min_um, z_max_um;
  /* zsweep */
  double sweep_x_um, sweep_y_um, sweep_z_from_um, sweep_z_to_um, sweep_speed_um_per_us;
  double sweep_tilt_deg; /* the slide's tilt about y: a bead x um off sweep_x is x tan(tilt) deeper */
  /* helix */
  double helix_speed_min, helix_speed_max;   /* um/us */
  double helix_radius_min_um, helix_radius_max_um, helix_axial_amp_max_um;
  double helix_axial_period_min_us, helix_axial_period_max_us;
  /* random */
  int random_modes;
  double random_speed_min, random_speed_max;  /* RMS speed, um/us */
  double random_period_min_us, random_period_max_us;
  /* worm */
  double worm_crawl_um_per_us, worm_wave_amp_um, worm_wavelength_um, worm_z_amp_um,
      worm_z_period_us, worm_neuron_s_um[4];

  sim_illum_type illum;
  double illum_pulse_us, illum_gap_min_us, illum_gap_max_us, illum_period_us;
  int has_spikes;
  double spike_pulse_min_us, spike_pulse_max_us, spike_gap_min_us, spike_gap_max_us,
      spike_baseline;

  /* ---- layout, rebuilt from the seed ---- */
  sim_object *obj;          /* n_objects */
  sim_worm *worms;          /* n_worms */
  int n_worms;
  int64_t *illum_edges;     /* random pulses: on, off, on, off... (us from t0) */
  int64_t n_illum_edges;
  int64_t *spike_edges;     /* all objects' on/off pairs (us from t0) */
  int64_t n_spike_edges;
  int hot_x[64], hot_y[64]; /* hot pixel positions */
};

/* Object k's spike edges (NULL when it has none: no arithmetic on NULL). */
static inline const int64_t *sim_spike_edges(const elfm_scene *s, const sim_object *o)
{
  return o->spike_count ? s->spike_edges + o->spike_first : NULL;
}

/* layout.c: build obj/worms/edges from the scene fields and seed. */
elfm_status sim_layout_build(elfm_scene *s, elfm_error *err);
void sim_layout_free(elfm_scene *s);

/* Position (um) of object k at t_rel_us (from t0), the stage pass index
 * (0 for other motions). No field-stop or brightness. */
void sim_object_position(const elfm_scene *s, int k, double t_rel_us, double pos[3],
                         int64_t *pass);
/* Light factor of object k at t_rel (illumination x spike), without the field stop. */
double sim_object_light(const elfm_scene *s, int k, int64_t t_rel_us);
/* Field-stop transmission at lateral position (x, y). */
double sim_field_stop(const elfm_scene *s, double x_um, double y_um);

/* Edge times (us from t0) of all light changes in (a, b]: the global
 * illumination's and every object's spikes. Writes at most cap, returns the
 * count found (may exceed cap). */
int64_t sim_light_edges(const elfm_scene *s, int64_t a_rel, int64_t b_rel, int64_t *out,
                        int64_t cap);

/* 1 if object k's light (illumination or its spikes) changes in (a, b]. */
int sim_object_light_changes(const elfm_scene *s, int k, int64_t a_rel, int64_t b_rel);

/* builtin_scenes.c (generated at build time from datasets/scenes/\*.json). */
typedef struct sim_builtin_scene {
  const char *name;
  const unsigned char *json;
  size_t len;
} sim_builtin_scene;
extern const sim_builtin_scene sim_builtin_scenes[];
extern const int sim_n_builtin_scenes;

#endif
