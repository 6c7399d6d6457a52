/* cmd_track_bin.c — `track --bin-px`: peaks found in a binned volume,
 * refined on the full-sampled voxels around them.
 *
 * With --bin-px 2 the driver refocuses each frame binned 2 x 2 (a quarter
 * of the voxels, recon/pipeline.c), and the peak detector runs on that
 * volume. Its peaks' fits (position, sigmas, intensity) and widths are
 * those of 2-pixel voxels: the widths come out ~35 % wider on flow, and the
 * motion lead, which is taken from the in-focus peaks' widths
 * (track_motion_lead_um), grows with them. So each peak is refined again
 * here, as the detector would have refined it in the full-sampled volume:
 * the full plan's voxels around it are made from the frame
 * (elfm_refocus_plane_piece, elfm_refocus_value_at), the largest of the 3 x 3 about its position
 * taken for its voxel, and elfm_peaks_refine_at fits that piece.
 * docs/tracker.md "Peaks found in a binned volume" has the measurements. */
#include "cmd_track.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* The piece's half side: the width's +-6 voxels (tracker/peaks.c) and
 * +-1 for the move to the 3 x 3's largest voxel. */
#define BIN_HALF 7

static int piece_planes(const track_ctx *c) { return 2 * c->o->peaks.fit_half_z + 1; }

/* cmd_track.h */
elfm_status track_bin_setup(track_ctx *c, elfm_error *err)
{
  if (c->o->bin_px <= 1) return ELFM_OK;
  const size_t side = 2 * BIN_HALF + 1;
  c->bin_piece_len = side * side * (size_t)piece_planes(c);
  c->bin_piece = malloc((size_t)c->n_threads * c->bin_piece_len * sizeof *c->bin_piece);
  if (!c->bin_piece) return elfm_error_set(err, ELFM_ERR_NOMEM, NULL, -1, "out of memory (peaks' pieces)");
  return ELFM_OK;
}

static int imin(int a, int b) { return a < b ? a : b; }
static int imax(int a, int b) { return a > b ? a : b; }
static int clampi(int v, int lo, int hi) { return imin(imax(v, lo), hi); }

/* cmd_track.h */
void track_bin_refine(track_ctx *c, const elfm_refocus_plan *plan, const elfm_frame *frame,
                      int thread, elfm_detection *det, int n)
{
  const elfm_volume *g = &c->geo;
  const int fz = c->o->peaks.fit_half_z;
  float *buf = c->bin_piece + (size_t)thread * c->bin_piece_len;
  for (int i = 0; i < n; i++) {
    const int X0 = clampi((int)lround(elfm_volume_x_vox(g, det[i].x_um)), 0, g->w - 1);
    const int Y0 = clampi((int)lround(elfm_volume_y_vox(g, det[i].y_um)), 0, g->h - 1);
    const int K = clampi((int)lround(elfm_volume_z_vox(g, det[i].z_um)), 0, g->nz - 1);
    /* the piece: its box cut at the volume's edges */
    const int x0 = imax(X0 - BIN_HALF, 0), x1 = imin(X0 + BIN_HALF + 1, g->w);
    const int y0 = imax(Y0 - BIN_HALF, 0), y1 = imin(Y0 + BIN_HALF + 1, g->h);
    const int k0 = imax(K - fz, 0), k1 = imin(K + fz + 1, g->nz);
    const int pw = x1 - x0, ph = y1 - y0, pn = k1 - k0;
    memset(buf, 0, (size_t)pw * ph * pn * sizeof *buf);
    float *pl = buf + (size_t)(K - k0) * pw * ph;
    double plane[(2 * BIN_HALF + 1) * (2 * BIN_HALF + 1)];
    elfm_refocus_plane_piece(plan, frame, x0, y0, pw, ph, K, plane);
    for (int j = 0; j < pw * ph; j++) pl[j] = (float)plane[j];
    /* the voxel: the largest of the 3 x 3 about the binned peak's position
     * (the first of equals, row by row) */
    int Xm = X0, Ym = Y0;
    for (int Y = Y0 - 1; Y <= Y0 + 1; Y++)
      for (int X = X0 - 1; X <= X0 + 1; X++)
        if (X >= x0 && X < x1 && Y >= y0 && Y < y1 &&
            pl[(Y - y0) * pw + (X - x0)] > pl[(Ym - y0) * pw + (Xm - x0)]) {
          Xm = X;
          Ym = Y;
        }
    for (int k = k0; k < k1; k++)
      if (k != K)
        buf[((size_t)(k - k0) * ph + (Ym - y0)) * pw + (Xm - x0)] =
            (float)elfm_refocus_value_at(plan, frame, Xm, Ym, k);
    elfm_volume piece = {.w = pw, .h = ph, .nz = pn, .data = buf, .t_us = det[i].t_us,
                         .frame = det[i].frame, .um_per_px = g->um_per_px,
                         .z_min_um = 0, .z_step_um = g->z_step_um};
    elfm_detection d = det[i];
    elfm_peaks_refine_at(c->pk[thread], &piece, Xm - x0, Ym - y0, K - k0, &d);
    /* the piece's um are about its own centre: back to the volume's by the
     * offset from the voxel */
    d.x_um = elfm_volume_x_um(g, Xm) + d.x_um - elfm_volume_x_um(&piece, Xm - x0);
    d.y_um = elfm_volume_y_um(g, Ym) + d.y_um - elfm_volume_y_um(&piece, Ym - y0);
    d.z_um = elfm_volume_z_um(g, K) + d.z_um - elfm_volume_z_um(&piece, K - k0);
    det[i] = d;
  }
}
