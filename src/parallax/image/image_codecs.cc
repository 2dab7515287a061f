#include "parallax/image/image_codecs.h"

#include <png.h>
#include <tiffio.h>

#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <csetjmp>
#include <cstdarg>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <memory>
#include <mutex>
#include <optional>
#include <stdexcept>
#include <vector>

// jpeglib.h needs FILE and size_t declared first.
#include <jpeglib.h>

#include "parallax/image/common_png.h"
#include "parallax/util/byte_order.h"

namespace parallax {
namespace {

[[noreturn]] void Throw(const std::string& message) { throw std::runtime_error(message); }

// ---- JPEG ----------------------------------------------------------------------------

// libjpeg reports fatal errors through error_exit, which must not return: it jumps back to
// the setjmp in the caller, which throws. Warnings (e.g. a premature end of data, which
// still decodes) are dropped, as OpenCV drops them.
struct JpegError {
  jpeg_error_mgr manager;
  std::jmp_buf jump;
  char message[JMSG_LENGTH_MAX];
};

void JpegErrorExit(j_common_ptr info) {
  auto* error = reinterpret_cast<JpegError*>(info->err);
  (*info->err->format_message)(info, error->message);
  std::longjmp(error->jump, 1);
}

void JpegSilence(j_common_ptr) {}

cv::Mat DecodeJpeg(std::string_view bytes) {
  jpeg_decompress_struct info;
  JpegError error;
  info.err = jpeg_std_error(&error.manager);
  error.manager.error_exit = JpegErrorExit;
  error.manager.output_message = JpegSilence;
  cv::Mat image;
  if (setjmp(error.jump)) {
    jpeg_destroy_decompress(&info);
    Throw(error.message);
  }
  jpeg_create_decompress(&info);
  jpeg_mem_src(&info, reinterpret_cast<const unsigned char*>(bytes.data()),
               static_cast<unsigned long>(bytes.size()));
  jpeg_read_header(&info, TRUE);
  if (info.jpeg_color_space == JCS_CMYK || info.jpeg_color_space == JCS_YCCK) {
    jpeg_destroy_decompress(&info);
    Throw("CMYK JPEG is not supported");
  }
  const bool gray = info.num_components == 1;
  info.out_color_space = gray ? JCS_GRAYSCALE : JCS_EXT_BGR;
  jpeg_start_decompress(&info);
  image.create(static_cast<int>(info.output_height), static_cast<int>(info.output_width),
               gray ? CV_8UC1 : CV_8UC3);
  while (info.output_scanline < info.output_height) {
    JSAMPROW row = image.ptr<unsigned char>(static_cast<int>(info.output_scanline));
    jpeg_read_scanlines(&info, &row, 1);
  }
  jpeg_finish_decompress(&info);
  jpeg_destroy_decompress(&info);
  return image;
}

// ---- PNG -----------------------------------------------------------------------------

struct PngReader {
  std::string_view bytes;
  size_t offset = 0;
  char message[256] = "";
};

void PngError(png_structp png, png_const_charp message) {
  auto* reader = static_cast<PngReader*>(png_get_error_ptr(png));
  std::snprintf(reader->message, sizeof(reader->message), "%s", message);
  png_longjmp(png, 1);
}

void PngWarning(png_structp, png_const_charp) {}

void PngRead(png_structp png, png_bytep out, png_size_t length) {
  auto* reader = static_cast<PngReader*>(png_get_io_ptr(png));
  if (length > reader->bytes.size() - reader->offset) png_error(png, "truncated PNG data");
  std::memcpy(out, reader->bytes.data() + reader->offset, length);
  reader->offset += length;
}

cv::Mat DecodePng(std::string_view bytes) {
  if (std::optional<cv::Mat> image = DecodeCommonPng(bytes)) return std::move(*image);
  PngReader reader{bytes};
  png_structp png = png_create_read_struct(PNG_LIBPNG_VER_STRING, &reader, PngError, PngWarning);
  if (png == nullptr) Throw("cannot create a PNG reader");
  png_infop info = png_create_info_struct(png);
  cv::Mat image;
  std::vector<png_bytep> rows;
  if (info == nullptr || setjmp(png_jmpbuf(png))) {
    png_destroy_read_struct(&png, &info, nullptr);
    Throw(reader.message[0] != '\0' ? reader.message : "cannot decode PNG");
  }
  png_set_read_fn(png, &reader, PngRead);
  png_read_info(png, info);
  const int color_type = png_get_color_type(png, info);
  const int bit_depth = png_get_bit_depth(png, info);
  const bool transparent = png_get_valid(png, info, PNG_INFO_tRNS) != 0;
  // Expand palettes and low bit depths to 8 bits, transparency to alpha, gray plus alpha to
  // BGRA, 16-bit samples to host (little-endian) order, colour to BGR: imdecode's layout.
  if (color_type == PNG_COLOR_TYPE_PALETTE) png_set_palette_to_rgb(png);
  if (color_type == PNG_COLOR_TYPE_GRAY && bit_depth < 8) png_set_expand_gray_1_2_4_to_8(png);
  if (transparent) png_set_tRNS_to_alpha(png);
  if ((color_type & PNG_COLOR_MASK_COLOR) == 0 &&
      ((color_type & PNG_COLOR_MASK_ALPHA) != 0 || transparent)) {
    png_set_gray_to_rgb(png);
  }
  if (bit_depth == 16) png_set_swap(png);
  png_set_bgr(png);
  png_set_interlace_handling(png);
  png_read_update_info(png, info);
  const int channels = png_get_channels(png, info);
  const int depth = png_get_bit_depth(png, info) == 16 ? CV_16U : CV_8U;
  image.create(static_cast<int>(png_get_image_height(png, info)),
               static_cast<int>(png_get_image_width(png, info)), CV_MAKETYPE(depth, channels));
  rows.resize(static_cast<size_t>(image.rows));
  for (int y = 0; y < image.rows; ++y) rows[y] = image.ptr<png_byte>(y);
  png_read_image(png, rows.data());
  png_read_end(png, nullptr);
  png_destroy_read_struct(&png, &info, nullptr);
  return image;
}

// ---- TIFF ----------------------------------------------------------------------------

// libtiff's handlers are process-wide; the message goes to the decoding thread's buffer.
thread_local std::string tiff_message;

void TiffError(const char*, const char* format, va_list args) {
  char buffer[512];
  std::vsnprintf(buffer, sizeof(buffer), format, args);
  if (tiff_message.empty()) tiff_message = buffer;
}

void TiffWarning(const char*, const char*, va_list) {}

struct TiffMemory {
  std::string_view bytes;
  toff_t offset = 0;
};

tmsize_t TiffRead(thandle_t handle, void* out, tmsize_t size) {
  auto* memory = static_cast<TiffMemory*>(handle);
  if (memory->offset >= memory->bytes.size()) return 0;
  const tmsize_t available = static_cast<tmsize_t>(memory->bytes.size() - memory->offset);
  const tmsize_t count = std::min(size, available);
  std::memcpy(out, memory->bytes.data() + memory->offset, static_cast<size_t>(count));
  memory->offset += static_cast<toff_t>(count);
  return count;
}

tmsize_t TiffWrite(thandle_t, void*, tmsize_t) { return -1; }

toff_t TiffSeek(thandle_t handle, toff_t offset, int whence) {
  auto* memory = static_cast<TiffMemory*>(handle);
  const toff_t base = whence == SEEK_SET   ? 0
                      : whence == SEEK_CUR ? memory->offset
                                           : static_cast<toff_t>(memory->bytes.size());
  memory->offset = base + offset;
  return memory->offset;
}

int TiffClose(thandle_t) { return 0; }

toff_t TiffSize(thandle_t handle) {
  return static_cast<toff_t>(static_cast<TiffMemory*>(handle)->bytes.size());
}

int TiffMap(thandle_t, void**, toff_t*) { return 0; }
void TiffUnmap(thandle_t, void*, toff_t) {}

// Gray or RGB(A) strips of 8 or 16 bits are read as stored; anything else (palette, YCbCr,
// tiles, planes, other depths) through libtiff's RGBA interface as 8-bit BGRA.
cv::Mat DecodeTiff(std::string_view bytes) {
  static std::once_flag handlers_set;
  std::call_once(handlers_set, [] {
    TIFFSetErrorHandler(TiffError);
    TIFFSetWarningHandler(TiffWarning);
  });
  tiff_message.clear();
  TiffMemory memory{bytes};
  const std::unique_ptr<TIFF, void (*)(TIFF*)> tiff(
      TIFFClientOpen("memory", "rm", &memory, TiffRead, TiffWrite, TiffSeek, TiffClose, TiffSize,
                     TiffMap, TiffUnmap),
      [](TIFF* t) {
        if (t != nullptr) TIFFClose(t);
      });
  const auto fail = [](const char* what) {
    Throw(tiff_message.empty() ? std::string(what) : tiff_message);
  };
  if (!tiff) fail("cannot open TIFF");
  uint32_t width = 0, height = 0;
  uint16_t bits = 8, samples = 1, photometric = PHOTOMETRIC_MINISBLACK,
           planar = PLANARCONFIG_CONTIG, format = SAMPLEFORMAT_UINT;
  TIFFGetField(tiff.get(), TIFFTAG_IMAGEWIDTH, &width);
  TIFFGetField(tiff.get(), TIFFTAG_IMAGELENGTH, &height);
  TIFFGetFieldDefaulted(tiff.get(), TIFFTAG_BITSPERSAMPLE, &bits);
  TIFFGetFieldDefaulted(tiff.get(), TIFFTAG_SAMPLESPERPIXEL, &samples);
  TIFFGetFieldDefaulted(tiff.get(), TIFFTAG_PLANARCONFIG, &planar);
  TIFFGetFieldDefaulted(tiff.get(), TIFFTAG_SAMPLEFORMAT, &format);
  TIFFGetField(tiff.get(), TIFFTAG_PHOTOMETRIC, &photometric);
  if (width == 0 || height == 0 || width > INT32_MAX || height > INT32_MAX) fail("bad TIFF size");
  const int rows = static_cast<int>(height), cols = static_cast<int>(width);

  const bool as_stored = !TIFFIsTiled(tiff.get()) && planar == PLANARCONFIG_CONTIG &&
                         format == SAMPLEFORMAT_UINT && (bits == 8 || bits == 16) &&
                         ((photometric == PHOTOMETRIC_MINISBLACK && samples == 1) ||
                          (photometric == PHOTOMETRIC_RGB && (samples == 3 || samples == 4)));
  if (as_stored) {
    cv::Mat image(rows, cols, CV_MAKETYPE(bits == 16 ? CV_16U : CV_8U, samples));
    if (TIFFScanlineSize(tiff.get()) != static_cast<tmsize_t>(image.step[0])) {
      fail("unexpected TIFF scanline size");
    }
    for (int y = 0; y < rows; ++y) {
      if (TIFFReadScanline(tiff.get(), image.ptr(y), static_cast<uint32_t>(y), 0) < 0) {
        fail("cannot read TIFF scanline");
      }
    }
    if (samples == 3) cv::cvtColor(image, image, cv::COLOR_RGB2BGR);
    if (samples == 4) cv::cvtColor(image, image, cv::COLOR_RGBA2BGRA);
    return image;
  }
  cv::Mat rgba(rows, cols, CV_8UC4);
  if (!TIFFReadRGBAImageOriented(tiff.get(), width, height, rgba.ptr<uint32_t>(),
                                 ORIENTATION_TOPLEFT, 0)) {
    fail("cannot decode TIFF");
  }
  // ABGR words in host order are RGBA bytes on a little-endian machine.
  cv::cvtColor(rgba, rgba, cv::COLOR_RGBA2BGRA);
  return rgba;
}

// ---- BMP -----------------------------------------------------------------------------

// Uncompressed Windows bitmaps of 8 (palette), 24 and 32 bits, what encoders write; a gray
// palette gives one channel, as imdecode does.
cv::Mat DecodeBmp(std::string_view bytes) {
  if (bytes.size() < 54) Throw("BMP header truncated");
  const auto* data = reinterpret_cast<const uint8_t*>(bytes.data());
  const uint32_t data_offset = LittleEndian32(data + 10);
  const uint32_t header_size = LittleEndian32(data + 14);
  if (header_size < 40) Throw("unsupported BMP header version");
  const int32_t width = static_cast<int32_t>(LittleEndian32(data + 18));
  const int32_t signed_height = static_cast<int32_t>(LittleEndian32(data + 22));
  const uint32_t bits = LittleEndian16(data + 28);
  const uint32_t compression = LittleEndian32(data + 30);
  if (width <= 0 || signed_height == 0 || signed_height == INT32_MIN) Throw("bad BMP size");
  const bool bottom_up = signed_height > 0;
  const int height = bottom_up ? signed_height : -signed_height;
  // BI_RGB, or BI_BITFIELDS with 32 bits (read as BGRA, the masks every encoder writes).
  if (!(compression == 0 || (compression == 3 && bits == 32))) {
    Throw("unsupported BMP compression " + std::to_string(compression));
  }
  if (bits != 8 && bits != 24 && bits != 32) {
    Throw("unsupported BMP bit depth " + std::to_string(bits));
  }
  const size_t row_bytes = ((static_cast<size_t>(width) * bits + 31) / 32) * 4;
  // Division, not multiplication: a header may claim sizes whose product overflows.
  if (data_offset > bytes.size() ||
      row_bytes > (bytes.size() - data_offset) / static_cast<size_t>(height)) {
    Throw("BMP pixel data truncated");
  }
  const auto row = [&](int y) {
    const int stored = bottom_up ? height - 1 - y : y;
    return data + data_offset + row_bytes * static_cast<size_t>(stored);
  };
  if (bits == 24 || bits == 32) {
    cv::Mat image(height, width, bits == 24 ? CV_8UC3 : CV_8UC4);
    for (int y = 0; y < height; ++y) {
      std::memcpy(image.ptr(y), row(y), static_cast<size_t>(width) * (bits / 8));
    }
    return image;
  }
  uint32_t num_colors = LittleEndian32(data + 46);
  if (num_colors == 0 || num_colors > 256) num_colors = 256;
  const size_t palette_offset = 14 + header_size;
  if (palette_offset + 4 * num_colors > data_offset) Throw("BMP palette truncated");
  std::vector<cv::Vec3b> palette(256, cv::Vec3b(0, 0, 0));
  bool gray = true;
  for (uint32_t i = 0; i < num_colors; ++i) {
    const auto* entry = data + palette_offset + 4 * i;
    palette[i] = cv::Vec3b(entry[0], entry[1], entry[2]);
    gray = gray && entry[0] == entry[1] && entry[1] == entry[2];
  }
  cv::Mat image(height, width, gray ? CV_8UC1 : CV_8UC3);
  for (int y = 0; y < height; ++y) {
    const uint8_t* indices = row(y);
    for (int x = 0; x < width; ++x) {
      const cv::Vec3b& color = palette[indices[x]];
      if (gray) {
        image.at<uint8_t>(y, x) = color[0];
      } else {
        image.at<cv::Vec3b>(y, x) = color;
      }
    }
  }
  return image;
}

// ---- Encoding ------------------------------------------------------------------------

void PngWrite(png_structp png, png_bytep data, png_size_t length) {
  static_cast<std::string*>(png_get_io_ptr(png))
      ->append(reinterpret_cast<const char*>(data), length);
}

void PngFlush(png_structp) {}

}  // namespace

cv::Mat DecodeImage(std::string_view bytes, ImageFormat format) {
  switch (format) {
    case ImageFormat::kJpeg:
      return DecodeJpeg(bytes);
    case ImageFormat::kPng:
      return DecodePng(bytes);
    case ImageFormat::kTiff:
      return DecodeTiff(bytes);
    case ImageFormat::kBmp:
      return DecodeBmp(bytes);
    case ImageFormat::kUnknown:
      break;
  }
  Throw("unknown image format");
}

std::string EncodePng(const cv::Mat& image) {
  if (image.empty() || (image.depth() != CV_8U && image.depth() != CV_16U) ||
      (image.channels() != 1 && image.channels() != 3 && image.channels() != 4)) {
    Throw("EncodePng: 8- or 16-bit images of 1, 3 or 4 channels only");
  }
  std::string out;
  PngReader errors;  // Only its message buffer.
  png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, &errors, PngError, PngWarning);
  if (png == nullptr) Throw("cannot create a PNG writer");
  png_infop info = png_create_info_struct(png);
  std::vector<png_bytep> rows;
  if (info == nullptr || setjmp(png_jmpbuf(png))) {
    png_destroy_write_struct(&png, &info);
    Throw(errors.message[0] != '\0' ? errors.message : "cannot encode PNG");
  }
  png_set_write_fn(png, &out, PngWrite, PngFlush);
  // Fast deflate, as OpenCV's default: the renders are encoded once and read once.
  png_set_compression_level(png, 1);
  const int color_type = image.channels() == 1   ? PNG_COLOR_TYPE_GRAY
                         : image.channels() == 3 ? PNG_COLOR_TYPE_RGB
                                                 : PNG_COLOR_TYPE_RGB_ALPHA;
  png_set_IHDR(png, info, static_cast<png_uint_32>(image.cols),
               static_cast<png_uint_32>(image.rows), image.depth() == CV_16U ? 16 : 8, color_type,
               PNG_INTERLACE_NONE, PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
  png_write_info(png, info);
  if (image.channels() > 1) png_set_bgr(png);
  if (image.depth() == CV_16U) png_set_swap(png);
  rows.resize(static_cast<size_t>(image.rows));
  for (int y = 0; y < image.rows; ++y) rows[y] = const_cast<png_bytep>(image.ptr<png_byte>(y));
  png_write_image(png, rows.data());
  png_write_end(png, nullptr);
  png_destroy_write_struct(&png, &info);
  return out;
}

std::string EncodeJpeg(const cv::Mat& image, int quality) {
  if (image.empty() || image.depth() != CV_8U || (image.channels() != 1 && image.channels() != 3)) {
    Throw("EncodeJpeg: 8-bit gray or BGR images only");
  }
  jpeg_compress_struct info;
  JpegError error;
  info.err = jpeg_std_error(&error.manager);
  error.manager.error_exit = JpegErrorExit;
  error.manager.output_message = JpegSilence;
  unsigned char* buffer = nullptr;
  unsigned long size = 0;
  if (setjmp(error.jump)) {
    jpeg_destroy_compress(&info);
    std::free(buffer);
    Throw(error.message);
  }
  jpeg_create_compress(&info);
  jpeg_mem_dest(&info, &buffer, &size);
  info.image_width = static_cast<JDIMENSION>(image.cols);
  info.image_height = static_cast<JDIMENSION>(image.rows);
  info.input_components = image.channels();
  info.in_color_space = image.channels() == 1 ? JCS_GRAYSCALE : JCS_EXT_BGR;
  jpeg_set_defaults(&info);
  jpeg_set_quality(&info, std::clamp(quality, 1, 100), TRUE);
  jpeg_start_compress(&info, TRUE);
  while (info.next_scanline < info.image_height) {
    JSAMPROW row =
        const_cast<JSAMPROW>(image.ptr<unsigned char>(static_cast<int>(info.next_scanline)));
    jpeg_write_scanlines(&info, &row, 1);
  }
  jpeg_finish_compress(&info);
  std::string out(reinterpret_cast<const char*>(buffer), size);
  jpeg_destroy_compress(&info);
  std::free(buffer);
  return out;
}

}  // namespace parallax
