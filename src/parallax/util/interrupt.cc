#include "parallax/util/interrupt.h"

#include <atomic>
#include <csignal>
#include <mutex>

namespace parallax {
namespace {

// Written by the handler: a lock-free atomic is async-signal-safe.
std::atomic<int> pending_signal{0};
static_assert(std::atomic<int>::is_always_lock_free);

extern "C" void RecordSignal(int signal_number) {
  pending_signal.store(signal_number);
  // Back to the default actions (sigaction is async-signal-safe): a second signal of either
  // kind ends the process.
  struct sigaction default_action = {};
  default_action.sa_handler = SIG_DFL;
  sigemptyset(&default_action.sa_mask);
  sigaction(SIGINT, &default_action, nullptr);
  sigaction(SIGTERM, &default_action, nullptr);
}

}  // namespace

void InstallInterruptHandlers() {
  static std::once_flag once;
  std::call_once(once, [] {
    struct sigaction action = {};
    action.sa_handler = RecordSignal;
    sigemptyset(&action.sa_mask);
    action.sa_flags = SA_RESTART;
    sigaction(SIGINT, &action, nullptr);
    sigaction(SIGTERM, &action, nullptr);
  });
}

int PendingInterruptSignal() { return pending_signal.load(); }

void ThrowIfInterrupted(const std::string& what_was_kept) {
  const int signal_number = PendingInterruptSignal();
  if (signal_number != 0) throw Interrupted(signal_number, what_was_kept);
}

void SetPendingInterruptSignal(int signal_number) { pending_signal.store(signal_number); }

}  // namespace parallax
