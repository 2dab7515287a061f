#include "parallax/sfm/next_view.h"

#include <gtest/gtest.h>

namespace parallax {
namespace {

// Two images of one 100 x 100 camera: image 1 registered with one point per keypoint of a
// track; image 2 unregistered, its keypoints at `corners2` linked to those tracks.
struct TwoImages {
  CorrespondenceGraph graph;
  Reconstruction model;
};

void Build(const std::vector<Eigen::Vector2d>& keypoints2, TwoImages* scene) {
  scene->model.AddCamera(Camera::Create(1, CameraModelId::kPinhole, 100, 100, 100));
  FeatureMatches matches;
  for (image_t image_id : {1, 2}) {
    Image image;
    image.image_id = image_id;
    image.camera_id = 1;
    image.name = std::to_string(image_id);
    for (const Eigen::Vector2d& xy : keypoints2) image.points2D.push_back({xy, kInvalidPoint3DId});
    scene->model.AddImage(image);
    scene->graph.AddImage(image_id, keypoints2.size());
  }
  for (point2D_t idx = 0; idx < keypoints2.size(); ++idx) matches.push_back({idx, idx});
  scene->graph.AddCorrespondences(1, 2, matches);
  scene->graph.Finalize();
  scene->model.RegisterImage(1);
}

// The score of image 2 when the first `num_triangulated` keypoints of image 1 have a point.
double Score(const std::vector<Eigen::Vector2d>& keypoints2, size_t num_triangulated) {
  TwoImages scene;
  Build(keypoints2, &scene);
  TrackedReconstruction tracked(scene.graph, &scene.model);
  for (point2D_t idx = 0; idx < num_triangulated; ++idx) {
    Track track;
    track.AddElement(1, idx);
    tracked.AddPoint3D(Eigen::Vector3d(0, 0, 1), track);
  }
  return VisibilityScore(2, tracked);
}

TEST(VisibilityScore, SpreadPointsBeatAClumpOfMore) {
  const std::vector<Eigen::Vector2d> corners = {{5, 5}, {95, 5}, {5, 95}, {95, 95}};
  std::vector<Eigen::Vector2d> clump;
  for (int i = 0; i < 10; ++i) clump.emplace_back(50 + 0.1 * i, 50);
  EXPECT_GT(Score(corners, 4), Score(clump, 10));
}

TEST(VisibilityScore, NoTriangulatedPointsScoreZeroAndMoreOfTheSameCountAsATie) {
  const std::vector<Eigen::Vector2d> corners = {{5, 5}, {95, 5}, {5, 95}, {95, 95}};
  EXPECT_EQ(Score(corners, 0), 0.0);
  EXPECT_GT(Score(corners, 2), 0.0);
  EXPECT_GT(Score(corners, 4), Score(corners, 2));
  // A second point in an occupied cell only breaks ties.
  std::vector<Eigen::Vector2d> doubled = corners;
  doubled.emplace_back(6, 6);
  EXPECT_NEAR(Score(doubled, 5) - Score(corners, 4), 1e-3, 1e-12);
}

}  // namespace
}  // namespace parallax
