#include "parallax/util/run_lock.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <memory>
#include <string>

#include "parallax/util/check.h"
#include "parallax/util/file.h"
#include "parallax/util/test_dir.h"

namespace parallax {
namespace {

// flock(2) locks belong to the open file, so a second RunLock in the same process conflicts
// with the first exactly as a second process would.
TEST(RunLock, SecondHolderIsRefusedWithTheFirstOnesProcessId) {
  const test::ScopedTestDir dir("parallax_run_lock");
  const auto lock_path = OutputLockPath(dir.path());
  auto first = std::make_unique<RunLock>(lock_path, "out/");
  EXPECT_EQ(Trim(ReadFileToString(lock_path)), std::to_string(getpid()));
  try {
    RunLock second(lock_path, "out/");
    FAIL() << "the lock was taken twice";
  } catch (const InputError& error) {
    const std::string message = error.what();
    EXPECT_EQ(
        message.rfind(
            "out/: in use by another parallax run (process " + std::to_string(getpid()) + ")", 0),
        0u)
        << message;
    EXPECT_EQ(message.find('\n'), std::string::npos);
  }
  // Released with its holder: the lock file stays and is taken again.
  first.reset();
  EXPECT_NO_THROW(RunLock again(lock_path, "out/"));
}

TEST(RunLock, LockFilesSitBesideWhatTheyGuard) {
  EXPECT_EQ(DatabaseLockPath("out/database.db"), std::filesystem::path("out/database.db.lock"));
  EXPECT_EQ(OutputLockPath("out"), std::filesystem::path("out/.parallax.lock"));
}

TEST(RunLock, UncreatableLockFileNamesIt) {
  const test::ScopedTestDir dir("parallax_run_lock");
  const auto lock_path = dir.path() / "missing" / "db.lock";
  try {
    RunLock lock(lock_path, "db");
    FAIL() << "no error";
  } catch (const InputError& error) {
    EXPECT_NE(std::string(error.what()).find(lock_path.string()), std::string::npos);
  }
}

}  // namespace
}  // namespace parallax
