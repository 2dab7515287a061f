#include "parallax/cli/cli_common.h"

#include <exception>
#include <iostream>

#include "parallax/util/logging.h"

namespace parallax::cli {

void AddVerbosityFlags(CLI::App& app, VerbosityFlags* flags) {
  app.add_flag("-q,--quiet", flags->quiet, "Print only warnings and errors");
  app.add_flag("-v,--verbose", flags->verbose, "Print debug messages");
}

int RunCommand(CLI::App& app, int argc, char** argv, const VerbosityFlags& flags,
               const std::function<int()>& body) {
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& error) {
    return app.exit(error);
  }
  if (flags.quiet) SetLogLevel(LogLevel::kWarning);
  if (flags.verbose) SetLogLevel(LogLevel::kDebug);
  try {
    return body();
  } catch (const std::exception& error) {
    std::cerr << "error: " << error.what() << std::endl;
    return 1;
  }
}

}  // namespace parallax::cli
