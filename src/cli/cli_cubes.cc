// vlab cubes: not built yet (placeholder until its issue lands).
#include <cstdio>

#include "cli/cli_commands.h"

namespace vlab::cli {

Subcommand AddCubesCommand(CLI::App& app) {
  CLI::App* cmd = app.add_subcommand("cubes", "(not available in this build)");
  cmd->group("");  // hidden
  return {cmd, [] {
            std::fprintf(stderr, "vlab: error: 'cubes' is not available in this build\n");
            return 2;
          }};
}

}  // namespace vlab::cli
