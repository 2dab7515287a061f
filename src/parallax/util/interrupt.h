#pragma once

#include <stdexcept>
#include <string>

namespace parallax {

// Ctrl-C (SIGINT) and kill (SIGTERM) stop a run at its next safe point instead of at once: the
// command line installs handlers that only record the signal, and the long loops (extraction,
// matching, mapping) check at points where everything done so far is committed to the database
// and no output is half-written. A signal is process-wide by nature, hence a process-wide flag.

// Installs the handlers (once per process). A second signal of either kind ends the process
// at once, as without handlers: the user who presses Ctrl-C twice means it.
void InstallInterruptHandlers();

// The signal received since the handlers were installed (SIGINT, SIGTERM), or 0.
int PendingInterruptSignal();

// Thrown at a safe point after a signal; what() says what the stage kept.
class Interrupted : public std::runtime_error {
 public:
  Interrupted(int signal_number, const std::string& what_was_kept)
      : std::runtime_error(what_was_kept), signal_number_(signal_number) {}
  int signal_number() const { return signal_number_; }
  // The conventional exit status of a process ended by the signal: 128 + its number.
  int ExitStatus() const { return 128 + signal_number_; }

 private:
  int signal_number_;
};

// Throws Interrupted(signal, what_was_kept) when a signal is pending.
void ThrowIfInterrupted(const std::string& what_was_kept);

// Records `signal_number` as if it had been received (0 clears it): how a host that owns the
// signals itself stops a run at its next safe point (the Python module, where Python's own
// handler receives Ctrl-C), and how tests simulate a signal.
void SetPendingInterruptSignal(int signal_number);

}  // namespace parallax
