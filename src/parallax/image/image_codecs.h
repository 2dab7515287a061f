#pragma once

#include <opencv2/core.hpp>
#include <string>
#include <string_view>

#include "parallax/image/image_reader.h"

namespace parallax {

// Image decoding and encoding on libjpeg(-turbo), libpng and libtiff directly, instead of
// OpenCV's imgcodecs: Debian's imgcodecs links GDAL, GDCM, OpenEXR and about 120 more
// libraries, which multiplied the process's resident memory before it read a pixel
// (docs/dependencies.md).

// Decodes a whole file of `format` into the layout cv::imdecode(IMREAD_UNCHANGED) gives:
// 8 or 16 bits per sample, 1, 3 or 4 channels, colour in BGR(A) order. Throws
// std::runtime_error with the codec's one-line message on corrupt or unsupported data.
cv::Mat DecodeImage(std::string_view bytes, ImageFormat format);

// PNG of an 8- or 16-bit image with 1, 3 (BGR) or 4 (BGRA) channels.
std::string EncodePng(const cv::Mat& image);

// Baseline JPEG of an 8-bit gray or BGR image; quality 1-100.
std::string EncodeJpeg(const cv::Mat& image, int quality);

}  // namespace parallax
