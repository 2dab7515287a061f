#pragma once

#include <string>
#include <string_view>

#include "parallax/calibration/exif.h"

namespace parallax {

// Encodes the fields of `exif` that are set as a little-endian TIFF block, the inverse of
// ParseExifTiff: IFD0 (make, model, orientation), the Exif IFD (focal tags, pixel
// dimensions) and the GPS IFD. Rationals keep 1/10000 of a unit (a few millimetres of GPS
// position), so parsing the block back gives the fields to that precision.
std::string EncodeExifTiff(const ExifData& exif);

// `jpeg` with an APP1 "Exif" segment holding `tiff` right after its SOI marker, where
// cameras write it. Checks that `jpeg` starts with SOI and that `tiff` fits one segment.
std::string InsertJpegExif(std::string_view jpeg, std::string_view tiff);

}  // namespace parallax
