/* series_lod.c — polylines on the GPU with levels of detail and a cut at
 * the time cursor, so a frame draws only what can be seen.
 *
 * 1,000 tracks of 1,000 points at 1 kHz move well under a pixel per frame
 * at the default zoom: most of a million segments would fall inside one
 * pixel each. Every polyline is uploaded at 8 levels (every point, every
 * 2nd, 4th, ... 128th, always ending on the last point), in one buffer at
 * creation. Each frame picks, per polyline, the coarsest level whose chords
 * stay under GUI_LOD_MAX_SEG_PX on screen (from the polyline's mean 3D
 * segment length: projection only shortens, so this never undersamples a
 * steady track) and, when the cursor is inside the recording, draws the
 * points up to it plus the one segment that crosses it (the fragment shader
 * ends that segment exactly at the cursor). Nothing is uploaded per frame.
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

void gui_series_arrays_free(gui_series_gl *g)
{
  for (int l = 0; l < GUI_LOD_LEVELS; l++) {
    free(g->lvl_first[l]);
    free(g->lvl_count[l]);
    g->lvl_first[l] = NULL;
    g->lvl_count[l] = NULL;
  }
  free(g->t_ms);
  free(g->seg_um);
  free(g->draw_first);
  free(g->draw_count);
  g->t_ms = g->seg_um = NULL;
  g->draw_first = NULL;
  g->draw_count = NULL;
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
    ok &= g->lvl_first[l] && g->lvl_count[l];
  }
  g->t_ms = malloc((total ? total : 1) * sizeof *g->t_ms);
  g->seg_um = malloc(nl * sizeof *g->seg_um);
  g->draw_first = malloc(nl * sizeof *g->draw_first);
  g->draw_count = malloc(nl * sizeof *g->draw_count);
  float *buf = malloc((total ? total : 1) * GUI_VERTEX_FLOATS * sizeof *buf);
  if (!ok || !g->t_ms || !g->seg_um || !g->draw_first || !g->draw_count || !buf) {
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
      for (size_t j = 0; j < c; j++) {
        size_t i = a + (j + 1 == c ? n - 1 : j * stride);
        float *v = buf + q * GUI_VERTEX_FLOATS;
        v[0] = s->xyz_um[3 * i];
        v[1] = s->xyz_um[3 * i + 1];
        v[2] = s->xyz_um[3 * i + 2];
        v[3] = (float)((double)(s->t_us[i] - t0_us) / 1000.0);
        v[4] = key;
        g->t_ms[q] = v[3];
        q++;
      }
      if (l == 0) {
        double len = 0;
        for (size_t i = a + 1; i < a + n; i++) {
          const float *p0 = s->xyz_um + 3 * (i - 1), *p1 = s->xyz_um + 3 * i;
          len += sqrt((double)(p1[0] - p0[0]) * (p1[0] - p0[0]) +
                      (double)(p1[1] - p0[1]) * (p1[1] - p0[1]) +
                      (double)(p1[2] - p0[2]) * (p1[2] - p0[2]));
        }
        g->seg_um[k] = n > 1 ? (float)(len / (double)(n - 1)) : 0.0f;
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

void gui_series_prepare(gui_series_gl *g, double px_per_um, float cursor_ms, int full_detail)
{
  for (GLsizei k = 0; k < g->n_lines; k++) {
    int l = 0;
    double seg_px = g->seg_um[k] * px_per_um;
    if (seg_px > 0 && !full_detail) {
      double f = floor(log2(GUI_LOD_MAX_SEG_PX / seg_px));
      l = f < 0 ? 0 : f > GUI_LOD_LEVELS - 1 ? GUI_LOD_LEVELS - 1 : (int)f;
    }
    GLint first = g->lvl_first[l][k];
    GLsizei count = g->lvl_count[l][k];
    if (count > 0 && g->t_ms[first + count - 1] > cursor_ms) {
      size_t m = count_upto(g->t_ms + first, (size_t)count, cursor_ms);
      count = m == 0 ? 0 : (GLsizei)(m + 1 < (size_t)count ? m + 1 : (size_t)count);
    }
    g->draw_first[k] = first;
    g->draw_count[k] = count;
  }
}
