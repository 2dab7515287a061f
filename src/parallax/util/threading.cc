#include "parallax/util/threading.h"

#include <pthread.h>
#include <sched.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <exception>
#include <mutex>
#include <thread>
#include <vector>

namespace parallax {
namespace {

// True on a pool thread, and on a caller while the pool runs its task.
thread_local bool t_in_pool = false;

// Worker threads kept for the life of the process: ParallelFor hands them its loop instead of
// starting and joining threads on every call (bundle adjustment makes a few calls per
// iteration, over a thousand in a templeRing run). One caller at a time: a second caller at
// the same moment, or a call from inside a body, starts threads of its own as before.
class WorkerPool {
 public:
  // Never destroyed: a thread still in a body when the process exits would otherwise be
  // joined from a static destructor. A forked child starts a new pool (its threads are gone).
  static WorkerPool& Instance() { return *Pointer(); }

  // Runs task() on `count` pool threads and on the calling thread, and returns once all have
  // returned. False, with nothing run, when the pool is in use or the caller is in one of its
  // tasks. `task` must not throw.
  bool TryRun(int count, const std::function<void()>& task) {
    if (t_in_pool) return false;
    std::unique_lock<std::mutex> caller(caller_mutex_, std::try_to_lock);
    if (!caller.owns_lock()) return false;
    {
      std::lock_guard<std::mutex> lock(mutex_);
      for (; num_threads_ < count; ++num_threads_) {
        std::thread(&WorkerPool::Loop, this, num_threads_).detach();
      }
      task_ = &task;
      num_wanted_ = count;
      num_running_.store(count, std::memory_order_release);
      generation_.fetch_add(1, std::memory_order_release);
    }
    wake_.notify_all();
    t_in_pool = true;
    task();
    t_in_pool = false;
    SpinWhile([this] { return num_running_.load(std::memory_order_acquire) != 0; });
    std::unique_lock<std::mutex> lock(mutex_);
    done_.wait(lock, [this] { return num_running_.load() == 0; });
    task_ = nullptr;
    return true;
  }

 private:
  WorkerPool() = default;

  // Spins while `busy()` and for at most kSpinMicroseconds. Bundle adjustment hands the
  // pool a few loops of a hundred microseconds or less per iteration, with a little serial
  // work between them: waking a sleeping thread through the kernel took longer than many
  // of those loops (and more in a virtual machine), so a thread that has just finished
  // polls before it sleeps. Long enough to span the serial work between the loops of a
  // local adjustment (solve, step, norms), which 50 us did not (docs/defaults.md,
  // "Threads that wait a millisecond"). Other callers hand the pool one loop per stage or per
  // batch, so the spin after them is lost once.
  template <typename Busy>
  static void SpinWhile(const Busy& busy) {
    constexpr auto kSpin = std::chrono::microseconds(kSpinMicroseconds);
    const auto start = std::chrono::steady_clock::now();
    for (int polls = 1; busy(); ++polls) {
#if defined(__x86_64__) || defined(__i386__)
      __builtin_ia32_pause();
#endif
      if (polls % 64 == 0 && std::chrono::steady_clock::now() - start > kSpin) return;
    }
  }

  void Loop(int index) {
    t_in_pool = true;
    uint64_t seen = 0;
    for (;;) {
      SpinWhile([&] { return generation_.load(std::memory_order_acquire) == seen; });
      std::unique_lock<std::mutex> lock(mutex_);
      wake_.wait(lock, [&] { return generation_.load() != seen; });
      seen = generation_.load();
      if (index >= num_wanted_) continue;
      const std::function<void()>* task = task_;
      lock.unlock();
      (*task)();
      lock.lock();
      if (num_running_.fetch_sub(1, std::memory_order_release) == 1) done_.notify_one();
    }
  }

  static constexpr int kSpinMicroseconds = 1000;

  // Made on first use, so that no static initialiser elsewhere can find it unmade.
  static WorkerPool*& Pointer() {
    static WorkerPool* pool = [] {
      pthread_atfork(nullptr, nullptr, [] { Pointer() = new WorkerPool; });
      return new WorkerPool;
    }();
    return pool;
  }
  std::mutex caller_mutex_;  // Held by the thread whose loop the pool runs.
  // Guards what follows (changed only under it; the two atomics are also read without it,
  // by spinning threads).
  std::mutex mutex_;
  std::condition_variable wake_, done_;
  int num_threads_ = 0;
  const std::function<void()>* task_ = nullptr;
  int num_wanted_ = 0;               // Pool threads that run the current task.
  std::atomic<int> num_running_{0};  // Of those, the ones not finished.
  std::atomic<uint64_t> generation_{0};
};

}  // namespace

int EffectiveNumThreads(int requested) {
  if (requested > 0) return requested;
  // The cores this thread may run on: a rank that mpirun or srun bound to some cores (or a
  // container's cpuset) has fewer than the machine, and as many threads as the machine would
  // share them.
  cpu_set_t allowed;
  CPU_ZERO(&allowed);
  if (sched_getaffinity(0, sizeof(allowed), &allowed) == 0) {
    const int count = CPU_COUNT(&allowed);
    if (count > 0) return count;
  }
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
  const std::function<void()> work = [&]() {
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
  if (!WorkerPool::Instance().TryRun(workers - 1, work)) {
    std::vector<std::thread> threads;
    for (int t = 0; t < workers - 1; ++t) threads.emplace_back(work);
    work();
    for (auto& thread : threads) thread.join();
  }
  if (first_error) std::rethrow_exception(first_error);
}

}  // namespace parallax
