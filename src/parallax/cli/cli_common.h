#pragma once

#include <CLI/CLI.hpp>
#include <functional>
#include <string>

namespace parallax::cli {

// Adds --quiet / --verbose to a subcommand; applied by RunCommand.
struct VerbosityFlags {
  bool quiet = false;
  bool verbose = false;
};
void AddVerbosityFlags(CLI::App& app, VerbosityFlags* flags);

// Parses, applies the verbosity, runs `body`, and turns every exception into a one-line
// "error: ..." on stderr with exit code 1 (never a crash or a stack trace).
int RunCommand(CLI::App& app, int argc, char** argv, const VerbosityFlags& flags,
               const std::function<int()>& body);

}  // namespace parallax::cli
