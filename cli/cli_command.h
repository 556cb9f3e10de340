// Sub-commands of the mjtether tool register themselves here, one file each
// (plugin/cli_run.cc, ...), so that adding a command touches no other file.
//
//   namespace { const bool registered = mjtether::cli::Register({"name", "help", Setup}); }
//
// Setup adds the sub-command's options to `sub` and returns the function that runs it once
// parsing succeeded. Exit codes: 0 success, 1 the simulation diverged, 2 bad input, 3 MuJoCo
// error, 4 an external tool (ffmpeg, gnuplot) failed.
#ifndef MJTETHER_PLUGIN_CLI_COMMAND_H_
#define MJTETHER_PLUGIN_CLI_COMMAND_H_

#include <functional>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

namespace mjtether::cli {

struct Command {
  std::string name;
  std::string help;
  std::function<std::function<int()>(CLI::App* sub)> setup;
};

inline std::vector<Command>& Commands() {
  static std::vector<Command> commands;
  return commands;
}

inline bool Register(Command command) {
  Commands().push_back(std::move(command));
  return true;
}

}  // namespace mjtether::cli

#endif  // MJTETHER_PLUGIN_CLI_COMMAND_H_
