/* sim_test_util.h — a short simulated recording for tests that need real
 * events and their calibration (test_recon_plan, test_bin). */
#ifndef ELFM_TESTS_SIM_TEST_UTIL_H
#define ELFM_TESTS_SIM_TEST_UTIL_H

#include <stdio.h>

#include "check.h"
#include "elfm_datasets.h"
#include "elfm_recon.h"

/* Simulate `scene` for ms milliseconds into dir (no truth file), put the
 * events' path into events[0 .. n) and load the scene's calibration into
 * *cal. Each step's failure is counted (CHECK_OK). */
static inline void sim_test_scene(const char *scene, int ms, const char *dir, char *events, size_t n,
                                  elfm_calib *cal)
{
  elfm_error err;
  elfm_error_clear(&err);
  elfm_scene *sc = NULL;
  char kv[64], calib_path[700];
  snprintf(kv, sizeof kv, "duration_ms=%d", ms);
  CHECK_OK(elfm_scene_load(scene, &sc, &err), &err);
  CHECK_OK(elfm_scene_set_param(sc, kv, &err), &err);
  elfm_sim_options so = {.progress = NULL, .progress_user = NULL, .write_truth = 0};
  CHECK_OK(elfm_sim_run(sc, dir, &so, NULL, &err), &err);
  elfm_scene_free(sc);
  snprintf(events, n, "%s/events.raw", dir);
  snprintf(calib_path, sizeof calib_path, "%s/calib.json", dir);
  CHECK_OK(elfm_calib_load(calib_path, cal, &err), &err);
}

#endif
