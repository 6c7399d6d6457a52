/* elfm_datasets.h — the physics simulator: scenes of fluorescent objects seen
 * by an event camera behind a Fourier light-field microscope.
 *
 * A scene (JSON, datasets/scenes/NAME.json, built into the library) names
 * the optics, the sensor model, the objects and how they move and blink.
 * Every field must be present; the loader checks types, finiteness and
 * ranges and names the file and the key ("sensor.refractory_us") on error.
 *
 *   elfm_scene *s;
 *   elfm_scene_load("flow", &s, &err);            built-in name or a path
 *   elfm_scene_set_param(s, "objects.count=100", &err);  optional overrides
 *   elfm_scene_set_seed(s, 7, &err);               layout + noise seed
 *   elfm_sim_run(s, "out/", NULL, &stats, &err);   events.raw, truth.csv, calib.json
 *   elfm_scene_free(s);
 *
 * The random layout of a scene (object positions, paths, blink schedules) is
 * a function of (scene fields, seed) only, built by load/set_param/set_seed;
 * the truth queries below are then pure functions of time, usable without
 * running the simulation (scoring and recon tests ask them directly).
 * Same scene + same seed -> byte-identical output files.
 *
 * Ownership: elfm_scene_load/_parse allocate the scene; elfm_scene_free
 * frees it (NULL is a no-op). A scene is read-only during elfm_sim_run, so
 * several threads may query or simulate one scene at once.
 */
#ifndef ELFM_DATASETS_H
#define ELFM_DATASETS_H

#include <stddef.h>
#include <stdint.h>

#include "elfm_recon.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct elfm_scene elfm_scene;

/* Load a scene: a built-in name ("stage", "flow", ...; see
 * elfm_scene_builtin_name) or a path to a JSON file. On failure *out is
 * NULL and err names the file (or "scene NAME") and the key. */
elfm_status elfm_scene_load(const char *name_or_path, elfm_scene **out, elfm_error *err);

/* Same from JSON text in memory (len bytes); `source` names it in messages. */
elfm_status elfm_scene_parse(const char *json, size_t len, const char *source,
                             elfm_scene **out, elfm_error *err);

void elfm_scene_free(elfm_scene *s);

/* Built-in scenes: name of the k-th (0-based), NULL past the end. */
const char *elfm_scene_builtin_name(int k);

/* Override one field, "key.path=value" with a JSON value (numbers, strings,
 * arrays): e.g. "objects.count=100", "sensor.shot_noise_hz=0",
 * "duration_ms=50". The key must exist in the scene; the whole scene is
 * checked again and the layout rebuilt. On error the scene is unchanged. */
elfm_status elfm_scene_set_param(elfm_scene *s, const char *key_eq_value, elfm_error *err);
/* Several at once: every field set, then the scene checked once, so that
 * fields that must agree can change together (a stage's v0_mm_per_s and
 * v1_mm_per_s; one at a time, the first edit leaves them disagreeing and
 * is refused). On error the scene is unchanged. */
elfm_status elfm_scene_set_params(elfm_scene *s, const char *const *key_eq_values, int n,
                                  elfm_error *err);

/* Rebuild the random layout and noise streams from `seed` (the scene file's
 * "seed" field is the default). */
elfm_status elfm_scene_set_seed(elfm_scene *s, uint64_t seed, elfm_error *err);

/* ---- what a scene is ---- */
const char *elfm_scene_name(const elfm_scene *s);
uint64_t elfm_scene_seed(const elfm_scene *s);
const elfm_calib *elfm_scene_calib(const elfm_scene *s); /* owned by the scene */
int64_t elfm_scene_t0_us(const elfm_scene *s);       /* first event time (absolute) */
int64_t elfm_scene_duration_us(const elfm_scene *s);
int elfm_scene_n_objects(const elfm_scene *s);
/* 1 if the scene has light pulses (LED or per-object spikes): stimulus.csv. */
int elfm_scene_has_stimulus(const elfm_scene *s);

/* Ground truth of object k (0 <= k < n_objects) at absolute time t_us.
 * `id` is the track identity written to truth.csv: it equals k except in
 * stage scenes, where a bead leaving the field re-enters on the other side
 * as a new track (id = k + n_objects * pass). brightness is the factor on
 * the object's light: illumination x spike state x field stop (0 = dark). */
typedef struct elfm_truth {
  int64_t id;
  double x_um, y_um, z_um;
  double brightness;
} elfm_truth;
void elfm_scene_truth(const elfm_scene *s, int k, int64_t t_us, elfm_truth *out);

/* ---- simulating ---- */
typedef struct elfm_sim_stats {
  int64_t n_events, n_on, n_off;
  int64_t n_signal;     /* from the pixel model (light changes) */
  int64_t n_noise;      /* shot noise, leak and hot pixels */
  int64_t n_dropped_refractory;
  int64_t n_truth_rows;
  int64_t n_pixel_steps;  /* pixel model updates (the cost of the simulation) */
  int64_t n_steps;        /* time steps */
  int64_t duration_us;
  double events_per_s;  /* n_events / simulated seconds */
  double wall_s;        /* elapsed time of the run */
} elfm_sim_stats;

/* Called about every simulated millisecond batch: done/total simulated us.
 * Return non-zero to cancel (elfm_sim_run then returns ELFM_ERR_INVALID). */
typedef int (*elfm_sim_progress_fn)(void *user, int64_t done_us, int64_t total_us);

typedef struct elfm_sim_options {
  elfm_sim_progress_fn progress; /* may be NULL */
  void *progress_user;
  int write_truth;               /* 1: truth.csv (default when opt == NULL) */
} elfm_sim_options;

/* Receives the events in time order, one chunk per call (the chunk is
 * reused after the call returns). A non-OK status stops the simulation. */
typedef elfm_status (*elfm_sim_sink_fn)(void *user, const elfm_event_chunk *chunk,
                                        elfm_error *err);

/* Simulate the scene into directory out_dir (created if missing):
 * events.raw (EVT 3.0), truth.csv, calib.json and, when the scene has
 * light pulses, stimulus.csv. `opt` and `stats` may be NULL.
 * Memory is bounded per simulated slice, not by the duration. */
elfm_status elfm_sim_run(const elfm_scene *s, const char *out_dir,
                         const elfm_sim_options *opt, elfm_sim_stats *stats, elfm_error *err);

/* The same simulation, events handed to `sink` instead of a file, no other
 * files written (tests; in-memory pipelines). */
elfm_status elfm_sim_run_sink(const elfm_scene *s, elfm_sim_sink_fn sink, void *sink_user,
                              const elfm_sim_options *opt, elfm_sim_stats *stats,
                              elfm_error *err);

#ifdef __cplusplus
}
#endif
#endif
