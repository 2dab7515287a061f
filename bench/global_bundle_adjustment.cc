// One global bundle adjustment of a real model with each solver, from the same start: the
// model's poses turned by ~0.1 degree and its points moved by ~0.1 % of the scene, so that
// every solver has the same work to do. Prints time, iterations and cost per solver.
//
//   build/bench/global_bundle_adjustment MODEL_DIR [SOLVER...]   (default: all solvers)
//
// SOLVER is a --ba-solver name (dense-schur, sparse-schur, ceres, ceres-iterative). MODEL_DIR is a
// COLMAP model, e.g. OUT/sparse/0 of `parallax mapper` on `synth --layout aerial`.
// PARALLAX_CG_TOLERANCE sets the sparse solver's relative CG tolerance;
// PARALLAX_BA_REFINE_INTRINSICS=1 frees focal length and distortion.
#include <cstdio>
#include <cstdlib>
#include <iostream>
#include <string>
#include <vector>

#include "bench_tool_main.h"
#include "parallax/estimators/bundle_adjustment.h"
#include "parallax/math/random.h"
#include "parallax/scene/colmap_io.h"

namespace parallax {
namespace {

double SceneExtent(const Reconstruction& reconstruction) {
  Eigen::Vector3d min = Eigen::Vector3d::Constant(1e300), max = -min;
  for (const image_t image_id : reconstruction.RegImageIds()) {
    const Eigen::Vector3d center = reconstruction.GetImage(image_id).ProjectionCenter();
    min = min.cwiseMin(center);
    max = max.cwiseMax(center);
  }
  return (max - min).norm();
}

Reconstruction Perturbed(const Reconstruction& model) {
  SetPRNGSeed(7);
  Reconstruction perturbed = model;
  const double sigma = 1e-3 * SceneExtent(model);
  for (const auto& [point3D_id, point] : model.Points3D()) {
    perturbed.GetPoint3D(point3D_id).xyz += Eigen::Vector3d(
        RandomGaussian(0, sigma), RandomGaussian(0, sigma), RandomGaussian(0, sigma));
  }
  for (const image_t image_id : model.RegImageIds()) {
    Rigid3d& pose = perturbed.GetImage(image_id).cam_from_world;
    const Eigen::Vector3d axis =
        Eigen::Vector3d(RandomGaussian(0, 1), RandomGaussian(0, 1), RandomGaussian(0, 1))
            .normalized();
    pose.rotation =
        (pose.rotation * Eigen::Quaterniond(Eigen::AngleAxisd(0.002, axis))).normalized();
  }
  return perturbed;
}

int Run(int argc, char** argv) {
  if (argc < 2) {
    std::cerr << "usage: global_bundle_adjustment MODEL_DIR [SOLVER...]\n";
    return 2;
  }
  const Reconstruction model = ReadReconstruction(argv[1]);
  std::vector<std::string> solvers(argv + 2, argv + argc);
  if (solvers.empty()) solvers = {"dense-schur", "sparse-schur", "ceres", "ceres-iterative"};
  const Reconstruction start = Perturbed(model);
  std::printf("%zu images, %zu points, %zu observations\n", model.NumRegImages(),
              model.NumPoints3D(), model.NumObservations());
  std::printf(
      "| solver | seconds | iterations | s/iteration | CG iterations | initial cost | final cost "
      "|\n");
  std::printf("|---|---:|---:|---:|---:|---:|---:|\n");
  for (const std::string& name : solvers) {
    const auto solver = BundleAdjustmentSolverFromName(name);
    if (!solver) {
      std::cerr << "global_bundle_adjustment: unknown solver '" << name << "'\n";
      return 2;
    }
    BundleAdjustmentOptions options;
    options.solver = *solver;
    options.max_dense_schur_variables = 1 << 30;
    options.loss_function = LossFunctionType::kTrivial;
    options.max_num_iterations = 20;
    if (const char* tolerance = std::getenv("PARALLAX_CG_TOLERANCE")) {
      options.conjugate_gradient.relative_tolerance = std::atof(tolerance);
    }
    BundleAdjustmentConfig config;
    const std::vector<image_t> image_ids = start.RegImageIds();
    for (const image_t image_id : image_ids) config.AddImage(image_id);
    config.SetConstantPose(image_ids.front());
    // PARALLAX_BA_REFINE_INTRINSICS=1: focal length and distortion free, as in the mapper's
    // global adjustments of cameras without a prior.
    if (std::getenv("PARALLAX_BA_REFINE_INTRINSICS") != nullptr) {
      options.refine_focal_length = true;
      options.refine_extra_params = true;
    } else {
      for (const auto& [camera_id, camera] : start.Cameras())
        config.constant_cameras.insert(camera_id);
    }
    Reconstruction reconstruction = start;
    const BundleAdjustmentSummary summary = BundleAdjust(options, config, &reconstruction);
    std::printf("| %s | %.2f | %d | %.3f | %d | %.6g | %.6g |\n", summary.solver.c_str(),
                summary.seconds, summary.num_iterations,
                summary.seconds / std::max(1, summary.num_iterations),
                summary.num_linear_iterations, summary.initial_cost, summary.final_cost);
    std::fflush(stdout);
  }
  return 0;
}

}  // namespace
}  // namespace parallax

int main(int argc, char** argv) {
  return parallax::RunBenchTool("global_bundle_adjustment", parallax::Run, argc, argv);
}
