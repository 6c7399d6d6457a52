/* series_lod.c — polylines on the GPU: levels of detail, a handful of
 * draw calls, nothing uploaded per frame.
 *
 * Two costs were measured with Mesa llvmpipe (docs/viewer.md):
 *  - per draw call: one line strip per track (glMultiDrawArrays) cost about
 *    as much per track as 1,000 points did, so 1,000 tracks are drawn with
 *    primitive restart: one index list, a restart index between tracks, one
 *    glDrawElements per level of detail in use (at most GUI_LOD_LEVELS).
 *  - per vertex: at 1 kHz a track moves well under a pixel per frame at the
 *    default zoom. Every polyline is stored at 8 levels (every point, every
 *    2nd, ... 128th, always ending on its last point). Per frame each track
 *    uses the coarsest level whose chords stay under GUI_LOD_MAX_SEG_PX on
 *    screen, judged from its mean 3D segment length (projection only
 *    shortens, so a steady track is never undersampled).
 * Tracks are ordered by mean segment length, longest first, in every
 * level's index list; the level a track needs falls with that length, so
 * the tracks drawn at one level are one contiguous run of the list: one
 * draw call per level.
 * The time cursor stays a uniform: the fragment shader ends every segment
 * exactly at it.
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
    free(g->lvl_offset[l]);
    g->lvl_offset[l] = NULL;
  }
  free(g->seg_um);
  g->seg_um = NULL;
}

typedef struct seg_order {
  double seg_um;
  size_t line;
} seg_order;

static int seg_order_cmp(const void *a, const void *b)
{
  const seg_order *x = a, *y = b;
  if (x->seg_um != y->seg_um) return x->seg_um > y->seg_um ? -1 : 1;
  return x->line < y->line ? -1 : x->line > y->line;
}

static double mean_segment_um(const elfm_view_series *s, size_t k)
{
  size_t a = s->first[k], n = s->first[k + 1] - a;
  if (n < 2) return 0.0;
  double len = 0;
  for (size_t i = a + 1; i < a + n; i++) {
    const float *p0 = s->xyz_um + 3 * (i - 1), *p1 = s->xyz_um + 3 * i;
    double dx = (double)p1[0] - p0[0], dy = (double)p1[1] - p0[1], dz = (double)p1[2] - p0[2];
    len += sqrt(dx * dx + dy * dy + dz * dz);
  }
  return len / (double)(n - 1);
}

elfm_status gui_series_build(const elfm_view_series *s, int64_t t0_us, gui_series_gl *g,
                             float **vertices, uint32_t **indices, elfm_error *err)
{
  *vertices = NULL;
  *indices = NULL;
  size_t nv = 0, ni = 0;
  for (int l = 0; l < GUI_LOD_LEVELS; l++)
    for (size_t k = 0; k < s->n_lines; k++) {
      size_t c = level_count(s->first[k + 1] - s->first[k], l);
      nv += c;
      ni += c + 1; /* + the restart index */
    }
  /* Indices are 32-bit with 0xFFFFFFFF reserved for restarts. */
  if (nv >= (size_t)UINT32_MAX || ni > (size_t)INT32_MAX)
    return elfm_error_set(err, ELFM_ERR_RANGE, NULL, -1, "too many points to draw (%zu)",
                          s->n_points);
  size_t nl = s->n_lines;
  seg_order *order = malloc((nl ? nl : 1) * sizeof *order);
  g->seg_um = malloc((nl ? nl : 1) * sizeof *g->seg_um);
  int ok = order && g->seg_um;
  for (int l = 0; l < GUI_LOD_LEVELS; l++) {
    g->lvl_offset[l] = malloc((nl + 1) * sizeof *g->lvl_offset[l]);
    ok &= g->lvl_offset[l] != NULL;
  }
  float *vb = malloc((nv ? nv : 1) * GUI_VERTEX_FLOATS * sizeof *vb);
  uint32_t *ib = malloc((ni ? ni : 1) * sizeof *ib);
  if (!ok || !vb || !ib) {
    free(order);
    free(vb);
    free(ib);
    gui_series_arrays_free(g);
    return elfm_error_set(err, ELFM_ERR_NOMEM, NULL, -1, "out of memory for vertices");
  }
  for (size_t k = 0; k < nl; k++) {
    order[k].seg_um = mean_segment_um(s, k);
    order[k].line = k;
  }
  qsort(order, nl, sizeof *order, seg_order_cmp);
  for (size_t r = 0; r < nl; r++) g->seg_um[r] = (float)order[r].seg_um;

  size_t q = 0, qi = 0;
  for (int l = 0; l < GUI_LOD_LEVELS; l++) {
    size_t stride = (size_t)1 << l;
    g->lvl_base[l] = qi;
    for (size_t r = 0; r < nl; r++) {
      size_t k = order[r].line, a = s->first[k], n = s->first[k + 1] - a;
      /* Golden-ratio steps around the colour map: neighbouring ids get far
       * apart colours in "by track" mode. */
      float key = (float)fmod((double)k * 0.6180339887498949, 1.0);
      size_t c = level_count(n, l);
      g->lvl_offset[l][r] = (GLsizei)(qi - g->lvl_base[l]);
      for (size_t j = 0; j < c; j++) {
        size_t i = a + (j + 1 == c ? n - 1 : j * stride);
        float *v = vb + q * GUI_VERTEX_FLOATS;
        v[0] = s->xyz_um[3 * i];
        v[1] = s->xyz_um[3 * i + 1];
        v[2] = s->xyz_um[3 * i + 2];
        v[3] = (float)((double)(s->t_us[i] - t0_us) / 1000.0);
        v[4] = key;
        ib[qi++] = (uint32_t)q++;
      }
      ib[qi++] = GUI_RESTART_INDEX;
    }
    g->lvl_offset[l][nl] = (GLsizei)(qi - g->lvl_base[l]);
  }
  free(order);
  g->n_lines = (GLsizei)nl;
  g->n_vertices = nv;
  g->n_indices = ni;
  *vertices = vb;
  *indices = ib;
  return ELFM_OK;
}

static int lod_level(float seg_um, double px_per_um)
{
  double seg_px = seg_um * px_per_um;
  if (!(seg_px > 0)) return GUI_LOD_LEVELS - 1; /* a track standing still */
  double f = floor(log2(GUI_LOD_MAX_SEG_PX / seg_px));
  return f < 0 ? 0 : f > GUI_LOD_LEVELS - 1 ? GUI_LOD_LEVELS - 1 : (int)f;
}

void gui_series_draw(const gui_series_gl *g, double px_per_um, int full_detail)
{
  if (!g->n_lines) return;
  glBindVertexArray(g->vao);
  glEnable(GL_PRIMITIVE_RESTART);
  glPrimitiveRestartIndex(GUI_RESTART_INDEX);
  GLsizei r = 0;
  while (r < g->n_lines) {
    /* The run of tracks (in falling segment length) that use level l. */
    int l = full_detail ? 0 : lod_level(g->seg_um[r], px_per_um);
    GLsizei e = full_detail ? g->n_lines : r + 1;
    while (e < g->n_lines && lod_level(g->seg_um[e], px_per_um) == l) e++;
    size_t first = g->lvl_base[l] + (size_t)g->lvl_offset[l][r];
    GLsizei count = g->lvl_offset[l][e] - g->lvl_offset[l][r];
    glDrawElements(GL_LINE_STRIP, count, GL_UNSIGNED_INT,
                   (const void *)(first * sizeof(uint32_t)));
    r = e;
  }
  glDisable(GL_PRIMITIVE_RESTART);
}
