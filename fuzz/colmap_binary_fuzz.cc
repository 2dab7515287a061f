// COLMAP binary model: cameras.bin, images.bin and points3D.bin. The input starts with two
// little-endian uint32 sizes, of the cameras and the images sections; the points follow.
// Accepted models must survive a binary round trip unchanged in size.
#include <cstring>
#include <sstream>

#include "fuzz/fuzz_common.h"
#include "parallax/scene/colmap_io.h"

namespace {

using parallax::Reconstruction;

bool ReadSections(const std::string sections[3], Reconstruction* model) {
  return parallax::fuzz::ParsesOrRejects([&] {
    std::istringstream cameras(sections[0], std::ios::binary);
    parallax::ReadCamerasBinary(cameras, "cameras.bin", model);
    std::istringstream images(sections[1], std::ios::binary);
    parallax::ReadImagesBinary(images, "images.bin", model);
    std::istringstream points(sections[2], std::ios::binary);
    parallax::ReadPoints3DBinary(points, "points3D.bin", model);
  });
}

uint32_t ReadSize(std::string_view* input) {
  uint32_t size = 0;
  if (input->size() < 4) {
    *input = std::string_view();
    return 0;
  }
  for (int i = 3; i >= 0; --i) size = (size << 8) | static_cast<uint8_t>((*input)[i]);
  input->remove_prefix(4);
  return size;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  std::string_view input = parallax::fuzz::AsStringView(data, size);
  const uint32_t cameras_size = ReadSize(&input);
  const uint32_t images_size = ReadSize(&input);
  std::string sections[3];
  sections[0] = std::string(input.substr(0, cameras_size));
  input.remove_prefix(std::min<size_t>(input.size(), cameras_size));
  sections[1] = std::string(input.substr(0, images_size));
  input.remove_prefix(std::min<size_t>(input.size(), images_size));
  sections[2] = std::string(input);
  Reconstruction model;
  if (!ReadSections(sections, &model)) return 0;

  std::ostringstream cameras(std::ios::binary), images(std::ios::binary), points(std::ios::binary);
  parallax::WriteCamerasBinary(model, cameras);
  parallax::WriteImagesBinary(model, images);
  parallax::WritePoints3DBinary(model, points);
  const std::string written[3] = {cameras.str(), images.str(), points.str()};
  Reconstruction again;
  if (!ReadSections(written, &again)) parallax::fuzz::Abort("round trip", "written model rejected");
  PARALLAX_FUZZ_EXPECT(again.NumCameras() == model.NumCameras());
  PARALLAX_FUZZ_EXPECT(again.NumImages() == model.NumImages());
  PARALLAX_FUZZ_EXPECT(again.NumPoints3D() == model.NumPoints3D());
  PARALLAX_FUZZ_EXPECT(again.NumObservations() == model.NumObservations());
  return 0;
}
