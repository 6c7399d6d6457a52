/* mip_plane.c — the MIP of the cursor's frame as a textured plane.
 *
 * The recon stage saves one depth-colour-coded MIP PNG per frame; the plane
 * shows the latest one at or before the cursor, under the tracks at the
 * volume's z_min. A PNG is decoded only when the frame changes, into one
 * reused buffer. Where a MIP picture is wider or taller than the volume's
 * x-y size (side panels with x-z and y-z projections), the x-y panel is
 * taken to be its top-left W x H corner (W x H = view_size_px of calib.json).
 */
#include <stdio.h>

#include "gl_internal.h"

/* Index of the last MIP with t_us <= t, or -1. */
static long mip_index_at(const elfm_view_data *d, int64_t t)
{
  long lo = 0, hi = (long)d->n_mips - 1, best = -1;
  while (lo <= hi) {
    long mid = lo + (hi - lo) / 2;
    if (d->mips[mid].t_us <= t) {
      best = mid;
      lo = mid + 1;
    } else {
      hi = mid - 1;
    }
  }
  return best;
}

int gui_mip_update(elfm_viewer *v)
{
  const elfm_view_data *d = v->data;
  if (!d->n_mips) return 0;
  long k = mip_index_at(d, v->cursor_us);
  if (k < 0) return 0;
  if (k == v->mip_loaded) return v->mip_ok;
  v->mip_loaded = k;
  v->mip_ok = 0;
  int w = 0, h = 0;
  elfm_error e;
  elfm_error_clear(&e);
  if (gui_png_read_into(d->mips[k].path, &v->mip_rgba, &v->mip_cap, &w, &h, &e) != ELFM_OK) {
    /* A broken MIP must not stop the viewer: say so on the status line. */
    elfm_error_format(&e, v->status_line, sizeof v->status_line);
    return 0;
  }
  v->status_line[0] = '\0';
  glBindTexture(GL_TEXTURE_2D, v->mip_tex);
  glPixelStorei(GL_UNPACK_ALIGNMENT, 1);
  glTexImage2D(GL_TEXTURE_2D, 0, GL_RGBA8, w, h, 0, GL_RGBA, GL_UNSIGNED_BYTE, v->mip_rgba);
  /* The x-y panel's share of the picture (top-left W x H when larger). */
  double fu = 1.0, fv = 1.0;
  if (d->volume_w_px > 0 && w > d->volume_w_px) fu = (double)d->volume_w_px / w;
  if (d->volume_h_px > 0 && h > d->volume_h_px) fv = (double)d->volume_h_px / h;
  const double *lo = d->box_min_um, *hi = d->box_max_um;
  float z = (float)lo[2];
  float q[6][5] = {
    {(float)lo[0], (float)lo[1], z, 0.0f, 0.0f},
    {(float)hi[0], (float)lo[1], z, (float)fu, 0.0f},
    {(float)hi[0], (float)hi[1], z, (float)fu, (float)fv},
    {(float)lo[0], (float)lo[1], z, 0.0f, 0.0f},
    {(float)hi[0], (float)hi[1], z, (float)fu, (float)fv},
    {(float)lo[0], (float)hi[1], z, 0.0f, (float)fv},
  };
  glBindBuffer(GL_ARRAY_BUFFER, v->mip_vbo);
  glBufferSubData(GL_ARRAY_BUFFER, 0, sizeof q, q);
  v->mip_ok = 1;
  return 1;
}
