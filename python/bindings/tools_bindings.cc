// The commands around the pipeline: evaluate, write_report, synthesize, calibrate.
#include <pybind11/eigen.h>
#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

#include "arrays.h"
#include "bindings.h"
#include "parallax/calibration/camera_json.h"
#include "parallax/calibration/checkerboard_calibration.h"
#include "parallax/export/image_undistortion.h"
#include "parallax/export/model_export_format.h"
#include "parallax/render/synthetic_scene.h"
#include "parallax/report/evaluation.h"
#include "parallax/report/ground_truth.h"
#include "parallax/report/report_folder.h"
#include "parallax/scene/colmap_io.h"
#include "parallax/util/check.h"
#include "released_call.h"

namespace py = pybind11;
namespace fs = std::filesystem;

namespace parallax::python {
namespace {

// A Reconstruction, or the path of a model folder.
Reconstruction ModelOf(const py::object& model) {
  if (py::isinstance<Reconstruction>(model)) return model.cast<Reconstruction>();
  return ReadReconstruction(model.cast<fs::path>());
}

py::object Evaluate(const py::object& model, const fs::path& ground_truth) {
  const Reconstruction reconstruction = ModelOf(model);
  const GroundTruth truth = ReadGroundTruth(ground_truth);
  EvaluationMetrics metrics;
  {
    py::gil_scoped_release release;
    metrics = EvaluateReconstruction(reconstruction, truth);
  }
  return FromJson(MetricsToJson(metrics));
}

fs::path WriteReport(const fs::path& output_dir, const std::optional<fs::path>& model,
                     const std::optional<fs::path>& database,
                     const std::optional<fs::path>& image_dir,
                     const std::optional<fs::path>& ground_truth,
                     const std::optional<std::string>& title) {
  ReportFolderOptions options;
  options.output_dir = output_dir;
  options.model_dir = model.value_or(fs::path());
  options.database_path = database.value_or(fs::path());
  options.image_dir = image_dir.value_or(fs::path());
  options.ground_truth_path = ground_truth.value_or(fs::path());
  options.title = title.value_or("");
  py::gil_scoped_release release;
  return WriteReportOfOutputFolder(options);
}

Reconstruction Synthesize(const fs::path& output_dir, int views, const std::string& layout,
                          const std::optional<std::pair<int, int>>& image_size, int width,
                          int height, double focal, uint64_t seed, double noise, double blur,
                          double lighting, const std::string& antialiasing, bool shadows,
                          double oblique, double gps_noise, const std::string& name, int threads,
                          const py::object& progress) {
  SyntheticSceneOptions options;
  options.num_views = views;
  options.layout = SyntheticSceneLayoutFromName(layout);
  options.width = image_size ? image_size->first : width;
  options.height = image_size ? image_size->second : height;
  options.focal_length = focal;
  options.seed = seed;
  options.noise_stddev = noise;
  options.blur_sigma = blur;
  options.lighting_variation = lighting;
  options.antialiasing = AntialiasingFromName(antialiasing);
  options.shadows = shadows;
  options.oblique_fraction = oblique;
  options.gps_noise = gps_noise;
  options.name = name;
  options.num_threads = threads;
  Reconstruction scene;
  RunReleasingGil([&] { scene = GenerateSyntheticScene(options, output_dir); }, progress);
  return scene;
}

int Undistort(const py::object& model, const fs::path& image_dir, const fs::path& output_dir,
              int max_size, double blank_pixels, int jpeg_quality, int threads,
              const py::object& progress) {
  const Reconstruction reconstruction = ModelOf(model);
  UndistortionOptions options;
  options.max_image_size = max_size;
  options.blank_pixels = blank_pixels;
  options.jpeg_quality = jpeg_quality;
  options.num_threads = threads;
  UndistortionResult result;
  RunReleasingGil(
      [&] { result = WriteUndistortedWorkspace(reconstruction, image_dir, output_dir, options); },
      progress);
  return static_cast<int>(result.num_images);
}

// The calibration as a dict: the camera.json fields and the per-image outcome.
py::dict Calibrate(const fs::path& image_dir, const std::pair<int, int>& pattern, double square,
                   const std::optional<fs::path>& output,
                   const std::optional<std::pair<int, int>>& size, bool k3, bool sector_based,
                   int threads) {
  CheckerboardCalibrationOptions options;
  std::tie(options.pattern_cols, options.pattern_rows) = pattern;
  if (size) std::tie(options.required_width, options.required_height) = *size;
  options.square_size = square;
  options.fit_k3 = k3;
  options.use_sector_based_detector = sector_based;
  options.num_threads = threads;
  const std::vector<fs::path> paths = ListCalibrationImages(image_dir);
  CheckerboardCalibrationResult result;
  {
    py::gil_scoped_release release;
    result = CalibrateFromCheckerboards(options, paths);
  }
  if (!result.success) throw std::runtime_error("calibration failed: " + result.message);
  if (output) WriteCameraJson(CalibratedCameraFromResult(result), *output);
  py::dict calibration;
  calibration["camera"] = py::cast(result.camera);
  calibration["K"] = py::cast(result.camera.CalibrationMatrix());
  calibration["distortion"] = result.distortion;
  calibration["rms_error_px"] = result.rms_error;
  calibration["width"] = result.width;
  calibration["height"] = result.height;
  calibration["num_used_images"] = result.num_used_images;
  py::list images;
  for (const CheckerboardImageResult& image : result.images) {
    py::dict entry;
    entry["name"] = image.path.filename().string();
    entry["status"] = CheckerboardImageStatusName(image.status);
    entry["reason"] = image.reason;
    entry["rms_error_px"] = image.rms_error;
    images.append(entry);
  }
  calibration["images"] = images;
  return calibration;
}

}  // namespace

void BindTools(py::module_& m) {
  m.def("evaluate", &Evaluate, py::arg("model"), py::arg("ground_truth"),
        "Compares a model (Reconstruction or model folder) with ground truth (Middlebury "
        "*_par.txt, a folder of Strecha *.camera files or a COLMAP model) after a robust "
        "similarity alignment, as `parallax evaluate --json`: centre and rotation errors, "
        "accuracy curves, per-image errors, track statistics. Returns a dict.");
  m.def("write_report", &WriteReport, py::arg("output_dir"), py::kw_only(),
        py::arg("model") = py::none(), py::arg("database") = py::none(),
        py::arg("image_dir") = py::none(), py::arg("ground_truth") = py::none(),
        py::arg("title") = py::none(),
        "Writes OUT/report.html for a finished run, as `parallax report`: model default "
        "OUT/sparse/0, database default OUT/database.db, images from summary.json. Returns the "
        "report's path.");
  const UndistortionOptions undistortion;
  m.def("undistort", &Undistort, py::arg("model"), py::arg("image_dir"), py::arg("output_dir"),
        py::kw_only(), py::arg("max_size") = undistortion.max_image_size,
        py::arg("blank_pixels") = undistortion.blank_pixels,
        py::arg("jpeg_quality") = undistortion.jpeg_quality,
        py::arg("threads") = undistortion.num_threads, py::arg("progress") = py::none(),
        "COLMAP's dense workspace from a model (Reconstruction or model folder) and its photos, "
        "as `parallax undistort`: output_dir/images (PINHOLE, same names), output_dir/sparse, "
        "output_dir/stereo. blank_pixels 0 crops to valid pixels, 1 keeps all of the photo. "
        "Returns the number of images written.");
  m.def(
      "export_model",
      [](const py::object& model, const fs::path& path, const std::string& format,
         const std::string& image_prefix) {
        ExportModel(ModelOf(model), format, path, {.image_prefix = image_prefix});
      },
      py::arg("model"), py::arg("path"), py::kw_only(), py::arg("format"),
      py::arg("image_prefix") = NerfstudioExportOptions().image_prefix,
      "Writes a model (Reconstruction or model folder) as `parallax export` does: format "
      "'nerfstudio' (transforms.json, sparse_pc.ply beside it), 'ply' (points and camera "
      "frustums), 'bundler' (bundle.out, list.txt beside it) or 'nvm'.");
  const SyntheticSceneOptions defaults;
  m.def("synthesize", &Synthesize, py::arg("output_dir"), py::kw_only(),
        py::arg("views") = defaults.num_views, py::arg("layout") = "ring",
        py::arg("image_size") = py::none(), py::arg("width") = defaults.width,
        py::arg("height") = defaults.height, py::arg("focal") = defaults.focal_length,
        py::arg("seed") = defaults.seed, py::arg("noise") = defaults.noise_stddev,
        py::arg("blur") = defaults.blur_sigma, py::arg("lighting") = defaults.lighting_variation,
        py::arg("antialiasing") = "quincunx", py::arg("shadows") = defaults.shadows,
        py::arg("oblique") = defaults.oblique_fraction, py::arg("gps_noise") = defaults.gps_noise,
        py::arg("name") = defaults.name, py::arg("threads") = defaults.num_threads,
        py::arg("progress") = py::none(),
        "Renders a synthetic scene with exact cameras into output_dir, as `parallax synth`: "
        "layout 'ring', 'hemisphere', 'sequence', 'aerial' or a hard scene, 'street', 'twin' "
        "or 'weak'; image_size=(w, h) sets width and height. Writes the images, "
        "<name>_par.txt, K.txt and gt/ (aerial and the hard scenes: gt/overlap_pairs.txt). "
        "Returns the exact views as a Reconstruction.");
  m.def("calibrate", &Calibrate, py::arg("image_dir"), py::arg("pattern"), py::kw_only(),
        py::arg("square") = 1.0, py::arg("output") = py::none(), py::arg("size") = py::none(),
        py::arg("k3") = false, py::arg("sector_based") = false, py::arg("threads") = -1,
        "Calibrates a camera from photos of a chessboard, as `parallax calibrate`: pattern = "
        "(inner corners per row, per column), e.g. (8, 6). Writes camera.json when output is "
        "given. Returns a dict: camera (OPENCV Camera), K, distortion (k1, k2, p1, p2, k3), "
        "rms_error_px, width, height, num_used_images, images (per-image status).");
}

}  // namespace parallax::python
