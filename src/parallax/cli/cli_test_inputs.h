#pragma once

// Bad inputs made at test time and the checks of what a user must see (header only, for the
// cli/*_test.cc end-to-end tests).
#include <gtest/gtest.h>
#include <sqlite3.h>

#include <array>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <optional>
#include <string>
#include <vector>

#include "parallax/cli/cli_test_process.h"
#include "parallax/util/file.h"

namespace parallax::test {

inline void WriteBytes(const fs::path& path, const std::string& bytes) {
  std::ofstream stream(path, std::ios::binary | std::ios::trunc);
  stream.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
  ASSERT_TRUE(stream.good()) << path;
}

inline std::string ReadBytes(const fs::path& path) { return ReadFileToString(path); }

// The first column of the first row of `sql` on a database opened read-only (a run being
// watched may hold it open for writing); nullopt while the file, its schema or the row does
// not exist.
inline std::optional<std::string> QueryFirstValue(const fs::path& database,
                                                  const std::string& sql) {
  std::error_code error;
  if (!fs::exists(database, error)) return std::nullopt;
  sqlite3* db = nullptr;
  std::optional<std::string> value;
  if (sqlite3_open_v2(database.c_str(), &db, SQLITE_OPEN_READONLY, nullptr) == SQLITE_OK) {
    sqlite3_busy_timeout(db, 1000);
    sqlite3_stmt* statement = nullptr;
    if (sqlite3_prepare_v2(db, sql.c_str(), -1, &statement, nullptr) == SQLITE_OK &&
        sqlite3_step(statement) == SQLITE_ROW) {
      const unsigned char* text = sqlite3_column_text(statement, 0);
      value = text != nullptr ? reinterpret_cast<const char*>(text) : "";
    }
    sqlite3_finalize(statement);
  }
  sqlite3_close_v2(db);
  return value;
}

// `text` with the first `from` replaced by `to`; a test failure when `from` is not in it (the
// malformed-file cases start from a valid file and must change it).
inline std::string Replace(std::string text, const std::string& from, const std::string& to) {
  const size_t pos = text.find(from);
  EXPECT_NE(pos, std::string::npos) << from;
  if (pos != std::string::npos) text.replace(pos, from.size(), to);
  return text;
}

inline std::string EncodeImage(const std::string& extension, const cv::Mat& image) {
  std::vector<uint8_t> buffer;
  EXPECT_TRUE(cv::imencode(extension, image, buffer));
  return std::string(buffer.begin(), buffer.end());
}

// Random discs on a random background: textured, and sharing nothing with another seed.
inline cv::Mat RandomTexture(int width, int height, uint64_t seed) {
  cv::RNG rng(seed);
  cv::Mat image(height, width, CV_8UC3,
                cv::Scalar(rng.uniform(0, 256), rng.uniform(0, 256), rng.uniform(0, 256)));
  for (int k = 0; k < width * height / 80; ++k) {
    const cv::Point center(rng.uniform(0, width), rng.uniform(0, height));
    cv::circle(image, center, rng.uniform(2, 12),
               cv::Scalar(rng.uniform(0, 256), rng.uniform(0, 256), rng.uniform(0, 256)),
               cv::FILLED);
  }
  return image;
}

inline uint32_t Crc32(const std::string& bytes) {
  uint32_t crc = 0xffffffffu;
  for (const char c : bytes) {
    crc ^= static_cast<uint8_t>(c);
    for (int bit = 0; bit < 8; ++bit) crc = (crc >> 1) ^ (0xedb88320u & (0u - (crc & 1u)));
  }
  return ~crc;
}

inline void PutBigEndian(uint32_t value, int num_bytes, std::string* bytes, size_t offset) {
  for (int i = 0; i < num_bytes; ++i) {
    (*bytes)[offset + i] = static_cast<char>((value >> (8 * (num_bytes - 1 - i))) & 0xff);
  }
}

// A PNG whose IHDR claims another size (with a valid chunk CRC, so decoders believe it).
inline std::string WithPngSize(std::string png, uint32_t width, uint32_t height) {
  PutBigEndian(width, 4, &png, 16);
  PutBigEndian(height, 4, &png, 20);
  PutBigEndian(Crc32(png.substr(12, 17)), 4, &png, 29);
  return png;
}

// A JPEG whose frame header (SOFn) claims another size.
inline std::string WithJpegSize(std::string jpeg, uint16_t width, uint16_t height) {
  size_t pos = 2;
  while (pos + 9 < jpeg.size() && static_cast<uint8_t>(jpeg[pos]) == 0xff) {
    const uint8_t marker = static_cast<uint8_t>(jpeg[pos + 1]);
    if (marker >= 0xc0 && marker <= 0xcf && marker != 0xc4 && marker != 0xc8 && marker != 0xcc) {
      PutBigEndian(height, 2, &jpeg, pos + 5);
      PutBigEndian(width, 2, &jpeg, pos + 7);
      return jpeg;
    }
    pos += 2 + ((static_cast<uint8_t>(jpeg[pos + 2]) << 8) | static_cast<uint8_t>(jpeg[pos + 3]));
  }
  ADD_FAILURE() << "no frame header found";
  return jpeg;
}

inline std::vector<std::string> LinesStartingWith(const std::string& text,
                                                  const std::string& prefix) {
  std::vector<std::string> lines;
  for (const std::string& line : SplitLines(text)) {
    if (line.rfind(prefix, 0) == 0) lines.push_back(line);
  }
  return lines;
}

// The run ended by itself with exit code 1 and exactly one error line, "error: <names>...",
// that contains `reason`.
inline void ExpectFailsWithOneLineError(const ProcessResult& result, const std::string& names,
                                        const std::string& reason) {
  EXPECT_EQ(result.signal, 0) << "killed by signal " << result.signal << "\n" << result.err;
  EXPECT_FALSE(result.timed_out) << result.err;
  EXPECT_EQ(result.exit_code, 1) << result.err;
  const std::vector<std::string> errors = LinesStartingWith(result.err, "error: ");
  ASSERT_EQ(errors.size(), 1u) << result.err;
  EXPECT_EQ(errors[0].rfind("error: " + names, 0), 0u) << errors[0];
  EXPECT_NE(errors[0].find(reason), std::string::npos) << errors[0];
}

// Exactly one warning line names `path` (as "<path>: ") and it gives `reason`.
inline void ExpectOneWarningNaming(const std::string& err, const fs::path& path,
                                   const std::string& reason) {
  std::vector<std::string> lines;
  for (const std::string& line : LinesStartingWith(err, "warning: ")) {
    if (line.find(path.string() + ": ") != std::string::npos) lines.push_back(line);
  }
  ASSERT_EQ(lines.size(), 1u) << "warnings naming " << path << ":\n" << err;
  EXPECT_NE(lines[0].find(reason), std::string::npos) << lines[0];
}

// No file of `dir` (recursively) is a temporary left by an interrupted atomic write.
inline void ExpectNoTemporaryFiles(const fs::path& dir) {
  std::error_code error;
  if (!fs::exists(dir, error)) return;
  for (const auto& entry : fs::recursive_directory_iterator(dir, error)) {
    const std::string name = entry.path().filename().string();
    EXPECT_EQ(name.find(".tmp-"), std::string::npos) << entry.path();
    EXPECT_EQ(name.find(".old-"), std::string::npos) << entry.path();
  }
}

// A failed run left no model, point cloud, summary or temporary file (only the database).
inline void ExpectNoPartialOutput(const fs::path& out) {
  EXPECT_FALSE(fs::exists(out / "sparse"));
  EXPECT_FALSE(fs::exists(out / "summary.json"));
  EXPECT_FALSE(fs::exists(out / "points.ply"));
  EXPECT_FALSE(fs::exists(out / "report.html"));
  ExpectNoTemporaryFiles(out);
}

}  // namespace parallax::test
