#pragma once

#include <opencv2/core.hpp>
#include <optional>
#include <string_view>

namespace parallax {

// Decodes the PNGs cameras and renderers write, 8-bit gray, RGB or RGBA, not interlaced and
// without a transparency chunk, into what DecodeImage gives (colour in BGR(A) order), with
// libdeflate instead of libpng and zlib, which is faster (BM_DecodePng; docs/dependencies.md).
// Every chunk's CRC and the stream's Adler-32 are checked as libpng checks them. nullopt for any
// other PNG and for anything wrong in one of these, so that libpng decodes it or says what is
// wrong.
std::optional<cv::Mat> DecodeCommonPng(std::string_view bytes);

}  // namespace parallax
