#include "parallax/sfm/model_merger.h"

#include <gtest/gtest.h>

#include <random>
#include <set>

#include "parallax/scene/synthetic_dataset.h"
#include "parallax/sfm/testing/synthetic_mapper_input.h"

namespace parallax {
namespace {

Sim3d MakeSim3(double scale, double angle, const Eigen::Vector3d& axis,
               const Eigen::Vector3d& translation) {
  return Sim3d(scale, Eigen::Quaterniond(Eigen::AngleAxisd(angle, axis.normalized())), translation);
}

// The part of `truth` seen by `image_ids`, in a frame of its own (model_from_truth): its
// images, and every point at least two of them see, with `outlier_share` of those points
// moved far off (as badly triangulated points are).
Reconstruction SubModel(const Reconstruction& truth, const std::vector<image_t>& image_ids,
                        const Sim3d& model_from_truth, double outlier_share = 0) {
  Reconstruction model;
  for (const auto& [camera_id, camera] : truth.Cameras()) model.AddCamera(camera);
  std::set<image_t> members(image_ids.begin(), image_ids.end());
  for (const image_t image_id : image_ids) {
    Image image = truth.GetImage(image_id);
    for (Point2D& point2D : image.points2D) point2D.point3D_id = kInvalidPoint3DId;
    image.cam_from_world = TransformCameraPose(model_from_truth, image.cam_from_world);
    model.AddImage(image);
    model.RegisterImage(image_id);
  }
  size_t count = 0;
  for (const auto& [point3D_id, point] : truth.Points3D()) {
    Track track;
    for (const TrackElement& element : point.track.elements) {
      if (members.count(element.image_id)) track.elements.push_back(element);
    }
    if (track.Length() < 2) continue;
    Eigen::Vector3d xyz = model_from_truth * point.xyz;
    if (outlier_share > 0 && (count++ % static_cast<size_t>(1.0 / outlier_share)) == 0) {
      xyz += Eigen::Vector3d(3, -2, 5) * model_from_truth.scale;
    }
    model.AddPoint3D(xyz, track);
  }
  return model;
}

Reconstruction SequenceTruth() {
  SyntheticDatasetOptions options;
  options.layout = SyntheticDatasetOptions::Layout::kSequence;
  options.num_images = 30;
  options.num_points3D = 3000;
  options.min_track_length = 2;
  options.seed = 4;
  Reconstruction truth;
  SynthesizeDataset(options, &truth);
  return truth;
}

std::vector<image_t> Range(image_t first, image_t last) {
  std::vector<image_t> ids;
  for (image_t id = first; id <= last; ++id) ids.push_back(id);
  return ids;
}

TEST(ModelMerger, OverlappingModelsInFramesOfTheirOwnJoinIntoOne) {
  const Reconstruction truth = SequenceTruth();
  std::vector<Reconstruction> models;
  models.push_back(SubModel(truth, Range(1, 12), MakeSim3(0.5, 0.3, {0, 0, 1}, {1, 2, 3})));
  // The largest, so the frame of the result; a fifth of its points badly off.
  models.push_back(SubModel(truth, Range(9, 24), MakeSim3(3.0, -1.2, {1, 1, 0}, {-5, 0, 2}), 0.2));
  models.push_back(SubModel(truth, Range(21, 30), MakeSim3(1.7, 2.0, {0, 1, 1}, {0, 7, -1})));
  std::vector<ModelMergeReport> reports;
  const Reconstruction merged = MergeModels(ModelMergerOptions(), models, &reports);
  ASSERT_EQ(merged.NumRegImages(), 30u);
  EXPECT_EQ(merged.NumPoints3D(), 0u);  // Poses only.
  ASSERT_EQ(reports.size(), 3u);
  for (const ModelMergeReport& report : reports) EXPECT_TRUE(report.success);
  EXPECT_EQ(reports[0].num_shared_images, 4u);
  EXPECT_GT(reports[0].num_inliers, 100u);
  // The second model's images keep their poses exactly; the others are in its frame.
  for (const image_t image_id : Range(9, 24)) {
    EXPECT_EQ(merged.GetImage(image_id).cam_from_world.translation,
              models[1].GetImage(image_id).cam_from_world.translation);
  }
  const PoseErrors errors = CompareToTruth(merged, truth);
  EXPECT_LT(errors.max_rotation_deg, 1e-7);
  EXPECT_LT(errors.max_center_error, 1e-7);
}

TEST(ModelMerger, ModelsThatShareTooLittleAreLeftOut) {
  const Reconstruction truth = SequenceTruth();
  std::vector<Reconstruction> models;
  models.push_back(SubModel(truth, Range(1, 15), Sim3d()));
  models.push_back(
      SubModel(truth, Range(14, 20), MakeSim3(2, 0.5, {1, 0, 0}, {0, 1, 0})));  // 2 shared.
  ModelMergerOptions options;
  options.min_shared_images = 3;
  std::vector<ModelMergeReport> reports;
  const Reconstruction merged = MergeModels(options, models, &reports);
  EXPECT_EQ(merged.NumRegImages(), 15u);
  EXPECT_TRUE(reports[0].success);
  EXPECT_FALSE(reports[1].success);
  EXPECT_EQ(reports[1].num_shared_images, 0u);  // Never tried.
}

TEST(ModelMerger, AModelWhosePointsDisagreeIsNotMerged) {
  const Reconstruction truth = SequenceTruth();
  std::vector<Reconstruction> models;
  models.push_back(SubModel(truth, Range(1, 15), Sim3d()));
  Reconstruction scrambled = SubModel(truth, Range(10, 20), Sim3d());
  // Every point moved at random: no similarity maps them onto the first model's.
  std::mt19937 generator(3);
  std::uniform_real_distribution<double> offset(-5, 5);
  for (auto& [point3D_id, point] : scrambled.Points3D()) {
    scrambled.GetPoint3D(point3D_id).xyz +=
        Eigen::Vector3d(offset(generator), offset(generator), offset(generator));
  }
  models.push_back(scrambled);
  std::vector<ModelMergeReport> reports;
  const Reconstruction merged = MergeModels(ModelMergerOptions(), models, &reports);
  EXPECT_EQ(merged.NumRegImages(), 15u);
  EXPECT_FALSE(reports[1].success);
  EXPECT_EQ(reports[1].num_shared_images, 6u);
  EXPECT_GT(reports[1].num_correspondences, 100u);
}

}  // namespace
}  // namespace parallax
