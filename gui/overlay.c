/* overlay.c — the 2D layer over the 3D scene: box tick labels, colour bar
 * with its labels, scale bar, time and mode read-out.
 *
 * Built each frame into the viewer's preallocated vertex array (capacity
 * GUI_OVERLAY_CAP, extra quads are dropped rather than allocated): a few
 * thousand vertices against the million of the tracks, which stay put.
 * Text is the 5x7 font, one small square per lit dot.
 */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "gl_internal.h"

/* Pixels per layout unit: 1 up to 1100-pixel-high pictures, 2 above. */
static int ov_unit(int height) { return height > 1100 ? 2 : 1; }

void elfm_overlay_colorbar_rect(int width, int height, int *x0, int *y0, int *x1, int *y1)
{
  int u = ov_unit(height);
  /* 120 units from the right edge leave room for labels like "-12345.6". */
  *x0 = width - 120 * u;
  *x1 = *x0 + 16 * u;
  *y0 = 60 * u;
  *y1 = height - 70 * u;
  if (*y1 < *y0 + 10) *y1 = *y0 + 10;
}

static void ov_vertex(elfm_viewer *v, double x, double y, const float c[4])
{
  float *q = v->ov + v->ov_n * GUI_OVERLAY_FLOATS;
  q[0] = (float)x;
  q[1] = (float)y;
  memcpy(q + 2, c, 4 * sizeof *q);
  v->ov_n++;
}

/* Quad from (x0,y0) to (x1,y1), colour ct on top and cb at the bottom. */
static void ov_quad2(elfm_viewer *v, double x0, double y0, double x1, double y1,
                     const float ct[4], const float cb[4])
{
  if (v->ov_n + 6 > GUI_OVERLAY_CAP) return;
  ov_vertex(v, x0, y0, ct);
  ov_vertex(v, x1, y0, ct);
  ov_vertex(v, x1, y1, cb);
  ov_vertex(v, x0, y0, ct);
  ov_vertex(v, x1, y1, cb);
  ov_vertex(v, x0, y1, cb);
}

static void ov_quad(elfm_viewer *v, double x0, double y0, double x1, double y1, const float c[4])
{
  ov_quad2(v, x0, y0, x1, y1, c, c);
}

/* Text with its top-left corner at (x, y); each font dot is s x s pixels,
 * characters advance 6 dots. */
static void ov_text(elfm_viewer *v, double x, double y, int s, const float c[4], const char *str)
{
  for (const char *p = str; *p; p++, x += 6 * s) {
    if (*p == ' ') continue;
    uint8_t rows[7];
    elfm_font_glyph(*p, rows);
    for (int r = 0; r < 7; r++)
      for (int col = 0; col < 5; col++)
        if (rows[r] & (0x10 >> col))
          ov_quad(v, x + col * s, y + r * s, x + (col + 1) * s, y + (r + 1) * s, c);
  }
}

static double ov_text_width(const char *str, int s)
{
  size_t n = strlen(str);
  return n ? (double)(6 * n - 1) * s : 0.0;
}

static const float col_text[4] = {0.85f, 0.86f, 0.88f, 1.0f};
static const float col_dim[4] = {0.60f, 0.62f, 0.66f, 1.0f};
static const float col_white[4] = {1.0f, 1.0f, 1.0f, 1.0f};

static void colorbar(elfm_viewer *v, int width, int height, int u, int s)
{
  const elfm_view_data *d = v->data;
  int x0, y0, x1, y1;
  elfm_overlay_colorbar_rect(width, height, &x0, &y0, &x1, &y1);
  /* 64 bands: finer than the eye separates the turbo map at this size.
   * Shared mode: the upper third magenta (the shader's colour), the rest
   * the map at the shader's 40 % */
  const int bands = 64, shared = v->mode == ELFM_COLOR_SHARED;
  const double y_split = y0 + (y1 - y0) / 3.0;
  for (int b = 0; b < bands; b++) {
    double s_top = 1.0 - (double)b / bands, s_bot = 1.0 - (double)(b + 1) / bands;
    float ct[4] = {0, 0, 0, 1}, cb[4] = {0, 0, 0, 1};
    elfm_colormap_rgb(s_top, ct);
    elfm_colormap_rgb(s_bot, cb);
    if (shared)
      for (int k = 0; k < 3; k++) {
        ct[k] *= (float)GUI_SHARED_DIM;
        cb[k] *= (float)GUI_SHARED_DIM;
      }
    double ya = y0 + (double)(y1 - y0) * b / bands, yb = y0 + (double)(y1 - y0) * (b + 1) / bands;
    ov_quad2(v, x0, ya, x1, yb, ct, cb);
  }
  if (shared) {
    static const float col_shared[4] = {GUI_SHARED_RGB, 1.0};
    ov_quad(v, x0, y0, x1, y_split, col_shared);
    ov_text(v, x1 + 7 * u, y0 + (y_split - y0) / 2 - 3.5 * s, s, col_text, "2+");
    ov_text(v, x1 + 7 * u, (y_split + y1) / 2 - 3.5 * s, s, col_text, "1");
  }
  const char *title = v->mode == ELFM_COLOR_TIME    ? "T (MS)"
                      : v->mode == ELFM_COLOR_DEPTH ? "Z (UM)"
                      : shared                      ? "CLAIMS"
                                                    : "BY TRACK";
  ov_text(v, x0, y0 - 14 * u - 7 * s, s, col_text, title);
  if (v->mode == ELFM_COLOR_TRACK || shared) return;
  double lo = v->mode == ELFM_COLOR_TIME ? d->t_min_us / 1000.0 : d->box_min_um[2];
  double hi = v->mode == ELFM_COLOR_TIME ? d->t_max_us / 1000.0 : d->box_max_um[2];
  for (int k = 0; k <= 4; k++) {
    double f = k / 4.0; /* 0 at the top (hi) */
    double val = hi + (lo - hi) * f;
    double y = y0 + (y1 - y0) * f;
    char txt[32];
    snprintf(txt, sizeof txt, v->mode == ELFM_COLOR_TIME ? "%.1f" : "%.0f", val);
    ov_quad(v, x1, y - 0.5 * u, x1 + 4 * u, y + 0.5 * u + (u > 1), col_text);
    ov_text(v, x1 + 7 * u, y - 3.5 * s, s, col_text, txt);
  }
  if (v->mode == ELFM_COLOR_TIME && v->cursor_us < d->t_max_us && d->t_max_us > d->t_min_us) {
    double f = (double)(d->t_max_us - v->cursor_us) / (double)(d->t_max_us - d->t_min_us);
    if (f > 1) f = 1;
    double y = y0 + (y1 - y0) * f;
    ov_quad(v, x0 - 6 * u, y - 1 * u, x1 + 2 * u, y + 1 * u, col_white);
  }
}

static void scalebar(elfm_viewer *v, int width, int height, int u, int s)
{
  double px_per_um = height / (2.0 * v->cam.half_height_um);
  double width_um = width / px_per_um;
  /* About a sixth of the picture, rounded to 1/2/5 x 10^k um. */
  double len_um = elfm_nice_step(width_um / 6.0, 1);
  double len_px = len_um * px_per_um;
  double x0 = 20 * u, y = height - 24 * u;
  ov_quad(v, x0, y, x0 + len_px, y + 3 * u, col_white);
  ov_quad(v, x0, y - 4 * u, x0 + u, y + 3 * u, col_white);
  ov_quad(v, x0 + len_px - u, y - 4 * u, x0 + len_px, y + 3 * u, col_white);
  char txt[32];
  snprintf(txt, sizeof txt, "%g UM", len_um);
  ov_text(v, x0 + 0.5 * (len_px - ov_text_width(txt, s)), y - 6 * u - 7 * s, s, col_text, txt);
}

/* A line of th pixels between two picture points, as a thin quad. */
static void ov_line(elfm_viewer *v, double x0, double y0, double x1, double y1, double th,
                    const float c[4])
{
  double dx = x1 - x0, dy = y1 - y0, len = sqrt(dx * dx + dy * dy);
  if (len <= 0 || v->ov_n + 6 > GUI_OVERLAY_CAP) return;
  double nx = -dy / len * 0.5 * th, ny = dx / len * 0.5 * th;
  ov_vertex(v, x0 + nx, y0 + ny, c);
  ov_vertex(v, x1 + nx, y1 + ny, c);
  ov_vertex(v, x1 - nx, y1 - ny, c);
  ov_vertex(v, x0 + nx, y0 + ny, c);
  ov_vertex(v, x1 - nx, y1 - ny, c);
  ov_vertex(v, x0 - nx, y0 - ny, c);
}

static void ov_text_centred(elfm_viewer *v, double x, double y, int s, const float c[4],
                            const char *str)
{
  ov_text(v, x - 0.5 * ov_text_width(str, s), y - 3.5 * s, s, c, str);
}

/* um ticks and labels on one outline edge per axis. Of the four box edges
 * parallel to an axis, the one whose middle projects furthest from the
 * box's centre is on the outline, so its labels fall outside the box and
 * do not cross the tracks; ties go to the lower one on the picture. */
static void box_ticks(elfm_viewer *v, int width, int height, int u, int s)
{
  const double *lo = v->data->box_min_um, *hi = v->data->box_max_um;
  double ctr[3], ext = 0, cc, cr;
  for (int a = 0; a < 3; a++) {
    ctr[a] = 0.5 * (lo[a] + hi[a]);
    ext = fmax(ext, hi[a] - lo[a]);
  }
  elfm_camera_project(&v->cam, width, height, ctr, &cc, &cr);
  static const char *const axis_name[3] = {"X UM", "Y UM", "Z UM"};
  for (int a = 0; a < 3; a++) {
    int b = (a + 1) % 3, c = (a + 2) % 3;
    double best = -1, mid[3] = {0, 0, 0};
    for (int k = 0; k < 4; k++) {
      double m[3], mc, mr;
      m[a] = ctr[a];
      m[b] = (k & 1) ? hi[b] : lo[b];
      m[c] = (k & 2) ? hi[c] : lo[c];
      elfm_camera_project(&v->cam, width, height, m, &mc, &mr);
      double score = hypot(mc - cc, mr - cr) + 1e-3 * mr;
      if (score > best) {
        best = score;
        memcpy(mid, m, sizeof mid);
      }
    }
    /* Outward: from the box's axis through the edge, 2.5 % of the longest
     * side long. */
    double o[3] = {0, 0, 0}, on = 0;
    o[b] = mid[b] - ctr[b];
    o[c] = mid[c] - ctr[c];
    on = sqrt(o[b] * o[b] + o[c] * o[c]);
    if (on > 0) {
      o[b] *= 0.025 * ext / on;
      o[c] *= 0.025 * ext / on;
    }
    double step = elfm_nice_step(hi[a] - lo[a], 5);
    int count = 0;
    for (double t = ceil(lo[a] / step - 1e-9) * step; t <= hi[a] + 1e-9 * step && count < 16;
         t += step, count++) {
      double p[3] = {mid[0], mid[1], mid[2]}, q[3], l[3];
      p[a] = t;
      for (int i = 0; i < 3; i++) {
        q[i] = p[i] + o[i];
        l[i] = p[i] + 3.2 * o[i];
      }
      double pc, pr, qc, qr, lc, lr;
      elfm_camera_project(&v->cam, width, height, p, &pc, &pr);
      elfm_camera_project(&v->cam, width, height, q, &qc, &qr);
      elfm_camera_project(&v->cam, width, height, l, &lc, &lr);
      ov_line(v, pc, pr, qc, qr, u, col_dim);
      char txt[24];
      snprintf(txt, sizeof txt, "%g", fabs(t) < 1e-9 * step ? 0.0 : t);
      ov_text_centred(v, lc, lr, s, col_dim, txt);
    }
    double n3[3], nc, nr;
    for (int i = 0; i < 3; i++) n3[i] = mid[i] + 7.0 * o[i];
    n3[a] = ctr[a] + 0.5 * step; /* between two tick labels */
    elfm_camera_project(&v->cam, width, height, n3, &nc, &nr);
    ov_text_centred(v, nc, nr, s, col_text, axis_name[a]);
  }
}

static void hud(elfm_viewer *v, int height, int u, int s)
{
  const elfm_view_data *d = v->data;
  char txt[160];
  double x = 20 * u, y = 16 * u;
  if (v->cursor_us >= d->t_max_us)
    snprintf(txt, sizeof txt, "T = %.3f MS (END)", d->t_max_us / 1000.0);
  else
    snprintf(txt, sizeof txt, "T = %.3f MS%s", v->cursor_us / 1000.0,
             v->playing ? "  PLAYING" : "  PAUSED");
  ov_text(v, x, y, s, col_text, txt);
  snprintf(txt, sizeof txt, "%zu TRACKS  %zu POINTS", d->tracks.n_lines, d->tracks.n_points);
  ov_text(v, x, y + 11 * s, s, col_dim, txt);
  snprintf(txt, sizeof txt, "%s%s", d->truth.n_lines && v->opt.show_truth ? "TRUTH: GREY  " : "",
           d->n_detections && v->opt.show_detections ? "DETECTIONS: WHITE" : "");
  ov_text(v, x, y + 22 * s, s, col_dim, txt);
  if (v->mode == ELFM_COLOR_SHARED && !d->tracks.shared)
    ov_text(v, x, y + 55 * s, s, col_text, "NO CLAIMS COLUMN: NOTHING MARKED");
  if (v->opt.visible && v->show_help) {
    ov_text(v, x, y + 33 * s, s, col_dim,
            "DRAG ROTATE  RIGHT-DRAG PAN  SCROLL ZOOM  R RESET  C COLOUR");
    ov_text(v, x, y + 44 * s, s, col_dim,
            "SPACE PLAY  ARROWS STEP  +/- SPEED  T D M LAYERS  H HELP  Q QUIT");
  }
  if (v->status_line[0])
    ov_text(v, 20 * u + 200 * u, height - 24 * u - 7 * s, s, col_text, v->status_line);
}

void gui_overlay_build(elfm_viewer *v, int width, int height)
{
  int u = ov_unit(height), s = 2 * u;
  v->ov_n = 0;
  box_ticks(v, width, height, u, s);
  colorbar(v, width, height, u, s);
  scalebar(v, width, height, u, s);
  hud(v, height, u, s);
}
