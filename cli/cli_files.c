/* cli_files.c — files and child processes for the subcommands (see cli.h):
 * output directories (made with their parents, their paths' length checked
 * first), whole small files read, and child processes run with a log, a
 * time limit and their peak memory (bench's sweep points). */
#include "cli.h"

#include <errno.h>
#include <fcntl.h>
#include <limits.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <sys/time.h>
#include <sys/types.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

int cli_mkdir_p(const char *path)
{
  char buf[PATH_MAX];
  if (cli_path_fmt(buf, sizeof buf, "%s", path) != 0) { /* -1 when it does not fit */
    errno = ENAMETOOLONG;
    return -1;
  }
  for (char *p = buf + 1; *p; p++) {
    if (*p != '/') continue;
    *p = '\0';
    if (mkdir(buf, 0777) != 0 && errno != EEXIST) return -1;
    *p = '/';
  }
  if (mkdir(buf, 0777) != 0 && errno != EEXIST) return -1;
  return 0;
}

int cli_out_fits(const char *cmd, const char *out, const char *longest_name)
{
  const size_t n = strlen(out), most = PATH_MAX - 1 - strlen(longest_name);
  if (n <= most) return 1;
  cli_message(cmd, CLI_FAIL, "--out: %.60s...: %zu characters, too long for its files' paths (at most %zu)",
              out, n, most);
  return 0;
}

char *cli_read_text(const char *path, long max_bytes)
{
  FILE *f = fopen(path, "rb");
  if (!f) return NULL;
  if (fseek(f, 0, SEEK_END) != 0) { fclose(f); return NULL; }
  long n = ftell(f);
  if (n < 0 || n > max_bytes) { fclose(f); return NULL; }
  rewind(f);
  char *s = malloc((size_t)n + 1);
  if (s && fread(s, 1, (size_t)n, f) != (size_t)n) { free(s); s = NULL; }
  if (s) s[n] = '\0';
  fclose(f);
  return s;
}

int cli_calib_write(const char *cmd, elfm_calib *c, const char *out)
{
  char tmp[PATH_MAX];
  if (snprintf(tmp, sizeof tmp, "%s.tmp", out) >= (int)sizeof tmp)
    return cli_message(cmd, CLI_FAIL, "--out %.60s...: path too long", out);
  elfm_error err;
  elfm_error_clear(&err);
  if (elfm_calib_save(c, tmp, &err)) {
    remove(tmp);
    return cli_message(cmd, CLI_FAIL, "%s: %s", out, err.message);
  }
  if (elfm_calib_load(tmp, c, &err)) {
    remove(tmp);
    return cli_message(cmd, CLI_FAIL, "the calibration is refused (%s not written): %s", out,
                       err.message);
  }
  if (rename(tmp, out) != 0) {
    const int e = errno;
    remove(tmp);
    return cli_message(cmd, CLI_FAIL, "%s: cannot write: %s", out, strerror(e));
  }
  return CLI_OK;
}

int cli_run_child(char *const argv[], int use_path, const char *log_path, double timeout_s,
                  double *wall_s, double *peak_rss_mb, double *cpu_s)
{
  double t0 = cli_now_s();
  fflush(stdout);
  fflush(stderr);
  pid_t pid = fork();
  if (pid < 0) return -1;
  if (pid == 0) {
    int fd = open(log_path, O_WRONLY | O_CREAT | O_TRUNC, 0644);
    if (fd >= 0) {
      dup2(fd, STDOUT_FILENO);
      dup2(fd, STDERR_FILENO);
      close(fd);
    }
    if (use_path) execvp(argv[0], argv);
    else execv(argv[0], argv);
    _exit(127);
  }
  int st = 0;
  struct rusage ru;
  memset(&ru, 0, sizeof ru);
  int timed_out = 0;
  /* Polling rather than a blocking wait, so that the time limit can be
   * kept; wait4 rather than waitpid for the child's own peak memory and
   * CPU time. */
  for (;;) {
    pid_t w = wait4(pid, &st, WNOHANG, &ru);
    if (w == pid) break;
    if (w < 0 && errno != EINTR) return -1;
    if (timeout_s > 0 && cli_now_s() - t0 > timeout_s && !timed_out) {
      kill(pid, SIGKILL); /* our own child, by its id */
      timed_out = 1;
    }
    struct timespec ts = {0, 5000000}; /* 5 ms: polling cost is negligible */
    nanosleep(&ts, NULL);
  }
  if (wall_s) *wall_s = cli_now_s() - t0;
  if (peak_rss_mb) *peak_rss_mb = (double)ru.ru_maxrss / 1024.0; /* Linux: kB */
  if (cpu_s)
    *cpu_s = (double)ru.ru_utime.tv_sec + 1e-6 * (double)ru.ru_utime.tv_usec +
             (double)ru.ru_stime.tv_sec + 1e-6 * (double)ru.ru_stime.tv_usec;
  if (timed_out) return -2;
  if (WIFEXITED(st)) return WEXITSTATUS(st);
  if (WIFSIGNALED(st)) return 128 + WTERMSIG(st);
  return -1;
}
