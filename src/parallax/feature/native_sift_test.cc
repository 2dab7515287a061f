#include "parallax/feature/native_sift.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>

#include "parallax/feature/blob_test_image.h"
#include "parallax/math/random.h"
#include "parallax/util/check.h"

namespace parallax {
namespace {

constexpr double kPi = 3.14159265358979323846;

// A bright Gaussian blob of standard deviation `sigma` centred at (cx, cy) in COLMAP's pixel
// convention (pixel (i, j) covers [i, i + 1) x [j, j + 1), its centre at (i + 0.5, j + 0.5)).
cv::Mat BlobImage(int width, int height, double cx, double cy, double sigma) {
  cv::Mat image(height, width, CV_8UC1);
  for (int j = 0; j < height; ++j) {
    for (int i = 0; i < width; ++i) {
      const double dx = i + 0.5 - cx, dy = j + 0.5 - cy;
      const double value = 60.0 + 150.0 * std::exp(-0.5 * (dx * dx + dy * dy) / (sigma * sigma));
      image.at<uint8_t>(j, i) = static_cast<uint8_t>(std::lround(value));
    }
  }
  return image;
}

cv::Mat TexturedImage(int width, int height, int num_blobs) {
  return test::BlobTexturedImage(width, height, num_blobs, /*max_sigma=*/8.0);
}

const SiftFrame& Strongest(const std::vector<SiftFrame>& frames) {
  PARALLAX_CHECK(!frames.empty());
  return *std::max_element(
      frames.begin(), frames.end(),
      [](const SiftFrame& a, const SiftFrame& b) { return a.response < b.response; });
}

// A blob's centre is found where it is, in the doubled first octave and without it: over
// blobs at many sub-pixel positions the errors average out to nothing (no offset from the
// upsampling or the octaves' subsampling; OpenCV's doubled octave is off by a quarter
// pixel), and each is within a few hundredths of the blob's size.
TEST(NativeSift, BlobPositionAndScaleAreExact) {
  for (const bool doubled : {true, false}) {
    for (const double sigma : {2.5, 4.0, 7.0}) {
      NativeSiftOptions options;
      options.double_first_octave = doubled;
      double sum_dx = 0, sum_dy = 0;
      constexpr int kPositions = 12;
      for (int k = 0; k < kPositions; ++k) {
        const double cx = 60 + RandomUniformReal(0, 1), cy = 48 + RandomUniformReal(0, 1);
        std::vector<SiftFrame> frames;
        std::vector<float> descriptors;
        ComputeNativeSift(BlobImage(128, 96, cx, cy, sigma), options, &frames, &descriptors);
        ASSERT_FALSE(frames.empty()) << "sigma " << sigma;
        ASSERT_EQ(descriptors.size(), 128 * frames.size());
        const SiftFrame& blob = Strongest(frames);
        EXPECT_LT(std::hypot(blob.x - cx, blob.y - cy), 0.06 * sigma)
            << "doubled " << doubled << ", sigma " << sigma;
        // The scale-normalised Laplacian of a Gaussian blob of sigma s peaks at scale s; the
        // difference of Gaussians finds it a little smaller.
        EXPECT_NEAR(blob.scale / sigma, 0.9, 0.08) << "doubled " << doubled << ", sigma " << sigma;
        sum_dx += blob.x - cx;
        sum_dy += blob.y - cy;
      }
      EXPECT_LT(std::abs(sum_dx / kPositions), 0.04)
          << "doubled " << doubled << ", sigma " << sigma;
      EXPECT_LT(std::abs(sum_dy / kPositions), 0.04)
          << "doubled " << doubled << ", sigma " << sigma;
    }
  }
}

// A quarter turn of the image (exact, no resampling) turns every frame with it: same scale,
// orientation + pi/2, the descriptor nearly the same. Each octave keeps every other sample
// starting from the first, so the sample grids turn onto themselves only where every
// octave's sides are odd: 127 x 95 at the image's own resolution.
TEST(NativeSift, QuarterTurnTurnsTheFrames) {
  const cv::Mat image = TexturedImage(127, 95, 120);
  cv::Mat turned;
  cv::rotate(image, turned, cv::ROTATE_90_CLOCKWISE);  // (x, y) -> (height - y, x)
  NativeSiftOptions options;
  options.double_first_octave = false;
  options.max_num_orientations = 1;
  std::vector<SiftFrame> frames, turned_frames;
  std::vector<float> descriptors, turned_descriptors;
  ComputeNativeSift(image, options, &frames, &descriptors);
  ComputeNativeSift(turned, options, &turned_frames, &turned_descriptors);
  ASSERT_GT(frames.size(), 20u);

  int num_found = 0, num_same_descriptor = 0;
  for (size_t i = 0; i < frames.size(); ++i) {
    const SiftFrame& frame = frames[i];
    const double expected_x = image.rows - frame.y, expected_y = frame.x;
    for (size_t j = 0; j < turned_frames.size(); ++j) {
      const SiftFrame& other = turned_frames[j];
      if (std::hypot(other.x - expected_x, other.y - expected_y) > 0.02 ||
          std::abs(other.scale / frame.scale - 1.0) > 1e-3) {
        continue;
      }
      ++num_found;
      const double turn =
          std::remainder(other.orientation - frame.orientation - 0.5 * kPi, 2 * kPi);
      EXPECT_LT(std::abs(turn), 0.02) << "frame " << i;
      double distance_sq = 0;
      for (int k = 0; k < 128; ++k) {
        const double d = descriptors[128 * i + k] - turned_descriptors[128 * j + k];
        distance_sq += d * d;
      }
      if (std::sqrt(distance_sq) < 0.1) ++num_same_descriptor;
      break;
    }
  }
  // Not all: OpenCV blurs rows before columns, so the turned image's layers differ in the
  // last bits, which moves ties between neighbouring samples, and cartToPolar's angles are
  // an approximation good to about 0.3 degrees.
  EXPECT_GT(num_found, 0.8 * frames.size()) << num_found << " of " << frames.size();
  EXPECT_GT(num_same_descriptor, 0.8 * num_found) << num_same_descriptor << " of " << num_found;
}

TEST(NativeSift, OrientationsPerExtremumAreCapped) {
  const cv::Mat image = TexturedImage(200, 150, 250);
  for (const int cap : {1, 2, 4}) {
    NativeSiftOptions options;
    options.max_num_orientations = cap;
    std::vector<SiftFrame> frames;
    std::vector<float> descriptors;
    ComputeNativeSift(image, options, &frames, &descriptors);
    ASSERT_FALSE(frames.empty());
    int most_at_one_place = 0;
    for (const SiftFrame& frame : frames) {
      int same_place = 0;
      for (const SiftFrame& other : frames) {
        same_place += other.x == frame.x && other.y == frame.y && other.scale == frame.scale;
      }
      most_at_one_place = std::max(most_at_one_place, same_place);
    }
    EXPECT_LE(most_at_one_place, cap);
    if (cap > 1) {
      EXPECT_GT(most_at_one_place, 1) << "cap " << cap;
    }
  }
}

TEST(NativeSift, StrongestFirstAndCutBeforeDescriptors) {
  const cv::Mat image = TexturedImage(200, 150, 250);
  NativeSiftOptions options;
  std::vector<SiftFrame> all, strongest;
  std::vector<float> all_descriptors, strongest_descriptors;
  ComputeNativeSift(image, options, &all, &all_descriptors);
  ASSERT_GT(all.size(), 60u);
  for (size_t i = 1; i < all.size(); ++i) EXPECT_GE(all[i - 1].response, all[i].response);
  options.max_num_features = 50;
  ComputeNativeSift(image, options, &strongest, &strongest_descriptors);
  ASSERT_EQ(strongest.size(), 50u);
  for (size_t i = 0; i < strongest.size(); ++i) {
    EXPECT_EQ(strongest[i].x, all[i].x);
    EXPECT_EQ(strongest[i].orientation, all[i].orientation);
  }
  EXPECT_TRUE(std::equal(strongest_descriptors.begin(), strongest_descriptors.end(),
                         all_descriptors.begin()));
}

TEST(NativeSift, DescriptorsAreClampedUnitVectors) {
  std::vector<SiftFrame> frames;
  std::vector<float> descriptors;
  ComputeNativeSift(TexturedImage(160, 120, 150), NativeSiftOptions(), &frames, &descriptors);
  ASSERT_FALSE(frames.empty());
  for (size_t i = 0; i < frames.size(); ++i) {
    double norm_sq = 0;
    float largest = 0;
    for (int k = 0; k < 128; ++k) {
      const float value = descriptors[128 * i + k];
      EXPECT_GE(value, 0.0f);
      norm_sq += value * value;
      largest = std::max(largest, value);
    }
    EXPECT_NEAR(std::sqrt(norm_sq), 1.0, 1e-4);
    // Clamped at 0.2, then renormalised: a component can grow back only a little.
    EXPECT_LT(largest, 0.35f);
  }
}

// Buffers kept between calls (one block the scale space is laid out in) give what fresh
// ones give, whether the next image is larger, smaller or the same size, with or without
// the doubled octave.
TEST(NativeSift, ReusedBuffersGiveWhatFreshOnesGive) {
  NativeSiftBuffers buffers;
  NativeSiftOptions undoubled;
  undoubled.double_first_octave = false;
  const struct {
    cv::Mat image;
    NativeSiftOptions options;
  } calls[] = {{TexturedImage(120, 90, 80), {}},
               {TexturedImage(200, 150, 250), {}},
               {TexturedImage(160, 120, 150), undoubled},
               {TexturedImage(160, 120, 150), {}},
               {TexturedImage(120, 90, 80), {}}};
  for (const auto& call : calls) {
    std::vector<SiftFrame> fresh, reused;
    std::vector<float> fresh_descriptors, reused_descriptors;
    ComputeNativeSift(call.image, call.options, &fresh, &fresh_descriptors);
    ComputeNativeSift(call.image, call.options, &reused, &reused_descriptors, &buffers);
    ASSERT_FALSE(fresh.empty());
    ASSERT_EQ(reused.size(), fresh.size());
    for (size_t i = 0; i < fresh.size(); ++i) {
      EXPECT_EQ(reused[i].x, fresh[i].x);
      EXPECT_EQ(reused[i].y, fresh[i].y);
      EXPECT_EQ(reused[i].scale, fresh[i].scale);
      EXPECT_EQ(reused[i].orientation, fresh[i].orientation);
    }
    EXPECT_EQ(reused_descriptors, fresh_descriptors);
  }
}

TEST(NativeSift, OptionsCheck) {
  NativeSiftOptions options;
  EXPECT_NO_THROW(options.Check());
  options.max_num_orientations = 0;
  EXPECT_THROW(options.Check(), CheckError);
  options = {};
  options.contrast_threshold = 0;
  EXPECT_THROW(options.Check(), CheckError);
  options = {};
  options.max_num_features = -1;
  EXPECT_THROW(options.Check(), CheckError);
  std::vector<SiftFrame> frames;
  std::vector<float> descriptors;
  EXPECT_THROW(
      ComputeNativeSift(cv::Mat(10, 10, CV_32F), NativeSiftOptions(), &frames, &descriptors),
      CheckError);
}

}  // namespace
}  // namespace parallax
