/* volume.c — allocation of elfm_volume (see elfm_volume.h), and of the
 * volumes a run keeps (big_alloc.h). */
#include "elfm_volume.h"

#include "big_alloc.h"

#include <stdlib.h>

static elfm_volume *volume_new(int w, int h, int nz, double um_per_px, double z_min_um,
                               double z_step_um, int big, elfm_error *err)
{
  if (w <= 0 || h <= 0 || nz <= 0 || w > 65535 || h > 65535 || nz > 65535) {
    elfm_error_set(err, ELFM_ERR_INVALID, NULL, -1,
                   "volume size %d x %d x %d is not positive or too large", w, h, nz);
    return NULL;
  }
  if ((size_t)w * (size_t)h * (size_t)nz > ELFM_VOLUME_MAX_VOXELS) {
    elfm_error_set(err, ELFM_ERR_RANGE, NULL, -1,
                   "volume size %d x %d x %d exceeds the limit of %zu voxels", w, h, nz,
                   ELFM_VOLUME_MAX_VOXELS);
    return NULL;
  }
  elfm_volume *v = calloc(1, sizeof *v);
  const size_t n = (size_t)w * (size_t)h * (size_t)nz;
  if (v) v->data = big ? elfm_big_calloc(n, sizeof *v->data) : calloc(n, sizeof *v->data);
  if (!v || !v->data) {
    free(v);
    elfm_error_set(err, ELFM_ERR_NOMEM, NULL, -1, "cannot allocate a %d x %d x %d volume", w, h, nz);
    return NULL;
  }
  v->w = w;
  v->h = h;
  v->nz = nz;
  v->um_per_px = um_per_px;
  v->z_min_um = z_min_um;
  v->z_step_um = z_step_um;
  v->data_big = big;
  return v;
}

elfm_volume *elfm_volume_create(int w, int h, int nz, double um_per_px,
                                double z_min_um, double z_step_um, elfm_error *err)
{
  return volume_new(w, h, nz, um_per_px, z_min_um, z_step_um, 0, err);
}

elfm_volume *elfm_volume_create_kept(int w, int h, int nz, double um_per_px,
                                     double z_min_um, double z_step_um, elfm_error *err)
{
  return volume_new(w, h, nz, um_per_px, z_min_um, z_step_um, 1, err);
}

void elfm_volume_free(elfm_volume *v)
{
  if (!v) return;
  if (v->data_big)
    elfm_big_free(v->data, (size_t)v->w * (size_t)v->h * (size_t)v->nz, sizeof *v->data);
  else
    free(v->data);
  free(v);
}
