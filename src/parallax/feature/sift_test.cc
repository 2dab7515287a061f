#include "parallax/feature/sift.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <iostream>
#include <limits>
#include <opencv2/imgproc.hpp>

#include "parallax/feature/blob_test_image.h"
#include "parallax/feature/matcher.h"
#include "parallax/image/image_reader.h"
#include "parallax/math/random.h"
#include "parallax/util/check.h"
#include "parallax/util/file.h"

namespace parallax {
namespace {

constexpr double kPi = 3.14159265358979323846;

cv::Mat TexturedImage(int width, int height, int num_blobs) {
  return test::BlobTexturedImage(width, height, num_blobs);
}

// How many of `frames` the `other` run found too: within a quarter of the frame's scale, at a
// scale within 25 %.
size_t NumFoundIn(const FeatureKeypoints& frames, const FeatureKeypoints& other) {
  size_t num_found = 0;
  for (const FeatureKeypoint& frame : frames) {
    for (const FeatureKeypoint& candidate : other) {
      const double scale_ratio = candidate.ComputeScale() / frame.ComputeScale();
      if (std::hypot(candidate.x - frame.x, candidate.y - frame.y) < 0.25 * frame.ComputeScale() &&
          scale_ratio > 0.8 && scale_ratio < 1.25) {
        ++num_found;
        break;
      }
    }
  }
  return num_found;
}

double AngleDifference(double a, double b) { return std::abs(std::remainder(a - b, 2 * kPi)); }

double Median(std::vector<double> values) {
  PARALLAX_CHECK(!values.empty());
  std::nth_element(values.begin(), values.begin() + values.size() / 2, values.end());
  return values[values.size() / 2];
}

// The tests that hold for both implementations run once for each.
class SiftTest : public ::testing::TestWithParam<SiftImplementation> {
 protected:
  SiftExtractionOptions Options() const {
    SiftExtractionOptions options;
    options.implementation = GetParam();
    return options;
  }
};

INSTANTIATE_TEST_SUITE_P(Implementations, SiftTest,
                         ::testing::Values(SiftImplementation::kNative,
                                           SiftImplementation::kOpenCv),
                         [](const ::testing::TestParamInfo<SiftImplementation>& info) {
                           return std::string(SiftImplementationName(info.param));
                         });

TEST_P(SiftTest, RotatedAndScaledCopyIsMatchedConsistently) {
  const cv::Mat image1 = TexturedImage(480, 360, 600);
  // image2 = image1 rotated by 30 degrees and scaled by 0.8 about the centre (OpenCV pixel
  // convention: integer pixel centres).
  const cv::Mat warp = cv::getRotationMatrix2D(cv::Point2f(240, 180), 30.0, 0.8);
  cv::Mat image2;
  cv::warpAffine(image1, image2, warp, image1.size(), cv::INTER_LINEAR, cv::BORDER_CONSTANT,
                 cv::Scalar(128));
  Eigen::Matrix2d linear;
  Eigen::Vector2d offset;
  linear << warp.at<double>(0, 0), warp.at<double>(0, 1), warp.at<double>(1, 0),
      warp.at<double>(1, 1);
  offset << warp.at<double>(0, 2), warp.at<double>(1, 2);

  const auto extractor = CreateSiftExtractor(Options());
  FeatureKeypoints keypoints1, keypoints2;
  FeatureDescriptors descriptors1, descriptors2;
  extractor->Extract(image1, &keypoints1, &descriptors1);
  extractor->Extract(image2, &keypoints2, &descriptors2);
  EXPECT_GT(keypoints1.size(), 200u);
  EXPECT_GT(keypoints2.size(), 150u);
  ASSERT_EQ(descriptors1.rows(), static_cast<Eigen::Index>(keypoints1.size()));
  ASSERT_EQ(descriptors1.cols(), 128);

  const FeatureMatches matches = MatchDescriptors(
      PrepareDescriptors(descriptors1), PrepareDescriptors(descriptors2), FeatureMatchingOptions());
  ASSERT_GT(matches.size(), 100u);
  std::vector<double> scale_ratios, orientation_errors;
  int num_inliers = 0;
  for (const FeatureMatch& match : matches) {
    const FeatureKeypoint& k1 = keypoints1[match.point2D_idx1];
    const FeatureKeypoint& k2 = keypoints2[match.point2D_idx2];
    // COLMAP convention: subtract 0.5 to warp with OpenCV's matrix, add it back after.
    const Eigen::Vector2d expected =
        linear * Eigen::Vector2d(k1.x - 0.5, k1.y - 0.5) + offset + Eigen::Vector2d(0.5, 0.5);
    if ((expected - Eigen::Vector2d(k2.x, k2.y)).norm() > 1.5) continue;
    ++num_inliers;
    scale_ratios.push_back(k2.ComputeScale() / k1.ComputeScale());
    // The keypoint's orientation follows the warp: the frame's x axis maps through `linear`.
    const double theta1 = k1.ComputeOrientation();
    const Eigen::Vector2d direction = linear * Eigen::Vector2d(std::cos(theta1), std::sin(theta1));
    orientation_errors.push_back(
        AngleDifference(std::atan2(direction.y(), direction.x()), k2.ComputeOrientation()));
  }
  EXPECT_GT(num_inliers, 0.9 * matches.size()) << num_inliers << " of " << matches.size();
  EXPECT_NEAR(Median(scale_ratios), 0.8, 0.05);
  EXPECT_LT(Median(orientation_errors), 3.0 * kPi / 180.0);
}

TEST_P(SiftTest, DescriptorsAreQuantisedUnitVectors) {
  const cv::Mat image = TexturedImage(320, 240, 300);
  for (const bool root_sift : {false, true}) {
    SiftExtractionOptions options = Options();
    options.root_sift = root_sift;
    FeatureKeypoints keypoints;
    FeatureDescriptors descriptors;
    CreateSiftExtractor(options)->Extract(image, &keypoints, &descriptors);
    ASSERT_GT(keypoints.size(), 50u);
    for (Eigen::Index i = 0; i < descriptors.rows(); ++i) {
      const double norm = descriptors.row(i).cast<double>().norm();
      // 512 x unit vector; rounding moves it by at most sqrt(128)/2, clamping at 255 only down.
      EXPECT_LE(norm, 512.0 + 6.0);
      EXPECT_GE(norm, root_sift ? 0.85 * 512.0 : 512.0 - 6.0);
    }
  }
}

TEST_P(SiftTest, DeterministicAndKeepsTheStrongest) {
  const cv::Mat image = TexturedImage(400, 300, 500);
  SiftExtractionOptions options = Options();
  FeatureKeypoints keypoints_a, keypoints_b, keypoints_limited;
  FeatureDescriptors descriptors_a, descriptors_b, descriptors_limited;
  CreateSiftExtractor(options)->Extract(image, &keypoints_a, &descriptors_a);
  CreateSiftExtractor(options)->Extract(image, &keypoints_b, &descriptors_b);
  ASSERT_EQ(keypoints_a.size(), keypoints_b.size());
  for (size_t i = 0; i < keypoints_a.size(); ++i) {
    EXPECT_EQ(keypoints_a[i].x, keypoints_b[i].x);
    EXPECT_EQ(keypoints_a[i].y, keypoints_b[i].y);
    EXPECT_EQ(keypoints_a[i].a11, keypoints_b[i].a11);
    EXPECT_EQ(keypoints_a[i].a21, keypoints_b[i].a21);
  }
  EXPECT_EQ(descriptors_a, descriptors_b);

  // The strongest 50 are the first 50 of the full, response-ordered list.
  ASSERT_GT(keypoints_a.size(), 100u);
  options.max_num_features = 50;
  CreateSiftExtractor(options)->Extract(image, &keypoints_limited, &descriptors_limited);
  ASSERT_EQ(keypoints_limited.size(), 50u);
  for (size_t i = 0; i < 50; ++i) {
    EXPECT_EQ(keypoints_limited[i].x, keypoints_a[i].x);
    EXPECT_EQ(keypoints_limited[i].y, keypoints_a[i].y);
  }
  EXPECT_EQ(descriptors_limited, descriptors_a.topRows(50));
}

TEST_P(SiftTest, LargeImagesAreDownscaledAndKeypointsRescaled) {
  const cv::Mat image = TexturedImage(800, 600, 1500);
  cv::Mat half;
  cv::resize(image, half, cv::Size(400, 300), 0, 0, cv::INTER_AREA);
  SiftExtractionOptions options = Options();
  FeatureKeypoints keypoints_half, keypoints_full;
  FeatureDescriptors descriptors_half, descriptors_full;
  CreateSiftExtractor(options)->Extract(half, &keypoints_half, &descriptors_half);
  options.max_image_size = 400;
  CreateSiftExtractor(options)->Extract(image, &keypoints_full, &descriptors_full);
  ASSERT_GT(keypoints_half.size(), 50u);
  ASSERT_EQ(keypoints_full.size(), keypoints_half.size());
  for (size_t i = 0; i < keypoints_half.size(); ++i) {
    // Pixel edges scale with the image, so COLMAP coordinates (edges at integers) double.
    EXPECT_FLOAT_EQ(keypoints_full[i].x, 2.0f * keypoints_half[i].x);
    EXPECT_FLOAT_EQ(keypoints_full[i].y, 2.0f * keypoints_half[i].y);
    EXPECT_NEAR(keypoints_full[i].ComputeScale(), 2.0f * keypoints_half[i].ComputeScale(), 1e-4);
    EXPECT_NEAR(keypoints_full[i].ComputeOrientation(), keypoints_half[i].ComputeOrientation(),
                1e-6);
  }
  EXPECT_EQ(descriptors_full, descriptors_half);
}

// Above max_upsampled_image_size the first octave is at the image's own resolution: OpenCV's
// detector then sees exactly the half-size image doubled, and finds the same blobs as with
// the doubled full image except the finest ones.
TEST(Sift, OpenCvLargeImagesAreNotUpsampled) {
  const cv::Mat image = TexturedImage(800, 600, 1500);
  cv::Mat half;
  cv::resize(image, half, cv::Size(400, 300), 0, 0, cv::INTER_AREA);
  SiftExtractionOptions options;
  options.implementation = SiftImplementation::kOpenCv;
  options.max_num_features = 100000;
  FeatureKeypoints keypoints_half, keypoints_own, keypoints_doubled;
  FeatureDescriptors descriptors_half, descriptors_own, descriptors_doubled;
  CreateSiftExtractor(options)->Extract(half, &keypoints_half, &descriptors_half);
  options.max_upsampled_image_size = 600;
  CreateSiftExtractor(options)->Extract(image, &keypoints_own, &descriptors_own);
  ASSERT_GT(keypoints_half.size(), 50u);
  ASSERT_EQ(keypoints_own.size(), keypoints_half.size());
  for (size_t i = 0; i < keypoints_half.size(); ++i) {
    EXPECT_FLOAT_EQ(keypoints_own[i].x, 2.0f * keypoints_half[i].x);
    EXPECT_FLOAT_EQ(keypoints_own[i].y, 2.0f * keypoints_half[i].y);
  }
  EXPECT_EQ(descriptors_own, descriptors_half);

  options.max_upsampled_image_size = 0;
  CreateSiftExtractor(options)->Extract(image, &keypoints_doubled, &descriptors_doubled);
  EXPECT_GT(keypoints_doubled.size(), keypoints_own.size());
  const size_t num_found = NumFoundIn(keypoints_own, keypoints_doubled);
  std::cout << num_found << " of " << keypoints_own.size() << " keypoints also found doubled ("
            << keypoints_doubled.size() << " there)\n";
  EXPECT_GT(num_found, 0.8 * keypoints_own.size());
}

// The native SIFT above max_upsampled_image_size starts at the image's own resolution: no
// frame finer than that octave's first layer, and most of its frames are the doubled run's.
TEST(Sift, NativeLargeImagesAreNotUpsampled) {
  const cv::Mat image = TexturedImage(800, 600, 1500);
  SiftExtractionOptions options;
  options.implementation = SiftImplementation::kNative;
  options.max_num_features = 100000;
  options.max_upsampled_image_size = 600;
  FeatureKeypoints keypoints_own, keypoints_doubled;
  FeatureDescriptors descriptors_own, descriptors_doubled;
  CreateSiftExtractor(options)->Extract(image, &keypoints_own, &descriptors_own);
  options.max_upsampled_image_size = 0;
  CreateSiftExtractor(options)->Extract(image, &keypoints_doubled, &descriptors_doubled);
  ASSERT_GT(keypoints_own.size(), 50u);
  EXPECT_GT(keypoints_doubled.size(), keypoints_own.size());
  const auto finest = [](const FeatureKeypoints& keypoints) {
    float scale = std::numeric_limits<float>::max();
    for (const FeatureKeypoint& keypoint : keypoints) {
      scale = std::min(scale, keypoint.ComputeScale());
    }
    return scale;
  };
  // Octave 0 starts at sigma 1.6; refinement moves a frame at most half a layer below it.
  EXPECT_GT(finest(keypoints_own), 1.6 * std::pow(2.0, -0.5 / 3) - 1e-3);
  EXPECT_LT(finest(keypoints_doubled), 1.4);
  const size_t num_found = NumFoundIn(keypoints_own, keypoints_doubled);
  EXPECT_GT(num_found, 0.8 * keypoints_own.size()) << num_found << " of " << keypoints_own.size();
}

// Both SIFTs store Lowe's descriptor layout, so a database may hold features of either (one
// made before the native SIFT was the default, say): the same frame found by both has nearly
// the same descriptor, and it is the nearest of the other's.
TEST(Sift, NativeAndOpenCvDescriptorsShareOneLayout) {
  const cv::Mat image = TexturedImage(320, 240, 400);
  FeatureKeypoints native_keypoints, opencv_keypoints;
  FeatureDescriptors native_descriptors, opencv_descriptors;
  SiftExtractionOptions options;
  options.implementation = SiftImplementation::kNative;
  CreateSiftExtractor(options)->Extract(image, &native_keypoints, &native_descriptors);
  options.implementation = SiftImplementation::kOpenCv;
  CreateSiftExtractor(options)->Extract(image, &opencv_keypoints, &opencv_descriptors);
  const UnitDescriptorRows native = ToUnitRows(native_descriptors);
  const UnitDescriptorRows opencv = ToUnitRows(opencv_descriptors);
  int num_counterparts = 0, num_nearest = 0;
  std::vector<double> similarities;
  for (size_t i = 0; i < native_keypoints.size(); ++i) {
    const FeatureKeypoint& k = native_keypoints[i];
    for (size_t j = 0; j < opencv_keypoints.size(); ++j) {
      const FeatureKeypoint& o = opencv_keypoints[j];
      // OpenCV's positions are a quarter pixel off (NativeSift.BlobPositionAndScaleAreExact).
      if (std::hypot(o.x - k.x - 0.25, o.y - k.y - 0.25) > 0.3 ||
          std::abs(o.ComputeScale() / k.ComputeScale() - 1.0) > 0.05 ||
          AngleDifference(o.ComputeOrientation(), k.ComputeOrientation()) > 0.1) {
        continue;
      }
      ++num_counterparts;
      Eigen::Index nearest = 0;
      (opencv * native.row(i).transpose()).maxCoeff(&nearest);
      similarities.push_back(opencv.row(j).dot(native.row(i)));
      if (nearest == static_cast<Eigen::Index>(j)) ++num_nearest;
      break;
    }
  }
  ASSERT_GT(num_counterparts, 50);
  EXPECT_GT(Median(similarities), 0.97);
  EXPECT_GT(num_nearest, 0.9 * num_counterparts) << num_nearest << " of " << num_counterparts;
}

TEST_P(SiftTest, EmptyAndFeaturelessImages) {
  const auto extractor = CreateSiftExtractor(Options());
  FeatureKeypoints keypoints(3);
  FeatureDescriptors descriptors(3, 128);
  extractor->Extract(cv::Mat(0, 0, CV_8UC1), &keypoints, &descriptors);
  EXPECT_TRUE(keypoints.empty());
  EXPECT_EQ(descriptors.rows(), 0);
  extractor->Extract(cv::Mat(100, 100, CV_8UC1, cv::Scalar(77)), &keypoints, &descriptors);
  EXPECT_TRUE(keypoints.empty());
  EXPECT_EQ(descriptors.rows(), 0);
  EXPECT_EQ(descriptors.cols(), 128);
  // Tiny images have too few octaves for any extremum, but must not fail.
  for (const int size : {1, 2, 3, 7, 16}) {
    cv::Mat tiny(size, size + 1, CV_8UC1);
    cv::randu(tiny, 0, 255);
    extractor->Extract(tiny, &keypoints, &descriptors);
    EXPECT_EQ(descriptors.rows(), static_cast<Eigen::Index>(keypoints.size()));
  }
  EXPECT_THROW(extractor->Extract(cv::Mat(10, 10, CV_8UC3), &keypoints, &descriptors), CheckError);
}

TEST(Sift, OptionsCheck) {
  SiftExtractionOptions options;
  EXPECT_NO_THROW(options.Check());
  options.max_num_features = 0;
  EXPECT_THROW(CreateSiftExtractor(options), CheckError);
  options = {};
  options.sigma = -1;
  EXPECT_THROW(options.Check(), CheckError);
  options = {};
  options.max_num_orientations = 0;
  EXPECT_THROW(options.Check(), CheckError);
}

// The figures the paper reports for templeRing with OpenCV's SIFT: 867 keypoints per image on
// average, 458 putative matches between templeR0001 and templeR0002.
TEST_P(SiftTest, TempleRingFigures) {
  const std::filesystem::path dir = DataRoot() / "templeRing" / "images";
  if (!std::filesystem::is_directory(dir)) GTEST_SKIP() << "no data at " << dir;
  const std::vector<std::filesystem::path> paths = ListImageFiles(dir);
  ASSERT_EQ(paths.size(), 47u);
  const auto extractor = CreateSiftExtractor(Options());
  size_t total = 0;
  FeatureDescriptors descriptors0001, descriptors0002;
  FeatureKeypoints keypoints;
  for (const auto& path : paths) {
    FeatureDescriptors descriptors;
    extractor->Extract(ReadBitmap(path).gray, &keypoints, &descriptors);
    total += keypoints.size();
    if (path.filename() == "templeR0001.png") descriptors0001 = descriptors;
    if (path.filename() == "templeR0002.png") descriptors0002 = descriptors;
  }
  const double mean_keypoints = static_cast<double>(total) / paths.size();
  std::cout << "templeRing: mean keypoints per image " << mean_keypoints << " (paper 867)\n";
  EXPECT_GT(mean_keypoints, 300);
  EXPECT_LT(mean_keypoints, 3000);

  ASSERT_GT(descriptors0001.rows(), 0);
  ASSERT_GT(descriptors0002.rows(), 0);
  const MatchableDescriptors matchable1 = PrepareDescriptors(descriptors0001);
  const MatchableDescriptors matchable2 = PrepareDescriptors(descriptors0002);
  FeatureMatchingOptions ratio_only;
  ratio_only.max_distance = 2.0;  // Unit vectors are at most 2 apart: no bound.
  ratio_only.cross_check = false;
  const size_t num_ratio = MatchDescriptors(matchable1, matchable2, ratio_only).size();
  const size_t num_default =
      MatchDescriptors(matchable1, matchable2, FeatureMatchingOptions()).size();
  std::cout << "templeR0001/0002: " << descriptors0001.rows() << " and " << descriptors0002.rows()
            << " keypoints; putative matches, ratio 0.8 only: " << num_ratio
            << ", with distance bound and cross-check (defaults): " << num_default
            << " (paper 458)\n";
  EXPECT_GT(num_ratio, 100u);
  EXPECT_LT(num_ratio, 2000u);
  EXPECT_LE(num_default, num_ratio);

  // The same with plain (not root) SIFT descriptors, as OpenCV outputs them.
  SiftExtractionOptions plain_options = Options();
  plain_options.root_sift = false;
  const auto plain_extractor = CreateSiftExtractor(plain_options);
  FeatureDescriptors plain1, plain2;
  plain_extractor->Extract(ReadBitmap(dir / "templeR0001.png").gray, &keypoints, &plain1);
  plain_extractor->Extract(ReadBitmap(dir / "templeR0002.png").gray, &keypoints, &plain2);
  const size_t num_plain_ratio =
      MatchDescriptors(PrepareDescriptors(plain1), PrepareDescriptors(plain2), ratio_only).size();
  std::cout << "templeR0001/0002 without root_sift: putative matches, ratio 0.8 only: "
            << num_plain_ratio << "\n";
  EXPECT_GT(num_plain_ratio, 100u);
  EXPECT_LT(num_plain_ratio, 2000u);
}

}  // namespace
}  // namespace parallax
