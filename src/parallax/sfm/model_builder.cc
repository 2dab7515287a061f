#include "parallax/sfm/model_builder.h"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <string>
#include <utility>

#include "parallax/math/random.h"
#include "parallax/sfm/observation_filter.h"
#include "parallax/sfm/point_completion.h"
#include "parallax/sfm/retriangulation.h"
#include "parallax/sfm/track_triangulation.h"
#include "parallax/util/logging.h"
#include "parallax/util/timer.h"

namespace parallax {

namespace {

std::string FormatDegrees(double degrees) {
  std::ostringstream stream;
  stream << degrees << " deg";
  return stream.str();
}

// The input's cameras and images, none registered yet.
Reconstruction Unregistered(const MapperInput& input) {
  Reconstruction reconstruction;
  for (const auto& [camera_id, camera] : input.cameras) reconstruction.AddCamera(camera);
  for (const auto& [image_id, image] : input.images) reconstruction.AddImage(image);
  return reconstruction;
}

}  // namespace

ModelBuilder::ModelBuilder(const IncrementalMapperOptions& options, const MapperInput& input,
                           const std::set<image_t>& used_images, MapperSummary* summary,
                           ProgressReporter* progress)
    : options_(options),
      input_(input),
      used_images_(used_images),
      summary_(summary),
      progress_(progress),
      reconstruction_(Unregistered(input)),
      model_(input.correspondence_graph, &reconstruction_),
      visibility_(&model_) {}

bool ModelBuilder::InitializeFromBestPair(InitialPairLedger* ledger) {
  InitialPairLedger own_ledger;
  if (ledger == nullptr) ledger = &own_ledger;
  std::vector<std::pair<image_pair_t, const TwoViewGeometry*>> candidates;
  const std::vector<InitThresholds> schedule = InitThresholdSchedule(options_);
  const int fewest_inliers = schedule.back().min_num_inliers;
  for (const auto& [pair_id, geometry] : input_.two_view_geometries) {
    const auto [image_id1, image_id2] = PairIdToImagePair(pair_id);
    if (used_images_.count(image_id1) || used_images_.count(image_id2)) continue;
    if (geometry.config == TwoViewGeometry::kPanoramic || ledger->started.count(pair_id)) continue;
    if (ledger->failed_start_images.count(image_id1) &&
        ledger->failed_start_images.count(image_id2)) {
      continue;
    }
    if (static_cast<int>(geometry.inlier_matches.size()) < fewest_inliers) continue;
    candidates.emplace_back(pair_id, &geometry);
  }
  std::stable_sort(candidates.begin(), candidates.end(), [](const auto& a, const auto& b) {
    return a.second->inlier_matches.size() > b.second->inlier_matches.size();
  });
  int num_pairs_tried = 0;
  for (const InitThresholds& thresholds : schedule) {
    // Every candidate is held to the step's thresholds (each is triangulated once, in the
    // ledger); the trials are the pairs that met them and were adjusted. A cap on candidates
    // instead left a forward walk's wide pairs, past the 200 with most inliers, untried.
    int trials = 0;
    for (const auto& [pair_id, geometry] : candidates) {
      // Sorted by inliers: the rest have too few for this step.
      if (static_cast<int>(geometry->inlier_matches.size()) < thresholds.min_num_inliers) break;
      if (trials >= options_.init_max_trials) break;
      ++num_pairs_tried;
      bool met_thresholds = false;
      if (InitializeFromPair(pair_id, *geometry, thresholds, ledger, &met_thresholds)) {
        start_.num_pairs_tried = num_pairs_tried - 1;
        return true;
      }
      if (met_thresholds) ++trials;
    }
    PARALLAX_LOG(Debug) << "mapper: no initial pair with " << thresholds.min_num_inliers
                        << " inliers at a median angle of " << thresholds.min_angle_deg << " deg";
  }
  return false;
}

// Starts from the registered images of `seed` that this input holds and no earlier model
// used, with the seed's poses and intrinsics; every track they see is triangulated anew.
// False (and nothing registered) when fewer than two qualify. The seed is a finished,
// adjusted model: as COLMAP's mapper does with --input_path, it is not adjusted again
// before the new images come in (see AdjustAfterRegistration).
bool ModelBuilder::InitializeFromModel(const Reconstruction& seed, SeedKind kind) {
  for (const auto& [camera_id, camera] : seed.Cameras()) {
    if (reconstruction_.ExistsCamera(camera_id)) {
      reconstruction_.GetCamera(camera_id).params = camera.params;
    }
  }
  std::vector<image_t> seeded;
  for (const image_t image_id : seed.RegImageIds()) {
    if (!reconstruction_.ExistsImage(image_id) || !Available(image_id)) continue;
    reconstruction_.GetImage(image_id).cam_from_world = seed.GetImage(image_id).cam_from_world;
    reconstruction_.RegisterImage(image_id);
    seeded.push_back(image_id);
  }
  if (seeded.size() < 2) {
    for (const image_t image_id : seeded) reconstruction_.DeRegisterImage(image_id);
    return false;
  }
  init_image_id1_ = seeded[0];
  init_image_id2_ = seeded[1];
  size_t num_observations = 0;
  {
    const ScopedTimer timer(&summary_->phase_seconds.completion);
    num_observations = CompleteAllTracks(options_.triangulation, &model_);
  }
  PARALLAX_LOG(Info) << "mapper: starting from " << seeded.size() << " posed images, "
                     << num_observations << " observations triangulated";
  // As for registered images: the error before any adjustment that includes the image.
  for (const image_t image_id : seeded) {
    summary_->images[image_id].error_before_ba_px =
        reconstruction_.MeanReprojectionErrorOfImage(image_id);
  }
  images_at_last_global_ba_ = reconstruction_.NumRegImages();
  points_at_last_global_ba_ = reconstruction_.NumPoints3D();
  start_ = ModelStartReport();
  start_.from_input_model = true;
  if (kind == SeedKind::kAdjusted) {
    num_seed_images_ = seeded.size();
    progress_->Increment(seeded.size());
  }
  return true;
}

bool ModelBuilder::Available(image_t image_id) const { return !used_images_.count(image_id); }

bool ModelBuilder::ImagesLeftToRegister() const {
  for (const auto& [image_id, image] : reconstruction_.Images()) {
    if (!image.registered && Available(image_id)) return true;
  }
  return false;
}

bool ModelBuilder::InitializeFromPair(image_pair_t pair_id, const TwoViewGeometry& geometry,
                                      const InitThresholds& thresholds, InitialPairLedger* ledger,
                                      bool* met_thresholds) {
  const auto [image_id1, image_id2] = PairIdToImagePair(pair_id);
  const Image& image1 = reconstruction_.GetImage(image_id1);
  const Image& image2 = reconstruction_.GetImage(image_id2);
  InitialPairLedger own_ledger;  // A pair tried alone is evaluated and forgotten.
  if (ledger == nullptr) ledger = &own_ledger;
  auto it = ledger->evaluations.find(pair_id);
  if (it == ledger->evaluations.end()) {
    it =
        ledger->evaluations
            .emplace(pair_id, EvaluateInitialPair(reconstruction_, pair_id, geometry,
                                                  options_.triangulation.max_reprojection_error_px))
            .first;
  }
  const InitialPairEvaluation* evaluation = &it->second;
  if (!evaluation->has_pose) return false;
  if (evaluation->num_triangulated < thresholds.min_num_inliers) {
    PARALLAX_LOG(Debug) << "mapper: initial pair " << image1.name << " + " << image2.name << ": "
                        << evaluation->num_triangulated << " of " << geometry.inlier_matches.size()
                        << " inliers triangulate";
    return false;
  }
  if (evaluation->median_angle_deg < thresholds.min_angle_deg) {
    PARALLAX_LOG(Debug) << "mapper: initial pair " << image1.name << " + " << image2.name
                        << ": median angle " << evaluation->median_angle_deg << " deg, below "
                        << thresholds.min_angle_deg;
    return false;
  }
  // Tried once: a pair that fails from here on would fail again.
  ledger->started.insert(pair_id);
  if (met_thresholds != nullptr) *met_thresholds = true;

  reconstruction_.GetImage(image_id1).cam_from_world = Rigid3d();
  reconstruction_.GetImage(image_id2).cam_from_world = evaluation->cam2_from_cam1;
  reconstruction_.RegisterImage(image_id1);
  reconstruction_.RegisterImage(image_id2);
  init_image_id1_ = image_id1;
  init_image_id2_ = image_id2;
  TriangulateImage(image_id1);
  for (const image_t image_id : {image_id1, image_id2}) {
    summary_->images[image_id].error_before_ba_px =
        reconstruction_.MeanReprojectionErrorOfImage(image_id);
  }
  AdjustGlobalBundle();
  if (static_cast<int>(reconstruction_.NumPoints3D()) < thresholds.min_num_inliers / 2) {
    PARALLAX_LOG(Debug) << "mapper: initial pair " << image_id1 << "-" << image_id2
                        << " kept too few points after adjustment";
    reconstruction_.DeRegisterImage(image_id1);
    reconstruction_.DeRegisterImage(image_id2);
    return false;
  }
  start_ = ModelStartReport();
  start_.image_id1 = image_id1;
  start_.image_id2 = image_id2;
  start_.thresholds = thresholds;
  start_.num_triangulated = evaluation->num_triangulated;
  start_.median_angle_deg = evaluation->median_angle_deg;
  const std::string relaxed =
      thresholds.step == 0 ? ""
                           : ", thresholds relaxed (step " + std::to_string(thresholds.step) +
                                 ") to " + std::to_string(thresholds.min_num_inliers) +
                                 " inliers and " + FormatDegrees(thresholds.min_angle_deg);
  PARALLAX_LOG(Info) << "mapper: initial pair " << image1.name << " + " << image2.name << " ("
                     << geometry.inlier_matches.size() << " inliers, median angle "
                     << evaluation->median_angle_deg << " deg, " << reconstruction_.NumPoints3D()
                     << " points" << relaxed << ")";
  progress_->Increment(2);
  return true;
}

// Unregistered images connected to the model, best first.
std::vector<image_t> ModelBuilder::NextImages(const std::map<image_t, int>& trials) {
  const ScopedTimer timer(&summary_->phase_seconds.next_view);
  // Each image's registered neighbours are counted as registrations come and go: walking
  // every registered image's neighbours before each registration grew as the square of the
  // number of images (docs/mapper-scaling.md, "Figures").
  const std::map<image_t, Image>& images = reconstruction_.Images();
  const size_t id_end = images.empty() ? 0 : images.rbegin()->first + 1;
  registered_neighbors_.resize(id_end, 0);
  counted_as_registered_.resize(id_end, 0);
  for (const auto& [image_id, image] : images) {
    if (image.registered == static_cast<bool>(counted_as_registered_[image_id])) continue;
    counted_as_registered_[image_id] = image.registered;
    const int delta = image.registered ? 1 : -1;
    for (const auto& [neighbor, count] : input_.correspondence_graph.NeighborsOf(image_id)) {
      if (neighbor < id_end) registered_neighbors_[neighbor] += delta;
    }
  }
  std::vector<image_t> connected;
  for (const auto& [image_id, image] : images) {
    if (registered_neighbors_[image_id] > 0 && !image.registered && Available(image_id)) {
      connected.push_back(image_id);
    }
  }
  visibility_.Update();
  std::vector<std::pair<double, image_t>> scored;
  for (const image_t image_id : connected) {
    const auto it = trials.find(image_id);
    if (it != trials.end() && it->second >= options_.max_registration_trials) continue;
    const double score = visibility_.Score(image_id);
    if (score > 0) scored.emplace_back(score, image_id);
  }
  std::stable_sort(scored.begin(), scored.end(),
                   [](const auto& a, const auto& b) { return a.first > b.first; });
  std::vector<image_t> ranked;
  for (const auto& [score, image_id] : scored) ranked.push_back(image_id);
  return ranked;
}

// RegisterImage, its time counted as registration apart from the triangulation it ends with.
bool ModelBuilder::RegisterImage(image_t image_id, MapperImageReport* report) {
  MapperPhaseSeconds& phases = summary_->phase_seconds;
  const double triangulation_before = phases.triangulation;
  const Timer timer;
  const bool registered = EstimatePoseAndRegister(image_id, report);
  phases.registration += timer.ElapsedSeconds() - (phases.triangulation - triangulation_before);
  return registered;
}

void ModelBuilder::TriangulateImage(image_t image_id) {
  const ScopedTimer timer(&summary_->phase_seconds.triangulation);
  parallax::TriangulateImage(options_.triangulation, image_id, &model_);
}

bool ModelBuilder::EstimatePoseAndRegister(image_t image_id, MapperImageReport* report) {
  Image& image = reconstruction_.GetImage(image_id);
  const Camera& camera = reconstruction_.GetCamera(image.camera_id);
  std::vector<Eigen::Vector2d> points2D;
  std::vector<Eigen::Vector3d> points3D;
  std::vector<std::pair<point2D_t, point3D_t>> links;
  // Every point of the keypoint's track (more than one where its elements disagreed);
  // RANSAC sorts them out. Points its correspondences alone lead to are left out: on the
  // 300-view aerial survey they cost 9 % in median rotation error (docs/defaults.md,
  // "Registration sees its tracks' points").
  const track_t* tracks = input_.correspondence_graph.TracksOfImage(image_id);
  for (point2D_t idx = 0; idx < image.points2D.size(); ++idx) {
    if (tracks[idx] == kInvalidTrackId) continue;
    const std::vector<point3D_t> point3D_ids = model_.PointsOfTrack(tracks[idx]);
    for (const point3D_t point3D_id : point3D_ids) {
      points2D.push_back(image.points2D[idx].xy);
      points3D.push_back(reconstruction_.GetPoint3D(point3D_id).xyz);
      links.emplace_back(idx, point3D_id);
    }
  }
  report->num_visible_points = points2D.size();
  const size_t min_inliers =
      static_cast<size_t>(relaxed_registration_ ? options_.relaxed_absolute_pose_min_num_inliers
                                                : options_.absolute_pose_min_num_inliers);
  const double min_inlier_ratio = relaxed_registration_
                                      ? options_.relaxed_absolute_pose_min_inlier_ratio
                                      : options_.absolute_pose_min_inlier_ratio;
  if (relaxed_registration_) ++report->num_relaxed_registration_trials;
  if (points2D.size() < min_inliers) {
    report->reason = "too few 2D-3D correspondences: " + std::to_string(points2D.size()) +
                     " (need " + std::to_string(min_inliers) +
                     (relaxed_registration_ ? ", relaxed)" : ")");
    return false;
  }
  // One seed per image (and attempt), derived from the mapper's: the same run registers the
  // same way whatever came before.
  AbsolutePoseEstimationOptions pose_options = options_.absolute_pose;
  pose_options.ransac.random_seed =
      DeriveSeed(options_.seed,
                 (static_cast<uint64_t>(image_id) << 8) | (report->num_registration_trials & 0xff));
  const AbsolutePoseReport pose = EstimateAbsolutePose(camera, points2D, points3D, pose_options);
  report->num_pnp_inliers = pose.num_inliers;
  const double inlier_ratio = static_cast<double>(pose.num_inliers) / points2D.size();
  if (!pose.success || pose.num_inliers < min_inliers || inlier_ratio < min_inlier_ratio) {
    report->reason = "PnP inliers below the bar: " + std::to_string(pose.num_inliers) + " of " +
                     std::to_string(points2D.size()) + " correspondences (need " +
                     std::to_string(min_inliers) + " and ratio " +
                     std::to_string(min_inlier_ratio) +
                     (relaxed_registration_ ? ", relaxed)" : ")");
    return false;
  }
  Rigid3d cam_from_world = pose.cam_from_world;
  Camera refined_camera = camera;
  if (!RefineAbsolutePose(options_.absolute_pose_refinement, pose.inlier_mask, points2D, points3D,
                          &cam_from_world, &refined_camera)) {
    report->reason = "pose rejected by non-linear refinement";
    return false;
  }
  image.cam_from_world = cam_from_world;
  reconstruction_.RegisterImage(image_id);
  const size_t num_added = AddRegistrationObservations(image_id, links, pose.inlier_mask);
  if (num_added < min_inliers / 2) {
    reconstruction_.DeRegisterImage(image_id);
    report->reason =
        "pose rejected: only " + std::to_string(num_added) + " observations fit after refinement";
    return false;
  }
  TriangulateImage(image_id);
  progress_->Increment();
  report->reason.clear();
  report->registered_relaxed = relaxed_registration_;
  report->error_before_ba_px = reconstruction_.MeanReprojectionErrorOfImage(image_id);
  PARALLAX_LOG(Debug) << "mapper: registered " << image.name << " (" << pose.num_inliers << "/"
                      << points2D.size() << " PnP inliers, " << reconstruction_.NumRegImages()
                      << " images, " << reconstruction_.NumPoints3D() << " points)";
  return true;
}

// Links the inliers of the new image to their points: one point per keypoint and one
// keypoint per point, the closest fit where there is a choice. Returns the number added.
size_t ModelBuilder::AddRegistrationObservations(
    image_t image_id, const std::vector<std::pair<point2D_t, point3D_t>>& links,
    const std::vector<char>& inlier_mask) {
  std::map<point2D_t, std::pair<double, point3D_t>> point_of_keypoint;
  for (size_t i = 0; i < links.size(); ++i) {
    if (!inlier_mask[i]) continue;
    const auto [point2D_idx, point3D_id] = links[i];
    const double error = reconstruction_.ReprojectionError(
        image_id, point2D_idx, reconstruction_.GetPoint3D(point3D_id).xyz);
    if (!(error <= options_.triangulation.max_reprojection_error_px)) continue;
    const auto [it, inserted] = point_of_keypoint.try_emplace(point2D_idx, error, point3D_id);
    if (!inserted && error < it->second.first) it->second = {error, point3D_id};
  }
  std::map<point3D_t, std::pair<double, point2D_t>> keypoint_of_point;
  for (const auto& [point2D_idx, fit] : point_of_keypoint) {
    const auto [it, inserted] = keypoint_of_point.try_emplace(fit.second, fit.first, point2D_idx);
    if (!inserted && fit.first < it->second.first) it->second = {fit.first, point2D_idx};
  }
  for (const auto& [point3D_id, fit] : keypoint_of_point) {
    model_.AddObservation(point3D_id, {image_id, fit.second});
  }
  return keypoint_of_point.size();
}

// Photos added to a finished model, fewer than its images. They are settled by local
// adjustments, then one round of the final global one: each local window holds the seed
// images that see the new one best, and the seed was adjusted, filtered and completed as a
// whole in its own run. The intermediate global adjustments and extra final rounds that the
// usual schedule adds took time and gained nothing (docs/adding-photos.md, bench/add_photos.sh).
bool ModelBuilder::ExtendingSeed() const {
  return reconstruction_.NumRegImages() < 2 * num_seed_images_;
}

// A local adjustment around the new image, or a global one once the model has grown by the
// ratios since the last.
void ModelBuilder::AdjustAfterRegistration(image_t image_id) {
  const bool grown =
      !ExtendingSeed() && (reconstruction_.NumRegImages() >=
                               options_.global_ba_images_ratio * images_at_last_global_ba_ ||
                           reconstruction_.NumPoints3D() >=
                               options_.global_ba_points_ratio * points_at_last_global_ba_);
  if (grown) {
    AdjustGlobalBundle();
  } else {
    AdjustLocalBundle(image_id);
  }
}

// Cameras with a known focal length stay fixed; others are refined once the model has
// enough images to constrain them.
void ModelBuilder::SetCameraConstancy(BundleAdjustmentConfig* config) const {
  for (const auto& [camera_id, camera] : reconstruction_.Cameras()) {
    if (camera.has_prior_focal_length || reconstruction_.NumRegImages() < 3) {
      config->constant_cameras.insert(camera_id);
    }
  }
}

// Fixes rotation and position through the first image's pose. The scale stays free: LM's
// damping keeps the system definite along it, and the gradient has no component there, so
// it does not drift. Holding one translation coordinate of the second image (COLMAP's way)
// gives that block a 2-d tangent space, which sends Ceres' Schur elimination from its
// fixed-size <2,3,3> kernels to the slower dynamic ones, for the same model to four digits
// (docs/performance.md, "Gauge: the first image's pose alone held").
void ModelBuilder::FixGauge(BundleAdjustmentConfig* config) const {
  config->SetConstantPose(init_image_id1_);
}

void ModelBuilder::AdjustLocalBundle(image_t image_id) {
  std::map<image_t, size_t> shared;
  const Image& image = reconstruction_.GetImage(image_id);
  std::vector<point3D_t> point3D_ids;
  for (const Point2D& point2D : image.points2D) {
    if (!point2D.HasPoint3D()) continue;
    point3D_ids.push_back(point2D.point3D_id);
    for (const TrackElement& element :
         reconstruction_.GetPoint3D(point2D.point3D_id).track.elements) {
      if (element.image_id != image_id) ++shared[element.image_id];
    }
  }
  std::vector<std::pair<size_t, image_t>> ranked;
  for (const auto& [other, count] : shared) ranked.emplace_back(count, other);
  std::stable_sort(ranked.begin(), ranked.end(),
                   [](const auto& a, const auto& b) { return a.first > b.first; });
  BundleAdjustmentConfig config;
  config.AddImage(image_id);
  for (size_t i = 0;
       i < ranked.size() && static_cast<int>(config.images.size()) < options_.local_ba_num_images;
       ++i) {
    config.AddImage(ranked[i].second);
  }
  if (config.images.size() == reconstruction_.NumRegImages()) FixGauge(&config);
  for (const auto& [camera_id, camera] : reconstruction_.Cameras()) {
    config.constant_cameras.insert(camera_id);
  }
  RunBundleAdjustment(options_.local_ba, config, &summary_->phase_seconds.local_ba);
  ++summary_->num_local_ba;
  // Points of the adjusted images may have moved: filter them, then let the new image's
  // tracks pick up observations that now fit.
  std::vector<point3D_t> affected;
  for (const image_t adjusted : config.images) {
    for (const Point2D& point2D : reconstruction_.GetImage(adjusted).points2D) {
      if (point2D.HasPoint3D()) affected.push_back(point2D.point3D_id);
    }
  }
  std::sort(affected.begin(), affected.end());
  affected.erase(std::unique(affected.begin(), affected.end()), affected.end());
  {
    const ScopedTimer timer(&summary_->phase_seconds.filtering);
    FilterPoints(options_.filter, affected, &reconstruction_);
  }
  TriangulateImage(image_id);
  const ScopedTimer timer(&summary_->phase_seconds.completion);
  CompleteAndMergePoints(options_.triangulation, affected, &model_);
}

// Intermediate global adjustments run one round; the last one (`final`) refines until the
// model stops changing, with more solver iterations.
void ModelBuilder::AdjustGlobalBundle(bool final) {
  const size_t num_observations_before = reconstruction_.NumObservations();
  const bool refine_principal_point = final && PrincipalPointsConstrained();
  const std::map<camera_t, std::vector<double>> params_before = CameraParams();
  // Pairs left under-reconstructed get their second chance here, before the adjustment
  // that settles the points they add.
  const size_t num_retriangulated = RetriangulatePairs();
  AdjustGlobalBundleRounds(final, refine_principal_point);
  if (refine_principal_point && !IntrinsicsPlausible()) {
    PARALLAX_LOG(Info) << "mapper: refined principal point left the image centre; "
                          "adjusting again with it fixed";
    for (const auto& [camera_id, params] : params_before) {
      reconstruction_.GetCamera(camera_id).params = params;
    }
    AdjustGlobalBundleRounds(final, /*refine_principal_point=*/false);
  }
  images_at_last_global_ba_ = reconstruction_.NumRegImages();
  points_at_last_global_ba_ = reconstruction_.NumPoints3D();
  PARALLAX_LOG(Debug) << "mapper: global BA on " << images_at_last_global_ba_ << " images, "
                      << points_at_last_global_ba_ << " points (" << num_observations_before
                      << " -> " << reconstruction_.NumObservations() << " observations, "
                      << num_retriangulated << " re-triangulated)";
}

// The principal point is worth freeing only when every camera being refined is seen by
// enough images; with few views it trades off against focal length and pose.
bool ModelBuilder::PrincipalPointsConstrained() const {
  if (options_.final_principal_point_min_images <= 0 || !options_.final_ba.refine_focal_length) {
    return false;
  }
  std::map<camera_t, int> num_images;
  for (const image_t image_id : reconstruction_.RegImageIds()) {
    ++num_images[reconstruction_.GetImage(image_id).camera_id];
  }
  bool any = false;
  for (const auto& [camera_id, count] : num_images) {
    if (reconstruction_.GetCamera(camera_id).has_prior_focal_length) continue;
    if (count < options_.final_principal_point_min_images) return false;
    any = true;
  }
  return any;
}

std::map<camera_t, std::vector<double>> ModelBuilder::CameraParams() const {
  std::map<camera_t, std::vector<double>> params;
  for (const auto& [camera_id, camera] : reconstruction_.Cameras())
    params[camera_id] = camera.params;
  return params;
}

// Refined cameras: principal points within the central 20 % of the image, focal lengths within
// 0.1-10x the image size, distortion below 1.
bool ModelBuilder::IntrinsicsPlausible() const {
  for (const auto& [camera_id, camera] : reconstruction_.Cameras()) {
    if (camera.has_prior_focal_length) continue;  // Held fixed.
    const double dx = camera.PrincipalPointX() / camera.width - 0.5;
    const double dy = camera.PrincipalPointY() / camera.height - 0.5;
    if (!(std::abs(dx) <= 0.1 && std::abs(dy) <= 0.1) || camera.HasBogusParams(0.1, 10.0, 1.0)) {
      return false;
    }
  }
  return true;
}

void ModelBuilder::AdjustGlobalBundleRounds(bool final, bool refine_principal_point) {
  // A few photos added to a finished model: one robust round (its seed went through them).
  const int max_rounds = final && !ExtendingSeed() ? options_.global_ba_max_refinements : 1;
  for (int round = 0; round < max_rounds; ++round) {
    BundleAdjustmentConfig config;
    for (const image_t image_id : reconstruction_.RegImageIds()) config.AddImage(image_id);
    FixGauge(&config);
    SetCameraConstancy(&config);
    BundleAdjustmentOptions ba_options = final ? options_.final_ba : options_.global_ba;
    ba_options.refine_principal_point |= refine_principal_point;
    RunBundleAdjustment(ba_options, config, &summary_->phase_seconds.global_ba);
    ++summary_->num_global_ba;
    const size_t num_filtered = FilterObservations();
    const size_t num_completed = CompleteTracks();
    const size_t num_observations = std::max<size_t>(1, reconstruction_.NumObservations());
    // Stop refining once the model barely changes.
    if (static_cast<double>(num_filtered + num_completed) / num_observations < 0.001) break;
  }
}

// Adds the solver's time to `phase_seconds` (local or global BA).
void ModelBuilder::RunBundleAdjustment(const BundleAdjustmentOptions& ba_options,
                                       const BundleAdjustmentConfig& config,
                                       double* phase_seconds) {
  const BundleAdjustmentSummary ba_summary = BundleAdjust(ba_options, config, &reconstruction_);
  *phase_seconds += ba_summary.seconds;
  const std::string linear_iterations =
      ba_summary.num_linear_iterations > 0
          ? ", " + std::to_string(ba_summary.num_linear_iterations) + " CG iterations"
          : "";
  PARALLAX_LOG(Debug) << "mapper: BA over " << config.images.size() << " images, "
                      << ba_summary.num_residuals << " observations: " << ba_summary.num_iterations
                      << " iterations" << linear_iterations << ", " << ba_summary.seconds << " s, "
                      << ba_summary.solver << ", " << LossFunctionName(ba_options.loss_function)
                      << " loss (" << ba_summary.termination << ")";
}
size_t ModelBuilder::FilterObservations() {
  const ScopedTimer timer(&summary_->phase_seconds.filtering);
  return FilterAllPoints(options_.filter, &reconstruction_);
}

size_t ModelBuilder::CompleteTracks() {
  const ScopedTimer timer(&summary_->phase_seconds.completion);
  return CompleteAllTracks(options_.triangulation, &model_) +
         CompleteAndMergeAllPoints(options_.triangulation, &model_);
}

size_t ModelBuilder::RetriangulatePairs() {
  const ScopedTimer timer(&summary_->phase_seconds.retriangulation);
  return RetriangulateUnderReconstructedPairs(options_.triangulation, &model_);
}

bool ModelBuilder::GrewSinceGlobalAdjustment() const {
  return reconstruction_.NumRegImages() != images_at_last_global_ba_ ||
         reconstruction_.NumPoints3D() != points_at_last_global_ba_;
}

}  // namespace parallax
