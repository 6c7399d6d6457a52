/* cmd_recon.c — eventlfm recon: events (or a light-field TIFF stack) ->
 * refocused volumes (EXR), depth-coded MIPs (PNG) and summary.json.
 * Options go into a struct, the work into elfm_recon_run (recon/pipeline.c). */
#include <errno.h>
#include <getopt.h>
#include <limits.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include <cjson/cJSON.h>

#include "cli.h"

typedef struct recon_args {
  const char *calib, *events, *tiff, *out;
  elfm_recon_options ro;
  int save_volumes, save_mips, quiet;
} recon_args;

typedef struct recon_out {
  const recon_args *a;
  char dir[4096];
  FILE *ffr;              /* frames.csv */
  char p_fr[4200];
  int64_t saved_volumes, saved_mips;
  elfm_status status;
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
          "  --crop-margin-px N   widen each view's crop box (default 0)\n"
          "  --tiff-frame-us N    TIFF: time between pages (default dt)\n"
          "output:\n"
          "  --save-volumes       write every volume as EXR\n"
          "  --save-mips          write every volume's MIP as PNG\n"
          "  --quiet              no progress line\n"
          "  -h, --help           this text\n");
}

static int make_dir(const char *path)
{
  if (mkdir(path, 0777) == 0 || errno == EEXIST) return 1;
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

static elfm_status on_volume(const elfm_volume *v, void *user, elfm_error *err)
{
  recon_out *o = user;
  char path[4200];
  /* every volume's time and window: volumes and MIPs are named by frame,
   * and windows opened by trigger edges are not evenly spaced */
  elfm_status fs = cli_frames_csv_row(o->ffr, o->p_fr, v, -1, err);
  if (fs != ELFM_OK) return fs;
  if (o->a->save_volumes) {
    snprintf(path, sizeof path, "%s/volumes/vol_%06lld.exr", o->dir, (long long)v->frame);
    elfm_status st = elfm_volume_write_exr(v, path, err);
    if (st) return st;
    o->saved_volumes++;
  }
  if (o->a->save_mips) {
    snprintf(path, sizeof path, "%s/mips/mip_%06lld.png", o->dir, (long long)v->frame);
    elfm_status st = elfm_volume_write_mip_png(v, path, 0, 1, err);
    if (st) return st;
    o->saved_mips++;
  }
  return ELFM_OK;
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
    case O_MARGIN: ok = cli_parse_int("recon", "--crop-margin-px", optarg, &r->refocus.crop_margin_px); break;
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
  elfm_recon_stats s;
  memset(&s, 0, sizeof s);
  elfm_status st = a.tiff ? elfm_recon_run_tiff(a.tiff, &cal, r, on_volume, &o, &s, &err)
                          : elfm_recon_run(a.events, &cal, r, on_volume, &o, &s, &err);
  if (!a.quiet) fputc('\n', stderr);
  /* frames.csv holds the volumes made before an error too: close it first */
  int fr_bad = ferror(o.ffr) | (fclose(o.ffr) != 0);
  if (fr_bad) cli_message("recon", CLI_FAIL, "%s: write failed: %s", o.p_fr, strerror(errno));
  if (!write_summary(&a, &o, &cal, &s, st ? &err : NULL) || fr_bad) return CLI_FAIL;
  if (st) return cli_fail("recon", &err);
  if (!a.tiff && cli_check_trigger_start("recon", &r->framer, a.events, s.frames, s.triggers))
    return CLI_FAIL;
  if (!a.quiet)
    fprintf(stderr, "recon: %lld events -> %lld volumes (%lld sparse) in %.2f s: %.0f volumes/s, "
            "%.2f Mev/s, %.2fx real time; %s/summary.json\n",
            (long long)s.events, (long long)s.frames, (long long)s.frames_sparse, s.wall_s,
            s.volumes_per_s, s.events_per_s * 1e-6, s.realtime_factor, o.dir);
  return CLI_OK;
}
