#include "parallax/scene/synthetic_dataset.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <numbers>
#include <random>
#include <string>
#include <vector>

#include "parallax/geometry/essential_matrix.h"
#include "parallax/geometry/look_at.h"
#include "parallax/scene/database.h"
#include "parallax/util/check.h"
#include "parallax/util/logging.h"

namespace parallax {
namespace {

// A local generator keeps the dataset a function of the options alone, whatever the state
// of the thread's shared generator.
class Sampler {
 public:
  explicit Sampler(uint64_t seed) : engine_(seed) {}
  double Uniform(double min, double max) {
    return std::uniform_real_distribution<double>(min, max)(engine_);
  }
  double Gaussian(double stddev) {
    return stddev > 0 ? std::normal_distribution<double>(0.0, stddev)(engine_) : 0.0;
  }
  size_t Index(size_t size) { return std::uniform_int_distribution<size_t>(0, size - 1)(engine_); }
  template <typename T>
  void Shuffle(std::vector<T>* elements) {
    std::shuffle(elements->begin(), elements->end(), engine_);
  }

 private:
  std::mt19937_64 engine_;
};

std::vector<Rigid3d> MakeCameraPoses(const SyntheticDatasetOptions& options, Sampler* sampler) {
  std::vector<Rigid3d> poses;
  const int n = options.num_images;
  const double d = options.camera_distance;
  for (int i = 0; i < n; ++i) {
    Eigen::Vector3d center = Eigen::Vector3d::Zero();
    Eigen::Vector3d target = Eigen::Vector3d::Zero();
    switch (options.layout) {
      case SyntheticDatasetOptions::Layout::kRing: {
        const double angle = 2.0 * std::numbers::pi * i / n;
        center = Eigen::Vector3d(d * std::cos(angle), d * std::sin(angle), 0.3 * d);
        break;
      }
      case SyntheticDatasetOptions::Layout::kHemisphere: {
        const double azimuth = sampler->Uniform(0.0, 2.0 * std::numbers::pi);
        const double elevation = sampler->Uniform(10.0, 70.0) * std::numbers::pi / 180.0;
        center = d * Eigen::Vector3d(std::cos(elevation) * std::cos(azimuth),
                                     std::cos(elevation) * std::sin(azimuth), std::sin(elevation));
        break;
      }
      case SyntheticDatasetOptions::Layout::kSequence: {
        const double x = (i - 0.5 * (n - 1)) * options.sequence_step;
        center = Eigen::Vector3d(x, -d, 0.0);
        target = Eigen::Vector3d(x, 0.0, 0.0);
        break;
      }
    }
    // A little jitter of the aim so that no two cameras share an exact symmetry.
    const double jitter = 0.02 * d;
    target += Eigen::Vector3d(sampler->Gaussian(jitter), sampler->Gaussian(jitter),
                              sampler->Gaussian(jitter));
    poses.push_back(LookAt(center, target));
  }
  return poses;
}

Eigen::Vector3d SamplePoint(const SyntheticDatasetOptions& options, Sampler* sampler) {
  const double r = options.scene_radius;
  if (options.layout != SyntheticDatasetOptions::Layout::kSequence) {
    return Eigen::Vector3d(sampler->Uniform(-r, r), sampler->Uniform(-r, r),
                           sampler->Uniform(-r, r));
  }
  // A slab along the path, wide and tall enough to fill the views.
  const double half_length = 0.5 * (options.num_images - 1) * options.sequence_step;
  const double half_width = options.camera_distance * 0.5 * options.width / options.focal_length;
  const double half_height = options.camera_distance * 0.5 * options.height / options.focal_length;
  return Eigen::Vector3d(sampler->Uniform(-half_length - half_width, half_length + half_width),
                         sampler->Uniform(-r, r), sampler->Uniform(-half_height, half_height));
}

// A SIFT-like descriptor: non-negative, L2 norm 512 as in COLMAP's uint8 normalisation.
Eigen::VectorXd RandomDescriptor(Sampler* sampler) {
  Eigen::VectorXd descriptor(128);
  for (int i = 0; i < 128; ++i) {
    const double value = sampler->Uniform(0.0, 1.0);
    descriptor(i) = value * value;
  }
  return descriptor * (512.0 / descriptor.norm());
}

void StoreDescriptor(const Eigen::VectorXd& descriptor, FeatureDescriptors* descriptors,
                     size_t row) {
  for (int i = 0; i < 128; ++i) {
    (*descriptors)(row, i) =
        static_cast<uint8_t>(std::clamp(std::round(descriptor(i)), 0.0, 255.0));
  }
}

// Angle in radians between the rays from two camera centres to a point.
double TriangulationAngle(const Eigen::Vector3d& center1, const Eigen::Vector3d& center2,
                          const Eigen::Vector3d& point) {
  const Eigen::Vector3d ray1 = (point - center1).normalized();
  const Eigen::Vector3d ray2 = (point - center2).normalized();
  return std::acos(std::clamp(ray1.dot(ray2), -1.0, 1.0));
}

}  // namespace

void SyntheticDatasetOptions::Check() const {
  PARALLAX_CHECK_GT(num_cameras, 0);
  PARALLAX_CHECK_GE(num_images, num_cameras);
  PARALLAX_CHECK_GE(num_images, 2);
  PARALLAX_CHECK_GE(num_points3D, 0);
  PARALLAX_CHECK(ExistsCameraModel(static_cast<int>(camera_model_id)));
  PARALLAX_CHECK_GT(width, 0);
  PARALLAX_CHECK_GT(height, 0);
  PARALLAX_CHECK_GT(focal_length, 0.0);
  PARALLAX_CHECK_GT(scene_radius, 0.0);
  PARALLAX_CHECK_GT(camera_distance, 0.0);
  PARALLAX_CHECK_GT(sequence_step, 0.0);
  PARALLAX_CHECK_GE(point2D_noise_stddev, 0.0);
  PARALLAX_CHECK_GE(outlier_ratio, 0.0);
  PARALLAX_CHECK_GE(min_track_length, 2);
  PARALLAX_CHECK_LE(min_track_length, num_images);
  PARALLAX_CHECK_GT(min_depth, 0.0);
  if (layout != Layout::kSequence) {
    PARALLAX_CHECK_MSG(camera_distance > std::sqrt(3.0) * scene_radius + min_depth,
                       "cameras must be outside the cube of points");
  }
}

void SynthesizeDataset(const SyntheticDatasetOptions& options, Reconstruction* truth) {
  options.Check();
  PARALLAX_CHECK(truth != nullptr);
  PARALLAX_CHECK_EQ(truth->NumCameras() + truth->NumImages() + truth->NumPoints3D(), 0u);
  Sampler sampler(options.seed);

  std::vector<Camera> cameras;
  for (int k = 0; k < options.num_cameras; ++k) {
    Camera camera =
        Camera::Create(static_cast<camera_t>(k + 1), options.camera_model_id,
                       options.focal_length * (1.0 + 0.05 * k), options.width, options.height);
    const std::vector<int> extra_idxs = CameraModelExtraIdxs(options.camera_model_id);
    if (!extra_idxs.empty()) camera.params[extra_idxs[0]] = options.distortion;
    camera.has_prior_focal_length = true;
    cameras.push_back(camera);
  }
  const std::vector<Rigid3d> poses = MakeCameraPoses(options, &sampler);

  // Candidate points are kept when enough images see them.
  struct Observation {
    int point_idx;  // -1 for an outlier keypoint
    Eigen::Vector2d xy;
  };
  std::vector<std::vector<Observation>> observations(options.num_images);
  std::vector<Eigen::Vector3d> points;
  const int max_attempts = 100 * options.num_points3D + 1000;
  std::vector<std::pair<int, Eigen::Vector2d>> visible;
  for (int attempt = 0;
       attempt < max_attempts && static_cast<int>(points.size()) < options.num_points3D;
       ++attempt) {
    const Eigen::Vector3d xyz = SamplePoint(options, &sampler);
    visible.clear();
    for (int i = 0; i < options.num_images; ++i) {
      const Eigen::Vector3d point_in_cam = poses[i] * xyz;
      if (point_in_cam.z() < options.min_depth) continue;
      const Eigen::Vector2d xy = cameras[i % options.num_cameras].ImgFromCam(point_in_cam);
      if (xy.x() < 0 || xy.y() < 0 || xy.x() > options.width || xy.y() > options.height) continue;
      visible.emplace_back(i, xy);
    }
    if (static_cast<int>(visible.size()) < options.min_track_length) continue;
    const int point_idx = static_cast<int>(points.size());
    points.push_back(xyz);
    for (const auto& [i, xy] : visible) {
      const Eigen::Vector2d noise(sampler.Gaussian(options.point2D_noise_stddev),
                                  sampler.Gaussian(options.point2D_noise_stddev));
      observations[i].push_back({point_idx, xy + noise});
    }
  }
  PARALLAX_CHECK_MSG(static_cast<int>(points.size()) == options.num_points3D,
                     "only " << points.size() << " of " << options.num_points3D
                             << " points are seen by " << options.min_track_length
                             << " images; widen the views or shrink the scene");

  std::vector<Track> tracks(points.size());
  for (int i = 0; i < options.num_images; ++i) {
    std::vector<Observation>& image_observations = observations[i];
    const int num_outliers =
        static_cast<int>(std::lround(options.outlier_ratio * image_observations.size()));
    for (int k = 0; k < num_outliers; ++k) {
      image_observations.push_back({-1, Eigen::Vector2d(sampler.Uniform(0.0, options.width),
                                                        sampler.Uniform(0.0, options.height))});
    }
    sampler.Shuffle(&image_observations);

    Image image;
    image.image_id = static_cast<image_t>(i + 1);
    image.camera_id = cameras[i % options.num_cameras].camera_id;
    char name[32];
    std::snprintf(name, sizeof(name), "image%04d.png", i + 1);
    image.name = name;
    image.cam_from_world = poses[i];
    image.points2D.resize(image_observations.size());
    for (size_t k = 0; k < image_observations.size(); ++k) {
      image.points2D[k].xy = image_observations[k].xy;
      if (image_observations[k].point_idx >= 0) {
        tracks[image_observations[k].point_idx].AddElement(image.image_id,
                                                           static_cast<point2D_t>(k));
      }
    }
    if (i < options.num_cameras) truth->AddCamera(cameras[i]);
    truth->AddImage(std::move(image));
    truth->RegisterImage(static_cast<image_t>(i + 1));
  }
  for (size_t p = 0; p < points.size(); ++p) {
    const Eigen::Matrix<uint8_t, 3, 1> color(static_cast<uint8_t>(sampler.Index(256)),
                                             static_cast<uint8_t>(sampler.Index(256)),
                                             static_cast<uint8_t>(sampler.Index(256)));
    truth->AddPoint3D(points[p], std::move(tracks[p]), color);
  }
}

void SyntheticDatabaseOptions::Check() const {
  PARALLAX_CHECK_GE(outlier_match_ratio, 0.0);
  PARALLAX_CHECK_GE(min_num_matches, 1);
  PARALLAX_CHECK_GE(descriptor_noise_stddev, 0.0);
}

void WriteSyntheticDatabase(const Reconstruction& truth, Database* database,
                            const SyntheticDatabaseOptions& options) {
  options.Check();
  PARALLAX_CHECK(database != nullptr);
  Sampler sampler(options.seed);
  // One transaction for everything: far faster than one per write.
  DatabaseTransaction transaction(database);
  for (const auto& [camera_id, camera] : truth.Cameras()) {
    database->WriteCamera(camera, /*use_camera_id=*/true);
  }

  std::map<point3D_t, Eigen::VectorXd> point_descriptors;
  for (const auto& [point3D_id, point] : truth.Points3D()) {
    point_descriptors.emplace(point3D_id, RandomDescriptor(&sampler));
  }
  std::map<image_t, image_t> database_image_ids;
  for (const auto& [image_id, image] : truth.Images()) {
    FeatureKeypoints keypoints;
    keypoints.reserve(image.points2D.size());
    FeatureDescriptors descriptors(image.points2D.size(), 128);
    for (size_t k = 0; k < image.points2D.size(); ++k) {
      const Point2D& point2D = image.points2D[k];
      keypoints.emplace_back(
          static_cast<float>(point2D.xy.x()), static_cast<float>(point2D.xy.y()),
          static_cast<float>(sampler.Uniform(1.5, 6.0)),
          static_cast<float>(sampler.Uniform(-std::numbers::pi, std::numbers::pi)));
      Eigen::VectorXd descriptor;
      if (point2D.HasPoint3D()) {
        descriptor = point_descriptors.at(point2D.point3D_id);
        for (int i = 0; i < 128; ++i)
          descriptor(i) += sampler.Gaussian(options.descriptor_noise_stddev);
      } else {
        descriptor = RandomDescriptor(&sampler);
      }
      StoreDescriptor(descriptor, &descriptors, k);
    }
    database_image_ids[image_id] =
        database->WriteImageWithFeatures(image.name, image.camera_id, keypoints, descriptors);
  }

  // The true matches: every pair of observations of one point (smaller truth id first).
  std::map<std::pair<image_t, image_t>, FeatureMatches> pair_matches;
  for (const auto& [point3D_id, point] : truth.Points3D()) {
    const std::vector<TrackElement>& elements = point.track.elements;
    for (size_t a = 0; a < elements.size(); ++a) {
      for (size_t b = 0; b < elements.size(); ++b) {
        if (elements[a].image_id >= elements[b].image_id) continue;
        pair_matches[{elements[a].image_id, elements[b].image_id}].push_back(
            {elements[a].point2D_idx, elements[b].point2D_idx});
      }
    }
  }

  for (auto& [pair, matches] : pair_matches) {
    if (static_cast<int>(matches.size()) < options.min_num_matches) continue;
    const Image& image1 = truth.GetImage(pair.first);
    const Image& image2 = truth.GetImage(pair.second);
    const Camera& camera1 = truth.GetCamera(image1.camera_id);
    const Camera& camera2 = truth.GetCamera(image2.camera_id);

    TwoViewGeometry geometry;
    geometry.inlier_matches = matches;
    const Rigid3d cam2_from_cam1 = image2.cam_from_world * image1.cam_from_world.Inverse();
    const double baseline = cam2_from_cam1.translation.norm();
    geometry.cam2_from_cam1 = cam2_from_cam1;
    if (baseline > 1e-12) {
      geometry.config = TwoViewGeometry::kCalibrated;
      geometry.cam2_from_cam1.translation /= baseline;
      geometry.E = EssentialFromPose(geometry.cam2_from_cam1);
      geometry.F = FundamentalFromEssential(geometry.E, camera1.CalibrationMatrix(),
                                            camera2.CalibrationMatrix());
    } else {
      geometry.config = TwoViewGeometry::kPanoramic;
    }
    std::vector<double> angles;
    angles.reserve(matches.size());
    for (const FeatureMatch& match : matches) {
      const point3D_t point3D_id = image1.points2D[match.point2D_idx1].point3D_id;
      angles.push_back(TriangulationAngle(image1.ProjectionCenter(), image2.ProjectionCenter(),
                                          truth.GetPoint3D(point3D_id).xyz));
    }
    std::nth_element(angles.begin(), angles.begin() + angles.size() / 2, angles.end());
    geometry.triangulation_angle = angles[angles.size() / 2];

    // Wrong matches go to the raw matches only, preferably between outlier keypoints.
    std::vector<point2D_t> free1, free2;
    for (point2D_t k = 0; k < image1.points2D.size(); ++k) {
      if (!image1.points2D[k].HasPoint3D()) free1.push_back(k);
    }
    for (point2D_t k = 0; k < image2.points2D.size(); ++k) {
      if (!image2.points2D[k].HasPoint3D()) free2.push_back(k);
    }
    const auto pick = [&](const Image& image, const std::vector<point2D_t>& free) {
      return free.empty() ? static_cast<point2D_t>(sampler.Index(image.points2D.size()))
                          : free[sampler.Index(free.size())];
    };
    const size_t num_outliers = std::lround(options.outlier_match_ratio * matches.size());
    FeatureMatches raw_matches = matches;
    for (size_t k = 0; k < num_outliers; ++k) {
      const point2D_t idx1 = pick(image1, free1);
      const point2D_t idx2 = pick(image2, free2);
      const point3D_t id1 = image1.points2D[idx1].point3D_id;
      if (id1 != kInvalidPoint3DId && id1 == image2.points2D[idx2].point3D_id) continue;
      raw_matches.push_back({idx1, idx2});
    }
    sampler.Shuffle(&raw_matches);

    const image_t database_id1 = database_image_ids.at(pair.first);
    const image_t database_id2 = database_image_ids.at(pair.second);
    database->WriteMatches(database_id1, database_id2, raw_matches);
    database->WriteTwoViewGeometry(database_id1, database_id2, geometry);
  }
  transaction.Commit();
  PARALLAX_LOG(Debug) << "synthetic database: " << truth.NumImages() << " images, "
                      << pair_matches.size() << " matched pairs";
}

}  // namespace parallax
