/* cmd_calib_refine_help.c — eventlfm calib refine --help, and the frames'
 * defaults it lists (the parsing and the work are in cmd_calib_refine.c). */
#include <stdio.h>

#include "cli.h"

void calib_refine_recon_defaults(elfm_recon_options *ro)
{
  elfm_recon_options_default(ro);
  /* track's frames: ON events, no median, no view-agreement rule (cmd_track_opts.c) */
  ro->framer.polarity = ELFM_POL_ON;
  ro->median = 0;
  ro->refocus.agree_frac = 0;
}

void calib_refine_usage(FILE *f)
{
  fprintf(f,
          "usage: eventlfm calib refine --calib calib.json --events FILE --out refined.json\n"
          "                             [options]\n\n"
          "Fits the views' centres (cx, cy) of calib.json to a recording of bright points\n"
          "(beads that move or blink, so that the event camera sees them) and writes the\n"
          "calibration with the moved centres. First the lens array's turn against the\n"
          "sensor's rows: the turn within --turn-deg whose volumes are sharpest over the\n"
          "first 20 ms turns every view's centre and disparity. Then each pass refocuses\n"
          "--ms of the recording (from its first event, or from --from-us to --to-us at\n"
          "most), fits every bright peak from all views and moves each view by the median\n"
          "of its images' misses. Moves no recording can see are left out: all views\n"
          "alike (the volume's x-y origin) and in proportion to the disparities (its focal\n"
          "plane). The disparities keep their length (from the optics) and turn with the\n"
          "grid of fitted centres (optics.mla_rotation_deg records the turn found).\n"
          "A view whose images stay in one place (the central view of a bead swept\n"
          "through z) is set on the grid of the others instead. Objects that move\n"
          "slowly show in few peaks on the time surface: with fewer than 20 over the\n"
          "stretch and --repr not given, the integral is tried (above 30 unless\n"
          "--threshold is given) and taken if it shows 20 or more (for a z sweep, give\n"
          "a --ms that covers it).\n"
          "--sweep, for one object (a bead) swept through z, such as on a piezo: each\n"
          "view's image is found in every frame and the centres fitted to where they\n"
          "lie, from centres any distance off that keeps each image in its view's crop\n"
          "(a calibration from the optics alone); then the passes. Several beads side\n"
          "by side (a slide, tilted or not; a view's brightest 32) are matched as one\n"
          "pattern moved in every view; beads that do not move together, or views\n"
          "fitted off the lenslets' grid, are refused. No turn's search or coarse\n"
          "step (a turned array is fitted all the same), the integral unless --repr\n"
          "is given, --ms 5000 unless given.\n"
          "Per-pass progress, the turn and each view's move on stderr.\n\n"
          "  --ms T               read T ms of the recording per pass (200)\n"
          "  --passes N           passes, 0..20 (4); each uses the previous one's centres\n"
          "                       (0: the turn and the coarse step alone, or --sweep's fit)\n"
          "  --threshold V        peaks above V on the 0..255 time surface only (60)\n"
          "  --min-views N        views that must agree with a point's fit (12; with\n"
          "                       fewer than 25 views 12 / 25 of them, at least 3)\n"
          "  --min-points N       a view moves only with at least N misses (20)\n"
          "  --search-px R        first a coarse step: each view's images are looked for\n"
          "                       up to R px from where the centres put them (12; 0: no\n"
          "                       such step), for centres from the optics alone\n"
          "  --turn-deg A         look for the lens array turned up to A degrees, 0..45\n"
          "                       (5; 0: no such search)\n"
          "  --sweep              the recording is one object, or several side by side,\n"
          "                       swept through z (above)\n"
          "  --sweep-um-per-ms V  (implies --sweep) the object moved in z at V um/ms\n"
          "                       (a piezo's ramps, up or down): the disparities are\n"
          "                       scaled so that the fitted depths move at V (the depth\n"
          "                       scale, which no recording of unknown motion shows)\n"
          "  --keep-focal-plane   the sweep's focal plane stays the calibration's (by\n"
          "                       default it moves to where the sweep's images were\n"
          "                       strongest: the object in focus; a sweep up and down\n"
          "                       gives it each way, a one-way sweep is also read\n"
          "                       backwards from a copy in $TMPDIR, removed after)\n"
          "  --keep-scale         the sweep's um_per_px and disparities stay the\n"
          "                       calibration's (by default, with the focal plane\n"
          "                       moved, the views' grid against the start's gives\n"
          "                       the relay's magnification, which scales both)\n"
          "  --quiet              no progress\n"
          "frames and refocusing (the same options as eventlfm track's; its defaults;\n"
          "--z-*-um set the passes' planes, the file written keeps its own):\n");
  elfm_recon_options d;
  calib_refine_recon_defaults(&d);
  cli_recon_options_usage(f, &d);
  fprintf(f, "  -h, --help           this text\n");
}
