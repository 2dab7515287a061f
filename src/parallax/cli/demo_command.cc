#include <iomanip>
#include <iostream>

#include "parallax/cli/cli_common.h"
#include "parallax/cli/commands.h"
#include "parallax/pipeline/reconstruction_pipeline.h"
#include "parallax/render/synthetic_scene.h"
#include "parallax/report/evaluation.h"
#include "parallax/util/file.h"
#include "parallax/util/timer.h"

namespace parallax::cli {

// The embedded default: no data needed. Synthesises a textured temple seen from a ring of
// cameras, reconstructs it with the exact K, evaluates against the exact cameras and writes
// the report.
int RunDemo(int argc, char** argv) {
  CLI::App app("Synthesise a scene, reconstruct it, evaluate it against the exact cameras",
               "parallax demo");
  std::string output_dir = "parallax-demo";
  SyntheticSceneOptions scene;
  scene.num_views = 30;
  app.add_option("--output", output_dir, "Output folder")->capture_default_str();
  app.add_option("--views", scene.num_views, "Number of synthetic views")
      ->capture_default_str()
      ->check(CLI::Range(3, 2000));
  app.add_option("--seed", scene.seed, "Seed of the scene")->capture_default_str();
  VerbosityFlags flags;
  AddVerbosityFlags(app, &flags);
  return RunCommand(app, argc, argv, flags, [&] {
    const std::filesystem::path output(output_dir);
    const std::filesystem::path scene_dir = output / "scene";
    Timer total_timer;

    Timer timer;
    GenerateSyntheticScene(scene, scene_dir);
    const double synth_seconds = timer.ElapsedSeconds();

    ReconstructionPipelineOptions options;
    options.extraction.camera.intrinsics_path = scene_dir / "K.txt";
    options.extraction.camera.single_camera = true;
    options.ground_truth_path = scene_dir / (scene.name + "_par.txt");
    options.write_report = true;
    options.report_title =
        "Parallax demo: synthetic temple, " + std::to_string(scene.num_views) + " views";
    SetSeed(scene.seed, &options);
    const ReconstructionPipelineResult result =
        RunReconstructionPipeline(options, scene_dir, output / "reconstruction");
    if (!result.Success()) {
      std::cerr << "error: demo scene could not be reconstructed: "
                << result.mapping.summary.failure << std::endl;
      return 1;
    }
    std::cout << MetricsToText(*result.evaluation) << "\n";
    std::cout << std::fixed << std::setprecision(2) << "demo: rendered " << scene.num_views
              << " views in " << synth_seconds << " s; reconstructed in "
              << result.summary["timings_s"]["total"].get<double>() << " s; total "
              << total_timer.ElapsedSeconds() << " s\n"
              << "demo: report " << result.report_path.string() << std::endl;
    return 0;
  });
}

}  // namespace parallax::cli
