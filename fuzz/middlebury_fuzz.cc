// Middlebury *_par.txt ground truth (templeRing's format).
#include <cmath>
#include <sstream>

#include "fuzz/fuzz_common.h"
#include "parallax/report/ground_truth.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  std::istringstream stream{std::string(parallax::fuzz::AsStringView(data, size))};
  parallax::GroundTruth truth;
  if (!parallax::fuzz::ParsesOrRejects(
          [&] { truth = parallax::ReadMiddleburyGroundTruth(stream, "templeR_par.txt"); })) {
    return 0;
  }
  for (const parallax::GroundTruthImage& image : truth.images) {
    PARALLAX_FUZZ_EXPECT(!image.name.empty());
    PARALLAX_FUZZ_EXPECT(image.camera.VerifyParams());
    PARALLAX_FUZZ_EXPECT(image.cam_from_world.rotation.coeffs().allFinite());
    PARALLAX_FUZZ_EXPECT(std::abs(image.cam_from_world.rotation.norm() - 1) < 1e-6);
    PARALLAX_FUZZ_EXPECT(image.cam_from_world.translation.allFinite());
  }
  return 0;
}
