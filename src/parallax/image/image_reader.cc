#include "parallax/image/image_reader.h"

#include "parallax/image/image_codecs.h"
#include "parallax/util/byte_order.h"

#include <algorithm>
#include <array>
#include <cctype>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <opencv2/imgproc.hpp>
#include <string_view>
#include <system_error>

#include "parallax/util/check.h"
#include "parallax/util/file.h"

namespace parallax {
namespace {

// Random access to the first bytes of an image, from a file (header-only reads) or from memory.
class ByteSource {
 public:
  virtual ~ByteSource() = default;
  // Copies `size` bytes at `offset` into `out`; false when the source is shorter.
  virtual bool Read(uint64_t offset, size_t size, uint8_t* out) = 0;
};

class FileByteSource : public ByteSource {
 public:
  explicit FileByteSource(const std::filesystem::path& path) : stream_(path, std::ios::binary) {}
  bool IsOpen() const { return static_cast<bool>(stream_); }
  bool Read(uint64_t offset, size_t size, uint8_t* out) override {
    stream_.clear();
    stream_.seekg(static_cast<std::streamoff>(offset));
    if (!stream_) return false;
    stream_.read(reinterpret_cast<char*>(out), static_cast<std::streamsize>(size));
    return stream_.gcount() == static_cast<std::streamsize>(size);
  }

 private:
  std::ifstream stream_;
};

class MemoryByteSource : public ByteSource {
 public:
  explicit MemoryByteSource(std::string_view data) : data_(data) {}
  bool Read(uint64_t offset, size_t size, uint8_t* out) override {
    if (offset > data_.size() || size > data_.size() - offset) return false;
    std::memcpy(out, data_.data() + offset, size);
    return true;
  }

 private:
  std::string_view data_;
};

ImageFormat DetectFormat(ByteSource& source) {
  std::array<uint8_t, 8> magic{};
  if (!source.Read(0, 2, magic.data())) return ImageFormat::kUnknown;
  const bool have8 = source.Read(0, 8, magic.data());
  const bool have4 = have8 || source.Read(0, 4, magic.data());
  static constexpr uint8_t kPngMagic[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
  if (have8 && std::memcmp(magic.data(), kPngMagic, 8) == 0) return ImageFormat::kPng;
  if (have4 && magic[0] == 0xff && magic[1] == 0xd8 && magic[2] == 0xff) return ImageFormat::kJpeg;
  if (have4 && ((magic[0] == 'I' && magic[1] == 'I' && magic[2] == 42 && magic[3] == 0) ||
                (magic[0] == 'M' && magic[1] == 'M' && magic[2] == 0 && magic[3] == 42))) {
    return ImageFormat::kTiff;
  }
  // "BM" alone is weak evidence; require the 14-byte file header plus a DIB header size.
  if (magic[0] == 'B' && magic[1] == 'M') {
    uint8_t dib[4];
    if (source.Read(14, 4, dib) && LittleEndian32(dib) >= 12) return ImageFormat::kBmp;
  }
  return ImageFormat::kUnknown;
}

std::optional<ImageSize> MakeSize(int64_t width, int64_t height) {
  if (width <= 0 || height <= 0 || width > INT32_MAX || height > INT32_MAX) return std::nullopt;
  return ImageSize{static_cast<int>(width), static_cast<int>(height)};
}

std::optional<ImageSize> ReadPngSize(ByteSource& source) {
  // Signature (8), then the IHDR chunk: length (4), "IHDR", width (4), height (4), all big-endian.
  uint8_t header[16];
  if (!source.Read(8, 16, header) || std::memcmp(header + 4, "IHDR", 4) != 0) return std::nullopt;
  return MakeSize(BigEndian32(header + 8), BigEndian32(header + 12));
}

bool IsJpegStartOfFrame(uint8_t marker) {
  // SOF0..SOF15 except DHT (C4), JPG (C8) and DAC (CC).
  return marker >= 0xc0 && marker <= 0xcf && marker != 0xc4 && marker != 0xc8 && marker != 0xcc;
}

// Walks the JPEG marker segments from SOI. Stops at the first frame header (SOFn) when
// `scan_offset` is null, else continues to the first scan (SOS) and stores its offset there.
// Segment lengths are followed, so markers inside APPn payloads (an EXIF thumbnail has its
// own SOF, SOS and EOI) are never mistaken for the main image's.
std::optional<ImageSize> WalkJpeg(ByteSource& source, uint64_t* scan_offset) {
  std::optional<ImageSize> size;
  uint64_t offset = 2;  // After SOI.
  for (int segment = 0; segment < 10000; ++segment) {
    uint8_t byte;
    if (!source.Read(offset, 1, &byte) || byte != 0xff) return std::nullopt;
    uint8_t marker = 0xff;
    while (marker == 0xff) {  // Fill bytes may precede a marker.
      if (!source.Read(++offset, 1, &marker)) return std::nullopt;
    }
    ++offset;
    if (marker == 0x01 || (marker >= 0xd0 && marker <= 0xd8)) continue;  // No payload.
    if (marker == 0xd9) return std::nullopt;                             // EOI before any scan.
    if (marker == 0xda) {
      if (size && scan_offset != nullptr) *scan_offset = offset;
      return size;  // Scan data before a frame header: nullopt.
    }
    uint8_t length_bytes[2];
    if (!source.Read(offset, 2, length_bytes)) return std::nullopt;
    const uint32_t length = BigEndian16(length_bytes);
    if (length < 2) return std::nullopt;
    if (IsJpegStartOfFrame(marker) && !size) {
      // Length (2), sample precision (1), height (2), width (2).
      uint8_t frame[5];
      if (length < 7 || !source.Read(offset + 2, 5, frame)) return std::nullopt;
      size = MakeSize(BigEndian16(frame + 3), BigEndian16(frame + 1));
      if (!size || scan_offset == nullptr) return size;
    }
    offset += length;
  }
  return std::nullopt;
}

std::optional<ImageSize> ReadJpegSize(ByteSource& source) { return WalkJpeg(source, nullptr); }

std::optional<ImageSize> ReadBmpSize(ByteSource& source) {
  // 14-byte file header, then the DIB header; BITMAPCOREHEADER (12 bytes) has 16-bit sizes,
  // the later ones 32-bit signed sizes (negative height: rows stored top-down).
  uint8_t dib[12];
  if (!source.Read(14, 12, dib)) return std::nullopt;
  const uint32_t dib_size = LittleEndian32(dib);
  if (dib_size == 12) return MakeSize(LittleEndian16(dib + 4), LittleEndian16(dib + 6));
  if (dib_size < 16) return std::nullopt;
  const auto width = static_cast<int32_t>(LittleEndian32(dib + 4));
  const auto height = static_cast<int32_t>(LittleEndian32(dib + 8));
  return MakeSize(width, height == INT32_MIN ? int64_t{0} : std::abs(int64_t{height}));
}

std::optional<ImageSize> ReadTiffSize(ByteSource& source) {
  uint8_t header[8];
  if (!source.Read(0, 8, header)) return std::nullopt;
  const bool little = header[0] == 'I';
  auto read16 = [little](const uint8_t* bytes) {
    return little ? LittleEndian16(bytes) : BigEndian16(bytes);
  };
  auto read32 = [little](const uint8_t* bytes) {
    return little ? LittleEndian32(bytes) : BigEndian32(bytes);
  };
  // The first IFD holds the full-resolution image; tags 256 (width) and 257 (length), stored
  // inline as SHORT (type 3) or LONG (type 4).
  const uint64_t ifd_offset = read32(header + 4);
  uint8_t count_bytes[2];
  if (!source.Read(ifd_offset, 2, count_bytes)) return std::nullopt;
  const uint32_t num_entries = read16(count_bytes);
  int64_t width = -1, height = -1;
  for (uint32_t i = 0; i < num_entries && (width < 0 || height < 0); ++i) {
    uint8_t entry[12];
    if (!source.Read(ifd_offset + 2 + 12 * uint64_t{i}, 12, entry)) return std::nullopt;
    const uint32_t tag = read16(entry);
    if (tag != 256 && tag != 257) continue;
    const uint32_t type = read16(entry + 2);
    int64_t value;
    if (type == 3) {
      value = read16(entry + 8);
    } else if (type == 4) {
      value = read32(entry + 8);
    } else {
      return std::nullopt;
    }
    (tag == 256 ? width : height) = value;
  }
  return MakeSize(width, height);
}

std::optional<ImageSize> ReadSize(ImageFormat format, ByteSource& source) {
  switch (format) {
    case ImageFormat::kPng:
      return ReadPngSize(source);
    case ImageFormat::kJpeg:
      return ReadJpegSize(source);
    case ImageFormat::kBmp:
      return ReadBmpSize(source);
    case ImageFormat::kTiff:
      return ReadTiffSize(source);
    case ImageFormat::kUnknown:
      break;
  }
  return std::nullopt;
}

// Decoders fill a truncated JPEG with gray and only warn, so check the end markers ourselves:
// a JPEG needs an EOI after the start of its first scan, a PNG its IEND chunk.
bool LooksComplete(ImageFormat format, std::string_view data) {
  if (format == ImageFormat::kPng) return data.rfind("IEND") != std::string_view::npos;
  if (format == ImageFormat::kJpeg) {
    MemoryByteSource source(data);
    uint64_t scan_offset = 0;
    if (!WalkJpeg(source, &scan_offset) || scan_offset == 0) return false;
    const size_t end = data.rfind("\xff\xd9");
    return end != std::string_view::npos && end > scan_offset;
  }
  return true;
}

const char* FormatName(ImageFormat format) {
  switch (format) {
    case ImageFormat::kPng:
      return "PNG";
    case ImageFormat::kJpeg:
      return "JPEG";
    case ImageFormat::kTiff:
      return "TIFF";
    case ImageFormat::kBmp:
      return "BMP";
    case ImageFormat::kUnknown:
      break;
  }
  return "unknown";
}

[[noreturn]] void Fail(const std::filesystem::path& path, const std::string& reason) {
  throw InputError(path.string() + ": " + reason);
}

// Any depth and channel count the decoders produce, to 8-bit BGR plus 8-bit gray.
Bitmap ToBitmap(const std::filesystem::path& path, const cv::Mat& decoded) {
  cv::Mat image8;
  switch (decoded.depth()) {
    case CV_8U:
      image8 = decoded;
      break;
    case CV_16U:
      decoded.convertTo(image8, CV_8U, 1.0 / 257.0);
      break;
    case CV_32F:  // Float TIFFs hold intensities in [0, 1].
      decoded.convertTo(image8, CV_8U, 255.0);
      break;
    default:
      Fail(path, "unsupported pixel depth " + std::to_string(decoded.depth()));
  }
  Bitmap bitmap;
  switch (image8.channels()) {
    case 1:
      bitmap.gray = image8;
      cv::cvtColor(bitmap.gray, bitmap.color, cv::COLOR_GRAY2BGR);
      return bitmap;
    case 2:  // Gray plus alpha: drop alpha.
      cv::extractChannel(image8, bitmap.gray, 0);
      cv::cvtColor(bitmap.gray, bitmap.color, cv::COLOR_GRAY2BGR);
      return bitmap;
    case 3:
      bitmap.color = image8;
      break;
    case 4:  // Alpha is dropped, not composited: SfM only needs the intensities.
      cv::cvtColor(image8, bitmap.color, cv::COLOR_BGRA2BGR);
      break;
    default:
      Fail(path, "unsupported channel count " + std::to_string(image8.channels()));
  }
  cv::cvtColor(bitmap.color, bitmap.gray, cv::COLOR_BGR2GRAY);
  return bitmap;
}

// Bytes read before the whole file: enough for every header we parse (a JPEG's frame header
// may follow a 64 KiB EXIF segment and other APPn segments).
constexpr uintmax_t kHeaderProbeBytes = 1 << 20;

// cv::Exception messages span several lines; the CLI prints one.
std::string OneLine(std::string text) {
  for (char& c : text) {
    if (c == '\n' || c == '\r') c = ' ';
  }
  return Trim(text);
}

bool HasImageExtension(const std::filesystem::path& path) {
  std::string extension = path.extension().string();
  std::transform(extension.begin(), extension.end(), extension.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return extension == ".jpg" || extension == ".jpeg" || extension == ".png" ||
         extension == ".tif" || extension == ".tiff" || extension == ".bmp";
}

struct CheckedHeader {
  ImageFormat format;
  ImageSize size;
};

// The format and size from the header, refusing unknown formats, unreadable headers and
// images over the pixel limit. `bytes` is the file's head; when it is not the whole file a
// header that runs past it is "not found yet" rather than malformed, so the check is skipped
// and DecodeBitmap repeats it on the whole file.
CheckedHeader CheckHeader(std::string_view bytes, const std::filesystem::path& source,
                          const ImageReaderOptions& options, bool complete) {
  MemoryByteSource byte_source(bytes);
  const ImageFormat format = DetectFormat(byte_source);
  if (format == ImageFormat::kUnknown) Fail(source, "not a PNG, JPEG, TIFF or BMP image");
  const std::optional<ImageSize> size = ReadSize(format, byte_source);
  if (!size) {
    if (!complete) return {format, ImageSize{}};
    Fail(source, std::string("malformed or truncated ") + FormatName(format) + " header");
  }
  const int64_t num_pixels = int64_t{size->width} * size->height;
  if (num_pixels > options.max_image_pixels) {
    Fail(source,
         "image is " + std::to_string(size->width) + "x" + std::to_string(size->height) +
             " pixels, more than max_image_pixels = " + std::to_string(options.max_image_pixels));
  }
  return {format, *size};
}

}  // namespace

void ImageReaderOptions::Check() const { PARALLAX_CHECK_GT(max_image_pixels, 0); }

ImageFormat DetectImageFormat(const std::filesystem::path& path) {
  FileByteSource source(path);
  if (!source.IsOpen()) return ImageFormat::kUnknown;
  return DetectFormat(source);
}

std::optional<ImageSize> ReadImageSize(const std::filesystem::path& path) {
  FileByteSource source(path);
  if (!source.IsOpen()) return std::nullopt;
  return ReadSize(DetectFormat(source), source);
}

ImageFormat DetectImageFormatFromBytes(std::string_view bytes) {
  MemoryByteSource source(bytes);
  return DetectFormat(source);
}

std::optional<ImageSize> ReadImageSizeFromBytes(std::string_view bytes) {
  MemoryByteSource source(bytes);
  return ReadSize(DetectFormat(source), source);
}

bool Bitmap::RgbAt(double x, double y, uint8_t rgb[3]) const {
  if (color.empty() || !std::isfinite(x) || !std::isfinite(y)) return false;
  // Clamped as doubles, so that no value outside int's range is converted.
  const int column = static_cast<int>(std::clamp(x, 0.0, color.cols - 1.0));
  const int row = static_cast<int>(std::clamp(y, 0.0, color.rows - 1.0));
  const cv::Vec3b bgr = color.at<cv::Vec3b>(row, column);
  rgb[0] = bgr[2];
  rgb[1] = bgr[1];
  rgb[2] = bgr[0];
  return true;
}

Bitmap ReadBitmap(const std::filesystem::path& path, const ImageReaderOptions& options) {
  options.Check();
  std::error_code error;
  if (!std::filesystem::is_regular_file(path, error)) Fail(path, "not a readable file");
  std::ifstream stream(path, std::ios::binary);
  if (!stream) Fail(path, "cannot open for reading");
  const auto file_size = std::filesystem::file_size(path, error);
  if (error) Fail(path, "cannot read the file size");
  if (file_size == 0) Fail(path, "empty file");
  if (file_size > static_cast<uintmax_t>(INT32_MAX)) Fail(path, "file larger than 2 GiB");
  // Only the header first: a huge image is refused before the whole file is read.
  std::string data(std::min<uintmax_t>(file_size, kHeaderProbeBytes), '\0');
  stream.read(data.data(), static_cast<std::streamsize>(data.size()));
  if (stream.gcount() != static_cast<std::streamsize>(data.size())) Fail(path, "read failed");
  CheckHeader(data, path, options, /*complete=*/data.size() == file_size);
  if (data.size() < file_size) {
    const size_t head_size = data.size();
    data.resize(file_size);
    stream.read(data.data() + head_size, static_cast<std::streamsize>(file_size - head_size));
    if (stream.gcount() != static_cast<std::streamsize>(file_size - head_size)) {
      Fail(path, "read failed");
    }
  }
  return DecodeBitmap(data, path, options);
}

Bitmap DecodeBitmap(std::string_view bytes, const std::filesystem::path& source,
                    const ImageReaderOptions& options) {
  options.Check();
  if (bytes.empty()) Fail(source, "empty file");
  if (bytes.size() > static_cast<size_t>(INT32_MAX)) Fail(source, "file larger than 2 GiB");
  const auto [format, size] = CheckHeader(bytes, source, options, /*complete=*/true);
  if (!LooksComplete(format, bytes)) Fail(source, std::string("truncated ") + FormatName(format));

  cv::Mat decoded;
  try {
    decoded = DecodeImage(bytes, format);
  } catch (const std::exception& exception) {
    Fail(source,
         std::string("cannot decode ") + FormatName(format) + ": " + OneLine(exception.what()));
  }
  if (decoded.empty()) Fail(source, std::string("cannot decode ") + FormatName(format));
  if (decoded.cols != size.width || decoded.rows != size.height) {
    Fail(source, "decoded size " + std::to_string(decoded.cols) + "x" +
                     std::to_string(decoded.rows) + " differs from the header's " +
                     std::to_string(size.width) + "x" + std::to_string(size.height));
  }
  return ToBitmap(source, decoded);
}

std::vector<std::filesystem::path> ListImageFiles(const std::filesystem::path& dir,
                                                  std::vector<RejectedImageFile>* rejected) {
  std::error_code error;
  if (!std::filesystem::exists(dir, error)) {
    throw MissingFileError(dir.string() + ": no such folder");
  }
  if (!std::filesystem::is_directory(dir, error)) {
    throw InputError(dir.string() + ": not a directory");
  }
  std::vector<std::filesystem::path> paths;
  std::vector<RejectedImageFile> rejected_here;
  for (const auto& entry : std::filesystem::directory_iterator(dir, error)) {
    std::error_code entry_error;
    if (!entry.is_regular_file(entry_error)) continue;
    if (DetectImageFormat(entry.path()) != ImageFormat::kUnknown) {
      paths.push_back(entry.path());
    } else if (HasImageExtension(entry.path())) {
      const uintmax_t size = std::filesystem::file_size(entry.path(), entry_error);
      rejected_here.push_back(
          {entry.path(), entry_error ? "cannot read the file"
                         : size == 0 ? "empty file"
                                     : "not a PNG, JPEG, TIFF or BMP image (by content)"});
    }
  }
  if (error) throw InputError(dir.string() + ": cannot list: " + error.message());
  const auto by_name = [](const std::filesystem::path& a, const std::filesystem::path& b) {
    return a.filename().string() < b.filename().string();
  };
  std::sort(paths.begin(), paths.end(), by_name);
  if (rejected != nullptr) {
    std::sort(rejected_here.begin(), rejected_here.end(),
              [&](const auto& a, const auto& b) { return by_name(a.path, b.path); });
    rejected->insert(rejected->end(), rejected_here.begin(), rejected_here.end());
  }
  return paths;
}

}  // namespace parallax
