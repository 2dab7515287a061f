#include "parallax/util/threading.h"

#include <algorithm>
#include <atomic>
#include <exception>
#include <mutex>
#include <thread>
#include <vector>

namespace parallax {

int EffectiveNumThreads(int requested) {
  if (requested > 0) return requested;
  return std::max(1u, std::thread::hardware_concurrency());
}

void ParallelFor(size_t begin, size_t end, int num_threads,
                 const std::function<void(size_t)>& body) {
  if (end <= begin) return;
  const size_t count = end - begin;
  const int workers = static_cast<int>(std::min<size_t>(EffectiveNumThreads(num_threads), count));
  if (workers <= 1) {
    for (size_t i = begin; i < end; ++i) body(i);
    return;
  }
  std::atomic<size_t> next{begin};
  std::exception_ptr first_error;
  std::mutex error_mutex;
  auto work = [&]() {
    for (size_t i = next++; i < end; i = next++) {
      try {
        body(i);
      } catch (...) {
        std::lock_guard<std::mutex> lock(error_mutex);
        if (!first_error) first_error = std::current_exception();
        next = end;  // Stop handing out work.
      }
    }
  };
  std::vector<std::thread> threads;
  for (int t = 0; t < workers - 1; ++t) threads.emplace_back(work);
  work();
  for (auto& thread : threads) thread.join();
  if (first_error) std::rethrow_exception(first_error);
}

}  // namespace parallax
