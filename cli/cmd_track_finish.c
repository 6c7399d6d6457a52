/* cmd_track_finish.c — eventlfm track's finished tracks: queued in the
 * linker's order, smoothed by whichever thread is free, filtered and
 * written in order (see cmd_track.h). */
#include <stdlib.h>
#include <string.h>

#include "cmd_track.h"

/* A track whose points the robust fit mostly rejects is not one object
 * (ghosts joined across gaps: on the stage scene such tracks ran against
 * the stage and biased its velocity by 1 %). */
static int too_many_outliers(const track_ctx *c, const elfm_track *t)
{
  return (double)t->n_outliers > c->o->max_outlier_frac * (double)t->n;
}

/* Smooth t; *refit = 1 when it was smoothed again by classical GCV. The
 * modified GCV (gcv_gamma > 1) prices each effective parameter higher, for
 * detections whose errors are correlated from frame to frame; on a track
 * that turns more than most, that can choose a fit so stiff that the
 * robust loss rejects its own object's points, and the track would be
 * dropped as "not one object". Whether it is one is decided on the flexible
 * fit. Worm 200 ms seed 10 at gcv_gamma 5: a 101-point track of a neuron
 * dropped so, alpha 0.948 -> 0.871 (docs/tracker.md "The integral's spline
 * weight"). */
static elfm_status smooth_track(const track_ctx *c, elfm_track *t, const elfm_smooth_options *so,
                                int *refit, elfm_error *err)
{
  *refit = 0;
  elfm_status st = elfm_track_smooth(t, so, err);
  const int gcv = so->spline_weight_ms3 <= 0 && (so->model == ELFM_MODEL_SPLINE ||
                                                  (so->model == ELFM_MODEL_AUTO && so->allow_spline));
  if (st != ELFM_OK || !gcv || !(so->gcv_gamma > 1) || !too_many_outliers(c, t)) return st;
  elfm_smooth_options o1 = *so;
  o1.gcv_gamma = 1;
  *refit = 1;
  return elfm_track_smooth(t, &o1, err);
}

elfm_status track_write_track(track_ctx *c, elfm_track *t, elfm_error *err)
{
  elfm_status st = ELFM_OK;
  /* Written to tracks.csv and the XML scratch at once and freed: the run
   * keeps its info only, a later piece's folded into its track's. */
  if (c->n_info == c->info_cap) {
    size_t cap = c->info_cap ? 2 * c->info_cap : 64;
    elfm_track_info *p = realloc(c->info, cap * sizeof *p);
    if (!p) st = elfm_error_set(err, ELFM_ERR_NOMEM, NULL, -1, "out of memory (track infos)");
    else {
      c->info = p;
      c->info_cap = cap;
    }
  }
  if (st == ELFM_OK) st = elfm_tracks_write_csv(c->ftr, c->p_tr, t, err);
  if (st == ELFM_OK) st = elfm_track_xml_add(c->xml, t, err);
  if (st == ELFM_OK) {
    elfm_track_info ti;
    elfm_track_info_get(t, &ti);
    size_t e = c->n_info;
    if (t->partial && t->piece > 0) /* its track's entry, from the newest */
      for (e = c->n_info; e-- > 0 && c->info[e].id != t->id;) {}
    if (e < c->n_info) elfm_track_info_merge(&c->info[e], &ti);
    else c->info[c->n_info++] = ti;
    c->n_points_kept += (int64_t)ti.n;
  }
  elfm_track_free(t);
  return st;
}

/* Filter a smoothed track (st: its smoothing's status) and write it. */
static elfm_status finish_track(track_ctx *c, elfm_track *t, elfm_status st, elfm_error *err)
{
  if (st == ELFM_OK && too_many_outliers(c, t)) {
    c->n_rejected++;
    elfm_track_free(t);
    return ELFM_OK;
  }
  if (st != ELFM_OK) {
    elfm_track_free(t);
    return st;
  }
  if (c->o->motion == MOTION_STAGE) return track_stage_filter(c, t, err);
  return track_write_track(c, t, err);
}

/* The finished tracks and pieces wait in c->fq, in the linker's order, to
 * be smoothed and written. Each track is its own single-threaded Ceres
 * problem, smoothed by whichever thread takes it: during the run, the
 * driver's threads between their other jobs (track_side_work, through
 * elfm_recon_options.side_work), so that the delivering thread, which
 * links every frame, does not also smooth every track; at the end, all the
 * threads at once (track_drain). The delivering thread writes them, in
 * order, as soon as the oldest is smoothed: filtering and writing stay in
 * the linker's order, so the output does not depend on the thread count
 * or on who smoothed what. Each carries its options and a copy of the
 * frame times, which the delivering thread goes on changing. */
enum { FIN_WAIT, FIN_BUSY, FIN_DONE };

struct fin_track {
  elfm_track *t;
  elfm_smooth_options so;
  elfm_frame_times ft;   /* so.frame_times points here */
  int state;             /* FIN_*, under c->fq_mu */
  elfm_status st;        /* how its smoothing went */
  elfm_error err;
  int refit;             /* 1: smoothed again by classical GCV (smooth_track) */
  double s;              /* seconds spent smoothing it */
};

static void fin_free(struct fin_track *f)
{
  if (!f) return;
  elfm_track_free(f->t);
  elfm_frame_times_free(&f->ft);
  free(f);
}

/* A new entry for t, with the run's options as they are now; on no memory
 * t is freed and NULL returned. */
static struct fin_track *fin_new(track_ctx *c, elfm_track *t, elfm_error *err)
{
  struct fin_track *f = calloc(1, sizeof *f);
  if (f) {
    f->t = t;
    elfm_frame_times_init(&f->ft);
    if (elfm_frame_times_copy(&f->ft, &c->frame_times, err) != ELFM_OK) {
      fin_free(f);
      return NULL;
    }
    f->so = c->o->smooth;
    f->so.frame_times = &f->ft;
    f->so.motion_lead_um = track_motion_lead_um(c);
    f->state = FIN_WAIT;
    return f;
  }
  elfm_track_free(t);
  elfm_error_set(err, ELFM_ERR_NOMEM, NULL, -1, "out of memory (finished tracks)");
  return NULL;
}

/* Append f to the queue (the delivering thread); on no memory f is freed. */
static elfm_status fin_push(track_ctx *c, struct fin_track *f, elfm_error *err)
{
  mtx_lock(&c->fq_mu);
  if (c->fq_head > 0 && c->fq_head == c->fq_n) c->fq_head = c->fq_n = 0;
  if (c->fq_n == c->fq_cap && c->fq_head > 0) { /* the written ones' room back */
    memmove(c->fq, c->fq + c->fq_head, (c->fq_n - c->fq_head) * sizeof *c->fq);
    c->fq_n -= c->fq_head;
    c->fq_head = 0;
  }
  if (c->fq_n == c->fq_cap) {
    const size_t cap = c->fq_cap ? 2 * c->fq_cap : 64;
    struct fin_track **a = realloc(c->fq, cap * sizeof *a);
    if (!a) {
      mtx_unlock(&c->fq_mu);
      fin_free(f);
      return elfm_error_set(err, ELFM_ERR_NOMEM, NULL, -1, "out of memory (finished tracks)");
    }
    c->fq = a;
    c->fq_cap = cap;
  }
  c->fq[c->fq_n++] = f;
  mtx_unlock(&c->fq_mu);
  return ELFM_OK;
}

static void fin_smooth(const track_ctx *c, struct fin_track *f)
{
  const double t0 = cli_now_s();
  elfm_error_clear(&f->err);
  f->st = smooth_track(c, f->t, &f->so, &f->refit, &f->err);
  f->s = cli_now_s() - t0;
}

/* elfm_recon_options.side_work: smooth the oldest waiting track; 0 when
 * none waits. */
int track_side_work(void *user, int thread)
{
  (void)thread;
  track_ctx *c = user;
  struct fin_track *f = NULL;
  mtx_lock(&c->fq_mu);
  for (size_t i = c->fq_head; i < c->fq_n && !f; i++)
    if (c->fq[i]->state == FIN_WAIT) f = c->fq[i];
  if (f) f->state = FIN_BUSY;
  mtx_unlock(&c->fq_mu);
  if (!f) return 0;
  fin_smooth(c, f); /* f stays in the queue: only its writer frees it, once DONE */
  mtx_lock(&c->fq_mu);
  f->state = FIN_DONE;
  mtx_unlock(&c->fq_mu);
  return 1;
}

/* Queue the tracks the linker has finished, and the pieces of long live
 * tracks that are due (--piece-points); then write the smoothed ones at
 * the queue's head. at_end (after the run; no other thread works): smooth
 * what still waits first, all threads at once. */
elfm_status track_drain(track_ctx *c, int at_end, elfm_error *err)
{
  elfm_track *t;
  elfm_status st = ELFM_OK;
  while (st == ELFM_OK && (t = elfm_link_pop_finished(c->lk))) {
    st = track_fill_end(c, t, err);
    if (st != ELFM_OK) {
      elfm_track_free(t);
      break;
    }
    track_det_velocities(c, t);
    struct fin_track *f = fin_new(c, t, err);
    st = f ? fin_push(c, f, err) : ELFM_ERR_NOMEM;
  }
  /* and the old points of long live tracks, as pieces (elfm_link_take_piece) */
  while (st == ELFM_OK && c->o->piece_points > 0) {
    const int pp = c->o->piece_points;
    st = elfm_link_take_piece(c->lk, (size_t)pp, track_piece_keep(pp), track_piece_context(pp), &t,
                              err);
    if (st != ELFM_OK || !t) break;
    struct fin_track *f = fin_new(c, t, err);
    st = f ? fin_push(c, f, err) : ELFM_ERR_NOMEM;
    c->n_pieces++;
  }
  /* after an error the queued tracks are left: track_ctx_free frees them */
  if (st != ELFM_OK) return st;
  if (at_end) {
    const size_t h = c->fq_head, n = c->fq_n - h;
    const int nt = n > 1 && c->n_threads > 1 ? c->n_threads : 1;
#pragma omp parallel for num_threads(nt) schedule(dynamic, 1) if (nt > 1)
    for (size_t i = 0; i < n; i++)
      if (c->fq[h + i]->state == FIN_WAIT) {
        fin_smooth(c, c->fq[h + i]);
        c->fq[h + i]->state = FIN_DONE;
      }
  }
  for (;;) {
    mtx_lock(&c->fq_mu);
    struct fin_track *f = c->fq_head < c->fq_n && c->fq[c->fq_head]->state == FIN_DONE
                              ? c->fq[c->fq_head++]
                              : NULL;
    mtx_unlock(&c->fq_mu);
    if (!f) break;
    c->t_smooth += f->s;
    c->n_refit_gcv += f->refit;
    if (f->st != ELFM_OK && err) *err = f->err;
    st = finish_track(c, f->t, f->st, err); /* writes or frees the track */
    f->t = NULL;
    fin_free(f);
    if (st != ELFM_OK) break;
  }
  return st;
}

void track_finish_free(track_ctx *c)
{
  for (size_t i = c->fq_head; i < c->fq_n; i++) fin_free(c->fq[i]);
  free(c->fq);
  c->fq = NULL;
  c->fq_head = c->fq_n = c->fq_cap = 0;
  if (c->fq_mu_ok) mtx_destroy(&c->fq_mu);
  c->fq_mu_ok = 0;
}
