// Two-view geometric verification (LO-RANSAC over E, F and H, as the matching stage runs it)
// per image pair, and the minimal solvers it is made of.
//
//   build-X/bench/two_view_geometry_bench [--benchmark_filter=...]
//
// Pairs: SIFT features of templeRing with its known calibration, matched with the default
// options: templeR0001/templeR0002 (neighbours, about 430 matches, almost all inliers) and
// templeR0001/templeR0022 (no overlap, about 25 chance matches: the pair RANSAC must reject,
// the common case of exhaustive matching). When the data is missing a synthetic scene of the
// same sizes stands in. Each iteration reseeds the generator, as the matching stage does.

#include <benchmark/benchmark.h>

#include <cstdio>
#include <string>
#include <vector>

#include "parallax/estimators/solvers/essential_matrix.h"
#include "parallax/estimators/solvers/fundamental_matrix.h"
#include "parallax/estimators/solvers/homography_matrix.h"
#include "parallax/estimators/two_view_geometry.h"
#include "parallax/feature/matcher.h"
#include "parallax/feature/sift.h"
#include "parallax/image/image_reader.h"
#include "parallax/math/random.h"
#include "parallax/util/file.h"

namespace parallax {
namespace {

struct PairData {
  std::string name;
  Camera camera;
  std::vector<Eigen::Vector2d> points1, points2;
  FeatureMatches matches;
};

Camera TempleCamera() {
  Camera camera = Camera::Create(1, CameraModelId::kPinhole, 1520.4, 640, 480);
  camera.params = {1520.4, 1525.9, 302.32, 246.87};
  camera.has_prior_focal_length = true;
  return camera;
}

// Keypoints (as stored: pixel centres at +0.5) and descriptors of one templeRing image.
bool TempleFeatures(int number, std::vector<Eigen::Vector2d>* points,
                    MatchableDescriptors* descriptors) {
  const std::filesystem::path dir = DataRoot() / "templeRing" / "images";
  char name[64];
  std::snprintf(name, sizeof(name), "templeR%04d.png", number);
  if (!std::filesystem::exists(dir / name)) return false;
  const auto extractor = CreateSiftExtractor(SiftExtractionOptions());
  FeatureKeypoints keypoints;
  FeatureDescriptors raw;
  extractor->Extract(ReadBitmap(dir / name).gray, &keypoints, &raw);
  points->clear();
  for (const FeatureKeypoint& keypoint : keypoints) points->emplace_back(keypoint.x, keypoint.y);
  *descriptors = PrepareDescriptors(raw);
  return true;
}

// A synthetic stand-in: `num_inliers` projections of random points seen by two cameras
// 0.3 rad apart, plus `num_outliers` random matches.
PairData SyntheticPair(const std::string& name, int num_inliers, int num_outliers) {
  PairData pair;
  pair.name = name + " (synthetic: no templeRing data)";
  pair.camera = TempleCamera();
  const Rigid3d cam2_from_cam1(Eigen::Quaterniond(Eigen::AngleAxisd(0.3, Eigen::Vector3d::UnitY())),
                               Eigen::Vector3d(-1, 0, 0.1));
  for (int i = 0; i < num_inliers + num_outliers; ++i) {
    const Eigen::Vector3d point(RandomUniformReal(-1, 1), RandomUniformReal(-1, 1),
                                RandomUniformReal(5, 8));
    pair.points1.push_back(pair.camera.ImgFromCam(point));
    pair.points2.push_back(
        i < num_inliers ? pair.camera.ImgFromCam(cam2_from_cam1 * point)
                        : Eigen::Vector2d(RandomUniformReal(0, 640), RandomUniformReal(0, 480)));
    pair.matches.push_back({static_cast<point2D_t>(i), static_cast<point2D_t>(i)});
  }
  return pair;
}

PairData TemplePair(int number1, int number2, int synthetic_inliers, int synthetic_outliers) {
  char name[64];
  std::snprintf(name, sizeof(name), "templeR%04d/templeR%04d", number1, number2);
  PairData pair;
  MatchableDescriptors descriptors1, descriptors2;
  if (!TempleFeatures(number1, &pair.points1, &descriptors1) ||
      !TempleFeatures(number2, &pair.points2, &descriptors2)) {
    return SyntheticPair(name, synthetic_inliers, synthetic_outliers);
  }
  FeatureMatchingOptions options;
  options.num_threads = 1;
  pair.matches = MatchDescriptors(descriptors1, descriptors2, options);
  pair.name = name;
  pair.camera = TempleCamera();
  return pair;
}

// 0: overlapping neighbours; 1: no overlap.
const PairData& Pair(int which) {
  static const std::vector<PairData> pairs = {TemplePair(1, 2, 420, 10), TemplePair(1, 22, 5, 20)};
  return pairs.at(which);
}

void BM_TwoViewGeometry(benchmark::State& state) {
  const PairData& pair = Pair(static_cast<int>(state.range(0)));
  const TwoViewGeometryOptions options;
  TwoViewGeometry geometry;
  for (auto _ : state) {
    SetPRNGSeed(1);
    geometry = EstimateTwoViewGeometry(pair.camera, pair.points1, pair.camera, pair.points2,
                                       pair.matches, options);
    benchmark::DoNotOptimize(geometry.inlier_matches.data());
  }
  state.counters["matches"] = static_cast<double>(pair.matches.size());
  state.counters["inliers"] = static_cast<double>(geometry.inlier_matches.size());
  state.counters["config"] = geometry.config;
  state.SetLabel(pair.name);
}
BENCHMARK(BM_TwoViewGeometry)->ArgName("pair")->DenseRange(0, 1)->Unit(benchmark::kMicrosecond);

// Minimal samples of the overlapping pair (pixels for F and H, normalised for E).
template <int kSampleSize>
std::vector<std::pair<std::vector<Eigen::Vector2d>, std::vector<Eigen::Vector2d>>> Samples(
    bool normalized) {
  const PairData& pair = Pair(0);
  std::vector<std::pair<std::vector<Eigen::Vector2d>, std::vector<Eigen::Vector2d>>> samples(64);
  for (auto& [sample1, sample2] : samples) {
    for (int i = 0; i < kSampleSize; ++i) {
      const FeatureMatch& match = pair.matches[static_cast<size_t>(
          RandomUniformInteger(0, static_cast<int64_t>(pair.matches.size()) - 1))];
      const Eigen::Vector2d& point1 = pair.points1[match.point2D_idx1];
      const Eigen::Vector2d& point2 = pair.points2[match.point2D_idx2];
      sample1.push_back(normalized ? pair.camera.CamFromImg(point1) : point1);
      sample2.push_back(normalized ? pair.camera.CamFromImg(point2) : point2);
    }
  }
  return samples;
}

template <int kSampleSize,
          void (*Solver)(const std::vector<Eigen::Vector2d>&, const std::vector<Eigen::Vector2d>&,
                         std::vector<Eigen::Matrix3d>*)>
void BM_Solver(benchmark::State& state) {
  // Arg: 1 for normalised coordinates (E), 0 for pixels.
  const auto samples = Samples<kSampleSize>(state.range(0) != 0);
  std::vector<Eigen::Matrix3d> models;
  size_t k = 0, num_models = 0;
  for (auto _ : state) {
    const auto& [sample1, sample2] = samples[k++ % samples.size()];
    Solver(sample1, sample2, &models);
    num_models += models.size();
    benchmark::DoNotOptimize(models.data());
  }
  state.counters["models_per_call"] =
      static_cast<double>(num_models) / static_cast<double>(state.iterations());
}
BENCHMARK_TEMPLATE(BM_Solver, 7, EstimateFundamentalMatrixSevenPoint)
    ->Name("BM_FundamentalSevenPoint")
    ->Arg(0);
BENCHMARK_TEMPLATE(BM_Solver, 5, EstimateEssentialMatrixFivePoint)
    ->Name("BM_EssentialFivePoint")
    ->Arg(1);
BENCHMARK_TEMPLATE(BM_Solver, 4, EstimateHomographyMatrix)->Name("BM_HomographyFourPoint")->Arg(0);
BENCHMARK_TEMPLATE(BM_Solver, 100, EstimateFundamentalMatrixEightPoint)
    ->Name("BM_FundamentalEightPoint100")
    ->Arg(0);

}  // namespace
}  // namespace parallax
