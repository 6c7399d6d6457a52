/* pipeline.c — the streaming driver (see elfm_pipeline.h).
 *
 * One pipeline for both sources (event files through the framer, TIFF
 * stacks page by page): read frames into a ring of slots, median-filter and
 * refocus them in parallel, hand the volumes to the callback in order (see
 * run_loop). The framer and the callback stay sequential (the
 * architecture's rule: parallel across frames, sequential state is only
 * ever touched by one thread at a time, in frame order).
 */
#include "elfm_pipeline.h"

#include "big_alloc.h"

#include <limits.h>
#include <math.h>
#include <omp.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <threads.h>
#include <time.h>

static double now_s(void)
{
  struct timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

void elfm_recon_options_default(elfm_recon_options *o)
{
  memset(o, 0, sizeof *o);
  elfm_framer_options_default(&o->framer);
  elfm_refocus_options_default(&o->refocus);
  o->median = 3;
  o->threads = 0;
  o->batch = 0;
  o->from_us = INT64_MIN;
  o->to_us = INT64_MAX;
  o->chunk_events = 65536; /* 0.9 MB of events: a few ms of a busy EVK4 */
}

typedef struct slot {
  elfm_frame *frame, *filtered, *blurred;
  elfm_frame *binned; /* bin_px > 1: the frame the volume is refocused from */
  elfm_volume *vol;
  elfm_refocus_workspace *ws;
  elfm_status status;
  elfm_error err;
} slot;

/* Where frames come from. */
typedef struct source {
  elfm_reader *reader;
  elfm_event_chunk *chunk;
  elfm_framer *framer;
  elfm_tiff_stack *tiff;
  int64_t tiff_page, tiff_frame_us;
  int64_t from_us, to_us;
  int eof;
  /* A read error met with events decoded before it: they are framed like
   * the rest, every window they close is made, then this is returned. */
  elfm_status read_st;
  elfm_error read_err;
  /* The reading stage's own counts (events, triggers, first and last
   * event, span, read_s, frame_s): only the thread reading writes them,
   * so they are kept apart from the delivery stage's and merged after. */
  elfm_recon_stats st;
} source;

typedef struct run {
  const elfm_recon_options *opt;
  const elfm_refocus_plan *plan; /* plan_own, or the caller's (opt->plan) */
  elfm_refocus_plan *plan_own;
  /* the volumes' plan: `plan`, or with bin_px > 1 the binned calibration's
   * (vplan_own, or the caller's opt->volume_plan) */
  const elfm_refocus_plan *vplan;
  elfm_refocus_plan *vplan_own;
  int bin_sw, bin_sh; /* bin_px > 1: the binned sensor (elfm_calib_bin), the binned frames' size */
  int threads, nslots;
  slot *slots;
  elfm_median **medians; /* one per thread */
  elfm_blur **blurs;     /* one per thread (blur_px > 0) */
  source src;
  elfm_recon_stats st;
  int64_t first_window_us;
} run;

static void run_free(run *r)
{
  if (r->slots)
    for (int i = 0; i < r->nslots; i++) {
      elfm_frame_free(r->slots[i].frame);
      elfm_frame_free(r->slots[i].filtered);
      elfm_frame_free(r->slots[i].blurred);
      elfm_frame_free(r->slots[i].binned);
      elfm_volume_free(r->slots[i].vol);
      elfm_refocus_workspace_free(r->slots[i].ws);
    }
  free(r->slots);
  if (r->medians)
    for (int i = 0; i < r->threads; i++) elfm_median_free(r->medians[i]);
  free(r->medians);
  if (r->blurs)
    for (int i = 0; i < r->threads; i++) elfm_blur_free(r->blurs[i]);
  free(r->blurs);
  elfm_refocus_plan_free(r->plan_own);
  elfm_refocus_plan_free(r->vplan_own);
  elfm_reader_close(r->src.reader);
  elfm_chunk_free(r->src.chunk);
  elfm_framer_free(r->src.framer);
  elfm_tiff_close(r->src.tiff);
}

elfm_status elfm_recon_layout(const elfm_recon_options *o, int *threads, int *slots,
                              elfm_error *err)
{
  if (o->threads < 0 || o->threads > 1024 || o->batch < 0 || o->batch > 4096)
    return elfm_error_set(err, ELFM_ERR_INVALID, NULL, -1, "threads %d / batch %d out of range",
                          o->threads, o->batch);
  *threads = o->threads > 0 ? o->threads : omp_get_max_threads();
  /* Two frames per thread: room for the reading and the delivering stage
   * to run ahead of and behind the refocusing threads (run_loop), while
   * the slots' memory (a volume each) stays small. More did not help:
   * `track` on flow 1 s, 2 threads, one run each, 4 / 6 / 8 / 12 slots:
   * 2.08 / 2.16 / 2.23 / 2.24 s wall, 78 / 95 / 111 / 143 MiB. */
  *slots = o->batch > 0 ? o->batch : 2 * *threads;
  return ELFM_OK;
}

/* The ring's memory against the machine's, before any of it is made: each
 * slot holds a frame (and its median's and its blur's, 8 bytes a sensor
 * pixel each) and a volume, and a long recording fills every slot. A
 * batch or thread count far beyond the cores (the options allow 4096
 * and 1024) asked for more than the machine has, and the run was killed
 * once the ring filled: `track --batch 256` on the paper's sensor held
 * 3.3 GB at 300 ms, 4096 would be ~45 GB. Refused when the ring would take
 * more than half of the physical memory (not checked where the system
 * does not tell it). */
static elfm_status ring_fits(const run *r, const elfm_calib *calib, int use_median,
                             elfm_error *err)
{
  const double have_b = elfm_physical_memory_bytes();
  if (!(have_b > 0)) return ELFM_OK;
  int w, h, nz;
  elfm_refocus_plan_size(r->vplan, &w, &h, &nz);
  const double frames = 1.0 + (use_median != 0) + (r->opt->blur_px > 0);
  const double slot_b = 8.0 * calib->sensor_width_px * calib->sensor_height_px * frames +
                        4.0 * w * h * nz;
  const double ring_b = slot_b * r->nslots;
  if (ring_b <= 0.5 * have_b) return ELFM_OK;
  return elfm_error_set(err, ELFM_ERR_NOMEM, NULL, -1,
                        "%d frames in flight (batch, for %d threads) would take %.0f MB of frames "
                        "and volumes, more than half of this machine's %.0f MB: give a smaller "
                        "batch or fewer threads",
                        r->nslots, r->threads, ring_b / 1048576.0, have_b / 1048576.0);
}

static elfm_status run_setup(run *r, const elfm_calib *calib, const elfm_recon_options *opt,
                             int use_median, elfm_error *err)
{
  r->opt = opt;
  if (opt->median != 0 && opt->median != 3 && opt->median != 5)
    return elfm_error_set(err, ELFM_ERR_INVALID, NULL, -1, "median %d: use 0, 3 or 5", opt->median);
  if (opt->blur_px < 0 || opt->blur_px > 2)
    return elfm_error_set(err, ELFM_ERR_INVALID, NULL, -1, "blur %d px: use 0, 1 or 2", opt->blur_px);
  if (opt->from_us >= opt->to_us)
    return elfm_error_set(err, ELFM_ERR_INVALID, NULL, -1, "from_us %lld is not before to_us %lld",
                          (long long)opt->from_us, (long long)opt->to_us);
  if (opt->integral_start_us < 0 || opt->integral_start_age_us < 0)
    return elfm_error_set(err, ELFM_ERR_INVALID, NULL, -1,
                          "integral_start_us %lld and integral_start_age_us %lld must be >= 0",
                          (long long)opt->integral_start_us, (long long)opt->integral_start_age_us);
  elfm_status st = elfm_framer_options_check(&opt->framer, err);
  if (st) return st;
  if (opt->plan) {
    st = elfm_refocus_plan_fits(opt->plan, calib, err);
    if (st) return st;
    r->plan = opt->plan;
  } else {
    st = elfm_refocus_plan_create(calib, &opt->refocus, &r->plan_own, err);
    if (st) return st;
    r->plan = r->plan_own;
  }
  r->vplan = r->plan;
  if (opt->bin_px < 0 || opt->bin_px > 4)
    return elfm_error_set(err, ELFM_ERR_INVALID, NULL, -1, "binning %d px: use 1 to 4", opt->bin_px);
  if (opt->bin_px > 1) {
    elfm_calib binned;
    st = elfm_calib_bin(calib, opt->bin_px, &binned, err);
    if (st) return st;
    r->bin_sw = binned.sensor_width_px;
    r->bin_sh = binned.sensor_height_px;
    if (opt->volume_plan) {
      st = elfm_refocus_plan_fits(opt->volume_plan, &binned, err);
      if (st) return st;
      r->vplan = opt->volume_plan;
    } else {
      st = elfm_refocus_plan_create(&binned, &opt->refocus, &r->vplan_own, err);
      if (st) return st;
      r->vplan = r->vplan_own;
    }
  }
  st = elfm_recon_layout(opt, &r->threads, &r->nslots, err);
  if (st) return st;
  st = ring_fits(r, calib, use_median, err);
  if (st) return st;
  r->slots = calloc((size_t)r->nslots, sizeof *r->slots);
  r->medians = calloc((size_t)r->threads, sizeof *r->medians);
  r->blurs = calloc((size_t)r->threads, sizeof *r->blurs);
  if (!r->slots || !r->medians || !r->blurs)
    return elfm_error_set(err, ELFM_ERR_NOMEM, NULL, -1, "out of memory (pipeline)");
  const int sw = calib->sensor_width_px, sh = calib->sensor_height_px;
  for (int i = 0; i < r->nslots; i++) {
    slot *s = &r->slots[i];
    if (!(s->frame = elfm_frame_create(sw, sh, err))) return err ? err->code : ELFM_ERR_NOMEM;
    if (use_median && !(s->filtered = elfm_frame_create(sw, sh, err)))
      return err ? err->code : ELFM_ERR_NOMEM;
    if (opt->blur_px > 0 && !(s->blurred = elfm_frame_create(sw, sh, err)))
      return err ? err->code : ELFM_ERR_NOMEM;
    if (opt->bin_px > 1 && !(s->binned = elfm_frame_create(r->bin_sw, r->bin_sh, err)))
      return err ? err->code : ELFM_ERR_NOMEM;
    if (!(s->vol = elfm_refocus_volume_create(r->vplan, err))) return err ? err->code : ELFM_ERR_NOMEM;
    st = elfm_refocus_workspace_create(r->vplan, &s->ws, err);
    if (st) return st;
  }
  if (use_median)
    for (int t = 0; t < r->threads; t++) {
      st = elfm_median_create(opt->median, sw, sh, &r->medians[t], err);
      if (st) return st;
    }
  if (opt->blur_px > 0)
    for (int t = 0; t < r->threads; t++) {
      st = elfm_blur_create(opt->blur_px, sw, sh, &r->blurs[t], err);
      if (st) return st;
    }
  r->st.t_first_us = r->src.st.t_first_us = INT64_MAX;
  r->st.t_last_us = r->src.st.t_last_us = INT64_MIN;
  r->first_window_us = INT64_MIN;
  return ELFM_OK;
}

/* Next frame from the event file: pull closed windows from the framer,
 * reading chunks until one closes or the file (or to_us) ends. */
static elfm_status source_events_next(run *r, elfm_frame *out, int *got, elfm_error *err)
{
  source *s = &r->src;
  *got = 0;
  for (;;) {
    double t0 = now_s();
    int ok = elfm_framer_next(s->framer, out);
    s->st.frame_s += now_s() - t0;
    if (ok) {
      if (out->t_start_us >= s->to_us) return ELFM_OK; /* past the range: done */
      *got = 1;
      return ELFM_OK;
    }
    if (s->eof) {
      if (s->read_st && err) *err = s->read_err;
      return s->read_st;
    }
    t0 = now_s();
    elfm_status st = elfm_reader_read(s->reader, s->chunk, err);
    s->st.read_s += now_s() - t0;
    elfm_event_chunk *c = s->chunk;
    if (st) {
      /* A truncated or corrupt file: the events before the error are
       * still the recording's (an acquisition cut short keeps all but
       * its last word); they end it as its last events would (the last
       * window made too, as at the end of a file), and the error comes
       * once their windows are made. Dropped with their chunk, they were
       * up to 65536 events: seconds of a sparse scene. */
      s->read_st = st;
      if (err) s->read_err = *err;
      else elfm_error_set(&s->read_err, st, elfm_reader_path(s->reader), -1, "read failed");
      s->eof = 1;
    }
    if (c->n == 0 && c->n_trig == 0) {
      s->eof = 1;
      elfm_framer_finish(s->framer);
      continue;
    }
    /* clip to [from, to): the reader was positioned at from_us; the end
     * is found here, and then no more is read */
    size_t lo = 0, hi = c->n;
    while (lo < hi && c->t_us[lo] < s->from_us) lo++;
    while (hi > lo && c->t_us[hi - 1] >= s->to_us) hi--;
    if (hi < c->n) {
      s->eof = 1;
      s->read_st = ELFM_OK; /* an error past to_us is outside the range asked for */
    }
    if (c->n_trig > 0 && c->trig[c->n_trig - 1].t_us >= s->to_us) s->eof = 1;
    if (lo > 0) { /* only in the first chunk after a seek: shift down */
      memmove(c->t_us, c->t_us + lo, (hi - lo) * sizeof *c->t_us);
      memmove(c->x, c->x + lo, (hi - lo) * sizeof *c->x);
      memmove(c->y, c->y + lo, (hi - lo) * sizeof *c->y);
      memmove(c->p, c->p + lo, (hi - lo) * sizeof *c->p);
    }
    c->n = hi - lo;
    for (size_t k = 0; k < c->n_trig; k++)
      s->st.triggers += c->trig[k].t_us >= s->from_us && c->trig[k].t_us < s->to_us;
    if (c->n > 0) {
      if (c->t_us[0] < s->st.t_first_us) s->st.t_first_us = c->t_us[0];
      s->st.t_last_us = c->t_us[c->n - 1];
      s->st.events += (int64_t)c->n;
    }
    t0 = now_s();
    st = elfm_framer_push(s->framer, c, err);
    s->st.frame_s += now_s() - t0;
    if (st) {
      /* name the file: the framer does not know it */
      if (err && !err->file[0])
        snprintf(err->file, sizeof err->file, "%s", elfm_reader_path(s->reader));
      return st;
    }
    if (s->eof) elfm_framer_finish(s->framer);
  }
}

static elfm_status source_tiff_next(run *r, elfm_frame *out, int *got, elfm_error *err)
{
  source *s = &r->src;
  double t0 = now_s();
  elfm_status st = elfm_tiff_read(s->tiff, out, got, err);
  s->st.read_s += now_s() - t0;
  if (st || !*got) return st;
  out->index = s->tiff_page;
  out->t_start_us = s->tiff_page * s->tiff_frame_us;
  out->t_end_us = out->t_start_us + s->tiff_frame_us;
  out->t_us = out->t_start_us + s->tiff_frame_us / 2; /* an exposure: its centre */
  out->n_events = 0;
  out->n_triggers = 0;
  s->tiff_page++;
  return ELFM_OK;
}

/* How far through the input (elfm_recon_stats.done_frac): by the file's
 * bytes, or by event time when the run stops at to_us inside the file.
 * Reads the source: only on the thread reading, or after the run. */
static double done_frac(const run *r)
{
  if (!r->src.reader) return -1; /* a TIFF stack: pages, not known ahead */
  double f = elfm_reader_fraction(r->src.reader);
  const int64_t to = r->opt->to_us, last = r->src.st.t_last_us;
  if (to != INT64_MAX && last != INT64_MIN) {
    const int64_t from = r->opt->from_us != INT64_MIN ? r->opt->from_us : r->src.st.t_first_us;
    if (to > from && last >= from) {
      const double ft = (double)(last - from) / (double)(to - from);
      if (ft > f) f = ft > 1 ? 1 : ft;
    }
  }
  return f;
}

/* The reading stage's counts into the stats `st` (which has the rest). */
static void stats_take_source(elfm_recon_stats *st, const elfm_recon_stats *src)
{
  st->events = src->events;
  st->triggers = src->triggers;
  st->t_first_us = src->t_first_us;
  st->t_last_us = src->t_last_us;
  st->span_s = src->span_s;
  st->read_s = src->read_s;
  st->frame_s = src->frame_s;
}

/* Wall time so far and the rates it gives (none while it is 0). */
static void stats_set_rates(elfm_recon_stats *st, double wall_s)
{
  st->wall_s = wall_s;
  if (wall_s > 0) {
    st->events_per_s = (double)st->events / wall_s;
    st->volumes_per_s = (double)st->frames / wall_s;
    st->realtime_factor = st->span_s / wall_s;
  }
}

/* The run as a pipeline of three stages over a ring of slots, frame f in
 * slot f % nslots:
 *
 *   read      one frame at a time, in order (the reader and the framer
 *             carry state from frame to frame);
 *   refocus   median, blur, refocus and the worker hook, on any number
 *             of frames at once;
 *   deliver   the callback, one frame at a time, in order.
 *
 * Every thread of the team takes whichever job is ready: the next
 * delivery first, then the next read, then the callback's side work (see
 * elfm_recon_options.side_work), then a refocus, so that the two
 * sequential stages never wait on the parallel one while it has slack,
 * and what the callback hands off is done before more frames pile up.
 * Before, a batch of frames was read, then refocused in parallel, then
 * delivered, and the other threads idled while one read and delivered:
 * on `track` (flow, 2 threads) reading and delivering were a quarter of
 * the wall time. The outputs do not change: each frame is read, refocused
 * and delivered exactly as before, and only the order in which different
 * frames' work runs does. A slot is read into again only once delivered.
 *
 * The shared counters live under one mutex; the jobs run outside it. */
enum { SLOT_FREE, SLOT_READ, SLOT_BUSY, SLOT_DONE };

typedef struct pipe {
  mtx_t mu;
  cnd_t cv;
  unsigned char *state;         /* [nslots] SLOT_* */
  int64_t n_read, n_taken;      /* frames read; frames taken to refocus */
  int64_t n_delivered;          /* frames delivered */
  int reading, delivering;      /* a thread is in that stage */
  int src_end;                  /* no more frames: the input's end or error */
  int stop;                     /* a delivery failed: no more work */
  elfm_status src_st, st;       /* the input's error; the delivery's */
  elfm_error src_err, err;
  int64_t side_gen;             /* deliveries so far: each may leave side work */
  int64_t side_empty_gen;       /* side_work found nothing as of this delivery */
  elfm_recon_stats src_pub;     /* the reading stage's counts, as of its last frame */
  double done_pub;              /* and how far through the input */
  double t_start, t_progress;
} pipe;

typedef enum { JOB_NONE, JOB_DELIVER, JOB_READ, JOB_SIDE, JOB_REFOCUS, JOB_EXIT } job_kind;

/* The next job for a thread (p->mu held): which, and its frame. */
static job_kind job_next(const run *r, const pipe *p, int64_t *frame)
{
  if (p->stop) return JOB_EXIT;
  const int ns = r->nslots;
  if (!p->delivering && p->n_delivered < p->n_read &&
      p->state[p->n_delivered % ns] == SLOT_DONE) {
    *frame = p->n_delivered;
    return JOB_DELIVER;
  }
  if (!p->reading && !p->src_end && p->n_read < p->n_delivered + ns) {
    *frame = p->n_read;
    return JOB_READ;
  }
  if (r->opt->side_work && p->side_gen != p->side_empty_gen) {
    *frame = p->side_gen;
    return JOB_SIDE;
  }
  if (p->n_taken < p->n_read) {
    *frame = p->n_taken;
    return JOB_REFOCUS;
  }
  if (p->src_end && !p->reading && p->n_delivered == p->n_read) return JOB_EXIT;
  return JOB_NONE;
}

/* Read frame f into its slot; returns 1 when a frame was read. */
static int job_read(run *r, pipe *p, slot *s)
{
  elfm_error e;
  elfm_error_clear(&e);
  int got = 1;
  elfm_status st = r->src.tiff ? source_tiff_next(r, s->frame, &got, &e)
                               : source_events_next(r, s->frame, &got, &e);
  if (st) got = 0;
  if (got) {
    if (r->first_window_us == INT64_MIN) r->first_window_us = s->frame->t_start_us;
    double span = (double)(s->frame->t_end_us - r->first_window_us) * 1e-6;
    if (span > r->src.st.span_s) r->src.st.span_s = span;
  }
  const double done = done_frac(r);
  mtx_lock(&p->mu);
  if (st) {
    p->src_st = st;
    p->src_err = e;
  }
  p->src_end = !got;
  p->src_pub = r->src.st;
  p->done_pub = done;
  return got;
}

static void job_refocus(run *r, slot *s, int i, int thread, elfm_refocus_path path, int use_median)
{
  const elfm_refocus_plan *plan = r->plan;
  const elfm_frame *in = s->frame;
  if (use_median) {
    elfm_median_apply(r->medians[thread], s->frame, s->filtered);
    in = s->filtered;
  }
  if (s->blurred) {
    elfm_blur_apply(r->blurs[thread], in, s->blurred);
    in = s->blurred;
  }
  if (r->opt->no_refocus) {
    elfm_refocus_stamp(r->vplan, in, s->vol);
    s->status = ELFM_OK;
  } else if (s->binned) {
    s->status = elfm_frame_bin(s->binned, in, r->opt->bin_px, &s->err);
    if (s->status == ELFM_OK)
      s->status = elfm_refocus_execute_path(r->vplan, path, s->binned, s->vol, s->ws, &s->err);
  } else {
    s->status = elfm_refocus_execute_path(plan, path, in, s->vol, s->ws, &s->err);
  }
  if (s->status == ELFM_OK && r->opt->worker)
    s->status = r->opt->worker(s->vol, in, plan, i, thread, r->opt->worker_user, &s->err);
}

/* Deliver the frame in slot i: its refocus error, or the callback. */
static elfm_status job_deliver(run *r, slot *s, int i, elfm_volume_fn on_volume, void *user,
                               elfm_error *e)
{
  if (s->status) {
    *e = s->err;
    return s->status;
  }
  if (!r->opt->no_refocus) { /* no_refocus took no path: neither count */
    if (elfm_refocus_workspace_last_path(s->ws) == ELFM_PATH_SPARSE) r->st.frames_sparse++;
    else r->st.frames_dense++;
  }
  const double t0 = now_s();
  elfm_status st = r->opt->on_volume_slot ? r->opt->on_volume_slot(s->vol, i, user, e)
                   : on_volume                ? on_volume(s->vol, user, e)
                                              : ELFM_OK;
  r->st.callback_s += now_s() - t0;
  if (st == ELFM_OK) r->st.frames++;
  return st;
}

/* After a delivery (p->mu held): the progress call, every 0.25 s. It runs
 * on the delivering thread, like the callback, so it may read the state
 * the callback keeps. */
static void deliver_progress(run *r, pipe *p)
{
  const double now = now_s();
  if (!r->opt->progress || now - p->t_progress < 0.25) return;
  p->t_progress = now;
  elfm_recon_stats st = r->st;
  stats_take_source(&st, &p->src_pub);
  stats_set_rates(&st, now - p->t_start);
  st.done_frac = p->done_pub;
  r->opt->progress(&st, r->opt->progress_user);
}

static void pipe_work(run *r, pipe *p, int use_median, elfm_refocus_path path,
                      elfm_volume_fn on_volume, void *user)
{
  const int thread = omp_get_thread_num();
  const int ns = r->nslots;
  mtx_lock(&p->mu);
  for (;;) {
    int64_t f = 0;
    const job_kind k = job_next(r, p, &f);
    if (k == JOB_EXIT) break;
    if (k == JOB_NONE) {
      cnd_wait(&p->cv, &p->mu);
      continue;
    }
    if (k == JOB_SIDE) {
      /* f: the deliveries as of this call; when it finds nothing, no
       * side work is looked for again until the next delivery */
      mtx_unlock(&p->mu);
      const int did = r->opt->side_work(r->opt->side_user, thread);
      mtx_lock(&p->mu);
      if (!did && f > p->side_empty_gen) p->side_empty_gen = f;
      continue;
    }
    const int i = (int)(f % ns);
    slot *s = &r->slots[i];
    if (k == JOB_READ) {
      p->reading = 1;
      mtx_unlock(&p->mu);
      const int got = job_read(r, p, s); /* returns with p->mu held */
      if (got) {
        p->state[i] = SLOT_READ;
        p->n_read++;
      }
      p->reading = 0;
    } else if (k == JOB_REFOCUS) {
      p->state[i] = SLOT_BUSY;
      p->n_taken++;
      mtx_unlock(&p->mu);
      const double t0 = now_s();
      job_refocus(r, s, i, thread, path, use_median);
      const double dt = now_s() - t0;
      mtx_lock(&p->mu);
      r->st.refocus_s += dt;
      p->state[i] = SLOT_DONE;
    } else { /* JOB_DELIVER */
      p->delivering = 1;
      mtx_unlock(&p->mu);
      elfm_error e;
      elfm_error_clear(&e);
      const elfm_status st = job_deliver(r, s, i, on_volume, user, &e);
      mtx_lock(&p->mu);
      p->delivering = 0;
      if (st) {
        p->st = st;
        p->err = e;
        p->stop = 1;
      } else {
        p->state[i] = SLOT_FREE;
        p->n_delivered++;
        p->side_gen++;
        deliver_progress(r, p);
      }
    }
    cnd_broadcast(&p->cv);
  }
  mtx_unlock(&p->mu);
}

static elfm_status run_loop(run *r, int use_median, elfm_refocus_path path,
                            elfm_volume_fn on_volume, void *user, elfm_error *err)
{
  pipe p;
  memset(&p, 0, sizeof p);
  p.state = calloc((size_t)r->nslots, 1);
  if (!p.state) return elfm_error_set(err, ELFM_ERR_NOMEM, NULL, -1, "out of memory (pipeline)");
  if (mtx_init(&p.mu, mtx_plain) != thrd_success) {
    free(p.state);
    return elfm_error_set(err, ELFM_ERR_NOMEM, NULL, -1, "pipeline: cannot create a mutex");
  }
  if (cnd_init(&p.cv) != thrd_success) {
    mtx_destroy(&p.mu);
    free(p.state);
    return elfm_error_set(err, ELFM_ERR_NOMEM, NULL, -1, "pipeline: cannot create a condition");
  }
  p.t_start = p.t_progress = now_s();
#pragma omp parallel num_threads(r->threads)
  pipe_work(r, &p, use_median, path, on_volume, user);
  cnd_destroy(&p.cv);
  mtx_destroy(&p.mu);
  free(p.state);
  stats_take_source(&r->st, &r->src.st);
  /* A delivery's error first: it stopped the run. An input error (a
   * corrupt block in the file) ended the reading, but the frames read
   * before it were still refocused and delivered. */
  if (p.st) {
    if (err) *err = p.err;
    return p.st;
  }
  if (p.src_st && err) *err = p.src_err;
  r->st.input_error = p.src_st != ELFM_OK;
  return p.src_st;
}

static void run_finish_stats(run *r, double wall_s, elfm_recon_stats *out)
{
  stats_set_rates(&r->st, wall_s);
  r->st.done_frac = done_frac(r);
  if (out) *out = r->st;
}

/* The integral's start levels: a second pass over the first
 * integral_start_us of events (from from_us), set on the framer before
 * the run reads anything. Memory: two floats per pixel, freed here. */
static elfm_status integral_start_levels(const char *events_path, const elfm_recon_options *opt,
                                         int w, int h, elfm_framer *framer, elfm_error *err)
{
  elfm_levels lv;
  elfm_status st = elfm_levels_create(w, h, &lv, err);
  if (st) return st;
  elfm_reader *rd = NULL;
  elfm_event_chunk *c = NULL;
  st = elfm_reader_open(events_path, &opt->reader, &rd, err);
  if (!st) {
    c = elfm_chunk_create(opt->chunk_events ? opt->chunk_events : 65536, err);
    if (!c) st = err ? err->code : ELFM_ERR_NOMEM;
  }
  /* A read error here (a truncated or corrupt file) ends this pass with the
   * levels read so far: the run's own pass meets the same error after
   * delivering every volume before it, and reports it then. */
  int stop = 0;
  if (!st && opt->from_us != INT64_MIN) stop = elfm_reader_seek_us(rd, opt->from_us, NULL) != ELFM_OK;
  int64_t t_end = INT64_MAX;
  while (!st && !stop) {
    if (elfm_reader_read(rd, c, NULL) != ELFM_OK || (c->n == 0 && c->n_trig == 0)) break;
    elfm_event_chunk v = *c; /* the events at or after from_us, before to_us */
    size_t lo = 0;
    while (lo < v.n && v.t_us[lo] < opt->from_us) lo++;
    v.t_us += lo;
    v.x += lo;
    v.y += lo;
    v.p += lo;
    v.n -= lo;
    if (v.n == 0) continue;
    if (t_end == INT64_MAX) {
      t_end = opt->integral_start_us > INT64_MAX - v.t_us[0] ? INT64_MAX
                                                              : v.t_us[0] + opt->integral_start_us;
      if (opt->to_us < t_end) t_end = opt->to_us;
    }
    if (elfm_levels_add(&lv, &v, opt->framer.off_weight, t_end) < v.n) break;
  }
  if (!st && lv.t_first_us != INT64_MIN) {
    elfm_levels_result(&lv, opt->framer.off_weight);
    /* leaked as if set integral_start_age_us before the first event */
    const float k = (float)exp(-(double)opt->integral_start_age_us / opt->framer.tau_us);
    for (size_t i = 0; i < (size_t)w * (size_t)h; i++) lv.sum[i] *= k;
    st = elfm_framer_set_levels(framer, lv.sum, err);
  }
  elfm_chunk_free(c);
  elfm_reader_close(rd);
  elfm_levels_free(&lv);
  return st;
}

elfm_status elfm_recon_run(const char *events_path, const elfm_calib *calib,
                           const elfm_recon_options *opt, elfm_volume_fn on_volume, void *user,
                           elfm_recon_stats *stats, elfm_error *err)
{
  const double t_start = now_s();
  elfm_recon_options def;
  if (!opt) {
    elfm_recon_options_default(&def);
    opt = &def;
  }
  run r;
  memset(&r, 0, sizeof r);
  const int use_median = opt->median != 0;
  elfm_status st = run_setup(&r, calib, opt, use_median, err);
  if (!st) st = elfm_reader_open(events_path, &opt->reader, &r.src.reader, err);
  if (!st) {
    int w = elfm_reader_width(r.src.reader), h = elfm_reader_height(r.src.reader);
    if ((w && w != calib->sensor_width_px) || (h && h != calib->sensor_height_px))
      st = elfm_error_set(err, ELFM_ERR_INVALID, events_path, -1,
                          "events are %d x %d but the calibration's sensor is %d x %d", w, h,
                          calib->sensor_width_px, calib->sensor_height_px);
  }
  if (!st) {
    size_t cap = opt->chunk_events ? opt->chunk_events : 65536;
    r.src.chunk = elfm_chunk_create(cap, err);
    if (!r.src.chunk) st = err ? err->code : ELFM_ERR_NOMEM;
  }
  if (!st) {
    elfm_framer_options fo = opt->framer;
    if (opt->from_us != INT64_MIN && fo.start == ELFM_START_FIRST_EVENT) {
      fo.start = ELFM_START_AT_TIME;
      fo.start_us = opt->from_us;
    }
    st = elfm_framer_create(&fo, calib->sensor_width_px, calib->sensor_height_px, &r.src.framer, err);
  }
  r.src.from_us = opt->from_us;
  r.src.to_us = opt->to_us;
  if (!st && opt->integral_start_us > 0 && opt->framer.repr == ELFM_REPR_INTEGRAL)
    st = integral_start_levels(events_path, opt, calib->sensor_width_px, calib->sensor_height_px,
                               r.src.framer, err);
  if (!st && opt->from_us != INT64_MIN) st = elfm_reader_seek_us(r.src.reader, opt->from_us, err);
  if (!st) st = run_loop(&r, use_median, ELFM_PATH_AUTO, on_volume, user, err);
  run_finish_stats(&r, now_s() - t_start, stats);
  run_free(&r);
  return st;
}

elfm_status elfm_recon_run_tiff(const char *tiff_path, const elfm_calib *calib,
                                const elfm_recon_options *opt, elfm_volume_fn on_volume,
                                void *user, elfm_recon_stats *stats, elfm_error *err)
{
  const double t_start = now_s();
  elfm_recon_options def;
  if (!opt) {
    elfm_recon_options_default(&def);
    def.median = 0;
    opt = &def;
  }
  run r;
  memset(&r, 0, sizeof r);
  const int use_median = opt->median != 0;
  elfm_status st = run_setup(&r, calib, opt, use_median, err);
  if (!st) st = elfm_tiff_open(tiff_path, &r.src.tiff, err);
  if (!st && (elfm_tiff_width(r.src.tiff) != calib->sensor_width_px ||
              elfm_tiff_height(r.src.tiff) != calib->sensor_height_px))
    st = elfm_error_set(err, ELFM_ERR_INVALID, tiff_path, -1,
                        "pages are %d x %d but the calibration's sensor is %d x %d",
                        elfm_tiff_width(r.src.tiff), elfm_tiff_height(r.src.tiff),
                        calib->sensor_width_px, calib->sensor_height_px);
  r.src.tiff_frame_us = opt->tiff_frame_us > 0 ? opt->tiff_frame_us : opt->framer.dt_us;
  elfm_refocus_path path = opt->refocus.path == ELFM_PATH_AUTO ? ELFM_PATH_DENSE : opt->refocus.path;
  if (!st) st = run_loop(&r, use_median, path, on_volume, user, err);
  r.st.span_s = (double)r.src.tiff_page * (double)r.src.tiff_frame_us * 1e-6;
  run_finish_stats(&r, now_s() - t_start, stats);
  run_free(&r);
  return st;
}
