// camera.json (calibration/camera_json.h). Accepted cameras must write back and read back
// to the same values.
#include <cmath>
#include <sstream>

#include "fuzz/fuzz_common.h"
#include "parallax/calibration/camera_json.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string text(parallax::fuzz::AsStringView(data, size));
  parallax::CalibratedCamera calibrated;
  if (!parallax::fuzz::ParsesOrRejects(
          [&] { calibrated = parallax::ParseCameraJson(text, "camera.json"); })) {
    return 0;
  }
  PARALLAX_FUZZ_EXPECT(calibrated.camera.VerifyParams());
  const double shift = parallax::K3ShiftPixels(calibrated);
  PARALLAX_FUZZ_EXPECT(!std::isnan(shift) && shift >= 0);
  std::ostringstream written;
  parallax::WriteCameraJson(calibrated, written);
  parallax::CalibratedCamera again;
  if (!parallax::fuzz::ParsesOrRejects(
          [&] { again = parallax::ParseCameraJson(written.str(), "written camera.json"); })) {
    parallax::fuzz::Abort("round trip", "written camera.json rejected: " + written.str());
  }
  PARALLAX_FUZZ_EXPECT(again.camera.params == calibrated.camera.params);
  PARALLAX_FUZZ_EXPECT(again.camera.width == calibrated.camera.width);
  PARALLAX_FUZZ_EXPECT(again.camera.height == calibrated.camera.height);
  PARALLAX_FUZZ_EXPECT(again.k3 == calibrated.k3);
  PARALLAX_FUZZ_EXPECT(again.num_images == calibrated.num_images);
  return 0;
}
