// Image header sniffing (image/image_reader.h): format by magic number, size from the PNG,
// JPEG, TIFF or BMP header, and the whole read path with a small pixel limit, so the decoders
// only ever see images the header check let through.
#include "fuzz/fuzz_common.h"
#include "parallax/image/image_reader.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string_view bytes = parallax::fuzz::AsStringView(data, size);
  const parallax::ImageFormat format = parallax::DetectImageFormatFromBytes(bytes);
  const std::optional<parallax::ImageSize> header_size = parallax::ReadImageSizeFromBytes(bytes);
  if (header_size) {
    PARALLAX_FUZZ_EXPECT(format != parallax::ImageFormat::kUnknown);
    PARALLAX_FUZZ_EXPECT(header_size->width > 0 && header_size->height > 0);
  }
  parallax::ImageReaderOptions options;
  options.max_image_pixels = 64 * 64;
  parallax::Bitmap bitmap;
  if (!parallax::fuzz::ParsesOrRejects(
          [&] { bitmap = parallax::DecodeBitmap(bytes, "image", options); })) {
    return 0;
  }
  PARALLAX_FUZZ_EXPECT(header_size.has_value());
  PARALLAX_FUZZ_EXPECT(bitmap.Width() == header_size->width);
  PARALLAX_FUZZ_EXPECT(bitmap.Height() == header_size->height);
  PARALLAX_FUZZ_EXPECT(bitmap.color.type() == CV_8UC3 && bitmap.gray.type() == CV_8UC1);
  PARALLAX_FUZZ_EXPECT(bitmap.color.size() == bitmap.gray.size());
  return 0;
}
