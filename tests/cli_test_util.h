/* cli_test_util.h — what the tests that run the eventlfm program share
 * (include after check.h). */
#ifndef ELFM_TESTS_CLI_TEST_UTIL_H
#define ELFM_TESTS_CLI_TEST_UTIL_H

#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/wait.h>
#include <unistd.h>

/* Run `eventlfm ARGS` from the build tree, stdout to DIR/out.txt, stderr
 * to DIR/err.txt; its exit code (-1: it did not exit). */
static inline int cli_run(const char *dir, const char *args)
{
  char cmd[4096];
  snprintf(cmd, sizeof cmd, "%s/eventlfm %s >%s/out.txt 2>%s/err.txt", ELFM_BINARY_DIR, args, dir, dir);
  int rc = system(cmd);
  return WIFEXITED(rc) ? WEXITSTATUS(rc) : -1;
}

/* Before a test of the command: 1 when the eventlfm program is built and
 * dir (a mkdtemp template) was made; else 0, with a SKIP line saying why. */
static inline int cli_test_ready(char *dir)
{
  char bin[600];
  snprintf(bin, sizeof bin, "%s/eventlfm", ELFM_BINARY_DIR);
  if (access(bin, X_OK) != 0) {
    printf("SKIP the command: %s not built\n", bin);
    return 0;
  }
  if (!mkdtemp(dir)) {
    printf("SKIP the command: no temporary directory\n");
    return 0;
  }
  return 1;
}

/* Write `text` to DIR/NAME; 0, or -1 (perror'd) when it cannot. */
static inline int cli_write_file(const char *dir, const char *name, const char *text)
{
  char path[700];
  snprintf(path, sizeof path, "%s/%s", dir, name);
  FILE *f = fopen(path, "w");
  if (!f) { perror(path); return -1; }
  int bad = fputs(text, f) < 0;
  bad |= fclose(f) != 0;
  return bad ? -1 : 0;
}

/* DIR/NAME's first size - 1 bytes into buf, NUL-terminated; 0 when it
 * cannot be opened. */
static inline int cli_read_file(const char *dir, const char *name, char *buf, size_t size)
{
  char path[700];
  snprintf(path, sizeof path, "%s/%s", dir, name);
  FILE *f = fopen(path, "r");
  if (!f) return 0;
  size_t n = fread(buf, 1, size - 1, f);
  fclose(f);
  buf[n] = '\0';
  return 1;
}

/* 1 when DIR/NAME's first 8 kB hold `text`. */
static inline int cli_file_has(const char *dir, const char *name, const char *text)
{
  char buf[8192];
  return cli_read_file(dir, name, buf, sizeof buf) && strstr(buf, text) != NULL;
}

/* 1 when files a and b both exist and hold the same bytes (outputs of two
 * runs that must not differ). */
static inline int cli_same_file(const char *a, const char *b)
{
  FILE *fa = fopen(a, "rb"), *fb = fopen(b, "rb");
  int same = fa && fb;
  while (same) {
    char x[4096], y[4096];
    size_t na = fread(x, 1, sizeof x, fa), nb = fread(y, 1, sizeof y, fb);
    if (na != nb || memcmp(x, y, na) != 0) same = 0;
    if (na < sizeof x) break;
  }
  if (fa) fclose(fa);
  if (fb) fclose(fb);
  return same;
}

#endif
