#pragma once

#include "parallax/sfm/tracked_reconstruction.h"

namespace parallax {

struct TrackTriangulationOptions {
  double min_angle_deg = 1.5;              // Smallest triangulation angle a new point needs.
  double max_reprojection_error_px = 4.0;  // Observations further off are not part of the point.
  int max_pair_trials = 30;                // View pairs tried as hypotheses for long tracks.
  void Check() const;
};

// Triangulates a track that has no 3D point yet from its elements in registered images:
// two-view hypotheses (linear triangulation) scored by how many views agree (positive depth,
// reprojection error), the best refit on its agreeing views by multi-view triangulation.
// Returns the new point id, or kInvalidPoint3DId when fewer than two views agree with enough
// angle.
point3D_t TriangulateTrack(const TrackTriangulationOptions& options, track_t track_id,
                           TrackedReconstruction* model);

// Adds to the track's point every registered element it lacks whose reprojection fits.
// Returns the number of observations added.
size_t ContinueTrack(const TrackTriangulationOptions& options, track_t track_id,
                     TrackedReconstruction* model);

// ContinueTrack when the track has a point, else TriangulateTrack. Returns the observations
// added.
size_t ContinueOrTriangulateTrack(const TrackTriangulationOptions& options, track_t track_id,
                                  TrackedReconstruction* model);

// Continues or triangulates every track with an element in `image_id`.
size_t TriangulateImage(const TrackTriangulationOptions& options, image_t image_id,
                        TrackedReconstruction* model);

// Continues or triangulates every track (after global bundle adjustment).
size_t CompleteAllTracks(const TrackTriangulationOptions& options, TrackedReconstruction* model);

}  // namespace parallax
