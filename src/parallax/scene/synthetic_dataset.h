#pragma once

#include <cstdint>

#include "parallax/geometry/camera_models.h"
#include "parallax/scene/reconstruction.h"

namespace parallax {

class Database;

// A random scene with exact ground truth for unit tests of every stage: 3D points in a
// bounded volume, cameras looking at it, keypoints that are the projections of the visible
// points (plus optional noise and random outlier keypoints), and the true tracks.
struct SyntheticDatasetOptions {
  enum class Layout {
    kRing,        // cameras on a horizontal circle around the points, looking at the centre
    kHemisphere,  // cameras at random azimuths and elevations (10..70 deg) around the points
    kSequence,    // cameras along a line, looking sideways at a long slab of points
  };

  // Number of distinct cameras (intrinsics); image i uses camera 1 + i % num_cameras.
  int num_cameras = 1;
  // Number of images (all registered in the truth).
  int num_images = 10;
  // Number of 3D points to keep (each seen by at least min_track_length images).
  int num_points3D = 200;
  // Camera model of every camera; extra parameters get `distortion` then zeros.
  CameraModelId camera_model_id = CameraModelId::kPinhole;
  // Image size in pixels.
  int width = 640;
  int height = 480;
  // Focal length in pixels of camera 1; camera k gets focal_length * (1 + 0.05 * (k - 1)).
  double focal_length = 600.0;
  // First radial distortion coefficient of models that have one.
  double distortion = 0.0;
  // Arrangement of the cameras.
  Layout layout = Layout::kRing;
  // Points lie in a cube of this half size around the origin (ring, hemisphere) or in a slab
  // this deep along the sequence.
  double scene_radius = 1.0;
  // Distance of the cameras from the origin (ring, hemisphere) or from the slab's middle
  // plane (sequence).
  double camera_distance = 4.0;
  // Distance between consecutive cameras of the sequence layout.
  double sequence_step = 0.3;
  // Standard deviation in pixels of the Gaussian noise added to every true keypoint.
  double point2D_noise_stddev = 0.0;
  // Random keypoints (observing no 3D point) added to every image, as a fraction of its true
  // observations: 0.25 adds one outlier keypoint per four observations.
  double outlier_ratio = 0.0;
  // A point is kept only when at least this many images see it.
  int min_track_length = 2;
  // Points closer than this to a camera (along its axis) count as not visible.
  double min_depth = 0.1;
  // Seed of the generator; the same options give the same dataset.
  uint64_t seed = 0;

  void Check() const;
};

// Fills `truth` (which must be empty) with cameras 1..num_cameras, registered images
// 1..num_images named "image0001.png"..., and points 1..num_points3D whose tracks link the
// true keypoints. Keypoints of an image are in random order; outlier keypoints have no 3D
// point. Throws CheckError when the layout cannot see enough points.
void SynthesizeDataset(const SyntheticDatasetOptions& options, Reconstruction* truth);

// How the database is filled from a truth.
struct SyntheticDatabaseOptions {
  // Random wrong matches added to the raw matches of every pair (not to the verified inliers),
  // as a fraction of the pair's true matches. They pair keypoints with no 3D point when the
  // images have some, else random keypoints.
  double outlier_match_ratio = 0.0;
  // Pairs sharing fewer points than this get neither matches nor a two-view geometry.
  int min_num_matches = 1;
  // Noise (in descriptor units, 0..255) added per observation to a point's descriptor.
  double descriptor_noise_stddev = 8.0;
  // Seed of the generator for descriptors and outlier matches.
  uint64_t seed = 0;

  void Check() const;
};

// Writes the truth into `database` so that the mapper can be tested without feature
// extraction: cameras (with their ids), images (by name), keypoints (points2D, with a random
// scale and orientation), descriptors (one random 128-byte descriptor per 3D point, perturbed
// per observation, so that a descriptor matcher recovers the true matches; random ones for
// outlier keypoints), the true matches of every pair of images that share points, and a
// calibrated two-view geometry per such pair: inliers = the true matches, E and F from the
// true relative pose, cam2_from_cam1 with unit baseline, triangulation_angle the median
// triangulation angle. Meant for an empty database, where image ids equal the truth's ids.
void WriteSyntheticDatabase(const Reconstruction& truth, Database* database,
                            const SyntheticDatabaseOptions& options = {});

}  // namespace parallax
