/* main.c — eventlfm: one program, a table of subcommands (after git's git.c).
 * Exact names only; every subcommand answers --help. Before exiting 0 we
 * check that stdout really reached its destination (a full disk or a closed
 * pipe must not pass for success). */
#include <errno.h>
#include <stdio.h>
#include <string.h>

#include "cli.h"

struct cmd_entry {
  const char *name;
  int (*fn)(int argc, char **argv);
  const char *summary;
};

static const struct cmd_entry commands[] = {
  {"info", cmd_info, "describe an event file: format, geometry, counts, rates"},
  {"convert", cmd_convert, "convert an event file to EVT 3.0 or CSV, optionally a time range"},
  {"calib", cmd_calib, "build calib.json from optics (calib from-optics)"},
  {"simulate", cmd_simulate, "simulate a scene: events.raw, truth.csv, calib.json"},
  {"recon", cmd_recon, "events -> refocused volumes (EXR), MIPs (PNG), summary.json"},
  {"track", cmd_track, "events -> volumes -> detections -> smoothed 3D tracks"},
  {"traces", cmd_traces, "each object's intensity frame by frame (flashes, spikes)"},
  {"score", cmd_score, "score detections/tracks against simulator truth (SPEC 7)"},
  {"view", cmd_view, "show time-coded 3D tracks in a window, or render a screenshot"},
  {"bench", cmd_bench, "sweep settings on simulated scenes: speed against error"},
  {"demo", cmd_demo, "simulate a short flow scene, track it, score it"},
};
#define N_COMMANDS (sizeof commands / sizeof commands[0])

static void usage(FILE *f)
{
  fprintf(f, "usage: eventlfm <command> [options]   (eventlfm <command> --help for more)\n\n"
             "commands:\n");
  for (size_t i = 0; i < N_COMMANDS; i++)
    fprintf(f, "  %-10s %s\n", commands[i].name, commands[i].summary);
}

static int finish_stdout(int rc)
{
  /* fflush + ferror catches ENOSPC/EIO/EPIPE on stdout; fclose reports
   * errors of the final write-back (git does the same). */
  if (fflush(stdout) != 0 || ferror(stdout) || fclose(stdout) != 0) {
    fprintf(stderr, "eventlfm: error writing standard output: %s\n", strerror(errno));
    return rc ? rc : CLI_FAIL;
  }
  return rc;
}

int main(int argc, char **argv)
{
  if (argc < 2) {
    usage(stderr);
    return CLI_USAGE;
  }
  if (!strcmp(argv[1], "--help") || !strcmp(argv[1], "-h") || !strcmp(argv[1], "help")) {
    usage(stdout);
    return finish_stdout(CLI_OK);
  }
  if (!strcmp(argv[1], "--version")) {
    printf("eventlfm 0.1.0\n");
    return finish_stdout(CLI_OK);
  }
  for (size_t i = 0; i < N_COMMANDS; i++)
    if (!strcmp(argv[1], commands[i].name))
      return finish_stdout(commands[i].fn(argc - 1, argv + 1));
  fprintf(stderr, "eventlfm: '%s' is not a command\n\n", argv[1]);
  usage(stderr);
  return CLI_USAGE;
}
