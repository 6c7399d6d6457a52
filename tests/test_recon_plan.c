/* test_recon_plan.c — elfm_recon_run with the caller's refocus plan
 * (elfm_recon_options.plan): the same volumes, bit for bit, as with the
 * plan the run makes itself; the plan still the caller's after the run
 * (AddressSanitizer would see a run that freed it); a plan made for other
 * planes or another sensor refused before any volume, with the reason.
 *
 * Why: `eventlfm track` makes one plan for its detectors' geometry, the
 * driver and its gap fills' view fits (three plans before, ~16 ms each at
 * the paper's geometry). */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "check.h"
#include "elfm_datasets.h"
#include "elfm_recon.h"
#include "sim_test_util.h"

#define MAX_VOL 64

typedef struct sums {
  int n;
  double s[MAX_VOL];
} sums;

/* Each volume's weighted sum: a voxel moved or changed changes it. */
static elfm_status on_volume(const elfm_volume *v, void *user, elfm_error *err)
{
  (void)err;
  sums *c = user;
  if (c->n < MAX_VOL) {
    double s = 0;
    const size_t n = (size_t)v->w * v->h * v->nz;
    for (size_t i = 0; i < n; i++) s += v->data[i] * (1.0 + (double)(i % 13));
    c->s[c->n] = s;
  }
  c->n++;
  return ELFM_OK;
}

int main(void)
{
  char dir[] = "/tmp/elfm_recon_plan_XXXXXX";
  if (!mkdtemp(dir)) SKIP("cannot make a temporary directory");
  elfm_error err;
  elfm_error_clear(&err);
  char events[700];
  elfm_calib cal;
  sim_test_scene("flow", 6, dir, events, sizeof events, &cal);

  elfm_recon_options o;
  elfm_recon_options_default(&o);
  o.threads = 2;
  sums own = {0}, given = {0};
  CHECK_OK(elfm_recon_run(events, &cal, &o, on_volume, &own, NULL, &err), &err);
  CHECK(own.n >= 5 && own.n <= MAX_VOL);

  elfm_refocus_plan *plan = NULL;
  CHECK_OK(elfm_refocus_plan_create(&cal, &o.refocus, &plan, &err), &err);
  o.plan = plan;
  CHECK_OK(elfm_recon_run(events, &cal, &o, on_volume, &given, NULL, &err), &err);
  CHECK_EQ_INT(given.n, own.n);
  int differ = 0;
  for (int i = 0; i < own.n && i < MAX_VOL; i++) differ += given.s[i] != own.s[i];
  CHECK_EQ_INT(differ, 0);
  /* the plan is still the caller's: it makes a volume of its geometry */
  elfm_volume *v = elfm_refocus_volume_create(plan, &err);
  CHECK(v != NULL && v->nz == elfm_calib_n_planes(&cal) && v->w == cal.view_w_px);
  elfm_volume_free(v);

  /* the same plan for a calibration of other planes, or another sensor:
   * refused, no volume delivered */
  elfm_calib other = cal;
  other.z_step_um = cal.z_step_um * 2;
  sums none = {0};
  elfm_error_clear(&err);
  CHECK(elfm_recon_run(events, &other, &o, on_volume, &none, NULL, &err) == ELFM_ERR_INVALID);
  CHECK_MSG(strstr(err.message, "another calibration") != NULL, "message: %s", err.message);
  CHECK_EQ_INT(none.n, 0);
  other = cal;
  other.sensor_width_px = cal.sensor_width_px + 16;
  elfm_error_clear(&err);
  CHECK(elfm_recon_run(events, &other, &o, on_volume, &none, NULL, &err) == ELFM_ERR_INVALID);
  CHECK_EQ_INT(none.n, 0);
  elfm_refocus_plan_free(plan);

  char cmd[800];
  snprintf(cmd, sizeof cmd, "rm -rf '%s'", dir);
  if (system(cmd) != 0) fprintf(stderr, "could not remove %s\n", dir);
  return check_report();
}
