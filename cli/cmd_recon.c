/* cmd_recon.c — eventlfm recon: events (or a light-field TIFF stack) ->
 * refocused volumes (EXR), depth-coded MIPs (PNG) and summary.json.
 * Options go into a struct, the work into elfm_recon_run (recon/pipeline.c). */
#include <errno.h>
#include <getopt.h>
#include <limits.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <threads.h>

#include <cjson/cJSON.h>

#include "cli.h"

typedef struct recon_args {
  const char *calib, *events, *tiff, *out;
  elfm_recon_options ro;
  int save_volumes, save_mips, quiet;
} recon_args;

/* A volume waiting to be written (--save-volumes, --save-mips). The
 * callback copies each volume into a queue, and the run's threads write
 * them between their other jobs (elfm_recon_options.side_work), the
 * delivering thread too when the queue is full; the rest at the end, all
 * threads at once. Written from the callback itself, one at a time, the
 * EXR files (ZIP) were 43 ms per 144 x 144 x 101 volume while the other
 * threads waited: the files are independent, so they are written side by
 * side. The queue holds at most `cap` copies: memory does not grow with
 * the recording. A written copy goes to `spare` and is the next volume's
 * copy: the copies are made once per run, not once per volume (a fresh
 * volume's pages are zeroed and faulted in, each time, only to be
 * overwritten by the copy). */
enum { JOB_WAIT, JOB_BUSY, JOB_DONE };

typedef struct out_job {
  elfm_volume *v;         /* a copy: the run reuses its slot */
  int state;              /* JOB_*, under recon_out.mu */
  int wrote_volume, wrote_mip;
  elfm_status st;
  elfm_error err;
} out_job;

typedef struct recon_out {
  const recon_args *a;
  char dir[4096];
  FILE *ffr;              /* frames.csv */
  char p_fr[4200];
  int64_t saved_volumes, saved_mips;
  double write_s;         /* seconds spent writing files, all threads' summed */
  elfm_status status;
  /* the write queue: jobs q[(head + i) % cap], i < n, in frame order */
  mtx_t mu;
  cnd_t done;             /* a job became JOB_DONE */
  out_job *q;
  size_t cap, head, n;
  elfm_volume **spare;    /* written copies to reuse, at most cap */
  size_t n_spare;
} recon_out;

static void usage(FILE *f)
{
  elfm_recon_options d;
  elfm_recon_options_default(&d);
  fprintf(f,
          "usage: eventlfm recon --calib calib.json (--events FILE | --tiff STACK.tif) --out DIR\n"
          "                      [options]\n\n"
          "Refocuses events (or a conventional light-field TIFF stack) into volumes on the\n"
          "z planes of the calibration and writes DIR/summary.json and DIR/frames.csv (each\n"
          "volume's frame, t_us, window and events); with --save-volumes\n"
          "DIR/volumes/vol_NNNNNN.exr (one float channel per z plane), with --save-mips\n"
          "DIR/mips/mip_NNNNNN.png (depth-colour-coded x-y, x-z, y-z projections).\n\n"
          "frames and refocusing (the same options as eventlfm track's):\n");
  cli_recon_options_usage(f, &d);
  fprintf(f,
          "                       (median 3: the paper's; ghost agree:0.3: the measured\n"
          "                       best, docs/recon.md)\n"
          "  --crop-margin-px N   widen each view's crop box, 0..1000 px (default 0)\n"
          "  --tiff-frame-us N    TIFF: time between pages (default dt)\n"
          "output:\n"
          "  --save-volumes       write every volume as EXR\n"
          "  --save-mips          write every volume's MIP as PNG\n"
          "  --quiet              no progress line\n"
          "  -h, --help           this text\n");
}

static int make_dir(const char *path)
{
  if (cli_mkdir_p(path) == 0) return 1; /* and its parents */
  cli_message("recon", CLI_FAIL, "%s: cannot create directory: %s", path, strerror(errno));
  return 0;
}

static void progress(const elfm_recon_stats *s, void *user)
{
  (void)user;
  char left[64];
  fprintf(stderr, "\rrecon: %lld volumes, %.3f s of recording%s, %.2f Mev/s, %.2fx real time   ",
          (long long)s->frames, s->span_s,
          cli_progress_left(left, sizeof left, s->done_frac, s->wall_s), s->events_per_s * 1e-6,
          s->wall_s > 0 ? s->span_s / s->wall_s : 0.0);
}

/* Write one job's files (any thread; no lock held). */
static void job_write(const recon_out *o, out_job *j)
{
  char path[4200];
  j->st = ELFM_OK;
  if (o->a->save_volumes) {
    snprintf(path, sizeof path, "%s/volumes/vol_%06lld.exr", o->dir, (long long)j->v->frame);
    j->st = elfm_volume_write_exr(j->v, path, &j->err);
    if (j->st) return;
    j->wrote_volume = 1;
  }
  if (o->a->save_mips) {
    snprintf(path, sizeof path, "%s/mips/mip_%06lld.png", o->dir, (long long)j->v->frame);
    j->st = elfm_volume_write_mip_png(j->v, path, 0, 1, &j->err);
    if (j->st) return;
    j->wrote_mip = 1;
  }
}

/* Take a waiting job and write it: 1, or 0 when none waits. */
static int job_take(recon_out *o)
{
  out_job *j = NULL;
  mtx_lock(&o->mu);
  for (size_t i = 0; i < o->n && !j; i++) {
    out_job *c = &o->q[(o->head + i) % o->cap];
    if (c->state == JOB_WAIT) j = c;
  }
  if (j) j->state = JOB_BUSY;
  mtx_unlock(&o->mu);
  if (!j) return 0;
  const double t0 = cli_now_s();
  job_write(o, j);
  const double dt = cli_now_s() - t0;
  mtx_lock(&o->mu);
  o->write_s += dt;
  j->state = JOB_DONE;
  cnd_broadcast(&o->done);
  mtx_unlock(&o->mu);
  return 1;
}

static int side_work(void *user, int thread)
{
  (void)thread;
  return job_take(user);
}

/* Retire the written jobs at the head of the queue, in frame order: count
 * their files, free their copies; a failed write's error is returned (its
 * job retired too). Until the queue holds fewer than `below` jobs, write
 * a waiting one here, or else wait for the other threads' writes. */
static elfm_status jobs_retire(recon_out *o, size_t below, elfm_error *err)
{
  elfm_status st = ELFM_OK;
  mtx_lock(&o->mu);
  for (;;) {
    while (st == ELFM_OK && o->n > 0 && o->q[o->head].state == JOB_DONE) {
      out_job *j = &o->q[o->head];
      o->saved_volumes += j->wrote_volume;
      o->saved_mips += j->wrote_mip;
      if (j->st != ELFM_OK) {
        st = j->st;
        *err = j->err;
      }
      if (o->n_spare < o->cap) o->spare[o->n_spare++] = j->v;
      else elfm_volume_free(j->v);
      memset(j, 0, sizeof *j);
      o->head = (o->head + 1) % o->cap;
      o->n--;
    }
    if (st != ELFM_OK || o->n < below) break;
    int waiting = 0;
    for (size_t i = 0; i < o->n && !waiting; i++) waiting = o->q[(o->head + i) % o->cap].state == JOB_WAIT;
    if (waiting) {
      mtx_unlock(&o->mu);
      job_take(o);
      mtx_lock(&o->mu);
    } else {
      cnd_wait(&o->done, &o->mu);
    }
  }
  mtx_unlock(&o->mu);
  return st;
}

static elfm_status on_volume(const elfm_volume *v, void *user, elfm_error *err)
{
  recon_out *o = user;
  /* every volume's time and window: volumes and MIPs are named by frame,
   * and windows opened by trigger edges are not evenly spaced */
  elfm_status fs = cli_frames_csv_row(o->ffr, o->p_fr, v, -1, err);
  if (fs != ELFM_OK) return fs;
  if (!o->a->save_volumes && !o->a->save_mips) return ELFM_OK;
  elfm_status st = jobs_retire(o, o->cap, err); /* room for one more */
  if (st != ELFM_OK) return st;
  mtx_lock(&o->mu);
  elfm_volume *c = o->n_spare > 0 ? o->spare[--o->n_spare] : NULL;
  mtx_unlock(&o->mu);
  if (c && (c->w != v->w || c->h != v->h || c->nz != v->nz)) {
    elfm_volume_free(c); /* a run's volumes are all one size; kept for safety */
    c = NULL;
  }
  if (!c && !(c = elfm_volume_create(v->w, v->h, v->nz, v->um_per_px, v->z_min_um, v->z_step_um, err)))
    return err->code ? err->code : ELFM_ERR_NOMEM;
  float *data = c->data;
  const int data_big = c->data_big;
  *c = *v; /* every field: times, window, counts, geometry */
  c->data = data;
  c->data_big = data_big;
  memcpy(c->data, v->data, (size_t)v->w * v->h * v->nz * sizeof *c->data);
  mtx_lock(&o->mu);
  out_job *j = &o->q[(o->head + o->n) % o->cap];
  memset(j, 0, sizeof *j);
  j->v = c;
  j->state = JOB_WAIT;
  o->n++;
  mtx_unlock(&o->mu);
  return ELFM_OK;
}

/* After the run: write what still waits, all threads at once, and retire
 * every job; the first failed write's error is returned in *err (the
 * other jobs' files are written all the same). */
static elfm_status jobs_finish(recon_out *o, int threads, elfm_error *err)
{
  if (!o->q) return ELFM_OK;
#pragma omp parallel num_threads(threads)
  while (job_take(o)) {
  }
  elfm_status first = ELFM_OK;
  elfm_error e;
  elfm_error_clear(&e);
  while (o->n > 0) {
    elfm_status st = jobs_retire(o, 1, &e);
    if (st != ELFM_OK && first == ELFM_OK) {
      first = st;
      *err = e;
    }
  }
  return first;
}

/* run_err: the error that stopped the run early, or NULL. The summary then
 * says so ("input_error"), so that the counts of a run cut short by a bad
 * file are not mistaken for the whole recording's. */
static int write_summary(const recon_args *a, const recon_out *o, const elfm_calib *cal,
                         const elfm_recon_stats *s, const elfm_error *run_err)
{
  const elfm_recon_options *r = &a->ro;
  cJSON *p = NULL;
  cJSON *root = cli_summary_start(a->calib, a->tiff ? "tiff" : "events", a->tiff ? a->tiff : a->events,
                                  run_err, r, &p);
  cJSON_AddNumberToObject(p, "crop_margin_px", r->refocus.crop_margin_px);
  cJSON_AddNumberToObject(p, "threads", r->threads);
  cJSON *g = cJSON_AddObjectToObject(root, "volume");
  cJSON_AddNumberToObject(g, "w", cal->view_w_px);
  cJSON_AddNumberToObject(g, "h", cal->view_h_px);
  cJSON_AddNumberToObject(g, "nz", elfm_calib_n_planes(cal));
  cJSON_AddNumberToObject(g, "um_per_px", cal->um_per_px);
  cJSON_AddNumberToObject(g, "z_min_um", cal->z_min_um);
  cJSON_AddNumberToObject(g, "z_step_um", cal->z_step_um);
  cJSON *c = cJSON_AddObjectToObject(root, "counts");
  cJSON_AddNumberToObject(c, "events", (double)s->events);
  cJSON_AddNumberToObject(c, "triggers", (double)s->triggers);
  cJSON_AddNumberToObject(c, "volumes", (double)s->frames);
  cJSON_AddNumberToObject(c, "volumes_sparse", (double)s->frames_sparse);
  cJSON_AddNumberToObject(c, "volumes_dense", (double)s->frames_dense);
  cJSON_AddNumberToObject(c, "saved_volumes", (double)o->saved_volumes);
  cJSON_AddNumberToObject(c, "saved_mips", (double)o->saved_mips);
  cli_summary_timing(root, s);
  /* output_s is the callback's time: the copies for the writers; the
   * writing itself, on any of the threads, is here */
  cJSON_AddNumberToObject(cJSON_GetObjectItem(root, "timing"), "write_s", o->write_s);
  char path[4200];
  snprintf(path, sizeof path, "%s/summary.json", o->dir);
  return cli_json_save(root, path, "recon");
}

int cmd_recon(int argc, char **argv)
{
  recon_args a;
  memset(&a, 0, sizeof a);
  elfm_recon_options_default(&a.ro);
  enum { O_CALIB = 256, O_EVENTS, O_TIFF, O_OUT, O_MARGIN, O_TIFF_US, O_SAVE_V,
         O_SAVE_M, O_QUIET };
  static const struct option opts[] = {
    CLI_RECON_LONG_OPTIONS,
    {"calib", required_argument, 0, O_CALIB}, {"events", required_argument, 0, O_EVENTS},
    {"tiff", required_argument, 0, O_TIFF}, {"out", required_argument, 0, O_OUT},
    {"crop-margin-px", required_argument, 0, O_MARGIN},
    {"tiff-frame-us", required_argument, 0, O_TIFF_US}, {"save-volumes", no_argument, 0, O_SAVE_V},
    {"save-mips", no_argument, 0, O_SAVE_M}, {"quiet", no_argument, 0, O_QUIET},
    {"help", no_argument, 0, 'h'}, {0, 0, 0, 0}};
  elfm_recon_options *r = &a.ro;
  cli_recon_parse rp = {.ro = r};
  optind = 1;
  opterr = 0;
  int c;
  while ((c = getopt_long(argc, argv, ":h", opts, NULL)) != -1) {
    const int k = cli_parse_recon_option("recon", c, optarg, &rp);
    if (k == 0) return CLI_USAGE;
    if (k > 0) continue;
    int ok = 1;
    switch (c) {
    case 'h': usage(stdout); return CLI_OK;
    case O_CALIB: a.calib = optarg; break;
    case O_EVENTS: a.events = optarg; break;
    case O_TIFF: a.tiff = optarg; break;
    case O_OUT: a.out = optarg; break;
    case O_MARGIN:
      ok = cli_parse_int_in("recon", "--crop-margin-px", optarg, 0, 1000, "0..1000", &r->refocus.crop_margin_px);
      break;
    case O_TIFF_US: ok = cli_parse_int64("recon", "--tiff-frame-us", optarg, &r->tiff_frame_us); break;
    case O_SAVE_V: a.save_volumes = 1; break;
    case O_SAVE_M: a.save_mips = 1; break;
    case O_QUIET: a.quiet = 1; break;
    default: return cli_bad_option("recon", c, argv);
    }
    if (!ok) return CLI_USAGE;
  }
  if (optind < argc) return cli_message("recon", CLI_USAGE, "unexpected argument '%s'", argv[optind]);
  if (!a.calib || !a.out || (!a.events == !a.tiff)) {
    usage(stderr);
    return cli_message("recon", CLI_USAGE, "--calib, --out and one of --events / --tiff are required");
  }
  if (!cli_check_recon_options("recon", &rp)) return CLI_USAGE;
  elfm_error err;
  elfm_error_clear(&err);
  if (a.tiff && r->median == 3 && !a.quiet)
    cli_message("recon", 0, "note: --median 3 also filters the TIFF frames (use --median 0 for raw)");
  elfm_calib cal;
  if (elfm_calib_load(a.calib, &cal, &err)) return cli_fail("recon", &err);
  double planes[3];
  cli_recon_planes(&rp, planes);
  if (!cli_apply_planes("recon", planes, a.calib, &cal)) return CLI_USAGE;

  recon_out o;
  memset(&o, 0, sizeof o);
  o.a = &a;
  /* the longest name it writes, before any directory is made */
  const char *longest = a.save_volumes ? "/volumes/vol_000000.exr"
                        : a.save_mips  ? "/mips/mip_000000.png"
                                       : "/summary.json";
  if (!cli_out_fits("recon", a.out, longest)) return CLI_FAIL;
  snprintf(o.dir, sizeof o.dir, "%s", a.out);
  if (!make_dir(o.dir)) return CLI_FAIL;
  char sub[4200];
  if (a.save_volumes) {
    snprintf(sub, sizeof sub, "%s/volumes", o.dir);
    if (!make_dir(sub)) return CLI_FAIL;
  }
  if (a.save_mips) {
    snprintf(sub, sizeof sub, "%s/mips", o.dir);
    if (!make_dir(sub)) return CLI_FAIL;
  }
  snprintf(o.p_fr, sizeof o.p_fr, "%s/frames.csv", o.dir);
  if (!(o.ffr = fopen(o.p_fr, "w")))
    return cli_message("recon", CLI_FAIL, "%s: cannot write: %s", o.p_fr, strerror(errno));
  if (cli_frames_csv_header(o.ffr, o.p_fr, 0, &err) != ELFM_OK) {
    fclose(o.ffr);
    return cli_fail("recon", &err);
  }
  if (!a.quiet) r->progress = progress;
  int threads = 1, slots = 1;
  if (elfm_recon_layout(r, &threads, &slots, &err) != ELFM_OK) {
    fclose(o.ffr);
    return cli_fail("recon", &err);
  }
  if (a.save_volumes || a.save_mips) {
    /* one copy per thread being written and one more waiting: flow 200 ms
     * at 2 threads, --save-volumes, 3 runs each: the same wall time as two
     * per thread (4.19 / 4.16 s), whose peak memory was no lower */
    o.cap = (size_t)threads + 1;
    o.q = calloc(o.cap, sizeof *o.q);
    o.spare = calloc(o.cap, sizeof *o.spare);
    if (!o.q || !o.spare || mtx_init(&o.mu, mtx_plain) != thrd_success) {
      free(o.q);
      free(o.spare);
      fclose(o.ffr);
      return cli_message("recon", CLI_FAIL, "out of memory (write queue)");
    }
    if (cnd_init(&o.done) != thrd_success) {
      mtx_destroy(&o.mu);
      free(o.q);
      free(o.spare);
      fclose(o.ffr);
      return cli_message("recon", CLI_FAIL, "out of memory (write queue)");
    }
    r->side_work = side_work;
    r->side_user = &o;
  }
  elfm_recon_stats s;
  memset(&s, 0, sizeof s);
  elfm_status st = a.tiff ? elfm_recon_run_tiff(a.tiff, &cal, r, on_volume, &o, &s, &err)
                          : elfm_recon_run(a.events, &cal, r, on_volume, &o, &s, &err);
  if (o.q) {
    /* the volumes made are written even after an error (the first error
     * is the one reported) */
    elfm_error we;
    elfm_error_clear(&we);
    elfm_status ws = jobs_finish(&o, threads, &we);
    if (ws != ELFM_OK && st == ELFM_OK) {
      st = ws;
      err = we;
    }
    cnd_destroy(&o.done);
    mtx_destroy(&o.mu);
    free(o.q);
    o.q = NULL;
    for (size_t i = 0; i < o.n_spare; i++) elfm_volume_free(o.spare[i]);
    free(o.spare);
  }
  if (!a.quiet) fputc('\n', stderr);
  /* frames.csv holds the volumes made before an error too: close it first */
  int fr_bad = ferror(o.ffr) | (fclose(o.ffr) != 0);
  if (fr_bad) cli_message("recon", CLI_FAIL, "%s: write failed: %s", o.p_fr, strerror(errno));
  if (!write_summary(&a, &o, &cal, &s, st ? &err : NULL) || fr_bad) return CLI_FAIL;
  if (st) return cli_fail("recon", &err);
  if (!a.tiff && !a.quiet) cli_note_no_events("recon", a.events, r->from_us, r->to_us, s.events);
  if (!a.tiff && cli_check_trigger_start("recon", &r->framer, a.events, s.frames, s.triggers))
    return CLI_FAIL;
  if (!a.quiet)
    fprintf(stderr, "recon: %lld events -> %lld volumes (%lld sparse) in %.2f s: %.0f volumes/s, "
            "%.2f Mev/s, %.2fx real time; %s/summary.json\n",
            (long long)s.events, (long long)s.frames, (long long)s.frames_sparse, s.wall_s,
            s.volumes_per_s, s.events_per_s * 1e-6, s.realtime_factor, o.dir);
  return CLI_OK;
}
