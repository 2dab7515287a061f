#pragma once

#include <cstdint>
#include <filesystem>
#include <opencv2/core.hpp>
#include <optional>
#include <string>

namespace parallax {

enum class ImageFormat { kUnknown, kPng, kJpeg, kTiff, kBmp };

// The format from the file's first bytes (magic numbers), whatever its extension says.
ImageFormat DetectImageFormat(const std::filesystem::path& path);

// Width and height read from the header alone (no decoding); nullopt when unreadable.
struct ImageSize {
  int width = 0;
  int height = 0;
};
std::optional<ImageSize> ReadImageSize(const std::filesystem::path& path);

struct ImageReaderOptions {
  // Refuse images with more pixels than this before decoding them.
  int64_t max_image_pixels = 100'000'000;
  void Check() const;
};

// An image in memory: 8-bit BGR colour and 8-bit gray (16-bit, RGBA and gray inputs are
// converted).
struct Bitmap {
  cv::Mat color;  // CV_8UC3, BGR
  cv::Mat gray;   // CV_8UC1
  int Width() const { return gray.cols; }
  int Height() const { return gray.rows; }
};

// Reads by content. Throws InputError "<path>: <reason>" (not an image, truncated, too large).
Bitmap ReadBitmap(const std::filesystem::path& path, const ImageReaderOptions& options = {});

// Files of `dir` (not recursive) that look like images by content, sorted by name.
std::vector<std::filesystem::path> ListImageFiles(const std::filesystem::path& dir);

}  // namespace parallax
