#pragma once

#include <map>
#include <set>
#include <vector>

#include "parallax/estimators/bundle_adjustment.h"
#include "parallax/scene/reconstruction.h"
#include "parallax/sfm/incremental_mapper_options.h"
#include "parallax/sfm/initial_pair.h"
#include "parallax/sfm/mapper_input.h"
#include "parallax/sfm/mapper_summary.h"
#include "parallax/sfm/next_view.h"
#include "parallax/sfm/tracked_reconstruction.h"
#include "parallax/util/progress.h"

namespace parallax {

// The steps of building one model, each callable on its own (COLMAP's IncrementalMapper
// exposes the same steps; IncrementalMapper::Reconstruct is the loop that orders them). The
// model starts with the input's cameras and images, none registered; images that `used_images`
// holds (registered by earlier models) are never used. Every step adds its time to the
// summary's phases and its outcome to the summary's image reports.
//
//   initialise     InitializeFromBestPair, InitializeFromPair, InitializeFromModel
//   register next  NextImages, RegisterImage (PnP, refinement, then TriangulateImage)
//   triangulate    TriangulateImage, RetriangulatePairs
//   adjust         AdjustAfterRegistration, AdjustLocalBundle, AdjustGlobalBundle
//   filter         FilterObservations
//   complete       CompleteTracks (tracks completed, points merged)
//
// Steps that need registered images (all but initialisation and NextImages) expect a model
// that was initialised.
class ModelBuilder {
 public:
  ModelBuilder(const IncrementalMapperOptions& options, const MapperInput& input,
               const std::set<image_t>& used_images, MapperSummary* summary,
               ProgressReporter* progress);
  // The builder keeps a reference to `used_images`: a temporary set would dangle.
  ModelBuilder(const IncrementalMapperOptions&, const MapperInput&, std::set<image_t>&&,
               MapperSummary*, ProgressReporter*) = delete;

  Reconstruction& Model() { return reconstruction_; }
  const Reconstruction& Model() const { return reconstruction_; }
  // The model with its tracks: which point each track seeded.
  const TrackedReconstruction& Tracked() const { return model_; }

  // ----- Initialisation ---------------------------------------------------------------------
  // Walks InitThresholdSchedule: at each step, the verified pairs of unused images with at
  // least that step's inliers, most inliers first, until one starts the model (at most
  // init_max_trials of them meeting the thresholds and being adjusted per step). `ledger` (shared
  // by the models of a run; none: one of its own) keeps each pair's evaluation and skips pairs an
  // earlier model started from. False when no pair qualifies at any step.
  bool InitializeFromBestPair(InitialPairLedger* ledger = nullptr);
  // Registers the two images of `pair_id` with the pair's relative pose, triangulates their
  // matches and adjusts both. False (nothing registered) when fewer than the thresholds'
  // inliers triangulate, their median angle is below theirs, or fewer than half that many
  // points survive the adjustment. `met_thresholds` (when given) is set when the pair met
  // the thresholds, whether or not the adjustment then kept it.
  bool InitializeFromPair(image_pair_t pair_id, const TwoViewGeometry& geometry,
                          const InitThresholds& thresholds, InitialPairLedger* ledger = nullptr,
                          bool* met_thresholds = nullptr);
  // What a seed model is: a finished, adjusted model given by the user (its images counted
  // as new registrations, a few photos added to it settled lightly: ExtendingSeed), or this
  // run's models joined by JoinModels (counted already, and never adjusted as a whole: the
  // full schedule follows).
  enum class SeedKind { kAdjusted, kJoined };
  // Starts from the registered images of `seed` that this input holds and no earlier model
  // used, with the seed's poses and intrinsics; every track they see is triangulated anew.
  // False (and nothing registered) when fewer than two qualify.
  bool InitializeFromModel(const Reconstruction& seed, SeedKind kind = SeedKind::kAdjusted);

  // ----- Registration -----------------------------------------------------------------------
  // Unregistered images connected to the model, best first by visibility score, leaving out
  // those that `trials` says failed max_registration_trials times.
  std::vector<image_t> NextImages(const std::map<image_t, int>& trials);
  // PnP RANSAC on the image's 2D-3D correspondences, pose refinement, observations of the
  // inliers, then TriangulateImage. False, with `report->reason`, when any bar is not met.
  bool RegisterImage(image_t image_id, MapperImageReport* report);
  // From now on, registration holds images to the relaxed PnP bars
  // (relaxed_absolute_pose_min_num_inliers and _ratio): the last pass.
  void RelaxRegistration() { relaxed_registration_ = true; }
  bool RegistrationRelaxed() const { return relaxed_registration_; }
  // Unregistered images left that no earlier model used.
  bool ImagesLeftToRegister() const;
  // How the model started (set by a successful initialisation).
  const ModelStartReport& Start() const { return start_; }

  // ----- Triangulation ----------------------------------------------------------------------
  // New points from the image's tracks, and the image's keypoints added to points they fit.
  void TriangulateImage(image_t image_id);
  // Image pairs left under-reconstructed, triangulated again with relaxed thresholds.
  // Returns the observations added.
  size_t RetriangulatePairs();

  // ----- Bundle adjustment ------------------------------------------------------------------
  // A local adjustment around the new image, or a global one once the model has grown by
  // global_ba_images_ratio or global_ba_points_ratio since the last.
  void AdjustAfterRegistration(image_t image_id);
  // The image and the local_ba_num_images - 1 images sharing most points with it, cameras
  // fixed; then the points they see filtered and completed.
  void AdjustLocalBundle(image_t image_id);
  // Every registered image, after RetriangulatePairs; filtered and completed after each
  // round. `final`: the robust final adjustment, refined until the model stops changing (and
  // the principal point freed when the cameras are seen enough).
  void AdjustGlobalBundle(bool final = false);
  // Images or points added since the last global adjustment.
  bool GrewSinceGlobalAdjustment() const;

  // ----- Filtering and completion -----------------------------------------------------------
  // Observations and points that stopped fitting (ObservationFilterOptions). Returns the
  // observations removed.
  size_t FilterObservations();
  // Tracks completed with the observations that now fit, and points merged. Returns the
  // observations added or merged.
  size_t CompleteTracks();

 private:
  bool Available(image_t image_id) const;
  bool EstimatePoseAndRegister(image_t image_id, MapperImageReport* report);
  size_t AddRegistrationObservations(image_t image_id,
                                     const std::vector<std::pair<point2D_t, point3D_t>>& links,
                                     const std::vector<char>& inlier_mask);
  bool ExtendingSeed() const;
  void SetCameraConstancy(BundleAdjustmentConfig* config) const;
  void FixGauge(BundleAdjustmentConfig* config) const;
  bool PrincipalPointsConstrained() const;
  std::map<camera_t, std::vector<double>> CameraParams() const;
  bool IntrinsicsPlausible() const;
  void AdjustGlobalBundleRounds(bool final, bool refine_principal_point);
  void RunBundleAdjustment(const BundleAdjustmentOptions& ba_options,
                           const BundleAdjustmentConfig& config, double* phase_seconds);

  const IncrementalMapperOptions& options_;
  const MapperInput& input_;
  const std::set<image_t>& used_images_;
  MapperSummary* summary_;
  ProgressReporter* progress_;
  Reconstruction reconstruction_;
  TrackedReconstruction model_;
  VisibilityScores visibility_;            // Of the unregistered images, for ranking the next view.
  std::vector<int> registered_neighbors_;  // By image id, as of the last ranking.
  std::vector<char> counted_as_registered_;  // By image id: in its neighbours' counts.
  image_t init_image_id1_ = kInvalidImageId;
  image_t init_image_id2_ = kInvalidImageId;
  size_t images_at_last_global_ba_ = 0;
  size_t points_at_last_global_ba_ = 0;
  size_t num_seed_images_ = 0;  // Registered from an input model (Extend).
  ModelStartReport start_;
  bool relaxed_registration_ = false;
};

}  // namespace parallax
