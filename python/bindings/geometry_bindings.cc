// The paper's geometry on numpy arrays: F, E (with the relative pose), H, absolute pose, DLT
// resection split into K, R, t, and linear triangulation. Each estimator runs Parallax's
// LO-RANSAC and returns an EstimationResult.
#include <pybind11/eigen.h>
#include <pybind11/numpy.h>
#include <pybind11/stl.h>

#include <cmath>
#include <limits>

#include "arrays.h"
#include "bindings.h"
#include "parallax/estimators/absolute_pose.h"
#include "parallax/estimators/solvers/dlt_resection.h"
#include "parallax/estimators/solvers/essential_matrix.h"
#include "parallax/estimators/solvers/fundamental_matrix.h"
#include "parallax/estimators/solvers/homography_matrix.h"
#include "parallax/geometry/essential_matrix.h"
#include "parallax/geometry/triangulation.h"
#include "parallax/optim/ransac.h"

namespace py = pybind11;

namespace parallax::python {
namespace {

// What every estimator returns; estimators add their own attributes (E: cam2_from_cam1; DLT:
// K, R, t).
struct EstimationResult {
  bool success = false;
  py::object model = py::none();
  py::array_t<bool> inlier_mask;
  size_t num_inliers = 0;
  size_t num_trials = 0;
};

RansacOptions MakeRansacOptions(double max_error, double confidence, int max_num_trials,
                                uint64_t seed) {
  RansacOptions options;
  options.max_error = max_error;
  options.confidence = confidence;
  options.max_num_trials = max_num_trials;
  options.random_seed = seed;
  if (!(max_error > 0)) throw py::value_error("max_error: must be positive");
  if (!(confidence > 0 && confidence < 1)) throw py::value_error("confidence: must be in (0, 1)");
  if (max_num_trials <= 0) throw py::value_error("max_num_trials: must be positive");
  return options;
}

template <typename Model>
py::object ToResult(const RansacReport<Model>& report, size_t num_points) {
  EstimationResult result;
  result.success = report.success;
  result.num_trials = report.num_trials;
  result.num_inliers = report.success ? report.num_inliers : 0;
  result.inlier_mask =
      FromMask(report.success ? report.inlier_mask : std::vector<char>(num_points, 0));
  if (report.success) result.model = py::cast(report.model);
  return py::cast(std::move(result));
}

void RequireSameLength(size_t a, size_t b, const char* names) {
  if (a != b) {
    throw py::value_error(std::string(names) + ": different numbers of points (" +
                          std::to_string(a) + " and " + std::to_string(b) + ")");
  }
}

template <typename Estimator, typename LocalEstimator, typename X, typename Y>
RansacReport<typename Estimator::M_t> RunRansac(const RansacOptions& options,
                                                const std::vector<X>& x, const std::vector<Y>& y) {
  py::gil_scoped_release release;
  return LoRansac<Estimator, LocalEstimator>(options).Estimate(x, y);
}

// F or H from pixel correspondences: the same arrays in, the same result out.
template <typename Estimator, typename LocalEstimator>
py::object EstimateFromPixelPairs(const py::array& points1, const py::array& points2,
                                  double max_error, double confidence, int max_num_trials,
                                  uint64_t seed) {
  const auto x1 = ToPoints2D(points1, "points1");
  const auto x2 = ToPoints2D(points2, "points2");
  RequireSameLength(x1.size(), x2.size(), "points1, points2");
  const auto report = RunRansac<Estimator, LocalEstimator>(
      MakeRansacOptions(max_error, confidence, max_num_trials, seed), x1, x2);
  return ToResult(report, x1.size());
}

Eigen::Matrix3d CheckedCalibration(const Eigen::Matrix3d& K, const char* name) {
  if (!(K(0, 0) > 0 && K(1, 1) > 0) || K(2, 2) == 0 || K(1, 0) != 0 || K(2, 0) != 0 ||
      K(2, 1) != 0) {
    throw py::value_error(std::string(name) +
                          ": not a calibration matrix (upper triangular, positive focal lengths)");
  }
  return K / K(2, 2);
}

std::vector<Eigen::Vector2d> Normalized(const std::vector<Eigen::Vector2d>& pixels,
                                        const Eigen::Matrix3d& K) {
  const Eigen::Matrix3d K_inverse = K.inverse();
  std::vector<Eigen::Vector2d> points;
  points.reserve(pixels.size());
  for (const Eigen::Vector2d& pixel : pixels) {
    points.push_back((K_inverse * pixel.homogeneous()).hnormalized());
  }
  return points;
}

py::object EstimateEssential(const py::array& points1, const py::array& points2,
                             const Eigen::Matrix3d& K1, const std::optional<Eigen::Matrix3d>& K2,
                             double max_error, double confidence, int max_num_trials,
                             uint64_t seed) {
  const Eigen::Matrix3d camera1 = CheckedCalibration(K1, "K1");
  const Eigen::Matrix3d camera2 = K2 ? CheckedCalibration(*K2, "K2") : camera1;
  const auto x1 = Normalized(ToPoints2D(points1, "points1"), camera1);
  const auto x2 = Normalized(ToPoints2D(points2, "points2"), camera2);
  RequireSameLength(x1.size(), x2.size(), "points1, points2");
  // The pixel threshold on the normalised plane (as verification does).
  const double mean_focal = (camera1(0, 0) + camera1(1, 1) + camera2(0, 0) + camera2(1, 1)) / 4;
  const auto report =
      RunRansac<EssentialMatrixFivePointEstimator, EssentialMatrixEightPointEstimator>(
          MakeRansacOptions(max_error / mean_focal, confidence, max_num_trials, seed), x1, x2);
  py::object result = ToResult(report, x1.size());
  result.attr("cam2_from_cam1") = py::none();
  if (report.success) {
    std::vector<Eigen::Vector2d> inliers1, inliers2;
    for (size_t i = 0; i < x1.size(); ++i) {
      if (!report.inlier_mask[i]) continue;
      inliers1.push_back(x1[i]);
      inliers2.push_back(x2[i]);
    }
    Rigid3d cam2_from_cam1;
    if (PoseFromEssentialMatrix(report.model, inliers1, inliers2, &cam2_from_cam1)) {
      result.attr("cam2_from_cam1") = py::cast(cam2_from_cam1);
    }
  }
  return result;
}

py::object EstimatePose(const py::array& points2D, const py::array& points3D, const Camera& camera,
                        double max_error, double confidence, int max_num_trials, uint64_t seed) {
  const auto x = ToPoints2D(points2D, "points2D");
  const auto X = ToPoints3D(points3D, "points3D");
  RequireSameLength(x.size(), X.size(), "points2D, points3D");
  AbsolutePoseEstimationOptions options;
  options.ransac = MakeRansacOptions(max_error, confidence, max_num_trials, seed);
  AbsolutePoseReport report;
  {
    py::gil_scoped_release release;
    report = EstimateAbsolutePose(camera, x, X, options);
  }
  RansacReport<Rigid3d> ransac;
  ransac.success = report.success;
  ransac.model = report.cam_from_world;
  ransac.num_inliers = report.num_inliers;
  ransac.num_trials = report.num_trials;
  ransac.inlier_mask = report.inlier_mask;
  return ToResult(ransac, x.size());
}

py::object ResectDlt(const py::array& points2D, const py::array& points3D, double max_error,
                     double confidence, int max_num_trials, uint64_t seed) {
  const auto x = ToPoints2D(points2D, "points2D");
  const auto X = ToPoints3D(points3D, "points3D");
  RequireSameLength(x.size(), X.size(), "points2D, points3D");
  const auto report = RunRansac<DLTResectionEstimator, DLTResectionEstimator>(
      MakeRansacOptions(max_error, confidence, max_num_trials, seed), x, X);
  py::object result = ToResult(report, x.size());
  result.attr("K") = py::none();
  result.attr("R") = py::none();
  result.attr("t") = py::none();
  Eigen::Matrix3d K, R;
  Eigen::Vector3d t;
  if (report.success && DecomposeProjectionMatrix(report.model, &K, &R, &t)) {
    result.attr("K") = py::cast(K);
    result.attr("R") = py::cast(R);
    result.attr("t") = py::cast(t);
  }
  return result;
}

py::array_t<double> Triangulate(const Matrix3x4d& proj_matrix1, const Matrix3x4d& proj_matrix2,
                                const py::array& points1, const py::array& points2) {
  const auto x1 = ToPoints2D(points1, "points1");
  const auto x2 = ToPoints2D(points2, "points2");
  RequireSameLength(x1.size(), x2.size(), "points1, points2");
  std::vector<Eigen::Vector3d> points(x1.size());
  for (size_t i = 0; i < x1.size(); ++i) {
    const auto point = TriangulatePoint(proj_matrix1, proj_matrix2, x1[i], x2[i]);
    points[i] =
        point ? *point : Eigen::Vector3d::Constant(std::numeric_limits<double>::quiet_NaN());
  }
  return FromPoints(points);
}

// The RANSAC keywords every estimator takes, after its own.
auto RansacArgs(double default_max_error) {
  return std::make_tuple(py::arg("max_error") = default_max_error, py::arg("confidence") = 0.9999,
                         py::arg("max_num_trials") = 10000, py::arg("seed") = 0);
}

}  // namespace

void BindGeometry(py::module_& m) {
  py::class_<EstimationResult>(m, "EstimationResult", py::dynamic_attr(),
                               "The outcome of a robust estimation.")
      .def_readonly("success", &EstimationResult::success)
      .def_readonly("model", &EstimationResult::model, "The model, None when none was found.")
      .def_readonly("inlier_mask", &EstimationResult::inlier_mask,
                    "One bool per correspondence: inlier of the model.")
      .def_readonly("num_inliers", &EstimationResult::num_inliers)
      .def_readonly("num_trials", &EstimationResult::num_trials, "RANSAC samples drawn.")
      .def("__bool__", [](const EstimationResult& result) { return result.success; })
      .def("__repr__", [](const EstimationResult& result) {
        return "EstimationResult(success=" + std::string(result.success ? "True" : "False") +
               ", num_inliers=" + std::to_string(result.num_inliers) +
               ", num_trials=" + std::to_string(result.num_trials) + ")";
      });

  const auto [max_error4, confidence, trials, seed] = RansacArgs(4.0);
  m.def("estimate_fundamental_matrix",
        &EstimateFromPixelPairs<FundamentalMatrixSevenPointEstimator,
                                FundamentalMatrixEightPointEstimator>,
        py::arg("points1"), py::arg("points2"), py::kw_only(), max_error4, confidence, trials, seed,
        "Fundamental matrix F (x2^T F x1 = 0) from N x 2 pixel correspondences: 7-point "
        "samples, normalised 8-point refits (LO-RANSAC); max_error is the Sampson distance in "
        "pixels. result.model is F (3 x 3).");
  m.def("estimate_homography",
        &EstimateFromPixelPairs<HomographyMatrixEstimator, HomographyMatrixEstimator>,
        py::arg("points1"), py::arg("points2"), py::kw_only(), max_error4, confidence, trials, seed,
        "Homography H (x2 ~ H x1) from N x 2 pixel correspondences (4-point DLT, LO-RANSAC); "
        "max_error in pixels. result.model is H (3 x 3).");
  m.def("estimate_essential_matrix", &EstimateEssential, py::arg("points1"), py::arg("points2"),
        py::arg("K1"), py::arg("K2") = py::none(), py::kw_only(), max_error4, confidence, trials,
        seed,
        "Essential matrix E from N x 2 pixel correspondences of cameras K1 and K2 (default K1): "
        "5-point samples (Nister), 8-point refits; max_error in pixels. result.model is E; "
        "result.cam2_from_cam1 the relative pose (Rigid3d, unit translation) chosen by "
        "cheirality on the inliers.");
  const auto [max_error12, confidence12, trials12, seed12] = RansacArgs(12.0);
  m.def("estimate_absolute_pose", &EstimatePose, py::arg("points2D"), py::arg("points3D"),
        py::arg("camera"), py::kw_only(), max_error12, confidence12, trials12, seed12,
        "Pose of a calibrated camera from N x 2 pixels and N x 3 world points: P3P samples, "
        "EPnP refits (LO-RANSAC); max_error is the reprojection error in pixels. result.model is "
        "cam_from_world (Rigid3d).");
  m.def("dlt_resection", &ResectDlt, py::arg("points2D"), py::arg("points3D"), py::kw_only(),
        max_error4, confidence, trials, seed,
        "Projection matrix P = K [R | t] of an uncalibrated camera from N >= 6 pixel / world "
        "correspondences (normalised DLT in LO-RANSAC), split by QR: result.model is P (3 x 4), "
        "result.K (upper triangular, K[2, 2] = 1), result.R (rotation), result.t.");
  m.def("triangulate_points", &Triangulate, py::arg("proj_matrix1"), py::arg("proj_matrix2"),
        py::arg("points1"), py::arg("points2"),
        "Linear (DLT) triangulation of N correspondences seen by two 3 x 4 projection matrices: "
        "[R | t] with normalised points, or K [R | t] with pixels. Returns N x 3; rows of NaN "
        "where the system is degenerate.");
}

}  // namespace parallax::python
