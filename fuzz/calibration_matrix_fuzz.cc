// K.txt (--intrinsics; pipeline/camera_setup.h ReadCalibrationMatrix). The parser reads a
// path, so each input goes through a temporary file. An accepted K must give a usable camera.
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>

#include "fuzz/fuzz_common.h"
#include "parallax/pipeline/camera_setup.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  static const std::filesystem::path path = [] {
    std::atexit([] {
      std::error_code ignored;
      std::filesystem::remove(
          std::filesystem::temp_directory_path() /
              ("parallax_calibration_matrix_fuzz_" + std::to_string(getpid()) + ".txt"),
          ignored);
    });
    return std::filesystem::temp_directory_path() /
           ("parallax_calibration_matrix_fuzz_" + std::to_string(getpid()) + ".txt");
  }();
  {
    std::ofstream file(path, std::ios::binary | std::ios::trunc);
    file.write(reinterpret_cast<const char*>(data), static_cast<std::streamsize>(size));
  }
  Eigen::Matrix3d K;
  if (!parallax::fuzz::ParsesOrRejects([&] { K = parallax::ReadCalibrationMatrix(path); })) {
    return 0;
  }
  PARALLAX_FUZZ_EXPECT(K.allFinite());
  PARALLAX_FUZZ_EXPECT(K(0, 0) > 0 && K(1, 1) > 0 && K(2, 2) == 1);
  parallax::CameraSetupOptions options;
  const parallax::Camera camera = parallax::MakeCamera(options, K, 640, 480);
  PARALLAX_FUZZ_EXPECT(camera.VerifyParams());
  return 0;
}
