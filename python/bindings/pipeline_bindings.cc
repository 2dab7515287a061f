// The pipeline's stages, one call each, with the command line's flags as keyword options
// (option_flags.h): extract_features, match, map, reconstruct. Each releases the GIL, reports
// progress through an optional callback and stops cleanly on Ctrl-C (released_call.h).
#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

#include "arrays.h"
#include "bindings.h"
#include "option_flags.h"
#include "parallax/cli/mapper_options_cli.h"
#include "parallax/cli/pipeline_options_cli.h"
#include "parallax/pipeline/database_stages.h"
#include "parallax/pipeline/reconstruction_pipeline.h"
#include "parallax/pipeline/run_summary.h"
#include "parallax/util/logging.h"
#include "released_call.h"

namespace py = pybind11;
namespace fs = std::filesystem;

namespace parallax::python {
namespace {

// What reconstruct returns.
struct ReconstructionRunResult {
  std::vector<Reconstruction> models;
  py::object summary;
  py::object evaluation = py::none();
  py::object report_path = py::none();
};

template <typename Options>
using AddOptionFlags = void (*)(CLI::App&, Options*);

// The flags of `add_flags` as AddFlags, bound to options that are never parsed into (for the
// docstrings and stubs; the defaults they show are the options' own).
template <typename Options>
AddFlags FlagsOf(AddOptionFlags<Options> add_flags) {
  return [add_flags](CLI::App& app) {
    static Options options;
    add_flags(app, &options);
  };
}

// Each function's flags, as `parallax features|match|mapper|reconstruct` has them.
const std::map<std::string, AddFlags>& FunctionFlags() {
  static const auto* flags = new std::map<std::string, AddFlags>{
      {"extract_features", FlagsOf<ExtractionStageOptions>(cli::AddExtractionOptions)},
      {"match", FlagsOf<MatchingStageOptions>(cli::AddMatchingOptions)},
      {"map", FlagsOf<MappingStageOptions>(cli::AddMapperOptions)},
      {"reconstruct", FlagsOf<ReconstructionPipelineOptions>(cli::AddReconstructionOptions)},
  };
  return *flags;
}

// Default options with `function`'s keyword arguments parsed into them as `add_flags`' flags.
template <typename Options>
Options ParseOptions(const std::string& function, const py::kwargs& kwargs,
                     AddOptionFlags<Options> add_flags) {
  Options options;
  CLI::App app;
  add_flags(app, &options);
  ParseKeywordOptions(function, kwargs, app);
  return options;
}

std::string Doc(const std::string& function, const std::string& summary) {
  return summary +
         "\n\nprogress: a callable (stage, done, total) called on this thread as the work "
         "advances, or None.\nCtrl-C stops the call at its next safe point; what was stored "
         "stays, and the same call resumes.\n\nKeyword options (the command line's flags, '_' "
         "for '-'):\n" +
         DescribeKeywordOptions(FunctionFlags().at(function));
}

ExtractionStageResult ExtractFeatures(const fs::path& image_dir, const fs::path& database,
                                      int threads, const py::object& progress,
                                      const py::kwargs& kwargs) {
  ExtractionStageOptions options =
      ParseOptions<ExtractionStageOptions>("extract_features", kwargs, cli::AddExtractionOptions);
  options.num_threads = threads;
  ExtractionStageResult result;
  RunReleasingGil([&] { result = ExtractFeaturesIntoDatabase(options, image_dir, database); },
                  progress);
  return result;
}

MatchingStageResult Match(const fs::path& database, int threads, uint64_t seed,
                          const py::object& progress, const py::kwargs& kwargs) {
  MatchingStageOptions options =
      ParseOptions<MatchingStageOptions>("match", kwargs, cli::AddMatchingOptions);
  options.num_threads = threads;
  options.seed = seed;
  MatchingStageResult result;
  RunReleasingGil([&] { result = MatchDatabase(options, database); }, progress);
  return result;
}

std::vector<Reconstruction> Map(const fs::path& database, const fs::path& image_dir,
                                const fs::path& output_dir, uint64_t seed,
                                const py::object& progress, const py::kwargs& kwargs) {
  MappingStageOptions options =
      ParseOptions<MappingStageOptions>("map", kwargs, cli::AddMapperOptions);
  options.mapper.seed = seed;
  MappingStageResult result;
  RunReleasingGil([&] { result = MapDatabase(options, database, image_dir, output_dir); },
                  progress);
  if (result.models.empty()) {
    throw std::runtime_error("no model could be started: " + result.summary.failure);
  }
  return std::move(result.models);
}

ReconstructionRunResult Reconstruct(const fs::path& image_dir, const fs::path& output_dir,
                                    const std::optional<fs::path>& database,
                                    const std::optional<fs::path>& ground_truth, bool report,
                                    bool remap, int threads, uint64_t seed,
                                    const py::object& progress, const py::kwargs& kwargs) {
  ReconstructionPipelineOptions options = ParseOptions<ReconstructionPipelineOptions>(
      "reconstruct", kwargs, cli::AddReconstructionOptions);
  SetSeedAndThreads(seed, threads, kwargs.contains("ba_threads"), &options);
  options.database_path = database.value_or(fs::path());
  options.ground_truth_path = ground_truth.value_or(fs::path());
  options.write_report = report;
  options.extend_model_with_new_photos = !remap;
  ReconstructionPipelineResult result;
  RunReleasingGil([&] { result = RunReconstructionPipeline(options, image_dir, output_dir); },
                  progress);
  if (!result.Success()) {
    throw std::runtime_error(image_dir.string() +
                             ": no model could be started: " + result.mapping.summary.failure);
  }
  ReconstructionRunResult run;
  run.models = std::move(result.mapping.models);
  run.summary = FromJson(result.summary);
  if (result.evaluation) run.evaluation = FromJson(MetricsToJson(*result.evaluation));
  if (!result.report_path.empty()) run.report_path = py::cast(result.report_path);
  return run;
}

LogLevel LogLevelFromName(const std::string& name) {
  static const std::map<std::string, LogLevel> kLevels = {{"debug", LogLevel::kDebug},
                                                          {"info", LogLevel::kInfo},
                                                          {"warning", LogLevel::kWarning},
                                                          {"error", LogLevel::kError},
                                                          {"silent", LogLevel::kSilent}};
  const auto it = kLevels.find(name);
  if (it == kLevels.end()) {
    throw py::value_error("level: expected debug, info, warning, error or silent, got '" + name +
                          "'");
  }
  return it->second;
}

void BindResults(py::module_& m) {
  py::class_<ExtractionStageResult>(m, "ExtractionResult", "What extract_features did.")
      .def_readonly("num_images_found", &ExtractionStageResult::num_images_found)
      .def_readonly("num_extracted", &ExtractionStageResult::num_extracted)
      .def_readonly("num_skipped", &ExtractionStageResult::num_skipped,
                    "Already in the database (a resumed run).")
      .def_readonly("failed", &ExtractionStageResult::failed, "(image name, reason) pairs.")
      .def_readonly("mean_num_keypoints", &ExtractionStageResult::mean_num_keypoints)
      .def_readonly("seconds", &ExtractionStageResult::seconds)
      .def("__repr__", [](const ExtractionStageResult& result) {
        return "ExtractionResult(" + std::to_string(result.num_images_found) + " images, " +
               std::to_string(result.num_extracted) + " extracted, " +
               std::to_string(result.num_skipped) + " already in the database)";
      });
  py::class_<MatchingStageResult>(m, "MatchResult", "What match did.")
      .def_readonly("num_pairs", &MatchingStageResult::num_pairs, "Pairs selected.")
      .def_readonly("num_skipped", &MatchingStageResult::num_skipped,
                    "Already verified (a resumed run).")
      .def_readonly("num_matched", &MatchingStageResult::num_matched)
      .def_readonly("num_verified", &MatchingStageResult::num_verified)
      .def_readonly("num_preemptive_rejected", &MatchingStageResult::num_preemptive_rejected)
      .def_readonly("approximate", &MatchingStageResult::approximate,
                    "Whether descriptors were matched approximately, in cells.")
      .def_readonly("seconds", &MatchingStageResult::seconds)
      .def(
          "summary",
          [](const MatchingStageResult& result) { return FromJson(MatchingSummary(result)); },
          "The matching section of summary.json.")
      .def("__repr__", [](const MatchingStageResult& result) {
        return "MatchResult(" + std::to_string(result.num_pairs) + " pairs, " +
               std::to_string(result.num_verified) + " verified, " +
               std::to_string(result.num_skipped) + " already verified)";
      });
  py::class_<ReconstructionRunResult>(m, "ReconstructionResult", "What reconstruct made.")
      .def_readonly("models", &ReconstructionRunResult::models, "Largest first.")
      .def_readonly("summary", &ReconstructionRunResult::summary,
                    "summary.json as a dict: timings, per-image errors before and after BA, ...")
      .def_readonly("evaluation", &ReconstructionRunResult::evaluation,
                    "The comparison with ground_truth (as evaluate returns it), or None.")
      .def_readonly("report_path", &ReconstructionRunResult::report_path)
      .def("__repr__", [](const ReconstructionRunResult& result) {
        return "ReconstructionResult(" + std::to_string(result.models.size()) + " model(s))";
      });
}

}  // namespace

void BindPipeline(py::module_& m) {
  BindResults(m);
  m.def("extract_features", &ExtractFeatures, py::arg("image_dir"), py::arg("database"),
        py::kw_only(), py::arg("threads") = -1, py::arg("progress") = py::none(),
        Doc("extract_features",
            "Detects SIFT features in every image of image_dir (not recursive) and stores "
            "them in the database (COLMAP's format), as `parallax features`. Images already "
            "there are skipped. Returns an ExtractionResult.")
            .c_str());
  m.def("match", &Match, py::arg("database"), py::kw_only(), py::arg("threads") = -1,
        py::arg("seed") = 0, py::arg("progress") = py::none(),
        Doc("match",
            "Matches the selected pairs (pairs='auto', 'exhaustive', 'sequential', "
            "'retrieval' or 'spatial') and verifies them geometrically, as `parallax match`. "
            "Verified pairs are skipped. Returns a MatchResult.")
            .c_str());
  m.def("map", &Map, py::arg("database"), py::arg("image_dir"), py::arg("output_dir"),
        py::kw_only(), py::arg("seed") = 0, py::arg("progress") = py::none(),
        Doc("map",
            "Runs the incremental mapper on a database, as `parallax mapper`: writes "
            "OUT/sparse/<k>/, OUT/points.ply and OUT/summary.json and returns the models "
            "(Reconstruction), largest first. Raises RuntimeError when no model could start.")
            .c_str());
  m.def("reconstruct", &Reconstruct, py::arg("image_dir"), py::arg("output_dir"), py::kw_only(),
        py::arg("database") = py::none(), py::arg("ground_truth") = py::none(),
        py::arg("report") = false, py::arg("remap") = false, py::arg("threads") = -1,
        py::arg("seed") = 0, py::arg("progress") = py::none(),
        Doc("reconstruct",
            "The whole pipeline, as `parallax reconstruct`: features, matching, mapping, "
            "outputs in output_dir (database OUT/database.db unless database is given), the "
            "evaluation against ground_truth (*_par.txt, a gt/ folder of *.camera files or a "
            "COLMAP model) and OUT/report.html when report=True. Reruns resume; photos added "
            "since an earlier run are registered into its model unless remap=True. Returns a "
            "ReconstructionResult.")
            .c_str());
  m.def(
      "set_log_level", [](const std::string& level) { SetLogLevel(LogLevelFromName(level)); },
      py::arg("level"),
      "How much the C++ core prints on stderr: 'debug', 'info' (default), 'warning', 'error' "
      "or 'silent'.");
  m.def(
      "_keyword_options",
      [](const std::string& function) {
        const auto it = FunctionFlags().find(function);
        if (it == FunctionFlags().end()) throw py::key_error(function);
        return ListKeywordOptions(it->second);
      },
      py::arg("function"), "The keyword options of a pipeline function (for the type stubs).");
}

}  // namespace parallax::python
