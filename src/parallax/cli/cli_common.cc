#include "parallax/cli/cli_common.h"

#include "parallax/util/check.h"

#include <algorithm>
#include <cctype>
#include <csignal>
#include <exception>
#include <iostream>
#include <string>

#include "parallax/util/file.h"
#include "parallax/util/interrupt.h"
#include "parallax/util/logging.h"

namespace parallax::cli {

// "8x6" -> (8, 6); false unless two positive integers joined by 'x' or 'X'.
bool ParseDimensions(const std::string& text, int* first, int* second) {
  const size_t separator = text.find_first_of("xX");
  if (separator == std::string::npos || separator == 0 || separator + 1 == text.size()) {
    return false;
  }
  const std::string a = text.substr(0, separator), b = text.substr(separator + 1);
  const auto all_digits = [](const std::string& part) {
    return part.size() <= 6 &&
           std::all_of(part.begin(), part.end(), [](unsigned char c) { return std::isdigit(c); });
  };
  if (!all_digits(a) || !all_digits(b)) return false;
  *first = std::stoi(a);
  *second = std::stoi(b);
  return *first > 0 && *second > 0;
}

CLI::Validator DimensionsValidator(const std::string& example) {
  return CLI::Validator(
      [example](std::string& text) -> std::string {
        int first = 0, second = 0;
        if (ParseDimensions(text, &first, &second)) return "";
        return "expected two positive integers like " + example + ", got '" + text + "'";
      },
      "AxB");
}

void AddSeedOption(CLI::App& app, uint64_t* seed) {
  app.add_option("--seed", *seed,
                 "Random seed (same inputs, options and seed: same result; bit for bit with "
                 "--ba-threads 1)")
      ->capture_default_str();
}

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
  } catch (const InputError& error) {
    // A flag's value that its conversion refuses (--camera-params with a non-number).
    std::cerr << "error: " << error.what() << std::endl;
    return 1;
  }
  if (flags.quiet) SetLogLevel(LogLevel::kWarning);
  if (flags.verbose) SetLogLevel(LogLevel::kDebug);
  // Ctrl-C and kill stop the run at its next safe point (util/interrupt.h).
  InstallInterruptHandlers();
  try {
    return body();
  } catch (const Interrupted& interrupted) {
    std::cerr << "interrupted (" << (interrupted.signal_number() == SIGINT ? "SIGINT" : "SIGTERM")
              << "): " << interrupted.what() << "; run the same command again to resume"
              << std::endl;
    return interrupted.ExitStatus();
  } catch (const std::exception& error) {
    // Some libraries' messages (OpenCV's, SQLite's) span lines; the user gets one.
    std::string message = error.what();
    for (char& c : message) {
      if (c == '\n' || c == '\r') c = ' ';
    }
    std::cerr << "error: " << Trim(message) << std::endl;
    return 1;
  }
}

}  // namespace parallax::cli
