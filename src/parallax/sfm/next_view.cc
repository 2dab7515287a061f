#include "parallax/sfm/next_view.h"

#include <algorithm>

namespace parallax {
namespace {

constexpr int kNumLevels = 3;
constexpr int kLevelOffset[kNumLevels] = {0, 4, 20};

// Cells per side of the level's grid; a cell at a finer level is worth more.
constexpr int GridSize(int level) { return 2 << level; }

// The cell of the keypoint at each level of the pyramid (indices into one array of all
// three grids).
std::array<int, kNumLevels> CellsOf(const Eigen::Vector2d& xy, double width, double height) {
  std::array<int, kNumLevels> cells;
  for (int level = 0; level < kNumLevels; ++level) {
    const int size = GridSize(level);
    const int cx = std::clamp(static_cast<int>(xy.x() / width * size), 0, size - 1);
    const int cy = std::clamp(static_cast<int>(xy.y() / height * size), 0, size - 1);
    cells[level] = kLevelOffset[level] + cy * size + cx;
  }
  return cells;
}

// Ties between equally spread images go to the one seeing more points.
double ScoreOf(double cells_score, size_t num_visible) {
  return num_visible == 0 ? 0.0 : cells_score + 1e-3 * num_visible;
}

}  // namespace

double VisibilityScore(image_t image_id, const TrackedReconstruction& model) {
  const Reconstruction& reconstruction = model.Model();
  const Image& image = reconstruction.GetImage(image_id);
  const Camera& camera = reconstruction.GetCamera(image.camera_id);
  const double width = std::max<double>(1.0, camera.width);
  const double height = std::max<double>(1.0, camera.height);
  std::array<char, 4 + 16 + 64> occupied{};  // No allocation per call.
  size_t num_visible = 0;
  double cells_score = 0;
  const track_t* tracks = model.Graph().TracksOfImage(image_id);
  for (point2D_t idx = 0; idx < image.points2D.size(); ++idx) {
    const track_t track_id = tracks[idx];
    if (track_id == kInvalidTrackId || model.PointOfTrack(track_id) == kInvalidPoint3DId) continue;
    ++num_visible;
    const std::array<int, kNumLevels> cells = CellsOf(image.points2D[idx].xy, width, height);
    for (int level = 0; level < kNumLevels; ++level) {
      if (!occupied[cells[level]]) {
        occupied[cells[level]] = 1;
        cells_score += GridSize(level);
      }
    }
  }
  return ScoreOf(cells_score, num_visible);
}

VisibilityScores::VisibilityScores(TrackedReconstruction* model) : model_(model) {
  const Reconstruction& reconstruction = model->Model();
  const std::map<image_t, Image>& images = reconstruction.Images();
  pyramids_.resize(images.empty() ? 0 : images.rbegin()->first + 1);
  for (const auto& [image_id, image] : images) {
    const Camera& camera = reconstruction.GetCamera(image.camera_id);
    Pyramid& pyramid = pyramids_[image_id];
    pyramid.image = &image;  // std::map nodes stay put, and the model never drops an image.
    pyramid.width = std::max<double>(1.0, camera.width);
    pyramid.height = std::max<double>(1.0, camera.height);
  }
  counted_.assign(model->Graph().NumTracks(), 0);
  Update();
}

void VisibilityScores::Update() {
  for (const track_t track_id : model_->TakeChangedTracks()) {
    const char visible = model_->PointOfTrack(track_id) != kInvalidPoint3DId;
    if (visible == counted_[track_id]) continue;
    Count(track_id, visible ? 1 : -1);
    counted_[track_id] = visible;
  }
}

void VisibilityScores::Count(track_t track_id, int delta) {
  for (const TrackElement& element : model_->Graph().TrackElements(track_id)) {
    if (element.image_id >= pyramids_.size()) continue;
    Pyramid& pyramid = pyramids_[element.image_id];
    if (pyramid.image == nullptr) continue;
    pyramid.num_visible += delta;
    const std::array<int, kNumLevels> cells =
        CellsOf(pyramid.image->points2D[element.point2D_idx].xy, pyramid.width, pyramid.height);
    for (int level = 0; level < kNumLevels; ++level) {
      uint32_t& count = pyramid.keypoints_in_cell[cells[level]];
      // A cell counts once it holds a keypoint, and stops when its last one goes.
      if (delta > 0 && count++ == 0) pyramid.cells_score += GridSize(level);
      if (delta < 0 && --count == 0) pyramid.cells_score -= GridSize(level);
    }
  }
}

double VisibilityScores::Score(image_t image_id) const {
  if (image_id >= pyramids_.size() || pyramids_[image_id].image == nullptr) return 0.0;
  const Pyramid& pyramid = pyramids_[image_id];
  return ScoreOf(pyramid.cells_score, pyramid.num_visible);
}

}  // namespace parallax
