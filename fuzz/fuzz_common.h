#pragma once

// Shared by the fuzz targets: a parser may reject its input only with InputError (a one-line
// message for the user). Any other exception (a CheckError from a precondition the parser let
// through, std::out_of_range, std::bad_alloc, ...) is a bug: abort, so libFuzzer records the
// input as a crash.
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <string>
#include <string_view>

#include "parallax/util/check.h"

namespace parallax::fuzz {

[[noreturn]] inline void Abort(const char* what, const std::string& message) {
  std::fprintf(stderr, "fuzz: %s: %s\n", what, message.c_str());
  std::abort();
}

// Runs `parse`; returns false when it rejected the input with an InputError.
template <typename Parse>
bool ParsesOrRejects(Parse&& parse) {
  try {
    parse();
    return true;
  } catch (const InputError& error) {
    const std::string message = error.what();
    // A rejection must be one line naming its source.
    if (message.empty() || message.find('\n') != std::string::npos) {
      Abort("InputError message is not one line", message);
    }
    return false;
  } catch (const CheckError& error) {
    Abort("CheckError", error.what());
  } catch (const std::exception& error) {
    Abort("unexpected exception", error.what());
  }
}

// Properties that must hold for accepted input.
#define PARALLAX_FUZZ_EXPECT(condition)                                       \
  do {                                                                        \
    if (!(condition)) ::parallax::fuzz::Abort("property failed", #condition); \
  } while (false)

inline std::string_view AsStringView(const uint8_t* data, size_t size) {
  return std::string_view(reinterpret_cast<const char*>(data), size);
}

}  // namespace parallax::fuzz
