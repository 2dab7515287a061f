#pragma once

#include "parallax/sfm/tracked_reconstruction.h"

namespace parallax {

// Thresholds of the triangulator: creating points from tracks, continuing them into new
// views, completing and merging them (point_completion.h), and re-triangulating image pairs
// that are under-reconstructed (retriangulation.h).
struct TrackTriangulationOptions {
  double min_angle_deg = 1.5;  // Smallest triangulation angle a new point needs.
  // Observations further off are not part of a point when it is made or grows. Looser than
  // the 4 px filter after each adjustment, as COLMAP's 2 degrees are: a pose not yet adjusted
  // puts good observations a few pixels off, and the filter removes the bad ones later. 8 px
  // against 4, with the native SIFT: mean track length on templeRing 6.26 against 6.10 and
  // fountain-P11 4.84 against 4.76; median centre error 0.71 against 0.64 mm and 2.06 against
  // 2.09 mm (docs/defaults.md, "Tracks seed points").
  double max_reprojection_error_px = 8.0;
  int max_pair_trials = 30;  // View pairs tried as hypotheses for long tracks.
  // Features that only two images saw get no point (COLMAP's tri_ignore_two_view_tracks):
  // they tie two cameras by one weak constraint and never grow.
  bool ignore_two_view_tracks = true;
  // Completion, merging and re-triangulation (COLMAP's, with its values 5, on, 0.2) are off
  // by default: on templeRing, fountain-P11 and a 300-view aerial survey they made tracks
  // longer but no pose more accurate, and mapping the survey slower (docs/defaults.md,
  // "Tracks seed points").
  // Correspondence hops a point grows along when completed (0: no completion).
  int complete_max_transitivity = 0;
  // Points that correspondences link merge when one point fits all their observations.
  bool merge_points = false;
  // Image pairs with a smaller share of their verified matches in one point are
  // re-triangulated once, with the relaxed thresholds below (0: never).
  double retriangulate_min_ratio = 0;
  double retriangulate_min_angle_deg = 1.0;
  double retriangulate_max_reprojection_error_px = 8.0;
  void Check() const;
};

// Triangulates a new point from the track's elements in registered images that belong to no
// point yet (a track whose elements disagree can hold several points): two-view hypotheses
// (linear triangulation) scored by how many views agree (positive depth, reprojection error),
// the best refit on its agreeing views by multi-view triangulation. Returns the new point id,
// or kInvalidPoint3DId when fewer than two views agree with enough angle.
point3D_t TriangulateTrack(const TrackTriangulationOptions& options, track_t track_id,
                           TrackedReconstruction* model);

// Adds a free keypoint to the point it fits best among `candidates` and the points of its
// correspondences, when one that does not observe its image yet reprojects within the
// threshold. Returns that point, or kInvalidPoint3DId when none fits.
point3D_t ContinueKeypoint(const TrackTriangulationOptions& options, const TrackElement& element,
                           const std::vector<point3D_t>& candidates, TrackedReconstruction* model);

// ContinueKeypoint for every free element of the track, with the track's points as
// candidates. Returns the number of observations added.
size_t ContinueTrack(const TrackTriangulationOptions& options, track_t track_id,
                     TrackedReconstruction* model);

// ContinueTrack, then TriangulateTrack on the elements that are still free. Returns the
// observations added.
size_t ContinueOrTriangulateTrack(const TrackTriangulationOptions& options, track_t track_id,
                                  TrackedReconstruction* model);

// Continues or triangulates every track with an element in `image_id`, and continues its
// keypoints that have correspondences but no track (their unions were refused).
size_t TriangulateImage(const TrackTriangulationOptions& options, image_t image_id,
                        TrackedReconstruction* model);

// Continues or triangulates every track (after global bundle adjustment: elements left out
// earlier get another chance in the adjusted model).
size_t CompleteAllTracks(const TrackTriangulationOptions& options, TrackedReconstruction* model);

}  // namespace parallax
