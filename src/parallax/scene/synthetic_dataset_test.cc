#include "parallax/scene/synthetic_dataset.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <set>

#include <unistd.h>

#include "parallax/scene/database.h"
#include "parallax/util/check.h"

namespace parallax {
namespace {

using Layout = SyntheticDatasetOptions::Layout;

// Every observation projects exactly (or within noise) and both directions of every
// observation agree.
void ExpectConsistent(const SyntheticDatasetOptions& options, const Reconstruction& truth) {
  ASSERT_EQ(truth.NumCameras(), static_cast<size_t>(options.num_cameras));
  ASSERT_EQ(truth.NumImages(), static_cast<size_t>(options.num_images));
  ASSERT_EQ(truth.NumRegImages(), static_cast<size_t>(options.num_images));
  ASSERT_EQ(truth.NumPoints3D(), static_cast<size_t>(options.num_points3D));
  size_t num_observations = 0;
  for (const auto& [point3D_id, point] : truth.Points3D()) {
    EXPECT_GE(point.track.Length(), static_cast<size_t>(options.min_track_length));
    std::set<image_t> images;
    for (const TrackElement& element : point.track.elements) {
      const Image& image = truth.GetImage(element.image_id);
      EXPECT_TRUE(images.insert(element.image_id).second) << "two observations in one image";
      ASSERT_LT(element.point2D_idx, image.points2D.size());
      EXPECT_EQ(image.points2D[element.point2D_idx].point3D_id, point3D_id);
      const Eigen::Vector3d point_in_cam = image.cam_from_world * point.xyz;
      EXPECT_GE(point_in_cam.z(), options.min_depth);
    }
    num_observations += point.track.Length();
  }
  size_t num_linked = 0;
  for (const auto& [image_id, image] : truth.Images()) {
    EXPECT_EQ(image.camera_id, 1 + (image_id - 1) % options.num_cameras);
    for (const Point2D& point2D : image.points2D) {
      // Noise may push a keypoint a few sigma past the border.
      const double margin = 5 * options.point2D_noise_stddev;
      EXPECT_GE(point2D.xy.x(), -margin);
      EXPECT_GE(point2D.xy.y(), -margin);
      EXPECT_LE(point2D.xy.x(), options.width + margin);
      EXPECT_LE(point2D.xy.y(), options.height + margin);
      if (point2D.HasPoint3D()) ++num_linked;
    }
  }
  EXPECT_EQ(num_linked, num_observations);
  EXPECT_EQ(truth.NumObservations(), num_observations);
}

TEST(SynthesizeDataset, RingIsExactWithoutNoise) {
  SyntheticDatasetOptions options;
  options.num_images = 12;
  options.num_points3D = 300;
  Reconstruction truth;
  SynthesizeDataset(options, &truth);
  ExpectConsistent(options, truth);
  EXPECT_LT(truth.UpdatePointErrors(), 1e-9);
  // Every camera of the ring sees the whole cube.
  EXPECT_NEAR(truth.ComputeMeanTrackLength(), options.num_images, 1e-12);
  // Cameras stay on the ring and look at the centre.
  for (const auto& [image_id, image] : truth.Images()) {
    const Eigen::Vector3d center = image.ProjectionCenter();
    EXPECT_NEAR(center.norm(), options.camera_distance * std::sqrt(1 + 0.09), 1e-9);
    EXPECT_GT(image.ViewingDirection().dot(-center.normalized()), 0.99);
  }
}

TEST(SynthesizeDataset, EveryLayoutAndModelIsConsistent) {
  for (const Layout layout : {Layout::kRing, Layout::kHemisphere, Layout::kSequence}) {
    for (const CameraModelId model :
         {CameraModelId::kSimplePinhole, CameraModelId::kSimpleRadial, CameraModelId::kOpenCV}) {
      SyntheticDatasetOptions options;
      options.layout = layout;
      options.camera_model_id = model;
      options.distortion = model == CameraModelId::kSimplePinhole ? 0.0 : -0.05;
      options.num_cameras = 2;
      options.num_images = 15;
      options.num_points3D = 150;
      options.min_track_length = 3;
      options.seed = 7;
      Reconstruction truth;
      SynthesizeDataset(options, &truth);
      ExpectConsistent(options, truth);
      EXPECT_LT(truth.UpdatePointErrors(), 1e-6);
      EXPECT_NE(truth.GetCamera(1).MeanFocalLength(), truth.GetCamera(2).MeanFocalLength());
    }
  }
}

TEST(SynthesizeDataset, SequenceHasLocalTracks) {
  SyntheticDatasetOptions options;
  options.layout = Layout::kSequence;
  options.num_images = 40;
  options.num_points3D = 500;
  Reconstruction truth;
  SynthesizeDataset(options, &truth);
  ExpectConsistent(options, truth);
  // Each point is seen by neighbouring images only: the farthest points (camera_distance +
  // scene_radius away) stay in view over 5 * 640 / 600 = 5.3 m, about 18 steps.
  const double mean_track_length = truth.ComputeMeanTrackLength();
  EXPECT_GT(mean_track_length, 3);
  EXPECT_LT(mean_track_length, 0.5 * options.num_images);
  for (const auto& [point3D_id, point] : truth.Points3D()) {
    image_t min_id = kInvalidImageId, max_id = 0;
    for (const TrackElement& element : point.track.elements) {
      min_id = std::min(min_id, element.image_id);
      max_id = std::max(max_id, element.image_id);
    }
    EXPECT_LE(max_id - min_id, 20u);
  }
}

TEST(SynthesizeDataset, NoiseHasTheRequestedStatistics) {
  SyntheticDatasetOptions options;
  options.num_images = 20;
  options.num_points3D = 1000;
  options.point2D_noise_stddev = 1.5;
  Reconstruction truth;
  SynthesizeDataset(options, &truth);
  ExpectConsistent(options, truth);
  // Per-axis residuals of the true points: zero mean, the requested standard deviation.
  double sum = 0, sum_squares = 0;
  size_t count = 0;
  for (const auto& [point3D_id, point] : truth.Points3D()) {
    for (const TrackElement& element : point.track.elements) {
      const Image& image = truth.GetImage(element.image_id);
      const Eigen::Vector2d projection =
          truth.GetCamera(image.camera_id).ImgFromCam(image.cam_from_world * point.xyz);
      const Eigen::Vector2d residual = image.points2D[element.point2D_idx].xy - projection;
      sum += residual.sum();
      sum_squares += residual.squaredNorm();
      count += 2;
    }
  }
  ASSERT_GT(count, 20000u);
  EXPECT_NEAR(sum / count, 0.0, 0.05);
  EXPECT_NEAR(std::sqrt(sum_squares / count), options.point2D_noise_stddev, 0.03);
}

TEST(SynthesizeDataset, OutliersAreUnlinkedKeypoints) {
  SyntheticDatasetOptions options;
  options.num_images = 8;
  options.num_points3D = 400;
  options.outlier_ratio = 0.25;
  Reconstruction truth;
  SynthesizeDataset(options, &truth);
  ExpectConsistent(options, truth);
  for (const auto& [image_id, image] : truth.Images()) {
    EXPECT_EQ(image.NumPoints2D() - image.num_points3D,
              static_cast<size_t>(std::lround(0.25 * image.num_points3D)));
  }
}

TEST(SynthesizeDataset, DeterministicForASeed) {
  SyntheticDatasetOptions options;
  options.layout = Layout::kHemisphere;
  options.point2D_noise_stddev = 1.0;
  options.outlier_ratio = 0.1;
  options.seed = 42;
  Reconstruction a, b, c;
  SynthesizeDataset(options, &a);
  SynthesizeDataset(options, &b);
  options.seed = 43;
  SynthesizeDataset(options, &c);
  ASSERT_EQ(a.NumObservations(), b.NumObservations());
  for (const auto& [image_id, image] : a.Images()) {
    const Image& other = b.GetImage(image_id);
    EXPECT_EQ(image.cam_from_world.translation, other.cam_from_world.translation);
    ASSERT_EQ(image.NumPoints2D(), other.NumPoints2D());
    for (size_t k = 0; k < image.NumPoints2D(); ++k) {
      EXPECT_EQ(image.points2D[k].xy, other.points2D[k].xy);
      EXPECT_EQ(image.points2D[k].point3D_id, other.points2D[k].point3D_id);
    }
  }
  EXPECT_NE(a.GetPoint3D(1).xyz, c.GetPoint3D(1).xyz);
}

TEST(SynthesizeDataset, RejectsBadOptions) {
  SyntheticDatasetOptions options;
  options.camera_distance = 1.0;  // inside the cube of points
  Reconstruction truth;
  EXPECT_THROW(SynthesizeDataset(options, &truth), CheckError);
  options = SyntheticDatasetOptions();
  options.num_images = 3;
  options.min_track_length = 4;
  EXPECT_THROW(SynthesizeDataset(options, &truth), CheckError);
  // Views so narrow that almost no point is seen twice.
  options = SyntheticDatasetOptions();
  options.layout = SyntheticDatasetOptions::Layout::kHemisphere;
  options.focal_length = 1e5;
  EXPECT_THROW(SynthesizeDataset(options, &truth), CheckError);
}

class SyntheticDatabaseTest : public ::testing::Test {
 protected:
  void SetUp() override {
    path_ = std::filesystem::temp_directory_path() /
            ("parallax_synthetic_dataset_test_" + std::to_string(::getpid()) + ".db");
    std::filesystem::remove(path_);
  }
  void TearDown() override { std::filesystem::remove(path_); }
  std::filesystem::path path_;
};

TEST_F(SyntheticDatabaseTest, WritesTheTrueMatchesAndGeometries) {
  SyntheticDatasetOptions options;
  options.layout = Layout::kSequence;
  options.sequence_step = 1.0;
  options.num_cameras = 2;
  options.num_images = 10;
  options.num_points3D = 300;
  options.outlier_ratio = 0.2;
  Reconstruction truth;
  SynthesizeDataset(options, &truth);
  SyntheticDatabaseOptions database_options;
  database_options.outlier_match_ratio = 0.3;
  database_options.min_num_matches = 5;

  Database database(path_);
  WriteSyntheticDatabase(truth, &database, database_options);
  EXPECT_EQ(database.NumCameras(), 2u);
  EXPECT_EQ(database.NumImages(), truth.NumImages());
  for (const Camera& camera : database.ReadAllCameras()) {
    EXPECT_EQ(camera.params, truth.GetCamera(camera.camera_id).params);
  }
  for (const auto& [image_id, image] : truth.Images()) {
    ASSERT_EQ(database.ImageIdByName(image.name), image_id);
    const FeatureKeypoints keypoints = database.ReadKeypoints(image_id);
    ASSERT_EQ(keypoints.size(), image.NumPoints2D());
    for (size_t k = 0; k < keypoints.size(); ++k) {
      EXPECT_NEAR(keypoints[k].x, image.points2D[k].xy.x(), 1e-3);
      EXPECT_NEAR(keypoints[k].y, image.points2D[k].xy.y(), 1e-3);
    }
    const FeatureDescriptors descriptors = database.ReadDescriptors(image_id);
    EXPECT_EQ(descriptors.rows(), static_cast<Eigen::Index>(image.NumPoints2D()));
    EXPECT_EQ(descriptors.cols(), 128);
  }

  size_t num_pairs = 0, num_inliers = 0, num_raw = 0;
  for (const auto& [pair_id, geometry] : database.ReadTwoViewGeometries()) {
    ++num_pairs;
    const auto [image_id1, image_id2] = PairIdToImagePair(pair_id);
    const Image& image1 = truth.GetImage(image_id1);
    const Image& image2 = truth.GetImage(image_id2);
    EXPECT_EQ(geometry.config, TwoViewGeometry::kCalibrated);
    ASSERT_GE(geometry.inlier_matches.size(), 5u);
    const Eigen::Matrix3d K1 = truth.GetCamera(image1.camera_id).CalibrationMatrix();
    const Eigen::Matrix3d K2 = truth.GetCamera(image2.camera_id).CalibrationMatrix();
    for (const FeatureMatch& match : geometry.inlier_matches) {
      const Point2D& point1 = image1.points2D[match.point2D_idx1];
      const Point2D& point2 = image2.points2D[match.point2D_idx2];
      ASSERT_TRUE(point1.HasPoint3D());
      EXPECT_EQ(point1.point3D_id, point2.point3D_id);
      // Exact epipolar constraint on the noiseless keypoints, with E and F.
      const Eigen::Vector3d x1 = point1.xy.homogeneous(), x2 = point2.xy.homogeneous();
      EXPECT_NEAR(x2.dot(geometry.F * x1) / (geometry.F * x1).head<2>().norm(), 0.0, 1e-6);
      const Eigen::Vector3d y1 = K1.inverse() * x1, y2 = K2.inverse() * x2;
      EXPECT_NEAR(y2.dot(geometry.E * y1), 0.0, 1e-9);
    }
    EXPECT_NEAR(geometry.cam2_from_cam1.translation.norm(), 1.0, 1e-12);
    // Raw matches hold the inliers plus about 30% wrong ones.
    const FeatureMatches matches = database.ReadMatches(image_id1, image_id2);
    const std::set<std::pair<point2D_t, point2D_t>> raw = [&] {
      std::set<std::pair<point2D_t, point2D_t>> set;
      for (const FeatureMatch& match : matches) set.emplace(match.point2D_idx1, match.point2D_idx2);
      return set;
    }();
    for (const FeatureMatch& match : geometry.inlier_matches) {
      EXPECT_TRUE(raw.count({match.point2D_idx1, match.point2D_idx2}));
    }
    EXPECT_LE(matches.size(), 1.31 * geometry.inlier_matches.size() + 1);
    num_inliers += geometry.inlier_matches.size();
    num_raw += matches.size();
  }
  EXPECT_GT(num_raw, 1.25 * num_inliers);
  // Views 1 m apart see 4.3 to 5.3 m of the slab: only near neighbours share points.
  EXPECT_GT(num_pairs, 9u);
  EXPECT_LT(num_pairs, 45u);
  EXPECT_FALSE(database.ExistsTwoViewGeometry(1, 10));
}

TEST_F(SyntheticDatabaseTest, DescriptorsOfOnePointAreNearestNeighbours) {
  SyntheticDatasetOptions options;
  options.num_images = 3;
  options.num_points3D = 200;
  options.outlier_ratio = 0.5;
  Reconstruction truth;
  SynthesizeDataset(options, &truth);
  Database database(path_);
  WriteSyntheticDatabase(truth, &database);
  const FeatureDescriptors descriptors1 = database.ReadDescriptors(1);
  const FeatureDescriptors descriptors2 = database.ReadDescriptors(2);
  const Image& image1 = truth.GetImage(1);
  const Image& image2 = truth.GetImage(2);
  size_t num_correct = 0, num_true = 0;
  for (Eigen::Index i = 0; i < descriptors1.rows(); ++i) {
    if (!image1.points2D[i].HasPoint3D()) continue;
    ++num_true;
    Eigen::Index best = -1;
    double best_distance = 1e30;
    for (Eigen::Index j = 0; j < descriptors2.rows(); ++j) {
      const double distance =
          (descriptors1.row(i).cast<double>() - descriptors2.row(j).cast<double>()).squaredNorm();
      if (distance < best_distance) {
        best_distance = distance;
        best = j;
      }
    }
    if (image2.points2D[best].point3D_id == image1.points2D[i].point3D_id) ++num_correct;
  }
  EXPECT_EQ(num_correct, num_true);
}

}  // namespace
}  // namespace parallax
