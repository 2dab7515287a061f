#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <opencv2/core.hpp>

#include "parallax/geometry/rigid3.h"
#include "parallax/render/scene_model.h"
#include "parallax/scene/camera.h"

namespace parallax {

// How many rays make a pixel.
enum class Antialiasing {
  kNone,      // one ray through the pixel's centre
  kQuincunx,  // the centre (weight 1/2) and the 4 corners (1/8 each), corners shared with
              // the neighbours: about 2 rays per pixel
  kGrid3x3,   // a 3x3 grid, equal weights: 9 rays per pixel
};

struct RenderOptions {
  // Anti-aliasing pattern.
  Antialiasing antialiasing = Antialiasing::kQuincunx;
  // Unit vector towards the sun, world frame (z up).
  Eigen::Vector3d sun_direction = Eigen::Vector3d(0.5, -0.4, 0.77).normalized();
  // Irradiance of direct sunlight and of the ambient sky light (albedo 1 -> their sum).
  double sun_intensity = 0.75;
  double ambient_intensity = 0.35;
  // Gain on the final image (exposure differences between views).
  double exposure = 1.0;
  // Trace shadow rays towards the sun.
  bool shadows = true;
  // Standard deviation in pixels of a Gaussian blur applied to the rendered image (0: none).
  double blur_sigma = 0.0;
  // Standard deviation of additive Gaussian pixel noise in grey levels (0..255), after blur.
  double noise_stddev = 0.0;
  // Seed of the pixel noise.
  uint64_t noise_seed = 0;
  // Threads over image rows (<= 0: all cores). The image does not depend on it.
  int num_threads = -1;

  void Check() const;
};

// Ray-casts the scene as seen by `camera` at `cam_from_world`: an 8-bit BGR image
// (CV_8UC3, camera.width x camera.height), Lambert-shaded. Pixel (col, row) covers
// [col, col + 1) x [row, row + 1) in the camera's image coordinates (COLMAP's convention:
// the first pixel's centre is (0.5, 0.5)), so keypoints in the image are directly in the
// camera's coordinates. Every other model is rendered through Camera::CamRayFromImg
// (slower), fisheyes beyond 180 degrees and the full sphere included.
// When `depth` is not null it gets, per pixel (CV_32FC1), the depth of the surface at the
// pixel's centre (z in the camera frame for a perspective model, the distance along the
// ray for fisheye and spherical ones), 0 where the ray reaches the sky.
cv::Mat RenderView(const SceneModel& scene, const Camera& camera, const Rigid3d& cam_from_world,
                   const RenderOptions& options, cv::Mat* depth = nullptr);

}  // namespace parallax
