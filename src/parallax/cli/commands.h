#pragma once

// One entry point per subcommand. Each parses its own arguments (argv[0] is the subcommand
// name) with CLI11 and returns the process exit code.
namespace parallax::cli {

int RunVersion(int argc, char** argv);

}  // namespace parallax::cli
