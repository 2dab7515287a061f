#include "released_call.h"

#include <chrono>
#include <condition_variable>
#include <csignal>
#include <exception>
#include <mutex>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include "parallax/util/interrupt.h"
#include "parallax/util/progress.h"

namespace py = pybind11;

namespace parallax::python {
namespace {

// How often the waiting thread looks for progress and signals.
constexpr std::chrono::milliseconds kPollInterval(50);

struct ProgressCount {
  std::string stage;
  size_t done = 0;
  size_t total = 0;
};

// Counts from the worker's threads, latest per stage: a slow callback never falls behind.
class ProgressQueue {
 public:
  void Push(const std::string& stage, size_t done, size_t total) {
    std::lock_guard<std::mutex> lock(mutex_);
    for (ProgressCount& count : counts_) {
      if (count.stage == stage) {
        count.done = std::max(count.done, done);
        count.total = total;
        return;
      }
    }
    counts_.push_back({stage, done, total});
  }
  std::vector<ProgressCount> Take() {
    std::lock_guard<std::mutex> lock(mutex_);
    return std::exchange(counts_, {});
  }

 private:
  std::mutex mutex_;
  std::vector<ProgressCount> counts_;
};

// Installs the queue as the process's progress listener for its lifetime.
class ScopedProgressListener {
 public:
  explicit ScopedProgressListener(ProgressQueue* queue)
      : previous_(SetProgressListener([queue](const std::string& stage, size_t done, size_t total) {
          queue->Push(stage, done, total);
        })) {}
  ~ScopedProgressListener() { SetProgressListener(std::move(previous_)); }
  ScopedProgressListener(const ScopedProgressListener&) = delete;
  ScopedProgressListener& operator=(const ScopedProgressListener&) = delete;

 private:
  ProgressListener previous_;
};

}  // namespace

void RunReleasingGil(const std::function<void()>& work, const py::object& progress) {
  ProgressQueue queue;
  const ScopedProgressListener listener(&queue);
  SetPendingInterruptSignal(0);

  std::mutex mutex;
  std::condition_variable finished_changed;
  bool finished = false;
  std::exception_ptr failure;
  std::thread worker([&] {
    try {
      work();
    } catch (...) {
      failure = std::current_exception();
    }
    std::lock_guard<std::mutex> lock(mutex);
    finished = true;
    finished_changed.notify_all();
  });

  const auto deliver_progress = [&] {
    for (const ProgressCount& count : queue.Take()) {
      if (!progress.is_none()) progress(count.stage, count.done, count.total);
    }
  };
  try {
    bool done = false;
    while (!done) {
      {
        py::gil_scoped_release release;
        std::unique_lock<std::mutex> lock(mutex);
        done = finished_changed.wait_for(lock, kPollInterval, [&] { return finished; });
      }
      deliver_progress();
      if (PyErr_CheckSignals() != 0) throw py::error_already_set();
    }
  } catch (...) {
    // Ctrl-C or the callback's exception: the work stops at its next safe point.
    SetPendingInterruptSignal(SIGINT);
    {
      py::gil_scoped_release release;
      worker.join();
    }
    SetPendingInterruptSignal(0);
    throw;
  }
  worker.join();
  deliver_progress();
  if (failure) std::rethrow_exception(failure);
}

}  // namespace parallax::python
