#include "parallax/feature/gaussian_blur.h"

#include <gtest/gtest.h>

#include <numeric>
#include <opencv2/imgproc.hpp>

#include "parallax/util/check.h"

namespace parallax {
namespace {

cv::Mat RandomImage(int width, int height, uint64_t seed) {
  cv::Mat image(height, width, CV_32F);
  cv::RNG rng(seed);
  rng.fill(image, cv::RNG::UNIFORM, 0.0f, 1.0f);
  return image;
}

TEST(GaussianHalfKernel, IsOpenCvsKernelForFloatImages) {
  for (const double sigma : {0.7, 1.23, 1.6, 3.09}) {
    const std::vector<float> half = GaussianHalfKernel(sigma);
    const int size = static_cast<int>(2 * half.size() - 1);
    EXPECT_EQ(size, cvRound(sigma * 8 + 1) | 1) << sigma;
    const cv::Mat expected = cv::getGaussianKernel(size, sigma, CV_32F);
    for (size_t i = 0; i < half.size(); ++i) {
      EXPECT_EQ(half[i], expected.at<float>(static_cast<int>(half.size() - 1 + i)));
      EXPECT_EQ(half[i], expected.at<float>(static_cast<int>(half.size() - 1 - i)));
    }
    EXPECT_NEAR(std::accumulate(half.begin() + 1, half.end(), 0.0f) * 2 + half[0], 1.0f, 1e-6f);
  }
}

// Sizes around the 16- and 32-sample blocks and the steps of four rows, and smaller than the
// kernel (every border replicated); kernels of 1 and 3 taps too.
TEST(GaussianBlur, MatchesOpenCvsReplicatedBorderBlur) {
  const std::vector<cv::Size> sizes = {{640, 480}, {97, 33}, {32, 5}, {31, 64},
                                       {48, 6},    {17, 7},  {5, 3},  {1, 1}};
  uint64_t seed = 1;
  for (const cv::Size& size : sizes) {
    const cv::Mat image = RandomImage(size.width, size.height, seed++);
    for (const double sigma : {0.05, 0.3, 1.23, 1.6, 3.09}) {
      cv::Mat expected, blurred;
      cv::GaussianBlur(image, expected, cv::Size(), sigma, sigma, cv::BORDER_REPLICATE);
      GaussianBlur(image, sigma, &blurred);
      ASSERT_EQ(blurred.size(), image.size());
      ASSERT_EQ(blurred.type(), CV_32F);
      EXPECT_LT(cv::norm(blurred, expected, cv::NORM_INF), 1e-6)
          << size.width << "x" << size.height << " sigma " << sigma;
    }
  }
}

// A view is blurred as an image of its own (OpenCV's BORDER_ISOLATED): nothing outside it is
// read.
TEST(GaussianBlur, BlursAViewOfALargerImageAsAnImageOfItsOwn) {
  const cv::Mat image = RandomImage(200, 100, 7);
  const cv::Mat view = image(cv::Rect(13, 9, 150, 70));
  cv::Mat expected, blurred;
  cv::GaussianBlur(view.clone(), expected, cv::Size(), 2.0, 2.0, cv::BORDER_REPLICATE);
  GaussianBlur(view, 2.0, &blurred);
  EXPECT_LT(cv::norm(blurred, expected, cv::NORM_INF), 1e-6);
}

TEST(GaussianBlur, SpreadsAnImpulseAsTheKernelsOuterProduct) {
  cv::Mat impulse = cv::Mat::zeros(41, 45, CV_32F);
  impulse.at<float>(20, 22) = 1.0f;
  cv::Mat blurred;
  GaussianBlur(impulse, 1.6, &blurred);
  const std::vector<float> half = GaussianHalfKernel(1.6);
  const int radius = static_cast<int>(half.size()) - 1;
  for (int dy = -radius; dy <= radius; ++dy) {
    for (int dx = -radius; dx <= radius; ++dx) {
      EXPECT_NEAR(blurred.at<float>(20 + dy, 22 + dx), half[std::abs(dy)] * half[std::abs(dx)],
                  1e-7f);
    }
  }
  EXPECT_NEAR(cv::sum(blurred)[0], 1.0, 1e-5);
}

// Rows are reported once each, in order, already holding their final values (37 rows: the
// last step of four has rows past the end, which are not reported).
TEST(GaussianBlur, ReportsEachRowInOrderOnceItIsWritten) {
  const cv::Mat image = RandomImage(50, 37, 11);
  cv::Mat blurred;
  std::vector<int> reported;
  cv::Mat seen(image.size(), CV_32F, cv::Scalar(-1));
  GaussianBlur(image, 1.6, &blurred, [&](int row) {
    reported.push_back(row);
    blurred.row(row).copyTo(seen.row(row));
  });
  std::vector<int> expected(image.rows);
  std::iota(expected.begin(), expected.end(), 0);
  EXPECT_EQ(reported, expected);
  EXPECT_EQ(cv::norm(seen, blurred, cv::NORM_INF), 0.0);
}

// Every window, at the borders and inside, narrow and wide, gets exactly the full blur's
// floats, and nothing outside it is written.
TEST(WindowedGaussianBlur, WritesTheFullBlursFloatsInTheWindowAlone) {
  const std::vector<cv::Size> sizes = {{640, 480}, {97, 33}, {31, 64}, {17, 7}, {5, 3}};
  uint64_t seed = 21;
  for (const cv::Size& size : sizes) {
    const cv::Mat image = RandomImage(size.width, size.height, seed++);
    cv::RNG rng(seed++);
    for (const double sigma : {0.3, 1.23, 3.09}) {
      cv::Mat full;
      GaussianBlur(image, sigma, &full);
      WindowedGaussianBlur windowed(image, sigma);
      for (int trial = 0; trial < 20; ++trial) {
        // 3 x 3 windows (what the native SIFT asks for), then any.
        const int width = trial < 10 ? std::min(3, size.width) : rng.uniform(1, size.width + 1);
        const int height = trial < 10 ? std::min(3, size.height) : rng.uniform(1, size.height + 1);
        const cv::Rect window(rng.uniform(0, size.width - width + 1),
                              rng.uniform(0, size.height - height + 1), width, height);
        cv::Mat blurred(image.size(), CV_32F, cv::Scalar(-1));
        std::vector<int> reported;
        windowed.Blur(window, &blurred, [&](int row) { reported.push_back(row); });
        cv::Mat expected(image.size(), CV_32F, cv::Scalar(-1));
        full(window).copyTo(expected(window));
        ASSERT_EQ(cv::norm(blurred, expected, cv::NORM_INF), 0.0)
            << size.width << "x" << size.height << " sigma " << sigma << " window " << window;
        std::vector<int> rows(window.height);
        std::iota(rows.begin(), rows.end(), window.y);
        EXPECT_EQ(reported, rows);
      }
    }
  }
}

// AVX-512 gives the build's vectors' floats bit for bit: the full image and windows, widths
// that leave AVX-512 blocks, AVX2 blocks and single columns, kernels of 1 to 41 taps.
TEST(GaussianBlur, TheWidestVectorsGiveTheBuildsFloats) {
  if (!BlurHasAvx512()) GTEST_SKIP() << "this CPU has no AVX-512: both are the build's vectors";
  const std::vector<cv::Size> sizes = {{1280, 40}, {640, 48}, {97, 33}, {200, 9}, {17, 7}};
  uint64_t seed = 41;
  for (const cv::Size& size : sizes) {
    const cv::Mat image = RandomImage(size.width, size.height, seed++);
    cv::RNG rng(seed++);
    for (const double sigma : {0.1, 0.3, 1.23, 3.09, 5.0}) {
      cv::Mat build, widest;
      GaussianBlur(image, sigma, &build, nullptr, BlurVectors::kBuild);
      GaussianBlur(image, sigma, &widest, nullptr, BlurVectors::kWidest);
      ASSERT_EQ(cv::norm(build, widest, cv::NORM_INF), 0.0)
          << size.width << "x" << size.height << " sigma " << sigma;
      WindowedGaussianBlur build_window(image, sigma, BlurVectors::kBuild);
      WindowedGaussianBlur widest_window(image, sigma, BlurVectors::kWidest);
      for (int trial = 0; trial < 10; ++trial) {
        const int width = rng.uniform(1, size.width + 1);
        const int height = rng.uniform(1, size.height + 1);
        const cv::Rect window(rng.uniform(0, size.width - width + 1),
                              rng.uniform(0, size.height - height + 1), width, height);
        cv::Mat a(image.size(), CV_32F, cv::Scalar(-1)), b(image.size(), CV_32F, cv::Scalar(-1));
        build_window.Blur(window, &a);
        widest_window.Blur(window, &b);
        ASSERT_EQ(cv::norm(a, b, cv::NORM_INF), 0.0)
            << size.width << "x" << size.height << " sigma " << sigma << " window " << window;
      }
    }
  }
}

// Into a buffer of the window's own: the same floats, rows out_stride apart.
TEST(WindowedGaussianBlur, WritesAWindowIntoABufferOfItsOwn) {
  const cv::Mat image = RandomImage(150, 90, 31);
  cv::Mat full;
  GaussianBlur(image, 3.09, &full);
  WindowedGaussianBlur windowed(image, 3.09);
  for (const cv::Rect window : {cv::Rect(0, 0, 3, 3), cv::Rect(70, 40, 3, 3),
                                cv::Rect(147, 87, 3, 3), cv::Rect(10, 5, 40, 9)}) {
    constexpr size_t kStride = 41;
    std::vector<float> out(kStride * window.height + 1, -1.0f);
    windowed.Blur(window, out.data(), kStride);
    for (int y = 0; y < window.height; ++y) {
      for (int x = 0; x < window.width; ++x) {
        ASSERT_EQ(out[y * kStride + x], full.at<float>(window.y + y, window.x + x)) << window;
      }
      for (size_t x = window.width; x < kStride; ++x) EXPECT_EQ(out[y * kStride + x], -1.0f);
    }
  }
}

TEST(WindowedGaussianBlur, RejectsWindowsOutsideTheImageAndItsInputAsOutput) {
  cv::Mat image = RandomImage(20, 10, 5);
  WindowedGaussianBlur windowed(image, 1.6);
  cv::Mat blurred(image.size(), CV_32F);
  EXPECT_THROW(windowed.Blur(cv::Rect(18, 0, 3, 3), &blurred), CheckError);
  EXPECT_THROW(windowed.Blur(cv::Rect(0, -1, 3, 3), &blurred), CheckError);
  EXPECT_THROW(windowed.Blur(cv::Rect(0, 0, 3, 3), &image), CheckError);
  EXPECT_THROW(windowed.Blur(cv::Rect(0, 0, 3, 3), image.ptr<float>(4), 3), CheckError);
  std::vector<float> narrow(9);
  EXPECT_THROW(windowed.Blur(cv::Rect(0, 0, 3, 3), narrow.data(), 2), CheckError);
  cv::Mat small(5, 5, CV_32F);
  EXPECT_THROW(windowed.Blur(cv::Rect(0, 0, 3, 3), &small), CheckError);
}

TEST(GaussianBlur, RejectsItsInputAsOutputAndOtherTypes) {
  cv::Mat image = RandomImage(20, 10, 3);
  EXPECT_THROW(GaussianBlur(image, 1.6, &image), CheckError);
  cv::Mat bytes(10, 20, CV_8U, cv::Scalar(5)), blurred;
  EXPECT_THROW(GaussianBlur(bytes, 1.6, &blurred), CheckError);
}

}  // namespace
}  // namespace parallax
