#include "parallax/feature/resample.h"

#include <gtest/gtest.h>

#include <opencv2/imgproc.hpp>

#include "parallax/util/check.h"

namespace parallax {
namespace {

// The same floats as OpenCV's bilinear resize, on sizes with odd and even sides, one row or
// column, and one pixel.
TEST(UpsampleTwice, IsOpenCvsBilinearResizeBitForBit) {
  uint64_t seed = 1;
  for (const cv::Size size : {cv::Size(640, 480), cv::Size(97, 33), cv::Size(5, 3), cv::Size(1, 7),
                              cv::Size(9, 1), cv::Size(1, 1)}) {
    cv::Mat image(size, CV_32F);
    cv::RNG rng(seed++);
    rng.fill(image, cv::RNG::UNIFORM, 0.0f, 1.0f);
    cv::Mat expected, upsampled;
    cv::resize(image, expected, size * 2, 0, 0, cv::INTER_LINEAR);
    UpsampleTwice(image, &upsampled);
    ASSERT_EQ(upsampled.size(), expected.size());
    EXPECT_EQ(cv::norm(upsampled, expected, cv::NORM_INF), 0.0) << size;
  }
}

// A ramp stays a ramp between the edges, at half the slope: the weights are 1/4 and 3/4.
TEST(UpsampleTwice, InterpolatesBetweenPixelCentres) {
  cv::Mat ramp(1, 4, CV_32F);
  for (int x = 0; x < 4; ++x) ramp.at<float>(0, x) = static_cast<float>(4 * x);
  cv::Mat upsampled;
  UpsampleTwice(ramp, &upsampled);
  const std::vector<float> expected = {0, 1, 3, 5, 7, 9, 11, 12};
  for (int x = 0; x < 8; ++x) EXPECT_FLOAT_EQ(upsampled.at<float>(0, x), expected[x]) << x;
  for (int x = 0; x < 8; ++x) EXPECT_FLOAT_EQ(upsampled.at<float>(1, x), expected[x]) << x;
}

TEST(UpsampleTwice, RejectsOtherTypesAndItsInputAsOutput) {
  cv::Mat bytes(4, 4, CV_8U, cv::Scalar(1)), out;
  EXPECT_THROW(UpsampleTwice(bytes, &out), CheckError);
  cv::Mat image(4, 4, CV_32F, cv::Scalar(1));
  EXPECT_THROW(UpsampleTwice(image, &image), CheckError);
}

// The pixels OpenCV's nearest-neighbour resize to half the size picks (odd sides round down),
// here from a view of a larger image.
TEST(SampleEveryOther, IsOpenCvsNearestResizeToHalfTheSize) {
  cv::Mat image(70, 91, CV_32F);
  cv::RNG rng(5);
  rng.fill(image, cv::RNG::UNIFORM, 0.0f, 1.0f);
  for (const cv::Rect view :
       {cv::Rect(0, 0, 91, 70), cv::Rect(3, 2, 51, 33), cv::Rect(1, 1, 3, 2)}) {
    const cv::Mat src = image(view);
    cv::Mat expected, sampled;
    cv::resize(src, expected, cv::Size(src.cols / 2, src.rows / 2), 0, 0, cv::INTER_NEAREST);
    SampleEveryOther(src, &sampled);
    ASSERT_EQ(sampled.size(), expected.size()) << view;
    EXPECT_EQ(cv::norm(sampled, expected, cv::NORM_INF), 0.0) << view;
  }
  cv::Mat sampled;
  SampleEveryOther(image(cv::Rect(0, 0, 1, 5)), &sampled);
  EXPECT_TRUE(sampled.empty());
}

}  // namespace
}  // namespace parallax
