#include "parallax/util/logging.h"

#include <atomic>
#include <cstdio>
#include <mutex>

namespace parallax {
namespace {
std::atomic<LogLevel> g_log_level{LogLevel::kInfo};
std::mutex g_log_mutex;

const char* LevelPrefix(LogLevel level) {
  switch (level) {
    case LogLevel::kDebug:
      return "debug: ";
    case LogLevel::kWarning:
      return "warning: ";
    case LogLevel::kError:
      return "error: ";
    default:
      return "";
  }
}
}  // namespace

void SetLogLevel(LogLevel level) { g_log_level = level; }
LogLevel GetLogLevel() { return g_log_level; }
bool LogEnabled(LogLevel level) { return level >= g_log_level.load(); }

namespace internal {
LogLine::~LogLine() {
  const std::string line = std::string(LevelPrefix(level_)) + stream_.str() + "\n";
  std::lock_guard<std::mutex> lock(g_log_mutex);
  std::fputs(line.c_str(), stderr);
}
}  // namespace internal

}  // namespace parallax
