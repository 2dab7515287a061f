#include "parallax/util/progress.h"

#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <iostream>
#include <memory>
#include <sstream>
#include <utility>

#include "parallax/util/logging.h"

namespace parallax {
namespace {
// Terminal redraws at most this often; plain lines at least every 5 % or this often.
constexpr double kTerminalIntervalSeconds = 0.1;
constexpr double kPlainIntervalSeconds = 10.0;
constexpr size_t kPlainBuckets = 20;  // 5 % steps.

std::mutex listener_mutex;
// Shared so that a count being reported keeps its listener alive while it is replaced.
std::shared_ptr<const ProgressListener> listener;

std::shared_ptr<const ProgressListener> CurrentListener() {
  std::lock_guard<std::mutex> lock(listener_mutex);
  return listener;
}
}  // namespace

ProgressListener SetProgressListener(ProgressListener new_listener) {
  std::shared_ptr<const ProgressListener> replacement;
  if (new_listener) replacement = std::make_shared<const ProgressListener>(std::move(new_listener));
  std::lock_guard<std::mutex> lock(listener_mutex);
  std::shared_ptr<const ProgressListener> previous = std::exchange(listener, replacement);
  return previous ? *previous : ProgressListener();
}

ProgressReporter::ProgressReporter(std::string label, size_t total)
    : ProgressReporter(std::move(label), total, &std::cerr, isatty(fileno(stderr)) != 0) {}

ProgressReporter::ProgressReporter(std::string label, size_t total, std::ostream* stream,
                                   bool is_terminal)
    : label_(std::move(label)),
      total_(total),
      stream_(stream),
      is_terminal_(is_terminal),
      enabled_(LogEnabled(LogLevel::kInfo) && total > 0),
      start_(Clock::now()),
      last_print_(start_) {}

ProgressReporter::~ProgressReporter() { Finish(); }

size_t ProgressReporter::Done() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return done_;
}

void ProgressReporter::Increment(size_t count) {
  size_t done = 0;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    done_ += count;
    done = done_;
    MaybePrintLocked();
  }
  // Outside the lock: the listener may take its own locks (the Python module's queue).
  if (const std::shared_ptr<const ProgressListener> current = CurrentListener()) {
    (*current)(label_, done, total_);
  }
}

void ProgressReporter::MaybePrintLocked() {
  if (!enabled_ || finished_) return;
  const Clock::time_point now = Clock::now();
  const double since_print = std::chrono::duration<double>(now - last_print_).count();
  if (is_terminal_) {
    if (since_print >= kTerminalIntervalSeconds || done_ >= total_) PrintLocked(false);
    return;
  }
  const size_t bucket = std::min(done_, total_) * kPlainBuckets / total_;
  if (bucket > last_printed_bucket_ || since_print >= kPlainIntervalSeconds) {
    last_printed_bucket_ = bucket;
    PrintLocked(false);
  }
}

void ProgressReporter::Finish() {
  std::lock_guard<std::mutex> lock(mutex_);
  if (finished_) return;
  finished_ = true;
  if (!enabled_) return;
  // A terminal line always ends with the final count and a newline; plain output only
  // adds a line when the last one printed was not already the final state.
  if (is_terminal_) {
    PrintLocked(true);
  } else if (!printed_anything_ || last_printed_bucket_ < kPlainBuckets) {
    PrintLocked(true);
  }
}

void ProgressReporter::PrintLocked(bool final_line) {
  const Clock::time_point now = Clock::now();
  const double elapsed = std::chrono::duration<double>(now - start_).count();
  std::ostringstream line;
  line << label_ << ": " << done_ << "/" << total_;
  const double rate = elapsed > 0 ? done_ / elapsed : 0.0;
  line.setf(std::ios::fixed);
  line.precision(rate < 10 ? 2 : 1);
  line << " (" << rate << "/s";
  if (done_ < total_ && rate > 0) {
    line << ", ETA " << static_cast<long>(std::ceil((total_ - done_) / rate)) << "s";
  } else if (done_ >= total_) {
    line.precision(1);
    line << ", " << elapsed << "s";
  }
  line << ")";
  if (is_terminal_) {
    // Clear to the end of the line so a shorter line leaves no stale characters.
    *stream_ << "\r" << line.str() << "\033[K";
    if (final_line) *stream_ << "\n";
  } else {
    *stream_ << line.str() << "\n";
  }
  stream_->flush();
  last_print_ = now;
  printed_anything_ = true;
}

}  // namespace parallax
