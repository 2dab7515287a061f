#include <iostream>

#include "parallax/cli/cli_common.h"
#include "parallax/cli/commands.h"
#include "parallax/report/evaluation.h"
#include "parallax/report/ground_truth.h"
#include "parallax/report/html_report.h"
#include "parallax/scene/colmap_io.h"
#include "parallax/util/check.h"
#include "parallax/util/file.h"
#include "parallax/util/logging.h"

namespace parallax::cli {

namespace fs = std::filesystem;

int RunReport(int argc, char** argv) {
  CLI::App app("Write OUT/report.html: a self-contained page with the model, matches and timings",
               "parallax report");
  std::string output, gt_path, image_path, database_path, model_path;
  app.add_option("output", output, "Output folder of `parallax reconstruct`")->required();
  app.add_option("--gt", gt_path,
                 "Ground truth to compare with (*_par.txt, *.camera folder or COLMAP model)");
  app.add_option("--images", image_path, "Image folder (default: OUT/images when it exists)");
  app.add_option("--database", database_path, "Database (default: OUT/database.db)");
  app.add_option("--model", model_path, "Model folder (default: OUT/sparse/0)");
  VerbosityFlags flags;
  AddVerbosityFlags(app, &flags);
  return RunCommand(app, argc, argv, flags, [&] {
    const fs::path out = output;
    if (!fs::is_directory(out)) throw InputError(output + ": output folder does not exist");
    const fs::path model_dir = model_path.empty() ? out / "sparse" / "0" : fs::path(model_path);
    if (!fs::is_directory(model_dir)) throw InputError(model_dir.string() + ": no model");
    const Reconstruction model = ReadReconstruction(model_dir);

    HtmlReportInputs inputs;
    inputs.reconstruction = &model;
    const fs::path summary_path = out / "summary.json";
    if (fs::exists(summary_path)) {
      try {
        inputs.summary = nlohmann::json::parse(ReadFileToString(summary_path));
      } catch (const nlohmann::json::exception& error) {
        throw InputError(summary_path.string() + ": " + error.what());
      }
    } else {
      PARALLAX_LOG(Warning) << summary_path.string() << " missing: no timings or per-image errors";
    }

    std::unique_ptr<Database> database;
    const fs::path db_path = database_path.empty() ? out / "database.db" : fs::path(database_path);
    if (fs::exists(db_path)) {
      database = std::make_unique<Database>(db_path);
      inputs.database = database.get();
    } else if (!database_path.empty()) {
      throw InputError(database_path + ": database does not exist");
    } else {
      PARALLAX_LOG(Warning) << db_path.string() << " missing: no keypoint or match statistics";
    }

    if (!image_path.empty()) {
      if (!fs::is_directory(image_path))
        throw InputError(image_path + ": image folder does not exist");
      inputs.image_dir = image_path;
    } else if (inputs.summary.is_object() && inputs.summary.contains("image_path") &&
               inputs.summary["image_path"].is_string() &&
               fs::is_directory(inputs.summary["image_path"].get<std::string>())) {
      inputs.image_dir = inputs.summary["image_path"].get<std::string>();
    } else if (fs::is_directory(out / "images")) {
      inputs.image_dir = out / "images";
    } else {
      PARALLAX_LOG(Warning) << "no image folder (use --images): the report shows no pictures";
    }

    if (!gt_path.empty()) {
      inputs.evaluation = EvaluateReconstruction(model, ReadGroundTruth(gt_path));
    }
    fs::path normalized = fs::absolute(out).lexically_normal();
    if (normalized.filename().empty()) normalized = normalized.parent_path();
    inputs.title = "Parallax report: " + normalized.filename().string();
    const fs::path report_path = out / "report.html";
    WriteHtmlReport(inputs, report_path);
    std::cout << "Wrote " << report_path.string() << " (" << fs::file_size(report_path) / 1024
              << " KiB)" << std::endl;
    return 0;
  });
}

}  // namespace parallax::cli
