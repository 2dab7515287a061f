#include "parallax/sfm/next_view.h"

#include <algorithm>
#include <array>

namespace parallax {

double VisibilityScore(image_t image_id, const TrackedReconstruction& model) {
  constexpr int kNumLevels = 3;
  const Reconstruction& reconstruction = model.Model();
  const Image& image = reconstruction.GetImage(image_id);
  const Camera& camera = reconstruction.GetCamera(image.camera_id);
  const double width = std::max<double>(1.0, camera.width);
  const double height = std::max<double>(1.0, camera.height);
  // Cells of the 2x2, 4x4 and 8x8 grids, one after the other: no allocation per call (the
  // mapper scores every connected image before each registration).
  std::array<char, 4 + 16 + 64> occupied{};
  constexpr int kLevelOffset[kNumLevels] = {0, 4, 20};
  size_t num_visible = 0;
  double score = 0;
  const track_t* tracks = model.Graph().TracksOfImage(image_id);
  for (point2D_t idx = 0; idx < image.points2D.size(); ++idx) {
    const track_t track_id = tracks[idx];
    if (track_id == kInvalidTrackId || model.PointOfTrack(track_id) == kInvalidPoint3DId) continue;
    ++num_visible;
    const Eigen::Vector2d& xy = image.points2D[idx].xy;
    for (int level = 0; level < kNumLevels; ++level) {
      const int cells = 2 << level;
      const int cx = std::clamp(static_cast<int>(xy.x() / width * cells), 0, cells - 1);
      const int cy = std::clamp(static_cast<int>(xy.y() / height * cells), 0, cells - 1);
      char& cell = occupied[kLevelOffset[level] + cy * cells + cx];
      if (!cell) {
        cell = 1;
        score += cells;  // A new cell at a finer level is worth more.
      }
    }
  }
  // Ties between equally spread images go to the one seeing more points.
  return num_visible == 0 ? 0.0 : score + 1e-3 * num_visible;
}

}  // namespace parallax
