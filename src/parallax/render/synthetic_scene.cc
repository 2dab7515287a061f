#include "parallax/render/synthetic_scene.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <iomanip>
#include <numbers>
#include <ostream>
#include <random>

#include "parallax/calibration/exif_writer.h"
#include "parallax/geometry/look_at.h"
#include "parallax/image/image_codecs.h"
#include "parallax/render/covisibility.h"
#include "parallax/render/hard_layouts.h"
#include "parallax/render/procedural_texture.h"
#include "parallax/util/check.h"
#include "parallax/util/file.h"
#include "parallax/util/logging.h"
#include "parallax/util/threading.h"
#include "parallax/util/timer.h"

namespace parallax {
namespace {

constexpr double kDegrees = std::numbers::pi / 180.0;
// Distance between consecutive views of the sequence, in metres.
constexpr double kSequenceStep = 0.6;
// The aerial survey at the default focal length: flying height, and the share of an image
// that overlaps the next one along a strip and the neighbouring strip.
constexpr double kSurveyAltitude = 60.0;
constexpr double kForwardOverlap = 0.8;
constexpr double kSideOverlap = 0.65;
constexpr double kObliqueTilt = 30.0;

// Camera axes from a viewing direction and the world direction that should point up in the
// image (it need not be orthogonal to `forward`): x right, y down, z forward.
Rigid3d CameraLooking(const Eigen::Vector3d& center, const Eigen::Vector3d& forward,
                      const Eigen::Vector3d& image_up) {
  const Eigen::Vector3d z = forward.normalized();
  const Eigen::Vector3d y = -(image_up - image_up.dot(z) * z).normalized();
  Eigen::Matrix3d rotation;
  rotation.row(0) = y.cross(z).transpose();
  rotation.row(1) = y.transpose();
  rotation.row(2) = z.transpose();
  return Rigid3d(rotation, -rotation * center);
}

// Strips of the survey: the views fill strips flown back and forth along y, enough strips
// that the surveyed area is about square.
struct SurveyPlan {
  int num_strips = 1;
  int views_per_strip = 1;
  double strip_spacing = 0.0;  // metres between strips (x)
  double view_spacing = 0.0;   // metres between views along a strip (y)

  SurveyPlan(const SyntheticSceneOptions& options, double zoom) {
    const double altitude = kSurveyAltitude * zoom;
    const double focal_length = options.EffectiveFocalLength();
    strip_spacing = (1.0 - kSideOverlap) * altitude * options.width / focal_length;
    view_spacing = (1.0 - kForwardOverlap) * altitude * options.height / focal_length;
    num_strips = std::max(
        1,
        static_cast<int>(std::lround(std::sqrt(options.num_views * view_spacing / strip_spacing))));
    views_per_strip = (options.num_views + num_strips - 1) / num_strips;
    num_strips = (options.num_views + views_per_strip - 1) / views_per_strip;
  }
  Eigen::Vector2d HalfExtent() const {
    return 0.5 *
           Eigen::Vector2d((num_strips - 1) * strip_spacing, (views_per_strip - 1) * view_spacing);
  }
};

// Poses of the aerial survey in flight order: nadir views, a share tilted, small attitude and
// position errors as a drone's.
std::vector<Rigid3d> AerialSurveyPoses(const SyntheticSceneOptions& options, double zoom,
                                       std::mt19937_64* engine) {
  const SurveyPlan plan(options, zoom);
  const Eigen::Vector2d half = plan.HalfExtent();
  const auto jitter = [engine](double stddev) {
    return std::normal_distribution<double>(0.0, stddev)(*engine);
  };
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  std::vector<Rigid3d> poses;
  for (int i = 0; i < options.num_views; ++i) {
    const int strip = i / plan.views_per_strip, step = i % plan.views_per_strip;
    // Back and forth: odd strips fly south, so their images are upside down to even ones.
    const bool northwards = strip % 2 == 0;
    const double y =
        (northwards ? step : plan.views_per_strip - 1 - step) * plan.view_spacing - half.y();
    const Eigen::Vector3d center(strip * plan.strip_spacing - half.x() + jitter(0.7),
                                 y + jitter(0.7), kSurveyAltitude * zoom + jitter(1.0));
    const double heading = (northwards ? 90.0 : -90.0) + jitter(3.0);
    const Eigen::Vector3d flight(std::cos(heading * kDegrees), std::sin(heading * kDegrees), 0.0);
    // About 1.7 degrees of attitude error on the gimbal.
    const Eigen::Vector3d attitude_error(jitter(0.03), jitter(0.03), 0.0);
    Eigen::Vector3d forward = Eigen::Vector3d(0, 0, -1) + attitude_error;
    if (unit(*engine) < options.oblique_fraction) {
      // Tilted towards one of the four directions relative to the flight.
      const int side = static_cast<int>(4 * unit(*engine)) % 4;
      const Eigen::Vector3d left(-flight.y(), flight.x(), 0.0);
      const Eigen::Vector3d toward = side == 0   ? flight
                                     : side == 1 ? -flight
                                     : side == 2 ? left
                                                 : -left;
      forward = std::cos(kObliqueTilt * kDegrees) * Eigen::Vector3d(0, 0, -1) +
                std::sin(kObliqueTilt * kDegrees) * toward + attitude_error;
    }
    poses.push_back(CameraLooking(center, forward, flight));
  }
  return poses;
}

bool IsHardLayout(SyntheticSceneOptions::Layout layout) {
  return layout == SyntheticSceneOptions::Layout::kStreet ||
         layout == SyntheticSceneOptions::Layout::kTwin ||
         layout == SyntheticSceneOptions::Layout::kWeak;
}

// Whether the views are written as JPEG with EXIF (the survey always, the rest on request).
bool WritesExif(const SyntheticSceneOptions& options) {
  return options.layout == SyntheticSceneOptions::Layout::kAerial || options.write_exif;
}

std::string ViewName(int view_idx, const SyntheticSceneOptions& options) {
  const bool aerial = options.layout == SyntheticSceneOptions::Layout::kAerial;
  char name[32];
  std::snprintf(name, sizeof(name),
                aerial ? "IMG_%05d.jpg" : (options.write_exif ? "view_%04d.jpg" : "view_%04d.png"),
                view_idx + 1);
  return name;
}

double SequenceLength(const SyntheticSceneOptions& options) {
  return (options.num_views - 1) * kSequenceStep;
}

void WriteMatrixRow(std::ostream& stream, const Eigen::Matrix3d& matrix) {
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) stream << ' ' << matrix(r, c);
  }
}

// What a camera writes into its JPEGs: focal length in mm with the sensor's size (as focal
// plane resolution) and the 35 mm equivalent (a spherical camera has none), pixel size; a
// drone adds its GPS position.
ExifData SyntheticViewExif(const SyntheticSceneOptions& options, const Camera& camera,
                           const Image& image) {
  constexpr double kSensorWidthMm = 6.4;
  const bool aerial = options.layout == SyntheticSceneOptions::Layout::kAerial;
  ExifData exif;
  exif.make = "Parallax";
  exif.model = aerial ? "synth aerial" : "synth " + camera.ModelName();
  if (camera.Projection() != CameraProjection::kSpherical) {
    exif.focal_length_mm = camera.FocalLengthX() * kSensorWidthMm / camera.width;
    exif.focal_plane_x_resolution = camera.width / (0.1 * kSensorWidthMm);  // pixels per cm
    exif.focal_plane_resolution_unit = 3;
    exif.focal_length_35mm = camera.FocalLengthX() * 36.0 / std::max(camera.width, camera.height);
  }
  exif.pixel_x_dimension = camera.width;
  exif.pixel_y_dimension = camera.height;
  if (aerial) {
    const GeodeticPosition gps =
        SyntheticGpsPosition(options, image.image_id, ProjectionCenter(image.cam_from_world));
    exif.gps_latitude = gps.latitude;
    exif.gps_longitude = gps.longitude;
    exif.gps_altitude = gps.altitude;
  }
  return exif;
}

}  // namespace

void SyntheticSceneOptions::Check() const {
  PARALLAX_CHECK_GE(num_views, 2);
  PARALLAX_CHECK_GE(width, 16);
  PARALLAX_CHECK_GE(height, 16);
  PARALLAX_CHECK_GE(focal_length, 0.0);
  PARALLAX_CHECK_GE(noise_stddev, 0.0);
  PARALLAX_CHECK_GE(blur_sigma, 0.0);
  PARALLAX_CHECK_GE(lighting_variation, 0.0);
  PARALLAX_CHECK_LE(lighting_variation, 1.0);
  PARALLAX_CHECK_GE(oblique_fraction, 0.0);
  PARALLAX_CHECK_LE(oblique_fraction, 1.0);
  PARALLAX_CHECK_GE(gps_noise, 0.0);
  PARALLAX_CHECK(!name.empty());
  PARALLAX_CHECK_MSG(ExistsCameraModel(static_cast<int>(camera_model)), "unknown camera model");
  if (!camera_params.empty()) {
    if (static_cast<int>(camera_params.size()) != CameraModelNumParams(camera_model)) {
      throw InputError("--camera-params: " + std::to_string(camera_params.size()) +
                       " values, but " + CameraModelName(camera_model) + " takes " +
                       std::to_string(CameraModelNumParams(camera_model)) + " (" +
                       CameraModelParamsInfo(camera_model) + ")");
    }
    if (!SyntheticCamera(*this).VerifyParams()) {
      throw InputError("--camera-params: focal lengths must be positive and finite");
    }
  }
  const CameraProjection projection = CameraModelProjection(camera_model);
  const double max_fov = projection == CameraProjection::kPerspective ? 170.0 : 360.0;
  if (field_of_view < 0 || field_of_view > max_fov) {
    throw InputError("--fov: " + std::to_string(field_of_view) + " degrees is outside (0, " +
                     std::to_string(static_cast<int>(max_fov)) + "] for " +
                     CameraModelName(camera_model));
  }
}

double SyntheticSceneOptions::EffectiveFocalLength() const {
  const CameraProjection projection = CameraModelProjection(camera_model);
  if (projection == CameraProjection::kSpherical) return 0.9 * width;
  if (!camera_params.empty()) {
    Camera camera;
    camera.model_id = camera_model;
    camera.params = camera_params;
    return camera.MeanFocalLength();
  }
  if (field_of_view > 0) {
    const double half_angle = 0.5 * field_of_view * kDegrees;
    return projection == CameraProjection::kFisheye ? 0.5 * width / half_angle
                                                    : 0.5 * width / std::tan(half_angle);
  }
  return focal_length > 0 ? focal_length : 0.9 * width;
}

Camera SyntheticCamera(const SyntheticSceneOptions& options) {
  Camera camera = Camera::Create(1, options.camera_model, options.EffectiveFocalLength(),
                                 options.width, options.height);
  if (!options.camera_params.empty()) camera.params = options.camera_params;
  camera.has_prior_focal_length = true;
  return camera;
}

SyntheticSceneOptions::Layout SyntheticSceneLayoutFromName(const std::string& name) {
  if (name == "ring") return SyntheticSceneOptions::Layout::kRing;
  if (name == "hemisphere") return SyntheticSceneOptions::Layout::kHemisphere;
  if (name == "sequence") return SyntheticSceneOptions::Layout::kSequence;
  if (name == "aerial") return SyntheticSceneOptions::Layout::kAerial;
  if (name == "street") return SyntheticSceneOptions::Layout::kStreet;
  if (name == "twin") return SyntheticSceneOptions::Layout::kTwin;
  if (name == "weak") return SyntheticSceneOptions::Layout::kWeak;
  throw InputError("unknown layout '" + name +
                   "' (expected ring, hemisphere, sequence, aerial, street, twin or weak)");
}

Antialiasing AntialiasingFromName(const std::string& name) {
  if (name == "none") return Antialiasing::kNone;
  if (name == "quincunx") return Antialiasing::kQuincunx;
  if (name == "grid3x3") return Antialiasing::kGrid3x3;
  throw InputError("unknown antialiasing '" + name + "' (expected none, quincunx or grid3x3)");
}

SceneModelOptions SyntheticSceneModelOptions(const SyntheticSceneOptions& options) {
  switch (options.layout) {
    case SyntheticSceneOptions::Layout::kStreet:
      return StreetSceneOptions(options);
    case SyntheticSceneOptions::Layout::kTwin:
      return TwinSceneOptions(options);
    case SyntheticSceneOptions::Layout::kWeak:
      return WeakSceneOptions(options);
    default:
      break;
  }
  SceneModelOptions scene_options;
  scene_options.seed = options.seed;
  if (options.layout == SyntheticSceneOptions::Layout::kSequence) {
    scene_options.num_temples =
        1 + static_cast<int>(std::lround(SequenceLength(options) / scene_options.temple_spacing));
  }
  if (options.layout == SyntheticSceneOptions::Layout::kAerial) {
    // The town reaches past the survey by the width of an oblique view's field.
    const double zoom = options.EffectiveFocalLength() / (0.9 * options.width);
    scene_options.kind = SceneModelOptions::Kind::kTown;
    scene_options.town_half_size = SurveyPlan(options, zoom).HalfExtent().maxCoeff() + 120.0 * zoom;
  }
  return scene_options;
}

Reconstruction SyntheticSceneViews(const SyntheticSceneOptions& options) {
  options.Check();
  const double focal_length = options.EffectiveFocalLength();
  // Keep the framing of the default 58 degree view whatever the focal length.
  const double zoom = focal_length / (0.9 * options.width);
  std::mt19937_64 engine(options.seed ^ 0x2545F4914F6CDD1Dull);
  const auto jitter = [&engine](double stddev) {
    return std::normal_distribution<double>(0.0, stddev)(engine);
  };
  const SceneModelOptions scene_options = SyntheticSceneModelOptions(options);
  const double row_middle = 0.5 * (scene_options.num_temples - 1) * scene_options.temple_spacing;
  const double phase = std::uniform_real_distribution<double>(0.0, 2.0 * std::numbers::pi)(engine);

  Reconstruction views;
  views.AddCamera(SyntheticCamera(options));
  const int n = options.num_views;
  if (options.layout == SyntheticSceneOptions::Layout::kAerial) {
    // Names from a random permutation, ids in name order: neither says where a view is.
    const std::vector<Rigid3d> poses = AerialSurveyPoses(options, zoom, &engine);
    std::vector<int> name_of_view(n);
    for (int i = 0; i < n; ++i) name_of_view[i] = i;
    std::shuffle(name_of_view.begin(), name_of_view.end(), engine);
    std::vector<int> view_of_name(n);
    for (int i = 0; i < n; ++i) view_of_name[name_of_view[i]] = i;
    for (int k = 0; k < n; ++k) {
      Image image;
      image.image_id = static_cast<image_t>(k + 1);
      image.camera_id = 1;
      image.name = ViewName(k, options);
      image.cam_from_world = poses[view_of_name[k]];
      views.AddImage(std::move(image));
      views.RegisterImage(static_cast<image_t>(k + 1));
    }
    return views;
  }
  if (IsHardLayout(options.layout)) {
    const std::vector<Rigid3d> poses =
        options.layout == SyntheticSceneOptions::Layout::kStreet ? StreetWalkPoses(options, &engine)
        : options.layout == SyntheticSceneOptions::Layout::kTwin ? TwinOrbitPoses(options, &engine)
                                                                 : WeakLinkPoses(options, &engine);
    for (int i = 0; i < n; ++i) {
      Image image;
      image.image_id = static_cast<image_t>(i + 1);
      image.camera_id = 1;
      image.name = ViewName(i, options);
      image.cam_from_world = poses[i];
      views.AddImage(std::move(image));
      views.RegisterImage(static_cast<image_t>(i + 1));
    }
    return views;
  }
  for (int i = 0; i < n; ++i) {
    Eigen::Vector3d center = Eigen::Vector3d::Zero();
    Eigen::Vector3d target = Eigen::Vector3d::Zero();
    switch (options.layout) {
      case SyntheticSceneOptions::Layout::kRing: {
        const double azimuth = phase + 2.0 * std::numbers::pi * i / n;
        const double radius = 21.0 * zoom;
        center =
            Eigen::Vector3d(radius * std::cos(azimuth), radius * std::sin(azimuth), 0.45 * radius);
        target = Eigen::Vector3d(0.0, 0.0, 3.0);
        break;
      }
      case SyntheticSceneOptions::Layout::kHemisphere: {
        // A spiral, so that consecutive views stay close (about 15 degrees apart or less).
        const double turns = std::max(1.0, n / 24.0);
        const double azimuth = phase + 2.0 * std::numbers::pi * turns * i / n;
        const double elevation = (10.0 + 55.0 * i / (n - 1)) * kDegrees;
        const double radius = 23.0 * zoom;
        center =
            radius * Eigen::Vector3d(std::cos(elevation) * std::cos(azimuth),
                                     std::cos(elevation) * std::sin(azimuth), std::sin(elevation));
        center.z() += 1.0;
        target = Eigen::Vector3d(0.0, 0.0, 2.5);
        break;
      }
      case SyntheticSceneOptions::Layout::kAerial:
      case SyntheticSceneOptions::Layout::kStreet:
      case SyntheticSceneOptions::Layout::kTwin:
      case SyntheticSceneOptions::Layout::kWeak:
        break;  // Returned above.
      case SyntheticSceneOptions::Layout::kSequence: {
        // Walking past the row, the gaze swinging slowly forwards and backwards.
        const double x = row_middle - 0.5 * SequenceLength(options) + i * kSequenceStep;
        const double distance = 20.0 * zoom;
        const double yaw = 18.0 * kDegrees * std::sin(phase + 2.0 * std::numbers::pi * i / 60.0);
        center = Eigen::Vector3d(x, -distance, 6.5 * zoom + 0.4 * std::sin(phase + 0.37 * i));
        target = Eigen::Vector3d(x + distance * std::tan(yaw), 0.0, 1.0);
        break;
      }
    }
    center += Eigen::Vector3d(jitter(0.3), jitter(0.3), jitter(0.2)) * zoom;
    target += Eigen::Vector3d(jitter(0.3), jitter(0.3), jitter(0.2));

    Image image;
    image.image_id = static_cast<image_t>(i + 1);
    image.camera_id = 1;
    image.name = ViewName(i, options);
    image.cam_from_world = LookAt(center, target);
    views.AddImage(std::move(image));
    views.RegisterImage(static_cast<image_t>(i + 1));
  }
  return views;
}

GeodeticPosition SyntheticSurveyOrigin() { return {46.5191, 6.5668, 400.0}; }

GeodeticPosition SyntheticGpsPosition(const SyntheticSceneOptions& options, image_t image_id,
                                      const Eigen::Vector3d& center) {
  std::mt19937_64 engine(
      Mix32(static_cast<uint32_t>(options.seed) ^ 0x6B5Du) * 0x9E3779B97F4A7C15ull + image_id);
  std::normal_distribution<double> noise(0.0, options.gps_noise);
  const Eigen::Vector3d noisy =
      center + Eigen::Vector3d(noise(engine), noise(engine), 2.0 * noise(engine));
  return GeodeticFromEnu(noisy, SyntheticSurveyOrigin());
}

RenderOptions SyntheticSceneRenderOptions(const SyntheticSceneOptions& options, int view_idx) {
  RenderOptions render_options;
  render_options.antialiasing = options.antialiasing;
  render_options.shadows = options.shadows;
  render_options.blur_sigma = options.blur_sigma;
  render_options.noise_stddev = options.noise_stddev;
  render_options.noise_seed =
      Mix32(static_cast<uint32_t>(options.seed) ^ Mix32(view_idx + 1)) + (options.seed >> 32);
  render_options.num_threads = options.num_threads;
  if (options.lighting_variation > 0.0) {
    std::mt19937_64 engine(options.seed * 0x9E3779B97F4A7C15ull + view_idx + 1);
    std::uniform_real_distribution<double> uniform(-1.0, 1.0);
    const double x = options.lighting_variation;
    const Eigen::Vector3d& sun = render_options.sun_direction;
    const double azimuth = std::atan2(sun.y(), sun.x()) + 40.0 * kDegrees * x * uniform(engine);
    const double elevation = std::clamp(std::asin(sun.z()) + 15.0 * kDegrees * x * uniform(engine),
                                        15.0 * kDegrees, 85.0 * kDegrees);
    render_options.sun_direction =
        Eigen::Vector3d(std::cos(elevation) * std::cos(azimuth),
                        std::cos(elevation) * std::sin(azimuth), std::sin(elevation));
    render_options.exposure = 1.0 + 0.25 * x * uniform(engine);
    render_options.ambient_intensity *= 1.0 + 0.2 * x * uniform(engine);
  }
  return render_options;
}

Reconstruction GenerateSyntheticScene(const SyntheticSceneOptions& options,
                                      const std::filesystem::path& output_dir) {
  options.Check();
  const Timer timer;
  const Reconstruction views = SyntheticSceneViews(options);
  const SceneModel scene(SyntheticSceneModelOptions(options));
  const Camera& camera = views.GetCamera(1);
  CreateDirectoryOrThrow(output_dir);
  CreateDirectoryOrThrow(output_dir / "gt");

  // Whole views per thread: rendering and encoding then both run in parallel.
  const bool exif = WritesExif(options);
  const std::vector<image_t> image_ids = views.RegImageIds();
  ParallelFor(0, image_ids.size(), options.num_threads, [&](size_t i) {
    const Image& image = views.GetImage(image_ids[i]);
    RenderOptions render_options = SyntheticSceneRenderOptions(options, static_cast<int>(i));
    render_options.num_threads = 1;
    const cv::Mat rendered = RenderView(scene, camera, image.cam_from_world, render_options);
    const std::string encoded =
        exif ? InsertJpegExif(EncodeJpeg(rendered, 92),
                              EncodeExifTiff(SyntheticViewExif(options, camera, image)))
             : EncodePng(rendered);
    WriteFileAtomically(
        output_dir / image.name,
        [&encoded](std::ostream& stream) {
          stream.write(encoded.data(), static_cast<std::streamsize>(encoded.size()));
        },
        /*binary=*/true);
    PARALLAX_LOG(Debug) << "rendered " << image.name;
  });

  // K.txt and the Middlebury file describe a pinhole; any other lens has gt/cameras.txt
  // only, or a reconstruction would take K.txt for its intrinsics.
  const bool pinhole = IsPinholeCameraModel(camera.model_id);
  const Eigen::Matrix3d K = pinhole ? camera.CalibrationMatrix() : Eigen::Matrix3d::Identity();
  if (pinhole)
    WriteFileAtomically(output_dir / (options.name + "_par.txt"), [&](std::ostream& stream) {
      stream << std::setprecision(17) << views.NumImages() << '\n';
      for (const auto& [image_id, image] : views.Images()) {
        stream << image.name;
        WriteMatrixRow(stream, K);
        WriteMatrixRow(stream, image.cam_from_world.rotation.toRotationMatrix());
        const Eigen::Vector3d& t = image.cam_from_world.translation;
        stream << ' ' << t.x() << ' ' << t.y() << ' ' << t.z() << '\n';
      }
    });
  if (pinhole)
    WriteFileAtomically(output_dir / "K.txt", [&](std::ostream& stream) {
      stream << std::setprecision(17);
      for (int r = 0; r < 3; ++r) stream << K(r, 0) << ' ' << K(r, 1) << ' ' << K(r, 2) << '\n';
    });
  WriteFileAtomically(output_dir / "gt" / "cameras.txt", [&](std::ostream& stream) {
    stream << "# Camera list with one line of data per camera:\n"
              "#   CAMERA_ID, MODEL, WIDTH, HEIGHT, PARAMS[]\n"
              "# Number of cameras: 1\n";
    stream << std::setprecision(17) << camera.camera_id << ' ' << camera.ModelName() << ' '
           << camera.width << ' ' << camera.height;
    for (const double param : camera.params) stream << ' ' << param;
    stream << '\n';
  });
  WriteFileAtomically(output_dir / "gt" / "images.txt", [&](std::ostream& stream) {
    stream << "# Image list with two lines of data per image:\n"
              "#   IMAGE_ID, QW, QX, QY, QZ, TX, TY, TZ, CAMERA_ID, NAME\n"
              "#   POINTS2D[] as (X, Y, POINT3D_ID)\n"
              "# Number of images: "
           << views.NumImages() << ", mean observations per image: 0\n";
    stream << std::setprecision(17);
    for (const auto& [image_id, image] : views.Images()) {
      const Eigen::Quaterniond& q = image.cam_from_world.rotation;
      const Eigen::Vector3d& t = image.cam_from_world.translation;
      stream << image_id << ' ' << q.w() << ' ' << q.x() << ' ' << q.y() << ' ' << q.z() << ' '
             << t.x() << ' ' << t.y() << ' ' << t.z() << ' ' << image.camera_id << ' ' << image.name
             << "\n\n";
    }
  });
  WriteFileAtomically(output_dir / "gt" / "points3D.txt", [](std::ostream& stream) {
    stream << "# 3D point list with one line of data per point:\n"
              "#   POINT3D_ID, X, Y, Z, R, G, B, ERROR, TRACK[] as (IMAGE_ID, POINT2D_IDX)\n"
              "# Number of points: 0, mean track length: 0\n";
  });
  if (options.layout == SyntheticSceneOptions::Layout::kAerial || IsHardLayout(options.layout)) {
    const Timer covisibility_timer;
    CovisibilityOptions covisibility_options;
    covisibility_options.seed = options.seed;
    covisibility_options.num_threads = options.num_threads;
    const std::vector<CovisiblePair> pairs =
        ComputeCovisiblePairs(scene, views, covisibility_options);
    WriteFileAtomically(output_dir / "gt" / "overlap_pairs.txt", [&](std::ostream& stream) {
      for (const CovisiblePair& pair : pairs) {
        stream << views.GetImage(pair.image_id1).name << ' ' << views.GetImage(pair.image_id2).name
               << ' ' << pair.num_shared_points << '\n';
      }
    });
    PARALLAX_LOG(Info) << "synthetic scene: " << pairs.size() << " pairs of views share at least "
                       << covisibility_options.min_shared_points << " scene points ("
                       << covisibility_timer.ElapsedSeconds() << " s)";
  }
  PARALLAX_LOG(Info) << "synthetic scene: " << views.NumImages() << " views of " << options.width
                     << "x" << options.height << " in " << output_dir.string() << " ("
                     << scene.NumTemples() << " temple(s), " << timer.ElapsedSeconds() << " s)";
  return views;
}

}  // namespace parallax
