#include "parallax/image/image_codecs.h"

#include <gtest/gtest.h>

#include <opencv2/imgcodecs.hpp>
#include <stdexcept>
#include <string>
#include <vector>

namespace parallax {
namespace {

cv::Mat RandomImage(int depth, int channels) {
  cv::Mat image(37, 53, CV_MAKETYPE(depth, channels));
  cv::randu(image, 0, depth == CV_16U ? 65535 : 255);
  return image;
}

std::string OpenCvEncode(const std::string& extension, const cv::Mat& image) {
  std::vector<uchar> bytes;
  EXPECT_TRUE(cv::imencode(extension, image, bytes));
  return std::string(bytes.begin(), bytes.end());
}

cv::Mat OpenCvDecode(const std::string& bytes) {
  return cv::imdecode(std::vector<uchar>(bytes.begin(), bytes.end()), cv::IMREAD_UNCHANGED);
}

bool Identical(const cv::Mat& a, const cv::Mat& b) {
  return a.type() == b.type() && a.size() == b.size() && cv::norm(a, b, cv::NORM_INF) == 0;
}

// What OpenCV's encoders write, our decoders read exactly as OpenCV's decoders do.
TEST(ImageCodecs, DecodesWhatOpenCvDecodes) {
  struct Case {
    std::string extension;
    ImageFormat format;
    int depth;
    int channels;
  };
  const std::vector<Case> cases = {
      {".png", ImageFormat::kPng, CV_8U, 1},   {".png", ImageFormat::kPng, CV_8U, 3},
      {".png", ImageFormat::kPng, CV_8U, 4},   {".png", ImageFormat::kPng, CV_16U, 1},
      {".png", ImageFormat::kPng, CV_16U, 3},  {".png", ImageFormat::kPng, CV_16U, 4},
      {".tif", ImageFormat::kTiff, CV_8U, 1},  {".tif", ImageFormat::kTiff, CV_8U, 3},
      {".tif", ImageFormat::kTiff, CV_16U, 1}, {".tif", ImageFormat::kTiff, CV_16U, 3},
      {".bmp", ImageFormat::kBmp, CV_8U, 1},   {".bmp", ImageFormat::kBmp, CV_8U, 3},
      {".jpg", ImageFormat::kJpeg, CV_8U, 1},  {".jpg", ImageFormat::kJpeg, CV_8U, 3},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.extension + " depth " + std::to_string(c.depth) + " channels " +
                 std::to_string(c.channels));
    const std::string bytes = OpenCvEncode(c.extension, RandomImage(c.depth, c.channels));
    const cv::Mat ours = DecodeImage(bytes, c.format);
    EXPECT_TRUE(Identical(ours, OpenCvDecode(bytes)));
  }
}

TEST(ImageCodecs, PngRoundTripsExactly) {
  for (const int depth : {CV_8U, CV_16U}) {
    for (const int channels : {1, 3, 4}) {
      const cv::Mat image = RandomImage(depth, channels);
      const std::string png = EncodePng(image);
      EXPECT_TRUE(Identical(DecodeImage(png, ImageFormat::kPng), image));
      EXPECT_TRUE(Identical(OpenCvDecode(png), image));  // A standard PNG.
    }
  }
}

TEST(ImageCodecs, JpegIsCloseAtHighQuality) {
  cv::Mat image(64, 80, CV_8UC3);
  for (int y = 0; y < image.rows; ++y) {
    for (int x = 0; x < image.cols; ++x) {
      image.at<cv::Vec3b>(y, x) = cv::Vec3b(static_cast<uchar>(3 * x), static_cast<uchar>(4 * y),
                                            static_cast<uchar>(2 * (x + y)));
    }
  }
  const std::string jpeg = EncodeJpeg(image, 95);
  const cv::Mat decoded = DecodeImage(jpeg, ImageFormat::kJpeg);
  ASSERT_EQ(decoded.type(), CV_8UC3);
  EXPECT_LT(cv::norm(decoded, image, cv::NORM_L1) / image.total() / 3, 2.0);
  EXPECT_TRUE(Identical(decoded, OpenCvDecode(jpeg)));
  EXPECT_LT(EncodeJpeg(image, 20).size(), jpeg.size());
}

TEST(ImageCodecs, CorruptDataThrowsWithTheCodecsMessage) {
  const std::string png = EncodePng(RandomImage(CV_8U, 3));
  std::string corrupt = png;
  for (size_t i = 60; i < corrupt.size() - 20; ++i) corrupt[i] = static_cast<char>(i * 7);
  EXPECT_THROW(DecodeImage(corrupt, ImageFormat::kPng), std::runtime_error);
  EXPECT_THROW(DecodeImage(png.substr(0, 40), ImageFormat::kPng), std::runtime_error);
  EXPECT_THROW(DecodeImage("\xff\xd8\xff\xe0 not a jpeg", ImageFormat::kJpeg), std::runtime_error);
  EXPECT_THROW(DecodeImage("II*\0garbage", ImageFormat::kTiff), std::runtime_error);
  EXPECT_THROW(DecodeImage("BM short", ImageFormat::kBmp), std::runtime_error);
  try {
    DecodeImage(png.substr(0, 40), ImageFormat::kPng);
  } catch (const std::runtime_error& error) {
    EXPECT_NE(std::string(error.what()), "");
  }
  EXPECT_THROW(EncodePng(cv::Mat(4, 4, CV_32F)), std::runtime_error);
  EXPECT_THROW(EncodeJpeg(cv::Mat(4, 4, CV_16U), 90), std::runtime_error);
}

}  // namespace
}  // namespace parallax
