/* fuzz_exr.c — libFuzzer target for the EXR volume reader
 * (elfm_volume_read_exr in recon/volume_exr.c, through OpenEXR's C API):
 * any bytes must give a volume or a clean error, never a crash or leak. */
#include "elfm_recon.h"
#include "fuzz_file_common.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
  char path[] = "/tmp/fuzz_exr_XXXXXX";
  if (fuzz_write_temp(path, data, size) == 0) {
    elfm_volume *v = NULL;
    elfm_error err;
    if (elfm_volume_read_exr(path, &v, &err) == ELFM_OK) {
      /* The contract: a whole w x h x nz volume. Touch its last voxel. */
      volatile float last = v->data[(size_t)v->w * (size_t)v->h * (size_t)v->nz - 1];
      (void)last;
    }
    elfm_volume_free(v);
  }
  unlink(path);
  return 0;
}
