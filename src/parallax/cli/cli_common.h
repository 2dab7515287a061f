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

// Parses, applies the verbosity, installs the SIGINT/SIGTERM handlers, runs `body`, and turns
// every exception into a one-line "error: ..." on stderr with exit code 1 (never a crash or a
// stack trace); a run stopped by a signal prints one line saying what was kept and that the
// same command resumes, and exits 130 (SIGINT) or 143 (SIGTERM).
int RunCommand(CLI::App& app, int argc, char** argv, const VerbosityFlags& flags,
               const std::function<int()>& body);

}  // namespace parallax::cli
