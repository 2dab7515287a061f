#include "parallax/util/file.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <stdexcept>

#include "parallax/util/check.h"

namespace parallax {
namespace {

TEST(File, AtomicWriteLeavesNoTempFileAndRoundTrips) {
  const auto dir = std::filesystem::temp_directory_path() / "parallax_file_test";
  std::filesystem::create_directories(dir);
  const auto path = dir / "out.txt";
  WriteTextFileAtomically(path, "hello\n");
  EXPECT_EQ(ReadFileToString(path), "hello\n");
  for (const auto& entry : std::filesystem::directory_iterator(dir)) {
    EXPECT_EQ(entry.path().filename(), "out.txt");
  }
  std::filesystem::remove_all(dir);
}

TEST(File, FailedWriterKeepsPreviousContent) {
  const auto dir = std::filesystem::temp_directory_path() / "parallax_file_test2";
  std::filesystem::create_directories(dir);
  const auto path = dir / "model.txt";
  WriteTextFileAtomically(path, "old");
  EXPECT_THROW(WriteFileAtomically(path,
                                   [](std::ostream& stream) {
                                     stream << "half";
                                     throw std::runtime_error("interrupted");
                                   }),
               std::runtime_error);
  EXPECT_EQ(ReadFileToString(path), "old");
  std::filesystem::remove_all(dir);
}

TEST(File, MissingFileNamesPath) {
  try {
    ReadFileToString("/nonexistent/parallax.txt");
    FAIL() << "expected InputError";
  } catch (const InputError& error) {
    EXPECT_NE(std::string(error.what()).find("/nonexistent/parallax.txt"), std::string::npos);
  }
}

TEST(File, SplitLinesDropsCarriageReturns) {
  const auto lines = SplitLines("a b\r\nc\r\n");
  ASSERT_EQ(lines.size(), 2u);
  EXPECT_EQ(lines[0], "a b");
  EXPECT_EQ(lines[1], "c");
  EXPECT_EQ(Trim("  x y \t"), "x y");
}

}  // namespace
}  // namespace parallax
