/* cmd_traces.c — eventlfm traces: each object's intensity, frame by frame.
 *
 * Objects are a `track` run's tracks, or (static samples: a slice whose
 * neurons flash, beads at rest) clusters of its detections. The events are
 * framed again with the same options as `track`, and in each frame every
 * object's refocused value is read where the object is (elfm_traces.h);
 * no volume is refocused, so this costs little more than reading the file.
 * Options into a struct; the work into elfm_recon_run with no_refocus. */
#include <errno.h>
#include <getopt.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <cjson/cJSON.h>

#include "cli.h"
#include "cmd_track.h"

typedef struct traces_args {
  const char *calib, *events, *tracks, *dets, *out;
  elfm_recon_options ro;
  int hold, min_dets, quiet;
  double cluster_um, cluster_kz;
} traces_args;

typedef struct traces_run {
  elfm_trace_objects *obj;
  elfm_trace_row *rows;
  const elfm_frame **slot_frame;
  const elfm_refocus_plan **slot_plan;
  FILE *f;
  char path[4200];
  int64_t n_rows;
} traces_run;

static void usage(FILE *f)
{
  track_opts t;
  track_defaults(&t);
  fprintf(f,
          "usage: eventlfm traces --calib calib.json --events FILE --out DIR\n"
          "                       (--tracks tracks.csv [--hold] | --detections detections.csv\n"
          "                        [--cluster-um R] [--cluster-kz K] [--min-detections N])\n"
          "                       [frame options]\n\n"
          "Each object's intensity, frame by frame: the refocused volume's value where the\n"
          "object is, whether it was detected in that frame or not (a flash, a spike, a\n"
          "bead going dark). Objects are the tracks of `eventlfm track` (positions between\n"
          "a track's points linear in time), or, for a static sample (a slice whose\n"
          "neurons flash, beads at rest), clusters of its detections: brightest first, a\n"
          "detection joins the nearest cluster within R um, its mean the object's place.\n"
          "The events are framed again as `track` frames them (give the same frame\n"
          "options); no volume is refocused (8 voxels x the views per object and frame).\n"
          "Writes DIR/traces.csv (object_id, frame, t_us, x_um, y_um, z_um, intensity,\n"
          "detected), DIR/objects.csv (object_id, x_um, y_um, z_um, n_points,\n"
          "n_detected, first_t_us, last_t_us) and DIR/traces_summary.json (inputs,\n"
          "options, counts, timing). Progress on stderr.\n\n"
          "objects:\n"
          "  --tracks FILE        tracks.csv of `eventlfm track`\n"
          "  --hold               a track's object also before its first point and after\n"
          "                       its last, at those points (static objects seen only while\n"
          "                       they flashed)\n"
          "  --detections FILE    detections.csv of `eventlfm track`: static objects\n"
          "  --cluster-um R       their clustering radius, sqrt(dx2 + dy2 + (dz/K)2) (3)\n"
          "  --cluster-kz K       its axial scale (2: the axial blur is ~5x the lateral)\n"
          "  --min-detections N   clusters of fewer detections are dropped (1)\n"
          "frames (as eventlfm track's; defaults the same):\n");
  cli_recon_options_usage(f, &t.recon);
  fprintf(f,
          "  --quiet              no progress line\n"
          "  -h, --help           this text\n");
}

static void progress(const elfm_recon_stats *s, void *user)
{
  (void)user;
  char left[64];
  fprintf(stderr, "\rtraces: %lld frames, %.3f s of recording%s, %.2f Mev/s   ",
          (long long)s->frames, s->span_s,
          cli_progress_left(left, sizeof left, s->done_frac, s->wall_s), s->events_per_s * 1e-6);
}

/* Worker (parallel): remember the slot's frame; the sampling runs in frame
 * order in the callback, where each object's cursor moves forward. */
static elfm_status keep_frame(const elfm_volume *vol, const elfm_frame *frame,
                              const elfm_refocus_plan *plan, int slot, int thread, void *user,
                              elfm_error *err)
{
  (void)vol, (void)thread, (void)err;
  traces_run *t = user;
  t->slot_frame[slot] = frame;
  t->slot_plan[slot] = plan;
  return ELFM_OK;
}

static elfm_status on_frame(const elfm_volume *vol, int slot, void *user, elfm_error *err)
{
  traces_run *t = user;
  const size_t n = elfm_trace_objects_frame(t->obj, t->slot_plan[slot], t->slot_frame[slot], vol,
                                            t->rows);
  for (size_t i = 0; i < n; i++) {
    const elfm_trace_row *r = &t->rows[i];
    if (fprintf(t->f, "%lld,%lld,%lld,%.4f,%.4f,%.4f,%.6g,%d\n", (long long)r->id,
                (long long)vol->frame, (long long)vol->t_us, r->x_um, r->y_um, r->z_um,
                r->intensity, r->detected) < 0)
      return elfm_error_set(err, ELFM_ERR_IO, t->path, -1, "write failed: %s", strerror(errno));
  }
  t->n_rows += (int64_t)n;
  return ELFM_OK;
}

static int write_objects(const traces_args *a, const elfm_trace_objects *o)
{
  char path[4200];
  snprintf(path, sizeof path, "%s/objects.csv", a->out);
  FILE *f = fopen(path, "w");
  if (!f) return cli_message("traces", CLI_FAIL, "%s: cannot write: %s", path, strerror(errno));
  int ok = fprintf(f, "object_id,x_um,y_um,z_um,n_points,n_detected,first_t_us,last_t_us\n") >= 0;
  for (size_t i = 0; ok && i < elfm_trace_objects_count(o); i++) {
    elfm_trace_object_info in;
    elfm_trace_objects_info(o, i, &in);
    ok = fprintf(f, "%lld,%.4f,%.4f,%.4f,%zu,%zu,%lld,%lld\n", (long long)in.id, in.x_um, in.y_um,
                 in.z_um, in.n_points, in.n_detected, (long long)in.first_t_us,
                 (long long)in.last_t_us) >= 0;
  }
  if (fclose(f) != 0) ok = 0;
  if (!ok) return cli_message("traces", CLI_FAIL, "%s: write failed: %s", path, strerror(errno));
  return CLI_OK;
}

/* DIR/traces_summary.json: what was read with which options, and what came
 * out (a name of its own: `track` writes summary.json, often to the same
 * directory). run_err: the error that cut the run short, or NULL. */
static int write_summary(const traces_args *a, size_t n_obj, const traces_run *t,
                         const elfm_recon_stats *s, const elfm_error *run_err)
{
  cJSON *p = NULL;
  cJSON *root = cli_summary_start(a->calib, "events", a->events, run_err, &a->ro, &p);
  cJSON_AddStringToObject(cJSON_GetObjectItem(root, "input"), a->tracks ? "tracks" : "detections",
                          a->tracks ? a->tracks : a->dets);
  cJSON_AddStringToObject(p, "objects", a->tracks ? "tracks" : "detection clusters");
  if (a->tracks) {
    cJSON_AddBoolToObject(p, "hold", a->hold);
  } else {
    cJSON_AddNumberToObject(p, "cluster_um", a->cluster_um);
    cJSON_AddNumberToObject(p, "cluster_kz", a->cluster_kz);
    cJSON_AddNumberToObject(p, "min_detections", a->min_dets);
  }
  cJSON *c = cJSON_AddObjectToObject(root, "counts");
  cJSON_AddNumberToObject(c, "objects", (double)n_obj);
  cJSON_AddNumberToObject(c, "events", (double)s->events);
  cJSON_AddNumberToObject(c, "frames", (double)s->frames);
  cJSON_AddNumberToObject(c, "rows", (double)t->n_rows);
  cli_summary_timing(root, s); /* refocus_s: the median filter alone (no_refocus) */
  char path[4200];
  snprintf(path, sizeof path, "%s/traces_summary.json", a->out);
  return cli_json_save(root, path, "traces");
}

int cmd_traces(int argc, char **argv)
{
  traces_args a;
  memset(&a, 0, sizeof a);
  track_opts td;
  track_defaults(&td);
  a.ro = td.recon; /* `track`'s framing, so that the frames are the same */
  a.cluster_um = 3;
  a.cluster_kz = 2;
  a.min_dets = 1;
  enum { O_CALIB = 256, O_EVENTS, O_OUT, O_TRACKS, O_DETS, O_HOLD, O_CLUM, O_CLKZ, O_MIND,
         O_QUIET };
  static const struct option opts[] = {
    CLI_RECON_LONG_OPTIONS,
    {"calib", required_argument, 0, O_CALIB}, {"events", required_argument, 0, O_EVENTS},
    {"out", required_argument, 0, O_OUT}, {"tracks", required_argument, 0, O_TRACKS},
    {"detections", required_argument, 0, O_DETS}, {"hold", no_argument, 0, O_HOLD},
    {"cluster-um", required_argument, 0, O_CLUM}, {"cluster-kz", required_argument, 0, O_CLKZ},
    {"min-detections", required_argument, 0, O_MIND}, {"quiet", no_argument, 0, O_QUIET},
    {"help", no_argument, 0, 'h'}, {0, 0, 0, 0}};
  cli_recon_parse rp = {.ro = &a.ro};
  optind = 1;
  opterr = 0;
  int c;
  while ((c = getopt_long(argc, argv, ":h", opts, NULL)) != -1) {
    const int k = cli_parse_recon_option("traces", c, optarg, &rp);
    if (k == 0) return CLI_USAGE;
    if (k > 0) continue;
    int ok = 1;
    switch (c) {
    case 'h': usage(stdout); return CLI_OK;
    case O_CALIB: a.calib = optarg; break;
    case O_EVENTS: a.events = optarg; break;
    case O_OUT: a.out = optarg; break;
    case O_TRACKS: a.tracks = optarg; break;
    case O_DETS: a.dets = optarg; break;
    case O_HOLD: a.hold = 1; break;
    case O_CLUM:
      ok = cli_parse_double_in("traces", "--cluster-um", optarg, 0, 1, 1e4, "> 0 and <= 10000",
                               &a.cluster_um);
      break;
    case O_CLKZ:
      ok = cli_parse_double_in("traces", "--cluster-kz", optarg, 0, 1, 1e3, "> 0 and <= 1000",
                               &a.cluster_kz);
      break;
    case O_MIND: ok = cli_parse_int_in("traces", "--min-detections", optarg, 1, 1000000,
                                     "1..1000000", &a.min_dets); break;
    case O_QUIET: a.quiet = 1; break;
    default: return cli_bad_option("traces", c, argv);
    }
    if (!ok) return CLI_USAGE;
  }
  if (optind < argc) return cli_message("traces", CLI_USAGE, "unexpected argument '%s'", argv[optind]);
  if (!a.calib || !a.events || !a.out || (!a.tracks == !a.dets)) {
    usage(stderr);
    return cli_message("traces", CLI_USAGE,
                       "--calib, --events, --out and one of --tracks / --detections are required");
  }
  if (a.hold && !a.tracks)
    return cli_message("traces", CLI_USAGE, "--hold goes with --tracks (clusters are held anyway)");
  if (!cli_check_recon_options("traces", &rp)) return CLI_USAGE;
  if (!cli_out_fits("traces", a.out, "/traces_summary.json")) return CLI_FAIL;
  elfm_error err;
  elfm_error_clear(&err);
  elfm_calib cal;
  if (elfm_calib_load(a.calib, &cal, &err)) return cli_fail("traces", &err);
  double planes[3];
  cli_recon_planes(&rp, planes);
  if (!cli_apply_planes("traces", planes, a.calib, &cal)) return CLI_USAGE;

  const char *in = a.tracks ? a.tracks : a.dets;
  elfm_table *tab = NULL;
  if (elfm_table_load_csv(in, &tab, &err)) return cli_fail("traces", &err);
  traces_run t;
  memset(&t, 0, sizeof t);
  elfm_status st = a.tracks ? elfm_trace_objects_from_tracks(tab, a.hold, &t.obj, &err)
                            : elfm_trace_objects_from_detections(tab, a.cluster_um, a.cluster_kz,
                                                                 a.min_dets, &t.obj, &err);
  elfm_table_free(tab);
  if (st) return cli_fail("traces", &err);
  if (cli_mkdir_p(a.out) != 0) {
    elfm_trace_objects_free(t.obj);
    return cli_message("traces", CLI_FAIL, "%s: cannot create directory: %s", a.out, strerror(errno));
  }
  if (write_objects(&a, t.obj) != CLI_OK) {
    elfm_trace_objects_free(t.obj);
    return CLI_FAIL;
  }
  int threads = 0, slots = 0;
  if (elfm_recon_layout(&a.ro, &threads, &slots, &err)) {
    elfm_trace_objects_free(t.obj);
    return cli_fail("traces", &err);
  }
  const size_t nobj = elfm_trace_objects_count(t.obj);
  t.rows = malloc((nobj ? nobj : 1) * sizeof *t.rows);
  t.slot_frame = calloc((size_t)slots, sizeof *t.slot_frame);
  t.slot_plan = calloc((size_t)slots, sizeof *t.slot_plan);
  snprintf(t.path, sizeof t.path, "%s/traces.csv", a.out);
  if (!t.rows || !t.slot_frame || !t.slot_plan || !(t.f = fopen(t.path, "w"))) {
    int rc = t.rows && t.slot_frame && t.slot_plan
                 ? cli_message("traces", CLI_FAIL, "%s: cannot write: %s", t.path, strerror(errno))
                 : cli_message("traces", CLI_FAIL, "out of memory");
    free(t.rows);
    free(t.slot_frame);
    free(t.slot_plan);
    elfm_trace_objects_free(t.obj);
    return rc;
  }
  fprintf(t.f, "object_id,frame,t_us,x_um,y_um,z_um,intensity,detected\n");
  a.ro.no_refocus = 1;
  a.ro.worker = keep_frame;
  a.ro.worker_user = &t;
  a.ro.on_volume_slot = on_frame;
  if (!a.quiet) a.ro.progress = progress;
  elfm_recon_stats s;
  memset(&s, 0, sizeof s);
  st = elfm_recon_run(a.events, &cal, &a.ro, NULL, &t, &s, &err);
  if (!a.quiet) fputc('\n', stderr);
  /* the rows of the frames read before an error are kept: close first */
  const int bad = ferror(t.f) | (fclose(t.f) != 0);
  free(t.rows);
  free(t.slot_frame);
  free(t.slot_plan);
  elfm_trace_objects_free(t.obj);
  if (bad) return cli_message("traces", CLI_FAIL, "%s: write failed: %s", t.path, strerror(errno));
  if (!write_summary(&a, nobj, &t, &s, st ? &err : NULL)) return CLI_FAIL;
  if (st) return cli_fail("traces", &err);
  if (!a.quiet)
    fprintf(stderr, "traces: %zu objects, %lld frames, %lld rows in %.2f s; %s\n", nobj,
            (long long)s.frames, (long long)t.n_rows, s.wall_s, t.path);
  return CLI_OK;
}
