#include "parallax/calibration/exif_writer.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

#include "parallax/util/check.h"

namespace parallax {
namespace {

// One IFD being written: entries sorted by tag (as TIFF requires) with their value bytes.
class IfdWriter {
 public:
  void Ascii(uint16_t tag, const std::string& text) { Add(tag, 2, text.size() + 1, text + '\0'); }
  void Byte(uint16_t tag, uint8_t value) {
    Add(tag, 1, 1, std::string(1, static_cast<char>(value)));
  }
  void Short(uint16_t tag, uint16_t value) { Add(tag, 3, 1, Le16(value)); }
  void Long(uint16_t tag, uint32_t value) { Add(tag, 4, 1, Le32(value)); }
  void Rationals(uint16_t tag, const std::vector<double>& values) {
    std::string bytes;
    for (const double value : values) {
      // Denominator 10000 keeps four decimals; the numerator must fit 32 bits.
      const double scaled = std::round(std::clamp(value, 0.0, 4.0e5) * 1e4);
      bytes += Le32(static_cast<uint32_t>(scaled)) + Le32(10000);
    }
    Add(tag, 5, values.size(), bytes);
  }
  bool Empty() const { return entries_.empty(); }

  // The IFD placed at `offset` in the block, followed by its out-of-line values.
  std::string Serialize(uint32_t offset) const {
    std::vector<Entry> entries = entries_;
    std::stable_sort(entries.begin(), entries.end(),
                     [](const Entry& a, const Entry& b) { return a.tag < b.tag; });
    std::string directory = Le16(static_cast<uint16_t>(entries.size()));
    std::string values;
    const uint32_t values_offset = offset + SerializedDirectorySize(entries.size());
    for (const Entry& entry : entries) {
      directory += Le16(entry.tag) + Le16(entry.type) + Le32(entry.count);
      if (entry.bytes.size() <= 4) {
        directory += entry.bytes + std::string(4 - entry.bytes.size(), '\0');
      } else {
        directory += Le32(values_offset + static_cast<uint32_t>(values.size()));
        values += entry.bytes;
        if (values.size() % 2 == 1) values += '\0';  // Values start on word boundaries.
      }
    }
    return directory + Le32(0) + values;
  }

  static std::string Le16(uint16_t value) {
    return {static_cast<char>(value & 0xFF), static_cast<char>(value >> 8)};
  }
  static std::string Le32(uint32_t value) { return Le16(value & 0xFFFF) + Le16(value >> 16); }

 private:
  struct Entry {
    uint16_t tag;
    uint16_t type;
    uint32_t count;
    std::string bytes;
  };
  void Add(uint16_t tag, uint16_t type, size_t count, std::string bytes) {
    entries_.push_back({tag, type, static_cast<uint32_t>(count), std::move(bytes)});
  }
  static uint32_t SerializedDirectorySize(size_t num_entries) {
    return static_cast<uint32_t>(2 + 12 * num_entries + 4);
  }

  std::vector<Entry> entries_;
};

// Degrees, minutes and seconds of an absolute angle.
std::vector<double> DegreesMinutesSeconds(double degrees) {
  degrees = std::abs(degrees);
  const double whole_degrees = std::floor(degrees);
  const double minutes = (degrees - whole_degrees) * 60;
  const double whole_minutes = std::floor(minutes);
  return {whole_degrees, whole_minutes, (minutes - whole_minutes) * 60};
}

}  // namespace

std::string EncodeExifTiff(const ExifData& exif) {
  IfdWriter exif_ifd, gps_ifd;
  if (exif.focal_length_mm) exif_ifd.Rationals(0x920A, {*exif.focal_length_mm});
  if (exif.focal_length_35mm) {
    exif_ifd.Short(0xA405, static_cast<uint16_t>(std::lround(*exif.focal_length_35mm)));
  }
  if (exif.focal_plane_x_resolution) exif_ifd.Rationals(0xA20E, {*exif.focal_plane_x_resolution});
  if (exif.focal_plane_resolution_unit) {
    exif_ifd.Short(0xA210, static_cast<uint16_t>(*exif.focal_plane_resolution_unit));
  }
  if (exif.pixel_x_dimension) exif_ifd.Long(0xA002, static_cast<uint32_t>(*exif.pixel_x_dimension));
  if (exif.pixel_y_dimension) exif_ifd.Long(0xA003, static_cast<uint32_t>(*exif.pixel_y_dimension));
  if (exif.gps_latitude && exif.gps_longitude) {
    gps_ifd.Ascii(0x0001, *exif.gps_latitude < 0 ? "S" : "N");
    gps_ifd.Rationals(0x0002, DegreesMinutesSeconds(*exif.gps_latitude));
    gps_ifd.Ascii(0x0003, *exif.gps_longitude < 0 ? "W" : "E");
    gps_ifd.Rationals(0x0004, DegreesMinutesSeconds(*exif.gps_longitude));
    if (exif.gps_altitude) {
      gps_ifd.Byte(0x0005, *exif.gps_altitude < 0 ? 1 : 0);
      gps_ifd.Rationals(0x0006, {std::abs(*exif.gps_altitude)});
    }
  }
  const bool has_exif_ifd = !exif_ifd.Empty(), has_gps_ifd = !gps_ifd.Empty();
  // IFD0 holds the pointers to the other two, whose offsets depend on IFD0's size but not
  // the other way round: lay it out once with placeholders, then for real.
  const auto make_ifd0 = [&](uint32_t exif_offset, uint32_t gps_offset) {
    IfdWriter ifd0;
    if (exif.make) ifd0.Ascii(0x010F, *exif.make);
    if (exif.model) ifd0.Ascii(0x0110, *exif.model);
    if (exif.orientation) ifd0.Short(0x0112, static_cast<uint16_t>(*exif.orientation));
    if (has_exif_ifd) ifd0.Long(0x8769, exif_offset);
    if (has_gps_ifd) ifd0.Long(0x8825, gps_offset);
    return ifd0;
  };
  constexpr uint32_t kIfd0Offset = 8;
  const uint32_t exif_offset =
      kIfd0Offset + static_cast<uint32_t>(make_ifd0(0, 0).Serialize(kIfd0Offset).size());
  const uint32_t gps_offset =
      exif_offset +
      (has_exif_ifd ? static_cast<uint32_t>(exif_ifd.Serialize(exif_offset).size()) : 0);

  std::string tiff = "II" + IfdWriter::Le16(42) + IfdWriter::Le32(kIfd0Offset);
  tiff += make_ifd0(exif_offset, gps_offset).Serialize(kIfd0Offset);
  if (has_exif_ifd) tiff += exif_ifd.Serialize(exif_offset);
  if (has_gps_ifd) tiff += gps_ifd.Serialize(gps_offset);
  return tiff;
}

std::string InsertJpegExif(std::string_view jpeg, std::string_view tiff) {
  PARALLAX_CHECK_MSG(jpeg.size() >= 2 && static_cast<uint8_t>(jpeg[0]) == 0xFF &&
                         static_cast<uint8_t>(jpeg[1]) == 0xD8,
                     "not a JPEG stream (no SOI marker)");
  constexpr std::string_view kExifHeader("Exif\0\0", 6);
  const size_t length = 2 + kExifHeader.size() + tiff.size();
  PARALLAX_CHECK_LE(length, 0xFFFFu);
  std::string result(jpeg.substr(0, 2));
  result += {'\xFF', '\xE1', static_cast<char>(length >> 8), static_cast<char>(length & 0xFF)};
  result += kExifHeader;
  result += tiff;
  result += jpeg.substr(2);
  return result;
}

}  // namespace parallax
