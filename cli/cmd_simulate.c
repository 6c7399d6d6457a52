/* cmd_simulate.c — eventlfm simulate SCENE --out DIR: run the physics
 * simulator (datasets/) and write events.raw, truth.csv, calib.json and,
 * for blinking scenes, stimulus.csv. */
#include <getopt.h>
#include <inttypes.h>
#include <stdio.h>
#include <string.h>
#include <unistd.h>

#include "cli.h"
#include "elfm_datasets.h"

#define MAX_PARAMS 64

typedef struct simulate_opts {
  const char *scene, *out;
  int have_seed;
  int64_t seed;
  double duration_ms; /* < 0: the scene's */
  const char *params[MAX_PARAMS + 1]; /* + the duration */
  int n_params;
  int quiet, no_truth, list;
} simulate_opts;

static void usage(FILE *f)
{
  fprintf(f,
          "usage: eventlfm simulate SCENE --out DIR [--seed N] [--duration-ms D]\n"
          "                         [--param key=value ...] [--no-truth] [--quiet]\n"
          "       eventlfm simulate --list\n"
          "\n"
          "Simulates an event camera behind the Fourier light-field microscope.\n"
          "SCENE is a built-in scene name (see --list) or a scene JSON file.\n"
          "Writes DIR/events.raw (EVT 3.0), DIR/truth.csv, DIR/calib.json and, when\n"
          "the scene has light pulses, DIR/stimulus.csv. The event rate goes to stderr.\n"
          "  --out DIR          output directory (created if missing)\n"
          "  --seed N           random layout and noise (default: the scene's seed);\n"
          "                     same seed, same bytes\n"
          "  --duration-ms D    simulated duration (default: the scene's)\n"
          "  --param key=value  override a scene field, e.g. objects.count=100,\n"
          "                     sensor.shot_noise_hz=0 (repeatable; all are set, then\n"
          "                     the scene is checked once, so fields that must agree,\n"
          "                     such as a stage's motion.v0_mm_per_s and v1, change\n"
          "                     together)\n"
          "  --no-truth         skip truth.csv\n"
          "  --quiet            no progress on stderr\n"
          "  --list             list the built-in scenes\n"
          "  -h, --help         this text\n");
}

/* Progress every 10 %: one updating line on a terminal, else one line each. */
static int progress(void *user, int64_t done_us, int64_t total_us)
{
  int *last = user;
  int pct = total_us > 0 ? (int)(100 * done_us / total_us) : 100;
  if (pct / 10 != *last / 10) {
    int tty = isatty(STDERR_FILENO);
    fprintf(stderr, "%ssimulate: %3d%%%s", tty ? "\r" : "", pct,
            (!tty || done_us == total_us) ? "\n" : "");
    *last = pct;
  }
  return 0;
}

int cmd_simulate(int argc, char **argv)
{
  enum { O_OUT = 256, O_SEED, O_DUR, O_PARAM, O_NOTRUTH, O_QUIET, O_LIST };
  static const struct option longopts[] = {
      {"out", required_argument, 0, O_OUT},
      {"seed", required_argument, 0, O_SEED},
      {"duration-ms", required_argument, 0, O_DUR},
      {"param", required_argument, 0, O_PARAM},
      {"no-truth", no_argument, 0, O_NOTRUTH},
      {"quiet", no_argument, 0, O_QUIET},
      {"list", no_argument, 0, O_LIST},
      {"help", no_argument, 0, 'h'},
      {0, 0, 0, 0}};
  simulate_opts o;
  memset(&o, 0, sizeof o);
  o.duration_ms = -1;
  int c, ok = 1;
  optind = 1;
  while (ok && (c = getopt_long(argc, argv, "h", longopts, NULL)) != -1) {
    switch (c) {
    case O_OUT: o.out = optarg; break;
    case O_SEED:
      ok = cli_parse_int64("simulate", "--seed", optarg, &o.seed);
      if (ok && o.seed < 0) ok = !cli_message("simulate", CLI_USAGE, "--seed must be >= 0");
      o.have_seed = 1;
      break;
    case O_DUR:
      ok = cli_parse_double("simulate", "--duration-ms", optarg, &o.duration_ms);
      if (ok && !(o.duration_ms > 0))
        ok = !cli_message("simulate", CLI_USAGE, "--duration-ms must be > 0");
      break;
    case O_PARAM:
      if (o.n_params == MAX_PARAMS) {
        cli_message("simulate", CLI_USAGE, "at most %d --param options", MAX_PARAMS);
        return CLI_USAGE;
      }
      o.params[o.n_params++] = optarg;
      break;
    case O_NOTRUTH: o.no_truth = 1; break;
    case O_QUIET: o.quiet = 1; break;
    case O_LIST: o.list = 1; break;
    case 'h': usage(stdout); return CLI_OK;
    default: usage(stderr); return CLI_USAGE;
    }
  }
  if (!ok) return CLI_USAGE;
  if (o.list) {
    for (int k = 0; elfm_scene_builtin_name(k); k++) printf("%s\n", elfm_scene_builtin_name(k));
    return CLI_OK;
  }
  if (optind != argc - 1) {
    usage(stderr);
    return cli_message("simulate", CLI_USAGE, "need exactly one SCENE");
  }
  o.scene = argv[optind];
  if (!o.out) return cli_message("simulate", CLI_USAGE, "--out DIR is required");

  elfm_error err;
  elfm_error_clear(&err);
  elfm_scene *s = NULL;
  if (elfm_scene_load(o.scene, &s, &err)) return cli_fail("simulate", &err);
  int rc = CLI_OK;
  /* every --param and the duration in one edit, checked once: fields that
   * must agree (a stage's v0 and v1) can then change together */
  char kv[64];
  if (o.duration_ms > 0) {
    snprintf(kv, sizeof kv, "duration_ms=%.17g", o.duration_ms);
    o.params[o.n_params++] = kv;
  }
  if (elfm_scene_set_params(s, o.params, o.n_params, &err)) rc = cli_fail("simulate", &err);
  if (rc == CLI_OK && o.have_seed && elfm_scene_set_seed(s, (uint64_t)o.seed, &err))
    rc = cli_fail("simulate", &err);
  if (rc == CLI_OK) {
    int last = -1;
    elfm_sim_options so = {o.quiet ? NULL : progress, &last, !o.no_truth};
    elfm_sim_stats st;
    if (!cli_out_fits("simulate", o.out, "/stimulus.csv")) { /* the longest name */
      elfm_scene_free(s);
      return CLI_FAIL;
    }
    /* the directory's parents: elfm_sim_run makes the directory itself
     * (and says so when it cannot) */
    (void)cli_mkdir_p(o.out);
    if (elfm_sim_run(s, o.out, &so, &st, &err)) {
      rc = cli_fail("simulate", &err);
    } else {
      fprintf(stderr,
              "simulate: scene %s seed %" PRIu64 ": %" PRId64 " events in %.3f s (%.2f Mev/s: "
              "%" PRId64 " from light changes, %" PRId64 " noise), %d objects, wall %.2f s\n",
              elfm_scene_name(s), elfm_scene_seed(s), st.n_events, (double)st.duration_us * 1e-6,
              st.events_per_s * 1e-6, st.n_signal, st.n_noise, elfm_scene_n_objects(s), st.wall_s);
      if (!o.quiet)
        fprintf(stderr, "simulate: %" PRId64 " time steps, %.3g pixel updates\n", st.n_steps,
                (double)st.n_pixel_steps);
      printf("%s/events.raw\n", o.out);
    }
  }
  elfm_scene_free(s);
  return rc;
}
