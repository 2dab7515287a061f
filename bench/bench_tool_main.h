#pragma once

#include <exception>
#include <iostream>

namespace parallax {

// The body of a bench tool's main(): run's exit status, or, when it throws (an image or model
// that cannot be read), one line naming the tool and the problem and exit status 1, instead
// of std::terminate.
inline int RunBenchTool(const char* name, int (*run)(int, char**), int argc, char** argv) {
  try {
    return run(argc, argv);
  } catch (const std::exception& error) {
    std::cerr << name << ": " << error.what() << std::endl;
    return 1;
  }
}

}  // namespace parallax
