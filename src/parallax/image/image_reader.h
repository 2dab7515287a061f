#pragma once

#include <cstdint>
#include <filesystem>
#include <opencv2/core.hpp>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

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

// The same two from bytes in memory (a file's head, or all of it).
ImageFormat DetectImageFormatFromBytes(std::string_view bytes);
std::optional<ImageSize> ReadImageSizeFromBytes(std::string_view bytes);

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
  // Red, green and blue of the pixel that contains (x, y), with pixel centres at +0.5 (the
  // keypoints' convention), or of the nearest border pixel when (x, y) lies outside (SIFT can
  // refine a keypoint past the border: one in 70,000 on templeRing). False only for an empty
  // image or a non-finite position.
  bool RgbAt(double x, double y, uint8_t rgb[3]) const;
};

// Reads by content. Throws InputError "<path>: <reason>" (not an image, truncated, too large).
Bitmap ReadBitmap(const std::filesystem::path& path, const ImageReaderOptions& options = {});
// Decodes a whole image file held in memory; `source` starts every InputError message. The
// header's size is checked against max_image_pixels before any decoding.
Bitmap DecodeBitmap(std::string_view bytes, const std::filesystem::path& source,
                    const ImageReaderOptions& options = {});

// A file that ListImageFiles left out although its name says it is an image, and why.
struct RejectedImageFile {
  std::filesystem::path path;
  std::string reason;
};

// Files of `dir` (not recursive) that look like images by content, sorted by name. Files
// named like images (.jpg, .jpeg, .png, .tif, .tiff, .bmp, any case) that are not images by
// content (empty, text) are appended to `rejected` when given, so callers can warn about them.
std::vector<std::filesystem::path> ListImageFiles(
    const std::filesystem::path& dir, std::vector<RejectedImageFile>* rejected = nullptr);

}  // namespace parallax
