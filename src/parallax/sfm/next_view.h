#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include "parallax/sfm/tracked_reconstruction.h"

namespace parallax {

// How well an unregistered image would be constrained by the model: its keypoints whose
// track already has a 3D point, counted in a pyramid of grids (2x2, 4x4, 8x8) over the image
// so that well spread points score higher than a clump (COLMAP's visibility pyramid idea).
// Zero when the image sees no 3D point.
double VisibilityScore(image_t image_id, const TrackedReconstruction& model);

// VisibilityScore of every image of the model, kept as counts per grid cell that follow the
// tracks as they gain and lose points. Scoring every connected image before each
// registration instead grew as the square of the number of images (docs/mapper-scaling.md,
// "Figures").
class VisibilityScores {
 public:
  explicit VisibilityScores(TrackedReconstruction* model);
  // Follows the tracks whose point changed since the last call.
  void Update();
  // VisibilityScore(image_id, model) as of the last Update; 0 for images the model lacks.
  double Score(image_t image_id) const;

 private:
  static constexpr int kNumCells = 4 + 16 + 64;  // The 2x2, 4x4 and 8x8 grids in a row.
  struct Pyramid {
    const Image* image = nullptr;
    double width = 1;
    double height = 1;
    std::array<uint32_t, kNumCells> keypoints_in_cell{};
    int cells_score = 0;  // Sum over occupied cells of their grid's size.
    uint32_t num_visible = 0;
  };
  // Adds (+1) or removes (-1) the track's keypoints from their images' pyramids.
  void Count(track_t track_id, int delta);

  TrackedReconstruction* model_;
  std::vector<Pyramid> pyramids_;  // By image id.
  std::vector<char> counted_;      // By track: its keypoints are in the pyramids.
};

}  // namespace parallax
