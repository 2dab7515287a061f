#include "parallax/sfm/incremental_mapper.h"

#include <algorithm>
#include <map>
#include <optional>
#include <set>
#include <sstream>
#include <string>

#include "parallax/sfm/model_builder.h"
#include "parallax/util/check.h"
#include "parallax/util/interrupt.h"
#include "parallax/util/logging.h"
#include "parallax/util/progress.h"
#include "parallax/util/timer.h"

namespace parallax {

Reconstruction ExtractRegisteredModel(const Reconstruction& reconstruction) {
  Reconstruction model;
  std::set<camera_t> camera_ids;
  for (const auto& [image_id, image] : reconstruction.Images()) {
    if (image.registered) camera_ids.insert(image.camera_id);
  }
  for (camera_t camera_id : camera_ids) model.AddCamera(reconstruction.GetCamera(camera_id));
  for (const auto& [image_id, image] : reconstruction.Images()) {
    if (!image.registered) continue;
    Image copy = image;
    for (Point2D& point : copy.points2D) point.point3D_id = kInvalidPoint3DId;
    model.AddImage(std::move(copy));
    model.RegisterImage(image_id);
  }
  for (const auto& [point3D_id, point] : reconstruction.Points3D()) {
    model.AddPoint3DWithId(point3D_id, point);
  }
  return model;
}

namespace {

// Registers the best-ranked image that registers, then adjusts around it. False when none of
// the candidates registers; each attempt counts in `trials` and the image's report.
bool RegisterNextImage(ModelBuilder* builder, MapperSummary* summary,
                       std::map<image_t, int>* trials) {
  for (const image_t image_id : builder->NextImages(*trials)) {
    MapperImageReport& report = summary->images[image_id];
    ++report.num_registration_trials;
    ++(*trials)[image_id];
    if (builder->RegisterImage(image_id, &report)) {
      builder->AdjustAfterRegistration(image_id);
      return true;
    }
    PARALLAX_LOG(Debug) << "mapper: image " << image_id << " not registered: " << report.reason;
  }
  return false;
}

// The paper's Algorithm 1 after initialisation: register the next best view (triangulating
// and adjusting as it goes) until none registers; then one global adjustment and
// re-triangulation may make room for more, unless every image is in or nothing changed
// since the last; the final robust adjustment ends the model.
void GrowModel(ModelBuilder* builder, MapperSummary* summary) {
  std::map<image_t, int> trials;
  while (true) {
    // Between registrations the model is consistent, and nothing is written until the
    // mapper returns: a signal here leaves the outputs of the last finished run as they were.
    ThrowIfInterrupted("mapping stopped after " + std::to_string(builder->Model().NumRegImages()) +
                       " registered images; no model was written");
    if (RegisterNextImage(builder, summary, &trials)) continue;
    if (builder->ImagesLeftToRegister() && builder->GrewSinceGlobalAdjustment()) {
      builder->AdjustGlobalBundle();
      trials.clear();
      if (!builder->NextImages(trials).empty()) continue;
    }
    break;
  }
  builder->AdjustGlobalBundle(/*final=*/true);
}

}  // namespace

IncrementalMapper::IncrementalMapper(const IncrementalMapperOptions& options,
                                     const MapperInput& input)
    : options_(options), input_(input) {
  options_.Check();
}

std::vector<Reconstruction> IncrementalMapper::Reconstruct(MapperSummary* summary) {
  return Run(nullptr, summary);
}

std::vector<Reconstruction> IncrementalMapper::Extend(const Reconstruction& seed,
                                                      MapperSummary* summary) {
  return Run(&seed, summary);
}

std::vector<Reconstruction> IncrementalMapper::Run(const Reconstruction* seed,
                                                   MapperSummary* summary) {
  PARALLAX_CHECK(summary != nullptr);
  Timer timer;
  *summary = MapperSummary();
  for (const auto& [image_id, image] : input_.images) summary->images[image_id];

  std::vector<Reconstruction> models;
  std::set<image_t> used_images;
  // Registrations over all models; images that never register leave it short of the total.
  std::optional<ProgressReporter> own_progress;
  if (progress_ == nullptr) own_progress.emplace("mapping", input_.images.size());
  ProgressReporter& progress = progress_ != nullptr ? *progress_ : *own_progress;
  while (static_cast<int>(models.size()) < options_.max_num_models) {
    ModelBuilder builder(options_, input_, used_images, summary, &progress);
    const bool seeded = seed != nullptr && models.empty() && builder.InitializeFromModel(*seed);
    if (!seeded && !builder.InitializeFromBestPair()) break;
    GrowModel(&builder, summary);
    Reconstruction& model = builder.Model();
    const size_t num_registered = model.NumRegImages();
    PARALLAX_LOG(Info) << "mapper: model " << models.size() << " has " << num_registered
                       << " images and " << model.NumPoints3D() << " points";
    for (const image_t image_id : model.RegImageIds()) used_images.insert(image_id);
    if (static_cast<int>(num_registered) >= options_.min_model_size) {
      models.push_back(ExtractRegisteredModel(model));
    }
    if (!options_.multiple_models) break;
  }
  if (own_progress) own_progress->Finish();
  std::stable_sort(models.begin(), models.end(), [](const auto& a, const auto& b) {
    return a.NumRegImages() > b.NumRegImages();
  });

  for (size_t index = 0; index < models.size(); ++index) {
    Reconstruction& model = models[index];
    model.UpdatePointErrors();
    for (const image_t image_id : model.RegImageIds()) {
      MapperImageReport& report = summary->images[image_id];
      report.model_index = static_cast<int>(index);
      report.reason.clear();
      report.error_after_ba_px = model.MeanReprojectionErrorOfImage(image_id);
    }
  }
  for (auto& [image_id, report] : summary->images) {
    if (report.model_index >= 0 || !report.reason.empty()) continue;
    if (input_.correspondence_graph.NeighborsOf(image_id).empty()) {
      report.reason = "no verified matches with any other image";
    } else if (used_images.count(image_id)) {
      report.reason = "its model had fewer than " + std::to_string(options_.min_model_size) +
                      " images and was discarded";
    } else {
      report.reason =
          "never connected to a reconstructed image (matched only with images "
          "that were not registered)";
    }
  }
  if (models.empty()) {
    summary->failure = "no initial image pair has enough verified matches (" +
                       std::to_string(options_.init_min_num_inliers) +
                       ") with enough triangulation angle";
  }
  summary->seconds = timer.ElapsedSeconds();
  std::ostringstream phases;
  for (const auto& [name, seconds] : summary->phase_seconds.Named()) {
    phases << ", " << name << " " << seconds << " s";
  }
  PARALLAX_LOG(Info) << "mapper: " << summary->seconds << " s" << phases.str();
  return models;
}

}  // namespace parallax
