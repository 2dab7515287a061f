#include "parallax/util/content_hash.h"

#include <gtest/gtest.h>

#include <fstream>
#include <string>

#include "parallax/util/check.h"
#include "parallax/util/test_dir.h"

namespace parallax {
namespace {

// Digests as `xxh128sum` (Debian's xxhash package) prints them.
TEST(ContentHash, MatchesTheReferenceDigests) {
  EXPECT_EQ(HashBytes(""), "99aa06d3014798d86001c324468d497f");
  EXPECT_EQ(HashBytes("abc"), "06b05ab6733a618578af5f94892f3950");
}

TEST(ContentHash, FileDigestIsTheDigestOfItsBytesAcrossBlocks) {
  const test::ScopedTestDir dir("parallax_content_hash");
  std::string bytes;
  for (int i = 0; i < 200000; ++i) bytes.push_back(static_cast<char>((i * 7919) % 251));
  const auto path = dir.path() / "file.bin";
  std::ofstream(path, std::ios::binary) << bytes;
  EXPECT_EQ(HashFile(path), HashBytes(bytes));
  // One byte changed anywhere, here in the last block, changes the digest.
  bytes[150000] ^= 1;
  EXPECT_NE(HashFile(path), HashBytes(bytes));
}

TEST(ContentHash, UnreadableFileNamesThePath) {
  const test::ScopedTestDir dir("parallax_content_hash");
  const auto missing = dir.path() / "missing.png";
  try {
    HashFile(missing);
    FAIL() << "no error";
  } catch (const InputError& error) {
    EXPECT_NE(std::string(error.what()).find(missing.string()), std::string::npos);
  }
}

}  // namespace
}  // namespace parallax
