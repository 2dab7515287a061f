#include "parallax/sfm/next_view.h"

#include <gtest/gtest.h>

#include <iterator>
#include <random>

#include "parallax/sfm/testing/synthetic_mapper_input.h"
#include "parallax/sfm/track_triangulation.h"

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

// The cached scores equal the scores computed afresh through every kind of edit the mapper
// makes: images registered and triangulated, observations filtered, points deleted and
// merged, images deregistered, and tracks left by a point that lives on.
TEST(VisibilityScores, FollowEveryEditOfTheModel) {
  PosedSyntheticScene scene(/*num_images=*/10, /*num_points3D=*/400);
  TrackedReconstruction tracked(scene.input.correspondence_graph, &scene.model);
  VisibilityScores scores(&tracked);
  const TrackTriangulationOptions triangulation;
  const auto expect_fresh_scores = [&](const std::string& step) {
    scores.Update();
    for (const auto& [image_id, image] : scene.model.Images()) {
      ASSERT_EQ(scores.Score(image_id), VisibilityScore(image_id, tracked))
          << "image " << image_id << " after " << step;
    }
  };
  const auto register_image = [&](image_t image_id) {
    scene.model.RegisterImage(image_id);
    TriangulateImage(triangulation, image_id, &tracked);
  };
  for (image_t image_id = 1; image_id <= 4; ++image_id) register_image(image_id);
  expect_fresh_scores("registering four images");
  EXPECT_GT(scores.Score(5), 0.0);

  std::mt19937 random(7);
  const auto random_point = [&]() {
    auto it = scene.model.Points3D().begin();
    std::advance(it, random() % scene.model.NumPoints3D());
    return it->first;
  };
  image_t next_image = 5;
  for (int step = 0; step < 1000 && scene.model.NumPoints3D() > 2; ++step) {
    switch (random() % 6) {
      case 0:  // A new image, or new points in a registered one for what was deleted.
        if (next_image <= 10) {
          register_image(next_image++);
        } else {
          const std::vector<image_t> registered = scene.model.RegImageIds();
          TriangulateImage(triangulation, registered[random() % registered.size()], &tracked);
        }
        break;
      case 1: {
        const Point3D& point = scene.model.GetPoint3D(random_point());
        const TrackElement element = point.track.elements[random() % point.track.Length()];
        scene.model.DeleteObservation(element.image_id, element.point2D_idx);
        break;
      }
      case 2:
        scene.model.DeletePoint3D(random_point());
        break;
      case 3: {
        const point3D_t point3D_id1 = random_point();
        const point3D_t point3D_id2 = random_point();
        if (point3D_id1 != point3D_id2) tracked.MergePoints3D(point3D_id1, point3D_id2);
        break;
      }
      case 4: {  // Every element of one track leaves a (merged) point that lives on.
        const Point3D& point = scene.model.GetPoint3D(random_point());
        const CorrespondenceGraph& graph = scene.input.correspondence_graph;
        const TrackElement first = point.track.elements.front();
        const track_t track_id = graph.TrackOf(first.image_id, first.point2D_idx);
        for (const TrackElement& element : std::vector<TrackElement>(point.track.elements)) {
          if (graph.TrackOf(element.image_id, element.point2D_idx) == track_id) {
            scene.model.DeleteObservation(element.image_id, element.point2D_idx);
          }
        }
        break;
      }
      default: {
        const std::vector<image_t> registered = scene.model.RegImageIds();
        if (registered.size() > 3) scene.model.DeRegisterImage(registered[random() % 4]);
      }
    }
    expect_fresh_scores("step " + std::to_string(step));
  }
}

}  // namespace
}  // namespace parallax
