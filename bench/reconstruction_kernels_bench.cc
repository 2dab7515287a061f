// The mapper's hot kernels: linear triangulation of one point from two and from several views,
// and one bundle-adjustment iteration on a synthetic problem of templeRing's size (47 images,
// ~6500 points, ~30000 observations: tracks of 4-5 consecutive images on a ring).
//
//   build-X/bench/reconstruction_kernels_bench [--benchmark_filter=...]

#include <benchmark/benchmark.h>

#include <algorithm>
#include <vector>

#include "parallax/estimators/bundle_adjustment.h"
#include "parallax/geometry/triangulation.h"
#include "parallax/math/random.h"
#include "parallax/scene/synthetic_dataset.h"

namespace parallax {
namespace {

// Views on a ring around the origin looking at it, and random points near the origin seen
// by all of them (normalised image coordinates with 1e-3 noise, about 1 px).
struct TriangulationProblem {
  std::vector<Matrix3x4d> cams_from_world;
  std::vector<std::vector<Eigen::Vector2d>> points;  // Per 3D point, one per view.
};

TriangulationProblem MakeTriangulationProblem(int num_views, int num_points) {
  TriangulationProblem problem;
  for (int view = 0; view < num_views; ++view) {
    const double angle = 0.15 * view;
    const Eigen::Vector3d center(4.0 * std::sin(angle), 0.0, -4.0 * std::cos(angle));
    // Rotation whose z axis points from the centre to the origin.
    const Eigen::Matrix3d cam_from_world =
        Eigen::AngleAxisd(-angle, Eigen::Vector3d::UnitY()).toRotationMatrix();
    Matrix3x4d projection;
    projection << cam_from_world, -cam_from_world * center;
    problem.cams_from_world.push_back(projection);
  }
  for (int i = 0; i < num_points; ++i) {
    const Eigen::Vector3d point(RandomUniformReal(-1, 1), RandomUniformReal(-1, 1),
                                RandomUniformReal(-1, 1));
    std::vector<Eigen::Vector2d> observations;
    for (const Matrix3x4d& projection : problem.cams_from_world) {
      observations.push_back((projection * point.homogeneous()).hnormalized() +
                             Eigen::Vector2d(RandomGaussian(0, 1e-3), RandomGaussian(0, 1e-3)));
    }
    problem.points.push_back(std::move(observations));
  }
  return problem;
}

void BM_TriangulatePoint(benchmark::State& state) {
  const TriangulationProblem problem = MakeTriangulationProblem(2, 1024);
  size_t k = 0, num_found = 0;
  for (auto _ : state) {
    const auto& observations = problem.points[k++ % problem.points.size()];
    const auto point3D = TriangulatePoint(problem.cams_from_world[0], problem.cams_from_world[1],
                                          observations[0], observations[1]);
    num_found += point3D.has_value();
    benchmark::DoNotOptimize(point3D);
  }
  state.counters["found"] =
      static_cast<double>(num_found) / static_cast<double>(state.iterations());
}
BENCHMARK(BM_TriangulatePoint);

// Arg: number of views.
void BM_TriangulateMultiViewPoint(benchmark::State& state) {
  const TriangulationProblem problem =
      MakeTriangulationProblem(static_cast<int>(state.range(0)), 1024);
  size_t k = 0;
  for (auto _ : state) {
    const auto point3D = TriangulateMultiViewPoint(problem.cams_from_world,
                                                   problem.points[k++ % problem.points.size()]);
    benchmark::DoNotOptimize(point3D);
  }
}
BENCHMARK(BM_TriangulateMultiViewPoint)->ArgName("views")->Arg(3)->Arg(5)->Arg(10);

// templeRing-sized: 47 images on a ring, 6500 points, each kept in 4-5 consecutive images
// (random track length) with 0.5 px noise, then points moved by ~1 % of the scene and poses
// by ~0.1 degree so that the iteration has work to do.
const Reconstruction& TempleSizedProblem() {
  static const Reconstruction problem = [] {
    SyntheticDatasetOptions options;
    options.num_images = 47;
    options.num_points3D = 6500;
    options.width = 640;
    options.height = 480;
    options.focal_length = 1520.0;
    options.camera_distance = 5.0;
    options.scene_radius = 0.5;
    options.point2D_noise_stddev = 0.5;
    options.seed = 7;
    Reconstruction reconstruction;
    SynthesizeDataset(options, &reconstruction);
    const std::vector<image_t> image_ids = reconstruction.RegImageIds();
    std::vector<point3D_t> point_ids;
    for (const auto& [point3D_id, point] : reconstruction.Points3D())
      point_ids.push_back(point3D_id);
    for (const point3D_t point3D_id : point_ids) {
      // Keep a window of consecutive images around the ring, as a real track would.
      const auto& track = reconstruction.GetPoint3D(point3D_id).track.elements;
      const size_t length = static_cast<size_t>(RandomUniformInteger(4, 5));
      const auto first = static_cast<size_t>(RandomUniformInteger(0, 46));
      std::vector<TrackElement> removed;
      for (const TrackElement& element : track) {
        const size_t position = (element.image_id - image_ids.front() + 47 - first) % 47;
        if (position >= length) removed.push_back(element);
      }
      if (track.size() - removed.size() < 2) {
        reconstruction.DeletePoint3D(point3D_id);
        continue;
      }
      for (const TrackElement& element : removed) {
        reconstruction.DeleteObservation(element.image_id, element.point2D_idx);
      }
    }
    for (const auto& [point3D_id, point] : reconstruction.Points3D()) {
      reconstruction.GetPoint3D(point3D_id).xyz += Eigen::Vector3d(
          RandomGaussian(0, 0.005), RandomGaussian(0, 0.005), RandomGaussian(0, 0.005));
    }
    for (const image_t image_id : image_ids) {
      Rigid3d& pose = reconstruction.GetImage(image_id).cam_from_world;
      const Eigen::Vector3d axis =
          Eigen::Vector3d(RandomGaussian(0, 1), RandomGaussian(0, 1), RandomGaussian(0, 1))
              .normalized();
      pose.rotation =
          (pose.rotation * Eigen::Quaterniond(Eigen::AngleAxisd(0.002, axis))).normalized();
    }
    return reconstruction;
  }();
  return problem;
}

// Args: threads, solver (0: Parallax's dense Schur LM, 1: Ceres), side by side.
void BM_BundleAdjustmentIteration(benchmark::State& state) {
  const Reconstruction& problem = TempleSizedProblem();
  BundleAdjustmentOptions options;
  options.solver =
      state.range(1) == 0 ? BundleAdjustmentSolver::kDenseSchur : BundleAdjustmentSolver::kCeres;
  options.max_num_iterations = 1;
  options.num_threads = static_cast<int>(state.range(0));
  BundleAdjustmentConfig config;
  const std::vector<image_t> image_ids = problem.RegImageIds();
  for (const image_t image_id : image_ids) config.AddImage(image_id);
  // Gauge: the first pose and one coordinate of the second.
  config.SetConstantPose(image_ids[0]);
  config.constant_translation_coordinates.insert({image_ids[1], 0});
  BundleAdjustmentSummary summary;
  for (auto _ : state) {
    state.PauseTiming();
    Reconstruction reconstruction = problem;
    state.ResumeTiming();
    summary = BundleAdjust(options, config, &reconstruction);
    benchmark::DoNotOptimize(summary.final_cost);
  }
  state.counters["images"] = static_cast<double>(problem.NumRegImages());
  state.counters["points"] = static_cast<double>(problem.NumPoints3D());
  state.counters["observations"] = static_cast<double>(problem.NumObservations());
  state.SetLabel(summary.solver);
  state.counters["cost_ratio"] =
      summary.initial_cost > 0 ? summary.final_cost / summary.initial_cost : 0;
}
BENCHMARK(BM_BundleAdjustmentIteration)
    ->ArgNames({"threads", "ceres"})
    ->ArgsProduct({{1, 2}, {0, 1}})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

}  // namespace
}  // namespace parallax
