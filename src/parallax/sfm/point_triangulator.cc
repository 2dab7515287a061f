#include "parallax/sfm/point_triangulator.h"

#include <set>

#include "parallax/estimators/bundle_adjustment.h"
#include "parallax/sfm/model_builder.h"
#include "parallax/util/check.h"
#include "parallax/util/logging.h"
#include "parallax/util/progress.h"

namespace parallax {

Reconstruction TriangulateIntoPoses(const IncrementalMapperOptions& options,
                                    const MapperInput& input, const Reconstruction& posed,
                                    MapperSummary* summary) {
  ProgressReporter progress("triangulating", posed.NumRegImages());
  const std::set<image_t> no_used_images;
  ModelBuilder builder(options, input, no_used_images, summary, &progress);
  if (!builder.InitializeFromModel(posed)) {
    throw InputError(
        "point triangulation needs at least two posed images that the database "
        "holds; " +
        std::to_string(posed.NumRegImages()) + " posed, fewer found");
  }
  builder.CompleteTracks();
  builder.FilterObservations();
  // Poses and intrinsics as given: only the points move (COLMAP fixes the existing images).
  BundleAdjustmentConfig config = WholeModelConfig(builder.Model(), /*fix_poses=*/true);
  for (const auto& [camera_id, camera] : builder.Model().Cameras()) {
    config.constant_cameras.insert(camera_id);
  }
  const BundleAdjustmentSummary adjustment =
      BundleAdjust(options.final_ba, config, &builder.Model());
  summary->phase_seconds.global_ba += adjustment.seconds;
  builder.FilterObservations();
  progress.Finish();
  Reconstruction& model = builder.Model();
  model.UpdatePointErrors();
  summary->models.resize(1);
  summary->models[0].num_images = model.NumRegImages();
  summary->models[0].num_points = model.NumPoints3D();
  for (const auto& [image_id, image] : model.Images()) {
    MapperImageReport& report = summary->images[image_id];
    if (image.registered) {
      report.model_index = 0;
      report.error_after_ba_px = model.MeanReprojectionErrorOfImage(image_id);
    } else {
      report.reason = "not in the posed model (point triangulation registers no image)";
    }
  }
  PARALLAX_LOG(Info) << "mapper: " << model.NumPoints3D() << " points triangulated into "
                     << model.NumRegImages() << " fixed poses";
  return model;
}

}  // namespace parallax
