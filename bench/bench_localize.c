/* bench_localize.c — what the view fit (elfm_refocus_localize) can do at
 * best on a simulated scene: for every frame and every bead inside the
 * volume, the fit is started at the bead's true position (an oracle start,
 * as if the detector and the linker were perfect) and scored with the SPEC 7
 * gate. Prints, per depth band, the fraction of truth points it finds, its
 * lateral and axial RMSE, and the time per fit. The gap between this and
 * `eventlfm score` on the same scene is what detection and linking lose;
 * what is missing here the frames do not hold (docs/tracker.md "View fit").
 *
 * usage: bench_localize SCENE_DIR [min_views] [dt_us] [frames] [centred]
 *   SCENE_DIR from `eventlfm simulate` (calib.json, events.raw, truth.csv);
 *   min_views 8 (the guided fit's), dt_us 1000; ON events, time surface
 *   tau = dt, as `eventlfm track` frames them. frames K > 1: the fit sums
 *   each view's windows over the last K frames, each placed where the bead
 *   truly was (elfm_refocus_localize_frames with oracle offsets): the most
 *   a motion-compensated fit over K frames could find. "centred": the K
 *   frames around the scored one (K odd), as gap filling uses them
 *   (`track --fill-frames`); flow seed 1, 8 views, K = 3, at |z| 60-80 um:
 *   found 0.80 either way, 0.54 with one frame. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "bench_clock.h"
#include "elfm_recon.h"

typedef struct {
  int id;
  double t_us, x_um, y_um, z_um, brightness;
} truth_row;

typedef struct {
  truth_row *rows;
  size_t n;
  int n_ids;
  size_t *first; /* [n_ids + 1]: rows of id k are first[k] .. first[k+1]-1, by time */
} truth_table;

static int cmp_row(const void *a, const void *b)
{
  const truth_row *p = a, *q = b;
  if (p->id != q->id) return p->id < q->id ? -1 : 1;
  return (p->t_us > q->t_us) - (p->t_us < q->t_us);
}

static int truth_load(const char *path, truth_table *T)
{
  FILE *f = fopen(path, "r");
  if (!f) return 0;
  char line[512];
  size_t cap = 4096;
  memset(T, 0, sizeof *T);
  T->rows = malloc(cap * sizeof *T->rows);
  if (!T->rows || !fgets(line, sizeof line, f)) {
    fclose(f);
    return 0;
  }
  while (fgets(line, sizeof line, f)) {
    truth_row r;
    if (sscanf(line, "%d,%lf,%lf,%lf,%lf,%lf", &r.id, &r.t_us, &r.x_um, &r.y_um, &r.z_um,
               &r.brightness) != 6 || r.id < 0 || r.id > 1000000)
      continue;
    if (T->n == cap) {
      truth_row *nr = realloc(T->rows, 2 * cap * sizeof *nr);
      if (!nr) break;
      T->rows = nr;
      cap *= 2;
    }
    T->rows[T->n++] = r;
    if (r.id + 1 > T->n_ids) T->n_ids = r.id + 1;
  }
  fclose(f);
  qsort(T->rows, T->n, sizeof *T->rows, cmp_row);
  T->first = calloc((size_t)T->n_ids + 1, sizeof *T->first);
  if (!T->first) return 0;
  for (size_t i = 0; i < T->n; i++) T->first[T->rows[i].id + 1]++;
  for (int k = 0; k < T->n_ids; k++) T->first[k + 1] += T->first[k];
  return T->n > 0;
}

/* Truth of bead k at t_us, linearly interpolated; 0 outside its samples or
 * when it is dark (SPEC 7 counts a bead only while bright). */
static int truth_at(const truth_table *T, int k, double t_us, double p[3])
{
  size_t lo = T->first[k], hi = T->first[k + 1];
  if (hi - lo < 2 || t_us < T->rows[lo].t_us || t_us >= T->rows[hi - 1].t_us) return 0;
  while (hi - lo > 1) {
    size_t mid = (lo + hi) / 2;
    if (T->rows[mid].t_us <= t_us) lo = mid;
    else hi = mid;
  }
  const truth_row *a = &T->rows[lo], *b = &T->rows[lo + 1];
  double w = (t_us - a->t_us) / (b->t_us - a->t_us);
  if (!(a->brightness + w * (b->brightness - a->brightness) > 0)) return 0;
  p[0] = a->x_um + w * (b->x_um - a->x_um);
  p[1] = a->y_um + w * (b->y_um - a->y_um);
  p[2] = a->z_um + w * (b->z_um - a->z_um);
  return 1;
}

int main(int argc, char **argv)
{
  if (argc < 2 || argc > 6 || !strcmp(argv[1], "-h") || !strcmp(argv[1], "--help")) {
    fprintf(stderr, "usage: bench_localize SCENE_DIR [min_views (8)] [dt_us (1000)] [frames (1)] "
                    "[centred]\n");
    return argc < 2 ? 2 : 0;
  }
  const char *dir = argv[1];
  const int min_views = argc > 2 ? atoi(argv[2]) : 8;
  const long dt_us = argc > 3 ? atol(argv[3]) : 1000;
  enum { MAXK = 16 };
  const int nk = argc > 4 ? atoi(argv[4]) : 1;
  const int centred = argc > 5 && !strcmp(argv[5], "centred");
  if (min_views < 2 || min_views > 255 || dt_us < 50 || dt_us > 10000000 || nk < 1 || nk > MAXK ||
      (argc > 5 && !centred) || (centred && nk % 2 == 0)) {
    fprintf(stderr, "bench_localize: min_views must be 2..255, dt_us 50..1e7, frames 1..16 "
                    "(odd with centred)\n");
    return 2;
  }
  char path[1200];
  elfm_error err;
  elfm_calib c;
  snprintf(path, sizeof path, "%s/calib.json", dir);
  if (elfm_calib_load(path, &c, &err) != ELFM_OK) {
    fprintf(stderr, "bench_localize: %s\n", err.message);
    return 1;
  }
  truth_table T;
  snprintf(path, sizeof path, "%s/truth.csv", dir);
  if (!truth_load(path, &T)) {
    fprintf(stderr, "bench_localize: cannot read %s\n", path);
    return 1;
  }
  elfm_refocus_plan *plan = NULL;
  elfm_framer *fr = NULL;
  elfm_reader *rd = NULL;
  elfm_framer_options fo;
  elfm_framer_options_default(&fo);
  fo.polarity = ELFM_POL_ON;
  fo.dt_us = dt_us;
  fo.tau_us = (double)dt_us;
  snprintf(path, sizeof path, "%s/events.raw", dir);
  if (elfm_refocus_plan_create(&c, NULL, &plan, &err) != ELFM_OK ||
      elfm_framer_create(&fo, c.sensor_width_px, c.sensor_height_px, &fr, &err) != ELFM_OK ||
      elfm_reader_open(path, NULL, &rd, &err) != ELFM_OK) {
    fprintf(stderr, "bench_localize: %s\n", err.message);
    return 1;
  }
  elfm_event_chunk *ch = elfm_chunk_create(1 << 16, &err);
  elfm_frame *fm = elfm_frame_create(c.sensor_width_px, c.sensor_height_px, &err);
  /* ring of the last nk frames (sparse copies), ring[head] the newest */
  elfm_frame *ring[MAXK] = {NULL};
  int n_ring = 0, head = 0;
  for (int j = 0; j < nk; j++)
    if (!(ring[j] = elfm_frame_create(c.sensor_width_px, c.sensor_height_px, &err))) fm = NULL;
  if (!ch || !fm) {
    fprintf(stderr, "bench_localize: out of memory\n");
    return 1;
  }
  int W, H, NZ;
  elfm_refocus_plan_size(plan, &W, &H, &NZ);
  const double half_x_um = 0.5 * (W - 1) * c.um_per_px, half_y_um = 0.5 * (H - 1) * c.um_per_px;
  const double z_lo = c.z_min_um, z_hi = c.z_min_um + (NZ - 1) * c.z_step_um;
  elfm_localize_options lo;
  elfm_localize_options_default(&lo);
  lo.min_views = min_views;
  enum { NB = 5 };
  const double edge[NB + 1] = {0, 20, 40, 60, 80, 1e9};
  long tot[NB] = {0}, found[NB] = {0};
  double e_lat2[NB] = {0}, e_z2[NB] = {0}, fit_s = 0;
  long fits = 0;
  int eof = 0;
  for (;;) {
    if (!elfm_framer_next(fr, fm)) {
      if (eof) break;
      if (elfm_reader_read(rd, ch, &err) != ELFM_OK) {
        fprintf(stderr, "bench_localize: %s\n", err.message);
        return 1;
      }
      if (ch->n == 0 && ch->n_trig == 0) {
        eof = 1;
        elfm_framer_finish(fr);
      } else if (elfm_framer_push(fr, ch, &err) != ELFM_OK) {
        fprintf(stderr, "bench_localize: %s\n", err.message);
        return 1;
      }
      continue;
    }
    head = (head + 1) % nk; /* fm into the ring's next slot (same size: cannot fail) */
    elfm_frame_copy(ring[head], fm, &err);
    if (n_ring < nk) n_ring++;
    if (centred && n_ring < nk) continue;
    const elfm_frame *tgt = centred ? ring[(head - nk / 2 + nk) % nk] : fm;
    for (int k = 0; k < T.n_ids; k++) {
      double p[3];
      if (!truth_at(&T, k, (double)tgt->t_us, p)) continue;
      if (fabs(p[0]) > half_x_um || fabs(p[1]) > half_y_um || p[2] < z_lo || p[2] > z_hi) continue;
      int b = 0;
      while (b < NB - 1 && fabs(p[2]) >= edge[b + 1]) b++;
      tot[b]++;
      const double X = p[0] / c.um_per_px + 0.5 * (W - 1), Y = p[1] / c.um_per_px + 0.5 * (H - 1),
                   K = (p[2] - c.z_min_um) / c.z_step_um;
      elfm_localize_result r;
      double t0 = bench_wall_s();
      const elfm_frame *use[MAXK];
      double off[MAXK][3];
      int nu = 0;
      for (int j0 = 0; j0 < n_ring; j0++) {
        /* ring age j (0 = newest); centred: the scored frame (age nk/2)
         * first, then the newer ones, then the older */
        int j = centred ? (j0 == 0 ? nk / 2 : (j0 <= nk / 2 ? j0 - 1 : j0)) : j0;
        const elfm_frame *g = ring[(head - j + nk) % nk];
        double pj[3];
        if (!truth_at(&T, k, (double)g->t_us, pj)) continue;
        use[nu] = g;
        off[nu][0] = (pj[0] - p[0]) / c.um_per_px;
        off[nu][1] = (pj[1] - p[1]) / c.um_per_px;
        off[nu][2] = pj[2] - p[2];
        nu++;
      }
      int ok = nk == 1 ? elfm_refocus_localize(plan, tgt, X, Y, K, &lo, &r)
                       : nu > 0 && elfm_refocus_localize_frames(plan, use, (const double (*)[3])off,
                                                                nu, X, Y, K, &lo, &r);
      fit_s += bench_wall_s() - t0;
      fits++;
      if (!ok) continue;
      double dx = (r.x_vox - X) * c.um_per_px, dy = (r.y_vox - Y) * c.um_per_px,
             dz = (r.z_vox - K) * c.z_step_um;
      if (sqrt(dx * dx + dy * dy + dz * dz / 16) >= 4) continue; /* SPEC 7 gate */
      found[b]++;
      e_lat2[b] += dx * dx + dy * dy;
      e_z2[b] += dz * dz;
    }
  }
  printf("bench_localize: %s, view fit from the true position, min_views %d, dt %ld us, "
         "%d frame(s)\n", dir, min_views, dt_us, nk);
  printf("|z| um     truth  found   lateral RMSE/axis um  axial RMSE um\n");
  for (int b = 0; b < NB; b++) {
    if (!tot[b]) continue;
    char band[32];
    if (b < NB - 1) snprintf(band, sizeof band, "%3.0f-%3.0f", edge[b], edge[b + 1]);
    else snprintf(band, sizeof band, "%3.0f+    ", edge[b]);
    long m = found[b] ? found[b] : 1;
    printf("%s  %6ld  %.3f   %.2f                  %.2f\n", band, tot[b], (double)found[b] / tot[b],
           sqrt(e_lat2[b] / 2 / m), sqrt(e_z2[b] / m));
  }
  printf("%ld fits, %.1f us each (wall, one thread)\n", fits, fits ? 1e6 * fit_s / fits : 0.0);
  elfm_frame_free(fm);
  for (int j = 0; j < nk; j++) elfm_frame_free(ring[j]);
  elfm_chunk_free(ch);
  elfm_reader_close(rd);
  elfm_framer_free(fr);
  elfm_refocus_plan_free(plan);
  free(T.rows);
  free(T.first);
  return 0;
}
