#include <iostream>

#include "parallax/cli/cli_common.h"
#include "parallax/cli/commands.h"
#include "parallax/cli/mapper_options_cli.h"
#include "parallax/cli/pipeline_options_cli.h"
#include "parallax/distributed/distributed_stages.h"
#include "parallax/pipeline/reconstruction_pipeline.h"
#include "parallax/util/logging.h"

namespace parallax::cli {

int RunReconstruct(int argc, char** argv) {
  CLI::App app("Reconstruct cameras and a sparse point cloud from a folder of photos",
               "parallax reconstruct");
  std::string image_dir, output_dir, database_path;
  uint64_t seed = 0;
  int num_threads = -1;
  ReconstructionPipelineOptions options;
  app.add_option("--images", image_dir, "Folder of images (not recursive)")->required();
  app.add_option("--output", output_dir,
                 "Output folder: sparse/<k>/, points.ply, summary.json, database.db")
      ->required();
  app.add_option("--database", database_path,
                 "Database to use or resume (default OUT/database.db)");
  app.add_option("--threads", num_threads, "Worker threads for every stage (-1: all cores)")
      ->capture_default_str();
  AddSeedOption(app, &seed);
  app.add_flag("--report", options.write_report, "Also write OUT/report.html");
  app.add_flag("!--remap", options.extend_model_with_new_photos,
               "Map all photos from scratch even when OUT holds the model of an earlier run and "
               "only photos were added (default: the new photos are registered into it)");
  AddReconstructionOptions(app, &options);
  VerbosityFlags flags;
  AddVerbosityFlags(app, &flags);
  // Under mpirun or srun with more than one rank the stages are shared among the ranks
  // (distributed/distributed_stages.h); otherwise this is a group of one and nothing changes.
  const ProcessGroup group;
  const int status = RunCommand(app, argc, argv, flags, [&] {
    SetSeedAndThreads(seed, num_threads, app.count("--ba-threads") > 0, &options);
    options.database_path = database_path;
    std::optional<DistributedStages> stages;
    if (group.IsDistributed()) {
      stages.emplace(group, output_dir);
      // The other ranks' progress is the coordinator's to tell.
      if (!group.IsCoordinator() && !flags.verbose) SetLogLevel(LogLevel::kWarning);
      // Mapping is shared out by clusters, which the incremental mapper does not have.
      if (app.count("--mapper") == 0) {
        options.mapping.mapper_type = MapperType::kHierarchical;
        options.mapping.mapper_type_reason =
            "a distributed run maps clusters on its ranks (--mapper incremental maps on the "
            "first rank alone)";
      }
      if (group.IsCoordinator()) {
        PARALLAX_LOG(Info) << "distributed run: " << group.Size() << " ranks, shards in "
                           << (std::filesystem::path(output_dir) / "shards").string() << "; "
                           << (options.mapping.mapper_type == MapperType::kHierarchical
                                   ? "hierarchical"
                                   : "incremental")
                           << " mapper"
                           << (options.mapping.mapper_type_reason.empty()
                                   ? std::string(" (--mapper)")
                                   : ": " + options.mapping.mapper_type_reason);
      }
    }
    const ReconstructionPipelineResult result =
        RunReconstructionPipeline(options, image_dir, output_dir, stages ? &*stages : nullptr);
    if (stages) {
      for (const std::string& line : stages->RankReport()) PARALLAX_LOG(Info) << line;
    }
    if (!group.IsCoordinator()) return 0;
    PrintMappingResult(result.mapping, output_dir);
    if (!result.Success()) {
      std::cerr << "error: " << image_dir
                << ": no model could be started: " << result.mapping.summary.failure << std::endl;
      return 1;
    }
    if (!result.report_path.empty()) std::cout << "report: " << result.report_path.string() << "\n";
    double total = 0;
    for (const auto& [stage, seconds] : result.timings) {
      std::cout << stage << ": " << seconds << " s\n";
      total += seconds;
    }
    std::cout << "total: " << total
              << " s; summary: " << (std::filesystem::path(output_dir) / "summary.json").string()
              << std::endl;
    return 0;
  });
  // A rank that failed ends the job: the others may be waiting for it.
  if (status != 0 && group.IsDistributed()) group.Abort(status);
  return status;
}

}  // namespace parallax::cli
