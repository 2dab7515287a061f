#include "parallax/render/renderer.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <opencv2/imgproc.hpp>
#include <vector>

#include "parallax/util/check.h"
#include "parallax/util/threading.h"

namespace parallax {
namespace {

// Radiance along one ray. `sample_angle` is the angle between neighbouring samples, which
// sets the texture footprint.
Eigen::Vector3f Trace(const SceneModel& scene, const Eigen::Vector3d& origin,
                      const Eigen::Vector3d& direction, double sample_angle,
                      const RenderOptions& options) {
  SurfaceHit hit;
  if (!scene.Intersect(origin, direction, std::numeric_limits<double>::infinity(), &hit)) {
    return SceneModel::SkyColor(direction);
  }
  // Surfaces seen at grazing angles stretch the footprint along the slope by 1 / cosine; the
  // geometric mean of the two axes keeps detail there without much aliasing.
  const double cosine = std::max(std::abs(hit.normal.dot(direction)), 0.02);
  const double footprint = hit.distance * sample_angle / std::sqrt(cosine);
  const Eigen::Vector3f albedo = scene.Albedo(hit, footprint);
  double sun = std::max(0.0, hit.normal.dot(options.sun_direction));
  if (options.shadows && sun > 0.0 &&
      scene.Occluded(hit.point + 1e-6 * hit.distance * hit.normal, options.sun_direction,
                     std::numeric_limits<double>::infinity())) {
    sun = 0.0;
  }
  return albedo * static_cast<float>(options.ambient_intensity + options.sun_intensity * sun);
}

}  // namespace

void RenderOptions::Check() const {
  PARALLAX_CHECK_MSG(std::abs(sun_direction.norm() - 1.0) < 1e-6,
                     "sun_direction must be a unit vector");
  PARALLAX_CHECK_GE(sun_intensity, 0.0);
  PARALLAX_CHECK_GE(ambient_intensity, 0.0);
  PARALLAX_CHECK_GT(exposure, 0.0);
  PARALLAX_CHECK_GE(blur_sigma, 0.0);
  PARALLAX_CHECK_GE(noise_stddev, 0.0);
}

cv::Mat RenderView(const SceneModel& scene, const Camera& camera, const Rigid3d& cam_from_world,
                   const RenderOptions& options, cv::Mat* depth) {
  options.Check();
  PARALLAX_CHECK(camera.VerifyParams());
  PARALLAX_CHECK_GT(camera.width, 0u);
  PARALLAX_CHECK_GT(camera.height, 0u);
  const int width = static_cast<int>(camera.width), height = static_cast<int>(camera.height);
  const bool pinhole = IsPinholeCameraModel(camera.model_id);
  const double fx = pinhole ? camera.FocalLengthX() : 0.0,
               fy = pinhole ? camera.FocalLengthY() : 0.0;
  const double cx = pinhole ? camera.PrincipalPointX() : 0.0;
  const double cy = pinhole ? camera.PrincipalPointY() : 0.0;
  const bool perspective = camera.Projection() == CameraProjection::kPerspective;
  const Eigen::Matrix3d world_from_cam = cam_from_world.rotation.toRotationMatrix().transpose();
  const Eigen::Vector3d origin = ProjectionCenter(cam_from_world);
  // Angle between neighbouring rays near the optical axis: textures average out detail
  // finer than that.
  const double pixel_angle = camera.CamFromImgThreshold(1.0);
  const double sample_angle =
      options.antialiasing == Antialiasing::kQuincunx
          ? pixel_angle / std::sqrt(2.0)
          : (options.antialiasing == Antialiasing::kGrid3x3 ? pixel_angle / 3.0 : pixel_angle);
  const auto ray_in_cam = [&](double x, double y) -> Eigen::Vector3d {
    if (pinhole) return Eigen::Vector3d((x - cx) / fx, (y - cy) / fy, 1.0);
    // Every other lens through its own unprojection: fisheye rays beyond 90 degrees from
    // the axis and the whole sphere included.
    return camera.CamRayFromImg(Eigen::Vector2d(x, y));
  };
  const auto sample = [&](double x, double y) -> Eigen::Vector3f {
    return Trace(scene, origin, (world_from_cam * ray_in_cam(x, y)).normalized(), sample_angle,
                 options);
  };

  // Quincunx: the (width + 1) x (height + 1) pixel corners first, shared by neighbours.
  std::vector<Eigen::Vector3f> corners;
  if (options.antialiasing == Antialiasing::kQuincunx) {
    corners.resize(static_cast<size_t>(width + 1) * (height + 1));
    ParallelFor(0, height + 1, options.num_threads, [&](size_t row) {
      for (int col = 0; col <= width; ++col) corners[row * (width + 1) + col] = sample(col, row);
    });
  }

  cv::Mat image(height, width, CV_32FC3);
  if (depth != nullptr) depth->create(height, width, CV_32FC1);
  ParallelFor(0, height, options.num_threads, [&](size_t row) {
    cv::Vec3f* image_row = image.ptr<cv::Vec3f>(static_cast<int>(row));
    float* depth_row = depth != nullptr ? depth->ptr<float>(static_cast<int>(row)) : nullptr;
    for (int col = 0; col < width; ++col) {
      Eigen::Vector3f color = Eigen::Vector3f::Zero();
      switch (options.antialiasing) {
        case Antialiasing::kNone:
          color = sample(col + 0.5, row + 0.5);
          break;
        case Antialiasing::kQuincunx: {
          const Eigen::Vector3f* top = &corners[row * (width + 1) + col];
          const Eigen::Vector3f* bottom = top + (width + 1);
          color = 0.5f * sample(col + 0.5, row + 0.5) +
                  0.125f * (top[0] + top[1] + bottom[0] + bottom[1]);
          break;
        }
        case Antialiasing::kGrid3x3:
          for (int sy = 0; sy < 3; ++sy) {
            for (int sx = 0; sx < 3; ++sx)
              color += sample(col + (sx + 0.5) / 3.0, row + (sy + 0.5) / 3.0);
          }
          color /= 9.0f;
          break;
      }
      image_row[col] = cv::Vec3f(color.z(), color.y(), color.x());  // BGR
      if (depth_row != nullptr) {
        const Eigen::Vector3d ray = ray_in_cam(col + 0.5, row + 0.5);
        const Eigen::Vector3d direction = world_from_cam * ray;
        // z in the camera frame for a perspective lens; the distance along the ray for
        // the others, whose rays reach behind the image plane.
        const double along_z = perspective ? ray.z() : 1.0;
        SurfaceHit hit;
        depth_row[col] = scene.Intersect(origin, direction.normalized(),
                                         std::numeric_limits<double>::infinity(), &hit)
                             ? static_cast<float>(hit.distance * along_z / direction.norm())
                             : 0.0f;
      }
    }
  });

  if (options.blur_sigma > 0.0) {
    cv::GaussianBlur(image, image, cv::Size(), options.blur_sigma, options.blur_sigma,
                     cv::BORDER_REFLECT);
  }
  image *= options.exposure;
  if (options.noise_stddev > 0.0) {
    cv::Mat noise(image.size(), image.type());
    cv::RNG rng(options.noise_seed);
    rng.fill(noise, cv::RNG::NORMAL, 0.0, options.noise_stddev / 255.0);
    image += noise;
  }
  cv::Mat result;
  image.convertTo(result, CV_8UC3, 255.0);
  return result;
}

}  // namespace parallax
