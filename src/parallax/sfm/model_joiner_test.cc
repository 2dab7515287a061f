// Joining the disjoint models of one run through the tracks they share: exact halves of a
// ring, one moved by a known similarity, come back together; halves whose shared points
// disagree, or that share too few, stay apart.
#include "parallax/sfm/model_joiner.h"

#include <gtest/gtest.h>

#include <set>

#include "parallax/scene/synthetic_dataset.h"
#include "parallax/sfm/testing/synthetic_mapper_input.h"

namespace parallax {
namespace {

// The truth's images in `image_ids`, registered at their true poses moved by `moved_from_truth`,
// with the true points they see (observed by at least two of them).
Reconstruction Part(const Reconstruction& truth, const std::set<image_t>& image_ids,
                    const Sim3d& moved_from_truth) {
  Reconstruction part;
  for (const auto& [camera_id, camera] : truth.Cameras()) part.AddCamera(camera);
  for (const image_t image_id : image_ids) {
    Image image = truth.GetImage(image_id);
    for (Point2D& point2D : image.points2D) point2D.point3D_id = kInvalidPoint3DId;
    image.cam_from_world = TransformCameraPose(moved_from_truth, image.cam_from_world);
    part.AddImage(image);
    part.RegisterImage(image_id);
  }
  for (const auto& [point3D_id, point] : truth.Points3D()) {
    Track track;
    for (const TrackElement& element : point.track.elements) {
      if (image_ids.count(element.image_id)) track.elements.push_back(element);
    }
    if (track.Length() >= 2) part.AddPoint3D(moved_from_truth * point.xyz, track);
  }
  return part;
}

class ModelJoinerTest : public ::testing::Test {
 protected:
  ModelJoinerTest() {
    SyntheticDatasetOptions options;
    options.num_images = 12;
    options.num_points3D = 600;
    options.min_track_length = 3;
    options.seed = 11;
    SynthesizeDataset(options, &truth_);
    input_ = InputFromTruth(truth_);
  }
  Reconstruction truth_;
  MapperInput input_;
  const std::set<image_t> first_half_ = {1, 2, 3, 4, 5, 6};
  const std::set<image_t> second_half_ = {7, 8, 9, 10, 11, 12};
  const Sim3d moved_{
      2.5, Eigen::Quaterniond(Eigen::AngleAxisd(0.7, Eigen::Vector3d(1, 2, 3).normalized())),
      Eigen::Vector3d(4, -1, 3)};
};

TEST_F(ModelJoinerTest, HalvesMovedApartComeBackTogether) {
  const std::vector<Reconstruction> models = {Part(truth_, first_half_, Sim3d()),
                                              Part(truth_, second_half_, moved_)};
  std::vector<ModelJoinReport> reports;
  const Reconstruction joined =
      JoinModels(ModelJoinerOptions(), models, input_.correspondence_graph, &reports);
  ASSERT_EQ(reports.size(), 2u);
  EXPECT_TRUE(reports[0].joined);
  ASSERT_TRUE(reports[1].joined);
  EXPECT_GE(reports[1].num_shared_tracks, 30u);
  EXPECT_EQ(reports[1].num_inliers, reports[1].num_shared_tracks);  // Exact points all agree.
  EXPECT_NEAR(reports[1].joined_from_model.scale, 1.0 / moved_.scale, 1e-9);
  ASSERT_EQ(joined.NumRegImages(), 12u);
  EXPECT_EQ(joined.NumPoints3D(), 0u);  // Poses only: the caller triangulates.
  // The first half is the frame, the truth's: every pose is the true one.
  for (const image_t image_id : joined.RegImageIds()) {
    const Rigid3d& pose = joined.GetImage(image_id).cam_from_world;
    const Rigid3d& expected = truth_.GetImage(image_id).cam_from_world;
    EXPECT_LT(RotationAngleDegrees(pose.rotation, expected.rotation), 1e-6) << image_id;
    EXPECT_LT((ProjectionCenter(pose) - ProjectionCenter(expected)).norm(), 1e-6) << image_id;
  }
}

TEST_F(ModelJoinerTest, AModelWhosePointsDisagreeStaysApart) {
  Reconstruction scrambled = Part(truth_, second_half_, moved_);
  // Each point moved to another's place: the shared tracks fit no similarity.
  std::vector<Eigen::Vector3d> xyz;
  for (const auto& [point3D_id, point] : scrambled.Points3D()) xyz.push_back(point.xyz);
  size_t k = 0;
  for (const auto& [point3D_id, point] : scrambled.Points3D()) {
    scrambled.GetPoint3D(point3D_id).xyz = xyz[(k++ * 7 + 3) % xyz.size()];
  }
  const std::vector<Reconstruction> models = {Part(truth_, first_half_, Sim3d()), scrambled};
  std::vector<ModelJoinReport> reports;
  const Reconstruction joined =
      JoinModels(ModelJoinerOptions(), models, input_.correspondence_graph, &reports);
  EXPECT_TRUE(reports[0].joined);
  EXPECT_FALSE(reports[1].joined);
  EXPECT_GE(reports[1].num_shared_tracks, 30u);
  EXPECT_LT(reports[1].num_inliers, 30u);
  EXPECT_EQ(joined.NumRegImages(), first_half_.size());
}

TEST_F(ModelJoinerTest, TooFewSharedTracksLeaveTheModelsApart) {
  const std::vector<Reconstruction> models = {Part(truth_, first_half_, Sim3d()),
                                              Part(truth_, second_half_, moved_)};
  std::vector<ModelJoinReport> reports;
  ModelJoinerOptions options;
  JoinModels(options, models, input_.correspondence_graph, &reports);
  options.min_inlier_points = static_cast<int>(reports[1].num_shared_tracks) + 1;
  const Reconstruction joined = JoinModels(options, models, input_.correspondence_graph, &reports);
  EXPECT_FALSE(reports[1].joined);
  EXPECT_EQ(reports[1].num_inliers, 0u);  // Not even tried.
  EXPECT_EQ(joined.NumRegImages(), first_half_.size());
}

// The largest model is the frame whatever the order, and every model joins it.
TEST_F(ModelJoinerTest, TheLargestModelIsTheFrame) {
  const std::vector<Reconstruction> models = {Part(truth_, {7, 8, 9}, moved_),
                                              Part(truth_, {1, 2, 3, 4, 5, 6}, Sim3d()),
                                              Part(truth_, {10, 11, 12}, moved_.Inverse())};
  std::vector<ModelJoinReport> reports;
  const Reconstruction joined =
      JoinModels(ModelJoinerOptions(), models, input_.correspondence_graph, &reports);
  for (const ModelJoinReport& report : reports) EXPECT_TRUE(report.joined);
  EXPECT_NEAR(reports[1].joined_from_model.scale, 1.0, 1e-12);
  ASSERT_EQ(joined.NumRegImages(), 12u);
  for (const image_t image_id : joined.RegImageIds()) {
    const Rigid3d& pose = joined.GetImage(image_id).cam_from_world;
    const Rigid3d& expected = truth_.GetImage(image_id).cam_from_world;
    EXPECT_LT(RotationAngleDegrees(pose.rotation, expected.rotation), 1e-6) << image_id;
  }
}

}  // namespace
}  // namespace parallax
