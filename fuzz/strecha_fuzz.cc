// Strecha NAME.camera ground truth (fountain-P11's format).
#include <cmath>
#include <sstream>

#include "fuzz/fuzz_common.h"
#include "parallax/report/ground_truth.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  std::istringstream stream{std::string(parallax::fuzz::AsStringView(data, size))};
  parallax::GroundTruthImage image;
  if (!parallax::fuzz::ParsesOrRejects(
          [&] { image = parallax::ReadStrechaCamera(stream, "0000.jpg.camera", "0000.jpg"); })) {
    return 0;
  }
  PARALLAX_FUZZ_EXPECT(image.camera.VerifyParams());
  PARALLAX_FUZZ_EXPECT(image.camera.width > 0 && image.camera.height > 0);
  PARALLAX_FUZZ_EXPECT(image.cam_from_world.rotation.coeffs().allFinite());
  PARALLAX_FUZZ_EXPECT(std::abs(image.cam_from_world.rotation.norm() - 1) < 1e-6);
  PARALLAX_FUZZ_EXPECT(image.cam_from_world.translation.allFinite());
  return 0;
}
