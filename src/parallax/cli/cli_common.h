#pragma once

#include <CLI/CLI.hpp>
#include <cstdint>
#include <functional>
#include <string>

namespace parallax::cli {

// "8x6" -> (8, 6); false unless two positive integers joined by 'x' or 'X'.
bool ParseDimensions(const std::string& text, int* first, int* second);
// A CLI11 check that the value parses with ParseDimensions; `example` goes in its message.
CLI::Validator DimensionsValidator(const std::string& example);

// Adds --quiet / --verbose to a subcommand; applied by RunCommand.
struct VerbosityFlags {
  bool quiet = false;
  bool verbose = false;
};
void AddVerbosityFlags(CLI::App& app, VerbosityFlags* flags);

// --seed, the same words for every command that runs a randomised stage; `seed` is the seed
// field of that stage's options (reconstruct's is spread over its stages by SetSeed).
void AddSeedOption(CLI::App& app, uint64_t* seed);

// Parses, applies the verbosity, installs the SIGINT/SIGTERM handlers, runs `body`, and turns
// every exception into a one-line "error: ..." on stderr with exit code 1 (never a crash or a
// stack trace); a run stopped by a signal prints one line saying what was kept and that the
// same command resumes, and exits 130 (SIGINT) or 143 (SIGTERM).
int RunCommand(CLI::App& app, int argc, char** argv, const VerbosityFlags& flags,
               const std::function<int()>& body);

}  // namespace parallax::cli
