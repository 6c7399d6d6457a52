/* lfm_render.h — synthetic Fourier LFM frames for the recon tests: a bead's
 * 25 images drawn with the SPEC §2 projection (elfm_calib_project).
 *
 * render_views adds a Gaussian image of width sigma_px and peak amp in each
 * view (only the first only_views views when > 0), pixel values below 1
 * left out; offset_px moves the images of views v < n_offset along x (another
 * object there). Images beyond the lenslet field stop (half a view pitch,
 * 154 px, from the view centre: nothing reaches the neighbours' crops) are
 * not drawn. */
#ifndef ELFM_TESTS_LFM_RENDER_H
#define ELFM_TESTS_LFM_RENDER_H

#include <math.h>

#include "elfm_recon.h"

#define FIELD_STOP_PX 77.0

static inline void render_views(elfm_frame *f, const elfm_calib *c, double x, double y, double z,
                                double amp, double sigma_px, int only_views, int n_offset,
                                double offset_px)
{
  const int r = (int)ceil(3 * sigma_px);
  for (int v = 0; v < c->n_views; v++) {
    if (only_views > 0 && v >= only_views) break;
    double u, w;
    elfm_calib_project(c, v, x, y, z, &u, &w);
    if (v < n_offset) u += offset_px;
    if (fabs(u - c->views[v].cx_px) > FIELD_STOP_PX || fabs(w - c->views[v].cy_px) > FIELD_STOP_PX)
      continue;
    for (int yy = (int)floor(w) - r; yy <= (int)floor(w) + r + 1; yy++)
      for (int xx = (int)floor(u) - r; xx <= (int)floor(u) + r + 1; xx++) {
        if (xx < 0 || yy < 0 || xx >= f->w || yy >= f->h) continue;
        double d2 = (xx - u) * (xx - u) + (yy - w) * (yy - w);
        float a = (float)(amp * exp(-0.5 * d2 / (sigma_px * sigma_px)));
        if (a < 1.0f) continue;
        uint32_t i = (uint32_t)(yy * f->w + xx);
        elfm_frame_set(f, i, f->data[i] + a);
      }
  }
}

#endif
