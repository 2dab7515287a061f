// End-to-end tests of the camera flags of `parallax features` (shared with `reconstruct`):
// the built binary runs as a subprocess (its path comes from PARALLAX_BINARY, set by CTest).
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdlib>
#include <fstream>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "parallax/calibration/camera_json.h"
#include "parallax/math/random.h"
#include "parallax/scene/database.h"
#include "parallax/util/file.h"
#include "parallax/util/test_dir.h"

namespace parallax {
namespace {

namespace fs = std::filesystem;

class CameraFlagsTest : public ::testing::Test {
 protected:
  void SetUp() override {
    const char* binary = std::getenv("PARALLAX_BINARY");
    if (binary == nullptr || !fs::exists(binary)) GTEST_SKIP() << "PARALLAX_BINARY not set";
    binary_ = binary;
    fs::create_directories(dir_ / "images");
  }

  // Runs the binary; returns its exit code, stderr in *err.
  int Run(const std::string& arguments, std::string* err) {
    const fs::path out_path = dir_ / "stdout.txt", err_path = dir_ / "stderr.txt";
    const std::string command = "'" + binary_ + "' " + arguments + " >'" + out_path.string() +
                                "' 2>'" + err_path.string() + "'";
    const int status = std::system(command.c_str());
    *err = ReadFileToString(err_path);
    return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  }

  void WriteImage(const std::string& name, int width, int height) {
    cv::Mat image(height, width, CV_8UC1, cv::Scalar(128));
    for (int k = 0; k < 200; ++k) {
      cv::circle(image,
                 cv::Point(static_cast<int>(RandomUniformInteger(0, width - 1)),
                           static_cast<int>(RandomUniformInteger(0, height - 1))),
                 static_cast<int>(RandomUniformInteger(2, 8)),
                 cv::Scalar(static_cast<int>(RandomUniformInteger(0, 255))), cv::FILLED);
    }
    ASSERT_TRUE(cv::imwrite((dir_ / "images" / name).string(), image));
  }

  fs::path WriteCameraJsonFile(int width, int height) {
    CalibratedCamera calibrated;
    calibrated.camera.model_id = CameraModelId::kOpenCV;
    calibrated.camera.width = width;
    calibrated.camera.height = height;
    calibrated.camera.params = {310.5, 311.25, 159.75, 120.125, -0.21, 0.083, 0.0011, -0.0007};
    const fs::path path = dir_ / "camera.json";
    WriteCameraJson(calibrated, path);
    return path;
  }

  std::string binary_;
  const test::ScopedTestDir scoped_dir_{"parallax_camera_flags_test"};
  const fs::path dir_ = scoped_dir_.path();
};

TEST_F(CameraFlagsTest, CameraJsonBecomesTheDatabaseCamera) {
  WriteImage("a.png", 320, 240);
  WriteImage("b.png", 320, 240);
  WriteImage("c.png", 200, 100);  // Another size: skipped, with the reason.
  const fs::path json_path = WriteCameraJsonFile(320, 240);
  const fs::path database_path = dir_ / "database.db";
  std::string err;
  ASSERT_EQ(Run("features --images '" + (dir_ / "images").string() + "' --database '" +
                    database_path.string() + "' --camera '" + json_path.string() + "' --threads 2",
                &err),
            0)
      << err;
  EXPECT_NE(err.find("c.png: image is 200x100 but " + json_path.string() + " calibrates 320x240"),
            std::string::npos)
      << err;
  Database database(database_path);
  ASSERT_EQ(database.NumCameras(), 1u);
  EXPECT_EQ(database.NumImages(), 2u);
  const Camera camera = database.ReadAllCameras().front();
  EXPECT_EQ(camera.model_id, CameraModelId::kOpenCV);
  EXPECT_EQ(camera.width, 320u);
  EXPECT_EQ(camera.height, 240u);
  EXPECT_EQ(camera.params,
            (std::vector<double>{310.5, 311.25, 159.75, 120.125, -0.21, 0.083, 0.0011, -0.0007}));
  EXPECT_TRUE(camera.has_prior_focal_length);
}

TEST_F(CameraFlagsTest, CameraJsonExcludesOtherIntrinsics) {
  WriteImage("a.png", 320, 240);
  const fs::path json_path = WriteCameraJsonFile(320, 240);
  const fs::path k_path = dir_ / "K.txt";
  std::ofstream(k_path) << "300 0 160\n0 300 120\n0 0 1\n";
  const std::string base = "features --images '" + (dir_ / "images").string() + "' --database '" +
                           (dir_ / "database.db").string() + "' --camera '" + json_path.string() +
                           "'";
  std::string err;
  EXPECT_NE(Run(base + " --intrinsics '" + k_path.string() + "'", &err), 0);
  EXPECT_NE(err.find("--intrinsics"), std::string::npos) << err;
  EXPECT_NE(Run(base + " --camera-params 300,160,120", &err), 0);
  EXPECT_NE(Run(base + " --camera-model PINHOLE", &err), 0);
  EXPECT_EQ(err.rfind("error: --camera-model", 0), 0u) << err;
  const fs::path bad_json = dir_ / "bad.json";
  std::ofstream(bad_json) << "{\"model\": \"OPENCV\"}";
  EXPECT_EQ(Run("features --images '" + (dir_ / "images").string() + "' --database '" +
                    (dir_ / "other.db").string() + "' --camera '" + bad_json.string() + "'",
                &err),
            1);
  EXPECT_EQ(err.rfind("error: " + bad_json.string(), 0), 0u) << err;
}

}  // namespace
}  // namespace parallax
