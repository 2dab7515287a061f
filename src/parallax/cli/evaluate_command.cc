#include <iostream>

#include "parallax/cli/cli_common.h"
#include "parallax/cli/commands.h"
#include "parallax/report/evaluation.h"
#include "parallax/report/ground_truth.h"
#include "parallax/scene/colmap_io.h"
#include "parallax/util/check.h"

namespace parallax::cli {

int RunEvaluate(int argc, char** argv) {
  CLI::App app("Compare a model's camera poses with ground truth", "parallax evaluate");
  std::string model_path, gt_path;
  bool json = false;
  EvaluationOptions options;
  app.add_option("model", model_path, "Model folder (COLMAP format, e.g. OUT/sparse/0)")
      ->required();
  app.add_option("--gt", gt_path,
                 "Ground truth: a Middlebury *_par.txt file, a folder of Strecha *.camera files or "
                 "a COLMAP model folder (detected automatically)")
      ->required();
  app.add_flag("--json", json, "Print the metrics as JSON instead of a table");
  app.add_option("--alignment-threshold", options.alignment_max_error_ratio,
                 "Inlier distance of the alignment, as a fraction of the GT scene scale")
      ->capture_default_str();
  VerbosityFlags flags;
  AddVerbosityFlags(app, &flags);
  return RunCommand(app, argc, argv, flags, [&] {
    if (!std::filesystem::is_directory(model_path)) {
      throw InputError(model_path + ": model folder does not exist");
    }
    const Reconstruction model = ReadReconstruction(model_path);
    const GroundTruth gt = ReadGroundTruth(gt_path);
    const EvaluationMetrics metrics = EvaluateReconstruction(model, gt, options);
    if (json) {
      std::cout << MetricsToJson(metrics).dump(2) << std::endl;
    } else {
      std::cout << "Model " << model_path << " vs. ground truth " << gt.source << "\n"
                << MetricsToText(metrics) << std::flush;
    }
    return 0;
  });
}

}  // namespace parallax::cli
