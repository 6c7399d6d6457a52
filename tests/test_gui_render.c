/* test_gui_render.c — the viewer's pictures, checked pixel by pixel.
 *
 * Needs an X display with OpenGL 3.3: without DISPLAY the test starts itself
 * again under `xvfb-run` (Mesa's software renderer), and skips (exit 77)
 * when xvfb-run is not installed.
 *
 * Scene with known geometry: track A runs along x (t 0..100 ms), track B
 * along z, a grey truth line, white detections, a magenta MIP. The checks
 * project the known points with the viewer's camera and look at the pixels:
 * tracks where they project and in the colour of their time, hue falling
 * with time, background where nothing is, the colour bar, the time cursor,
 * colour by depth and by track, truth grey, detections white, the MIP plane,
 * and the CLI's --screenshot PNG.
 */
#define _GNU_SOURCE /* dl_iterate_phdr */
#include <dlfcn.h>
#include <errno.h>
#include <link.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include "check.h"
#include "elfm_gui.h"
#include "elfm_recon.h"

/* Under AddressSanitizer: Mesa and Xlib keep allocations for the process's
 * life (driver caches); our own leaks are still reported. Mesa's driver is
 * unloaded when GLFW terminates, and its leftovers would then show as
 * "<unknown module>"; pin_gl_modules() keeps it loaded so the names below
 * match. */
const char *__lsan_default_suppressions(void);
const char *__lsan_default_suppressions(void)
{
  return "leak:libGLX_mesa.so\nleak:swrast_dri.so\nleak:libgallium\nleak:libLLVM\n"
         "leak:libX11.so\nleak:libglapi.so\nleak:libGLdispatch.so\nleak:libdrm\n";
}

/* Keep the OpenGL driver's libraries mapped until exit (see above); only
 * under AddressSanitizer, so that other builds test the viewer exactly as
 * it runs. */
#if defined(__SANITIZE_ADDRESS__)
static int pin_one(struct dl_phdr_info *info, size_t size, void *data)
{
  (void)size;
  (void)data;
  const char *n = info->dlpi_name;
  if (n && *n &&
      (strstr(n, "_dri.so") || strstr(n, "gallium") || strstr(n, "LLVM")))
    dlopen(n, RTLD_NOW | RTLD_NOLOAD | RTLD_NODELETE); /* handle not needed: never closed */
  return 0;
}

static void pin_gl_modules(void) { dl_iterate_phdr(pin_one, NULL); }
#else
static void pin_gl_modules(void) {}
#endif

#define W 640
#define H 480

static char dir[256];
static uint8_t img[W * H * 3];

static const char *tpath(const char *name)
{
  static char p[4][512]; /* test driver: rotating buffers */
  static int k;
  k = (k + 1) % 4;
  snprintf(p[k], sizeof p[k], "%s/%s", dir, name);
  return p[k];
}

/* Re-run this program under xvfb-run when there is no display. */
static void ensure_display(char **argv)
{
  const char *d = getenv("DISPLAY");
  if (d && *d) return;
  if (getenv("ELFM_TEST_UNDER_XVFB")) SKIP("xvfb-run started, but no DISPLAY was set");
  const char *path = getenv("PATH");
  char found[1024] = "";
  for (const char *p = path ? path : "/usr/bin:/bin"; *p;) {
    const char *e = strchr(p, ':');
    size_t n = e ? (size_t)(e - p) : strlen(p);
    snprintf(found, sizeof found, "%.*s/xvfb-run", (int)n, p);
    if (access(found, X_OK) == 0) break;
    found[0] = '\0';
    p += n + (e != NULL);
  }
  if (!found[0])
    SKIP("no DISPLAY and xvfb-run is not installed (Debian: apt-get install xvfb xauth)");
  setenv("ELFM_TEST_UNDER_XVFB", "1", 1);
  /* xvfb-run -a takes the first free display from -n on; starting from a
   * number of our own makes a clash with another xvfb-run starting at the
   * same moment (other test runs on this machine) unlikely. */
  char num[16];
  snprintf(num, sizeof num, "%d", 100 + (int)(getpid() % 800));
  /* -noreset: Xvfb otherwise resets when its last client leaves, and a
   * viewer created during the reset cannot open the display (seen under
   * ctest -j2: "Failed to open display" between two viewers) */
  char *args[] = {found, "-a", "-n", num, "-s", "-screen 0 1280x1024x24 -noreset", argv[0], NULL};
  execv(found, args);
  SKIP("could not start xvfb-run: %s", strerror(errno));
}

static void write_file(const char *name, const char *text)
{
  FILE *f = fopen(tpath(name), "w");
  if (!f) {
    fprintf(stderr, "cannot write %s\n", tpath(name));
    exit(1);
  }
  fputs(text, f);
  fclose(f);
}

/* Track A: x -50..50 at y=-30, z=-40; track B: z -40..40 at x=40, y=30; both
 * t = 0..100 ms, one point per ms. Truth: x -50..50 at y=0, z=40.
 * Detections at t = 100 ms around (-40, 30, 20). */
static double a_pos(int i, int axis)
{
  double x[3] = {-50 + i, -30, -40};
  return x[axis];
}
static double b_pos(int i, int axis)
{
  double x[3] = {40, 30, -40 + 0.8 * i};
  return x[axis];
}
static double truth_pos(int i, int axis)
{
  double x[3] = {-50 + i, 0, 40};
  return x[axis];
}
static const double det_pos[3][3] = {{-40, 30, 20}, {-35, 35, 20}, {-45, 25, 25}};
/* and one at t = 50 ms, away from the lines: drawn only while the cursor is
 * within 10 frames after it */
static const double det_mid[3] = {10, -10, 0};

static void write_scene(void)
{
  char *buf = malloc(1 << 20);
  size_t n = 0;
  n += (size_t)sprintf(buf + n, "track_id,frame,t_us,x_um,y_um,z_um,raw_x_um,raw_y_um,"
                                "raw_z_um,vx_um_per_ms,vy_um_per_ms,vz_um_per_ms,intensity,"
                                "claims\n");
  /* A's detections at 40-60 ms lay in two tracks' gates (claims 2) */
  for (int i = 0; i <= 100; i++) {
    n += (size_t)sprintf(buf + n, "1,%d,%d,%g,%g,%g,,,,0,0,0,1,%d\n", i, i * 1000, a_pos(i, 0),
                         a_pos(i, 1), a_pos(i, 2), i >= 40 && i <= 60 ? 2 : 1);
    n += (size_t)sprintf(buf + n, "2,%d,%d,%g,%g,%g,,,,0,0,0,1,1\n", i, i * 1000, b_pos(i, 0),
                         b_pos(i, 1), b_pos(i, 2));
  }
  buf[n] = '\0';
  write_file("tracks.csv", buf);
  n = (size_t)sprintf(buf, "id,t_us,x_um,y_um,z_um,brightness\n");
  for (int i = 0; i <= 100; i++)
    n += (size_t)sprintf(buf + n, "5,%d,%g,%g,%g,1\n", i * 1000, truth_pos(i, 0),
                         truth_pos(i, 1), truth_pos(i, 2));
  write_file("truth.csv", buf);
  n = (size_t)sprintf(buf, "frame,t_us,x_um,y_um,z_um,intensity\n");
  for (int k = 0; k < 3; k++)
    n += (size_t)sprintf(buf + n, "100,100000,%g,%g,%g,1\n", det_pos[k][0], det_pos[k][1],
                         det_pos[k][2]);
  n += (size_t)sprintf(buf + n, "50,50000,%g,%g,%g,1\n", det_mid[0], det_mid[1], det_mid[2]);
  write_file("detections.csv", buf);
  free(buf);
  /* A 16 x 16 magenta MIP standing for t = 20 ms onwards. */
  mkdir(tpath("mips"), 0755);
  uint8_t mip[16 * 16 * 3];
  for (int i = 0; i < 16 * 16; i++) {
    mip[3 * i] = 255;
    mip[3 * i + 1] = 0;
    mip[3 * i + 2] = 255;
  }
  elfm_error err;
  CHECK_OK(elfm_png_write_rgb(tpath("mips/mip_t000020000.png"), 16, 16, mip, &err), &err);
}

static const uint8_t *px(int c, int r) { return img + ((size_t)r * W + c) * 3; }

static int saturation(const uint8_t *p)
{
  int mx = p[0] > p[1] ? (p[0] > p[2] ? p[0] : p[2]) : (p[1] > p[2] ? p[1] : p[2]);
  int mn = p[0] < p[1] ? (p[0] < p[2] ? p[0] : p[2]) : (p[1] < p[2] ? p[1] : p[2]);
  return mx - mn;
}

/* Is some pixel within +-2 px of (c, r) the truth's grey, or a detection's
 * white? */
static int grey_near(double c, double r)
{
  for (int dr = -2; dr <= 2; dr++)
    for (int dc = -2; dc <= 2; dc++) {
      const uint8_t *p = px((int)c + dc, (int)r + dr);
      if (saturation(p) < 12 && p[0] > 110 && p[0] < 200) return 1;
    }
  return 0;
}

static int white_near(double c, double r)
{
  for (int dr = -2; dr <= 2; dr++)
    for (int dc = -2; dc <= 2; dc++) {
      const uint8_t *p = px((int)c + dc, (int)r + dr);
      if (p[0] > 220 && p[1] > 220 && p[2] > 220) return 1;
    }
  return 0;
}

/* The most saturated pixel within +-rad of (c, r); NULL if none has
 * saturation >= 80 (grey, white and background have ~0). */
static const uint8_t *coloured_near(double c, double r, int rad)
{
  const uint8_t *best = NULL;
  int bs = 79;
  for (int dr = -rad; dr <= rad; dr++)
    for (int dc = -rad; dc <= rad; dc++) {
      int cc = (int)floor(c) + dc, rr = (int)floor(r) + dr;
      if (cc < 0 || rr < 0 || cc >= W || rr >= H) continue;
      int s = saturation(px(cc, rr));
      if (s > bs) {
        bs = s;
        best = px(cc, rr);
      }
    }
  return best;
}

/* A pixel within +-rad of (c, r) that `ok` accepts. */
static int any_near(double c, double r, int rad, int (*ok)(const uint8_t *p))
{
  for (int dr = -rad; dr <= rad; dr++)
    for (int dc = -rad; dc <= rad; dc++) {
      int cc = (int)floor(c) + dc, rr = (int)floor(r) + dr;
      if (cc >= 0 && rr >= 0 && cc < W && rr < H && ok(px(cc, rr))) return 1;
    }
  return 0;
}

/* the shared stretches' magenta (the shader's 1.0, 0.2, 1.0) */
static int is_magenta(const uint8_t *p) { return p[0] > 200 && p[1] < 110 && p[2] > 200; }
/* brighter than the background */
static int is_lit(const uint8_t *p) { return p[0] + p[1] + p[2] > 60; }

static double hue_of(const uint8_t *p)
{
  double h = elfm_color_hue_deg(p[0], p[1], p[2]);
  return h > 300 ? h - 360 : h; /* turbo's deep-red end wraps past 0 */
}

static void project(elfm_viewer *v, double (*pos)(int, int), int i, double *c, double *r)
{
  double p[3] = {pos(i, 0), pos(i, 1), pos(i, 2)};
  elfm_camera_project(elfm_viewer_camera(v), W, H, p, c, r);
}

static double seg_dist(double pc, double pr, double ac, double ar, double bc, double br)
{
  double dc = bc - ac, dr = br - ar, l2 = dc * dc + dr * dr;
  double t = l2 > 0 ? ((pc - ac) * dc + (pr - ar) * dr) / l2 : 0;
  t = t < 0 ? 0 : t > 1 ? 1 : t;
  return hypot(pc - (ac + t * dc), pr - (ar + t * dr));
}

/* Distance in pixels from (c, r) to anything the scene draws in 3D. */
static double dist_to_scene(elfm_viewer *v, const elfm_view_data *d, double c, double r)
{
  double best = 1e9;
  double (*lines[3])(int, int) = {a_pos, b_pos, truth_pos};
  for (int l = 0; l < 3; l++) {
    double ac, ar, bc, br;
    project(v, lines[l], 0, &ac, &ar);
    project(v, lines[l], 100, &bc, &br);
    best = fmin(best, seg_dist(c, r, ac, ar, bc, br));
  }
  for (int k = 0; k < 3; k++) {
    double dc, dr;
    elfm_camera_project(elfm_viewer_camera(v), W, H, det_pos[k], &dc, &dr);
    best = fmin(best, hypot(c - dc, r - dr));
  }
  const double *lo = d->box_min_um, *hi = d->box_max_um;
  for (int a = 0; a < 3; a++)
    for (int k = 0; k < 4; k++) {
      int b = (a + 1) % 3, e = (a + 2) % 3;
      double p0[3], p1[3], c0, r0, c1, r1;
      p0[a] = lo[a];
      p1[a] = hi[a];
      p0[b] = p1[b] = (k & 1) ? hi[b] : lo[b];
      p0[e] = p1[e] = (k & 2) ? hi[e] : lo[e];
      elfm_camera_project(elfm_viewer_camera(v), W, H, p0, &c0, &r0);
      elfm_camera_project(elfm_viewer_camera(v), W, H, p1, &c1, &r1);
      best = fmin(best, seg_dist(c, r, c0, r0, c1, r1));
    }
  return best;
}

static void render(elfm_viewer *v)
{
  elfm_error err;
  CHECK_OK(elfm_viewer_render_rgb(v, W, H, img, &err), &err);
}

int main(int argc, char **argv)
{
  (void)argc;
  ensure_display(argv);
  snprintf(dir, sizeof dir, "%s/gui_render_XXXXXX", P_tmpdir);
  if (!mkdtemp(dir)) SKIP("cannot make a temporary directory: %s", strerror(errno));
  write_scene();

  elfm_error err;
  elfm_view_data *d = NULL;
  CHECK_OK(elfm_view_data_load(dir, tpath("truth.csv"), &d, &err), &err);
  if (!d) return check_report();
  CHECK_EQ_INT(d->n_mips, 1);
  elfm_viewer_options o;
  elfm_viewer_options_default(&o);
  o.visible = 0;
  o.width = W;
  o.height = H;
  elfm_viewer *v = NULL;
  CHECK_OK(elfm_viewer_create(&o, d, &v, &err), &err);
  if (!v) {
    elfm_view_data_free(d);
    return check_report();
  }
  pin_gl_modules();

  /* 1. Everything shown, colour by time, no MIP (checked on its own). */
  elfm_viewer_show(v, 1, 1, 0);
  render(v);
  CHECK_OK(elfm_png_write_rgb(tpath("full.png"), W, H, img, &err), &err);
  int seen = 0, right_colour = 0, n = 0;
  double hue_early = 0, hue_late = 0;
  int n_early = 0, n_late = 0;
  for (int i = 0; i <= 100; i += 5, n++) {
    double c, r;
    project(v, a_pos, i, &c, &r);
    const uint8_t *p = coloured_near(c, r, 2);
    if (!p) continue;
    seen++;
    float e[3];
    elfm_colormap_rgb(i / 100.0, e);
    double dist = fabs(p[0] - 255.0 * e[0]) + fabs(p[1] - 255.0 * e[1]) + fabs(p[2] - 255.0 * e[2]);
    right_colour += dist < 90;
    if (i <= 25) { hue_early += hue_of(p); n_early++; }
    if (i >= 75) { hue_late += hue_of(p); n_late++; }
  }
  CHECK_MSG(seen >= n - 1, "track A visible at %d of %d projected points", seen, n);
  CHECK_MSG(right_colour >= n - 2, "track A in its time's colour at %d of %d points",
            right_colour, n);
  CHECK(n_early > 0 && n_late > 0);
  if (n_early && n_late) {
    hue_early /= n_early;
    hue_late /= n_late;
    CHECK_MSG(hue_early > hue_late + 90, "hue early %.0f vs late %.0f: not blue -> red",
              hue_early, hue_late);
  }
  /* Truth grey, detections white. */
  int grey = 0;
  n = 0;
  for (int i = 0; i <= 100; i += 10, n++) {
    double c, r;
    project(v, truth_pos, i, &c, &r);
    grey += grey_near(c, r);
  }
  CHECK_MSG(grey >= n - 1, "truth grey at %d of %d points", grey, n);
  int white = 0;
  for (int k = 0; k < 3; k++) {
    double c, r;
    elfm_camera_project(elfm_viewer_camera(v), W, H, det_pos[k], &c, &r);
    white += white_near(c, r);
  }
  CHECK_EQ_INT(white, 3);
  /* The detections of the last 10 frames before the cursor, no older and
   * none to come: the one at 50 ms is white at 50 and 59 ms, not at 49 or
   * 61 ms (and at the end, where all are shown). */
  const int64_t at_us[5] = {49000, 50000, 59000, 61000, INT64_MAX};
  const int want_mid[5] = {0, 1, 1, 0, 1};
  for (int k = 0; k < 5; k++) {
    elfm_viewer_set_cursor(v, at_us[k]);
    render(v);
    double c, r;
    elfm_camera_project(elfm_viewer_camera(v), W, H, det_mid, &c, &r);
    const int found = white_near(c, r);
    CHECK_MSG(found == want_mid[k], "cursor at %" PRId64 " us: the detection of 50 ms %s", at_us[k],
              found ? "drawn" : "not drawn");
  }
  /* Background where nothing projects: points inside the box's picture,
   * at least 10 px from every line and point of the scene. */
  int bg_checked = 0, bg_ok = 0;
  for (int r = H / 4; r < 3 * H / 4; r += 16)
    for (int c = W / 4; c < 3 * W / 4; c += 16) {
      if (dist_to_scene(v, d, c + 0.5, r + 0.5) < 10) continue;
      const uint8_t *p = px(c, r);
      bg_checked++;
      bg_ok += abs(p[0] - 23) <= 3 && abs(p[1] - 23) <= 3 && abs(p[2] - 26) <= 3;
    }
  CHECK_MSG(bg_checked > 50, "only %d background points to check", bg_checked);
  CHECK_EQ_INT(bg_ok, bg_checked);
  /* The colour bar: blue at the bottom, red at the top, hue falling upwards. */
  int x0, y0, x1, y1;
  elfm_overlay_colorbar_rect(W, H, &x0, &y0, &x1, &y1);
  int xc = (x0 + x1) / 2;
  double hb = hue_of(px(xc, y1 - 3)), ht = hue_of(px(xc, y0 + 3)), hm = hue_of(px(xc, (y0 + y1) / 2));
  CHECK_MSG(hb > 200 && hb < 260, "colour bar bottom hue %.0f", hb);
  CHECK_MSG(ht < 30, "colour bar top hue %.0f", ht);
  CHECK_MSG(hm < hb && hm > ht, "colour bar middle hue %.0f", hm);
  int falling = 1;
  double prev = 1e9;
  for (int y = y1 - 3; y >= y0 + 3; y -= 8) {
    double h = hue_of(px(xc, y));
    if (h > prev + 5) falling = 0;
    prev = h;
  }
  CHECK(falling);

  /* 2. Time cursor at 50 ms: A's first half drawn, its second half gone. */
  elfm_viewer_set_cursor(v, 50000);
  render(v);
  int before = 0, after = 0, nb = 0, na = 0;
  for (int i = 0; i <= 100; i += 5) {
    double c, r;
    project(v, a_pos, i, &c, &r);
    if (i <= 40) { nb++; before += coloured_near(c, r, 2) != NULL; }
    if (i >= 60) { na++; after += coloured_near(c, r, 2) != NULL; }
  }
  CHECK_MSG(before == nb, "before the cursor: %d of %d drawn", before, nb);
  CHECK_MSG(after == 0, "after the cursor: %d of %d still drawn", after, na);

  /* 2b. The keys' commands: frame steps, home/end, playback at its speed,
   * colour cycle, layer toggles, camera reset. Frames are 1 ms apart. */
  elfm_viewer_set_cursor(v, INT64_MAX);
  elfm_viewer_command(v, ELFM_CMD_STEP_BACK);
  CHECK_EQ_INT(elfm_viewer_cursor(v), 99000);
  elfm_viewer_command(v, ELFM_CMD_STEP_BACK_10);
  CHECK_EQ_INT(elfm_viewer_cursor(v), 89000);
  elfm_viewer_command(v, ELFM_CMD_STEP_FORWARD);
  CHECK_EQ_INT(elfm_viewer_cursor(v), 90000);
  elfm_viewer_command(v, ELFM_CMD_HOME);
  CHECK_EQ_INT(elfm_viewer_cursor(v), 0);
  elfm_viewer_command(v, ELFM_CMD_STEP_BACK);
  CHECK_EQ_INT(elfm_viewer_cursor(v), 0);
  elfm_viewer_command(v, ELFM_CMD_END);
  CHECK_EQ_INT(elfm_viewer_cursor(v), 100000);
  elfm_viewer_command(v, ELFM_CMD_STEP_FORWARD);
  CHECK_EQ_INT(elfm_viewer_cursor(v), 100000);
  /* Play from the end starts over; 100 ms recording plays in 10 s. */
  elfm_viewer_command(v, ELFM_CMD_PLAY_PAUSE);
  CHECK(elfm_viewer_playing(v));
  CHECK_EQ_INT(elfm_viewer_cursor(v), 0);
  elfm_viewer_advance(v, 1.0);
  CHECK_EQ_INT(elfm_viewer_cursor(v), 10000);
  elfm_viewer_command(v, ELFM_CMD_FASTER);
  elfm_viewer_advance(v, 1.0);
  CHECK_EQ_INT(elfm_viewer_cursor(v), 30000);
  elfm_viewer_command(v, ELFM_CMD_SLOWER);
  elfm_viewer_command(v, ELFM_CMD_PLAY_PAUSE);
  CHECK(!elfm_viewer_playing(v));
  elfm_viewer_advance(v, 1.0);
  CHECK_EQ_INT(elfm_viewer_cursor(v), 30000);
  elfm_viewer_command(v, ELFM_CMD_PLAY_PAUSE);
  elfm_viewer_advance(v, 100.0);
  CHECK_EQ_INT(elfm_viewer_cursor(v), 100000);
  CHECK(!elfm_viewer_playing(v));
  /* The speed keys stop at 1024 x and 1 / 1024 x the default (10 ms of
   * the recording per second): 20 presses of `faster` play 10.24 ms in a
   * millisecond, 30 of `slower` then 10 us in a second. */
  for (int k = 0; k < 20; k++) elfm_viewer_command(v, ELFM_CMD_FASTER);
  elfm_viewer_command(v, ELFM_CMD_HOME);
  elfm_viewer_command(v, ELFM_CMD_PLAY_PAUSE);
  elfm_viewer_advance(v, 0.001);
  CHECK_EQ_INT(elfm_viewer_cursor(v), 10240);
  for (int k = 0; k < 30; k++) elfm_viewer_command(v, ELFM_CMD_SLOWER);
  elfm_viewer_advance(v, 1.0);
  CHECK_EQ_INT(elfm_viewer_cursor(v), 10250);
  elfm_viewer_command(v, ELFM_CMD_END); /* stops playing */
  CHECK(!elfm_viewer_playing(v));
  CHECK_EQ_INT(elfm_viewer_color_mode(v), ELFM_COLOR_TIME);
  elfm_viewer_command(v, ELFM_CMD_CYCLE_COLOR);
  CHECK_EQ_INT(elfm_viewer_color_mode(v), ELFM_COLOR_DEPTH);
  elfm_viewer_command(v, ELFM_CMD_CYCLE_COLOR);
  CHECK_EQ_INT(elfm_viewer_color_mode(v), ELFM_COLOR_TRACK);
  elfm_viewer_command(v, ELFM_CMD_CYCLE_COLOR);
  CHECK_EQ_INT(elfm_viewer_color_mode(v), ELFM_COLOR_SHARED);
  elfm_viewer_command(v, ELFM_CMD_CYCLE_COLOR);
  CHECK_EQ_INT(elfm_viewer_color_mode(v), ELFM_COLOR_TIME);
  /* `t` hides the grey truth line, a second `t` shows it again. */
  int grey_on[2];
  for (int k = 0; k < 2; k++) {
    elfm_viewer_command(v, ELFM_CMD_TOGGLE_TRUTH);
    render(v);
    grey_on[k] = 0;
    for (int i = 10; i <= 90; i += 20) {
      double tc, tr;
      project(v, truth_pos, i, &tc, &tr);
      grey_on[k] |= grey_near(tc, tr);
    }
  }
  CHECK(!grey_on[0]);
  CHECK(grey_on[1]);
  /* `r` brings the camera back after a drag and a zoom. */
  elfm_camera cam0 = *elfm_viewer_camera(v);
  elfm_camera_rotate(elfm_viewer_camera(v), 120, -40);
  elfm_camera_zoom(elfm_viewer_camera(v), 4);
  CHECK(fabs(elfm_viewer_camera(v)->yaw_rad - cam0.yaw_rad) > 0.1);
  elfm_viewer_command(v, ELFM_CMD_RESET_VIEW);
  CHECK_NEAR(elfm_viewer_camera(v)->yaw_rad, cam0.yaw_rad, 1e-12);
  CHECK_NEAR(elfm_viewer_camera(v)->pitch_rad, cam0.pitch_rad, 1e-12);
  CHECK_NEAR(elfm_viewer_camera(v)->half_height_um, cam0.half_height_um, 1e-9);

  /* 3. Colour by depth: B runs from z=-40 to 40, so blue-ish to red-ish. */
  elfm_viewer_set_cursor(v, INT64_MAX);
  elfm_viewer_set_color_mode(v, ELFM_COLOR_DEPTH);
  render(v);
  double c, r;
  project(v, b_pos, 5, &c, &r);
  const uint8_t *pd = coloured_near(c, r, 2);
  project(v, b_pos, 95, &c, &r);
  const uint8_t *pu = coloured_near(c, r, 2);
  CHECK(pd && pu);
  if (pd && pu) CHECK_MSG(hue_of(pd) > hue_of(pu) + 60, "depth hue %.0f (z=-36) vs %.0f (z=36)",
                          hue_of(pd), hue_of(pu));
  /* Along A (constant z) all one colour in depth mode. */
  project(v, a_pos, 10, &c, &r);
  const uint8_t *a1 = coloured_near(c, r, 2);
  project(v, a_pos, 90, &c, &r);
  const uint8_t *a2 = coloured_near(c, r, 2);
  CHECK(a1 && a2);
  if (a1 && a2) CHECK_NEAR(hue_of(a1), hue_of(a2), 12);

  /* 4. Colour by track: each track one colour, the two different. */
  elfm_viewer_set_color_mode(v, ELFM_COLOR_TRACK);
  render(v);
  project(v, a_pos, 10, &c, &r);
  a1 = coloured_near(c, r, 2);
  project(v, a_pos, 90, &c, &r);
  a2 = coloured_near(c, r, 2);
  project(v, b_pos, 50, &c, &r);
  const uint8_t *b1 = coloured_near(c, r, 2);
  CHECK(a1 && a2 && b1);
  if (a1 && a2 && b1) {
    CHECK_NEAR(hue_of(a1), hue_of(a2), 12);
    CHECK_MSG(fabs(hue_of(a1) - hue_of(b1)) > 40, "track hues %.0f and %.0f too close",
              hue_of(a1), hue_of(b1));
  }

  /* 4b. Shared stretches: magenta on A where its detections lay in two
   * gates (40-60 ms), nowhere else; the MIP (magenta too) hidden. (How
   * the coarse levels of detail keep a stretch: test_gui_core.) */
  elfm_viewer_show(v, 1, 1, 0);
  elfm_viewer_set_color_mode(v, ELFM_COLOR_SHARED);
  {
    render(v);
    int mag[4];
    const int at_i[4] = {45, 55, 10, 90};
    for (int k = 0; k < 4; k++) {
      project(v, a_pos, at_i[k], &c, &r);
      mag[k] = any_near(c, r, 2, is_magenta);
    }
    project(v, b_pos, 50, &c, &r);
    const int mag_b = any_near(c, r, 2, is_magenta);
    CHECK_MSG(mag[0] && mag[1], "shared: A at 45 / 55 ms magenta %d / %d", mag[0], mag[1]);
    CHECK_MSG(!mag[2] && !mag[3] && !mag_b, "shared: magenta at A 10 / 90 ms %d / %d, B %d",
              mag[2], mag[3], mag_b);
    /* A's own colour, dimmed, where it is not shared */
    project(v, a_pos, 10, &c, &r);
    CHECK_MSG(any_near(c, r, 2, is_lit), "shared: A at 10 ms not drawn");
  }
  elfm_viewer_show(v, 1, 1, 1);

  /* 5. The MIP plane: magenta over the box floor once the cursor reaches
   * its time (20 ms: at 20 ms exactly), absent 1 us before it and when
   * switched off. */
  elfm_viewer_set_color_mode(v, ELFM_COLOR_TIME);
  int count[3];
  int64_t at[3] = {20000, 19999, 30000};
  int show[3] = {1, 1, 0};
  for (int k = 0; k < 3; k++) {
    elfm_viewer_show(v, 1, 1, show[k]);
    elfm_viewer_set_cursor(v, at[k]);
    render(v);
    count[k] = 0;
    for (size_t i = 0; i < (size_t)W * H; i++)
      count[k] += img[3 * i] > 180 && img[3 * i + 1] < 80 && img[3 * i + 2] > 180;
  }
  CHECK_MSG(count[0] > W * H / 20, "MIP plane: %d magenta pixels", count[0]);
  CHECK_EQ_INT(count[1], 0);
  CHECK_EQ_INT(count[2], 0);

  /* 5a. The scale bar (bottom left, white, 3 px thick) is as long as the
   * length its label says: about a sixth of the picture's width rounded
   * to 1/2/5 x 10^k um, at the camera's px per um. The scene is moved out
   * of the picture (and the MIP hidden) so that only the overlay is drawn
   * there. */
  {
    elfm_camera *cam = elfm_viewer_camera(v);
    const elfm_camera keep = *cam;
    cam->half_height_um = 50;
    cam->target_um[0] = cam->target_um[1] = 1e6;
    elfm_viewer_show(v, 0, 0, 0);
    render(v);
    const double px_per_um = H / (2.0 * 50);
    const double want_px = elfm_nice_step(W / px_per_um / 6.0, 1) * px_per_um;
    int longest = 0;
    for (int r = H - 40; r < H; r++) {
      int run = 0;
      for (int c = 0; c < W / 2; c++) {
        const uint8_t *p = img + 3 * ((size_t)r * W + (size_t)c);
        run = p[0] > 240 && p[1] > 240 && p[2] > 240 ? run + 1 : 0;
        if (run > longest) longest = run;
      }
    }
    CHECK_MSG(fabs(longest - want_px) <= 2, "scale bar %d px long, its label's length is %.1f px",
              longest, want_px);
    *cam = keep;
    elfm_viewer_show(v, 1, 1, 1);
  }

  elfm_viewer_free(v);
  v = NULL;
  elfm_view_data_free(d);
  d = NULL;

  /* 5b. Without MIP pictures, saved volumes (EXR) are projected: a volume
   * lit only in its last plane (z_max) gives the colour map's deep end. */
  mkdir(tpath("run2"), 0755);
  mkdir(tpath("run2/volumes"), 0755);
  char cmd0[1200];
  snprintf(cmd0, sizeof cmd0, "cp '%s' '%s'", tpath("tracks.csv"), tpath("run2/tracks.csv"));
  CHECK(system(cmd0) == 0);
  elfm_volume *vol = elfm_volume_create(16, 16, 5, 1.0, -40, 20, &err);
  CHECK(vol != NULL);
  if (vol) {
    for (int i = 0; i < 16 * 16; i++) vol->data[4 * 16 * 16 + i] = 2.0f;
    vol->t_us = 20000;
    CHECK_OK(elfm_volume_write_exr(vol, tpath("run2/volumes/vol_t000020000.exr"), &err), &err);
    elfm_volume_free(vol);
  }
  CHECK_OK(elfm_view_data_load(tpath("run2"), NULL, &d, &err), &err);
  if (d) {
    CHECK_EQ_INT(d->n_mips, 1);
    CHECK_OK(elfm_viewer_create(&o, d, &v, &err), &err);
  }
  if (v) {
    elfm_viewer_set_cursor(v, 30000);
    render(v);
    float e[3];
    elfm_colormap_rgb(1.0, e);
    int deep = 0;
    for (size_t i = 0; i < (size_t)W * H; i++)
      deep += fabs(img[3 * i] - 255.0 * e[0]) + fabs(img[3 * i + 1] - 255.0 * e[1]) +
                  fabs(img[3 * i + 2] - 255.0 * e[2]) < 40;
    CHECK_MSG(deep > W * H / 20, "volume MIP plane: %d pixels of the deep colour", deep);
  }
  if (!v) {
    elfm_view_data_free(d);
    return check_report();
  }

  /* 6. Another size through the same viewer (framebuffer rebuilt). */
  uint8_t *big = malloc(1000 * 700 * 3);
  CHECK_OK(elfm_viewer_render_rgb(v, 1000, 700, big, &err), &err);
  int lit_big = 0;
  for (size_t i = 0; i < 1000 * 700; i++) lit_big += saturation(big + 3 * i) > 80;
  CHECK(lit_big > 500);
  free(big);
  uint8_t tiny[3];
  CHECK_EQ_INT(elfm_viewer_render_rgb(v, 0, 5, tiny, &err), ELFM_ERR_INVALID);

  double mean = 0, worst = 0, cpu = 0;
  CHECK_OK(elfm_viewer_bench(v, 3, 320, 240, 1, &mean, &worst, &cpu, &err), &err);
  CHECK(mean > 0 && worst >= mean && cpu > 0);
  elfm_viewer_free(v);
  elfm_view_data_free(d);

  /* 7. Level of detail: 200 smooth tracks of 1000 points (1 kHz wiggles
   * that never cross themselves) drawn with coarse levels look like the
   * full-detail picture (< 3 % of the lit pixels differ visibly) while far
   * fewer vertices are drawn. */
  elfm_view_data *syn = calloc(1, sizeof *syn);
  if (syn) {
    size_t nt = 200, np = 1000;
    elfm_view_series *se = &syn->tracks;
    se->first = malloc((nt + 1) * sizeof *se->first);
    se->id = malloc(nt * sizeof *se->id);
    se->xyz_um = malloc(3 * nt * np * sizeof *se->xyz_um);
    se->t_us = malloc(nt * np * sizeof *se->t_us);
    for (size_t k = 0; k < nt; k++) {
      se->first[k] = k * np;
      se->id[k] = (int64_t)k;
      double x0 = -60 + (double)(k % 20) * 3, y0 = -60 + (double)(k / 20) * 12;
      for (size_t i = 0; i < np; i++) {
        double u = (double)i / np;
        float *p = se->xyz_um + 3 * (k * np + i);
        p[0] = (float)(x0 + 60 * u);
        p[1] = (float)(y0 + 3 * sin(2 * M_PI * 4 * u + k));
        p[2] = (float)(-80 + (double)k * 0.8 + 20 * u);
        se->t_us[k * np + i] = (int64_t)(i * 1000);
      }
    }
    se->first[nt] = nt * np;
    se->n_lines = nt;
    se->n_points = nt * np;
    syn->t_min_us = 0;
    syn->t_max_us = (int64_t)(np - 1) * 1000;
    syn->frame_dt_us = 1000;
    for (int a = 0; a < 3; a++) {
      syn->box_min_um[a] = -100;
      syn->box_max_um[a] = 100;
    }
  }
  static uint8_t full[W * H * 3];
  size_t drawn[2] = {0, 0};
  for (int pass = 0; syn && pass < 2; pass++) {
    o.full_detail = pass;
    v = NULL;
    CHECK_OK(elfm_viewer_create(&o, syn, &v, &err), &err);
    if (!v) break;
    CHECK_OK(elfm_viewer_render_rgb(v, W, H, pass ? full : img, &err), &err);
    drawn[pass] = elfm_viewer_drawn_vertices(v);
    elfm_viewer_free(v);
  }
  o.full_detail = 0;
  CHECK_EQ_INT(drawn[1], 200 * 1000);
  CHECK_MSG(drawn[0] * 4 < drawn[1], "level of detail drew %zu of %zu vertices", drawn[0],
            drawn[1]);
  long lit = 0, differ = 0;
  for (size_t i = 0; i < (size_t)W * H; i++) {
    lit += saturation(full + 3 * i) > 80;
    int m = 0;
    for (int k = 0; k < 3; k++) m = abs(full[3 * i + k] - img[3 * i + k]) > m ? abs(full[3 * i + k] - img[3 * i + k]) : m;
    differ += m > 60;
  }
  fprintf(stderr, "note: level of detail drew %zu of %zu vertices; %ld of %ld lit pixels differ\n",
          drawn[0], drawn[1], differ, lit);
  CHECK_MSG(lit > 5000, "full-detail picture has only %ld lit pixels", lit);
  CHECK_MSG(differ * 100 < 3 * lit, "level of detail changed %ld of %ld lit pixels", differ, lit);
  elfm_view_data_free(syn);

  /* 8. The CLI: --screenshot writes a PNG of the asked size with tracks;
   * --color's four maps give four pictures, and --at-us another moment
   * another picture (each once mapped to another mode, or the cursor left
   * at its start, by a fault that the library's checks above did not see). */
  const char *bin = ELFM_BINARY_DIR "/eventlfm";
  if (access(bin, X_OK) == 0) {
    static const char *const color[5] = {"depth", "time", "track", "shared", "depth"};
    static const int at_ms[5] = {60, 60, 60, 60, 30};
    uint8_t *shot[5] = {NULL};
    for (int k = 0; k < 5; k++) {
      char cmd[2048], png[64];
      snprintf(png, sizeof png, "cli%d.png", k);
      snprintf(cmd, sizeof cmd,
               "ASAN_OPTIONS=detect_leaks=0 %s view %s --truth %s --screenshot %s --size 400x300 "
               "--at-us %d000 --color %s 2>%s",
               bin, dir, tpath("truth.csv"), tpath(png), at_ms[k], color[k], tpath("cli.err"));
      int rc = system(cmd);
      CHECK_MSG(WIFEXITED(rc) && WEXITSTATUS(rc) == 0, "view --color %s --at-us %d000", color[k], at_ms[k]);
      int w = 0, h = 0;
      CHECK_OK(elfm_png_read_rgba(tpath(png), &w, &h, &shot[k], &err), &err);
      CHECK_EQ_INT(w, 400);
      CHECK_EQ_INT(h, 300);
      if (w != 400 || h != 300) {
        free(shot[k]);
        shot[k] = NULL;
      }
    }
    int sat = 0;
    for (int i = 0; shot[0] && i < 400 * 300; i++) sat += saturation(shot[0] + 4 * i) > 80;
    CHECK_MSG(sat > 200, "CLI screenshot has %d coloured pixels", sat);
    for (int a = 0; a < 5; a++)
      for (int b = a + 1; b < 5; b++) {
        if (!shot[a] || !shot[b] || (b == 4 && a != 0)) continue; /* the moment: depth only */
        int differ = 0;
        for (int i = 0; i < 400 * 300 * 4; i++) differ += shot[a][i] != shot[b][i];
        CHECK_MSG(differ > 100, "view --color %s --at-us %d000 and --color %s --at-us %d000: %d bytes differ",
                  color[a], at_ms[a], color[b], at_ms[b], differ);
      }
    for (int k = 0; k < 5; k++) free(shot[k]);
  } else {
    fprintf(stderr, "note: %s not built, CLI screenshot check left out\n", bin);
  }

  char cmd[600];
  if (check_failed_ == 0) {
    snprintf(cmd, sizeof cmd, "rm -rf '%s'", dir);
    if (system(cmd) != 0) fprintf(stderr, "note: could not remove %s\n", dir);
  } else {
    fprintf(stderr, "pictures kept in %s\n", dir);
  }
  return check_report();
}
