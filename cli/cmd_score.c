/* cmd_score.c — eventlfm score (not built yet: reports so and fails). */
#include "cli.h"

int cmd_score(int argc, char **argv)
{
  (void)argc;
  (void)argv;
  return cli_message("score", CLI_FAIL, "not implemented yet");
}
