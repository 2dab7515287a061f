#include "parallax/calibration/exif_writer.h"

#include <gtest/gtest.h>

#include <opencv2/imgcodecs.hpp>

#include "parallax/util/check.h"

namespace parallax {
namespace {

ExifData SurveyDroneExif() {
  ExifData exif;
  exif.make = "Parallax";
  exif.model = "synth aerial";
  exif.orientation = 1;
  exif.focal_length_mm = 4.5;
  exif.focal_length_35mm = 24;
  exif.pixel_x_dimension = 640;
  exif.pixel_y_dimension = 480;
  exif.gps_latitude = -33.856784;   // South.
  exif.gps_longitude = -70.123456;  // West.
  exif.gps_altitude = 612.25;
  return exif;
}

void ExpectSameFields(const ExifData& expected, const ExifData& actual) {
  EXPECT_EQ(actual.make, expected.make);
  EXPECT_EQ(actual.model, expected.model);
  EXPECT_EQ(actual.orientation, expected.orientation);
  ASSERT_TRUE(actual.focal_length_mm && actual.focal_length_35mm);
  EXPECT_NEAR(*actual.focal_length_mm, *expected.focal_length_mm, 1e-4);
  EXPECT_EQ(*actual.focal_length_35mm, *expected.focal_length_35mm);
  EXPECT_EQ(actual.pixel_x_dimension, expected.pixel_x_dimension);
  EXPECT_EQ(actual.pixel_y_dimension, expected.pixel_y_dimension);
  ASSERT_TRUE(actual.gps_latitude && actual.gps_longitude && actual.gps_altitude);
  // 1/10000 of an arc second is 3 mm on the ground.
  EXPECT_NEAR(*actual.gps_latitude, *expected.gps_latitude, 1e-7);
  EXPECT_NEAR(*actual.gps_longitude, *expected.gps_longitude, 1e-7);
  EXPECT_NEAR(*actual.gps_altitude, *expected.gps_altitude, 1e-4);
}

TEST(ExifWriter, TiffRoundTripKeepsEveryField) {
  const ExifData exif = SurveyDroneExif();
  const std::optional<ExifData> parsed = ParseExifTiff(EncodeExifTiff(exif));
  ASSERT_TRUE(parsed.has_value());
  ExpectSameFields(exif, *parsed);
}

TEST(ExifWriter, NorthEastAndBelowSeaLevel) {
  ExifData exif;
  exif.gps_latitude = 46.5;
  exif.gps_longitude = 6.25;
  exif.gps_altitude = -12.5;
  const std::optional<ExifData> parsed = ParseExifTiff(EncodeExifTiff(exif));
  ASSERT_TRUE(parsed && parsed->gps_latitude && parsed->gps_longitude && parsed->gps_altitude);
  EXPECT_NEAR(*parsed->gps_latitude, 46.5, 1e-9);
  EXPECT_NEAR(*parsed->gps_longitude, 6.25, 1e-9);
  EXPECT_NEAR(*parsed->gps_altitude, -12.5, 1e-9);
  EXPECT_FALSE(parsed->focal_length_mm.has_value());
}

TEST(ExifWriter, GpsWithoutLongitudeIsDropped) {
  ExifData exif;
  exif.gps_latitude = 10.0;  // A latitude alone is no position.
  const std::optional<ExifData> parsed = ParseExifTiff(EncodeExifTiff(exif));
  ASSERT_TRUE(parsed.has_value());
  EXPECT_FALSE(parsed->gps_latitude.has_value());
  EXPECT_FALSE(parsed->gps_longitude.has_value());
}

TEST(ExifWriter, BadLatitudeRefDropsThePosition) {
  ExifData exif = SurveyDroneExif();
  std::string tiff = EncodeExifTiff(exif);
  // The ref "S\0" is stored inline in its entry; make it "X".
  const size_t ref = tiff.find(std::string("S\0\0\0", 4));
  ASSERT_NE(ref, std::string::npos);
  tiff[ref] = 'X';
  const std::optional<ExifData> parsed = ParseExifTiff(tiff);
  ASSERT_TRUE(parsed.has_value());
  EXPECT_FALSE(parsed->gps_latitude.has_value());
  EXPECT_TRUE(parsed->focal_length_mm.has_value());  // The rest of the block survives.
}

TEST(ExifWriter, JpegWithExifStillDecodesAndParses) {
  cv::Mat image(48, 64, CV_8UC3, cv::Scalar(30, 120, 200));
  std::vector<uint8_t> encoded;
  ASSERT_TRUE(cv::imencode(".jpg", image, encoded));
  const std::string jpeg(encoded.begin(), encoded.end());
  const ExifData exif = SurveyDroneExif();
  const std::string with_exif = InsertJpegExif(jpeg, EncodeExifTiff(exif));
  const std::optional<ExifData> parsed = ParseJpegExif(with_exif);
  ASSERT_TRUE(parsed.has_value());
  ExpectSameFields(exif, *parsed);
  const cv::Mat decoded =
      cv::imdecode(std::vector<uint8_t>(with_exif.begin(), with_exif.end()), cv::IMREAD_COLOR);
  EXPECT_EQ(decoded.cols, 64);
  EXPECT_EQ(decoded.rows, 48);
  EXPECT_THROW(InsertJpegExif("not a jpeg", EncodeExifTiff(exif)), CheckError);
}

}  // namespace
}  // namespace parallax
