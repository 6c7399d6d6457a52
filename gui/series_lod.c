/* series_lod.c — polylines on the GPU with error-bounded levels of detail
 * and a cut at the time cursor, so a frame draws only what can be seen.
 *
 * With Mesa's software renderer the frame time grows with the number of
 * line segments drawn (docs/viewer.md), and 1,000 tracks of 1,000 points at
 * 1 kHz move well under a pixel per frame at the default zoom. Every
 * polyline is uploaded at 8 levels (every point, every 2nd, 4th, ... 128th,
 * always ending on its last point), in one buffer, at creation.
 *
 * For each polyline and level we store its error: the largest distance
 * between an original point and where the coarse polyline is at that
 * point's time (time-interpolated along the chord). It bounds what the eye
 * sees both in shape and in the colour-by-time and the cursor cut, which
 * the shaders interpolate in time along each chord. Each frame picks, per
 * polyline, the coarsest level whose error is under GUI_LOD_MAX_ERR_PX on
 * screen (an orthographic projection never lengthens a distance).
 *
 * In shared mode (ELFM_COLOR_SHARED) a level whose chords would stand for
 * shared and unshared points together is not used: the marked stretch
 * keeps its ends at every zoom. The other modes do not pay for it.
 *
 * When the cursor is inside the recording, a polyline is drawn up to it
 * plus the one segment that crosses it (the fragment shader ends that
 * segment exactly at the cursor). Per frame only the draw lists change.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "gl_internal.h"

static size_t level_count(size_t n, int level)
{
  if (n < 2) return n;
  size_t stride = (size_t)1 << level;
  return (n - 1 + stride - 1) / stride + 1; /* ceil((n-1)/stride) chords */
}

/* Index (within the polyline) of vertex j of a level with c vertices. */
static size_t level_point(size_t j, size_t c, size_t n, size_t stride)
{
  return j + 1 == c ? n - 1 : j * stride;
}

void gui_series_arrays_free(gui_series_gl *g)
{
  for (int l = 0; l < GUI_LOD_LEVELS; l++) {
    free(g->lvl_first[l]);
    free(g->lvl_count[l]);
    free(g->lvl_err_um[l]);
    free(g->lvl_mixed[l]);
    g->lvl_mixed[l] = NULL;
    g->lvl_first[l] = NULL;
    g->lvl_count[l] = NULL;
    g->lvl_err_um[l] = NULL;
  }
  free(g->t_ms);
  free(g->draw_first);
  free(g->draw_count);
  g->t_ms = NULL;
  g->draw_first = NULL;
  g->draw_count = NULL;
}

/* Largest distance (um) between points a..a+n-1 and the level's polyline
 * evaluated at each point's time. */
static double level_error_um(const elfm_view_series *s, size_t a, size_t n, int level)
{
  size_t c = level_count(n, level), stride = (size_t)1 << level;
  double worst = 0;
  for (size_t j = 0; j + 1 < c; j++) {
    size_t i0 = a + level_point(j, c, n, stride), i1 = a + level_point(j + 1, c, n, stride);
    const float *p0 = s->xyz_um + 3 * i0, *p1 = s->xyz_um + 3 * i1;
    double t0 = (double)s->t_us[i0], t1 = (double)s->t_us[i1];
    for (size_t i = i0 + 1; i < i1; i++) {
      double w = t1 > t0 ? ((double)s->t_us[i] - t0) / (t1 - t0) : 0.5;
      double d2 = 0;
      for (int ax = 0; ax < 3; ax++) {
        double q = p0[ax] + w * (p1[ax] - p0[ax]) - s->xyz_um[3 * i + ax];
        d2 += q * q;
      }
      if (d2 > worst) worst = d2;
    }
  }
  return sqrt(worst);
}

/* 1 when a chord of the level stands for points of both kinds (shared and
 * not): the points after its first vertex up to its last. */
static int level_mixes_shared(const elfm_view_series *s, size_t a, size_t n, int level)
{
  size_t c = level_count(n, level), stride = (size_t)1 << level;
  for (size_t j = 0; j + 1 < c; j++) {
    size_t i0 = a + level_point(j, c, n, stride), i1 = a + level_point(j + 1, c, n, stride);
    for (size_t i = i0 + 2; i <= i1; i++)
      if (s->shared[i] != s->shared[i0 + 1]) return 1;
  }
  return 0;
}

elfm_status gui_series_build(const elfm_view_series *s, int64_t t0_us, gui_series_gl *g,
                             float **vertices, elfm_error *err)
{
  *vertices = NULL;
  size_t total = 0;
  for (int l = 0; l < GUI_LOD_LEVELS; l++)
    for (size_t k = 0; k < s->n_lines; k++)
      total += level_count(s->first[k + 1] - s->first[k], l);
  if (total > (size_t)INT32_MAX || s->n_lines > (size_t)INT32_MAX)
    return elfm_error_set(err, ELFM_ERR_RANGE, NULL, -1, "too many points to draw (%zu)",
                          s->n_points);
  size_t nl = s->n_lines ? s->n_lines : 1;
  int ok = 1;
  for (int l = 0; l < GUI_LOD_LEVELS; l++) {
    g->lvl_first[l] = malloc(nl * sizeof *g->lvl_first[l]);
    g->lvl_count[l] = malloc(nl * sizeof *g->lvl_count[l]);
    g->lvl_err_um[l] = malloc(nl * sizeof *g->lvl_err_um[l]);
    g->lvl_mixed[l] = malloc(nl);
    ok &= g->lvl_first[l] && g->lvl_count[l] && g->lvl_err_um[l] && g->lvl_mixed[l];
  }
  g->t_ms = malloc((total ? total : 1) * sizeof *g->t_ms);
  g->draw_first = malloc(nl * sizeof *g->draw_first);
  g->draw_count = malloc(nl * sizeof *g->draw_count);
  float *buf = malloc((total ? total : 1) * GUI_VERTEX_FLOATS * sizeof *buf);
  if (!ok || !g->t_ms || !g->draw_first || !g->draw_count || !buf) {
    free(buf);
    gui_series_arrays_free(g);
    return elfm_error_set(err, ELFM_ERR_NOMEM, NULL, -1, "out of memory for vertices");
  }
  size_t q = 0;
  for (int l = 0; l < GUI_LOD_LEVELS; l++) {
    size_t stride = (size_t)1 << l;
    for (size_t k = 0; k < s->n_lines; k++) {
      size_t a = s->first[k], n = s->first[k + 1] - a;
      /* Golden-ratio steps around the colour map: neighbouring ids get far
       * apart colours in "by track" mode. */
      float key = (float)fmod((double)k * 0.6180339887498949, 1.0);
      g->lvl_first[l][k] = (GLint)q;
      size_t c = level_count(n, l);
      g->lvl_count[l][k] = (GLsizei)c;
      g->lvl_err_um[l][k] = l == 0 ? 0.0f : (float)level_error_um(s, a, n, l);
      /* A chord over shared and unshared points would mark them all: in
       * shared mode such a level is not used for this polyline (a straight
       * track would otherwise be one magenta chord from end to end) */
      g->lvl_mixed[l][k] = l > 0 && s->shared && level_mixes_shared(s, a, n, l);
      size_t prev = a; /* the last vertex's point */
      for (size_t j = 0; j < c; j++) {
        size_t i = a + level_point(j, c, n, stride);
        float *v = buf + q * GUI_VERTEX_FLOATS;
        /* The segment into this vertex stands for the points after the last
         * vertex up to this one: shared if any of them was, so a coarse
         * level still shows a one-point stretch (the shader takes the
         * segment's last vertex, OpenGL's provoking vertex). */
        uint8_t sh = 0;
        if (s->shared)
          for (size_t p = j == 0 ? i : prev + 1; p <= i; p++) sh |= s->shared[p];
        prev = i;
        v[5] = sh;
        v[0] = s->xyz_um[3 * i];
        v[1] = s->xyz_um[3 * i + 1];
        v[2] = s->xyz_um[3 * i + 2];
        v[3] = (float)((double)(s->t_us[i] - t0_us) / 1000.0);
        v[4] = key;
        g->t_ms[q] = v[3];
        q++;
      }
    }
  }
  g->n_lines = (GLsizei)s->n_lines;
  g->n_vertices = total;
  *vertices = buf;
  return ELFM_OK;
}

/* Number of vertices in t[0..n) with t <= cursor (t sorted ascending). */
static size_t count_upto(const float *t, size_t n, float cursor)
{
  size_t lo = 0, hi = n;
  while (lo < hi) {
    size_t mid = lo + (hi - lo) / 2;
    if (t[mid] <= cursor) lo = mid + 1;
    else hi = mid;
  }
  return lo;
}

size_t gui_series_prepare(gui_series_gl *g, double px_per_um, float cursor_ms, int full_detail,
                          int shared_mode)
{
  size_t drawn = 0;
  double max_err_um = GUI_LOD_MAX_ERR_PX / px_per_um;
  for (GLsizei k = 0; k < g->n_lines; k++) {
    int l = 0;
    if (!full_detail)
      for (l = GUI_LOD_LEVELS - 1; l > 0; l--)
        if (g->lvl_err_um[l][k] <= max_err_um && !(shared_mode && g->lvl_mixed[l][k])) break;
    GLint first = g->lvl_first[l][k];
    GLsizei count = g->lvl_count[l][k];
    if (count > 0 && g->t_ms[first + count - 1] > cursor_ms) {
      size_t m = count_upto(g->t_ms + first, (size_t)count, cursor_ms);
      count = m == 0 ? 0 : (GLsizei)(m + 1 < (size_t)count ? m + 1 : (size_t)count);
    }
    g->draw_first[k] = first;
    g->draw_count[k] = count;
    drawn += (size_t)count;
  }
  return drawn;
}
