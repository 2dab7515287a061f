#include "parallax/report/report_folder.h"

#include <memory>
#include <nlohmann/json.hpp>

#include "parallax/report/evaluation.h"
#include "parallax/report/ground_truth.h"
#include "parallax/report/html_report.h"
#include "parallax/scene/colmap_io.h"
#include "parallax/scene/database.h"
#include "parallax/util/check.h"
#include "parallax/util/file.h"
#include "parallax/util/logging.h"

namespace parallax {
namespace fs = std::filesystem;
namespace {

nlohmann::json ReadSummaryIfPresent(const fs::path& path) {
  if (!fs::exists(path)) {
    PARALLAX_LOG(Warning) << path.string() << " missing: no timings or per-image errors";
    return nullptr;
  }
  try {
    return nlohmann::json::parse(ReadFileToString(path));
  } catch (const nlohmann::json::exception& error) {
    throw InputError(path.string() + ": " + error.what());
  }
}

// The image folder: the one given, else the one the run used, else OUT/images.
fs::path FindImageDir(const ReportFolderOptions& options, const nlohmann::json& summary) {
  if (!options.image_dir.empty()) {
    if (!fs::is_directory(options.image_dir)) {
      throw MissingFileError(options.image_dir.string() + ": image folder does not exist");
    }
    return options.image_dir;
  }
  if (summary.is_object() && summary.contains("image_path") && summary["image_path"].is_string() &&
      fs::is_directory(summary["image_path"].get<std::string>())) {
    return summary["image_path"].get<std::string>();
  }
  if (fs::is_directory(options.output_dir / "images")) return options.output_dir / "images";
  PARALLAX_LOG(Warning) << "no image folder (use --images): the report shows no pictures";
  return {};
}

std::string DefaultTitle(const fs::path& output_dir) {
  fs::path normalized = fs::absolute(output_dir).lexically_normal();
  if (normalized.filename().empty()) normalized = normalized.parent_path();
  return "Parallax report: " + normalized.filename().string();
}

}  // namespace

fs::path WriteReportOfOutputFolder(const ReportFolderOptions& options) {
  const fs::path& out = options.output_dir;
  if (!fs::is_directory(out)) {
    throw MissingFileError(out.string() + ": output folder does not exist");
  }
  const fs::path model_dir = options.model_dir.empty() ? out / "sparse" / "0" : options.model_dir;
  if (!fs::is_directory(model_dir)) throw InputError(model_dir.string() + ": no model");
  const Reconstruction model = ReadReconstruction(model_dir);

  HtmlReportInputs inputs;
  inputs.reconstruction = &model;
  inputs.summary = ReadSummaryIfPresent(out / "summary.json");

  std::unique_ptr<Database> database;
  const fs::path database_path =
      options.database_path.empty() ? out / "database.db" : options.database_path;
  if (fs::exists(database_path)) {
    database = std::make_unique<Database>(database_path);
    inputs.database = database.get();
  } else if (!options.database_path.empty()) {
    throw MissingFileError(options.database_path.string() + ": database does not exist");
  } else {
    PARALLAX_LOG(Warning) << database_path.string() << " missing: no keypoint or match statistics";
  }

  inputs.image_dir = FindImageDir(options, inputs.summary);
  if (!options.ground_truth_path.empty()) {
    inputs.evaluation = EvaluateReconstruction(model, ReadGroundTruth(options.ground_truth_path));
  }
  inputs.title = options.title.empty() ? DefaultTitle(out) : options.title;
  const fs::path report_path = out / "report.html";
  WriteHtmlReport(inputs, report_path);
  return report_path;
}

}  // namespace parallax
