#include "parallax/util/progress.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <mutex>
#include <sstream>
#include <string>
#include <vector>

#include "parallax/util/file.h"
#include "parallax/util/logging.h"
#include "parallax/util/threading.h"

namespace parallax {
namespace {

class ProgressTest : public ::testing::Test {
 protected:
  void SetUp() override {
    saved_level_ = GetLogLevel();
    SetLogLevel(LogLevel::kInfo);
  }
  void TearDown() override { SetLogLevel(saved_level_); }
  LogLevel saved_level_ = LogLevel::kInfo;
};

TEST_F(ProgressTest, PlainLinesEveryFivePercent) {
  std::ostringstream stream;
  {
    ProgressReporter progress("matching", 200, &stream, /*is_terminal=*/false);
    for (int i = 0; i < 200; ++i) progress.Increment();
    EXPECT_EQ(progress.Done(), 200u);
  }
  const std::vector<std::string> lines = SplitLines(stream.str());
  ASSERT_EQ(lines.size(), 20u) << stream.str();
  EXPECT_EQ(lines[0].rfind("matching: 10/200 (", 0), 0u) << lines[0];
  EXPECT_NE(lines[0].find("/s, ETA "), std::string::npos) << lines[0];
  EXPECT_EQ(lines.back().rfind("matching: 200/200 (", 0), 0u) << lines.back();
  EXPECT_EQ(stream.str().find('\r'), std::string::npos);
}

TEST_F(ProgressTest, TerminalRewritesOneLine) {
  std::ostringstream stream;
  ProgressReporter progress("features", 3, &stream, /*is_terminal=*/true);
  progress.Increment(3);
  progress.Finish();
  progress.Finish();
  const std::string text = stream.str();
  // Every update starts with '\r'; only the final one ends the line.
  EXPECT_EQ(text.front(), '\r');
  EXPECT_EQ(std::count(text.begin(), text.end(), '\n'), 1);
  EXPECT_NE(text.rfind("features: 3/3 ("), std::string::npos) << text;
}

TEST_F(ProgressTest, UnfinishedRunPrintsItsLastState) {
  std::ostringstream stream;
  {
    ProgressReporter progress("features", 1000, &stream, /*is_terminal=*/false);
    progress.Increment(7);
  }
  const std::vector<std::string> lines = SplitLines(stream.str());
  ASSERT_EQ(lines.size(), 1u);
  EXPECT_EQ(lines[0].rfind("features: 7/1000 (", 0), 0u) << lines[0];
}

TEST_F(ProgressTest, SilentAboveInfo) {
  SetLogLevel(LogLevel::kWarning);
  std::ostringstream stream;
  {
    ProgressReporter progress("features", 10, &stream, /*is_terminal=*/false);
    for (int i = 0; i < 10; ++i) progress.Increment();
  }
  EXPECT_TRUE(stream.str().empty());
}

TEST_F(ProgressTest, IncrementIsThreadSafe) {
  std::ostringstream stream;
  ProgressReporter progress("pairs", 10000, &stream, /*is_terminal=*/false);
  ParallelFor(0, 10000, 4, [&](size_t) { progress.Increment(); });
  EXPECT_EQ(progress.Done(), 10000u);
  progress.Finish();
  const std::vector<std::string> lines = SplitLines(stream.str());
  EXPECT_EQ(lines.size(), 20u);
  EXPECT_EQ(lines.back().rfind("pairs: 10000/10000 (", 0), 0u);
}

TEST_F(ProgressTest, ListenerSeesEveryCountFromEveryThread) {
  std::mutex mutex;
  std::vector<size_t> counts;
  const ProgressListener previous =
      SetProgressListener([&](const std::string& label, size_t done, size_t total) {
        EXPECT_EQ(label, "pairs");
        EXPECT_EQ(total, 1000u);
        std::lock_guard<std::mutex> lock(mutex);
        counts.push_back(done);
      });
  EXPECT_FALSE(previous);
  std::ostringstream stream;
  {
    ProgressReporter progress("pairs", 1000, &stream, /*is_terminal=*/false);
    ParallelFor(0, 1000, 4, [&](size_t) { progress.Increment(); });
  }
  // Also with the stderr line silenced: the listener is not a log.
  SetLogLevel(LogLevel::kWarning);
  ProgressReporter("pairs", 1000, &stream, false).Increment(1000);
  SetLogLevel(LogLevel::kInfo);
  // Replaced by nothing, the listener hears no more.
  EXPECT_TRUE(SetProgressListener(previous));
  ProgressReporter("pairs", 1000, &stream, false).Increment();
  ASSERT_EQ(counts.size(), 1001u);
  std::sort(counts.begin(), counts.end() - 1);
  for (size_t i = 0; i < 1000; ++i) EXPECT_EQ(counts[i], i + 1);
  EXPECT_EQ(counts.back(), 1000u);
}

}  // namespace
}  // namespace parallax
