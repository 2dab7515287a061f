#include <iostream>

#include "parallax/cli/cli_common.h"
#include "parallax/cli/commands.h"
#include "parallax/report/report_folder.h"

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
    ReportFolderOptions options;
    options.output_dir = output;
    options.model_dir = model_path;
    options.database_path = database_path;
    options.image_dir = image_path;
    options.ground_truth_path = gt_path;
    const fs::path report_path = WriteReportOfOutputFolder(options);
    std::cout << "Wrote " << report_path.string() << " (" << fs::file_size(report_path) / 1024
              << " KiB)" << std::endl;
    return 0;
  });
}

}  // namespace parallax::cli
