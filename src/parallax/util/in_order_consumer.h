#pragma once

#include <condition_variable>
#include <cstddef>
#include <exception>
#include <functional>
#include <mutex>
#include <optional>
#include <thread>
#include <utility>
#include <vector>

namespace parallax {

// Hands values that worker threads produce out of order (value i of `count`) to `consume`
// in index order, on a thread of its own: the workers never wait for what consume does
// (a database write and its fsyncs), and consume never sees value i + 1 before value i.
//
//   InOrderConsumer<Result> writer(jobs.size(), [&](size_t i, Result& result) { ... });
//   ParallelFor(0, jobs.size(), threads, [&](size_t i) { writer.Put(i, Compute(i)); });
//   writer.Finish();
//
// Finish consumes the values up to the first index never put (after an interrupt, the
// workers' values that follow a gap are dropped) and rethrows what consume threw; once
// consume has thrown, Failed() is true, no further value is consumed, and the workers may
// stop early. The destructor finishes without rethrowing (the path of an exception already
// on its way).
template <typename T>
class InOrderConsumer {
 public:
  InOrderConsumer(size_t count, std::function<void(size_t index, T& value)> consume)
      : values_(count), consume_(std::move(consume)), thread_([this] { Run(); }) {}

  ~InOrderConsumer() { Stop(); }

  InOrderConsumer(const InOrderConsumer&) = delete;
  InOrderConsumer& operator=(const InOrderConsumer&) = delete;

  // Stores value `index` for the consumer; each index at most once, from any thread.
  void Put(size_t index, T value) {
    {
      const std::lock_guard<std::mutex> lock(mutex_);
      values_.at(index).emplace(std::move(value));
    }
    changed_.notify_one();
  }

  bool Failed() const {
    const std::lock_guard<std::mutex> lock(mutex_);
    return error_ != nullptr;
  }

  // Waits until every value put so far, up to the first gap, is consumed; rethrows the
  // consumer's exception. Call once the producers are done; Put may not follow.
  void Finish() {
    Stop();
    if (error_) std::rethrow_exception(error_);
  }

 private:
  void Run() {
    std::unique_lock<std::mutex> lock(mutex_);
    for (size_t next = 0; next < values_.size();) {
      changed_.wait(lock, [&] { return values_[next].has_value() || finishing_; });
      if (!values_[next].has_value()) return;  // Finishing at a gap.
      T value = std::move(*values_[next]);
      values_[next].reset();
      lock.unlock();
      try {
        consume_(next, value);
      } catch (...) {
        lock.lock();
        error_ = std::current_exception();
        return;
      }
      lock.lock();
      ++next;
    }
  }

  void Stop() {
    {
      const std::lock_guard<std::mutex> lock(mutex_);
      finishing_ = true;
    }
    changed_.notify_one();
    if (thread_.joinable()) thread_.join();
  }

  mutable std::mutex mutex_;
  std::condition_variable changed_;
  std::vector<std::optional<T>> values_;
  bool finishing_ = false;
  std::exception_ptr error_;
  std::function<void(size_t, T&)> consume_;
  std::thread thread_;  // Last: started once everything it reads is constructed.
};

}  // namespace parallax
