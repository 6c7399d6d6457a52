/* sim.c — the simulation driver: runs the physics (sim_step.c) slice by
 * slice, puts the events in time order, and writes the outputs.
 *
 * Per slice (default 1 ms): plan, step, noise (sim_step.c); then the events
 * of this slice and those delayed from the last are counting-sorted by time
 * (stable), the ones before the slice end are handed on (sink or EVT 3.0
 * writer, with the LED edges as triggers), later ones (latency) wait for the
 * next slice; truth.csv and stimulus.csv rows of the slice follow.
 * Memory: the pixel state (~30 MB for 1280x720) plus per-slice buffers that
 * grow to the busiest slice, never with the duration.
 */
#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>

#include "sim_ws.h"

/* the output files' paths: a directory and a name, as long as the system
 * takes (PATH_MAX on Linux, with its NUL) */
#define SIM_PATH_CHARS 4096

/* ---- step 5: sort, hand on, keep the late ones ---- */
typedef struct sim_out {
  elfm_sim_sink_fn sink;
  void *user;
  FILE *truth, *stim;
  const char *truth_path, *stim_path;
} sim_out;

static elfm_status emit_sorted(sim_ws *w, int64_t t_lo, int64_t t_end, int final,
                               const sim_out *out, elfm_error *err)
{
  const elfm_scene *s = w->s;
  size_t n = w->n_ev;
  size_t n_trig = 0;
  /* LED edges of this slice as trigger events (channel 0), like the
   * camera's trigger input wired to the LED driver. */
  for (size_t i = 0; i < w->n_stim; i++)
    if (w->stim[i].channel == 0) n_trig++;
  if (n == 0 && n_trig == 0) return ELFM_OK;
  int64_t t_hi = t_lo;
  for (size_t i = 0; i < n; i++)
    if (w->ev[i].t_us > t_hi) t_hi = w->ev[i].t_us;
  size_t range = (size_t)(t_hi - t_lo) + 1;
  if (!sim_grow((void **)&w->counts, &w->cap_counts, range + 1, sizeof *w->counts) ||
      !sim_grow((void **)&w->sorted, &w->cap_sorted, n + 1, sizeof *w->sorted))
    return elfm_error_set(err, ELFM_ERR_NOMEM, s->source, -1, "out of memory (sort)");
  memset(w->counts, 0, (range + 1) * sizeof *w->counts);
  for (size_t i = 0; i < n; i++) w->counts[w->ev[i].t_us - t_lo + 1]++;
  for (size_t i = 1; i <= range; i++) w->counts[i] += w->counts[i - 1];
  for (size_t i = 0; i < n; i++) w->sorted[w->counts[w->ev[i].t_us - t_lo]++] = w->ev[i];
  size_t n_out = n;
  if (!final) {
    n_out = 0;
    while (n_out < n && w->sorted[n_out].t_us < t_end) n_out++;
  }
  if (!sim_grow((void **)&w->c_t, &w->cap_ct, n_out + 1, sizeof *w->c_t) ||
      !sim_grow((void **)&w->c_x, &w->cap_cx, n_out + 1, sizeof *w->c_x) ||
      !sim_grow((void **)&w->c_y, &w->cap_cy, n_out + 1, sizeof *w->c_y) ||
      !sim_grow((void **)&w->c_p, &w->cap_cp, n_out + 1, sizeof *w->c_p))
    goto nomem;
  for (size_t i = 0; i < n_out; i++) {
    w->c_t[i] = w->sorted[i].t_us;
    w->c_x[i] = w->sorted[i].x;
    w->c_y[i] = w->sorted[i].y;
    w->c_p[i] = w->sorted[i].p;
    if (w->sorted[i].p) w->st.n_on++;
    else w->st.n_off++;
  }
  if (!sim_grow((void **)&w->c_trig, &w->cap_trig, n_trig + 1, sizeof *w->c_trig)) goto nomem;
  n_trig = 0;
  for (size_t i = 0; i < w->n_stim; i++) {
    if (w->stim[i].channel != 0) continue;
    w->c_trig[n_trig].t_us = w->stim[i].t_us;
    w->c_trig[n_trig].channel = 0;
    w->c_trig[n_trig].value = (uint8_t)w->stim[i].value;
    n_trig++;
  }
  w->st.n_events += (int64_t)n_out;
  if (out->sink && (n_out || n_trig)) {
    elfm_event_chunk ch;
    memset(&ch, 0, sizeof ch);
    ch.t_us = w->c_t;
    ch.x = w->c_x;
    ch.y = w->c_y;
    ch.p = w->c_p;
    ch.n = ch.cap = n_out;
    ch.trig = w->c_trig;
    ch.n_trig = ch.cap_trig = n_trig;
    elfm_status st = out->sink(out->user, &ch, err);
    if (st) return st;
  }
  /* Keep the rest for the next slice. */
  if (n > n_out) memcpy(w->ev, w->sorted + n_out, (n - n_out) * sizeof *w->ev);
  w->n_ev = n - n_out;
  return ELFM_OK;
nomem:
  return elfm_error_set(err, ELFM_ERR_NOMEM, s->source, -1, "out of memory (output chunk)");
}

/* ---- truth.csv and stimulus.csv ---- */
static elfm_status write_truth(sim_ws *w, int64_t a, int64_t b, int last, const sim_out *out,
                               elfm_error *err)
{
  const elfm_scene *s = w->s;
  if (!out->truth) return ELFM_OK;
  int64_t dt = s->truth_dt_us;
  int64_t t = ((a + dt - 1) / dt) * dt;
  for (;; t += dt) {
    if (t >= b) {
      if (!last) break;
      t = b; /* the end of the recording, once */
      last = 0;
    }
    for (int k = 0; k < s->n_objects; k++) {
      elfm_truth tr;
      elfm_scene_truth(s, k, s->t0_us + t, &tr);
      if (fprintf(out->truth, "%lld,%lld,%.4f,%.4f,%.4f,%.4g\n", (long long)tr.id,
                  (long long)(s->t0_us + t), tr.x_um, tr.y_um, tr.z_um, tr.brightness) < 0)
        return elfm_error_set(err, ELFM_ERR_IO, out->truth_path, -1, "write failed: %s",
                              strerror(errno));
      w->st.n_truth_rows++;
    }
  }
  return ELFM_OK;
}

/* Index of the first of edges[0..n) that is >= t (binary search: a long
 * recording has millions of LED edges; a slice must not scan them all). */
static int64_t first_edge_at(const int64_t *edges, int64_t n, int64_t t)
{
  int64_t lo = 0, hi = n;
  while (lo < hi) {
    int64_t mid = lo + (hi - lo) / 2;
    if (edges[mid] < t) lo = mid + 1;
    else hi = mid;
  }
  return lo;
}

static int cmp_stim(const void *pa, const void *pb)
{
  const sim_stim *a = pa, *b = pb;
  if (a->t_us != b->t_us) return (a->t_us > b->t_us) - (a->t_us < b->t_us);
  return a->channel - b->channel;
}

/* Light edges in [a, b): channel 0 the LED, channel k+1 object k's spikes. */
static elfm_status collect_stimulus(sim_ws *w, int64_t a, int64_t b, elfm_error *err)
{
  const elfm_scene *s = w->s;
  w->n_stim = 0;
  if (s->illum == SIM_ILLUM_RANDOM_PULSES || s->illum == SIM_ILLUM_PERIODIC) {
    /* The illumination alone: edges where it switches. */
    if (s->illum == SIM_ILLUM_RANDOM_PULSES) {
      for (int64_t i = first_edge_at(s->illum_edges, s->n_illum_edges, a);
           i < s->n_illum_edges && s->illum_edges[i] < b; i++) {
        int64_t e = s->illum_edges[i];
        if (!sim_grow((void **)&w->stim, &w->cap_stim, w->n_stim + 1, sizeof *w->stim)) goto nomem;
        w->stim[w->n_stim++] = (sim_stim){s->t0_us + e, 0, (int)((i & 1) == 0)};
      }
    } else {
      int64_t P = (int64_t)s->illum_period_us, len = (int64_t)s->illum_pulse_us;
      for (int64_t m = a / P - 1; m * P < b; m++) {
        int64_t e[2] = {m * P, m * P + len};
        for (int k = 0; k < 2; k++) {
          if (e[k] < a || e[k] >= b) continue;
          if (!sim_grow((void **)&w->stim, &w->cap_stim, w->n_stim + 1, sizeof *w->stim)) goto nomem;
          w->stim[w->n_stim++] = (sim_stim){s->t0_us + e[k], 0, k == 0};
        }
      }
    }
  }
  if (s->has_spikes) {
    for (int k = 0; k < s->n_objects; k++) {
      const sim_object *o = &s->obj[k];
      const int64_t *ed = sim_spike_edges(s, o);
      for (int64_t i = first_edge_at(ed, o->spike_count, a); i < o->spike_count && ed[i] < b; i++) {
        if (!sim_grow((void **)&w->stim, &w->cap_stim, w->n_stim + 1, sizeof *w->stim)) goto nomem;
        w->stim[w->n_stim++] = (sim_stim){s->t0_us + ed[i], k + 1, (int)((i & 1) == 0)};
      }
    }
  }
  if (w->n_stim > 1) qsort(w->stim, w->n_stim, sizeof *w->stim, cmp_stim);
  return ELFM_OK;
nomem:
  return elfm_error_set(err, ELFM_ERR_NOMEM, s->source, -1, "out of memory (stimulus)");
}

static elfm_status write_stimulus(sim_ws *w, const sim_out *out, elfm_error *err)
{
  if (!out->stim) return ELFM_OK;
  for (size_t i = 0; i < w->n_stim; i++) {
    if (fprintf(out->stim, "%lld,%d,%d\n", (long long)w->stim[i].t_us, w->stim[i].channel,
                w->stim[i].value) < 0)
      return elfm_error_set(err, ELFM_ERR_IO, out->stim_path, -1, "write failed: %s",
                            strerror(errno));
  }
  return ELFM_OK;
}

static double now_s(void)
{
  struct timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static elfm_status sim_core(const elfm_scene *s, const sim_out *out, const elfm_sim_options *opt,
                            elfm_sim_stats *stats, elfm_error *err)
{
  sim_ws w;
  double t_start = now_s();
  elfm_status st = sim_ws_init(&w, s, err);
  if (st) return st;
  const int64_t D = s->duration_us, S = s->slice_us;
  const int64_t n_slices = (D + S - 1) / S;
  for (int64_t q = 0; q < n_slices && st == ELFM_OK; q++) {
    int64_t a = q * S, b = a + S < D ? a + S : D;
    int last = q == n_slices - 1;
    if ((st = sim_plan_slice(&w, a, b, err))) break;
    if ((st = sim_step_slice(&w, q, a, b, err))) break;
    if ((st = sim_noise_slice(&w, q, a, b, err))) break;
    if ((st = collect_stimulus(&w, a, b, err))) break;
    if ((st = emit_sorted(&w, s->t0_us + a, s->t0_us + b, last, out, err))) break;
    if ((st = write_truth(&w, a, b, last, out, err))) break;
    if ((st = write_stimulus(&w, out, err))) break;
    if (opt && opt->progress && opt->progress(opt->progress_user, b, D)) {
      st = elfm_error_set(err, ELFM_ERR_INVALID, s->source, -1, "simulation cancelled");
      break;
    }
  }
  w.st.duration_us = D;
  w.st.events_per_s = (double)w.st.n_events / ((double)D * 1e-6);
  w.st.wall_s = now_s() - t_start;
  if (stats) *stats = w.st;
  sim_ws_free(&w);
  return st;
}

elfm_status elfm_sim_run_sink(const elfm_scene *s, elfm_sim_sink_fn sink, void *sink_user,
                              const elfm_sim_options *opt, elfm_sim_stats *stats, elfm_error *err)
{
  if (!s) return elfm_error_set(err, ELFM_ERR_INVALID, NULL, -1, "sim_run: NULL scene");
  sim_out out = {sink, sink_user, NULL, NULL, NULL, NULL};
  return sim_core(s, &out, opt, stats, err);
}

static elfm_status writer_sink(void *user, const elfm_event_chunk *chunk, elfm_error *err)
{
  return elfm_writer_write((elfm_writer *)user, chunk, err);
}

static elfm_status open_text(const char *path, const char *header, FILE **f, elfm_error *err)
{
  *f = fopen(path, "wb");
  if (!*f) return elfm_error_set(err, ELFM_ERR_IO, path, -1, "cannot create: %s", strerror(errno));
  if (fputs(header, *f) == EOF) {
    fclose(*f);
    *f = NULL;
    return elfm_error_set(err, ELFM_ERR_IO, path, -1, "write failed: %s", strerror(errno));
  }
  return ELFM_OK;
}

static elfm_status close_text(FILE *f, const char *path, elfm_status st, elfm_error *err)
{
  if (!f) return st;
  int bad = ferror(f);
  /* fclose reports errors of the final write-back (full disk). */
  if (fclose(f) != 0) bad = 1;
  if (bad && st == ELFM_OK)
    return elfm_error_set(err, ELFM_ERR_IO, path, -1, "write failed: %s", strerror(errno));
  return st;
}

elfm_status elfm_sim_run(const elfm_scene *s, const char *out_dir, const elfm_sim_options *opt,
                         elfm_sim_stats *stats, elfm_error *err)
{
  if (!s || !out_dir) return elfm_error_set(err, ELFM_ERR_INVALID, NULL, -1, "sim_run: NULL argument");
  /* checked before the directory is made: a refused name leaves nothing */
  char p_ev[SIM_PATH_CHARS], p_truth[SIM_PATH_CHARS], p_calib[SIM_PATH_CHARS], p_stim[SIM_PATH_CHARS];
  if (strlen(out_dir) + sizeof "/stimulus.csv" > sizeof p_ev) /* the longest name */
    return elfm_error_set(err, ELFM_ERR_INVALID, out_dir, -1,
                          "output directory name too long (%zu characters, at most %zu)",
                          strlen(out_dir), sizeof p_ev - sizeof "/stimulus.csv");
  if (mkdir(out_dir, 0777) != 0 && errno != EEXIST)
    return elfm_error_set(err, ELFM_ERR_IO, out_dir, -1, "cannot create directory: %s",
                          strerror(errno));
  snprintf(p_ev, sizeof p_ev, "%s/events.raw", out_dir);
  snprintf(p_truth, sizeof p_truth, "%s/truth.csv", out_dir);
  snprintf(p_calib, sizeof p_calib, "%s/calib.json", out_dir);
  snprintf(p_stim, sizeof p_stim, "%s/stimulus.csv", out_dir);

  elfm_status st = elfm_calib_save(&s->calib, p_calib, err);
  if (st) return st;
  elfm_writer *wr = NULL;
  if ((st = elfm_writer_open(p_ev, ELFM_FMT_EVT3, s->sensor.width, s->sensor.height, &wr, err)))
    return st;
  FILE *ft = NULL, *fs = NULL;
  int want_truth = opt ? opt->write_truth : 1;
  if (want_truth) st = open_text(p_truth, "id,t_us,x_um,y_um,z_um,brightness\n", &ft, err);
  if (!st && elfm_scene_has_stimulus(s)) st = open_text(p_stim, "t_us,channel,value\n", &fs, err);
  if (!st) {
    sim_out out = {writer_sink, wr, ft, fs, p_truth, p_stim};
    st = sim_core(s, &out, opt, stats, err);
  }
  st = close_text(ft, p_truth, st, err);
  st = close_text(fs, p_stim, st, err);
  elfm_status cs = elfm_writer_close(wr, st ? NULL : err);
  return st ? st : cs;
}

