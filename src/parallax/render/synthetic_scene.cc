#include "parallax/render/synthetic_scene.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <iomanip>
#include <numbers>
#include <ostream>
#include <random>

#include "parallax/feature/image_codecs.h"
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

// cam_from_world of a camera at `center` looking at `target`: x right, y down, image up
// towards world +z.
Rigid3d LookAt(const Eigen::Vector3d& center, const Eigen::Vector3d& target) {
  const Eigen::Vector3d forward = (target - center).normalized();
  const Eigen::Vector3d right = forward.cross(Eigen::Vector3d::UnitZ()).normalized();
  const Eigen::Vector3d down = forward.cross(right);
  Eigen::Matrix3d rotation;
  rotation.row(0) = right.transpose();
  rotation.row(1) = down.transpose();
  rotation.row(2) = forward.transpose();
  return Rigid3d(rotation, -rotation * center);
}

std::string ViewName(int view_idx) {
  char name[32];
  std::snprintf(name, sizeof(name), "view_%04d.png", view_idx + 1);
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
  PARALLAX_CHECK(!name.empty());
}

SyntheticSceneOptions::Layout SyntheticSceneLayoutFromName(const std::string& name) {
  if (name == "ring") return SyntheticSceneOptions::Layout::kRing;
  if (name == "hemisphere") return SyntheticSceneOptions::Layout::kHemisphere;
  if (name == "sequence") return SyntheticSceneOptions::Layout::kSequence;
  throw InputError("unknown layout '" + name + "' (expected ring, hemisphere or sequence)");
}

SceneModelOptions SyntheticSceneModelOptions(const SyntheticSceneOptions& options) {
  SceneModelOptions scene_options;
  scene_options.seed = options.seed;
  if (options.layout == SyntheticSceneOptions::Layout::kSequence) {
    scene_options.num_temples =
        1 + static_cast<int>(std::lround(SequenceLength(options) / scene_options.temple_spacing));
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
  views.AddCamera(Camera::Create(1, CameraModelId::kPinhole, focal_length, options.width, options.height));
  views.GetCamera(1).has_prior_focal_length = true;
  const int n = options.num_views;
  for (int i = 0; i < n; ++i) {
    Eigen::Vector3d center = Eigen::Vector3d::Zero();
    Eigen::Vector3d target = Eigen::Vector3d::Zero();
    switch (options.layout) {
      case SyntheticSceneOptions::Layout::kRing: {
        const double azimuth = phase + 2.0 * std::numbers::pi * i / n;
        const double radius = 21.0 * zoom;
        center = Eigen::Vector3d(radius * std::cos(azimuth), radius * std::sin(azimuth), 0.45 * radius);
        target = Eigen::Vector3d(0.0, 0.0, 3.0);
        break;
      }
      case SyntheticSceneOptions::Layout::kHemisphere: {
        // A spiral, so that consecutive views stay close (about 15 degrees apart or less).
        const double turns = std::max(1.0, n / 24.0);
        const double azimuth = phase + 2.0 * std::numbers::pi * turns * i / n;
        const double elevation = (10.0 + 55.0 * i / (n - 1)) * kDegrees;
        const double radius = 23.0 * zoom;
        center = radius * Eigen::Vector3d(std::cos(elevation) * std::cos(azimuth),
                                          std::cos(elevation) * std::sin(azimuth), std::sin(elevation));
        center.z() += 1.0;
        target = Eigen::Vector3d(0.0, 0.0, 2.5);
        break;
      }
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
    image.name = ViewName(i);
    image.cam_from_world = LookAt(center, target);
    views.AddImage(std::move(image));
    views.RegisterImage(static_cast<image_t>(i + 1));
  }
  return views;
}

RenderOptions SyntheticSceneRenderOptions(const SyntheticSceneOptions& options, int view_idx) {
  RenderOptions render_options;
  render_options.antialiasing = options.antialiasing;
  render_options.shadows = options.shadows;
  render_options.blur_sigma = options.blur_sigma;
  render_options.noise_stddev = options.noise_stddev;
  render_options.noise_seed = Mix32(static_cast<uint32_t>(options.seed) ^ Mix32(view_idx + 1)) +
                              (options.seed >> 32);
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
        Eigen::Vector3d(std::cos(elevation) * std::cos(azimuth), std::cos(elevation) * std::sin(azimuth),
                        std::sin(elevation));
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

  // Whole views per thread: rendering and PNG encoding then both run in parallel.
  const std::vector<image_t> image_ids = views.RegImageIds();
  ParallelFor(0, image_ids.size(), options.num_threads, [&](size_t i) {
    const Image& image = views.GetImage(image_ids[i]);
    RenderOptions render_options = SyntheticSceneRenderOptions(options, static_cast<int>(i));
    render_options.num_threads = 1;
    const cv::Mat rendered = RenderView(scene, camera, image.cam_from_world, render_options);
    const std::string png = EncodePng(rendered);
    WriteFileAtomically(output_dir / image.name, [&png](std::ostream& stream) {
      stream.write(reinterpret_cast<const char*>(png.data()), static_cast<std::streamsize>(png.size()));
    }, /*binary=*/true);
    PARALLAX_LOG(Debug) << "rendered " << image.name;
  });

  const Eigen::Matrix3d K = camera.CalibrationMatrix();
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
      stream << image_id << ' ' << q.w() << ' ' << q.x() << ' ' << q.y() << ' ' << q.z() << ' ' << t.x()
             << ' ' << t.y() << ' ' << t.z() << ' ' << image.camera_id << ' ' << image.name << "\n\n";
    }
  });
  WriteFileAtomically(output_dir / "gt" / "points3D.txt", [](std::ostream& stream) {
    stream << "# 3D point list with one line of data per point:\n"
              "#   POINT3D_ID, X, Y, Z, R, G, B, ERROR, TRACK[] as (IMAGE_ID, POINT2D_IDX)\n"
              "# Number of points: 0, mean track length: 0\n";
  });
  PARALLAX_LOG(Info) << "synthetic scene: " << views.NumImages() << " views of " << options.width << "x"
                     << options.height << " in " << output_dir.string() << " ("
                     << scene.Options().num_temples << " temple(s), " << timer.ElapsedSeconds() << " s)";
  return views;
}

}  // namespace parallax
