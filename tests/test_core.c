/* test_core.c — the error object and volume allocation. */
#include <string.h>

#include "check.h"
#include "elfm_recon.h"

int main(void)
{
  elfm_error err;
  elfm_error_clear(&err);
  CHECK_EQ_INT(err.code, ELFM_OK);

  char buf[1200];
  CHECK_EQ_INT(elfm_error_set(&err, ELFM_ERR_FORMAT, "a/b.raw", 4096, "bad word 0x%04x", 0xbeef),
               ELFM_ERR_FORMAT);
  elfm_error_format(&err, buf, sizeof buf);
  CHECK_MSG(strcmp(buf, "a/b.raw: byte 4096: bad word 0xbeef") == 0, "got '%s'", buf);

  elfm_error_set_line(&err, ELFM_ERR_FORMAT, "x.csv", 12, "need 4 fields");
  elfm_error_format(&err, buf, sizeof buf);
  CHECK_MSG(strcmp(buf, "x.csv:12: need 4 fields") == 0, "got '%s'", buf);

  /* A path longer than the buffer keeps its tail (the file name). */
  char longpath[2000];
  memset(longpath, 'd', sizeof longpath);
  strcpy(longpath + sizeof longpath - 12, "/events.raw");
  elfm_error_set(&err, ELFM_ERR_IO, longpath, -1, "gone");
  CHECK(strlen(err.file) == sizeof err.file - 1);
  CHECK(strcmp(err.file + strlen(err.file) - 11, "/events.raw") == 0);

  /* NULL error objects are allowed. */
  CHECK_EQ_INT(elfm_error_set(NULL, ELFM_ERR_IO, NULL, -1, "x"), ELFM_ERR_IO);

  elfm_volume *v = elfm_volume_create(4, 3, 2, 0.5, -1.0, 1.0, &err);
  CHECK(v != NULL);
  if (v) {
    CHECK_NEAR(elfm_volume_x_um(v, 0), -0.75, 1e-12);
    CHECK_NEAR(elfm_volume_y_um(v, 2), 0.5, 1e-12);
    CHECK_NEAR(elfm_volume_z_um(v, 1), 0.0, 1e-12);
    CHECK(v->data[4 * 3 * 2 - 1] == 0.0f);
  }
  elfm_volume_free(v);
  elfm_volume_free(NULL);
  CHECK(elfm_volume_create(0, 3, 2, 1, 0, 1, &err) == NULL);
  CHECK_EQ_INT(err.code, ELFM_ERR_INVALID);
  return check_report();
}
