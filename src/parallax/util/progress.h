#pragma once

#include <chrono>
#include <cstddef>
#include <functional>
#include <iosfwd>
#include <mutex>
#include <string>

namespace parallax {

// Progress of a long stage on stderr: "label: done/total (rate/s, ETA Ns)". On a terminal
// the line is rewritten in place with '\r'; otherwise (logs, pipes) a plain line is printed
// every ~5 % or 10 s. Silent when the log level is above Info. Increment() is thread-safe.
// Told of every ProgressReporter's count as it changes (label, done, total), from whichever
// thread counted; on top of the stderr line. The Python module passes the counts to a
// callback. Empty: none.
using ProgressListener = std::function<void(const std::string& label, size_t done, size_t total)>;
// Replaces the process-wide listener; returns the previous one.
ProgressListener SetProgressListener(ProgressListener listener);

class ProgressReporter {
 public:
  ProgressReporter(std::string label, size_t total);
  // For tests: write to `stream`, as a terminal or not.
  ProgressReporter(std::string label, size_t total, std::ostream* stream, bool is_terminal);
  ~ProgressReporter();
  ProgressReporter(const ProgressReporter&) = delete;
  ProgressReporter& operator=(const ProgressReporter&) = delete;

  void Increment(size_t count = 1);
  // Prints the final state (and the newline a terminal line needs); idempotent.
  void Finish();
  size_t Done() const;

 private:
  using Clock = std::chrono::steady_clock;
  void MaybePrintLocked();
  void PrintLocked(bool final_line);

  std::string label_;
  size_t total_;
  std::ostream* stream_;
  bool is_terminal_;
  bool enabled_;
  mutable std::mutex mutex_;
  size_t done_ = 0;
  bool finished_ = false;
  Clock::time_point start_;
  Clock::time_point last_print_;
  size_t last_printed_bucket_ = 0;  // In units of 5 % (plain-line mode).
  bool printed_anything_ = false;
};

}  // namespace parallax
