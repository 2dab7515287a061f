// Quality of the two SIFT implementations (issue 21: a native SIFT must match OpenCV's):
// each image is warped by known homographies (rotation, zoom, tilt), and for each warp the
// features of the original and of the warped copy are compared (Mikolajczyk & Schmid's
// protocol, simplified):
//   repeatability   frames of one image with a frame of the other within 1.5 px and a
//                   consistent scale, over the frames both images can see;
//   matching score  correct matches (the pipeline's matcher: ratio 0.8, cross-check), within
//                   3 px of where the homography puts them, over the frames both images see
//                   (repeatability counts places: a frame per orientation counts once);
//   precision       correct matches over all matches.
//
//   sift_quality IMAGE...      (e.g. $PARALLAX_DATA/templeRing/images/templeR000[1-5].png)
//
// Prints one markdown table: the mean over the images, per warp and implementation. Not a
// Google Benchmark: it measures quality (bench/run.sh times extraction in the pipeline).

#include <cmath>
#include <iomanip>
#include <iostream>
#include <map>
#include <opencv2/imgproc.hpp>
#include <set>
#include <string>
#include <tuple>
#include <vector>

#include "bench_tool_main.h"
#include "parallax/feature/matcher.h"
#include "parallax/feature/sift.h"
#include "parallax/image/image_reader.h"

namespace parallax {
namespace {

struct Warp {
  std::string name;
  double rotation_degrees = 0, zoom = 1, tilt = 0;  // tilt: perspective term, per pixel
};

// The homography in OpenCV's pixel convention (centres at integers), about the image centre.
cv::Matx33d WarpHomography(const Warp& warp, const cv::Size& size) {
  const double cx = 0.5 * (size.width - 1), cy = 0.5 * (size.height - 1);
  const double angle = warp.rotation_degrees * CV_PI / 180.0;
  const cv::Matx33d to_centre(1, 0, -cx, 0, 1, -cy, 0, 0, 1);
  const cv::Matx33d back(1, 0, cx, 0, 1, cy, 0, 0, 1);
  const cv::Matx33d rotate_zoom(warp.zoom * std::cos(angle), -warp.zoom * std::sin(angle), 0,
                                warp.zoom * std::sin(angle), warp.zoom * std::cos(angle), 0, 0, 0,
                                1);
  const cv::Matx33d tilt(1, 0, 0, 0, 1, 0, warp.tilt, 0, 1);
  return back * tilt * rotate_zoom * to_centre;
}

// A keypoint (COLMAP convention, centres at +0.5) through H (OpenCV convention), and the
// local scale change of H there.
cv::Point2d Apply(const cv::Matx33d& h, double x, double y, double* scale = nullptr) {
  const cv::Vec3d p = h * cv::Vec3d(x - 0.5, y - 0.5, 1.0);
  if (scale != nullptr) {
    const double w = p[2];
    const double a = (h(0, 0) - p[0] / w * h(2, 0)) / w, b = (h(0, 1) - p[0] / w * h(2, 1)) / w;
    const double c = (h(1, 0) - p[1] / w * h(2, 0)) / w, d = (h(1, 1) - p[1] / w * h(2, 1)) / w;
    *scale = std::sqrt(std::abs(a * d - b * c));
  }
  return {p[0] / p[2] + 0.5, p[1] / p[2] + 0.5};
}

bool Inside(const cv::Point2d& p, const cv::Size& size, double margin) {
  return p.x >= margin && p.y >= margin && p.x <= size.width - margin &&
         p.y <= size.height - margin;
}

struct Scores {
  double repeatability = 0, matching_score = 0, precision = 0;
  double keypoints = 0;
};

Scores Compare(const cv::Mat& image, const Warp& warp, const SiftExtractionOptions& options) {
  const cv::Matx33d h = WarpHomography(warp, image.size());
  cv::Mat warped;
  cv::warpPerspective(image, warped, h, image.size(), cv::INTER_LINEAR, cv::BORDER_CONSTANT,
                      cv::Scalar(0));
  const auto extractor = CreateSiftExtractor(options);
  FeatureKeypoints keypoints1, keypoints2;
  FeatureDescriptors descriptors1, descriptors2;
  extractor->Extract(image, &keypoints1, &descriptors1);
  extractor->Extract(warped, &keypoints2, &descriptors2);
  Scores scores;
  scores.keypoints = 0.5 * (keypoints1.size() + keypoints2.size());

  // Frames both images see (away from the warped border); a place with several orientations
  // counts once.
  constexpr double kMargin = 8.0;
  const cv::Matx33d h_inverse = h.inv();
  std::vector<int> seen1, seen2;
  std::set<std::tuple<float, float, float>> places1, places2;
  for (size_t i = 0; i < keypoints1.size(); ++i) {
    if (Inside(Apply(h, keypoints1[i].x, keypoints1[i].y), image.size(), kMargin)) {
      seen1.push_back(static_cast<int>(i));
      places1.insert({keypoints1[i].x, keypoints1[i].y, keypoints1[i].ComputeScale()});
    }
  }
  for (size_t j = 0; j < keypoints2.size(); ++j) {
    const FeatureKeypoint& k = keypoints2[j];
    if (Inside(Apply(h_inverse, k.x, k.y), image.size(), kMargin) &&
        Inside({k.x, k.y}, image.size(), kMargin)) {
      seen2.push_back(static_cast<int>(j));
      places2.insert({k.x, k.y, k.ComputeScale()});
    }
  }
  const double common = static_cast<double>(std::min(places1.size(), places2.size()));
  if (common == 0) return scores;

  std::set<std::tuple<float, float, float>> repeated;
  for (const int i : seen1) {
    const FeatureKeypoint& k1 = keypoints1[i];
    double scale_change = 1;
    const cv::Point2d p = Apply(h, k1.x, k1.y, &scale_change);
    for (const int j : seen2) {
      const FeatureKeypoint& k2 = keypoints2[j];
      const double ratio = k2.ComputeScale() / (k1.ComputeScale() * scale_change);
      if (std::hypot(k2.x - p.x, k2.y - p.y) < 1.5 && ratio > 1 / 1.5 && ratio < 1.5) {
        repeated.insert({k1.x, k1.y, k1.ComputeScale()});
        break;
      }
    }
  }
  scores.repeatability = repeated.size() / common;

  const FeatureMatches matches = MatchDescriptors(
      PrepareDescriptors(descriptors1), PrepareDescriptors(descriptors2), FeatureMatchingOptions());
  int correct = 0;
  for (const FeatureMatch& match : matches) {
    const FeatureKeypoint& k1 = keypoints1[match.point2D_idx1];
    const FeatureKeypoint& k2 = keypoints2[match.point2D_idx2];
    const cv::Point2d p = Apply(h, k1.x, k1.y);
    if (std::hypot(k2.x - p.x, k2.y - p.y) < 3.0) ++correct;
  }
  scores.matching_score = correct / static_cast<double>(std::min(seen1.size(), seen2.size()));
  scores.precision = matches.empty() ? 0.0 : static_cast<double>(correct) / matches.size();
  return scores;
}

int Run(int argc, char** argv) {
  if (argc < 2) {
    std::cerr << "usage: sift_quality IMAGE...\n";
    return 2;
  }
  const std::vector<Warp> warps = {{"rotation 30°", 30, 1, 0},
                                   {"zoom 0.6", 0, 0.6, 0},
                                   {"rotation 45° + zoom 0.8", 45, 0.8, 0},
                                   {"tilt", 10, 0.9, 4e-4}};
  const std::vector<SiftImplementation> implementations = {SiftImplementation::kNative,
                                                           SiftImplementation::kOpenCv};
  std::map<std::pair<int, int>, Scores> sums;  // (warp, implementation)
  for (int a = 1; a < argc; ++a) {
    const cv::Mat gray = ReadBitmap(argv[a]).gray;
    for (size_t w = 0; w < warps.size(); ++w) {
      for (size_t m = 0; m < implementations.size(); ++m) {
        SiftExtractionOptions options;
        options.contrast_threshold = 0.02;  // The pipeline's (extraction_stage.h).
        options.implementation = implementations[m];
        const Scores scores = Compare(gray, warps[w], options);
        Scores& sum = sums[{static_cast<int>(w), static_cast<int>(m)}];
        sum.repeatability += scores.repeatability;
        sum.matching_score += scores.matching_score;
        sum.precision += scores.precision;
        sum.keypoints += scores.keypoints;
      }
    }
  }
  const double n = argc - 1;
  std::cout << "| warp | SIFT | keypoints | repeatability | matching score | precision |\n"
               "|---|---|---:|---:|---:|---:|\n"
            << std::fixed;
  for (size_t w = 0; w < warps.size(); ++w) {
    for (size_t m = 0; m < implementations.size(); ++m) {
      const Scores& sum = sums[{static_cast<int>(w), static_cast<int>(m)}];
      std::cout << "| " << warps[w].name << " | " << SiftImplementationName(implementations[m])
                << " | " << std::setprecision(0) << sum.keypoints / n << " | "
                << std::setprecision(3) << sum.repeatability / n << " | " << sum.matching_score / n
                << " | " << sum.precision / n << " |\n";
    }
  }
  return 0;
}

}  // namespace
}  // namespace parallax

int main(int argc, char** argv) {
  return parallax::RunBenchTool("sift_quality", parallax::Run, argc, argv);
}
