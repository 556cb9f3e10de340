// mjtether: the command-line tool. Each sub-command lives in its own plugin/cli_*.cc and
// registers itself (cli_command.h).
//
// Exit codes: 0 success, 1 the simulation diverged, 2 bad input (model, declaration or
// options), 3 MuJoCo error, 4 an external tool failed, 5 an output could not be written
// (docs/bad_input.md), 130/143 stopped by SIGINT/SIGTERM (the outputs keep complete rows).
#include <mjtether/version.h>

#include <functional>
#include <string>
#include <vector>

#include "cli_command.h"
#include "mjtether.h"

int main(int argc, char** argv) {
  mjtether::InstallErrorHandlers();
  CLI::App app{"mjtether: lumped-mass ROV tethers in MuJoCo"};
  app.require_subcommand(1);
  // mjtether's version and the MuJoCo library it runs on (mj_versionString at run time).
  app.set_version_flag("--version", std::string("mjtether " MJTETHER_VERSION_STRING " (MuJoCo ") +
                                        mj_versionString() + ")");
  std::vector<std::pair<CLI::App*, std::function<int()>>> actions;
  for (const mjtether::cli::Command& c : mjtether::cli::Commands()) {
    CLI::App* sub = app.add_subcommand(c.name, c.help);
    actions.emplace_back(sub, c.setup(sub));
  }
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    const int code = app.exit(e);
    return code == 0 ? 0 : 2;
  }
  for (auto& [sub, action] : actions) {
    if (*sub) return action();
  }
  return 2;
}
