/* elfm_volume.h — a reconstructed volume: W x H x Nz floats with its time
 * and physical axes (SPEC §3, §5).
 *
 * Voxel (X, Y, k) is at x = (X - (W-1)/2) * um_per_px,
 *                        y = (Y - (H-1)/2) * um_per_px,
 *                        z = z_min_um + k * z_step_um.
 * data[((size_t)k * h + Y) * w + X]; the volume owns data.
 */
#ifndef ELFM_VOLUME_H
#define ELFM_VOLUME_H

#include <stddef.h>
#include <stdint.h>

#include "elfm_error.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct elfm_volume {
  int w, h, nz;
  float *data;
  int64_t t_us;       /* the time this volume stands for (SPEC §5) */
  int64_t frame;      /* index of the frame it was built from */
  /* the frame's window [t_start_us, t_end_us) and its events (elfm_frame);
   * a volume read back from a file has t_start_us = t_end_us = t_us and
   * n_events 0 (not stored) */
  int64_t t_start_us, t_end_us;
  size_t n_events;
  int64_t n_triggers;  /* the frame's (elfm_frame): trigger edges up to its end; 0 read back */
  double um_per_px, z_min_um, z_step_um;
  /* internal: 1 when data came from elfm_big_calloc (the volumes a run
   * keeps, recon/big_alloc.h: on 2 MiB pages), 0 from calloc; read by
   * elfm_volume_free. A copy of the struct must not carry it over to
   * another volume's data. */
  int data_big;
} elfm_volume;

/* The largest volume EventLFM allocates: 2^27 voxels, 512 MiB of floats.
 * The paper geometry is 144 x 144 x 101 (2.1 M voxels); a whole EVK4 view
 * (256 x 256) over 1000 planes is 66 M. The cap exists because sizes come
 * from files (an EXR data window, a calibration's view size): a header that
 * claims 60000 x 60000 must be refused, not allocated (found by fuzz_exr). */
#define ELFM_VOLUME_MAX_VOXELS ((size_t)1 << 27)

/* Allocate a zeroed volume; NULL (err filled) when a side is not positive,
 * w * h * nz exceeds ELFM_VOLUME_MAX_VOXELS (ELFM_ERR_RANGE), or memory
 * runs out. Free with elfm_volume_free (NULL is a no-op). */
elfm_volume *elfm_volume_create(int w, int h, int nz, double um_per_px,
                                double z_min_um, double z_step_um, elfm_error *err);
void elfm_volume_free(elfm_volume *v);

static inline double elfm_volume_x_um(const elfm_volume *v, double X)
{ return (X - (v->w - 1) * 0.5) * v->um_per_px; }
static inline double elfm_volume_y_um(const elfm_volume *v, double Y)
{ return (Y - (v->h - 1) * 0.5) * v->um_per_px; }
static inline double elfm_volume_z_um(const elfm_volume *v, double k)
{ return v->z_min_um + k * v->z_step_um; }
/* The inverses: voxel coordinates (fractional) of a position in um. */
static inline double elfm_volume_x_vox(const elfm_volume *v, double x_um)
{ return x_um / v->um_per_px + (v->w - 1) * 0.5; }
static inline double elfm_volume_y_vox(const elfm_volume *v, double y_um)
{ return y_um / v->um_per_px + (v->h - 1) * 0.5; }
static inline double elfm_volume_z_vox(const elfm_volume *v, double z_um)
{ return (z_um - v->z_min_um) / v->z_step_um; }

#ifdef __cplusplus
}
#endif
#endif
