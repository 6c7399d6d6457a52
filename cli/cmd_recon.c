/* cmd_recon.c — eventlfm recon (not built yet: reports so and fails). */
#include "cli.h"

int cmd_recon(int argc, char **argv)
{
  (void)argc;
  (void)argv;
  return cli_message("recon", CLI_FAIL, "not implemented yet");
}
