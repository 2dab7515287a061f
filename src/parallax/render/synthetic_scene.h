#pragma once

#include <cstdint>
#include <filesystem>
#include <string>

#include "parallax/render/renderer.h"
#include "parallax/render/scene_model.h"
#include "parallax/scene/reconstruction.h"

namespace parallax {

// A rendered image set of the temple scene with exact cameras, for end-to-end tests and
// demos of the whole pipeline (images -> SIFT -> matching -> mapping -> evaluation).
struct SyntheticSceneOptions {
  enum class Layout {
    kRing,        // a ring around one temple, looking at it from about 17 degrees above
    kHemisphere,  // a spiral around one temple from 10 to 65 degrees of elevation
    kSequence,    // a walk past a row of temples, looking sideways and down (sequential matching)
  };

  // Number of views.
  int num_views = 30;
  // Arrangement of the views.
  Layout layout = Layout::kRing;
  // Image size in pixels.
  int width = 640;
  int height = 480;
  // Focal length in pixels; 0 picks 0.9 * width (58 degrees across). Cameras move away with
  // the focal length so the framing stays the same.
  double focal_length = 0.0;
  // Seed of the textures, the jitter of the poses, the lighting changes and the pixel noise.
  uint64_t seed = 0;
  // Standard deviation of Gaussian pixel noise in grey levels (0..255).
  double noise_stddev = 0.0;
  // Standard deviation in pixels of a Gaussian blur of every view.
  double blur_sigma = 0.0;
  // Per-view lighting change in [0, 1]: at 1 the sun turns up to 40 degrees in azimuth and 15
  // in elevation and the exposure changes by up to 25%.
  double lighting_variation = 0.0;
  // Anti-aliasing of the renderer.
  Antialiasing antialiasing = Antialiasing::kQuincunx;
  // Cast sun shadows.
  bool shadows = true;
  // Prefix of the Middlebury-style camera file `<name>_par.txt`.
  std::string name = "synth";
  // Worker threads (<= 0: all cores).
  int num_threads = -1;

  void Check() const;
  double EffectiveFocalLength() const { return focal_length > 0 ? focal_length : 0.9 * width; }
};

// Parses "ring", "hemisphere" or "sequence"; throws InputError otherwise.
SyntheticSceneOptions::Layout SyntheticSceneLayoutFromName(const std::string& name);

// The scene for these options (one temple, or a row long enough for the sequence).
SceneModelOptions SyntheticSceneModelOptions(const SyntheticSceneOptions& options);

// The exact views without rendering: camera 1 (PINHOLE, principal point at the image centre),
// registered images 1..num_views named view_0001.png..., without keypoints.
Reconstruction SyntheticSceneViews(const SyntheticSceneOptions& options);

// Lighting, noise and blur of view `view_idx` (0-based).
RenderOptions SyntheticSceneRenderOptions(const SyntheticSceneOptions& options, int view_idx);

// Renders every view into `output_dir` (created if needed) as view_0001.png..., and writes
// the exact cameras: `<name>_par.txt` (first line the count, then per view
// `name k11..k33 r11..r33 t1 t2 t3`, projection K [R | t] world to camera, COLMAP's pixel
// convention), `K.txt` (3x3) and a COLMAP text model gt/{cameras,images,points3D}.txt
// without points. Deterministic for a seed. Returns the views (as SyntheticSceneViews).
Reconstruction GenerateSyntheticScene(const SyntheticSceneOptions& options,
                                      const std::filesystem::path& output_dir);

}  // namespace parallax
