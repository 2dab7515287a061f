#include "parallax/report/model_union.h"

#include <gtest/gtest.h>

#include "parallax/math/random.h"
#include "parallax/scene/synthetic_dataset.h"
#include "parallax/util/check.h"

namespace parallax {
namespace {

// Two overlapping parts of one exact scene, the second in a frame of its own: merged, every
// image sits where the first part's frame puts it, and the second part's points join.
TEST(UniteModels, AddsTheImagesAndPointsOfAnOverlappingModel) {
  SyntheticDatasetOptions options;
  options.num_images = 10;
  options.num_points3D = 200;
  Reconstruction truth;
  SynthesizeDataset(options, &truth);
  const std::vector<image_t> ids = truth.RegImageIds();
  Reconstruction base = truth, other = truth;
  for (size_t i = 6; i < ids.size(); ++i) base.DeRegisterImage(ids[i]);  // base: 1-6
  for (size_t i = 0; i < 3; ++i) other.DeRegisterImage(ids[i]);          // other: 4-10
  other.Transform(
      Sim3d(2.5, Eigen::Quaterniond(Eigen::AngleAxisd(0.7, Eigen::Vector3d(1, 2, 3).normalized())),
            Eigen::Vector3d(4, -1, 2)));

  ModelUnionReport report;
  const Reconstruction united = UniteModels(base, "base", other, &report);
  EXPECT_EQ(report.num_shared_images, 3u);
  EXPECT_EQ(report.num_images_added, 4u);
  EXPECT_NEAR(report.scale, 1 / 2.5, 1e-9);
  EXPECT_EQ(united.NumRegImages(), 10u);
  // Every image where the truth has it (base's frame is the truth's).
  for (const image_t image_id : united.RegImageIds()) {
    const Image& image = united.GetImage(image_id);
    const Image* truth_image = nullptr;
    for (const auto& [id, candidate] : truth.Images()) {
      if (candidate.name == image.name) truth_image = &candidate;
    }
    ASSERT_NE(truth_image, nullptr);
    EXPECT_LT((image.ProjectionCenter() - truth_image->ProjectionCenter()).norm(), 1e-8)
        << image.name;
  }
  // Added points lie on the truth's points and are seen only by the added images.
  EXPECT_GT(report.num_points_added, 0u);
  EXPECT_EQ(united.NumPoints3D(), base.NumPoints3D() + report.num_points_added);
  for (const auto& [point3D_id, point] : united.Points3D()) {
    for (const TrackElement& element : point.track.elements) {
      EXPECT_EQ(united.GetImage(element.image_id).points2D[element.point2D_idx].point3D_id,
                point3D_id);
    }
  }
  // Too little in common: a one-line error naming the base.
  Reconstruction far = truth;
  for (size_t i = 0; i < 8; ++i) far.DeRegisterImage(ids[i]);
  Reconstruction near = truth;
  for (size_t i = 2; i < ids.size(); ++i) near.DeRegisterImage(ids[i]);
  EXPECT_THROW(UniteModels(near, "near", far, nullptr), InputError);
}

}  // namespace
}  // namespace parallax
