/* cmd_calib.c — eventlfm calib from-optics: build calib.json from the optics
 * (SPEC §2), defaults = the EventLFM paper's system; `calib show FILE`
 * loads and checks a calib.json and prints its summary; `calib refine` is
 * in cmd_calib_refine.c. */
#include <getopt.h>
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "cli.h"

typedef struct calib_opts {
  elfm_optics optics;
  int width, height;
  double pixel_um;
  int view_w_px, view_h_px;
  double z_min_um, z_max_um, z_step_um;
  const char *out;
} calib_opts;

static void usage(FILE *f)
{
  fprintf(f,
          "usage: eventlfm calib from-optics [options] --out calib.json\n"
          "       eventlfm calib refine --calib calib.json --events FILE --out refined.json\n"
          "       eventlfm calib show calib.json\n"
          "\n"
          "from-optics builds a calibration from the microscope's optics (SPEC 2: exact\n"
          "non-paraxial view angles; views laid out at the nominal spacing around the\n"
          "sensor centre). Defaults are the EventLFM paper's system. refine fits the\n"
          "views' centres to a recording of beads (eventlfm calib refine --help). show\n"
          "lists the views and how much of each one's crop lies on the sensor.\n"
          "  --na X              objective NA (0.75)\n"
          "  --n-medium X        refractive index of the medium (1.0)\n"
          "  --magnification X   objective magnification f_tube/f_obj (20)\n"
          "  --f-tube-mm X       tube lens focal length (200)\n"
          "  --f-fourier-mm X    Fourier lens focal length (80)\n"
          "  --f-mla-mm X        microlens focal length (16.8)\n"
          "  --mla-pitch-um X    microlens pitch (600)\n"
          "  --relay X           relay magnification (1.25)\n"
          "  --wavelength-um X   emission wavelength (0.52)\n"
          "  --lenslets N        lenslets per side, odd (5)\n"
          "  --mla-rotation-deg A  the lens array turned against the sensor's rows, -45..45\n"
          "                      degrees (0): turns the views' centres and disparities\n"
          "  --sensor WxH        sensor size in pixels (1280x720, EVK4)\n"
          "  --pixel-um X        sensor pixel pitch (4.86, IMX636)\n"
          "  --view-size WxH     cropped view size = volume W x H (144x144)\n"
          "  --z-min-um X --z-max-um X --z-step-um X   refocus planes (-100, 100, 2)\n"
          "  --out FILE          where to write calib.json (required)\n"
          "  -h, --help          this text\n");
}

static int parse_wxh(const char *opt, const char *s, int *w, int *h)
{
  char a[32], b[32];
  const char *x = s ? strchr(s, 'x') : NULL;
  if (!x || (size_t)(x - s) >= sizeof a || strlen(x + 1) >= sizeof b) {
    cli_message("calib", CLI_USAGE, "%s expects WxH, got '%s'", opt, s ? s : "");
    return 0;
  }
  memcpy(a, s, (size_t)(x - s));
  a[x - s] = 0;
  strcpy(b, x + 1);
  return cli_parse_int("calib", opt, a, w) && cli_parse_int("calib", opt, b, h);
}

static int from_optics(int argc, char **argv)
{
  enum { O_NA = 256, O_NM, O_MAG, O_FT, O_FF, O_FM, O_PITCH, O_RELAY, O_WL, O_LENS, O_SENSOR,
         O_PIX, O_VIEW, O_ZMIN, O_ZMAX, O_ZSTEP, O_OUT, O_ROT };
  static const struct option longopts[] = {
      {"na", required_argument, 0, O_NA},
      {"n-medium", required_argument, 0, O_NM},
      {"magnification", required_argument, 0, O_MAG},
      {"f-tube-mm", required_argument, 0, O_FT},
      {"f-fourier-mm", required_argument, 0, O_FF},
      {"f-mla-mm", required_argument, 0, O_FM},
      {"mla-pitch-um", required_argument, 0, O_PITCH},
      {"relay", required_argument, 0, O_RELAY},
      {"wavelength-um", required_argument, 0, O_WL},
      {"lenslets", required_argument, 0, O_LENS},
      {"mla-rotation-deg", required_argument, 0, O_ROT},
      {"sensor", required_argument, 0, O_SENSOR},
      {"pixel-um", required_argument, 0, O_PIX},
      {"view-size", required_argument, 0, O_VIEW},
      {"z-min-um", required_argument, 0, O_ZMIN},
      {"z-max-um", required_argument, 0, O_ZMAX},
      {"z-step-um", required_argument, 0, O_ZSTEP},
      {"out", required_argument, 0, O_OUT},
      {"help", no_argument, 0, 'h'},
      {0, 0, 0, 0}};
  calib_opts o;
  memset(&o, 0, sizeof o);
  elfm_optics_default(&o.optics);
  o.width = 1280;
  o.height = 720;
  o.pixel_um = 4.86;
  o.view_w_px = o.view_h_px = 0; /* 0: keep from_optics' default */
  o.z_min_um = -100;
  o.z_max_um = 100;
  o.z_step_um = 2;
  int c, ok = 1;
  optind = 1;
  while (ok && (c = getopt_long(argc, argv, "h", longopts, NULL)) != -1) {
    switch (c) {
    case O_NA: ok = cli_parse_double("calib", "--na", optarg, &o.optics.na); break;
    case O_NM: ok = cli_parse_double("calib", "--n-medium", optarg, &o.optics.n_medium); break;
    case O_MAG: ok = cli_parse_double("calib", "--magnification", optarg, &o.optics.magnification); break;
    case O_FT: ok = cli_parse_double("calib", "--f-tube-mm", optarg, &o.optics.f_tube_mm); break;
    case O_FF: ok = cli_parse_double("calib", "--f-fourier-mm", optarg, &o.optics.f_fourier_mm); break;
    case O_FM: ok = cli_parse_double("calib", "--f-mla-mm", optarg, &o.optics.f_mla_mm); break;
    case O_PITCH: ok = cli_parse_double("calib", "--mla-pitch-um", optarg, &o.optics.mla_pitch_um); break;
    case O_RELAY: ok = cli_parse_double("calib", "--relay", optarg, &o.optics.relay); break;
    case O_WL: ok = cli_parse_double("calib", "--wavelength-um", optarg, &o.optics.wavelength_um); break;
    case O_LENS: ok = cli_parse_int("calib", "--lenslets", optarg, &o.optics.lenslets_per_side); break;
    case O_ROT: ok = cli_parse_double("calib", "--mla-rotation-deg", optarg, &o.optics.mla_rotation_deg); break;
    case O_SENSOR: ok = parse_wxh("--sensor", optarg, &o.width, &o.height); break;
    case O_PIX: ok = cli_parse_double("calib", "--pixel-um", optarg, &o.pixel_um); break;
    case O_VIEW: ok = parse_wxh("--view-size", optarg, &o.view_w_px, &o.view_h_px); break;
    case O_ZMIN: ok = cli_parse_double("calib", "--z-min-um", optarg, &o.z_min_um); break;
    case O_ZMAX: ok = cli_parse_double("calib", "--z-max-um", optarg, &o.z_max_um); break;
    case O_ZSTEP: ok = cli_parse_double("calib", "--z-step-um", optarg, &o.z_step_um); break;
    case O_OUT: o.out = optarg; break;
    case 'h': usage(stdout); return CLI_OK;
    default: usage(stderr); return CLI_USAGE;
    }
  }
  if (!ok) return CLI_USAGE;
  if (optind < argc) return cli_message("calib", CLI_USAGE, "unexpected argument '%s'", argv[optind]);
  if (!o.out) return cli_message("calib", CLI_USAGE, "--out FILE is required");
  if (!(o.z_step_um > 0) || o.z_max_um < o.z_min_um)
    return cli_message("calib", CLI_USAGE, "need --z-step-um > 0 and --z-max-um >= --z-min-um");
  if (o.view_w_px < 0 || o.view_h_px < 0 || (o.view_w_px == 0) != (o.view_h_px == 0))
    return cli_message("calib", CLI_USAGE, "--view-size must be positive WxH");

  elfm_error err;
  elfm_error_clear(&err);
  elfm_calib cal;
  if (elfm_calib_from_optics(&o.optics, o.width, o.height, o.pixel_um, &cal, &err))
    return cli_fail("calib", &err);
  if (o.view_w_px > 0) {
    cal.view_w_px = o.view_w_px;
    cal.view_h_px = o.view_h_px;
  }
  cal.z_min_um = o.z_min_um;
  cal.z_max_um = o.z_max_um;
  cal.z_step_um = o.z_step_um;
  int rc = cli_calib_write("calib", &cal, o.out);
  if (rc != CLI_OK) return rc;
  printf("%s: %d views, %.4f um/px, %d z planes\n", o.out, cal.n_views, cal.um_per_px,
         elfm_calib_n_planes(&cal));
  return CLI_OK;
}

/* The fraction of view v's crop (view_w x view_h px around its centre, the
 * part the refocus reads) that lies on the sensor. */
static int show(int argc, char **argv)
{
  if (argc != 2) {
    usage(stderr);
    return CLI_USAGE;
  }
  if (!strcmp(argv[1], "--help") || !strcmp(argv[1], "-h")) {
    usage(stdout);
    return CLI_OK;
  }
  elfm_error err;
  elfm_error_clear(&err);
  elfm_calib c;
  if (elfm_calib_load(argv[1], &c, &err)) return cli_fail("calib", &err);
  printf("sensor %dx%d, %.3f um pixels, %.5f um/px, view %dx%d, z %g..%g step %g (%d planes)\n",
         c.sensor_width_px, c.sensor_height_px, c.pixel_um, c.um_per_px, c.view_w_px,
         c.view_h_px, c.z_min_um, c.z_max_um, c.z_step_um, elfm_calib_n_planes(&c));
  /* the lens array's turn against the sensor's rows, as its centres and its
   * disparities each show it (calib refine turns the second to the first) */
  double turn_c, turn_d;
  elfm_calib_turns(&c, &turn_c, &turn_d);
  printf("lens array turned %+.3f deg against the sensor's rows (by its centres), %+.3f deg (by its "
         "disparities)\n", turn_c, turn_d);
  /* the grid's pitch against the one its optics give: they part when the
   * relay's magnification is not the optics' (calib refine --sweep takes
   * it from the grid, docs/recon.md "The focal plane from a sweep") */
  const double pitch = elfm_calib_grid_pitch(&c);
  if (isfinite(pitch)) {
    printf("views' grid %.2f px apart", pitch);
    if (c.has_optics && c.pixel_um > 0)
      printf(" (the lenslets' %g um x the relay's %.4f over the pixels: %.2f px)", c.optics.mla_pitch_um,
             c.optics.relay, c.optics.mla_pitch_um * c.optics.relay / c.pixel_um);
    printf("\n");
  }
  /* Why the crop's share on the sensor: a grid wider than the sensor (the
   * paper's 5 x 5 overhangs the EVK4's 720 rows; on a 640 x 480 sensor its
   * corner views are gone) leaves objects far from the axis seen by fewer
   * views, and recall falls there (docs/tracker.md "Scenes beyond the
   * built-ins"). */
  int whole = 0, part = 0, off = 0, least = -1;
  double least_f = 1;
  for (int k = 0; k < c.n_views; k++) {
    const elfm_view *v = &c.views[k];
    const double f = elfm_calib_view_on_sensor(&c, k);
    printf("view %2d (i=%+d, j=%+d): centre (%8.2f, %8.2f) px, shift (%+.5f, %+.5f) px/um, "
           "%3.0f %% on the sensor\n",
           k, v->i, v->j, v->cx_px, v->cy_px, v->dx_px_per_um, v->dy_px_per_um, 100 * f);
    if (f >= 1) whole++;
    else if (f <= 0) off++;
    else {
      part++;
      if (least < 0 || f < least_f) {
        least = k;
        least_f = f;
      }
    }
  }
  printf("%d of %d views wholly on the sensor, %d partly", whole, c.n_views, part);
  if (part) printf(" (view %d least: %.0f %%)", least, 100 * least_f);
  printf(", %d off it\n", off);
  return CLI_OK;
}

int cmd_calib(int argc, char **argv)
{
  if (argc < 2) {
    usage(stderr);
    return CLI_USAGE;
  }
  if (!strcmp(argv[1], "--help") || !strcmp(argv[1], "-h")) {
    usage(stdout);
    return CLI_OK;
  }
  if (!strcmp(argv[1], "from-optics")) return from_optics(argc - 1, argv + 1);
  if (!strcmp(argv[1], "show")) return show(argc - 1, argv + 1);
  if (!strcmp(argv[1], "refine")) return cmd_calib_refine(argc - 1, argv + 1);
  cli_message("calib", CLI_USAGE, "unknown action '%s'", argv[1]);
  usage(stderr);
  return CLI_USAGE;
}
