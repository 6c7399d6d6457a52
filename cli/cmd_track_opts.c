/* cmd_track_opts.c — eventlfm track's options: the parsing (--help's
 * text is in cmd_track_help.c). The defaults (where they differ from the
 * libraries', and why: each measured on the simulator), also those that
 * depend on other options, are in cmd_track_defaults.c and, for the motion
 * bias, cmd_track_bias.c; the run is in cmd_track.c. */
#include <errno.h>
#include <getopt.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cmd_track.h"

static int parse_vec3(const char *s, double v[3])
{
  char *end;
  for (int a = 0; a < 3; a++) {
    errno = 0;
    v[a] = strtod(s, &end);
    if (end == s || errno || !isfinite(v[a])) return 0;
    if (a < 2) {
      if (*end != ',') return 0;
      s = end + 1;
    }
  }
  return *end == 0;
}

/* A view-count option, 0 (off) or 2..255 (--guided-views, --fill-views):
 * 1, or 0 after a usage message. */
static int parse_views_or_off(const char *cmd, const char *opt, const char *a, int *out)
{
  if (!cli_parse_int(cmd, opt, a, out)) return 0;
  if (*out != 0 && (*out < 2 || *out > 255)) {
    cli_message(cmd, CLI_USAGE, "%s must be 0 or 2..255, not '%s'", opt, a);
    return 0;
  }
  return 1;
}

enum {
  O_CALIB = 1000, O_EVENTS, O_OUT, O_THK, O_THA, O_THR, O_RXY, O_RZ, O_SEP, O_REFINE, O_MAXDET,
  O_GATE, O_MAXGAP, O_MINPTS, O_LAG, O_MOTION, O_STAGEV, O_MODEL, O_LOSS, O_SPW, O_RES, O_MAXOUT, O_OUTMIN,
  O_THDEPTH, O_THMIN, O_VIEWSRULE, O_RESCUE, O_LEAD, O_LINKKZ, O_VEXP, O_HYST, O_WEAKGATE,
  O_GUIDED, O_GUIDEDR, O_GUIDEDM, O_VSUP, O_EXPLAIN, O_EXPLAINUM,
  O_STITCHN, O_STITCHG, O_STITCHL, O_SWAPN, O_LOC, O_LOCWIN,
  O_LOCPOW, O_LOCOUT, O_LOCMIN, O_LOCNEAR, O_GVIEWS, O_MLEAD, O_MDELAY,
  O_FILLV, O_FILLG, O_FILLN, O_FILLR, O_FILLK, O_FILLE, O_FILLRT, O_SPATH, O_CIRCN, O_CIRCNP, O_CIRCE, O_CIRCA, O_VFSIG, O_GRATIO, O_DEEPV, O_PRIO, O_GCVG, O_SPORD, O_SPTURN, O_MPATH, O_FSDP, O_MFADE, O_MSLOW, O_MSLOWS, O_MFAST, O_MFASTS, O_MBLUR,
  O_ENCUM, O_ENCPAD, O_ENCAPART, O_ENCR, O_ENCCR, O_ENCLR, O_RJOIN, O_RESTV, O_PIECE,
  O_LSCALE, O_PLSHIFT, O_BIN, O_TWIN, O_TWINN, O_PAIRFIT, O_DEEPW, O_DEEPZ, O_GAPART
};

/* Parse argv into *out (track defaults first). CLI_OK: run; TRACK_PARSE_HELP:
 * --help was printed; otherwise the usage error already shown. */
int track_opts_parse(int argc, char **argv, track_opts *out)
{
  static const char *const C = "track";
  track_opts o;
  track_defaults(&o);
  track_given g;
  memset(&g, 0, sizeof g);
  static const struct option lo[] = {
      CLI_RECON_LONG_OPTIONS,
      {"calib", required_argument, 0, O_CALIB}, {"events", required_argument, 0, O_EVENTS},
      {"out", required_argument, 0, O_OUT},
      {"threshold-k", required_argument, 0, O_THK}, {"threshold-abs", required_argument, 0, O_THA},
      {"threshold-rel", required_argument, 0, O_THR},
      {"threshold-depth-um", required_argument, 0, O_THDEPTH},
      {"threshold-min", required_argument, 0, O_THMIN},
      {"views-rule", required_argument, 0, O_VIEWSRULE},
      {"rescue-factor", required_argument, 0, O_RESCUE},
      {"stitch-points", required_argument, 0, O_STITCHN},
      {"stitch-gate-um", required_argument, 0, O_STITCHG},
      {"stitch-late-points", required_argument, 0, O_STITCHL},
      {"swap-points", required_argument, 0, O_SWAPN},
      {"encounter-um", required_argument, 0, O_ENCUM},
      {"encounter-pad", required_argument, 0, O_ENCPAD},
      {"encounter-apart", required_argument, 0, O_ENCAPART},
      {"rest-speed-um-per-ms", required_argument, 0, O_RESTV},
      {"encounter-ratio", required_argument, 0, O_ENCR},
      {"encounter-circle-ratio", required_argument, 0, O_ENCCR},
      {"encounter-line-ratio", required_argument, 0, O_ENCLR},
      {"review-join-factor", required_argument, 0, O_RJOIN},
      {"twin-um", required_argument, 0, O_TWIN}, {"twin-points", required_argument, 0, O_TWINN},
      {"weak-gate-um", required_argument, 0, O_WEAKGATE},
      {"guided-low", required_argument, 0, O_GUIDED},
      {"view-support", required_argument, 0, O_VSUP},
      {"explain-brighter", required_argument, 0, O_EXPLAIN},
      {"explain-um", required_argument, 0, O_EXPLAINUM},
      {"localize", required_argument, 0, O_LOC},
      {"localize-window-px", required_argument, 0, O_LOCWIN},
      {"localize-power", required_argument, 0, O_LOCPOW},
      {"localize-outlier-px", required_argument, 0, O_LOCOUT},
      {"localize-min-views", required_argument, 0, O_LOCMIN},
      {"localize-near-um", required_argument, 0, O_LOCNEAR},
      {"guided-views", required_argument, 0, O_GVIEWS},
      {"fill-views", required_argument, 0, O_FILLV},
      {"fill-gate-um", required_argument, 0, O_FILLG},
      {"view-fit-sigma", required_argument, 0, O_VFSIG},
      {"guided-min-ratio", required_argument, 0, O_GRATIO},
      {"guided-apart-um", required_argument, 0, O_GAPART},
      {"pair-fit-um", required_argument, 0, O_PAIRFIT},
      {"deep-window-us", required_argument, 0, O_DEEPW},
      {"deep-window-um", required_argument, 0, O_DEEPZ},
      {"deep-peak-views", required_argument, 0, O_DEEPV},
      {"priority-points", required_argument, 0, O_PRIO},
      {"gcv-gamma", required_argument, 0, O_GCVG},
      {"spline-order", required_argument, 0, O_SPORD},
      {"spline-turn", required_argument, 0, O_SPTURN},
      {"motion-along-path", required_argument, 0, O_MPATH},
      {"fit-sd-power", required_argument, 0, O_FSDP},
      {"motion-fade-um-per-ms", required_argument, 0, O_MFADE},
      {"motion-slow-lead-ms", required_argument, 0, O_MSLOW},
      {"motion-slow-um-per-ms", required_argument, 0, O_MSLOWS},
      {"motion-fast-lead-ms", required_argument, 0, O_MFAST},
      {"motion-fast-um-per-ms", required_argument, 0, O_MFASTS},
      {"motion-blur-lead-um", required_argument, 0, O_MBLUR},
      {"fill-max-gap", required_argument, 0, O_FILLN},
      {"fill-frames", required_argument, 0, O_FILLK},
      {"fill-ends", required_argument, 0, O_FILLE},
      {"fill-retry-um", required_argument, 0, O_FILLRT},
      {"short-path-um", required_argument, 0, O_SPATH},
      {"circle-points", required_argument, 0, O_CIRCN},
      {"circle-after", required_argument, 0, O_CIRCA},
      {"circle-next-path-um", required_argument, 0, O_CIRCNP},
      {"circle-end-points", required_argument, 0, O_CIRCE},
      {"fill-min-ratio", required_argument, 0, O_FILLR},
      {"guided-radius-um", required_argument, 0, O_GUIDEDR},
      {"guided-min-points", required_argument, 0, O_GUIDEDM},
      {"lead-sigmas", required_argument, 0, O_LEAD},
      {"link-kz", required_argument, 0, O_LINKKZ},
      {"views-exponent", required_argument, 0, O_VEXP},
      {"plane-shift-px", required_argument, 0, O_PLSHIFT}, {"bin-px", required_argument, 0, O_BIN},
      {"threshold-low", required_argument, 0, O_HYST},
      {"radius-xy-um", required_argument, 0, O_RXY},
      {"radius-z-um", required_argument, 0, O_RZ}, {"min-separation-um", required_argument, 0, O_SEP},
      {"refine", required_argument, 0, O_REFINE}, {"max-detections", required_argument, 0, O_MAXDET},
      {"gate-um", required_argument, 0, O_GATE}, {"max-gap", required_argument, 0, O_MAXGAP},
      {"min-points", required_argument, 0, O_MINPTS}, {"lag-correct", required_argument, 0, O_LAG},
      {"motion", required_argument, 0, O_MOTION},
      {"stage-velocity-um-per-ms", required_argument, 0, O_STAGEV},
      {"model", required_argument, 0, O_MODEL}, {"loss", required_argument, 0, O_LOSS},
      {"loss-scale", required_argument, 0, O_LSCALE},
      {"spline-weight-ms3", required_argument, 0, O_SPW}, {"resolution", no_argument, 0, O_RES},
      {"max-outlier-frac", required_argument, 0, O_MAXOUT},
      {"outlier-min-um", required_argument, 0, O_OUTMIN},
      {"piece-points", required_argument, 0, O_PIECE},
      {"motion-lead-um", required_argument, 0, O_MLEAD},
      {"motion-delay-us", required_argument, 0, O_MDELAY},
      {"quiet", no_argument, 0, 'q'}, {"help", no_argument, 0, 'h'}, {0, 0, 0, 0}};
  cli_recon_parse rp = {.ro = &o.recon};
  optind = 1;
  opterr = 0;
  int ch;
  while ((ch = getopt_long(argc, argv, ":hq", lo, NULL)) != -1) {
    const char *a = optarg;
    if (ch == CLI_RO_BLUR && a && !strcmp(a, "auto")) {
      o.blur_auto = 1;
      o.recon.blur_px = 0;
      continue;
    }
    const int k = cli_parse_recon_option(C, ch, a, &rp);
    if (k == 0) return CLI_USAGE;
    if (ch == CLI_RO_BLUR) o.blur_auto = 0;
    if (ch == CLI_RO_DT || ch == CLI_RO_STRIDE) o.dt_auto = 0;
    if (ch == CLI_RO_START) o.start_auto = 0;
    if (ch == CLI_RO_REPR || ch == CLI_RO_TAU || ch == CLI_RO_POLARITY || ch == CLI_RO_BLUR) o.repr_auto = 0;
    if (ch == CLI_RO_REPR || ch == CLI_RO_TAU || ch == CLI_RO_POLARITY) o.lin_auto = 0;
    if (ch == CLI_RO_TAU) o.tau_given = 1;
    if (k > 0) continue;
    switch (ch) {
    case 'h': track_usage(stdout); return TRACK_PARSE_HELP;
    case 'q': o.quiet = 1; break;
    case O_CALIB: o.calib = a; break;
    case O_EVENTS: o.events = a; break;
    case O_OUT: o.out = a; break;
    case O_THK: g.thr = 1; if (!cli_parse_double_in(C, "--threshold-k", a, 0, 0, 1e6, ">= 0 (0: off)", &o.peaks.k_sigma)) return CLI_USAGE; break;
    case O_THA: g.thr = 1; if (!cli_parse_double_in(C, "--threshold-abs", a, 0, 0, 1e12, ">= 0 (0: off)", &o.peaks.absolute)) return CLI_USAGE; break;
    case O_THDEPTH: g.depth = 1; if (!cli_parse_double_in(C, "--threshold-depth-um", a, 0, 0, 1e6, ">= 0 (0: off)", &o.peaks.depth_range_um)) return CLI_USAGE; break;
    case O_HYST: g.low = 1; if (!cli_parse_double_in(C, "--threshold-low", a, 0, 0, 1e12, ">= 0", &o.peaks.hysteresis_low)) return CLI_USAGE; break;
    case O_VEXP: if (!cli_parse_double_in(C, "--views-exponent", a, 0, 0, 4, "0..4", &o.views_exponent)) return CLI_USAGE; break;
    case O_PLSHIFT:
      if (!cli_parse_double_in(C, "--plane-shift-px", a, 0, 0, 100, "0..100 (0 = every plane)", &o.plane_shift_px))
        return CLI_USAGE;
      break;
    case O_BIN:
      if (!cli_parse_int_in(C, "--bin-px", a, 1, 4, "1..4 (1 = off)", &o.bin_px)) return CLI_USAGE;
      break;
    case O_LINKKZ: if (!cli_parse_double_in(C, "--link-kz", a, 0, 1, 100, "> 0 and <= 100", &o.link.kz)) return CLI_USAGE; break;
    case O_LEAD: if (!cli_parse_double(C, "--lead-sigmas", a, &o.link.lead_sigmas)) return CLI_USAGE; break;
    case O_GUIDEDR: if (!cli_parse_double(C, "--guided-radius-um", a, &o.guided_radius_um)) return CLI_USAGE; break;
    case O_GUIDEDM: g.gmp = 1; if (!cli_parse_int(C, "--guided-min-points", a, &o.guided_min_points)) return CLI_USAGE; break;
    case O_VSUP:
      if (strcmp(a, "auto") == 0) {
        o.view_support_auto = 1;
        break;
      }
      if (!cli_parse_double(C, "--view-support", a, &o.view_support)) return CLI_USAGE;
      if (!(o.view_support >= 0 && o.view_support <= 1))
        return cli_message(C, CLI_USAGE, "--view-support must be in 0..1 or auto");
      o.view_support_auto = 0;
      break;
    case O_EXPLAIN:
      if (!cli_parse_double(C, "--explain-brighter", a, &o.explain_brighter)) return CLI_USAGE;
      if (!(o.explain_brighter >= 0 && o.explain_brighter < 1))
        return cli_message(C, CLI_USAGE, "--explain-brighter must be in 0..1 (below 1)");
      break;
    case O_EXPLAINUM:
      if (!cli_parse_double(C, "--explain-um", a, &o.explain_um)) return CLI_USAGE;
      if (!(o.explain_um > 0 && o.explain_um <= 100))
        return cli_message(C, CLI_USAGE, "--explain-um must be in (0, 100]");
      break;
    case O_LOC:
      if (!strcmp(a, "views")) o.localize_views = 1;
      else if (!strcmp(a, "peak")) o.localize_views = 0;
      else return cli_message(C, CLI_USAGE, "--localize must be views or peak, not '%s'", a);
      break;
    case O_LOCWIN:
      if (!cli_parse_int(C, "--localize-window-px", a, &o.loc.half_window_px)) return CLI_USAGE;
      if (o.loc.half_window_px < 1 || o.loc.half_window_px > 32)
        return cli_message(C, CLI_USAGE, "--localize-window-px must be 1..32, not '%s'", a);
      break;
    case O_LOCPOW:
      g.locpow = 1;
      if (!cli_parse_int(C, "--localize-power", a, &o.loc.power)) return CLI_USAGE;
      if (o.loc.power < 1 || o.loc.power > 8)
        return cli_message(C, CLI_USAGE, "--localize-power must be 1..8, not '%s'", a);
      break;
    case O_LOCNEAR:
      if (!cli_parse_double_in(C, "--localize-near-um", a, 0, 0, 1000, "0..1000",
                               &o.localize_near_um))
        return CLI_USAGE;
      break;
    case O_LOCOUT:
      if (!cli_parse_double(C, "--localize-outlier-px", a, &o.loc.outlier_px)) return CLI_USAGE;
      if (!(o.loc.outlier_px > 0 && o.loc.outlier_px <= 1000))
        return cli_message(C, CLI_USAGE, "--localize-outlier-px must be > 0, not '%s'", a);
      break;
    case O_LOCMIN:
      g.locmin = 1;
      if (!cli_parse_int(C, "--localize-min-views", a, &o.loc.min_views)) return CLI_USAGE;
      if (o.loc.min_views < 2 || o.loc.min_views > 255)
        return cli_message(C, CLI_USAGE, "--localize-min-views must be 2..255, not '%s'", a);
      break;
    case O_FILLV:
      g.fillv = 1;
      if (!parse_views_or_off(C, "--fill-views", a, &o.fill_views)) return CLI_USAGE;
      break;
    case O_FILLG:
      if (!cli_parse_double_in(C, "--fill-gate-um", a, 0, 1, 100, "> 0 and <= 100", &o.fill_gate_um)) return CLI_USAGE;
      break;
    case O_VFSIG:
      /* from 0.001: at 1e-300 the fills' weights overflowed and a
       * track's fit failed, ending the run (tests/track_extremes.sh) */
      if (!cli_parse_double_in(C, "--view-fit-sigma", a, 0.001, 0, 1000, "0.001..1000",
                               &o.smooth.view_fit_sigma_factor))
        return CLI_USAGE;
      break;
    case O_DEEPV:
      g.deepv = 1;
      if (!parse_views_or_off(C, "--deep-peak-views", a, &o.deep_peak_views)) return CLI_USAGE;
      break;
    case O_PRIO:
      if (!cli_parse_int(C, "--priority-points", a, &o.link.priority_points)) return CLI_USAGE;
      if (o.link.priority_points < 0) {
        cli_message(C, CLI_USAGE, "--priority-points must be >= 0, not '%s'", a);
        return CLI_USAGE;
      }
      break;
    case O_GRATIO:
      if (!cli_parse_double_in(C, "--guided-min-ratio", a, 0, 0, 1, "0..1", &o.guided_min_ratio)) return CLI_USAGE;
      break;
    case O_GAPART:
      if (!cli_parse_double_in(C, "--guided-apart-um", a, 0, 0, 100, "0..100 (0: off)", &o.guided_apart_um))
        return CLI_USAGE;
      break;
    case O_PAIRFIT:
      if (!cli_parse_double_in(C, "--pair-fit-um", a, 0, 0, 100, "0..100 (0: off)", &o.pair_fit_um)) return CLI_USAGE;
      break;
    case O_DEEPW:
      if (!strcmp(a, "auto")) o.deep_window_us = -1;
      else if (!cli_parse_int64(C, "--deep-window-us", a, &o.deep_window_us)) return CLI_USAGE;
      else if (o.deep_window_us < 0 || o.deep_window_us > 10000000) {
        cli_message(C, CLI_USAGE, "--deep-window-us must be auto or 0..10000000 (0: off), not '%s'", a);
        return CLI_USAGE;
      }
      break;
    case O_DEEPZ:
      if (!cli_parse_double_in(C, "--deep-window-um", a, 0, 0, 1000, "0..1000 (0: every such fit)", &o.deep_window_um)) return CLI_USAGE;
      break;
    case O_FILLR:
      if (!cli_parse_double_in(C, "--fill-min-ratio", a, 0, 0, 1, "0..1", &o.fill_min_ratio)) return CLI_USAGE;
      break;
    case O_FILLK:
      g.fillk = 1;
      if (!cli_parse_int(C, "--fill-frames", a, &o.fill_frames)) return CLI_USAGE;
      if (o.fill_frames < 1 || o.fill_frames > TRACK_FILL_MAX_FRAMES || o.fill_frames % 2 == 0)
        return cli_message(C, CLI_USAGE, "--fill-frames must be odd, 1..%d, not '%s'",
                           TRACK_FILL_MAX_FRAMES, a);
      break;
    case O_FILLE:
      g.fille = 1;
      if (!cli_parse_on_off(C, "--fill-ends", a, &o.fill_ends)) return CLI_USAGE;
      break;
    case O_FILLRT:
      g.fretry = 1;
      if (!cli_parse_double_in(C, "--fill-retry-um", a, 0, 0, 10, "0..10", &o.fill_retry_um))
        return CLI_USAGE;
      break;
    case O_SPATH:
      g.spath = 1;
      if (!cli_parse_double_in(C, "--short-path-um", a, 0, 0, 1000, "0..1000", &o.link.short_path_um))
        return CLI_USAGE;
      break;
    case O_CIRCN:
      g.circ = 1;
      if (!cli_parse_int(C, "--circle-points", a, &o.link.circle_points)) return CLI_USAGE;
      if (o.link.circle_points != 0 && (o.link.circle_points < 6 || o.link.circle_points > 1000))
        return cli_message(C, CLI_USAGE, "--circle-points must be 0 (off) or 6..1000, not %s", a);
      break;
    case O_CIRCNP:
      g.circnext = 1;
      if (!cli_parse_double_in(C, "--circle-next-path-um", a, 0, 0, 10000, "0..10000",
                               &o.link.circle_next_path_um))
        return CLI_USAGE;
      break;
    case O_CIRCE:
      if (!cli_parse_int(C, "--circle-end-points", a, &o.link.circle_end_points)) return CLI_USAGE;
      if (o.link.circle_end_points != 0 &&
          (o.link.circle_end_points < 6 || o.link.circle_end_points > 1000))
        return cli_message(C, CLI_USAGE, "--circle-end-points must be 0 (off) or 6..1000, not %s", a);
      break;
    case O_CIRCA:
      if (!cli_parse_int_in(C, "--circle-after", a, 1, 1000, "1..1000 frames", &o.link.circle_after))
        return CLI_USAGE;
      break;
    case O_FILLN:
      if (!cli_parse_int(C, "--fill-max-gap", a, &o.fill_max_gap)) return CLI_USAGE;
      if (o.fill_max_gap < 1 || o.fill_max_gap > 1000)
        return cli_message(C, CLI_USAGE, "--fill-max-gap must be 1..1000, not '%s'", a);
      break;
    case O_GVIEWS:
      g.gviews = 1;
      if (!parse_views_or_off(C, "--guided-views", a, &o.guided_views)) return CLI_USAGE;
      break;
    case O_GUIDED: if (!cli_parse_double(C, "--guided-low", a, &o.guided_low)) return CLI_USAGE; break;
    case O_WEAKGATE: if (!cli_parse_double_in(C, "--weak-gate-um", a, 0, 0, 1e4, "0..10000 (0: the gate)", &o.link.weak_gate_um)) return CLI_USAGE; break;
    case O_RESCUE:
      if (!cli_parse_double_in(C, "--rescue-factor", a, 0, 0, 100, "0..100 (0: off)", &o.link.rescue_gate_factor))
        return CLI_USAGE;
      o.rescue_auto = 0;
      break;
    case O_STITCHN:
      if (!cli_parse_int(C, "--stitch-points", a, &o.link.stitch_points)) return CLI_USAGE;
      if (o.link.stitch_points != 0 && (o.link.stitch_points < 4 || o.link.stitch_points > 100000))
        return cli_message(C, CLI_USAGE, "--stitch-points must be 0 (off) or 4..100000, not %s", a);
      g.stitch = 1;
      break;
    case O_STITCHL:
      if (!cli_parse_int(C, "--stitch-late-points", a, &o.link.stitch_late_points)) return CLI_USAGE;
      if (o.link.stitch_late_points < 0 || o.link.stitch_late_points > 100000)
        return cli_message(C, CLI_USAGE, "--stitch-late-points must be 0 (off) or 1..100000, not %s", a);
      break;
    case O_SWAPN:
      if (!cli_parse_int(C, "--swap-points", a, &o.link.swap_points)) return CLI_USAGE;
      if (o.link.swap_points != 0 && (o.link.swap_points < 4 || o.link.swap_points > 100000))
        return cli_message(C, CLI_USAGE, "--swap-points must be 0 (off) or 4..100000, not %s", a);
      break;
    case O_ENCUM:
      if (!cli_parse_double_in(C, "--encounter-um", a, 0, 0, 1e6, ">= 0", &o.link.encounter_um)) return CLI_USAGE;
      break;
    case O_ENCCR:
      if (!cli_parse_double_in(C, "--encounter-circle-ratio", a, 0, 0, 1, "0 <= R <= 1",
                               &o.link.encounter_circle_ratio))
        return CLI_USAGE;
      break;
    case O_ENCLR:
      if (!cli_parse_double_in(C, "--encounter-line-ratio", a, 0, 0, 1, "0 <= R <= 1",
                               &o.link.encounter_line_ratio))
        return CLI_USAGE;
      break;
    case O_ENCR:
      if (!cli_parse_double_in(C, "--encounter-ratio", a, 0, 1, 1, "0 < R <= 1", &o.link.encounter_ratio))
        return CLI_USAGE;
      break;
    case O_RJOIN:
      if (!cli_parse_double_in(C, "--review-join-factor", a, 0, 0, 1e6, ">= 0", &o.link.review_join_factor))
        return CLI_USAGE;
      break;
    case O_TWIN:
      if (!cli_parse_double_in(C, "--twin-um", a, 0, 0, 1e6, ">= 0", &o.link.twin_um)) return CLI_USAGE;
      break;
    case O_TWINN:
      if (!cli_parse_int_in(C, "--twin-points", a, 1, 1000, "1..1000", &o.link.twin_points))
        return CLI_USAGE;
      break;
    case O_RESTV:
      if (!cli_parse_double_in(C, "--rest-speed-um-per-ms", a, 0, 0, 1e6, ">= 0",
                               &o.link.rest_speed_um_per_ms))
        return CLI_USAGE;
      break;
    case O_ENCAPART:
      if (!cli_parse_int(C, "--encounter-apart", a, &o.link.encounter_apart)) return CLI_USAGE;
      if (o.link.encounter_apart < 0)
        return cli_message(C, CLI_USAGE, "--encounter-apart must be >= 0, not '%s'", a);
      break;
    case O_ENCPAD:
      if (!cli_parse_int(C, "--encounter-pad", a, &o.link.encounter_pad)) return CLI_USAGE;
      if (o.link.encounter_pad < 0) {
        cli_message(C, CLI_USAGE, "--encounter-pad must be >= 0, not '%s'", a);
        return CLI_USAGE;
      }
      break;
    case O_STITCHG: if (!cli_parse_double_in(C, "--stitch-gate-um", a, 0, 0, 1e4, "0..10000", &o.link.stitch_gate_um)) return CLI_USAGE; break;
    case O_VIEWSRULE:
      if (!cli_parse_on_off(C, "--views-rule", a, &o.views_rule)) return CLI_USAGE;
      break;
    case O_THMIN: g.min = 1; if (!cli_parse_double_in(C, "--threshold-min", a, 0, 0, 1e12, ">= 0", &o.peaks.absolute_min)) return CLI_USAGE; break;
    case O_THR: g.thr = 1; if (!cli_parse_double_in(C, "--threshold-rel", a, 0, 0, 1, "0..1 (0: off)", &o.peaks.relative)) return CLI_USAGE; break;
    case O_RXY:
      if (!cli_parse_double_in(C, "--radius-xy-um", a, 0, 1, 1e4, "> 0", &o.peaks.radius_xy_um)) return CLI_USAGE;
      g.rxy = 1;
      break;
    case O_RZ: if (!cli_parse_double_in(C, "--radius-z-um", a, 0, 1, 1e4, "> 0", &o.peaks.radius_z_um)) return CLI_USAGE; break;
    case O_SEP: if (!cli_parse_double_in(C, "--min-separation-um", a, 0, 0, 1e4, ">= 0", &o.peaks.min_separation_um)) return CLI_USAGE; break;
    case O_REFINE:
      if (!strcmp(a, "gauss")) o.peaks.refine = ELFM_REFINE_GAUSSIAN;
      else if (!strcmp(a, "quad")) o.peaks.refine = ELFM_REFINE_QUADRATIC;
      else if (!strcmp(a, "none")) o.peaks.refine = ELFM_REFINE_NONE;
      else return cli_message(C, CLI_USAGE, "--refine must be gauss, quad or none, not '%s'", a);
      break;
    case O_MAXDET:
      if (!cli_parse_int(C, "--max-detections", a, &o.max_det)) return CLI_USAGE;
      if (o.max_det < 1 || o.max_det > 10000000) return cli_message(C, CLI_USAGE, "--max-detections must be 1..1e7");
      break;
    case O_GATE:
      if (!cli_parse_double_in(C, "--gate-um", a, 0, 1, 1e4, "> 0 and <= 10000", &o.link.gate_um))
        return CLI_USAGE;
      o.gate_auto = 0;
      break;
    case O_MAXGAP: if (!cli_parse_int_in(C, "--max-gap", a, 0, 1000000, "0..1000000 frames", &o.link.max_gap_frames)) return CLI_USAGE; break;
    case O_MINPTS: g.minpts = 1; if (!cli_parse_int_in(C, "--min-points", a, 1, 1000000, ">= 1", &o.link.min_points)) return CLI_USAGE; break;
    case O_LAG:
      if (!cli_parse_on_off(C, "--lag-correct", a, &o.lag_correct)) return CLI_USAGE;
      break;
    case O_MOTION:
      o.motion_auto = !strcmp(a, "auto");
      if (!strcmp(a, "auto") || !strcmp(a, "per-track")) o.motion = MOTION_AUTO;
      else if (!strcmp(a, "stage")) o.motion = MOTION_STAGE;
      else if (!strcmp(a, "free")) o.motion = MOTION_FREE;
      else return cli_message(C, CLI_USAGE, "--motion must be auto, per-track, stage or free, not '%s'", a);
      break;
    case O_STAGEV:
      if (!parse_vec3(a, o.stage_v))
        return cli_message(C, CLI_USAGE, "--stage-velocity-um-per-ms wants vx,vy,vz, not '%s'", a);
      o.has_stage_v = 1;
      break;
    case O_MODEL:
      if (!strcmp(a, "auto")) o.smooth.model = ELFM_MODEL_AUTO;
      else if (!strcmp(a, "cv")) o.smooth.model = ELFM_MODEL_CONST_VELOCITY;
      else if (!strcmp(a, "ca")) o.smooth.model = ELFM_MODEL_CONST_ACCEL;
      else if (!strcmp(a, "spline")) o.smooth.model = ELFM_MODEL_SPLINE;
      else return cli_message(C, CLI_USAGE, "--model must be auto, cv, ca or spline, not '%s'", a);
      break;
    case O_LOSS:
      if (!strcmp(a, "huber")) o.smooth.loss = ELFM_LOSS_HUBER;
      else if (!strcmp(a, "cauchy")) o.smooth.loss = ELFM_LOSS_CAUCHY;
      else if (!strcmp(a, "none")) o.smooth.loss = ELFM_LOSS_NONE;
      else return cli_message(C, CLI_USAGE, "--loss must be huber, cauchy or none, not '%s'", a);
      break;
    case O_LSCALE:
      /* from 0.001, as --view-fit-sigma: 1e-300 left no point inside the
       * loss, and a track's fit failed, ending the run */
      if (!cli_parse_double_in(C, "--loss-scale", a, 0.001, 0, 100, "0.001..100", &o.smooth.loss_scale))
        return CLI_USAGE;
      g.lscale = 1;
      break;
    case O_SPW: if (!cli_parse_double_in(C, "--spline-weight-ms3", a, 0, 0, 1e300, ">= 0 (0: chosen by GCV)", &o.smooth.spline_weight_ms3)) return CLI_USAGE; break;
    case O_GCVG:
      if (!cli_parse_double_in(C, "--gcv-gamma", a, 1, 0, 10, "1..10", &o.smooth.gcv_gamma)) return CLI_USAGE;
      g.gcvg = 1;
      break;
    case O_SPORD:
      if (!cli_parse_int(C, "--spline-order", a, &o.smooth.spline_order)) return CLI_USAGE;
      if (o.smooth.spline_order != 2 && o.smooth.spline_order != 3) {
        cli_message(C, CLI_USAGE, "--spline-order must be 2 or 3, not '%s'", a);
        return CLI_USAGE;
      }
      g.spord = 1;
      break;
    case O_SPTURN:
      if (!cli_parse_on_off(C, "--spline-turn", a, &o.smooth.spline_turn)) return CLI_USAGE;
      break;
    case O_MPATH:
      if (!cli_parse_on_off(C, "--motion-along-path", a, &o.smooth.motion_along_path)) return CLI_USAGE;
      break;
    case O_MFADE:
      if (!cli_parse_double_in(C, "--motion-fade-um-per-ms", a, 0, 1, 100, "> 0 and <= 100",
                               &o.smooth.motion_lead_fade_um_per_ms))
        return CLI_USAGE;
      g.fade = 1;
      break;
    case O_MSLOW:
      if (!cli_parse_double_in(C, "--motion-slow-lead-ms", a, 0, 0, 10, "0..10",
                               &o.smooth.motion_slow_lead_ms))
        return CLI_USAGE;
      g.mslow = 1;
      break;
    case O_MSLOWS:
      if (!cli_parse_double_in(C, "--motion-slow-um-per-ms", a, 0, 0, 100, "0..100",
                               &o.smooth.motion_slow_um_per_ms))
        return CLI_USAGE;
      g.mslows = 1;
      break;
    case O_MFAST:
      if (!cli_parse_double_in(C, "--motion-fast-lead-ms", a, 0, 0, 10, "0..10", &o.lead_fast_ms))
        return CLI_USAGE;
      break;
    case O_MFASTS:
      if (!cli_parse_double_in(C, "--motion-fast-um-per-ms", a, 0, 0, 100, "0..100",
                               &o.lead_fast_um_per_ms))
        return CLI_USAGE;
      break;
    case O_MBLUR:
      if (!cli_parse_double_in(C, "--motion-blur-lead-um", a, 0, 0, 10, "0..10", &o.lead_blur_um))
        return CLI_USAGE;
      break;
    case O_FSDP:
      if (!cli_parse_double_in(C, "--fit-sd-power", a, 0, 0, 4, "0..4", &o.smooth.fit_sd_power))
        return CLI_USAGE;
      g.fsdp = 1;
      break;
    case O_RES: o.resolution = 1; break;
    case O_MLEAD:
      if (!cli_parse_double_in(C, "--motion-lead-um", a, -100, 0, 100, "-100..100",
                               &o.smooth.motion_lead_um))
        return CLI_USAGE;
      g.mlead = 1;
      break;
    case O_MDELAY:
      if (!cli_parse_double_in(C, "--motion-delay-us", a, -1e6, 0, 1e6, "-1e6..1e6",
                               &o.smooth.motion_delay_us))
        return CLI_USAGE;
      g.mdelay = 1;
      break;
    case O_MAXOUT:
      if (!cli_parse_double(C, "--max-outlier-frac", a, &o.max_outlier_frac)) return CLI_USAGE;
      if (!(o.max_outlier_frac >= 0 && o.max_outlier_frac <= 1))
        return cli_message(C, CLI_USAGE, "--max-outlier-frac must be in 0..1");
      break;
    case O_OUTMIN:
      if (!cli_parse_double_in(C, "--outlier-min-um", a, 0, 0, 1e6, "0..1e6", &o.smooth.outlier_min_um))
        return CLI_USAGE;
      break;
    case O_PIECE:
      if (!cli_parse_int(C, "--piece-points", a, &o.piece_points)) return CLI_USAGE;
      if (o.piece_points < 0 || (o.piece_points > 0 && o.piece_points < 64))
        return cli_message(C, CLI_USAGE, "--piece-points must be 0 (off) or >= 64, not '%s'", a);
      break;
    default: return cli_bad_option(C, ch, argv);
    }
  }
  if (optind < argc) return cli_message(C, CLI_USAGE, "unexpected argument '%s'", argv[optind]);
  if (!o.calib || !o.events || !o.out)
    return cli_message(C, CLI_USAGE, "--calib, --events and --out are required (see --help)");
  if (!cli_check_recon_options(C, &rp)) return CLI_USAGE;
  /* the widths --resolution reports would be the binned volume's */
  if (o.bin_px > 1 && o.resolution)
    return cli_message(C, CLI_USAGE, "--resolution measures the volumes' widths: not with --bin-px %d",
                       o.bin_px);
  cli_recon_planes(&rp, o.planes_um);
  const int rc = track_opts_derive(&o, &g);
  if (rc != CLI_OK) return rc;
  *out = o;
  return CLI_OK;
}
