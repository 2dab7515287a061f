#pragma once

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "parallax/geometry/gps.h"
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
    kAerial,      // a drone survey of a town in overlapping strips, JPEG with EXIF focal and GPS
    // Hard scenes (render/hard_layouts.h), each named for the failure it provokes:
    kStreet,  // a walk down a street between two rows of temples, looking forward at eye
              // height, 1 m a step: small triangulation angles everywhere
    kTwin,    // a stadium orbit around two identical temples on different ground: repeated
              // structure that can fold a model
    kWeak,    // arcs around two temples 50 m apart joined by 2 to 4 distant views that see
              // both: a barely linked view graph that incremental SfM splits in two
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
  // The lens: any camera model, rendered ray per pixel through the model's own
  // unprojection. `camera_params` in COLMAP's order, when given, set it entirely (focal
  // length and field of view are then ignored); else the model starts from the focal
  // length with the principal point at the centre and no distortion.
  CameraModelId camera_model = CameraModelId::kPinhole;
  std::vector<double> camera_params;
  // Field of view across the image width in degrees (0: from the focal length). It sets the
  // focal length by the model's family: (width / 2) / tan(fov / 2) for a perspective lens,
  // (width / 2) / (fov / 2) in radians for a fisheye (equidistant), above 180 for a fisheye
  // wider than a hemisphere. A spherical camera sees everything and ignores it.
  double field_of_view = 0.0;
  // Write the views as JPEG (view_0001.jpg...) with EXIF focal length and sensor size, as a
  // camera does (the aerial survey always does, with GPS).
  bool write_exif = false;
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
  // kAerial: share of the views tilted 30 degrees off nadir (forwards, backwards or sideways).
  double oblique_fraction = 0.1;
  // kAerial: standard deviation in metres of the noise on the EXIF GPS positions (horizontal;
  // twice that vertically, as receivers are).
  double gps_noise = 3.0;
  // Prefix of the Middlebury-style camera file `<name>_par.txt`.
  std::string name = "synth";
  // Worker threads (<= 0: all cores).
  int num_threads = -1;

  void Check() const;
  // The focal length the views are framed for: the lens's (from its parameters, its field
  // of view or `focal_length`), 0.9 * width by default and for a spherical camera.
  double EffectiveFocalLength() const;
};

// The camera every view is taken with (camera 1).
Camera SyntheticCamera(const SyntheticSceneOptions& options);

// Parses "ring", "hemisphere", "sequence", "aerial", "street", "twin" or "weak"; throws
// InputError otherwise.
SyntheticSceneOptions::Layout SyntheticSceneLayoutFromName(const std::string& name);

// Parses "none", "quincunx" or "grid3x3"; throws InputError otherwise.
Antialiasing AntialiasingFromName(const std::string& name);

// The scene for these options (one temple, a row long enough for the sequence, a street of two
// rows, two temples alike or two apart, or the town).
SceneModelOptions SyntheticSceneModelOptions(const SyntheticSceneOptions& options);

// The exact views without rendering: camera 1 (SyntheticCamera: by default PINHOLE with the
// principal point at the image centre),
// registered images 1..num_views named view_0001.png..., without keypoints. Aerial views are
// named IMG_00001.jpg... in a random order that says nothing about where they were taken,
// ids in name order; world x east, y north, z up, metres.
Reconstruction SyntheticSceneViews(const SyntheticSceneOptions& options);

// Where the aerial survey's local frame (east, north, up) sits on the WGS84 ellipsoid.
GeodeticPosition SyntheticSurveyOrigin();

// The position EXIF records for an aerial view centred at `center` (local metres): its
// geodetic position with GPS noise drawn from the seed and the view's id.
GeodeticPosition SyntheticGpsPosition(const SyntheticSceneOptions& options, image_t image_id,
                                      const Eigen::Vector3d& center);

// Lighting, noise and blur of view `view_idx` (0-based).
RenderOptions SyntheticSceneRenderOptions(const SyntheticSceneOptions& options, int view_idx);

// Renders every view into `output_dir` (created if needed) as view_0001.png... (write_exif:
// view_0001.jpg with EXIF focal length and sensor size; aerial: IMG_00001.jpg... with GPS
// too), and writes the exact cameras:
// `<name>_par.txt` (first line the count, then per view `name k11..k33 r11..r33 t1 t2 t3`,
// projection K [R | t] world to camera, COLMAP's pixel convention) and `K.txt` (3x3), both for a
// pinhole camera only, and a COLMAP text
// model gt/{cameras,images,points3D}.txt without points; aerial surveys add gt/overlap_pairs.txt,
// one line `NAME1 NAME2 SHARED` per pair of views that see at least 30 scene points in common
// (ComputeCovisiblePairs), and so do the hard layouts (street, twin, weak), to measure the view
// graph a matcher finds against. Deterministic for a seed. Returns the views (as
// SyntheticSceneViews).
Reconstruction GenerateSyntheticScene(const SyntheticSceneOptions& options,
                                      const std::filesystem::path& output_dir);

}  // namespace parallax
