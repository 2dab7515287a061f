#include "parallax/calibration/exif.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "parallax/math/random.h"
#include "parallax/util/check.h"
#include "parallax/util/file.h"

namespace parallax {
namespace {

// Builds a TIFF/EXIF block by hand in either byte order: IFD0 at offset 8, followed by its
// out-of-line values, then the Exif IFD (pointed to by tag 0x8769) and its values.
class TiffBuilder {
 public:
  explicit TiffBuilder(bool little_endian) : little_endian_(little_endian) {}

  void AddAscii(bool exif_ifd, uint16_t tag, const std::string& text) {
    Add(exif_ifd, tag, 2, static_cast<uint32_t>(text.size() + 1), text + '\0');
  }
  void AddShort(bool exif_ifd, uint16_t tag, uint16_t value) {
    Add(exif_ifd, tag, 3, 1, U16(value));
  }
  void AddLong(bool exif_ifd, uint16_t tag, uint32_t value) {
    Add(exif_ifd, tag, 4, 1, U32(value));
  }
  void AddRational(bool exif_ifd, uint16_t tag, uint32_t numerator, uint32_t denominator) {
    Add(exif_ifd, tag, 5, 1, U32(numerator) + U32(denominator));
  }
  // An entry with raw fields, for malformed cases.
  void AddRaw(bool exif_ifd, uint16_t tag, uint16_t type, uint32_t count,
              const std::string& value) {
    Add(exif_ifd, tag, type, count, value);
  }

  std::string Build() const {
    std::string tiff = little_endian_ ? "II" : "MM";
    tiff += U16(42) + U32(8);
    const uint32_t ifd0_offset = 8;
    const bool has_exif_ifd = !exif_entries_.empty();
    const uint32_t ifd0_size = IfdSize(ifd0_entries_.size() + (has_exif_ifd ? 1 : 0));
    const uint32_t ifd0_data_size = DataSize(ifd0_entries_);
    const uint32_t exif_offset = ifd0_offset + ifd0_size + ifd0_data_size;
    std::vector<Entry> ifd0 = ifd0_entries_;
    if (has_exif_ifd) ifd0.push_back({0x8769, 4, 1, U32(exif_offset)});
    tiff += WriteIfd(ifd0, ifd0_offset);
    if (has_exif_ifd) tiff += WriteIfd(exif_entries_, exif_offset);
    return tiff;
  }

  std::string U16(uint16_t value) const {
    const char b0 = static_cast<char>(value & 0xFF), b1 = static_cast<char>(value >> 8);
    return little_endian_ ? std::string{b0, b1} : std::string{b1, b0};
  }
  std::string U32(uint32_t value) const {
    return little_endian_ ? U16(value & 0xFFFF) + U16(value >> 16)
                          : U16(value >> 16) + U16(value & 0xFFFF);
  }

 private:
  struct Entry {
    uint16_t tag;
    uint16_t type;
    uint32_t count;
    std::string value;
  };

  void Add(bool exif_ifd, uint16_t tag, uint16_t type, uint32_t count, const std::string& value) {
    (exif_ifd ? exif_entries_ : ifd0_entries_).push_back({tag, type, count, value});
  }
  static uint32_t IfdSize(size_t num_entries) { return 2 + 12 * num_entries + 4; }
  static uint32_t DataSize(const std::vector<Entry>& entries) {
    uint32_t size = 0;
    for (const Entry& entry : entries) {
      if (entry.value.size() > 4) size += entry.value.size();
    }
    return size;
  }
  // The IFD at `offset` followed by its out-of-line values.
  std::string WriteIfd(const std::vector<Entry>& entries, uint32_t offset) const {
    std::string ifd = U16(static_cast<uint16_t>(entries.size()));
    std::string data;
    uint32_t data_offset = offset + IfdSize(entries.size());
    for (const Entry& entry : entries) {
      ifd += U16(entry.tag) + U16(entry.type) + U32(entry.count);
      if (entry.value.size() <= 4) {
        ifd += entry.value + std::string(4 - entry.value.size(), '\0');
      } else {
        ifd += U32(data_offset + data.size());
        data += entry.value;
      }
    }
    return ifd + U32(0) + data;
  }

  bool little_endian_;
  std::vector<Entry> ifd0_entries_;
  std::vector<Entry> exif_entries_;
};

std::string Segment(uint8_t marker, const std::string& payload) {
  const size_t length = payload.size() + 2;
  return std::string{'\xFF', static_cast<char>(marker), static_cast<char>(length >> 8),
                     static_cast<char>(length & 0xFF)} +
         payload;
}

// SOI, APP0 (JFIF), an XMP APP1, the EXIF APP1, then a start of scan and some entropy bytes.
std::string MakeJpeg(const std::string& tiff) {
  std::string jpeg = "\xFF\xD8";
  jpeg += Segment(0xE0, std::string("JFIF\0\x01\x01\0\0\x01\0\x01\0\0", 14));
  jpeg += Segment(0xE1, std::string("http://ns.adobe.com/xap/1.0/\0<x/>", 34));
  jpeg += Segment(0xE1, std::string("Exif\0\0", 6) + tiff);
  jpeg += Segment(0xDA, std::string("\x01\x01\0\0\x3F\0", 6));
  jpeg += "\x12\x34\xFF\x00\x56\xFF\xD9";
  return jpeg;
}

// A Canon-like block: 50 mm lens, 4368 x 2912 sensor image, 3888000/1415 pixels per inch.
std::string MakeTypicalTiff(bool little_endian) {
  TiffBuilder builder(little_endian);
  builder.AddAscii(false, 0x010F, "Canon");
  builder.AddAscii(false, 0x0110, "Canon EOS 5D  ");
  builder.AddShort(false, 0x0112, 6);  // Rotate 90 degrees clockwise to view.
  builder.AddRational(true, 0x920A, 50, 1);
  builder.AddShort(true, 0xA405, 80);
  builder.AddRational(true, 0xA20E, 3888000, 1415);
  builder.AddShort(true, 0xA210, 2);
  builder.AddLong(true, 0xA002, 4368);
  builder.AddShort(true, 0xA003, 2912);
  return builder.Build();
}

void ExpectTypicalExif(const std::optional<ExifData>& exif) {
  ASSERT_TRUE(exif.has_value());
  EXPECT_EQ(exif->make, "Canon");
  EXPECT_EQ(exif->model, "Canon EOS 5D");
  EXPECT_EQ(exif->orientation, 6);
  ASSERT_TRUE(exif->focal_length_mm.has_value());
  EXPECT_DOUBLE_EQ(*exif->focal_length_mm, 50);
  EXPECT_EQ(exif->focal_length_35mm, 80);
  ASSERT_TRUE(exif->focal_plane_x_resolution.has_value());
  EXPECT_DOUBLE_EQ(*exif->focal_plane_x_resolution, 3888000.0 / 1415);
  EXPECT_EQ(exif->focal_plane_resolution_unit, 2);
  EXPECT_EQ(exif->pixel_x_dimension, 4368);
  EXPECT_EQ(exif->pixel_y_dimension, 2912);
}

TEST(Exif, ParsesLittleEndianBlock) { ExpectTypicalExif(ParseExifTiff(MakeTypicalTiff(true))); }

TEST(Exif, ParsesBigEndianBlock) { ExpectTypicalExif(ParseExifTiff(MakeTypicalTiff(false))); }

TEST(Exif, FindsExifSegmentInJpegInBothByteOrders) {
  ExpectTypicalExif(ParseJpegExif(MakeJpeg(MakeTypicalTiff(true))));
  ExpectTypicalExif(ParseJpegExif(MakeJpeg(MakeTypicalTiff(false))));
}

TEST(Exif, ReadsFromFileAndNamesMissingFile) {
  const auto dir = std::filesystem::temp_directory_path() / "parallax_exif_test";
  std::filesystem::create_directories(dir);
  const auto path = dir / "photo.jpg";
  WriteTextFileAtomically(path, MakeJpeg(MakeTypicalTiff(false)));
  ExpectTypicalExif(ReadExif(path));
  try {
    ReadExif(dir / "missing.jpg");
    ADD_FAILURE() << "expected InputError";
  } catch (const InputError& error) {
    EXPECT_EQ(std::string(error.what()).rfind((dir / "missing.jpg").string(), 0), 0u);
  }
  std::filesystem::remove_all(dir);
}

TEST(Exif, ReturnsNulloptWithoutExif) {
  EXPECT_FALSE(ParseJpegExif("").has_value());
  EXPECT_FALSE(ParseJpegExif("\x89PNG\r\n\x1a\n").has_value());
  std::string jpeg = "\xFF\xD8";
  jpeg += Segment(0xE0, std::string("JFIF\0\x01\x01\0\0\x01\0\x01\0\0", 14));
  jpeg += Segment(0xDA, std::string("\x01\x01\0\0\x3F\0", 6));
  EXPECT_FALSE(ParseJpegExif(jpeg).has_value());
  // APP1 whose payload is not EXIF.
  EXPECT_FALSE(ParseJpegExif("\xFF\xD8" + Segment(0xE1, "Exig0000II*\0")).has_value());
  EXPECT_FALSE(ParseExifTiff("II*\0").has_value());
  EXPECT_FALSE(ParseExifTiff(std::string("XX*\0\x08\0\0\0\0\0", 10)).has_value());
  EXPECT_FALSE(ParseExifTiff(std::string("II+\0\x08\0\0\0\0\0", 10)).has_value());

  // The shared checkerboard photos carry JFIF only.
  const auto photo = DataRoot() / "checkerboard" / "images" / "c4.jpg";
  if (std::filesystem::exists(photo)) {
    EXPECT_FALSE(ReadExif(photo).has_value());
  }
}

TEST(Exif, MalformedOffsetsDropTagsNotBlock) {
  TiffBuilder builder(true);
  builder.AddAscii(false, 0x010F, "Nikon");
  // FocalLength whose value offset points past the end of the block.
  builder.AddRaw(true, 0x920A, 5, 1, builder.U32(0xFFFFFFF0));
  // Rational with a zero denominator.
  builder.AddRational(true, 0xA20E, 1000, 0);
  // A count so large that count x size overflows 32 bits.
  builder.AddRaw(true, 0x0110, 2, 0xFFFFFFFF, builder.U32(16));
  // Unknown type.
  builder.AddRaw(true, 0xA405, 99, 1, builder.U32(50));
  builder.AddShort(true, 0xA002, 640);
  const auto exif = ParseExifTiff(builder.Build());
  ASSERT_TRUE(exif.has_value());
  EXPECT_EQ(exif->make, "Nikon");
  EXPECT_FALSE(exif->focal_length_mm.has_value());
  EXPECT_FALSE(exif->focal_plane_x_resolution.has_value());
  EXPECT_FALSE(exif->model.has_value());
  EXPECT_FALSE(exif->focal_length_35mm.has_value());
  EXPECT_EQ(exif->pixel_x_dimension, 640);
}

TEST(Exif, BadIfdPointers) {
  TiffBuilder builder(false);
  builder.AddAscii(false, 0x010F, "Sony");
  std::string tiff = builder.Build();
  // IFD0 beyond the end: not a usable block.
  std::string bad_ifd0 = tiff;
  bad_ifd0.replace(4, 4, builder.U32(0x7FFFFFFF));
  EXPECT_FALSE(ParseExifTiff(bad_ifd0).has_value());

  // Exif IFD pointer beyond the end, and one pointing back at IFD0 (a cycle): IFD0's tags stay.
  for (uint32_t exif_offset : {0xFFFFFFFFu, 8u}) {
    TiffBuilder cyclic(true);
    cyclic.AddAscii(false, 0x010F, "Sony");
    cyclic.AddLong(false, 0x8769, exif_offset);
    const auto exif = ParseExifTiff(cyclic.Build());
    ASSERT_TRUE(exif.has_value());
    EXPECT_EQ(exif->make, "Sony");
  }

  // An IFD that claims more entries than the block holds keeps the complete ones.
  TiffBuilder claims(true);
  claims.AddShort(false, 0xA405, 28);
  std::string truncated = claims.Build();
  truncated.replace(8, 2, claims.U16(5000));
  const auto exif = ParseExifTiff(truncated);
  ASSERT_TRUE(exif.has_value());
  EXPECT_EQ(exif->focal_length_35mm, 28);
}

TEST(Exif, TruncatedJpegsNeverReadOutOfBounds) {
  for (const bool little_endian : {true, false}) {
    const std::string jpeg = MakeJpeg(MakeTypicalTiff(little_endian));
    for (size_t size = 0; size <= jpeg.size(); ++size) {
      // A copy of exactly `size` bytes, so that a sanitizer sees any overread.
      const std::string prefix = jpeg.substr(0, size);
      const auto exif = ParseJpegExif(prefix);
      if (size == jpeg.size()) ExpectTypicalExif(exif);
    }
  }
}

TEST(Exif, RandomCorruptionNeverReadsOutOfBounds) {
  const std::string original = MakeJpeg(MakeTypicalTiff(true));
  int num_parsed = 0;
  for (int trial = 0; trial < 20000; ++trial) {
    std::string jpeg = original;
    const int num_flips = static_cast<int>(RandomUniformInteger(1, 8));
    for (int i = 0; i < num_flips; ++i) {
      jpeg[RandomUniformInteger(0, jpeg.size() - 1)] =
          static_cast<char>(RandomUniformInteger(0, 255));
    }
    jpeg.resize(RandomUniformInteger(jpeg.size() / 2, jpeg.size()));
    if (const auto exif = ParseJpegExif(jpeg)) {
      ++num_parsed;
      if (exif->focal_length_mm) {
        EXPECT_TRUE(std::isfinite(*exif->focal_length_mm));
      }
      if (exif->make) {
        EXPECT_LE(exif->make->size(), jpeg.size());
      }
    }
  }
  EXPECT_GT(num_parsed, 0);
}

TEST(Exif, FocalLengthFrom35mmEquivalent) {
  ExifData exif;
  exif.focal_length_35mm = 36;
  EXPECT_DOUBLE_EQ(*FocalLengthPixelsFromExif(exif, 4000, 3000), 4000);
  EXPECT_DOUBLE_EQ(*FocalLengthPixelsFromExif(exif, 3000, 4000), 4000);
  exif.focal_length_35mm = 27;
  EXPECT_DOUBLE_EQ(*FocalLengthPixelsFromExif(exif, 1200, 900), 900);
  EXPECT_FALSE(FocalLengthPixelsFromExif(exif, 0, 900).has_value());
  exif.focal_length_35mm = 0;
  EXPECT_FALSE(FocalLengthPixelsFromExif(exif, 1200, 900).has_value());
  exif.focal_length_35mm = 100000;  // A field of view of 0.02 degrees: a bogus tag.
  EXPECT_FALSE(FocalLengthPixelsFromExif(exif, 1200, 900).has_value());
  EXPECT_FALSE(FocalLengthPixelsFromExif(ExifData(), 1200, 900).has_value());
}

TEST(Exif, FocalLengthFromFocalPlaneResolution) {
  const ExifData exif = *ParseExifTiff(MakeTypicalTiff(true));
  const double pixels_per_mm = 3888000.0 / 1415 / 25.4;
  // Preferred over the (rounded) 35 mm equivalent.
  EXPECT_NEAR(*FocalLengthPixelsFromExif(exif, 4368, 2912), 50 * pixels_per_mm, 1e-9);
  // Resized to half: the focal length in pixels halves too.
  EXPECT_NEAR(*FocalLengthPixelsFromExif(exif, 2184, 1456), 25 * pixels_per_mm, 1e-9);

  ExifData centimetres = exif;
  centimetres.focal_plane_resolution_unit = 3;
  centimetres.focal_plane_x_resolution = 1000;  // 100 pixels per mm.
  EXPECT_NEAR(*FocalLengthPixelsFromExif(centimetres, 4368, 2912), 5000, 1e-9);
  ExifData no_unit = exif;
  no_unit.focal_plane_x_resolution = 1000;
  no_unit.focal_plane_resolution_unit.reset();  // EXIF's default: inches.
  EXPECT_NEAR(*FocalLengthPixelsFromExif(no_unit, 4368, 2912), 50 * 1000 / 25.4, 1e-9);

  // Unit 1 means "no absolute unit": fall back to the 35 mm equivalent (80 mm).
  ExifData relative = exif;
  relative.focal_plane_resolution_unit = 1;
  EXPECT_NEAR(*FocalLengthPixelsFromExif(relative, 4368, 2912), 80.0 / 36 * 4368, 1e-9);
}

TEST(Exif, FocalLengthFromSensorWidth) {
  ExifData exif;
  exif.focal_length_mm = 4.5;
  EXPECT_FALSE(FocalLengthPixelsFromExif(exif, 4000, 3000).has_value());
  EXPECT_NEAR(*FocalLengthPixelsFromExif(exif, 4000, 3000, 6.0), 3000, 1e-9);
  exif.focal_length_35mm = 24;
  EXPECT_NEAR(*FocalLengthPixelsFromExif(exif, 4000, 3000, 6.0), 3000, 1e-9);
  EXPECT_NEAR(*FocalLengthPixelsFromExif(exif, 4000, 3000), 24.0 / 36 * 4000, 1e-9);
}

}  // namespace
}  // namespace parallax
