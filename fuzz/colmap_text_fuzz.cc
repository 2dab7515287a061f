// COLMAP text model: cameras.txt, images.txt and points3D.txt. The input holds the three files
// separated by the byte 0x1E (ASCII record separator); missing sections are empty. Accepted
// models must survive a text round trip unchanged in size.
#include <sstream>

#include "fuzz/fuzz_common.h"
#include "parallax/scene/colmap_io.h"

namespace {

using parallax::Reconstruction;

// Reads the three sections into `model`; false when a reader rejected them.
bool ReadSections(const std::string_view sections[3], Reconstruction* model) {
  return parallax::fuzz::ParsesOrRejects([&] {
    std::istringstream cameras{std::string(sections[0])};
    parallax::ReadCamerasText(cameras, "cameras.txt", model);
    std::istringstream images{std::string(sections[1])};
    parallax::ReadImagesText(images, "images.txt", model);
    std::istringstream points{std::string(sections[2])};
    parallax::ReadPoints3DText(points, "points3D.txt", model);
  });
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  std::string_view input = parallax::fuzz::AsStringView(data, size);
  std::string_view sections[3];
  for (int k = 0; k < 3; ++k) {
    const size_t end = k < 2 ? input.find('\x1e') : std::string_view::npos;
    sections[k] = input.substr(0, end);
    input = end == std::string_view::npos ? std::string_view() : input.substr(end + 1);
  }
  Reconstruction model;
  if (!ReadSections(sections, &model)) return 0;

  std::ostringstream cameras, images, points;
  parallax::WriteCamerasText(model, cameras);
  parallax::WriteImagesText(model, images);
  parallax::WritePoints3DText(model, points);
  const std::string written[3] = {cameras.str(), images.str(), points.str()};
  const std::string_view views[3] = {written[0], written[1], written[2]};
  Reconstruction again;
  if (!ReadSections(views, &again)) parallax::fuzz::Abort("round trip", "written model rejected");
  PARALLAX_FUZZ_EXPECT(again.NumCameras() == model.NumCameras());
  PARALLAX_FUZZ_EXPECT(again.NumImages() == model.NumImages());
  PARALLAX_FUZZ_EXPECT(again.NumPoints3D() == model.NumPoints3D());
  PARALLAX_FUZZ_EXPECT(again.NumObservations() == model.NumObservations());
  return 0;
}
