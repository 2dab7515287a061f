#include "parallax/pipeline/camera_setup.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <fstream>

#include "parallax/util/check.h"

namespace parallax {
namespace {

namespace fs = std::filesystem;

class CameraSetupTest : public ::testing::Test {
 protected:
  void SetUp() override {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    dir_ = fs::temp_directory_path() /
           ("parallax_camera_setup_test_" + std::to_string(getpid()) + "_" + info->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  fs::path WriteText(const std::string& name, const std::string& text) {
    const fs::path path = dir_ / name;
    std::ofstream(path, std::ios::binary) << text;
    return path;
  }
  fs::path dir_;
};

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
  CameraAssigner assigner(CameraSetupOptions(), &database);
  const camera_t a = assigner.CameraForImage("a.png", 640, 480);
  const camera_t b = assigner.CameraForImage("b.png", 640, 480);
  const camera_t c = assigner.CameraForImage("c.png", 1280, 960);
  EXPECT_EQ(a, b);
  EXPECT_NE(a, c);
  EXPECT_EQ(database.NumCameras(), 2u);
  EXPECT_EQ(database.ReadCamera(c).params[0], 1.2 * 1280);

  // A resumed run reuses the cameras it finds.
  CameraAssigner resumed(CameraSetupOptions(), &database);
  EXPECT_EQ(resumed.CameraForImage("d.png", 1280, 960), c);
  EXPECT_EQ(database.NumCameras(), 2u);
  // Different settings make a different camera.
  CameraSetupOptions pinhole;
  pinhole.camera_model = "PINHOLE";
  CameraAssigner other(pinhole, &database);
  EXPECT_NE(other.CameraForImage("e.png", 640, 480), a);
  EXPECT_EQ(database.NumCameras(), 3u);
}

TEST_F(CameraSetupTest, SingleCameraAndCameraPerImage) {
  Database database(dir_ / "database.db");
  CameraSetupOptions single;
  single.single_camera = true;
  CameraAssigner single_assigner(single, &database);
  const camera_t a = single_assigner.CameraForImage("a.png", 640, 480);
  EXPECT_EQ(single_assigner.CameraForImage("b.png", 640, 480), a);
  ExpectInputErrorNaming([&] { single_assigner.CameraForImage("c.png", 641, 480); }, "c.png");

  CameraSetupOptions per_image;
  per_image.camera_per_image = true;
  CameraAssigner per_image_assigner(per_image, &database);
  const camera_t d = per_image_assigner.CameraForImage("d.png", 640, 480);
  const camera_t e = per_image_assigner.CameraForImage("e.png", 640, 480);
  EXPECT_NE(d, e);
  EXPECT_EQ(database.NumCameras(), 3u);

  CameraSetupOptions both = single;
  both.camera_per_image = true;
  EXPECT_THROW(CameraAssigner(both, &database), CheckError);
}

TEST_F(CameraSetupTest, AssignerReadsIntrinsicsFile) {
  Database database(dir_ / "database.db");
  CameraSetupOptions options;
  options.intrinsics_path = WriteText("K.txt", "800 0 330\n0 810 250\n0 0 1\n");
  CameraAssigner assigner(options, &database);
  const Camera camera = database.ReadCamera(assigner.CameraForImage("a.png", 640, 480));
  EXPECT_EQ(camera.model_id, CameraModelId::kPinhole);
  EXPECT_EQ(camera.params, (std::vector<double>{800, 810, 330, 250}));
  EXPECT_TRUE(camera.has_prior_focal_length);
  options.intrinsics_path = WriteText("bad.txt", "800 0 330\n");
  ExpectInputErrorNaming([&] { CameraAssigner(options, &database); },
                         options.intrinsics_path.string());
}

}  // namespace
}  // namespace parallax
