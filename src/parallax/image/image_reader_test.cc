#include "parallax/image/image_reader.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <fstream>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "parallax/math/random.h"
#include "parallax/util/check.h"
#include "parallax/util/test_dir.h"

namespace parallax {
namespace {

namespace fs = std::filesystem;

class ImageReaderTest : public ::testing::Test {
 protected:
  // A colour image with structure in every channel, so channel swaps would show.
  static cv::Mat TestImage(int width, int height, int type = CV_8UC3) {
    cv::Mat image(height, width, type);
    const int channels = image.channels();
    const double max_value = image.depth() == CV_16U ? 65535.0 : 255.0;
    for (int y = 0; y < height; ++y) {
      for (int x = 0; x < width; ++x) {
        for (int c = 0; c < channels; ++c) {
          const double value = std::fmod(17.0 * x + 31.0 * y + 67.0 * c, 256.0) / 255.0;
          if (image.depth() == CV_16U) {
            image.ptr<uint16_t>(y)[x * channels + c] = static_cast<uint16_t>(value * max_value);
          } else {
            image.ptr<uint8_t>(y)[x * channels + c] = static_cast<uint8_t>(value * max_value);
          }
        }
      }
    }
    return image;
  }

  fs::path Write(const std::string& name, const cv::Mat& image, const std::string& extension) {
    std::vector<uint8_t> bytes;
    EXPECT_TRUE(cv::imencode(extension, image, bytes));
    return WriteBytes(name, std::string(bytes.begin(), bytes.end()));
  }

  fs::path WriteBytes(const std::string& name, const std::string& bytes) {
    const fs::path path = dir_ / name;
    std::ofstream stream(path, std::ios::binary);
    stream.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
    return path;
  }

  static std::string ReadBytes(const fs::path& path) {
    std::ifstream stream(path, std::ios::binary);
    return std::string(std::istreambuf_iterator<char>(stream), {});
  }

  // Expects ReadBitmap to throw InputError "<path>: ..." mentioning `reason`.
  static void ExpectInputError(const fs::path& path, const std::string& reason,
                               const ImageReaderOptions& options = {}) {
    try {
      ReadBitmap(path, options);
      ADD_FAILURE() << "no exception for " << path;
    } catch (const InputError& error) {
      const std::string message = error.what();
      EXPECT_EQ(message.rfind(path.string() + ": ", 0), 0u) << message;
      EXPECT_NE(message.find(reason), std::string::npos) << message;
    }
  }

  static bool Equal(const cv::Mat& a, const cv::Mat& b) {
    return a.size() == b.size() && a.type() == b.type() && cv::norm(a, b, cv::NORM_INF) == 0;
  }

  const test::ScopedTestDir scoped_dir_{"parallax_image_reader"};
  const fs::path dir_ = scoped_dir_.path();
};

TEST_F(ImageReaderTest, DetectsFormatAndSizeOfEachFormat) {
  const cv::Mat image = TestImage(37, 23);
  const std::vector<std::pair<std::string, ImageFormat>> cases = {{".png", ImageFormat::kPng},
                                                                  {".jpg", ImageFormat::kJpeg},
                                                                  {".bmp", ImageFormat::kBmp},
                                                                  {".tif", ImageFormat::kTiff}};
  for (const auto& [extension, format] : cases) {
    SCOPED_TRACE(extension);
    const fs::path path = Write("image" + extension, image, extension);
    EXPECT_EQ(DetectImageFormat(path), format);
    const auto size = ReadImageSize(path);
    ASSERT_TRUE(size.has_value());
    EXPECT_EQ(size->width, 37);
    EXPECT_EQ(size->height, 23);
    const Bitmap bitmap = ReadBitmap(path);
    EXPECT_EQ(bitmap.Width(), 37);
    EXPECT_EQ(bitmap.Height(), 23);
    EXPECT_EQ(bitmap.color.type(), CV_8UC3);
    EXPECT_EQ(bitmap.gray.type(), CV_8UC1);
    if (format != ImageFormat::kJpeg) {
      EXPECT_TRUE(Equal(bitmap.color, image));  // Lossless formats round-trip exactly.
    } else {
      // Lossy: the same pixels as OpenCV's own colour read of the file.
      EXPECT_TRUE(Equal(bitmap.color, cv::imread(path.string(), cv::IMREAD_COLOR)));
    }
    cv::Mat expected_gray;
    cv::cvtColor(bitmap.color, expected_gray, cv::COLOR_BGR2GRAY);
    EXPECT_TRUE(Equal(bitmap.gray, expected_gray));
  }
}

TEST_F(ImageReaderTest, PngNamedJpgIsReadAsPng) {
  const cv::Mat image = TestImage(20, 10);
  const fs::path path = Write("actually_png.jpg", image, ".png");
  EXPECT_EQ(DetectImageFormat(path), ImageFormat::kPng);
  EXPECT_TRUE(Equal(ReadBitmap(path).color, image));
}

TEST_F(ImageReaderTest, SixteenBitImagesAreScaledToEightBits) {
  const cv::Mat image16 = TestImage(16, 12, CV_16UC3);
  cv::Mat expected8;
  image16.convertTo(expected8, CV_8U, 1.0 / 257.0);
  for (const std::string extension : {".png", ".tif"}) {
    SCOPED_TRACE(extension);
    const fs::path path = Write("image16" + extension, image16, extension);
    const Bitmap bitmap = ReadBitmap(path);
    EXPECT_TRUE(Equal(bitmap.color, expected8));
  }
  // A 16-bit gray image keeps its intensities as the gray plane.
  cv::Mat gray16;
  cv::extractChannel(image16, gray16, 1);
  cv::Mat expected_gray;
  gray16.convertTo(expected_gray, CV_8U, 1.0 / 257.0);
  const Bitmap bitmap = ReadBitmap(Write("gray16.png", gray16, ".png"));
  EXPECT_TRUE(Equal(bitmap.gray, expected_gray));
}

TEST_F(ImageReaderTest, RgbaAndGrayImagesAreConverted) {
  const cv::Mat bgra = TestImage(15, 9, CV_8UC4);
  cv::Mat expected_bgr;
  cv::cvtColor(bgra, expected_bgr, cv::COLOR_BGRA2BGR);
  EXPECT_TRUE(Equal(ReadBitmap(Write("rgba.png", bgra, ".png")).color, expected_bgr));

  cv::Mat gray;
  cv::extractChannel(bgra, gray, 2);
  const Bitmap bitmap = ReadBitmap(Write("gray.png", gray, ".png"));
  EXPECT_TRUE(Equal(bitmap.gray, gray));  // Gray passes through without a colour round trip.
  std::vector<cv::Mat> planes;
  cv::split(bitmap.color, planes);
  for (const cv::Mat& plane : planes) EXPECT_TRUE(Equal(plane, gray));
}

TEST(BitmapTest, RgbAtIsThePixelContainingThePointOrTheNearestBorderPixel) {
  Bitmap bitmap;
  bitmap.color = cv::Mat(3, 4, CV_8UC3);
  for (int row = 0; row < 3; ++row) {
    for (int column = 0; column < 4; ++column) {
      bitmap.color.at<cv::Vec3b>(row, column) = cv::Vec3b(column, row, 100);  // BGR.
    }
  }
  const auto rgb_at = [&bitmap](double x, double y) {
    uint8_t rgb[3] = {0, 0, 0};
    EXPECT_TRUE(bitmap.RgbAt(x, y, rgb)) << x << " " << y;
    return cv::Vec3i(rgb[0], rgb[1], rgb[2]);
  };
  EXPECT_EQ(rgb_at(0.5, 0.5), cv::Vec3i(100, 0, 0));
  EXPECT_EQ(rgb_at(2.99, 1.0), cv::Vec3i(100, 1, 2));
  EXPECT_EQ(rgb_at(3.5, 2.5), cv::Vec3i(100, 2, 3));
  // Outside: the nearest border pixel (SIFT refines a few keypoints past the border).
  EXPECT_EQ(rgb_at(-0.4, 1.5), cv::Vec3i(100, 1, 0));
  EXPECT_EQ(rgb_at(1.5, -15.4), cv::Vec3i(100, 0, 1));
  EXPECT_EQ(rgb_at(1e12, 1e12), cv::Vec3i(100, 2, 3));
  uint8_t rgb[3];
  EXPECT_FALSE(bitmap.RgbAt(std::nan(""), 1.0, rgb));
  EXPECT_FALSE(Bitmap().RgbAt(0.5, 0.5, rgb));
}

TEST_F(ImageReaderTest, TruncatedImagesAreRefused) {
  const cv::Mat image = TestImage(64, 48);
  for (const std::string extension : {".png", ".jpg"}) {
    SCOPED_TRACE(extension);
    const std::string bytes = ReadBytes(Write("full" + extension, image, extension));
    ASSERT_GT(bytes.size(), 200u);
    // Cut in the pixel data, and cut in the header.
    const fs::path half = WriteBytes("half" + extension, bytes.substr(0, bytes.size() / 2));
    ExpectInputError(half, "truncated");
    const fs::path header = WriteBytes("header" + extension, bytes.substr(0, 20));
    ExpectInputError(header, "header");
  }
}

TEST_F(ImageReaderTest, NonImagesAreRefused) {
  const fs::path empty = WriteBytes("empty.png", "");
  EXPECT_EQ(DetectImageFormat(empty), ImageFormat::kUnknown);
  EXPECT_FALSE(ReadImageSize(empty).has_value());
  ExpectInputError(empty, "empty");

  const fs::path text = WriteBytes("notes.jpg", "This is not an image, just some text.\n");
  EXPECT_EQ(DetectImageFormat(text), ImageFormat::kUnknown);
  ExpectInputError(text, "not a PNG, JPEG, TIFF or BMP image");

  ExpectInputError(dir_ / "missing.png", "not a readable file");
  EXPECT_EQ(DetectImageFormat(dir_ / "missing.png"), ImageFormat::kUnknown);
  EXPECT_FALSE(ReadImageSize(dir_ / "missing.png").has_value());

  // A valid header followed by garbage instead of compressed data.
  std::string garbage = ReadBytes(Write("valid.png", TestImage(30, 30), ".png"));
  for (size_t i = 40; i + 12 < garbage.size(); ++i) garbage[i] = static_cast<char>(i * 7);
  ExpectInputError(WriteBytes("garbage.png", garbage), "");
}

TEST_F(ImageReaderTest, HugeImagesAreRefusedFromTheHeader) {
  // PNG signature and an IHDR chunk claiming 100000 x 100000 RGB pixels, then IEND; no pixels.
  std::string png("\x89PNG\r\n\x1a\n", 8);
  png += std::string("\x00\x00\x00\x0dIHDR", 8);
  png += std::string("\x00\x01\x86\xa0\x00\x01\x86\xa0\x08\x02\x00\x00\x00", 13);
  png += std::string("\x00\x00\x00\x00", 4);  // CRC (not checked before refusing).
  png += std::string("\x00\x00\x00\x00IEND\xae\x42\x60\x82", 12);
  const fs::path path = WriteBytes("huge.png", png);
  EXPECT_EQ(DetectImageFormat(path), ImageFormat::kPng);
  const auto size = ReadImageSize(path);
  ASSERT_TRUE(size.has_value());
  EXPECT_EQ(size->width, 100000);
  EXPECT_EQ(size->height, 100000);
  ExpectInputError(path, "max_image_pixels");

  // The bound applies to ordinary images too.
  ImageReaderOptions options;
  options.max_image_pixels = 37 * 23 - 1;
  ExpectInputError(Write("small.png", TestImage(37, 23), ".png"), "max_image_pixels", options);
  options.max_image_pixels = 37 * 23;
  EXPECT_EQ(ReadBitmap(dir_ / "small.png", options).Width(), 37);
  options.max_image_pixels = 0;
  EXPECT_THROW(options.Check(), CheckError);
}

TEST_F(ImageReaderTest, JpegSizeIsFoundAfterLargeApplicationSegments) {
  const cv::Mat image = TestImage(41, 19);
  const std::string jpeg = ReadBytes(Write("plain.jpg", image, ".jpg"));
  // Insert a 5000-byte APP1 segment (as EXIF would be) right after SOI, preceded by fill
  // bytes. Its payload holds a fake thumbnail: SOI, a frame header claiming 9999 x 9999, a
  // scan and EOI, none of which may be taken for the main image's.
  const int length = 5000;
  std::string payload("\xff\xd8\xff\xc0\x00\x11\x08\x27\x0f\x27\x0f\x03", 12);
  payload += "\xff\xda" + std::string(100, '\x55') + "\xff\xd9";
  payload.resize(length - 2, '\xd9');
  std::string app1 = "\xff\xff\xff\xe1";
  app1 += static_cast<char>(length >> 8);
  app1 += static_cast<char>(length & 0xff);
  app1 += payload;
  const std::string with_exif = jpeg.substr(0, 2) + app1 + jpeg.substr(2);
  const fs::path path = WriteBytes("exif.jpg", with_exif);
  const auto size = ReadImageSize(path);
  ASSERT_TRUE(size.has_value());
  EXPECT_EQ(size->width, 41);
  EXPECT_EQ(size->height, 19);
  EXPECT_TRUE(Equal(ReadBitmap(path).color, cv::imread(path.string(), cv::IMREAD_COLOR)));
  // Cut inside the main image's scan: the thumbnail's EOI must not make it look complete.
  const fs::path truncated =
      WriteBytes("exif_truncated.jpg", with_exif.substr(0, with_exif.size() - 100));
  ExpectInputError(truncated, "truncated");
}

TEST_F(ImageReaderTest, TiffSizeInEitherByteOrder) {
  // Minimal big-endian TIFF header: IFD at offset 8 with ImageWidth (LONG) and ImageLength
  // (SHORT) only.
  std::string tiff("MM\x00\x2a\x00\x00\x00\x08", 8);
  tiff += std::string("\x00\x02", 2);
  tiff += std::string("\x01\x00\x00\x04\x00\x00\x00\x01\x00\x01\x11\x70", 12);  // 70000
  tiff += std::string("\x01\x01\x00\x03\x00\x00\x00\x01\x01\xf4\x00\x00", 12);  // 500
  tiff += std::string("\x00\x00\x00\x00", 4);
  const fs::path path = WriteBytes("big_endian.tiff", tiff);
  EXPECT_EQ(DetectImageFormat(path), ImageFormat::kTiff);
  const auto size = ReadImageSize(path);
  ASSERT_TRUE(size.has_value());
  EXPECT_EQ(size->width, 70000);
  EXPECT_EQ(size->height, 500);
  ImageReaderOptions options;
  options.max_image_pixels = 1000000;
  ExpectInputError(path, "max_image_pixels", options);
}

TEST_F(ImageReaderTest, ListImageFilesByContent) {
  const cv::Mat image = TestImage(8, 8);
  Write("b.png", image, ".png");
  Write("a.jpg", image, ".png");  // PNG content named .jpg.
  Write("c.bmp", image, ".bmp");
  Write("d.tif", image, ".tif");
  WriteBytes("e.jpg", "text");
  WriteBytes("f.png", "");
  WriteBytes("notes.txt", "hello");
  fs::create_directories(dir_ / "sub.png");
  Write("sub.png/inner.png", image, ".png");  // Not recursive.
  const std::vector<fs::path> files = ListImageFiles(dir_);
  std::vector<std::string> names;
  for (const fs::path& file : files) names.push_back(file.filename().string());
  EXPECT_EQ(names, (std::vector<std::string>{"a.jpg", "b.png", "c.bmp", "d.tif"}));
  EXPECT_THROW(ListImageFiles(dir_ / "missing"), InputError);

  // Files named like images that are not, for the caller to warn about; notes.txt is not one.
  WriteBytes("G.JPEG", "also text");
  std::vector<RejectedImageFile> rejected;
  EXPECT_EQ(ListImageFiles(dir_, &rejected).size(), 4u);
  ASSERT_EQ(rejected.size(), 3u);
  EXPECT_EQ(rejected[0].path, dir_ / "G.JPEG");
  EXPECT_EQ(rejected[0].reason, "not a PNG, JPEG, TIFF or BMP image (by content)");
  EXPECT_EQ(rejected[1].path, dir_ / "e.jpg");
  EXPECT_EQ(rejected[2].path, dir_ / "f.png");
  EXPECT_EQ(rejected[2].reason, "empty file");
}

TEST_F(ImageReaderTest, DecodesFromMemoryWithTheSameChecks) {
  const cv::Mat image = TestImage(40, 30);
  std::vector<uint8_t> png;
  ASSERT_TRUE(cv::imencode(".png", image, png));
  const std::string bytes(png.begin(), png.end());
  EXPECT_EQ(DetectImageFormatFromBytes(bytes), ImageFormat::kPng);
  const std::optional<ImageSize> size = ReadImageSizeFromBytes(bytes);
  ASSERT_TRUE(size.has_value());
  EXPECT_EQ(size->width, 40);
  EXPECT_EQ(size->height, 30);
  EXPECT_TRUE(Equal(DecodeBitmap(bytes, "memory.png").color, image));
  EXPECT_EQ(DetectImageFormatFromBytes("GIF89a"), ImageFormat::kUnknown);
  EXPECT_FALSE(ReadImageSizeFromBytes(bytes.substr(0, 20)).has_value());

  const auto expect_error = [](const std::string& data, const std::string& reason,
                               const ImageReaderOptions& options) {
    try {
      DecodeBitmap(data, "memory.png", options);
      ADD_FAILURE() << "no exception for " << reason;
    } catch (const InputError& error) {
      const std::string message = error.what();
      EXPECT_EQ(message.rfind("memory.png: ", 0), 0u) << message;
      EXPECT_NE(message.find(reason), std::string::npos) << message;
      EXPECT_EQ(message.find('\n'), std::string::npos) << message;
    }
  };
  expect_error("", "empty file", {});
  expect_error(bytes.substr(0, bytes.size() - 20), "truncated PNG", {});
  expect_error("hello", "not a PNG, JPEG, TIFF or BMP image", {});
  ImageReaderOptions small;
  small.max_image_pixels = 1000;
  expect_error(bytes, "40x30 pixels, more than max_image_pixels = 1000", small);
}

TEST_F(ImageReaderTest, LargeJpegHeaderBeyondTheFirstMegabyteIsStillFound) {
  // ReadBitmap checks the header from the file's first MiB before reading the rest; a frame
  // header behind 1.2 MB of application segments is then checked on the whole file.
  const cv::Mat image = TestImage(32, 24);
  std::vector<uint8_t> jpeg;
  ASSERT_TRUE(cv::imencode(".jpg", image, jpeg));
  std::string bytes(jpeg.begin(), jpeg.end());
  std::string segments;
  for (int k = 0; k < 20; ++k) {
    segments += std::string("\xff\xe9\xff\xff", 4) + std::string(65533, static_cast<char>(k));
  }
  bytes.insert(2, segments);
  const fs::path path = WriteBytes("padded.jpg", bytes);
  const Bitmap bitmap = ReadBitmap(path);
  EXPECT_EQ(bitmap.Width(), 32);
  EXPECT_EQ(bitmap.Height(), 24);
  ImageReaderOptions small;
  small.max_image_pixels = 100;
  ExpectInputError(path, "32x24 pixels, more than max_image_pixels = 100", small);
}

}  // namespace
}  // namespace parallax
