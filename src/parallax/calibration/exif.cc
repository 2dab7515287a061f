#include "parallax/calibration/exif.h"

#include <algorithm>
#include <cmath>
#include <fstream>

#include "parallax/util/check.h"
#include "parallax/util/file.h"

namespace parallax {
namespace {

constexpr uint16_t kTagMake = 0x010F;
constexpr uint16_t kTagModel = 0x0110;
constexpr uint16_t kTagOrientation = 0x0112;
constexpr uint16_t kTagExifIfdPointer = 0x8769;
constexpr uint16_t kTagGpsIfdPointer = 0x8825;
constexpr uint16_t kTagFocalLength = 0x920A;
constexpr uint16_t kTagPixelXDimension = 0xA002;
constexpr uint16_t kTagPixelYDimension = 0xA003;
constexpr uint16_t kTagFocalPlaneXResolution = 0xA20E;
constexpr uint16_t kTagFocalPlaneResolutionUnit = 0xA210;
constexpr uint16_t kTagFocalLengthIn35mmFilm = 0xA405;
// Tags of the GPS IFD (their own numbering space).
constexpr uint16_t kTagGpsLatitudeRef = 0x0001;
constexpr uint16_t kTagGpsLatitude = 0x0002;
constexpr uint16_t kTagGpsLongitudeRef = 0x0003;
constexpr uint16_t kTagGpsLongitude = 0x0004;
constexpr uint16_t kTagGpsAltitudeRef = 0x0005;
constexpr uint16_t kTagGpsAltitude = 0x0006;

// TIFF field types.
constexpr uint16_t kTypeByte = 1;
constexpr uint16_t kTypeAscii = 2;
constexpr uint16_t kTypeShort = 3;
constexpr uint16_t kTypeLong = 4;
constexpr uint16_t kTypeRational = 5;
constexpr uint16_t kTypeSShort = 8;
constexpr uint16_t kTypeSLong = 9;
constexpr uint16_t kTypeSRational = 10;

constexpr size_t kIfdEntrySize = 12;
// The EXIF segment is at most 64 KiB and follows SOI (and maybe APP0); this is ample.
constexpr size_t kMaxExifHeadBytes = 1 << 20;

uint64_t TypeSize(uint16_t type) {
  switch (type) {
    case 1:
    case 2:
    case 6:
    case 7:
      return 1;  // BYTE, ASCII, SBYTE, UNDEFINED
    case 3:
    case 8:
      return 2;  // SHORT, SSHORT
    case 4:
    case 9:
    case 11:
      return 4;  // LONG, SLONG, FLOAT
    case 5:
    case 10:
    case 12:
      return 8;  // RATIONAL, SRATIONAL, DOUBLE
    default:
      return 0;
  }
}

// Bounds-checked reads of a TIFF byte string in its declared byte order. Offsets are 64-bit so
// that offset + size never wraps around.
class TiffReader {
 public:
  TiffReader(std::string_view data, bool little_endian)
      : data_(data), little_endian_(little_endian) {}

  bool Contains(uint64_t offset, uint64_t size) const {
    return offset <= data_.size() && size <= data_.size() - offset;
  }
  bool ReadU16(uint64_t offset, uint16_t* value) const {
    if (!Contains(offset, 2)) return false;
    const uint16_t b0 = Byte(offset), b1 = Byte(offset + 1);
    *value = little_endian_ ? static_cast<uint16_t>(b0 | (b1 << 8))
                            : static_cast<uint16_t>((b0 << 8) | b1);
    return true;
  }
  bool ReadU32(uint64_t offset, uint32_t* value) const {
    if (!Contains(offset, 4)) return false;
    uint32_t result = 0;
    for (int i = 0; i < 4; ++i) {
      const uint32_t byte = Byte(offset + (little_endian_ ? 3 - i : i));
      result = (result << 8) | byte;
    }
    *value = result;
    return true;
  }
  uint8_t Byte(uint64_t offset) const { return static_cast<uint8_t>(data_[offset]); }
  std::string_view Bytes(uint64_t offset, uint64_t size) const {
    return data_.substr(offset, size);  // Callers checked Contains(offset, size).
  }

 private:
  std::string_view data_;
  bool little_endian_;
};

// One IFD entry with the absolute offset of its value bytes, already checked to lie inside
// the block.
struct IfdEntry {
  uint16_t tag = 0;
  uint16_t type = 0;
  uint32_t count = 0;
  uint64_t value_offset = 0;
};

bool ReadIfdEntry(const TiffReader& reader, uint64_t entry_offset, IfdEntry* entry) {
  uint32_t count = 0;
  if (!reader.ReadU16(entry_offset, &entry->tag) ||
      !reader.ReadU16(entry_offset + 2, &entry->type) ||
      !reader.ReadU32(entry_offset + 4, &count)) {
    return false;
  }
  entry->count = count;
  const uint64_t type_size = TypeSize(entry->type);
  if (type_size == 0 || count == 0) return false;
  const uint64_t total_size = type_size * count;  // < 2^35: no overflow.
  if (total_size <= 4) {
    entry->value_offset = entry_offset + 8;  // The value is stored inline.
  } else {
    uint32_t offset = 0;
    if (!reader.ReadU32(entry_offset + 8, &offset)) return false;
    entry->value_offset = offset;
  }
  return reader.Contains(entry->value_offset, total_size);
}

// The first value of a numeric entry, as a finite double.
std::optional<double> ReadNumber(const TiffReader& reader, const IfdEntry& entry) {
  double value = 0;
  switch (entry.type) {
    case kTypeByte:
      value = reader.Byte(entry.value_offset);
      break;
    case kTypeShort:
    case kTypeSShort: {
      uint16_t raw = 0;
      if (!reader.ReadU16(entry.value_offset, &raw)) return std::nullopt;
      value = entry.type == kTypeShort ? raw : static_cast<int16_t>(raw);
      break;
    }
    case kTypeLong:
    case kTypeSLong: {
      uint32_t raw = 0;
      if (!reader.ReadU32(entry.value_offset, &raw)) return std::nullopt;
      value = entry.type == kTypeLong ? static_cast<double>(raw)
                                      : static_cast<double>(static_cast<int32_t>(raw));
      break;
    }
    case kTypeRational:
    case kTypeSRational: {
      uint32_t numerator = 0, denominator = 0;
      if (!reader.ReadU32(entry.value_offset, &numerator) ||
          !reader.ReadU32(entry.value_offset + 4, &denominator) || denominator == 0) {
        return std::nullopt;
      }
      value = entry.type == kTypeRational ? static_cast<double>(numerator) / denominator
                                          : static_cast<double>(static_cast<int32_t>(numerator)) /
                                                static_cast<int32_t>(denominator);
      break;
    }
    default:
      return std::nullopt;
  }
  if (!std::isfinite(value)) return std::nullopt;
  return value;
}

std::optional<std::string> ReadAscii(const TiffReader& reader, const IfdEntry& entry) {
  if (entry.type != kTypeAscii) return std::nullopt;
  std::string text(reader.Bytes(entry.value_offset, entry.count));
  text = text.substr(0, text.find('\0'));
  while (!text.empty() && text.back() == ' ') text.pop_back();
  if (text.empty()) return std::nullopt;
  return text;
}

std::optional<int64_t> ReadInteger(const TiffReader& reader, const IfdEntry& entry) {
  if (entry.type != kTypeShort && entry.type != kTypeLong) return std::nullopt;
  const std::optional<double> value = ReadNumber(reader, entry);
  if (!value) return std::nullopt;
  return static_cast<int64_t>(*value);
}

// Offsets of the sub-IFDs that IFD0 points to.
struct SubIfdOffsets {
  std::optional<uint32_t> exif;
  std::optional<uint32_t> gps;
};

// Degrees from the three RATIONALs (degrees, minutes, seconds) of a GPS coordinate.
std::optional<double> ReadDegrees(const TiffReader& reader, const IfdEntry& entry) {
  if (entry.type != kTypeRational || entry.count != 3) return std::nullopt;
  double degrees = 0, unit = 1;
  for (uint64_t k = 0; k < 3; ++k, unit /= 60) {
    IfdEntry part = entry;
    part.value_offset = entry.value_offset + 8 * k;
    const std::optional<double> value = ReadNumber(reader, part);
    if (!value) return std::nullopt;
    degrees += *value * unit;
  }
  return degrees;
}

// The GPS IFD: a position is kept only when both coordinates and their refs are valid.
void ParseGpsIfd(const TiffReader& reader, uint64_t ifd_offset, ExifData* exif) {
  uint16_t num_entries = 0;
  if (!reader.ReadU16(ifd_offset, &num_entries)) return;
  std::optional<double> latitude, longitude, altitude;
  double latitude_sign = 1, longitude_sign = 1, altitude_sign = 1;
  bool latitude_ref_valid = true, longitude_ref_valid = true;
  for (uint64_t i = 0; i < num_entries; ++i) {
    const uint64_t entry_offset = ifd_offset + 2 + i * kIfdEntrySize;
    if (!reader.Contains(entry_offset, kIfdEntrySize)) break;
    IfdEntry entry;
    if (!ReadIfdEntry(reader, entry_offset, &entry)) continue;
    switch (entry.tag) {
      case kTagGpsLatitudeRef: {
        const std::optional<std::string> ref = ReadAscii(reader, entry);
        latitude_ref_valid = ref && (*ref == "N" || *ref == "S");
        latitude_sign = ref && *ref == "S" ? -1 : 1;
        break;
      }
      case kTagGpsLongitudeRef: {
        const std::optional<std::string> ref = ReadAscii(reader, entry);
        longitude_ref_valid = ref && (*ref == "E" || *ref == "W");
        longitude_sign = ref && *ref == "W" ? -1 : 1;
        break;
      }
      case kTagGpsLatitude:
        latitude = ReadDegrees(reader, entry);
        break;
      case kTagGpsLongitude:
        longitude = ReadDegrees(reader, entry);
        break;
      case kTagGpsAltitudeRef:
        if (entry.type == kTypeByte && reader.Byte(entry.value_offset) == 1) altitude_sign = -1;
        break;
      case kTagGpsAltitude:
        altitude = ReadNumber(reader, entry);
        break;
      default:
        break;
    }
  }
  if (latitude && longitude && latitude_ref_valid && longitude_ref_valid &&
      std::abs(*latitude) <= 90 && std::abs(*longitude) <= 180) {
    exif->gps_latitude = latitude_sign * *latitude;
    exif->gps_longitude = longitude_sign * *longitude;
    if (altitude) exif->gps_altitude = altitude_sign * *altitude;
  }
}

// Reads the tags we know from the IFD at `ifd_offset` into `exif`. Returns false when the IFD
// header itself lies outside the block; entries that are malformed are skipped one by one.
bool ParseIfd(const TiffReader& reader, uint64_t ifd_offset, ExifData* exif,
              SubIfdOffsets* sub_ifd_offsets) {
  uint16_t num_entries = 0;
  if (!reader.ReadU16(ifd_offset, &num_entries)) return false;
  for (uint64_t i = 0; i < num_entries; ++i) {
    const uint64_t entry_offset = ifd_offset + 2 + i * kIfdEntrySize;
    if (!reader.Contains(entry_offset, kIfdEntrySize)) break;  // Truncated IFD.
    IfdEntry entry;
    if (!ReadIfdEntry(reader, entry_offset, &entry)) continue;
    switch (entry.tag) {
      case kTagMake:
        exif->make = ReadAscii(reader, entry);
        break;
      case kTagModel:
        exif->model = ReadAscii(reader, entry);
        break;
      case kTagOrientation:
        if (const auto value = ReadInteger(reader, entry); value && *value >= 1 && *value <= 8) {
          exif->orientation = static_cast<int>(*value);
        }
        break;
      case kTagExifIfdPointer:
      case kTagGpsIfdPointer:
        if (sub_ifd_offsets != nullptr) {
          if (const auto value = ReadInteger(reader, entry)) {
            (entry.tag == kTagExifIfdPointer ? sub_ifd_offsets->exif : sub_ifd_offsets->gps) =
                static_cast<uint32_t>(*value);
          }
        }
        break;
      case kTagFocalLength:
        exif->focal_length_mm = ReadNumber(reader, entry);
        break;
      case kTagFocalLengthIn35mmFilm:
        exif->focal_length_35mm = ReadNumber(reader, entry);
        break;
      case kTagFocalPlaneXResolution:
        exif->focal_plane_x_resolution = ReadNumber(reader, entry);
        break;
      case kTagFocalPlaneResolutionUnit:
        if (const auto value = ReadInteger(reader, entry)) {
          exif->focal_plane_resolution_unit = static_cast<int>(*value);
        }
        break;
      case kTagPixelXDimension:
        exif->pixel_x_dimension = ReadInteger(reader, entry);
        break;
      case kTagPixelYDimension:
        exif->pixel_y_dimension = ReadInteger(reader, entry);
        break;
      default:
        break;
    }
  }
  return true;
}

}  // namespace

std::optional<ExifData> ParseExifTiff(std::string_view tiff) {
  if (tiff.size() < 8) return std::nullopt;
  bool little_endian = false;
  if (tiff[0] == 'I' && tiff[1] == 'I') {
    little_endian = true;
  } else if (!(tiff[0] == 'M' && tiff[1] == 'M')) {
    return std::nullopt;
  }
  const TiffReader reader(tiff, little_endian);
  uint16_t magic = 0;
  uint32_t ifd0_offset = 0;
  if (!reader.ReadU16(2, &magic) || magic != 42 || !reader.ReadU32(4, &ifd0_offset)) {
    return std::nullopt;
  }
  ExifData exif;
  SubIfdOffsets sub_ifd_offsets;
  if (!ParseIfd(reader, ifd0_offset, &exif, &sub_ifd_offsets)) return std::nullopt;
  // The Exif IFD holds the focal tags, the GPS IFD the position. Only these two pointers are
  // followed (no next-IFD chains), so a block whose offsets form a cycle cannot loop.
  if (sub_ifd_offsets.exif) ParseIfd(reader, *sub_ifd_offsets.exif, &exif, nullptr);
  if (sub_ifd_offsets.gps) ParseGpsIfd(reader, *sub_ifd_offsets.gps, &exif);
  return exif;
}

std::optional<ExifData> ParseJpegExif(std::string_view jpeg) {
  const auto byte = [&](size_t i) { return static_cast<uint8_t>(jpeg[i]); };
  if (jpeg.size() < 4 || byte(0) != 0xFF || byte(1) != 0xD8) return std::nullopt;
  size_t pos = 2;
  while (pos < jpeg.size()) {
    if (byte(pos) != 0xFF) return std::nullopt;            // Not at a marker: corrupt stream.
    while (pos < jpeg.size() && byte(pos) == 0xFF) ++pos;  // Fill bytes.
    if (pos >= jpeg.size()) return std::nullopt;
    const uint8_t marker = byte(pos++);
    if (marker == 0xDA || marker == 0xD9) return std::nullopt;  // Scan data or end: no EXIF.
    if ((marker >= 0xD0 && marker <= 0xD7) || marker == 0x01) continue;  // No length field.
    if (jpeg.size() - pos < 2) return std::nullopt;
    const size_t length = (static_cast<size_t>(byte(pos)) << 8) | byte(pos + 1);
    if (length < 2) return std::nullopt;
    const size_t payload_begin = pos + 2;
    const size_t available = jpeg.size() - payload_begin;
    const size_t payload_size = length - 2;
    if (marker == 0xE1) {
      // A truncated segment is parsed as far as it goes; the TIFF reader checks every offset.
      const std::string_view payload =
          jpeg.substr(payload_begin, std::min(payload_size, available));
      constexpr std::string_view kExifHeader("Exif\0\0", 6);
      if (payload.substr(0, kExifHeader.size()) == kExifHeader) {
        return ParseExifTiff(payload.substr(kExifHeader.size()));
      }
    }
    if (payload_size > available) return std::nullopt;
    pos = payload_begin + payload_size;
  }
  return std::nullopt;
}

std::optional<ExifData> ReadExif(const std::filesystem::path& path) {
  std::ifstream stream(path, std::ios::binary);
  if (!stream) ThrowCannotOpenForReading(path);
  std::string head(kMaxExifHeadBytes, '\0');
  stream.read(head.data(), static_cast<std::streamsize>(head.size()));
  if (stream.bad()) throw InputError(path.string() + ": read failed");
  head.resize(static_cast<size_t>(stream.gcount()));
  return ParseJpegExif(head);
}

std::optional<double> FocalLengthPixelsFromExif(const ExifData& exif, int width, int height,
                                                std::optional<double> sensor_width_mm) {
  if (width <= 0 || height <= 0) return std::nullopt;
  const double max_size = std::max(width, height);
  const auto plausible = [&](double focal_length) {
    return std::isfinite(focal_length) && focal_length >= 0.1 * max_size &&
           focal_length <= 100 * max_size;
  };
  if (exif.focal_length_mm && *exif.focal_length_mm > 0) {
    const double focal_length_mm = *exif.focal_length_mm;
    if (exif.focal_plane_x_resolution && *exif.focal_plane_x_resolution > 0) {
      // EXIF's default unit is the inch; 4 (mm) and 5 (µm) are common extensions.
      double unit_mm = 0;
      switch (exif.focal_plane_resolution_unit.value_or(2)) {
        case 2:
          unit_mm = 25.4;
          break;
        case 3:
          unit_mm = 10;
          break;
        case 4:
          unit_mm = 1;
          break;
        case 5:
          unit_mm = 1e-3;
          break;
        default:
          break;  // 1 = "no absolute unit": unusable.
      }
      if (unit_mm > 0) {
        double focal_length = focal_length_mm * *exif.focal_plane_x_resolution / unit_mm;
        // The resolution refers to the image the camera wrote; rescale if it was resized since.
        if (exif.pixel_x_dimension && exif.pixel_y_dimension && *exif.pixel_x_dimension > 0 &&
            *exif.pixel_y_dimension > 0) {
          focal_length *= max_size / static_cast<double>(std::max(*exif.pixel_x_dimension,
                                                                  *exif.pixel_y_dimension));
        }
        if (plausible(focal_length)) return focal_length;
      }
    }
    if (sensor_width_mm && *sensor_width_mm > 0) {
      const double focal_length = focal_length_mm / *sensor_width_mm * max_size;
      if (plausible(focal_length)) return focal_length;
    }
  }
  if (exif.focal_length_35mm && *exif.focal_length_35mm > 0) {
    const double focal_length = *exif.focal_length_35mm / 36.0 * max_size;
    if (plausible(focal_length)) return focal_length;
  }
  return std::nullopt;
}

}  // namespace parallax
