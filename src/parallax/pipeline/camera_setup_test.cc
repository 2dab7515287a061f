#include "parallax/pipeline/camera_setup.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdint>
#include <fstream>
#include <opencv2/imgcodecs.hpp>

#include "parallax/calibration/camera_json.h"
#include "parallax/calibration/exif.h"
#include "parallax/util/check.h"
#include "parallax/util/test_dir.h"

namespace parallax {
namespace {

namespace fs = std::filesystem;

class CameraSetupTest : public ::testing::Test {
 protected:
  fs::path WriteText(const std::string& name, const std::string& text) {
    const fs::path path = dir_ / name;
    std::ofstream(path, std::ios::binary) << text;
    return path;
  }
  const test::ScopedTestDir scoped_dir_{"parallax_camera_setup_test"};
  const fs::path dir_ = scoped_dir_.path();
};

// The EXIF fields a camera writes about its focal length, for a hand-made APP1 segment.
struct TestExif {
  std::string make;
  std::string model;
  double focal_length_mm = 0;  // 0: tag absent.
  int focal_length_35mm = 0;   // 0: tag absent.
};

std::string U16(uint16_t value) {  // Little endian ("II" TIFF).
  return {static_cast<char>(value & 0xFF), static_cast<char>(value >> 8)};
}
std::string U32(uint32_t value) { return U16(value & 0xFFFF) + U16(value >> 16); }

// A TIFF block: IFD0 {Make, Model, ExifIFD pointer} then the Exif IFD {FocalLength,
// FocalLengthIn35mmFilm}, each IFD followed by its out-of-line values.
std::string TiffBlock(const TestExif& exif) {
  struct Entry {
    uint16_t tag, type;
    uint32_t count;
    std::string value;
  };
  const auto write_ifd = [](const std::vector<Entry>& entries, uint32_t offset) {
    std::string ifd = U16(static_cast<uint16_t>(entries.size())), data;
    uint32_t data_offset = offset + 2 + 12 * static_cast<uint32_t>(entries.size()) + 4;
    for (const Entry& entry : entries) {
      ifd += U16(entry.tag) + U16(entry.type) + U32(entry.count);
      if (entry.value.size() <= 4) {
        ifd += entry.value + std::string(4 - entry.value.size(), '\0');
      } else {
        ifd += U32(data_offset + static_cast<uint32_t>(data.size()));
        data += entry.value;
      }
    }
    return ifd + U32(0) + data;
  };
  std::vector<Entry> ifd0, exif_ifd;
  if (!exif.make.empty()) {
    ifd0.push_back({0x010F, 2, uint32_t(exif.make.size() + 1), exif.make + '\0'});
  }
  if (!exif.model.empty()) {
    ifd0.push_back({0x0110, 2, uint32_t(exif.model.size() + 1), exif.model + '\0'});
  }
  if (exif.focal_length_mm > 0) {
    const auto numerator = static_cast<uint32_t>(std::lround(exif.focal_length_mm * 100));
    exif_ifd.push_back({0x920A, 5, 1, U32(numerator) + U32(100)});
  }
  if (exif.focal_length_35mm > 0) {
    exif_ifd.push_back({0xA405, 3, 1, U16(static_cast<uint16_t>(exif.focal_length_35mm))});
  }
  // The Exif IFD starts after IFD0 (with the pointer entry) and IFD0's values.
  std::vector<Entry> ifd0_with_pointer = ifd0;
  ifd0_with_pointer.push_back({0x8769, 4, 1, U32(0)});
  const uint32_t exif_offset = static_cast<uint32_t>(8 + write_ifd(ifd0_with_pointer, 8).size());
  ifd0_with_pointer.back().value = U32(exif_offset);
  return "II" + U16(42) + U32(8) + write_ifd(ifd0_with_pointer, 8) +
         write_ifd(exif_ifd, exif_offset);
}

// A gray JPEG from OpenCV (which writes no EXIF), with an APP1 "Exif" segment spliced in
// right after SOI when `exif` is given.
std::string JpegBytes(int width, int height, const std::optional<TestExif>& exif) {
  cv::Mat image(height, width, CV_8UC1);
  cv::randu(image, 0, 255);
  std::vector<uchar> buffer;
  PARALLAX_CHECK(cv::imencode(".jpg", image, buffer));
  std::string jpeg(buffer.begin(), buffer.end());
  if (!exif) return jpeg;
  const std::string payload = std::string("Exif\0\0", 6) + TiffBlock(*exif);
  const auto length = static_cast<uint16_t>(payload.size() + 2);
  const std::string segment = std::string("\xFF\xE1", 2) + static_cast<char>(length >> 8) +
                              static_cast<char>(length & 0xFF) + payload;
  return jpeg.substr(0, 2) + segment + jpeg.substr(2);
}

void ExpectInputErrorNaming(const std::function<void()>& body, const std::string& prefix) {
  try {
    body();
    FAIL() << "expected InputError";
  } catch (const InputError& error) {
    EXPECT_EQ(std::string(error.what()).rfind(prefix, 0), 0u) << error.what();
  }
}

TEST_F(CameraSetupTest, ReadsCalibrationMatrixWithWindowsLineEndings) {
  // As fountain-P11/K.txt is written: CRLF and a trailing space on each line.
  const fs::path path =
      WriteText("K.txt", "2759.48 0 1520.69 \r\n0 2764.16 1006.81 \r\n0 0 1 \r\n");
  const Eigen::Matrix3d K = ReadCalibrationMatrix(path);
  EXPECT_EQ(K(0, 0), 2759.48);
  EXPECT_EQ(K(1, 1), 2764.16);
  EXPECT_EQ(K(0, 2), 1520.69);
  EXPECT_EQ(K(1, 2), 1006.81);
  EXPECT_EQ(K(2, 2), 1.0);
  EXPECT_EQ(K(1, 0), 0.0);
  // Commas and brackets are accepted too.
  const Eigen::Matrix3d K2 =
      ReadCalibrationMatrix(WriteText("K2.txt", "[1000, 0, 320;\n 0, 1000, 240;\n 0, 0, 1]\n"));
  EXPECT_EQ(K2(0, 0), 1000.0);
  EXPECT_EQ(K2(1, 2), 240.0);
}

TEST_F(CameraSetupTest, RejectsMalformedCalibrationMatrix) {
  const fs::path short_path = WriteText("short.txt", "1000 0 320\n0 1000 240\n0 0\n");
  ExpectInputErrorNaming([&] { ReadCalibrationMatrix(short_path); }, short_path.string());
  const fs::path text_path = WriteText("text.txt", "1000 0 320\n0 f 240\n0 0 1\n");
  ExpectInputErrorNaming([&] { ReadCalibrationMatrix(text_path); }, text_path.string());
  const fs::path lower_path = WriteText("lower.txt", "1000 0 0\n0 1000 0\n320 240 1\n");
  ExpectInputErrorNaming([&] { ReadCalibrationMatrix(lower_path); }, lower_path.string());
  const fs::path negative_path = WriteText("negative.txt", "-1000 0 320\n0 1000 240\n0 0 1\n");
  ExpectInputErrorNaming([&] { ReadCalibrationMatrix(negative_path); }, negative_path.string());
  const fs::path missing_path = dir_ / "missing.txt";
  ExpectInputErrorNaming([&] { ReadCalibrationMatrix(missing_path); }, missing_path.string());
}

TEST_F(CameraSetupTest, DefaultCameraGuessesFocalLength) {
  const Camera camera = MakeCamera(CameraSetupOptions(), std::nullopt, 640, 480);
  EXPECT_EQ(camera.model_id, CameraModelId::kSimpleRadial);
  EXPECT_EQ(camera.params, (std::vector<double>{1.2 * 640, 320, 240, 0}));
  EXPECT_FALSE(camera.has_prior_focal_length);
  EXPECT_EQ(camera.width, 640u);
  EXPECT_EQ(camera.height, 480u);
  const Camera portrait = MakeCamera(CameraSetupOptions(), std::nullopt, 480, 640);
  EXPECT_EQ(portrait.params[0], 1.2 * 640);
}

TEST_F(CameraSetupTest, CalibrationMatrixGivesPinholeWithPrior) {
  Eigen::Matrix3d K;
  K << 1520.4, 0, 302.32, 0, 1525.9, 246.87, 0, 0, 1;
  const Camera camera = MakeCamera(CameraSetupOptions(), K, 640, 480);
  EXPECT_EQ(camera.model_id, CameraModelId::kPinhole);
  EXPECT_EQ(camera.params, (std::vector<double>{1520.4, 1525.9, 302.32, 246.87}));
  EXPECT_TRUE(camera.has_prior_focal_length);

  CameraSetupOptions options;
  options.camera_model = "SIMPLE_RADIAL";
  const Camera radial = MakeCamera(options, K, 640, 480);
  EXPECT_EQ(radial.model_id, CameraModelId::kSimpleRadial);
  EXPECT_DOUBLE_EQ(radial.params[0], 0.5 * (1520.4 + 1525.9));
  EXPECT_EQ(radial.params[1], 302.32);
  EXPECT_EQ(radial.params[3], 0.0);
  options.camera_model = "OPENCV";
  const Camera opencv = MakeCamera(options, K, 640, 480);
  EXPECT_EQ(opencv.params, (std::vector<double>{1520.4, 1525.9, 302.32, 246.87, 0, 0, 0, 0}));
}

TEST_F(CameraSetupTest, ExplicitParams) {
  EXPECT_EQ(ParseCameraParams(" 500, 510,320 ,240"), (std::vector<double>{500, 510, 320, 240}));
  ExpectInputErrorNaming([] { ParseCameraParams("500,x"); }, "--camera-params");
  ExpectInputErrorNaming([] { ParseCameraParams("500,,3"); }, "--camera-params");

  CameraSetupOptions options;
  options.camera_params = {500, 510, 320, 240};
  const Camera camera = MakeCamera(options, std::nullopt, 640, 480);
  EXPECT_EQ(camera.model_id, CameraModelId::kPinhole);
  EXPECT_EQ(camera.params, options.camera_params);
  EXPECT_TRUE(camera.has_prior_focal_length);

  options.camera_params = {500, 320, 240};
  ExpectInputErrorNaming([&] { MakeCamera(options, std::nullopt, 640, 480); }, "--camera-params");
  options.camera_model = "SIMPLE_PINHOLE";
  EXPECT_EQ(MakeCamera(options, std::nullopt, 640, 480).params, options.camera_params);
  options.camera_model = "FISHEYE_42";
  ExpectInputErrorNaming([&] { MakeCamera(options, std::nullopt, 640, 480); }, "--camera-model");
}

TEST_F(CameraSetupTest, OneCameraPerImageSizeByDefault) {
  Database database(dir_ / "database.db");
  CameraAssigner assigner(LoadCameraSetup(CameraSetupOptions()), &database);
  const camera_t a = assigner.CameraForImage("a.png", 640, 480);
  const camera_t b = assigner.CameraForImage("b.png", 640, 480);
  const camera_t c = assigner.CameraForImage("c.png", 1280, 960);
  EXPECT_EQ(a, b);
  EXPECT_NE(a, c);
  EXPECT_EQ(database.NumCameras(), 2u);
  EXPECT_EQ(database.ReadCamera(c).params[0], 1.2 * 1280);

  // A resumed run reuses the cameras it finds.
  CameraAssigner resumed(LoadCameraSetup(CameraSetupOptions()), &database);
  EXPECT_EQ(resumed.CameraForImage("d.png", 1280, 960), c);
  EXPECT_EQ(database.NumCameras(), 2u);
  // Different settings make a different camera.
  CameraSetupOptions pinhole;
  pinhole.camera_model = "PINHOLE";
  CameraAssigner other(LoadCameraSetup(pinhole), &database);
  EXPECT_NE(other.CameraForImage("e.png", 640, 480), a);
  EXPECT_EQ(database.NumCameras(), 3u);
}

TEST_F(CameraSetupTest, SingleCameraAndCameraPerImage) {
  Database database(dir_ / "database.db");
  CameraSetupOptions single;
  single.single_camera = true;
  CameraAssigner single_assigner(LoadCameraSetup(single), &database);
  const camera_t a = single_assigner.CameraForImage("a.png", 640, 480);
  EXPECT_EQ(single_assigner.CameraForImage("b.png", 640, 480), a);
  ExpectInputErrorNaming([&] { single_assigner.CameraForImage("c.png", 641, 480); }, "c.png");

  CameraSetupOptions per_image;
  per_image.camera_per_image = true;
  CameraAssigner per_image_assigner(LoadCameraSetup(per_image), &database);
  const camera_t d = per_image_assigner.CameraForImage("d.png", 640, 480);
  const camera_t e = per_image_assigner.CameraForImage("e.png", 640, 480);
  EXPECT_NE(d, e);
  EXPECT_EQ(database.NumCameras(), 3u);

  CameraSetupOptions both = single;
  both.camera_per_image = true;
  EXPECT_THROW(CameraAssigner(LoadCameraSetup(both), &database), CheckError);
}

TEST_F(CameraSetupTest, AssignerReadsIntrinsicsFile) {
  Database database(dir_ / "database.db");
  CameraSetupOptions options;
  options.intrinsics_path = WriteText("K.txt", "800 0 330\n0 810 250\n0 0 1\n");
  CameraAssigner assigner(LoadCameraSetup(options), &database);
  const Camera camera = database.ReadCamera(assigner.CameraForImage("a.png", 640, 480));
  EXPECT_EQ(camera.model_id, CameraModelId::kPinhole);
  EXPECT_EQ(camera.params, (std::vector<double>{800, 810, 330, 250}));
  EXPECT_TRUE(camera.has_prior_focal_length);
  options.intrinsics_path = WriteText("bad.txt", "800 0 330\n");
  ExpectInputErrorNaming([&] { CameraAssigner(LoadCameraSetup(options), &database); },
                         options.intrinsics_path.string());
}

TEST_F(CameraSetupTest, CameraJsonGivesFixedOpencvCamera) {
  CalibratedCamera calibrated;
  calibrated.camera.model_id = CameraModelId::kOpenCV;
  calibrated.camera.width = 1280;
  calibrated.camera.height = 960;
  calibrated.camera.params = {1038.7, 1038.8, 635.7, 477.7, 0.177, -0.459, -0.0012, -0.0023};
  calibrated.camera.has_prior_focal_length = true;
  calibrated.rms_error = 0.58;
  const fs::path json_path = dir_ / "camera.json";
  WriteCameraJson(calibrated, json_path);

  Database database(dir_ / "database.db");
  CameraSetupOptions options;
  options.camera_json_path = json_path;
  CameraAssigner assigner(LoadCameraSetup(options), &database);
  const camera_t a = assigner.CameraForImage("a.jpg", 1280, 960);
  EXPECT_EQ(assigner.CameraForImage("b.jpg", 1280, 960), a);
  const Camera camera = database.ReadCamera(a);
  EXPECT_EQ(camera.model_id, CameraModelId::kOpenCV);
  EXPECT_EQ(camera.width, 1280u);
  EXPECT_EQ(camera.height, 960u);
  EXPECT_EQ(camera.params, calibrated.camera.params);  // Distortion included, bit for bit.
  EXPECT_TRUE(camera.has_prior_focal_length);
  // Intrinsics belong to one image size.
  ExpectInputErrorNaming([&] { assigner.CameraForImage("small.jpg", 640, 480); }, "small.jpg");
  EXPECT_EQ(database.NumCameras(), 1u);

  // Asked to, bundle adjustment may refine them: no prior.
  options.refine_known_intrinsics = true;
  CameraAssigner refined(LoadCameraSetup(options), &database);
  const Camera initial = database.ReadCamera(refined.CameraForImage("c.jpg", 1280, 960));
  EXPECT_EQ(initial.params, calibrated.camera.params);
  EXPECT_FALSE(initial.has_prior_focal_length);
  EXPECT_EQ(database.NumCameras(), 2u);

  // One source of intrinsics at a time, and no other model.
  CameraSetupOptions both = options;
  both.intrinsics_path = WriteText("K.txt", "800 0 330\n0 810 250\n0 0 1\n");
  EXPECT_THROW(CameraAssigner(LoadCameraSetup(both), &database), InputError);
  CameraSetupOptions with_params = options;
  with_params.camera_params = {1000, 640, 480};
  EXPECT_THROW(CameraAssigner(LoadCameraSetup(with_params), &database), InputError);
  CameraSetupOptions pinhole = options;
  pinhole.camera_model = "PINHOLE";
  ExpectInputErrorNaming([&] { CameraAssigner(LoadCameraSetup(pinhole), &database); },
                         "--camera-model");
  CameraSetupOptions missing;
  missing.camera_json_path = dir_ / "missing.json";
  ExpectInputErrorNaming([&] { CameraAssigner(LoadCameraSetup(missing), &database); },
                         missing.camera_json_path.string());
}

TEST_F(CameraSetupTest, HandMadeExifJpegDecodesAndParses) {
  const std::string jpeg = JpegBytes(64, 48, TestExif{"Canon", "EOS 5D", 50.0, 50});
  const cv::Mat decoded =
      cv::imdecode(std::vector<uchar>(jpeg.begin(), jpeg.end()), cv::IMREAD_GRAYSCALE);
  EXPECT_EQ(decoded.cols, 64);
  EXPECT_EQ(decoded.rows, 48);
  const std::optional<ExifData> exif = ParseJpegExif(jpeg);
  ASSERT_TRUE(exif.has_value());
  EXPECT_EQ(exif->make, "Canon");
  EXPECT_EQ(exif->model, "EOS 5D");
  EXPECT_EQ(exif->focal_length_mm, 50.0);
  EXPECT_EQ(exif->focal_length_35mm, 50.0);
  EXPECT_FALSE(ParseJpegExif(JpegBytes(64, 48, std::nullopt)).has_value());
}

TEST_F(CameraSetupTest, ExifFocalLengthIsTheInitialFocal) {
  // 45 mm in 35 mm film terms on a 640-pixel-wide image: 45 / 36 * 640 = 800 px.
  const TestExif canon{"Canon", "EOS 5D", 0, 45};
  const fs::path exif1 = WriteText("exif1.jpg", JpegBytes(640, 480, canon));
  const fs::path exif2 = WriteText("exif2.jpg", JpegBytes(640, 480, canon));
  const fs::path zoomed =
      WriteText("zoomed.jpg", JpegBytes(640, 480, TestExif{"Canon", "EOS 5D", 0, 90}));
  const fs::path other_body =
      WriteText("other.jpg", JpegBytes(640, 480, TestExif{"Nikon", "D700", 0, 45}));
  const fs::path plain = WriteText("plain.jpg", JpegBytes(640, 480, std::nullopt));

  Database database(dir_ / "database.db");
  CameraAssigner assigner(LoadCameraSetup(CameraSetupOptions()), &database);
  const camera_t a = assigner.CameraForImage(exif1.string(), 640, 480);
  EXPECT_EQ(assigner.CameraForImage(exif2.string(), 640, 480), a);
  const Camera camera = database.ReadCamera(a);
  EXPECT_EQ(camera.model_id, CameraModelId::kSimpleRadial);
  EXPECT_DOUBLE_EQ(camera.params[0], 800.0);
  EXPECT_EQ(camera.params[1], 320.0);
  EXPECT_EQ(camera.params[2], 240.0);
  // An initial value, refined by bundle adjustment.
  EXPECT_FALSE(camera.has_prior_focal_length);

  // Another focal length or body: another camera, even at the same size and focal length.
  const camera_t z = assigner.CameraForImage(zoomed.string(), 640, 480);
  EXPECT_NE(z, a);
  EXPECT_DOUBLE_EQ(database.ReadCamera(z).params[0], 1600.0);
  const camera_t n = assigner.CameraForImage(other_body.string(), 640, 480);
  EXPECT_NE(n, a);
  EXPECT_DOUBLE_EQ(database.ReadCamera(n).params[0], 800.0);
  // No EXIF: the 1.2 x max(width, height) guess.
  const camera_t p = assigner.CameraForImage(plain.string(), 640, 480);
  EXPECT_NE(p, a);
  EXPECT_DOUBLE_EQ(database.ReadCamera(p).params[0], 1.2 * 640);
  EXPECT_FALSE(database.ReadCamera(p).has_prior_focal_length);
  EXPECT_EQ(database.NumCameras(), 4u);

  // A resumed run, seeing images in the same order, finds the same cameras (the database
  // keeps no EXIF, so equal cameras are told apart by order).
  CameraAssigner resumed(LoadCameraSetup(CameraSetupOptions()), &database);
  EXPECT_EQ(resumed.CameraForImage(exif2.string(), 640, 480), a);
  EXPECT_EQ(resumed.CameraForImage(zoomed.string(), 640, 480), z);
  EXPECT_EQ(resumed.CameraForImage(other_body.string(), 640, 480), n);
  EXPECT_EQ(resumed.CameraForImage(plain.string(), 640, 480), p);
  EXPECT_EQ(database.NumCameras(), 4u);
}

TEST_F(CameraSetupTest, ExifOverridesAndModes) {
  const fs::path exif_path =
      WriteText("exif.jpg", JpegBytes(640, 480, TestExif{"Canon", "EOS 5D", 0, 45}));
  const fs::path plain_path = WriteText("plain.jpg", JpegBytes(640, 480, std::nullopt));
  // Focal length in mm only: needs the sensor width (4 mm on a 6.4 mm sensor: 400 px).
  const fs::path mm_path = WriteText("mm.jpg", JpegBytes(640, 480, TestExif{"Phone", "X", 4.0, 0}));
  Database database(dir_ / "database.db");

  CameraSetupOptions no_exif;
  no_exif.use_exif = false;
  CameraAssigner ignoring(LoadCameraSetup(no_exif), &database);
  const camera_t a = ignoring.CameraForImage(exif_path.string(), 640, 480);
  EXPECT_EQ(ignoring.CameraForImage(plain_path.string(), 640, 480), a);
  EXPECT_DOUBLE_EQ(database.ReadCamera(a).params[0], 1.2 * 640);

  CameraSetupOptions sensor;
  sensor.sensor_width_mm = 6.4;
  CameraAssigner with_sensor(LoadCameraSetup(sensor), &database);
  EXPECT_DOUBLE_EQ(
      database.ReadCamera(with_sensor.CameraForImage(mm_path.string(), 640, 480)).params[0], 400.0);
  CameraAssigner without_sensor(LoadCameraSetup(CameraSetupOptions()), &database);
  EXPECT_DOUBLE_EQ(
      database.ReadCamera(without_sensor.CameraForImage(mm_path.string(), 640, 480)).params[0],
      1.2 * 640);

  // Known intrinsics win over EXIF.
  CameraSetupOptions known;
  known.camera_params = {1000, 320, 240, 0};
  known.camera_model = "SIMPLE_RADIAL";
  CameraAssigner with_known(LoadCameraSetup(known), &database);
  const Camera k = database.ReadCamera(with_known.CameraForImage(exif_path.string(), 640, 480));
  EXPECT_EQ(k.params[0], 1000.0);
  EXPECT_TRUE(k.has_prior_focal_length);

  // --single-camera: all images share the first image's camera, EXIF or not.
  CameraSetupOptions single;
  single.single_camera = true;
  CameraAssigner single_assigner(LoadCameraSetup(single), &database);
  const camera_t s = single_assigner.CameraForImage(exif_path.string(), 640, 480);
  EXPECT_EQ(single_assigner.CameraForImage(plain_path.string(), 640, 480), s);
  EXPECT_DOUBLE_EQ(database.ReadCamera(s).params[0], 800.0);

  // --camera-per-image: each image its own camera, each with its own EXIF focal length.
  CameraSetupOptions per_image;
  per_image.camera_per_image = true;
  CameraAssigner per_image_assigner(LoadCameraSetup(per_image), &database);
  const camera_t e1 = per_image_assigner.CameraForImage(exif_path.string(), 640, 480);
  const camera_t e2 = per_image_assigner.CameraForImage(exif_path.string(), 640, 480);
  EXPECT_NE(e1, e2);
  EXPECT_DOUBLE_EQ(database.ReadCamera(e2).params[0], 800.0);
}

}  // namespace
}  // namespace parallax
