// EXIF (calibration/exif.h): the JPEG APP1 walk, the TIFF-structured block and the focal
// length derived from it. Arbitrary bytes must parse or be refused, never read out of bounds.
#include <cmath>

#include "fuzz/fuzz_common.h"
#include "parallax/calibration/exif.h"

namespace {

void CheckFocalLength(const parallax::ExifData& exif) {
  for (const auto& [width, height] :
       {std::pair{640, 480}, std::pair{1, 1}, std::pair{8000, 6000}}) {
    const std::optional<double> focal =
        parallax::FocalLengthPixelsFromExif(exif, width, height, 6.17);
    if (focal) {
      PARALLAX_FUZZ_EXPECT(std::isfinite(*focal));
      PARALLAX_FUZZ_EXPECT(*focal > 0);
    }
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string_view bytes = parallax::fuzz::AsStringView(data, size);
  parallax::fuzz::ParsesOrRejects([&] {
    if (const auto exif = parallax::ParseJpegExif(bytes)) CheckFocalLength(*exif);
    if (const auto exif = parallax::ParseExifTiff(bytes)) CheckFocalLength(*exif);
  });
  return 0;
}
