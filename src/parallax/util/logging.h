#pragma once

#include <sstream>

namespace parallax {

// Library code never writes to stdout: log lines go to stderr, filtered by one global level
// that the CLI sets from --quiet / --verbose.
enum class LogLevel { kDebug = 0, kInfo = 1, kWarning = 2, kError = 3, kSilent = 4 };

void SetLogLevel(LogLevel level);
LogLevel GetLogLevel();
bool LogEnabled(LogLevel level);

namespace internal {
// Collects one line and emits it (thread-safe, whole lines) when destroyed.
class LogLine {
 public:
  explicit LogLine(LogLevel level) : level_(level) {}
  ~LogLine();
  template <typename T>
  LogLine& operator<<(const T& value) {
    stream_ << value;
    return *this;
  }

 private:
  LogLevel level_;
  std::ostringstream stream_;
};
}  // namespace internal

}  // namespace parallax

#define PARALLAX_LOG(level)                                      \
  if (!::parallax::LogEnabled(::parallax::LogLevel::k##level)) { \
  } else                                                         \
    ::parallax::internal::LogLine(::parallax::LogLevel::k##level)
