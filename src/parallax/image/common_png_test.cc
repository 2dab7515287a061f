#include "parallax/image/common_png.h"

#include <gtest/gtest.h>
#include <libdeflate.h>

#include <cstdint>
#include <cstdlib>
#include <opencv2/imgproc.hpp>
#include <string>
#include <vector>

#include "parallax/image/image_codecs.h"

namespace parallax {
namespace {

void AppendBigEndian32(uint32_t value, std::string* out) {
  for (int shift = 24; shift >= 0; shift -= 8) out->push_back(static_cast<char>(value >> shift));
}

void AppendChunk(const std::string& type, const std::string& body, std::string* png) {
  AppendBigEndian32(static_cast<uint32_t>(body.size()), png);
  const std::string typed = type + body;
  png->append(typed);
  AppendBigEndian32(libdeflate_crc32(0, typed.data(), typed.size()), png);
}

std::string Header(int width, int height, int bit_depth, int color_type, int interlace = 0) {
  std::string body;
  AppendBigEndian32(width, &body);
  AppendBigEndian32(height, &body);
  body += {static_cast<char>(bit_depth), static_cast<char>(color_type), 0, 0,
           static_cast<char>(interlace)};
  return body;
}

int PaethPredictor(int a, int b, int c) {
  const int p = a + b - c, pa = std::abs(p - a), pb = std::abs(p - b), pc = std::abs(p - c);
  return pa <= pb && pa <= pc ? a : (pb <= pc ? b : c);
}

// Row y filtered with filter type y % 5 (the PNG specification's definitions, written out
// here independently of the decoder), zlib-compressed, split over two IDAT chunks.
std::string FilteredImageData(const cv::Mat& image) {
  const int bpp = image.channels();
  const int length = image.cols * bpp;
  std::string raw;
  const std::vector<uint8_t> zeros(length, 0);
  for (int y = 0; y < image.rows; ++y) {
    const uint8_t* row = image.ptr<uint8_t>(y);
    const uint8_t* prior = y == 0 ? zeros.data() : image.ptr<uint8_t>(y - 1);
    const int filter = y % 5;
    raw.push_back(static_cast<char>(filter));
    for (int x = 0; x < length; ++x) {
      const int a = x >= bpp ? row[x - bpp] : 0, b = prior[x], c = x >= bpp ? prior[x - bpp] : 0;
      const int predictor = filter == 0   ? 0
                            : filter == 1 ? a
                            : filter == 2 ? b
                            : filter == 3 ? (a + b) / 2
                                          : PaethPredictor(a, b, c);
      raw.push_back(static_cast<char>(row[x] - predictor));
    }
  }
  libdeflate_compressor* compressor = libdeflate_alloc_compressor(6);
  std::string compressed(libdeflate_zlib_compress_bound(compressor, raw.size()), '\0');
  compressed.resize(libdeflate_zlib_compress(compressor, raw.data(), raw.size(), compressed.data(),
                                             compressed.size()));
  libdeflate_free_compressor(compressor);
  return compressed;
}

// A PNG of `image` (channels in the file's order: gray, RGB or RGBA), with `extra` chunks
// (type, body) after the header.
std::string MakePng(const cv::Mat& image,
                    const std::vector<std::pair<std::string, std::string>>& extra = {}) {
  const int color_type = image.channels() == 1 ? 0 : image.channels() == 3 ? 2 : 6;
  std::string png = "\x89PNG\r\n\x1a\n";
  AppendChunk("IHDR", Header(image.cols, image.rows, 8, color_type), &png);
  for (const auto& [type, body] : extra) AppendChunk(type, body, &png);
  const std::string data = FilteredImageData(image);
  AppendChunk("IDAT", data.substr(0, data.size() / 2), &png);
  AppendChunk("IDAT", data.substr(data.size() / 2), &png);
  AppendChunk("IEND", "", &png);
  return png;
}

cv::Mat RandomImage(int channels) {
  cv::Mat image(29, 41, CV_8UC(channels));
  cv::randu(image, 0, 256);
  return image;
}

bool Identical(const cv::Mat& a, const cv::Mat& b) {
  return a.type() == b.type() && a.size() == b.size() && cv::norm(a, b, cv::NORM_INF) == 0;
}

// Every filter type in every layout, against the pixels the file was made from, colour in
// BGR(A) order as DecodeImage gives it.
TEST(CommonPng, UndoesEveryFilterTypeInEveryLayout) {
  for (const int channels : {1, 3, 4}) {
    SCOPED_TRACE(channels);
    const cv::Mat image = RandomImage(channels);
    const std::optional<cv::Mat> decoded = DecodeCommonPng(MakePng(image));
    ASSERT_TRUE(decoded.has_value());
    cv::Mat expected = image.clone();
    if (channels == 3) cv::cvtColor(image, expected, cv::COLOR_RGB2BGR);
    if (channels == 4) cv::cvtColor(image, expected, cv::COLOR_RGBA2BGRA);
    EXPECT_TRUE(Identical(*decoded, expected));
  }
}

// Chunks libpng skips for these layouts are skipped here too.
TEST(CommonPng, SkipsAncillaryChunksAndASuggestedPalette) {
  const cv::Mat image = RandomImage(3);
  const std::string png = MakePng(image, {{"tEXt", std::string("Comment\0made in a test", 22)},
                                          {"PLTE", std::string("\x01\x02\x03\x04\x05\x06", 6)}});
  const std::optional<cv::Mat> decoded = DecodeCommonPng(png);
  ASSERT_TRUE(decoded.has_value());
  EXPECT_TRUE(Identical(*decoded, DecodeImage(MakePng(image), ImageFormat::kPng)));
}

// Other layouts and damaged files are libpng's: nullopt, never a guess.
TEST(CommonPng, LeavesOtherLayoutsAndDamagedFilesToLibpng) {
  const cv::Mat image = RandomImage(3);
  const std::string good = MakePng(image);
  ASSERT_TRUE(DecodeCommonPng(good).has_value());

  std::string sixteen_bits = "\x89PNG\r\n\x1a\n";
  AppendChunk("IHDR", Header(4, 4, 16, 2), &sixteen_bits);
  EXPECT_FALSE(DecodeCommonPng(sixteen_bits).has_value());
  std::string interlaced = "\x89PNG\r\n\x1a\n";
  AppendChunk("IHDR", Header(4, 4, 8, 2, /*interlace=*/1), &interlaced);
  EXPECT_FALSE(DecodeCommonPng(interlaced).has_value());
  std::string palette = "\x89PNG\r\n\x1a\n";
  AppendChunk("IHDR", Header(4, 4, 8, 3), &palette);
  EXPECT_FALSE(DecodeCommonPng(palette).has_value());

  EXPECT_FALSE(DecodeCommonPng(MakePng(image, {{"tRNS", std::string(6, '\0')}})).has_value());
  EXPECT_FALSE(DecodeCommonPng(MakePng(image, {{"ABCD", "critical"}})).has_value());
  EXPECT_FALSE(DecodeCommonPng(MakePng(RandomImage(1), {{"PLTE", "\x01\x02\x03"}})).has_value());

  std::string bad_crc = good;
  bad_crc[bad_crc.size() / 2] ^= 0x10;  // Inside the image data: its chunk's CRC fails.
  EXPECT_FALSE(DecodeCommonPng(bad_crc).has_value());
  for (const size_t cut : {size_t{7}, size_t{20}, good.size() / 2, good.size() - 1}) {
    EXPECT_FALSE(DecodeCommonPng(good.substr(0, cut)).has_value()) << cut;
  }
  EXPECT_FALSE(DecodeCommonPng("not a PNG at all").has_value());
}

// Image data that does not fill the image, or a filter type PNG does not have, with every
// chunk intact.
TEST(CommonPng, LeavesShortDataAndUnknownFiltersToLibpng) {
  const cv::Mat image = RandomImage(1);
  const std::string header = Header(image.cols, image.rows + 1, 8, 0);
  std::string short_data = "\x89PNG\r\n\x1a\n";
  AppendChunk("IHDR", header, &short_data);
  AppendChunk("IDAT", FilteredImageData(image), &short_data);
  AppendChunk("IEND", "", &short_data);
  EXPECT_FALSE(DecodeCommonPng(short_data).has_value());

  cv::Mat one_row = image.row(0).clone();
  std::string raw(1, '\x05');  // Filter type 5.
  raw.append(reinterpret_cast<const char*>(one_row.data), one_row.cols);
  libdeflate_compressor* compressor = libdeflate_alloc_compressor(1);
  std::string compressed(libdeflate_zlib_compress_bound(compressor, raw.size()), '\0');
  compressed.resize(libdeflate_zlib_compress(compressor, raw.data(), raw.size(), compressed.data(),
                                             compressed.size()));
  libdeflate_free_compressor(compressor);
  std::string unknown_filter = "\x89PNG\r\n\x1a\n";
  AppendChunk("IHDR", Header(one_row.cols, 1, 8, 0), &unknown_filter);
  AppendChunk("IDAT", compressed, &unknown_filter);
  AppendChunk("IEND", "", &unknown_filter);
  EXPECT_FALSE(DecodeCommonPng(unknown_filter).has_value());
  EXPECT_THROW(DecodeImage(unknown_filter, ImageFormat::kPng), std::runtime_error);
}

}  // namespace
}  // namespace parallax
