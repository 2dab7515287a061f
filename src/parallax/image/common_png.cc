#include "parallax/image/common_png.h"

#include <libdeflate.h>

#include <algorithm>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <memory>
#include <utility>
#include <vector>

#include "parallax/util/byte_order.h"

namespace parallax {
namespace {

constexpr uint8_t kSignature[8] = {137, 80, 78, 71, 13, 10, 26, 10};
constexpr size_t kIhdrLength = 13;
// The largest image decoded here; a larger one goes to libpng, which has its own limits.
constexpr size_t kMaxBytes = std::numeric_limits<int>::max();

struct DecompressorDeleter {
  void operator()(libdeflate_decompressor* decompressor) const {
    libdeflate_free_decompressor(decompressor);
  }
};

// What decoding needs besides the image, one per thread and reused from image to image: the
// decompressor (32 KB of tables), the image data of several IDAT chunks joined, and the
// inflated rows. A megabyte allocated afresh for each templeRing photo came back from the
// kernel page by page, and the faults outlasted the decoding (docs/performance.md,
// "PNG: decoding buffers reused per thread").
struct DecodingBuffers {
  std::unique_ptr<libdeflate_decompressor, DecompressorDeleter> decompressor{
      libdeflate_alloc_decompressor()};
  std::vector<uint8_t> joined, filtered;

  // Buffers this large are not kept for the next image.
  static constexpr size_t kMaxKeptBytes = size_t{64} << 20;
  void Trim() {
    for (std::vector<uint8_t>* buffer : {&joined, &filtered}) {
      if (buffer->capacity() > kMaxKeptBytes) std::vector<uint8_t>().swap(*buffer);
    }
  }
};

DecodingBuffers& ThreadBuffers() {
  thread_local DecodingBuffers buffers;
  return buffers;
}

bool ChunkIs(const uint8_t* type, const char* name) { return std::memcmp(type, name, 4) == 0; }

uint8_t Paeth(int left, int above, int upper_left) {
  const int estimate = left + above - upper_left;
  const int to_left = std::abs(estimate - left), to_above = std::abs(estimate - above),
            to_upper_left = std::abs(estimate - upper_left);
  if (to_left <= to_above && to_left <= to_upper_left) return static_cast<uint8_t>(left);
  return static_cast<uint8_t>(to_above <= to_upper_left ? above : upper_left);
}

// Undoes the Sub filter (each byte adds the one bpp before it) with the running sums in
// registers, one per byte of a pixel: through memory, each byte waited for the store of the byte
// bpp before it, which was most of decoding a templeRing photo, all of whose rows are Sub
// (docs/performance.md, "PNG: the Sub filter undone in registers").
template <int kBpp>
void UndoSub(const uint8_t* in, size_t length, uint8_t* out) {
  static_assert(kBpp == 1 || kBpp == 3 || kBpp == 4);
  uint8_t sum0 = 0, sum1 = 0, sum2 = 0, sum3 = 0;
  for (size_t x = 0; x < length; x += kBpp) {
    out[x] = sum0 = static_cast<uint8_t>(sum0 + in[x]);
    if constexpr (kBpp >= 3) {
      out[x + 1] = sum1 = static_cast<uint8_t>(sum1 + in[x + 1]);
      out[x + 2] = sum2 = static_cast<uint8_t>(sum2 + in[x + 2]);
    }
    if constexpr (kBpp == 4) out[x + 3] = sum3 = static_cast<uint8_t>(sum3 + in[x + 3]);
  }
}

// Undoes one row's filter (PNG specification, section 9): `prior` is the row above,
// already unfiltered (zeros above the first), `bpp` the bytes per pixel. False for an
// unknown filter type.
bool UnfilterRow(int filter, const uint8_t* in, const uint8_t* prior, int bpp, size_t length,
                 uint8_t* out) {
  const size_t first = std::min<size_t>(bpp, length);
  switch (filter) {
    case 0:
      std::memcpy(out, in, length);
      return true;
    case 1:
      // Rows are whole pixels (a length that is a multiple of bpp).
      if (bpp == 1) {
        UndoSub<1>(in, length, out);
      } else if (bpp == 3) {
        UndoSub<3>(in, length, out);
      } else if (bpp == 4) {
        UndoSub<4>(in, length, out);
      } else {
        std::memcpy(out, in, first);
        for (size_t x = first; x < length; ++x) {
          out[x] = static_cast<uint8_t>(in[x] + out[x - bpp]);
        }
      }
      return true;
    case 2:
      for (size_t x = 0; x < length; ++x) out[x] = static_cast<uint8_t>(in[x] + prior[x]);
      return true;
    case 3:
      for (size_t x = 0; x < first; ++x) out[x] = static_cast<uint8_t>(in[x] + (prior[x] >> 1));
      for (size_t x = first; x < length; ++x) {
        out[x] = static_cast<uint8_t>(in[x] + ((out[x - bpp] + prior[x]) >> 1));
      }
      return true;
    case 4:
      for (size_t x = 0; x < first; ++x) out[x] = static_cast<uint8_t>(in[x] + prior[x]);
      for (size_t x = first; x < length; ++x) {
        out[x] = static_cast<uint8_t>(in[x] + Paeth(out[x - bpp], prior[x], prior[x - bpp]));
      }
      return true;
    default:
      return false;
  }
}

void SwapRedAndBlue(int channels, size_t length, uint8_t* row) {
  for (size_t x = 0; x + 2 < length; x += channels) std::swap(row[x], row[x + 2]);
}

}  // namespace

std::optional<cv::Mat> DecodeCommonPng(std::string_view bytes) {
  const auto* data = reinterpret_cast<const uint8_t*>(bytes.data());
  const size_t size = bytes.size();
  if (size < sizeof(kSignature) || std::memcmp(data, kSignature, sizeof(kSignature)) != 0) {
    return std::nullopt;
  }
  // The chunks: IHDR first, then the image data (consecutive IDAT chunks) until IEND.
  uint32_t width = 0, height = 0;
  int channels = 0;
  std::vector<std::string_view> image_data;  // The IDAT chunks' bodies.
  bool seen_header = false, seen_data = false, data_ended = false, seen_end = false;
  for (size_t pos = sizeof(kSignature); !seen_end;) {
    if (size - pos < 12) return std::nullopt;
    const uint32_t length = BigEndian32(data + pos);
    const uint8_t* type = data + pos + 4;
    const uint8_t* body = data + pos + 8;
    if (length > size - pos - 12) return std::nullopt;
    if (libdeflate_crc32(0, type, 4 + size_t{length}) != BigEndian32(body + length)) {
      return std::nullopt;
    }
    pos += 12 + size_t{length};
    if (!seen_header) {
      if (!ChunkIs(type, "IHDR") || length != kIhdrLength) return std::nullopt;
      width = BigEndian32(body);
      height = BigEndian32(body + 4);
      const uint8_t bit_depth = body[8], color_type = body[9];
      const bool simple =
          body[10] == 0 && body[11] == 0 && body[12] == 0;  // Deflate, filters, no interlace.
      channels = color_type == 0 ? 1 : color_type == 2 ? 3 : color_type == 6 ? 4 : 0;
      if (bit_depth != 8 || channels == 0 || !simple || width == 0 || height == 0) {
        return std::nullopt;
      }
      seen_header = true;
      continue;
    }
    if (ChunkIs(type, "IDAT")) {
      if (data_ended) return std::nullopt;
      seen_data = true;
      image_data.emplace_back(reinterpret_cast<const char*>(body), length);
      continue;
    }
    data_ended = seen_data;
    if (ChunkIs(type, "IEND")) {
      seen_end = true;
      continue;
    }
    // A suggested palette for colour and ancillary chunks are skipped, as libpng skips them
    // for this layout; transparency, a palette for gray or after the data, a second header
    // or another critical chunk are left to libpng.
    const bool suggested_palette = ChunkIs(type, "PLTE") && channels >= 3 && !seen_data;
    const bool ancillary = (type[0] & 0x20) != 0;
    if (ChunkIs(type, "tRNS") || (!ancillary && !suggested_palette)) return std::nullopt;
  }
  if (!seen_data) return std::nullopt;

  const size_t row_bytes = size_t{width} * channels;
  if (row_bytes > kMaxBytes || height > kMaxBytes / row_bytes) return std::nullopt;
  DecodingBuffers& buffers = ThreadBuffers();
  struct TrimOnExit {
    DecodingBuffers& buffers;
    ~TrimOnExit() { buffers.Trim(); }
  } trim_on_exit{buffers};
  std::string_view compressed = image_data.front();
  if (image_data.size() > 1) {
    buffers.joined.clear();
    for (const std::string_view chunk : image_data) {
      buffers.joined.insert(buffers.joined.end(), chunk.begin(), chunk.end());
    }
    compressed = {reinterpret_cast<const char*>(buffers.joined.data()), buffers.joined.size()};
  }
  // Each row of the stream is one filter-type byte and the row's filtered bytes.
  std::vector<uint8_t>& filtered = buffers.filtered;
  filtered.resize(size_t{height} * (row_bytes + 1));
  size_t decompressed = 0;
  if (buffers.decompressor == nullptr ||
      libdeflate_zlib_decompress(buffers.decompressor.get(), compressed.data(), compressed.size(),
                                 filtered.data(), filtered.size(),
                                 &decompressed) != LIBDEFLATE_SUCCESS ||
      decompressed != filtered.size()) {
    return std::nullopt;
  }
  cv::Mat image(static_cast<int>(height), static_cast<int>(width), CV_8UC(channels));
  const std::vector<uint8_t> zeros(row_bytes, 0);
  for (int y = 0; y < image.rows; ++y) {
    const uint8_t* in = filtered.data() + static_cast<size_t>(y) * (row_bytes + 1);
    const uint8_t* prior = y == 0 ? zeros.data() : image.ptr<uint8_t>(y - 1);
    if (!UnfilterRow(in[0], in + 1, prior, channels, row_bytes, image.ptr<uint8_t>(y))) {
      return std::nullopt;
    }
    // Row y - 1 in BGR(A) order, now that row y no longer reads it in the file's order.
    if (y > 0 && channels >= 3) SwapRedAndBlue(channels, row_bytes, image.ptr<uint8_t>(y - 1));
  }
  if (channels >= 3) SwapRedAndBlue(channels, row_bytes, image.ptr<uint8_t>(image.rows - 1));
  return image;
}

}  // namespace parallax
