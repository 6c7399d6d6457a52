/* cmd_track.c — eventlfm track (not built yet: reports so and fails). */
#include "cli.h"

int cmd_track(int argc, char **argv)
{
  (void)argc;
  (void)argv;
  return cli_message("track", CLI_FAIL, "not implemented yet");
}
