/* fuzz_file_common.h — for parsers that take a path: write the fuzzer's
 * bytes to a fresh temporary file, return its path (caller unlinks). */
#ifndef ELFM_FUZZ_FILE_COMMON_H
#define ELFM_FUZZ_FILE_COMMON_H

#include <stddef.h>
#include <stdint.h>
#include <stdlib.h>
#include <unistd.h>

/* path: a buffer holding a mkstemp template ending in XXXXXX.
 * Returns 0 on success, -1 when the file could not be written. */
static inline int fuzz_write_temp(char *path, const uint8_t *data, size_t size)
{
  int fd = mkstemp(path);
  if (fd < 0) return -1;
  size_t off = 0;
  while (off < size) {
    ssize_t n = write(fd, data + off, size - off);
    if (n <= 0) break;
    off += (size_t)n;
  }
  close(fd);
  return off == size ? 0 : -1;
}

#endif
