/* test_gui_core.c — the viewer's parts that need no display: colour map,
 * camera projection, font, tick steps, levels of detail, loading run
 * directories and CSVs (and their errors), PNGs written and read (and PNGs
 * of other kinds), which key gives which command, and the clear failure
 * without a display (library and CLI). */
#include <errno.h>
#include <math.h>
#include <png.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/wait.h>

#include "check.h"
#include "elfm_recon.h"
#include "elfm_gui.h"
/* the levels of detail (gui_series_build; no OpenGL call): tests only */
#include "gl_internal.h"

static char tmpdir[256];

static void write_file(const char *name, const char *text)
{
  char p[512];
  snprintf(p, sizeof p, "%s/%s", tmpdir, name);
  FILE *f = fopen(p, "w");
  if (!f) {
    fprintf(stderr, "cannot write %s\n", p);
    exit(1);
  }
  fputs(text, f);
  fclose(f);
}

static const char *tpath(const char *name)
{
  static char p[4][512]; /* test driver: a few rotating buffers */
  static int k;
  k = (k + 1) % 4;
  snprintf(p[k], sizeof p[k], "%s/%s", tmpdir, name);
  return p[k];
}

static void test_colormap(void)
{
  float rgb[3];
  double prev = 1e9;
  int monotonic = 1;
  /* Hue must fall from blue to red as s grows: early/shallow blue, late/deep red. */
  for (int k = 0; k <= 20; k++) {
    elfm_colormap_rgb(k / 20.0, rgb);
    double h = elfm_color_hue_deg((int)(rgb[0] * 255), (int)(rgb[1] * 255), (int)(rgb[2] * 255));
    if (h > 300) h -= 360; /* deep red wraps */
    if (h > prev + 3) monotonic = 0;
    prev = h;
  }
  CHECK(monotonic);
  elfm_colormap_rgb(0.0, rgb);
  double h0 = elfm_color_hue_deg((int)(rgb[0] * 255), (int)(rgb[1] * 255), (int)(rgb[2] * 255));
  CHECK_MSG(h0 > 200 && h0 < 260, "s=0 hue %.1f not blue", h0);
  elfm_colormap_rgb(1.0, rgb);
  double h1 = elfm_color_hue_deg((int)(rgb[0] * 255), (int)(rgb[1] * 255), (int)(rgb[2] * 255));
  CHECK_MSG(h1 < 25 || h1 > 340, "s=1 hue %.1f not red", h1);
  /* Visible on the dark background: never near black. */
  for (int k = 0; k <= 10; k++) {
    elfm_colormap_rgb(k / 10.0, rgb);
    CHECK(fmaxf(rgb[0], fmaxf(rgb[1], rgb[2])) > 0.45f);
  }
  /* Clamped outside [0,1], NaN safe. */
  float a[3], b[3];
  elfm_colormap_rgb(-5, a);
  elfm_colormap_rgb(0, b);
  CHECK(a[0] == b[0] && a[1] == b[1] && a[2] == b[2]);
  elfm_colormap_rgb(NAN, a);
  CHECK(a[0] == b[0] && a[2] == b[2]);
  CHECK_NEAR(elfm_color_hue_deg(255, 0, 0), 0, 1e-9);
  CHECK_NEAR(elfm_color_hue_deg(0, 255, 0), 120, 1e-9);
  CHECK_NEAR(elfm_color_hue_deg(0, 0, 255), 240, 1e-9);
}

static void test_camera(void)
{
  double lo[3] = {-60, -40, -100}, hi[3] = {60, 40, 100};
  elfm_camera cam;
  elfm_camera_reset(&cam, lo, hi);
  double c, r;
  double centre[3] = {0, 0, 0};
  elfm_camera_project(&cam, 800, 600, centre, &c, &r);
  CHECK_NEAR(c, 400, 1e-9);
  CHECK_NEAR(r, 300, 1e-9);
  /* The whole box is inside the picture after a reset. */
  for (int k = 0; k < 8; k++) {
    double p[3] = {(k & 1) ? hi[0] : lo[0], (k & 2) ? hi[1] : lo[1], (k & 4) ? hi[2] : lo[2]};
    elfm_camera_project(&cam, 800, 600, p, &c, &r);
    CHECK(c > 0 && c < 800 && r > 0 && r < 600);
  }
  /* Head-on (yaw = pitch = 0): +x right, +y down, scale = height / (2 half). */
  cam.yaw_rad = cam.pitch_rad = 0;
  cam.half_height_um = 50;
  double px[3] = {10, 0, 0}, py[3] = {0, 10, 0}, pz[3] = {0, 0, 10};
  elfm_camera_project(&cam, 800, 600, px, &c, &r);
  CHECK_NEAR(c, 400 + 10 * 600 / 100.0, 1e-9);
  CHECK_NEAR(r, 300, 1e-9);
  elfm_camera_project(&cam, 800, 600, py, &c, &r);
  CHECK_NEAR(c, 400, 1e-9);
  CHECK_NEAR(r, 300 + 60, 1e-9);
  elfm_camera_project(&cam, 800, 600, pz, &c, &r);
  CHECK_NEAR(c, 400, 1e-9);
  CHECK_NEAR(r, 300, 1e-9);
  /* The GL matrix and the projection agree (any orientation). */
  cam.yaw_rad = 0.7;
  cam.pitch_rad = -0.3;
  cam.target_um[0] = 5;
  float m[16];
  elfm_camera_matrix(&cam, 800.0 / 600.0, m);
  double p[3] = {12, -7, 33};
  double clip[4];
  for (int i = 0; i < 4; i++)
    clip[i] = m[i] * p[0] + m[4 + i] * p[1] + m[8 + i] * p[2] + m[12 + i];
  elfm_camera_project(&cam, 800, 600, p, &c, &r);
  CHECK_NEAR(clip[3], 1.0, 1e-6);
  CHECK_NEAR((clip[0] + 1) * 0.5 * 800, c, 1e-3);
  CHECK_NEAR((1 - clip[1]) * 0.5 * 600, r, 1e-3);
  CHECK(fabs(clip[2]) < 1.0); /* within the depth range */
  /* Zoom in: points move away from the centre; pan moves the picture. */
  double c0, r0;
  elfm_camera_project(&cam, 800, 600, p, &c0, &r0);
  elfm_camera_zoom(&cam, 3);
  elfm_camera_project(&cam, 800, 600, p, &c, &r);
  CHECK(hypot(c - 400, r - 300) > hypot(c0 - 400, r0 - 300));
  elfm_camera_project(&cam, 800, 600, p, &c0, &r0);
  elfm_camera_pan(&cam, 25, -10, 600);
  elfm_camera_project(&cam, 800, 600, p, &c, &r);
  CHECK_NEAR(c - c0, 25, 1e-6);
  CHECK_NEAR(r - r0, -10, 1e-6);
  /* Rotation keeps distances to the target (orthographic, no scaling). */
  cam.target_um[0] = cam.target_um[1] = cam.target_um[2] = 0;
  double q[3] = {30, 0, 0};
  cam.yaw_rad = cam.pitch_rad = 0;
  elfm_camera_rotate(&cam, 100, 0);
  elfm_camera_project(&cam, 800, 600, q, &c, &r);
  double ppu = 600 / (2 * cam.half_height_um);
  CHECK(hypot(c - 400, r - 300) < 30 * ppu - 1); /* turned, so foreshortened */
  CHECK(hypot(c - 400, r - 300) > 0);
}

static void test_font_ticks(void)
{
  uint8_t g[7], h[7];
  const char *need = "0123456789ABCDEFGHIJKLMNOPQRSTUVWXYZ .,-+:=/()%_";
  for (const char *p = need; *p; p++) CHECK_MSG(elfm_font_glyph(*p, g), "glyph '%c'", *p);
  elfm_font_glyph('a', g);
  elfm_font_glyph('A', h);
  CHECK(!memcmp(g, h, 7));
  CHECK(!elfm_font_glyph('~', g)); /* not in the table: filled box */
  CHECK(g[0] == 0x1F && g[6] == 0x1F);
  /* Digits are all different glyphs, all within 5 columns. */
  uint8_t d[10][7];
  for (int k = 0; k < 10; k++) {
    elfm_font_glyph((char)('0' + k), d[k]);
    for (int r = 0; r < 7; r++) CHECK(d[k][r] < 0x20);
  }
  int distinct = 1;
  for (int a = 0; a < 10; a++)
    for (int b = a + 1; b < 10; b++) distinct &= memcmp(d[a], d[b], 7) != 0;
  CHECK(distinct);
  /* and every glyph differs from every other (a 0 drawn as an O, a 5 as
   * an S, would misread a label) */
  const size_t n_need = strlen(need);
  for (size_t a = 0; a < n_need; a++) {
    elfm_font_glyph(need[a], g);
    for (size_t b = a + 1; b < n_need; b++) {
      elfm_font_glyph(need[b], h);
      CHECK_MSG(memcmp(g, h, 7) != 0, "'%c' and '%c' are drawn alike", need[a], need[b]);
    }
  }
  CHECK_NEAR(elfm_nice_step(130, 5), 20, 1e-12);
  CHECK_NEAR(elfm_nice_step(200, 5), 50, 1e-12);
  CHECK_NEAR(elfm_nice_step(1.0, 5), 0.2, 1e-12);
  CHECK_NEAR(elfm_nice_step(700, 1), 500, 1e-9);
  int x0, y0, x1, y1;
  elfm_overlay_colorbar_rect(1280, 800, &x0, &y0, &x1, &y1);
  CHECK(x0 > 1000 && x1 > x0 && x1 < 1280 && y0 > 0 && y1 > y0 + 400 && y1 < 800);
}

static const char *tracks_csv =
  "track_id,frame,t_us,x_um,y_um,z_um,raw_x_um,raw_y_um,raw_z_um,vx_um_per_ms,vy_um_per_ms,"
  "vz_um_per_ms,intensity\n"
  "7,0,1000,1,2,3,1,2,3,0,0,0,5\n"
  "3,0,1000,-10,0,0,,,,0,0,0,5\n"
  "7,2,3000,5,2,3,5,2,3,0,0,0,5\n"
  "3,1,2000,-11,0,0,-11,0,0,0,0,0,5\n"
  "7,1,2000,3,2,3,3,2,3,0,0,0,5\n";

/* Loading run folder `run` finds one MIP, at t_us. */
static void expect_one_mip(const char *run, int64_t t_us)
{
  elfm_error err;
  elfm_view_data *d = NULL;
  CHECK_OK(elfm_view_data_load(tpath(run), NULL, &d, &err), &err);
  if (d) {
    CHECK_EQ_INT(d->n_mips, 1);
    if (d->n_mips == 1) CHECK_EQ_INT(d->mips[0].t_us, t_us);
  }
  elfm_view_data_free(d);
}

static void test_load(void)
{
  elfm_error err;
  elfm_view_data *d = NULL;
  write_file("run/tracks.csv", tracks_csv);
  write_file("run/detections.csv",
             "frame,t_us,x_um,y_um,z_um,intensity\n0,1000,1,2,3,9\n2,3000,40,2,3,9\n");
  CHECK_OK(elfm_view_data_load(tpath("run"), NULL, &d, &err), &err);
  if (d) {
    CHECK_EQ_INT(d->tracks.n_lines, 2);
    CHECK_EQ_INT(d->tracks.n_points, 5);
    CHECK_EQ_INT(d->tracks.id[0], 3);
    CHECK_EQ_INT(d->tracks.id[1], 7);
    CHECK_EQ_INT(d->tracks.first[1], 2);
    /* Sorted by time within a track. */
    CHECK_EQ_INT(d->tracks.t_us[2], 1000);
    CHECK_EQ_INT(d->tracks.t_us[4], 3000);
    CHECK_NEAR(d->tracks.xyz_um[3 * 3], 3, 1e-6);
    CHECK_NEAR(d->tracks.xyz_um[0], -10, 1e-6);
    CHECK_EQ_INT(d->n_detections, 2);
    CHECK_EQ_INT(d->t_min_us, 1000);
    CHECK_EQ_INT(d->t_max_us, 3000);
    CHECK_EQ_INT(d->frame_dt_us, 1000);
    CHECK(!d->box_from_calib);
    /* Box = data extent (x -11..40) with a 5 % margin. */
    CHECK_NEAR(d->box_min_um[0], -11 - 0.05 * 51, 1e-6);
    CHECK_NEAR(d->box_max_um[0], 40 + 0.05 * 51, 1e-6);
    CHECK_NEAR(d->box_min_um[2], 0 - 1.0, 1e-6); /* margin at least 1 um */
    CHECK(d->tracks.shared == NULL); /* no claims column */
  }
  elfm_view_data_free(d);

  /* With tracks.csv's claims (elfm_link_step: live tracks whose gate held
   * the detection): shared where 2 or more, in the points' time order; a
   * filled point (claims empty) is not. */
  write_file("claims.csv", "track_id,frame,t_us,x_um,y_um,z_um,claims\n"
                           "7,2,3000,5,2,3,1\n7,0,1000,1,2,3,2\n7,1,2000,3,2,3,\n"
                           "3,0,1000,-10,0,0,3\n3,1,2000,-11,0,0,0\n");
  CHECK_OK(elfm_view_data_load(tpath("claims.csv"), NULL, &d, &err), &err);
  if (d) {
    CHECK(d->tracks.shared != NULL);
    if (d->tracks.shared) {
      const uint8_t want[5] = {1, 0, 1, 0, 0}; /* track 3 at 1, 2 ms; track 7 at 1, 2, 3 ms */
      for (int i = 0; i < 5; i++) CHECK_EQ_INT(d->tracks.shared[i], want[i]);
    }
  }
  elfm_view_data_free(d);

  /* A truth.csv alone is shown as the coloured lines; with --truth it is
   * the overlay. */
  write_file("truth.csv", "id,t_us,x_um,y_um,z_um,brightness\n1,0,0,0,0,1\n1,100,1,0,0,1\n"
                          "2,0,5,5,5,0\n2,100,6,5,5,1\n");
  CHECK_OK(elfm_view_data_load(tpath("truth.csv"), NULL, &d, &err), &err);
  if (d) {
    CHECK_EQ_INT(d->tracks.n_lines, 2);
    CHECK_EQ_INT(d->truth.n_lines, 0);
  }
  elfm_view_data_free(d);
  CHECK_OK(elfm_view_data_load(tpath("run/tracks.csv"), tpath("truth.csv"), &d, &err), &err);
  if (d) {
    CHECK_EQ_INT(d->tracks.n_lines, 2);
    CHECK_EQ_INT(d->truth.n_lines, 2);
    CHECK_EQ_INT(d->n_detections, 2); /* companion detections.csv beside tracks.csv */
    CHECK_EQ_INT(d->t_min_us, 0);
  }
  elfm_view_data_free(d);

  /* calib.json beside (or one level up) sets the box: SPEC §3 voxel axes. */
  elfm_optics o;
  elfm_optics_default(&o);
  elfm_calib c;
  CHECK_OK(elfm_calib_from_optics(&o, 1280, 720, 4.86, &c, &err), &err);
  CHECK_OK(elfm_calib_save(&c, tpath("calib.json"), &err), &err);
  CHECK_OK(elfm_view_data_load(tpath("run"), NULL, &d, &err), &err);
  if (d) {
    CHECK(d->box_from_calib);
    CHECK_NEAR(d->box_max_um[0], 0.5 * (c.view_w_px - 1) * c.um_per_px, 1e-9);
    CHECK_NEAR(d->box_min_um[1], -0.5 * (c.view_h_px - 1) * c.um_per_px, 1e-9);
    CHECK_NEAR(d->box_min_um[2], c.z_min_um, 1e-9);
    CHECK_NEAR(d->box_max_um[2], c.z_max_um, 1e-9);
    CHECK_EQ_INT(d->volume_w_px, c.view_w_px);
  }
  elfm_view_data_free(d);
  /* A broken calib.json is reported, not ignored. */
  write_file("calib.json", "{\"sensor\": 3");
  CHECK(elfm_view_data_load(tpath("run"), NULL, &d, &err) != ELFM_OK);
  CHECK(d == NULL);
  CHECK(strstr(err.file, "calib.json") != NULL);
  remove(tpath("calib.json"));

  /* Elsewhere, found through the run's summary.json ("calib": path). */
  mkdir(tpath("sim"), 0755);
  mkdir(tpath("trk"), 0755);
  CHECK_OK(elfm_calib_save(&c, tpath("sim/calib.json"), &err), &err);
  write_file("trk/tracks.csv", tracks_csv);
  char summary[1200];
  snprintf(summary, sizeof summary, "{\"events\": \"x.raw\", \"calib\": \"%s\"}",
           tpath("sim/calib.json"));
  write_file("trk/summary.json", summary);
  CHECK_OK(elfm_view_data_load(tpath("trk"), NULL, &d, &err), &err);
  if (d) {
    CHECK(d->box_from_calib);
    CHECK(strstr(d->calib_path, "sim/calib.json") != NULL);
  }
  elfm_view_data_free(d);
  /* ... also from a summary.json of many tracks: 6000 entries, 1.1 MB (a
   * run's summary lists every track; the viewer read its first 1 MB only,
   * and a cut summary was not JSON, until the sixty-first session). */
  {
    FILE *f = fopen(tpath("trk/summary.json"), "w");
    CHECK(f != NULL);
    if (f) {
      fprintf(f, "{\"events\": \"x.raw\", \"calib\": \"%s\", \"tracks\": [", tpath("sim/calib.json"));
      for (int k = 0; k < 6000; k++)
        fprintf(f, "%s{\"id\": %d, \"first_frame\": 0, \"last_frame\": 999, \"points\": 1000, "
                   "\"model\": \"spline\", \"spline_weight_ms3\": 12.5, \"edf\": 30.25, "
                   "\"outliers\": 0, \"mean_velocity_um_per_ms\": [1.5, -2.25, 0.125]}",
                k ? ", " : "", k);
      fprintf(f, "]}\n");
      CHECK(ftell(f) > (1L << 20));
      fclose(f);
    }
  }
  CHECK_OK(elfm_view_data_load(tpath("trk"), NULL, &d, &err), &err);
  if (d) CHECK(d->box_from_calib);
  elfm_view_data_free(d);
  /* A summary.json that is not JSON only loses the hint. */
  write_file("trk/summary.json", "{ not json");
  CHECK_OK(elfm_view_data_load(tpath("trk"), NULL, &d, &err), &err);
  if (d) CHECK(!d->box_from_calib);
  elfm_view_data_free(d);

  /* MIP pictures: time from "t<digits>" / "t_us" names, or a frame index
   * through the tracks' frame clock (frame 0 at 1000 us, 1000 us a frame). */
  mkdir(tpath("run/mips"), 0755);
  write_file("run/mips/mip_t000002500.png", "x");
  write_file("run/mips/mip_t000001500.png", "x");
  write_file("run/mips/notes.txt", "x");
  CHECK_OK(elfm_view_data_load(tpath("run"), NULL, &d, &err), &err);
  if (d) {
    CHECK_EQ_INT(d->n_mips, 2);
    if (d->n_mips == 2) {
      CHECK_EQ_INT(d->mips[0].t_us, 1500);
      CHECK_EQ_INT(d->mips[1].t_us, 2500);
      CHECK(strstr(d->mips[1].path, "mip_t000002500.png") != NULL);
    }
  }
  elfm_view_data_free(d);
  remove(tpath("run/mips/mip_t000002500.png"));
  remove(tpath("run/mips/mip_t000001500.png"));
  write_file("run/mips/frame_000002.png", "x");
  expect_one_mip("run", 3000);
  /* A run whose frames start later (a recording cut with --from-us):
   * frame 9 lies 4 frames after frame 5's 6000 us, not 9 frames after it
   * (a clock that counted from frame 0 passed every test until a
   * mutation sweep) */
  mkdir(tpath("late"), 0755);
  mkdir(tpath("late/mips"), 0755);
  write_file("late/tracks.csv", "track_id,frame,t_us,x_um,y_um,z_um\n1,5,6000,0,0,0\n1,6,7000,1,0,0\n"
                                "1,7,8000,2,0,0\n");
  write_file("late/mips/mip_000009.png", "x");
  expect_one_mip("late", 10000);
  /* MIPs from elsewhere (--mips): recon names them by frame number. */
  mkdir(tpath("rec"), 0755);
  mkdir(tpath("rec/mips"), 0755);
  write_file("rec/mips/mip_000000.png", "x");
  write_file("rec/mips/mip_000001.png", "x");
  CHECK_OK(elfm_view_data_load(tpath("run"), NULL, &d, &err), &err);
  if (d) {
    CHECK(d->has_frame_clock);
    CHECK_OK(elfm_view_data_load_mips(d, tpath("rec"), &err), &err);
    CHECK_EQ_INT(d->n_mips, 2);
    if (d->n_mips == 2) {
      CHECK_EQ_INT(d->mips[0].t_us, 1000);
      CHECK_EQ_INT(d->mips[1].t_us, 2000);
    }
    /* The folder itself works too; failures leave the MIPs as they were. */
    CHECK_OK(elfm_view_data_load_mips(d, tpath("rec/mips"), &err), &err);
    CHECK_EQ_INT(d->n_mips, 2);
    CHECK_EQ_INT(elfm_view_data_load_mips(d, tpath("nodir"), &err), ELFM_ERR_IO);
    CHECK(strstr(err.file, "nodir") != NULL);
    CHECK_EQ_INT(elfm_view_data_load_mips(d, tpath("emptydir2"), &err), ELFM_ERR_IO);
    mkdir(tpath("emptydir2"), 0755);
    CHECK_EQ_INT(elfm_view_data_load_mips(d, tpath("emptydir2"), &err), ELFM_ERR_FORMAT);
    CHECK(strstr(err.file, "emptydir2") != NULL);
    CHECK_EQ_INT(d->n_mips, 2);
  }
  elfm_view_data_free(d);
}

/* The shared flag on the GPU's vertices (series_lod.c): each vertex marks
 * the segment into it, at every level of detail the OR over the points
 * that segment stands for, so one shared point stays visible zoomed out. */
static void test_lod_shared(void)
{
  float xyz[3 * 9] = {0};
  int64_t t[9];
  uint8_t sh[9] = {0, 0, 0, 0, 0, 1, 0, 0, 0};
  size_t first[2] = {0, 9};
  int64_t id[1] = {1};
  for (int i = 0; i < 9; i++) {
    t[i] = 1000 * i;
    xyz[3 * i] = (float)i;
  }
  elfm_view_series s = {1, 9, first, id, xyz, t, sh};
  gui_series_gl g;
  memset(&g, 0, sizeof g);
  float *vtx = NULL;
  elfm_error err;
  CHECK_OK(gui_series_build(&s, 0, &g, &vtx, &err), &err);
  if (vtx) {
    /* level 0: the segment 4 -> 5 (vertex 5) only */
    for (int i = 0; i < 9; i++)
      CHECK_EQ_INT((int)vtx[(size_t)(g.lvl_first[0][0] + i) * GUI_VERTEX_FLOATS + 5], i == 5);
    /* level 2 (points 0, 4, 8): the chord 4 -> 8 */
    CHECK_EQ_INT(g.lvl_count[2][0], 3);
    for (int j = 0; j < 3; j++)
      CHECK_EQ_INT((int)vtx[(size_t)(g.lvl_first[2][0] + j) * GUI_VERTEX_FLOATS + 5], j == 2);
    /* level 3 (points 0, 8) */
    CHECK_EQ_INT((int)vtx[(size_t)(g.lvl_first[3][0] + 1) * GUI_VERTEX_FLOATS + 5], 1);
    CHECK_EQ_INT((int)vtx[(size_t)g.lvl_first[3][0] * GUI_VERTEX_FLOATS + 5], 0);
    /* but a straight line's coarse chords would mark 4 points for 1: in
     * shared mode those levels are not drawn (mixed), in the others they
     * are (this straight line is one chord: 2 vertices) */
    CHECK(g.lvl_err_um[0][0] == 0.0f);
    for (int l = 1; l < GUI_LOD_LEVELS; l++) CHECK(g.lvl_mixed[l][0] && g.lvl_err_um[l][0] < 1e-6f);
    CHECK_EQ_INT(gui_series_prepare(&g, 1.0, 1e30f, 0, 1), 9);
    CHECK_EQ_INT(gui_series_prepare(&g, 1.0, 1e30f, 0, 0), 2);
  }
  free(vtx);
  gui_series_arrays_free(&g);
  /* a shared stretch on chord boundaries: levels 1-2 keep it exact */
  const uint8_t sh2[9] = {0, 0, 0, 0, 0, 1, 1, 1, 1};
  memcpy(sh, sh2, sizeof sh);
  memset(&g, 0, sizeof g);
  CHECK_OK(gui_series_build(&s, 0, &g, &vtx, &err), &err);
  CHECK(!g.lvl_mixed[1][0] && !g.lvl_mixed[2][0] && g.lvl_mixed[3][0]);
  CHECK_EQ_INT(gui_series_prepare(&g, 1.0, 1e30f, 0, 1), 3); /* level 2: 0, 4, 8 */
  free(vtx);
  gui_series_arrays_free(&g);
  /* without flags: 0 everywhere */
  s.shared = NULL;
  memset(&g, 0, sizeof g);
  CHECK_OK(gui_series_build(&s, 0, &g, &vtx, &err), &err);
  for (size_t i = 0; vtx && i < g.n_vertices; i++) CHECK_EQ_INT((int)vtx[i * GUI_VERTEX_FLOATS + 5], 0);
  free(vtx);
  gui_series_arrays_free(&g);
}

/* A level's error (series_lod.c) is each skipped point's distance from
 * the chord at its own time: a straight line at constant speed sampled
 * at uneven times (a track with gaps) is exact at every level, and the
 * same points moved off the line by 0.3 um once are not. */
static void test_lod_error(void)
{
  static const int64_t t_ms[9] = {0, 1, 2, 3, 10, 11, 12, 20, 21};
  float xyz[3 * 9];
  int64_t t[9];
  size_t first[2] = {0, 9};
  int64_t id[1] = {1};
  for (int i = 0; i < 9; i++) {
    t[i] = 1000 * t_ms[i];
    xyz[3 * i] = 2.5f * (float)t_ms[i]; /* 2.5 um/ms along x */
    xyz[3 * i + 1] = -1.0f * (float)t_ms[i];
    xyz[3 * i + 2] = 5;
  }
  elfm_view_series s = {1, 9, first, id, xyz, t, NULL};
  for (int bent = 0; bent < 2; bent++) {
    if (bent) xyz[3 * 3 + 1] += 0.3f; /* point 3, skipped at every level from 1 */
    gui_series_gl g;
    memset(&g, 0, sizeof g);
    float *vtx = NULL;
    elfm_error err;
    CHECK_OK(gui_series_build(&s, 0, &g, &vtx, &err), &err);
    for (int l = 1; vtx && l < GUI_LOD_LEVELS; l++)
      CHECK_MSG(bent ? fabsf(g.lvl_err_um[l][0] - 0.3f) < 1e-4f : g.lvl_err_um[l][0] < 1e-4f,
                "bent %d, level %d: error %g um", bent, l, (double)g.lvl_err_um[l][0]);
    free(vtx);
    gui_series_arrays_free(&g);
  }
}

static void test_load_errors(void)
{
  elfm_error err;
  elfm_view_data *d = (elfm_view_data *)&err; /* must be reset to NULL */
  CHECK_EQ_INT(elfm_view_data_load(tpath("nope.csv"), NULL, &d, &err), ELFM_ERR_IO);
  CHECK(d == NULL);
  CHECK(strstr(err.file, "nope.csv") != NULL);
  /* Header only: nothing to show, named with its line. */
  write_file("empty.csv", "track_id,frame,t_us,x_um,y_um,z_um\n");
  CHECK_EQ_INT(elfm_view_data_load(tpath("empty.csv"), NULL, &d, &err), ELFM_ERR_FORMAT);
  CHECK(strstr(err.file, "empty.csv") != NULL);
  CHECK_EQ_INT(err.line, 1);
  /* A missing column is named. */
  write_file("noz.csv", "track_id,frame,t_us,x_um,y_um\n1,0,0,1,2\n");
  CHECK_EQ_INT(elfm_view_data_load(tpath("noz.csv"), NULL, &d, &err), ELFM_ERR_FORMAT);
  CHECK(strstr(err.message, "z_um") != NULL);
  /* A bad number: file and line from the table loader. */
  write_file("bad.csv", "track_id,frame,t_us,x_um,y_um,z_um\n1,0,0,1,2,3\n1,1,100,abc,2,3\n");
  CHECK(elfm_view_data_load(tpath("bad.csv"), NULL, &d, &err) != ELFM_OK);
  CHECK_EQ_INT(err.line, 3);
  /* Truncated line (fewer fields). */
  write_file("short.csv", "track_id,frame,t_us,x_um,y_um,z_um\n1,0,0,1,2,3\n1,1,100\n");
  CHECK(elfm_view_data_load(tpath("short.csv"), NULL, &d, &err) != ELFM_OK);
  CHECK_EQ_INT(err.line, 3);
  /* Empty track id. */
  write_file("noid.csv", "track_id,frame,t_us,x_um,y_um,z_um\n,0,0,1,2,3\n");
  CHECK_EQ_INT(elfm_view_data_load(tpath("noid.csv"), NULL, &d, &err), ELFM_ERR_FORMAT);
  CHECK_EQ_INT(err.line, 2);
  /* --truth must be a truth file. */
  write_file("t2.csv", tracks_csv);
  CHECK_EQ_INT(elfm_view_data_load(tpath("t2.csv"), tpath("t2.csv"), &d, &err),
               ELFM_ERR_FORMAT);
  CHECK(strstr(err.message, "truth") != NULL);
  /* A directory with nothing to show. */
  mkdir(tpath("emptydir"), 0755);
  CHECK_EQ_INT(elfm_view_data_load(tpath("emptydir"), NULL, &d, &err), ELFM_ERR_IO);
  CHECK(strstr(err.file, "emptydir") != NULL);
  /* An empty file (not even a header). */
  write_file("zero.csv", "");
  CHECK(elfm_view_data_load(tpath("zero.csv"), NULL, &d, &err) != ELFM_OK);
  CHECK(strstr(err.file, "zero.csv") != NULL);
  CHECK(d == NULL);
  CHECK_EQ_INT(elfm_view_data_synthetic(0, 10, &d, &err), ELFM_ERR_INVALID);
}

static void test_synthetic(void)
{
  elfm_error err;
  elfm_view_data *d = NULL;
  CHECK_OK(elfm_view_data_synthetic(20, 50, &d, &err), &err);
  if (!d) return;
  CHECK_EQ_INT(d->tracks.n_lines, 20);
  CHECK_EQ_INT(d->tracks.n_points, 1000);
  CHECK_EQ_INT(d->t_max_us - d->t_min_us, 49000);
  int inside = 1;
  for (size_t i = 0; i < d->tracks.n_points; i++)
    for (int a = 0; a < 3; a++)
      inside &= d->tracks.xyz_um[3 * i + a] >= d->box_min_um[a] &&
                d->tracks.xyz_um[3 * i + a] <= d->box_max_um[a];
  CHECK(inside);
  elfm_view_data_free(d);
}

/* PNGs that another program wrote: grey, grey with 16 bits, grey with
 * alpha, RGBA, each handed back as 8-bit RGBA (the grey copied into R, G
 * and B; the alpha kept, or 255 where there is none). Written through
 * libpng's simplified API, which picks the file's colour type from the
 * format. */
static void test_png_kinds(void)
{
  const struct {
    const char *name;
    png_uint_32 format;
    int channels, bytes;
  } kinds[] = {
    {"grey8.png", PNG_FORMAT_GRAY, 1, 1},
    {"grey16.png", PNG_FORMAT_LINEAR_Y, 1, 2},
    {"greyA.png", PNG_FORMAT_GA, 2, 1},
    {"rgba.png", PNG_FORMAT_RGBA, 4, 1},
  };
  enum { W = 5, H = 3 };
  for (size_t k = 0; k < sizeof kinds / sizeof kinds[0]; k++) {
    uint16_t pix[W * H * 4];
    uint8_t pix8[W * H * 4];
    for (int i = 0; i < W * H * kinds[k].channels; i++) {
      const int v = (i * 37 + 11) % 256;
      pix8[i] = (uint8_t)v;
      pix[i] = (uint16_t)(v * 257); /* 16 bits whose top byte is v */
    }
    png_image im;
    memset(&im, 0, sizeof im);
    im.version = PNG_IMAGE_VERSION;
    im.width = W;
    im.height = H;
    im.format = kinds[k].format;
    const int wrote = png_image_write_to_file(&im, tpath(kinds[k].name), 0,
                                              kinds[k].bytes == 2 ? (const void *)pix : (const void *)pix8,
                                              0, NULL);
    png_image_free(&im);
    CHECK_MSG(wrote, "%s: %s", kinds[k].name, im.message);
    if (!wrote) continue;
    int w = 0, h = 0;
    uint8_t *rgba = NULL;
    elfm_error err;
    CHECK_OK(elfm_png_read_rgba(tpath(kinds[k].name), &w, &h, &rgba, &err), &err);
    CHECK_EQ_INT(w, W);
    CHECK_EQ_INT(h, H);
    int bad = rgba == NULL;
    for (int p = 0; rgba && p < W * H; p++) {
      const int c = kinds[k].channels;
      const uint8_t *src = pix8 + (size_t)p * c;
      const int grey = c <= 2, alpha = c == 2 || c == 4;
      const int want[4] = {src[0], grey ? src[0] : src[1], grey ? src[0] : src[2],
                           alpha ? src[c - 1] : 255};
      for (int q = 0; q < 4; q++) bad += rgba[4 * p + q] != want[q];
    }
    CHECK_MSG(!bad, "%s: %d channel values not as written", kinds[k].name, bad);
    free(rgba);
  }
}

static void test_png(void)
{
  elfm_error err;
  uint8_t rgb[3 * 4 * 3];
  for (int i = 0; i < 36; i++) rgb[i] = (uint8_t)(i * 7);
  CHECK_OK(elfm_png_write_rgb(tpath("a.png"), 4, 3, rgb, &err), &err);
  int w = 0, h = 0;
  uint8_t *rgba = NULL;
  CHECK_OK(elfm_png_read_rgba(tpath("a.png"), &w, &h, &rgba, &err), &err);
  CHECK_EQ_INT(w, 4);
  CHECK_EQ_INT(h, 3);
  int same = rgba != NULL;
  for (int p = 0; rgba && p < 12; p++)
    same &= rgba[4 * p] == rgb[3 * p] && rgba[4 * p + 1] == rgb[3 * p + 1] &&
            rgba[4 * p + 2] == rgb[3 * p + 2] && rgba[4 * p + 3] == 255;
  CHECK(same);
  free(rgba);
  /* Truncated PNG and not-a-PNG: errors naming the file. */
  FILE *f = fopen(tpath("a.png"), "rb");
  uint8_t buf[4096];
  size_t n = f ? fread(buf, 1, sizeof buf, f) : 0;
  if (f) fclose(f);
  f = fopen(tpath("trunc.png"), "wb");
  if (f) {
    fwrite(buf, 1, n / 2, f);
    fclose(f);
  }
  rgba = NULL;
  CHECK_EQ_INT(elfm_png_read_rgba(tpath("trunc.png"), &w, &h, &rgba, &err), ELFM_ERR_FORMAT);
  CHECK(rgba == NULL);
  CHECK(strstr(err.file, "trunc.png") != NULL);
  write_file("fake.png", "GIF89a not a png at all");
  CHECK_EQ_INT(elfm_png_read_rgba(tpath("fake.png"), &w, &h, &rgba, &err), ELFM_ERR_FORMAT);
  CHECK_EQ_INT(err.offset, 0);
  CHECK_EQ_INT(elfm_png_read_rgba(tpath("none.png"), &w, &h, &rgba, &err), ELFM_ERR_IO);
  CHECK_EQ_INT(elfm_png_write_rgb(tpath("nodir/x.png"), 4, 3, rgb, &err), ELFM_ERR_IO);
  test_png_kinds();
}

/* Without a display: a clear ELFM_ERR_DISPLAY from the library, and from the
 * CLI a non-zero exit (not a signal) with a message on stderr. */
/* A child's stderr, as text ("" when the file is missing). */
static void read_text(const char *path, char *buf, size_t cap)
{
  buf[0] = '\0';
  FILE *f = fopen(path, "r");
  if (!f) return;
  size_t n = fread(buf, 1, cap - 1, f);
  buf[n] = '\0';
  fclose(f);
}

static void test_no_display(void)
{
  unsetenv("DISPLAY");
  unsetenv("WAYLAND_DISPLAY");
  elfm_error err;
  elfm_view_data *d = NULL;
  CHECK_OK(elfm_view_data_synthetic(2, 2, &d, &err), &err);
  elfm_viewer_options o;
  elfm_viewer_options_default(&o);
  o.visible = 0;
  elfm_viewer *v = (elfm_viewer *)&err;
  CHECK_EQ_INT(elfm_viewer_create(&o, d, &v, &err), ELFM_ERR_DISPLAY);
  CHECK(v == NULL);
  CHECK(strstr(err.message, "display") != NULL);
  elfm_view_data_free(d);

  char cmd[1024];
  const char *bin = ELFM_BINARY_DIR "/eventlfm";
  if (access(bin, X_OK) != 0) {
    fprintf(stderr, "note: %s not built, CLI no-display check left out\n", bin);
    return;
  }
  /* Leak checking of the child is off: this checks its exit and message. */
  snprintf(cmd, sizeof cmd,
           "ASAN_OPTIONS=detect_leaks=0 %s view --synthetic 3x3 --screenshot %s 2>%s", bin,
           tpath("nd.png"), tpath("nd.err"));
  int rc = system(cmd);
  CHECK(WIFEXITED(rc));
  CHECK_EQ_INT(WEXITSTATUS(rc), 1);
  char msg[2048];
  read_text(tpath("nd.err"), msg, sizeof msg);
  CHECK_MSG(strstr(msg, "no display") != NULL, "stderr was: %s", msg);
  CHECK(access(tpath("nd.png"), F_OK) != 0);
  /* Usage errors exit 2 before any window. */
  snprintf(cmd, sizeof cmd, "%s view --size 10 x.csv 2>/dev/null", bin);
  rc = system(cmd);
  CHECK(WIFEXITED(rc) && WEXITSTATUS(rc) == 2);
  snprintf(cmd, sizeof cmd, "%s view 2>/dev/null", bin);
  rc = system(cmd);
  CHECK(WIFEXITED(rc) && WEXITSTATUS(rc) == 2);
  /* an unknown colour mode names the modes, shared among them */
  snprintf(cmd, sizeof cmd, "%s view --color purple x.csv 2>%s", bin, tpath("c.err"));
  rc = system(cmd);
  CHECK(WIFEXITED(rc) && WEXITSTATUS(rc) == 2);
  read_text(tpath("c.err"), msg, sizeof msg);
  CHECK_MSG(strstr(msg, "--color") && strstr(msg, "shared") && strstr(msg, "purple"),
            "stderr was: %s", msg);
  /* A missing input is a failure naming the file, before any window. */
  snprintf(cmd, sizeof cmd, "%s view %s 2>%s", bin, tpath("missing.csv"), tpath("m.err"));
  rc = system(cmd);
  CHECK(WIFEXITED(rc) && WEXITSTATUS(rc) == 1);
  read_text(tpath("m.err"), msg, sizeof msg);
  CHECK_MSG(strstr(msg, "missing.csv") != NULL, "stderr was: %s", msg);
}

/* Which key gives which command: the table of docs/viewer.md, and keys
 * that give none (q and Esc close the window in the key handler itself). */
static void test_keys(void)
{
  const struct {
    int key, shift;
    elfm_viewer_cmd cmd;
  } keys[] = {
    {GLFW_KEY_R, 0, ELFM_CMD_RESET_VIEW},
    {GLFW_KEY_C, 0, ELFM_CMD_CYCLE_COLOR},
    {GLFW_KEY_SPACE, 0, ELFM_CMD_PLAY_PAUSE},
    {GLFW_KEY_RIGHT, 0, ELFM_CMD_STEP_FORWARD},
    {GLFW_KEY_LEFT, 0, ELFM_CMD_STEP_BACK},
    {GLFW_KEY_RIGHT, 1, ELFM_CMD_STEP_FORWARD_10},
    {GLFW_KEY_LEFT, 1, ELFM_CMD_STEP_BACK_10},
    {GLFW_KEY_HOME, 0, ELFM_CMD_HOME},
    {GLFW_KEY_END, 0, ELFM_CMD_END},
    {GLFW_KEY_EQUAL, 0, ELFM_CMD_FASTER},
    {GLFW_KEY_EQUAL, 1, ELFM_CMD_FASTER}, /* `+` on most layouts */
    {GLFW_KEY_KP_ADD, 0, ELFM_CMD_FASTER},
    {GLFW_KEY_MINUS, 0, ELFM_CMD_SLOWER},
    {GLFW_KEY_KP_SUBTRACT, 0, ELFM_CMD_SLOWER},
    {GLFW_KEY_T, 0, ELFM_CMD_TOGGLE_TRUTH},
    {GLFW_KEY_D, 0, ELFM_CMD_TOGGLE_DETECTIONS},
    {GLFW_KEY_M, 0, ELFM_CMD_TOGGLE_MIP},
    {GLFW_KEY_H, 0, ELFM_CMD_TOGGLE_HELP},
  };
  for (size_t k = 0; k < sizeof keys / sizeof keys[0]; k++) {
    elfm_viewer_cmd cmd = (elfm_viewer_cmd)-1;
    const int got = elfm_viewer_key_command(keys[k].key, keys[k].shift, &cmd);
    CHECK_MSG(got && cmd == keys[k].cmd, "key %d (shift %d): command %d, not %d", keys[k].key,
              keys[k].shift, got ? (int)cmd : -1, (int)keys[k].cmd);
  }
  const int none[] = {GLFW_KEY_Q, GLFW_KEY_ESCAPE, GLFW_KEY_A, GLFW_KEY_X, GLFW_KEY_UP, GLFW_KEY_0};
  for (size_t k = 0; k < sizeof none / sizeof none[0]; k++) {
    elfm_viewer_cmd cmd;
    CHECK_MSG(!elfm_viewer_key_command(none[k], 0, &cmd), "key %d gives a command", none[k]);
  }
  /* the mouse: docs/viewer.md's table */
  CHECK(elfm_viewer_drag_mode(GLFW_MOUSE_BUTTON_LEFT, 0) == ELFM_DRAG_ROTATE);
  CHECK(elfm_viewer_drag_mode(GLFW_MOUSE_BUTTON_LEFT, 1) == ELFM_DRAG_PAN);
  CHECK(elfm_viewer_drag_mode(GLFW_MOUSE_BUTTON_RIGHT, 0) == ELFM_DRAG_PAN);
  CHECK(elfm_viewer_drag_mode(GLFW_MOUSE_BUTTON_RIGHT, 1) == ELFM_DRAG_PAN);
  CHECK(elfm_viewer_drag_mode(GLFW_MOUSE_BUTTON_MIDDLE, 0) == ELFM_DRAG_PAN);
  CHECK(elfm_viewer_drag_mode(GLFW_MOUSE_BUTTON_4, 0) == ELFM_DRAG_NONE);
}

int main(void)
{
  /* Work one level below a private directory: calib.json is also looked
   * for one level up, which must be ours, not /tmp's. */
  char top[200];
  snprintf(top, sizeof top, "%s/gui_core_XXXXXX", P_tmpdir);
  if (!mkdtemp(top)) SKIP("cannot make a temporary directory: %s", strerror(errno));
  snprintf(tmpdir, sizeof tmpdir, "%s/w", top);
  mkdir(tmpdir, 0755);
  mkdir(tpath("run"), 0755);
  test_colormap();
  test_camera();
  test_font_ticks();
  test_load();
  test_load_errors();
  test_lod_shared();
  test_lod_error();
  test_synthetic();
  test_png();
  test_keys();
  test_no_display();
  char cmd[600];
  snprintf(cmd, sizeof cmd, "rm -rf '%s'", top);
  if (system(cmd) != 0) fprintf(stderr, "note: could not remove %s\n", top);
  return check_report();
}
