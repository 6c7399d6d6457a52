/* cmd_view.c — eventlfm view: time-coded 3D tracks in a window, or one
 * rendered picture (--screenshot), or frame times (--bench-frames).
 * Options are parsed here; everything else is the gui library (elfm_gui.h). */
#include <getopt.h>
#include <inttypes.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cli.h"

#ifdef ELFM_HAVE_GUI
#include "elfm_gui.h"
#endif

static const char view_usage[] =
  "usage: eventlfm view RUN_DIR | tracks.csv | truth.csv | detections.csv [options]\n"
  "       eventlfm view --synthetic NxM [options]\n"
  "\n"
  "Shows tracks as lines coloured by time (or depth, or track), the box of the\n"
  "reconstructed volume with um ticks, a scale bar, raw detections as points,\n"
  "the MIP of the current frame (when the run saved mips/*.png) and truth in grey.\n"
  "\n"
  "options:\n"
  "  --truth FILE          overlay a simulator truth.csv in grey\n"
  "  --mips DIR            MIP pictures / volumes from elsewhere, e.g. the output of\n"
  "                        eventlfm recon --save-mips (DIR or DIR/mips, DIR/volumes)\n"
  "  --color MODE          (or --colour) time (default), depth, track, or shared:\n"
  "                        each track dimmed, magenta where its detections lay in\n"
  "                        the gates of 2+ tracks (tracks.csv's claims), where\n"
  "                        identities are uncertain\n"
  "  --screenshot OUT.png  render one picture off-screen and exit\n"
  "  --at-us T             time cursor for the picture (default: the end)\n"
  "  --size WxH            picture / window size in pixels (default 1280x800)\n"
  "  --bench-frames N      render N frames off-screen, print ms/frame on stderr;\n"
  "                        the cursor plays through the recording, or stays at\n"
  "                        --at-us T when given (a T past the end draws everything)\n"
  "  --synthetic NxM       N synthetic helical tracks of M points (no input file)\n"
  "  --no-truth, --no-detections, --no-mip   hide these layers\n"
  "  --full-detail         draw every point (no level of detail; for comparison)\n"
  "  -h, --help            this text\n"
  "\n"
  "controls: left-drag rotate, right-drag pan, scroll zoom, r reset view,\n"
  "c colour by time/depth/track/shared, space play/pause, left/right arrows one\n"
  "frame "
  "(shift: 10), home/end, +/- speed, t truth, d detections, m MIP, h help,\n"
  "q/Esc quit.\n"
  "Needs a display with OpenGL 3.3 (for scripts: xvfb-run -a eventlfm view ...).\n";

typedef struct view_opts {
  const char *input;
  const char *truth;
  const char *mips;
  const char *screenshot;
  const char *color;
  int64_t at_us;
  int have_at;
  int width, height;
  int bench_frames;
  int syn_tracks, syn_points;
  int no_truth, no_detections, no_mip, full_detail;
} view_opts;

/* "WxH" with both parts positive ints. */
static int parse_pair(const char *s, int *a, int *b)
{
  char *end = NULL;
  long x = strtol(s, &end, 10);
  if (end == s || (*end != 'x' && *end != 'X')) return 0;
  const char *p = end + 1;
  long y = strtol(p, &end, 10);
  if (end == p || *end != '\0' || x < 1 || y < 1 || x > 1000000 || y > 1000000) return 0;
  *a = (int)x;
  *b = (int)y;
  return 1;
}

static int view_parse(int argc, char **argv, view_opts *o)
{
  enum { O_TRUTH = 256, O_MIPS, O_COLOR, O_SHOT, O_AT, O_SIZE, O_BENCH, O_SYN, O_NOTRUTH, O_NODET,
         O_NOMIP, O_FULL };
  static const struct option longopts[] = {
    {"truth", required_argument, NULL, O_TRUTH},
    {"mips", required_argument, NULL, O_MIPS},
    {"color", required_argument, NULL, O_COLOR},
    {"colour", required_argument, NULL, O_COLOR},
    {"screenshot", required_argument, NULL, O_SHOT},
    {"at-us", required_argument, NULL, O_AT},
    {"size", required_argument, NULL, O_SIZE},
    {"bench-frames", required_argument, NULL, O_BENCH},
    {"synthetic", required_argument, NULL, O_SYN},
    {"no-truth", no_argument, NULL, O_NOTRUTH},
    {"no-detections", no_argument, NULL, O_NODET},
    {"no-mip", no_argument, NULL, O_NOMIP},
    {"full-detail", no_argument, NULL, O_FULL},
    {"help", no_argument, NULL, 'h'},
    {NULL, 0, NULL, 0},
  };
  memset(o, 0, sizeof *o);
  o->width = 1280;
  o->height = 800;
  optind = 1;
  opterr = 0;
  int c;
  while ((c = getopt_long(argc, argv, ":h", longopts, NULL)) != -1) {
    switch (c) {
    case 'h':
      fputs(view_usage, stdout);
      return -1;
    case O_TRUTH: o->truth = optarg; break;
    case O_MIPS: o->mips = optarg; break;
    case O_COLOR: o->color = optarg; break;
    case O_SHOT: o->screenshot = optarg; break;
    case O_AT:
      if (!cli_parse_int64("view", "--at-us", optarg, &o->at_us)) return CLI_USAGE;
      o->have_at = 1;
      break;
    case O_SIZE:
      if (!parse_pair(optarg, &o->width, &o->height) || o->width < 16 || o->height < 16 ||
          o->width > 16384 || o->height > 16384)
        return cli_message("view", CLI_USAGE, "--size expects WxH, 16..16384 each, got '%s'",
                           optarg);
      break;
    case O_BENCH:
      if (!cli_parse_int("view", "--bench-frames", optarg, &o->bench_frames)) return CLI_USAGE;
      if (o->bench_frames < 1)
        return cli_message("view", CLI_USAGE, "--bench-frames must be >= 1");
      break;
    case O_SYN:
      if (!parse_pair(optarg, &o->syn_tracks, &o->syn_points) || o->syn_points < 2 ||
          (int64_t)o->syn_tracks * o->syn_points > 50000000)
        return cli_message("view", CLI_USAGE,
                           "--synthetic expects NxM (tracks x points, M >= 2, N*M <= 5e7), "
                           "got '%s'", optarg);
      break;
    case O_NOTRUTH: o->no_truth = 1; break;
    case O_NODET: o->no_detections = 1; break;
    case O_NOMIP: o->no_mip = 1; break;
    case O_FULL: o->full_detail = 1; break;
    case ':':
      return cli_message("view", CLI_USAGE, "option %s needs a value", argv[optind - 1]);
    default:
      return cli_message("view", CLI_USAGE, "unknown option '%s' (see --help)",
                         argv[optind - 1]);
    }
  }
  if (optind < argc) o->input = argv[optind++];
  if (optind < argc)
    return cli_message("view", CLI_USAGE, "one input only, got also '%s'", argv[optind]);
  if (!o->input && !o->syn_tracks)
    return cli_message("view", CLI_USAGE, "no input: give a run directory or a CSV file "
                       "(see --help)");
  if (o->input && o->syn_tracks)
    return cli_message("view", CLI_USAGE, "give an input or --synthetic, not both");
  if (o->color && strcmp(o->color, "time") && strcmp(o->color, "depth") &&
      strcmp(o->color, "track") && strcmp(o->color, "shared"))
    return cli_message("view", CLI_USAGE, "--color expects time, depth, track or shared, got '%s'",
                       o->color);
  if (o->screenshot && o->bench_frames)
    return cli_message("view", CLI_USAGE, "--screenshot and --bench-frames exclude each other");
  return CLI_OK;
}

#ifdef ELFM_HAVE_GUI
static int view_main(const view_opts *o)
{
  elfm_error err;
  elfm_error_clear(&err);
  elfm_view_data *data = NULL;
  elfm_status st = o->syn_tracks
                       ? elfm_view_data_synthetic((size_t)o->syn_tracks, (size_t)o->syn_points,
                                                  &data, &err)
                       : elfm_view_data_load(o->input, o->truth, &data, &err);
  if (st == ELFM_OK && o->mips) st = elfm_view_data_load_mips(data, o->mips, &err);
  if (st != ELFM_OK) {
    elfm_view_data_free(data);
    return cli_fail("view", &err);
  }
  cli_message("view", 0,
              "%zu tracks (%zu points), %zu truth lines, %zu detections, %zu %s; "
              "t %.3f..%.3f ms; box %s",
              data->tracks.n_lines, data->tracks.n_points, data->truth.n_lines,
              data->n_detections, data->n_mips,
              data->n_mips && data->mips[0].is_volume ? "volumes" : "MIPs",
              data->t_min_us / 1000.0, data->t_max_us / 1000.0,
              data->calib_path[0] ? data->calib_path
              : o->syn_tracks     ? "synthetic"
                                  : "from the data");

  elfm_viewer_options vo;
  elfm_viewer_options_default(&vo);
  vo.width = o->width;
  vo.height = o->height;
  vo.visible = !(o->screenshot || o->bench_frames);
  vo.show_truth = !o->no_truth;
  vo.show_detections = !o->no_detections;
  vo.show_mip = !o->no_mip;
  vo.full_detail = o->full_detail;
  if (o->color)
    vo.color_mode = !strcmp(o->color, "depth")    ? ELFM_COLOR_DEPTH
                    : !strcmp(o->color, "track")  ? ELFM_COLOR_TRACK
                    : !strcmp(o->color, "shared") ? ELFM_COLOR_SHARED
                                                  : ELFM_COLOR_TIME;
  elfm_viewer *v = NULL;
  st = elfm_viewer_create(&vo, data, &v, &err);
  if (st != ELFM_OK) {
    elfm_view_data_free(data);
    return cli_fail("view", &err);
  }
  if (o->have_at) elfm_viewer_set_cursor(v, o->at_us);

  int rc = CLI_OK;
  if (o->screenshot) {
    uint8_t *rgb = malloc((size_t)o->width * o->height * 3);
    if (!rgb) {
      rc = cli_message("view", CLI_FAIL, "out of memory for a %dx%d picture", o->width,
                       o->height);
    } else {
      st = elfm_viewer_render_rgb(v, o->width, o->height, rgb, &err);
      if (st == ELFM_OK) st = elfm_png_write_rgb(o->screenshot, o->width, o->height, rgb, &err);
      if (st != ELFM_OK) rc = cli_fail("view", &err);
      else cli_message("view", 0, "wrote %s (%dx%d)", o->screenshot, o->width, o->height);
      free(rgb);
    }
  } else if (o->bench_frames) {
    double mean = 0, worst = 0, cpu = 0;
    st = elfm_viewer_bench(v, o->bench_frames, o->width, o->height, !o->have_at, &mean, &worst,
                           &cpu, &err);
    if (st != ELFM_OK) {
      rc = cli_fail("view", &err);
    } else {
      fprintf(stderr,
              "eventlfm view: bench %d frames %dx%d, %zu tracks, %zu points, %s, %s: "
              "%.3f ms/frame mean (%.1f fps), %.3f ms worst, %.3f ms CPU/frame; "
              "%zu vertices in the last frame\n",
              o->bench_frames, o->width, o->height, data->tracks.n_lines,
              data->tracks.n_points, o->have_at ? "cursor fixed" : "cursor sweeping",
              o->full_detail ? "full detail" : "level of detail", mean, mean > 0 ? 1000.0 / mean : 0.0, worst, cpu, elfm_viewer_drawn_vertices(v));
    }
  } else {
    st = elfm_viewer_run(v, &err);
    if (st != ELFM_OK) rc = cli_fail("view", &err);
  }
  elfm_viewer_free(v);
  elfm_view_data_free(data);
  return rc;
}
#endif

int cmd_view(int argc, char **argv)
{
  view_opts o;
  int rc = view_parse(argc, argv, &o);
  if (rc == -1) return CLI_OK; /* --help */
  if (rc != CLI_OK) return rc;
#ifdef ELFM_HAVE_GUI
  return view_main(&o);
#else
  return cli_message("view", CLI_FAIL, "this build has no viewer (configured with -DELFM_GUI=OFF)");
#endif
}
