#include "parallax/sfm/incremental_mapper.h"

#include <algorithm>
#include <map>
#include <optional>
#include <set>
#include <sstream>
#include <string>

#include "parallax/sfm/initial_pair.h"
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

// Each model's verified pairs with the images of every other (summary->models and the images'
// model_index set).
void LinkModels(const MapperInput& input, MapperSummary* summary) {
  std::map<std::pair<int, int>, ModelLink> links;
  for (const auto& [pair_id, geometry] : input.two_view_geometries) {
    const auto [image_id1, image_id2] = PairIdToImagePair(pair_id);
    const auto it1 = summary->images.find(image_id1);
    const auto it2 = summary->images.find(image_id2);
    if (it1 == summary->images.end() || it2 == summary->images.end()) continue;
    const int model1 = it1->second.model_index, model2 = it2->second.model_index;
    if (model1 < 0 || model2 < 0 || model1 == model2) continue;
    for (const auto& [from, to] : {std::pair(model1, model2), std::pair(model2, model1)}) {
      ModelLink& link = links[{from, to}];
      link.model_index = to;
      ++link.num_image_pairs;
      link.num_matches += geometry.inlier_matches.size();
    }
  }
  for (const auto& [models, link] : links) summary->models[models.first].links.push_back(link);
  for (MapperModelReport& report : summary->models) {
    std::stable_sort(
        report.links.begin(), report.links.end(),
        [](const ModelLink& a, const ModelLink& b) { return a.num_matches > b.num_matches; });
  }
}

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
// since the last; then a last pass at relaxed PnP bars; the final robust adjustment ends
// the model.
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
    // The last pass: what is left, against lower bars.
    if (!builder->RegistrationRelaxed() && builder->ImagesLeftToRegister()) {
      builder->RelaxRegistration();
      trials.clear();
      if (!builder->NextImages(trials).empty()) continue;
    }
    break;
  }
  builder->AdjustGlobalBundle(/*final=*/true);
}

// Joins the run's models by the tracks they share (JoinModels), then grows the joined one
// from its poses: all tracks triangulated anew, the seams adjusted, the images no model
// holds registered against the whole. Models left apart stay as they were.
void JoinAndGrow(const IncrementalMapperOptions& options, const MapperInput& input,
                 MapperSummary* summary, ProgressReporter* progress,
                 std::vector<Reconstruction>* models, std::vector<MapperModelReport>* starts) {
  std::vector<ModelJoinReport> reports;
  const Reconstruction joined =
      JoinModels(options.join, *models, input.correspondence_graph, &reports);
  std::set<image_t> apart_images;  // Of the models left apart: the joined model leaves them.
  size_t frame = 0;                // The largest model, whose start the joined one reports.
  int num_joined = 0;
  for (size_t index = 0; index < models->size(); ++index) {
    if ((*models)[index].NumRegImages() > (*models)[frame].NumRegImages()) frame = index;
    if (reports[index].joined) {
      ++num_joined;
    } else {
      for (const image_t image_id : (*models)[index].RegImageIds()) apart_images.insert(image_id);
    }
  }
  if (num_joined < 2) return;
  ModelBuilder builder(options, input, apart_images, summary, progress);
  if (!builder.InitializeFromModel(joined, ModelBuilder::SeedKind::kJoined)) return;
  PARALLAX_LOG(Info) << "mapper: joined " << num_joined << " models (" << joined.NumRegImages()
                     << " images); registering the rest against them";
  builder.AdjustGlobalBundle();
  GrowModel(&builder, summary);
  std::vector<Reconstruction> kept = {ExtractRegisteredModel(builder.Model())};
  std::vector<MapperModelReport> kept_starts = {(*starts)[frame]};
  kept_starts.front().num_joined_models = num_joined;
  for (size_t index = 0; index < models->size(); ++index) {
    if (reports[index].joined) continue;
    kept.push_back(std::move((*models)[index]));
    kept_starts.push_back((*starts)[index]);
  }
  *models = std::move(kept);
  *starts = std::move(kept_starts);
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
  std::vector<MapperModelReport> starts;  // How each kept model started.
  std::set<image_t> used_images;          // Registered in a kept model.
  InitialPairLedger ledger;
  // Registrations over all models; images that never register leave it short of the total.
  std::optional<ProgressReporter> own_progress;
  if (progress_ == nullptr) own_progress.emplace("mapping", input_.images.size());
  ProgressReporter& progress = progress_ != nullptr ? *progress_ : *own_progress;
  while (static_cast<int>(models.size()) < options_.max_num_models) {
    ModelBuilder builder(options_, input_, used_images, summary, &progress);
    const bool seeded = seed != nullptr && models.empty() && summary->num_discarded_models == 0 &&
                        builder.InitializeFromModel(*seed);
    if (!seeded && !builder.InitializeFromBestPair(&ledger)) break;
    GrowModel(&builder, summary);
    Reconstruction& model = builder.Model();
    const size_t num_registered = model.NumRegImages();
    PARALLAX_LOG(Info) << "mapper: model " << models.size() << " has " << num_registered
                       << " images and " << model.NumPoints3D() << " points";
    if (static_cast<int>(num_registered) >= options_.min_model_size) {
      for (const image_t image_id : model.RegImageIds()) used_images.insert(image_id);
      models.push_back(ExtractRegisteredModel(model));
      starts.emplace_back();
      starts.back().start = builder.Start();
    } else {
      // A start that went nowhere: its images stay free for later models to register, but
      // start none themselves.
      for (const image_t image_id : model.RegImageIds()) {
        ledger.failed_start_images.insert(image_id);
      }
      ++summary->num_discarded_models;
      PARALLAX_LOG(Info) << "mapper: discarded (fewer than " << options_.min_model_size
                         << " images); trying another initial pair";
      continue;
    }
    if (!options_.multiple_models) break;
  }
  if (models.size() >= 2 && options_.join_models) {
    JoinAndGrow(options_, input_, summary, &progress, &models, &starts);
  }
  if (own_progress) own_progress->Finish();
  std::vector<size_t> order(models.size());
  for (size_t i = 0; i < order.size(); ++i) order[i] = i;
  std::stable_sort(order.begin(), order.end(), [&models](size_t a, size_t b) {
    return models[a].NumRegImages() > models[b].NumRegImages();
  });
  {
    std::vector<Reconstruction> sorted;
    for (const size_t i : order) {
      sorted.push_back(std::move(models[i]));
      summary->models.push_back(starts[i]);
    }
    models = std::move(sorted);
  }

  for (size_t index = 0; index < models.size(); ++index) {
    Reconstruction& model = models[index];
    model.UpdatePointErrors();
    summary->models[index].num_images = model.NumRegImages();
    summary->models[index].num_points = model.NumPoints3D();
    for (const image_t image_id : model.RegImageIds()) {
      MapperImageReport& report = summary->images[image_id];
      report.model_index = static_cast<int>(index);
      report.reason.clear();
      report.error_after_ba_px = model.MeanReprojectionErrorOfImage(image_id);
    }
  }
  LinkModels(input_, summary);
  for (auto& [image_id, report] : summary->images) {
    if (report.model_index >= 0 || !report.reason.empty()) continue;
    if (input_.correspondence_graph.NeighborsOf(image_id).empty()) {
      report.reason = "no verified matches with any other image";
    } else if (ledger.failed_start_images.count(image_id)) {  // Only in discarded models.
      report.reason = "its model had fewer than " + std::to_string(options_.min_model_size) +
                      " images and was discarded";
    } else {
      report.reason =
          "never connected to a reconstructed image (matched only with images "
          "that were not registered)";
    }
  }
  if (models.empty()) {
    const InitThresholds loosest = InitThresholdSchedule(options_).back();
    std::ostringstream failure;
    failure << "no initial image pair has enough verified matches ("
            << options_.init_min_num_inliers << ") with enough triangulation angle ("
            << options_.init_min_triangulation_angle_deg << " deg), even relaxed to "
            << loosest.min_num_inliers << " and " << loosest.min_angle_deg << " deg";
    if (summary->num_discarded_models > 0) {
      failure << "; " << summary->num_discarded_models << " starts ended below "
              << options_.min_model_size << " images";
    }
    summary->failure = failure.str();
  }
  for (size_t index = 0; index < models.size(); ++index) {
    const MapperModelReport& report = summary->models[index];
    std::ostringstream links;
    for (const ModelLink& link : report.links) {
      links << (links.tellp() == 0 ? "; linked to " : ", ") << "model " << link.model_index
            << " by " << link.num_image_pairs << " image pairs (" << link.num_matches
            << " matches)";
    }
    PARALLAX_LOG(Info) << "mapper: model " << index << ": " << report.num_images << " images, "
                       << report.num_points << " points" << links.str();
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
