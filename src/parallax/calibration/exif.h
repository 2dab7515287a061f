#pragma once

#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <string_view>

namespace parallax {

// The few EXIF fields that tell a camera's focal length and where it was. Every field is
// optional: cameras write different subsets, and a malformed tag is dropped rather than
// failing the whole block.
struct ExifData {
  std::optional<std::string> make;                 // 0x010F, trailing NULs/spaces trimmed
  std::optional<std::string> model;                // 0x0110
  std::optional<double> focal_length_mm;           // 0x920A FocalLength (RATIONAL)
  std::optional<double> focal_length_35mm;         // 0xA405 FocalLengthIn35mmFilm (SHORT)
  std::optional<double> focal_plane_x_resolution;  // 0xA20E pixels per resolution unit
  std::optional<int> focal_plane_resolution_unit;  // 0xA210: 2 inch, 3 cm (4 mm, 5 µm)
  std::optional<int64_t> pixel_x_dimension;        // 0xA002 width the camera wrote
  std::optional<int64_t> pixel_y_dimension;        // 0xA003 height the camera wrote
  std::optional<int> orientation;                  // 0x0112 in IFD0: 1-8, 1 is upright
  // GPS IFD (tag 0x8825): degrees, north and east positive (refs 'S' and 'W' negate), metres
  // above sea level (AltitudeRef 1 negates). Latitude and longitude are kept only in pairs.
  std::optional<double> gps_latitude;   // 0x0001 ref, 0x0002 3 RATIONALs (deg, min, sec)
  std::optional<double> gps_longitude;  // 0x0003 ref, 0x0004
  std::optional<double> gps_altitude;   // 0x0005 ref, 0x0006 RATIONAL
};

// Parses a TIFF-structured EXIF block ("II*\0" or "MM\0*" header, IFD0, then the Exif IFD that
// tag 0x8769 points to). Nullopt when the header is malformed. Every read is bounds-checked,
// so arbitrary bytes are safe input.
std::optional<ExifData> ParseExifTiff(std::string_view tiff);

// Finds the APP1 "Exif\0\0" segment of a JPEG byte string (before the first scan) and parses
// it. Nullopt when the bytes are not a JPEG, have no EXIF segment, or the segment is malformed.
std::optional<ExifData> ParseJpegExif(std::string_view jpeg);

// Reads the head of a file (EXIF sits in the first 64 KiB segment after SOI) and parses it.
// Nullopt when the file has no usable EXIF; throws InputError naming the path when the file
// cannot be read.
std::optional<ExifData> ReadExif(const std::filesystem::path& path);

// The focal length in pixels of a `width` x `height` image, tried in order of precision:
//  1. FocalLength x FocalPlaneXResolution (pixels per mm on the sensor), rescaled when the
//     image was resized from PixelX/YDimension;
//  2. FocalLength / sensor_width_mm x max(width, height), when the caller knows the sensor;
//  3. FocalLengthIn35mmFilm / 36 x max(width, height) (36 mm is the width of the 35 mm frame).
// Results outside [0.1, 100] x max(width, height) (a field of view of over 157 or under 0.6
// degrees) are treated as bogus tags and skipped. Nullopt when nothing usable is present.
std::optional<double> FocalLengthPixelsFromExif(const ExifData& exif, int width, int height,
                                                std::optional<double> sensor_width_mm = {});

}  // namespace parallax
