/* mip_plane.c — the MIP of the cursor's frame as a textured plane.
 *
 * The recon stage saves one depth-colour-coded MIP PNG per frame (and/or
 * the volume as OpenEXR); the plane shows the latest one at or before the
 * cursor, under the tracks at the volume's z_min. A file is decoded only
 * when the frame changes, into one reused buffer. Where a MIP picture is
 * wider or taller than the volume's x-y size, it carries side panels
 * (recon/elfm_pipeline.h: x-y at the top left, x-z below, y-z right), and
 * the plane shows the top-left W x H (W x H = view_size_px of calib.json).
 * A volume is projected here: brightness = maximum along z over the
 * volume's maximum, colour = depth of that maximum through the viewer's own
 * colour map (so it matches the depth colour bar).
 */
#include <stdio.h>
#include <stdlib.h>

#include "elfm_recon.h"
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

/* Depth-coded MIP of an EXR volume into v->mip_rgba (grown if needed). */
static elfm_status mip_from_volume(elfm_viewer *v, const char *path, int *w, int *h,
                                   elfm_error *err)
{
  elfm_volume *vol = NULL;
  elfm_status st = elfm_volume_read_exr(path, &vol, err);
  if (st != ELFM_OK) return st;
  size_t plane = (size_t)vol->w * vol->h, need = plane * 4;
  if (need > v->mip_cap) {
    uint8_t *nb = realloc(v->mip_rgba, need);
    if (!nb) {
      elfm_volume_free(vol);
      return elfm_error_set(err, ELFM_ERR_NOMEM, path, -1, "out of memory");
    }
    v->mip_rgba = nb;
    v->mip_cap = need;
  }
  float vmax = 0;
  for (size_t i = 0; i < plane * (size_t)vol->nz; i++)
    if (vol->data[i] > vmax) vmax = vol->data[i];
  for (size_t i = 0; i < plane; i++) {
    float best = vol->data[i];
    int kbest = 0;
    for (int k = 1; k < vol->nz; k++) {
      float x = vol->data[(size_t)k * plane + i];
      if (x > best) {
        best = x;
        kbest = k;
      }
    }
    float rgb[3];
    elfm_colormap_rgb(vol->nz > 1 ? (double)kbest / (vol->nz - 1) : 0.5, rgb);
    float b = vmax > 0 && best > 0 ? best / vmax : 0;
    for (int c = 0; c < 3; c++) v->mip_rgba[4 * i + c] = (uint8_t)(255.0f * rgb[c] * b + 0.5f);
    v->mip_rgba[4 * i + 3] = 255;
  }
  *w = vol->w;
  *h = vol->h;
  elfm_volume_free(vol);
  return ELFM_OK;
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
  elfm_status st = d->mips[k].is_volume
                       ? mip_from_volume(v, d->mips[k].path, &w, &h, &e)
                       : gui_png_read_into(d->mips[k].path, &v->mip_rgba, &v->mip_cap, &w, &h, &e);
  if (st != ELFM_OK) {
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
