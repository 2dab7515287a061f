#include "parallax/util/interrupt.h"

#include <gtest/gtest.h>

#include <csignal>

namespace parallax {
namespace {

TEST(Interrupt, PendingSignalThrowsWithWhatWasKeptAndTheShellsExitStatus) {
  SetPendingInterruptSignal(0);
  EXPECT_NO_THROW(ThrowIfInterrupted("nothing"));
  SetPendingInterruptSignal(SIGINT);
  try {
    ThrowIfInterrupted("features of 3 images stored");
    FAIL() << "no exception";
  } catch (const Interrupted& interrupted) {
    EXPECT_STREQ(interrupted.what(), "features of 3 images stored");
    EXPECT_EQ(interrupted.signal_number(), SIGINT);
    EXPECT_EQ(interrupted.ExitStatus(), 130);
  }
  SetPendingInterruptSignal(SIGTERM);
  try {
    ThrowIfInterrupted("");
  } catch (const Interrupted& interrupted) {
    EXPECT_EQ(interrupted.ExitStatus(), 143);
  }
  SetPendingInterruptSignal(0);
}

// In a child process (a death test): the first signal is recorded and the process goes on;
// the second ends it as if no handler had been installed.
TEST(InterruptDeathTest, FirstSignalIsRecordedSecondEndsTheProcess) {
  EXPECT_EXIT(
      {
        InstallInterruptHandlers();
        std::raise(SIGTERM);
        if (PendingInterruptSignal() != SIGTERM) std::_Exit(3);
        std::raise(SIGINT);
        std::_Exit(4);  // Not reached.
      },
      ::testing::KilledBySignal(SIGINT), "");
}

}  // namespace
}  // namespace parallax
