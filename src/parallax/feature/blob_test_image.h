#pragma once

// For tests only: the images the SIFT tests detect in.

#include <algorithm>
#include <cmath>
#include <opencv2/core.hpp>

#include "parallax/math/random.h"

namespace parallax::test {

// Gray image of random Gaussian blobs (sigma 1.5 to `max_sigma` px, contrast up to +-90 on
// 128) from the seeded generator: blob-like structure at every scale is what the
// difference-of-Gaussians detector responds to.
inline cv::Mat BlobTexturedImage(int width, int height, int num_blobs, double max_sigma = 10.0) {
  cv::Mat image(height, width, CV_32F, cv::Scalar(128.0f));
  for (int b = 0; b < num_blobs; ++b) {
    const double cx = RandomUniformReal(0, width), cy = RandomUniformReal(0, height);
    const double sigma = RandomUniformReal(1.5, max_sigma);
    const double amplitude = RandomUniformReal(-90, 90);
    const int radius = static_cast<int>(3 * sigma) + 1;
    for (int y = std::max(0, static_cast<int>(cy) - radius);
         y < std::min(height, static_cast<int>(cy) + radius + 1); ++y) {
      for (int x = std::max(0, static_cast<int>(cx) - radius);
           x < std::min(width, static_cast<int>(cx) + radius + 1); ++x) {
        const double r2 = (x - cx) * (x - cx) + (y - cy) * (y - cy);
        image.at<float>(y, x) +=
            static_cast<float>(amplitude * std::exp(-0.5 * r2 / (sigma * sigma)));
      }
    }
  }
  cv::Mat image8;
  image.convertTo(image8, CV_8U);
  return image8;
}

}  // namespace parallax::test
