/* bench_peaks.c — peak detector speed on real refocused volumes.
 *
 * Refocuses the first N volumes of a recording with the `track` command's
 * frame settings (ON events, exponential surface tau 1 ms, 1 ms windows, no
 * median, no view agreement; 1 thread), keeps them in memory, then times
 * elfm_peaks_detect with the track defaults (absolute 50, 6 sigma) over all
 * of them, R rounds. Prints ms per volume (median round) and the peak count,
 * so a change of the detector can be checked for speed and same output.
 *   build-NAME/bench/bench_peaks CALIB EVENTS [volumes=100] [rounds=5]
 * e.g. after `eventlfm simulate flow --out /tmp/f --duration-ms 100`:
 *   build-NAME/bench/bench_peaks /tmp/f/calib.json /tmp/f/events.raw */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "elfm_recon.h"
#include "elfm_tracker.h"
#include "bench_clock.h"

typedef struct keep {
  elfm_volume **v;
  int n, cap;
} keep;

static elfm_status on_volume(const elfm_volume *vol, void *user, elfm_error *err)
{
  keep *k = user;
  if (k->n >= k->cap) /* enough: stop the run (main ignores this error) */
    return elfm_error_set(err, ELFM_ERR_INVALID, NULL, -1, "enough volumes");
  elfm_volume *c = elfm_volume_create(vol->w, vol->h, vol->nz, vol->um_per_px, vol->z_min_um,
                                      vol->z_step_um, err);
  if (!c) return err->code;
  memcpy(c->data, vol->data, (size_t)vol->w * vol->h * vol->nz * sizeof *c->data);
  c->frame = vol->frame;
  c->t_us = vol->t_us;
  k->v[k->n++] = c;
  return ELFM_OK;
}

static int cmp_d(const void *a, const void *b)
{
  double x = *(const double *)a, y = *(const double *)b;
  return (x > y) - (x < y);
}

int main(int argc, char **argv)
{
  if (argc < 3) {
    fprintf(stderr, "usage: bench_peaks CALIB EVENTS [volumes=100] [rounds=5]\n");
    return 2;
  }
  int nvol = argc > 3 ? atoi(argv[3]) : 100, rounds = argc > 4 ? atoi(argv[4]) : 5;
  if (nvol < 1 || rounds < 1 || rounds > 100) return 2;
  elfm_error err;
  elfm_calib cal_s;
  elfm_calib *cal = &cal_s;
  if (elfm_calib_load(argv[1], cal, &err) != ELFM_OK) {
    fprintf(stderr, "%s\n", err.message);
    return 1;
  }
  elfm_recon_options ro;
  elfm_recon_options_default(&ro);
  ro.framer.polarity = ELFM_POL_ON;
  ro.median = 0;
  ro.refocus.agree_frac = 0;
  ro.threads = 1;
  keep k = {calloc((size_t)nvol, sizeof(elfm_volume *)), 0, nvol};
  if (elfm_recon_run(argv[2], cal, &ro, on_volume, &k, NULL, &err) != ELFM_OK &&
      k.n < nvol) {
    fprintf(stderr, "recon: %s\n", err.message);
    return 1;
  }
  if (k.n == 0) {
    fprintf(stderr, "no volumes\n");
    return 1;
  }
  elfm_peaks_options po;
  elfm_peaks_options_default(&po);
  po.absolute = 50;
  elfm_peaks *pk = elfm_peaks_create(&po, k.v[0]->w, k.v[0]->h, k.v[0]->nz, &err);
  if (!pk) {
    fprintf(stderr, "%s\n", err.message);
    return 1;
  }
  elfm_detection *det = malloc(10000 * sizeof *det);
  double *ms = malloc((size_t)rounds * sizeof *ms);
  long total = 0;
  double checksum = 0;
  int above_abs = 0;  /* volumes whose threshold was set by the noise rule, not the absolute 50 */
  for (int r = 0; r < rounds; r++) {
    long tot = 0;
    double cs = 0, t = 0;
    for (int i = 0; i < k.n; i++) {
      int n = 0;
      double t0 = bench_wall_s();
      if (elfm_peaks_detect(pk, k.v[i], det, 10000, &n, &err) != ELFM_OK) {
        fprintf(stderr, "%s\n", err.message);
        return 1;
      }
      t += bench_wall_s() - t0;
      if (r == 0 && elfm_peaks_last_threshold(pk) > po.absolute) above_abs++;
      tot += n;
      for (int j = 0; j < n; j++) cs += det[j].x_um + 3 * det[j].y_um + 7 * det[j].z_um;
    }
    ms[r] = 1e3 * t / k.n;
    total = tot;
    checksum = cs;
  }
  qsort(ms, (size_t)rounds, sizeof *ms, cmp_d);
  printf("volumes %d of %d x %d x %d, rounds %d\n", k.n, k.v[0]->w, k.v[0]->h, k.v[0]->nz,
         rounds);
  printf("peaks per round %ld, position checksum %.6f\n", total, checksum);
  printf("volumes where the 6-sigma noise rule set the threshold: %d of %d\n", above_abs, k.n);
  printf("ms per volume: median %.3f, min %.3f, max %.3f\n", ms[rounds / 2], ms[0],
         ms[rounds - 1]);
  for (int i = 0; i < k.n; i++) elfm_volume_free(k.v[i]);
  free(k.v);
  free(det);
  free(ms);
  elfm_peaks_free(pk);
  return 0;
}
