// How much of the true tracks a mapper recovers (issue 20), on a synthetic scene whose
// verified matches were damaged the way real ones are: some missing, some wrong.
//
//   track_recovery make OUT [--images N] [--points N] [--drop F] [--wrong F] [--seed S]
//       writes OUT/database.db (COLMAP schema: keypoints, matches, verified geometries whose
//       inliers are the true matches less a share F dropped, with a share F replaced by the
//       nearest keypoint of another point) and OUT/truth/ (the exact model).
//   track_recovery score OUT MODEL
//       prints one JSON line: the share of the true observations (in the model's registered
//       images) that the model holds in a point made mostly of the same true point, the share
//       of its observations that belong to another true point, model points per true point,
//       and the mean track length.
//
// Not a Google Benchmark: it measures quality, and any mapper (this build's, an older one,
// COLMAP's) can be run between `make` and `score`; bench/track_recovery.sh does that.

#include <cstdlib>
#include <filesystem>
#include <iostream>
#include <limits>
#include <map>
#include <random>
#include <string>

#include "parallax/scene/colmap_io.h"
#include "parallax/scene/database.h"
#include "parallax/scene/synthetic_dataset.h"

namespace parallax {
namespace {

struct DamageOptions {
  double drop = 0.3;    // Share of the true matches left out.
  double wrong = 0.05;  // Share replaced by the nearest keypoint of another point.
  uint64_t seed = 7;
};

// The keypoint of image `image` nearest to `xy` that sees a point other than `point3D_id`.
point2D_t NearestOtherKeypoint(const Image& image, const Eigen::Vector2d& xy,
                               point3D_t point3D_id) {
  point2D_t best = kInvalidPoint2DIdx;
  double best_distance = std::numeric_limits<double>::max();
  for (point2D_t idx = 0; idx < image.points2D.size(); ++idx) {
    const Point2D& point2D = image.points2D[idx];
    if (!point2D.HasPoint3D() || point2D.point3D_id == point3D_id) continue;
    const double distance = (point2D.xy - xy).squaredNorm();
    if (distance < best_distance) {
      best_distance = distance;
      best = idx;
    }
  }
  return best;
}

void DamageVerifiedMatches(const Reconstruction& truth, const DamageOptions& options,
                           Database* database) {
  std::mt19937_64 generator(options.seed);
  std::uniform_real_distribution<double> uniform(0.0, 1.0);
  DatabaseTransaction transaction(database);
  for (auto [pair_id, geometry] : database->ReadTwoViewGeometries()) {
    const auto [image_id1, image_id2] = PairIdToImagePair(pair_id);
    const Image& image2 = truth.GetImage(image_id2);
    FeatureMatches damaged;
    for (const FeatureMatch& match : geometry.inlier_matches) {
      const double draw = uniform(generator);
      if (draw < options.drop) continue;
      if (draw < options.drop + options.wrong) {
        const Point2D& true_match = image2.points2D[match.point2D_idx2];
        const point2D_t other = NearestOtherKeypoint(image2, true_match.xy, true_match.point3D_id);
        if (other != kInvalidPoint2DIdx) damaged.push_back({match.point2D_idx1, other});
        continue;
      }
      damaged.push_back(match);
    }
    geometry.inlier_matches = damaged;
    database->DeleteTwoViewGeometry(image_id1, image_id2);
    database->WriteTwoViewGeometry(image_id1, image_id2, geometry);
  }
  transaction.Commit();
}

int Make(const std::filesystem::path& out, SyntheticDatasetOptions scene,
         const DamageOptions& damage) {
  std::filesystem::remove_all(out);
  std::filesystem::create_directories(out / "truth");
  Reconstruction truth;
  SynthesizeDataset(scene, &truth);
  WriteReconstructionBinary(truth, out / "truth");
  Database database(out / "database.db");
  WriteSyntheticDatabase(truth, &database);
  DamageVerifiedMatches(truth, damage, &database);
  std::cerr << "track_recovery: " << truth.NumImages() << " images, " << truth.NumPoints3D()
            << " points, " << truth.NumObservations() << " observations -> " << out << "\n";
  return 0;
}

int Score(const std::filesystem::path& out, const std::filesystem::path& model_dir) {
  const Reconstruction truth = ReadReconstruction(out / "truth");
  const Reconstruction model = ReadReconstruction(model_dir);
  // Images are matched by name: a mapper may number them its own way.
  std::map<std::string, image_t> truth_id_of_name;
  for (const auto& [image_id, image] : truth.Images()) truth_id_of_name[image.name] = image_id;
  auto true_point_of = [&](const TrackElement& element) {
    const image_t truth_id = truth_id_of_name.at(model.GetImage(element.image_id).name);
    return truth.GetImage(truth_id).points2D[element.point2D_idx].point3D_id;
  };

  size_t num_true = 0;
  for (const image_t image_id : model.RegImageIds()) {
    const image_t truth_id = truth_id_of_name.at(model.GetImage(image_id).name);
    for (const Point2D& point2D : truth.GetImage(truth_id).points2D) {
      num_true += point2D.HasPoint3D();
    }
  }
  size_t num_right = 0, num_wrong = 0, num_points = 0;
  std::map<point3D_t, size_t> points_per_truth;
  for (const auto& [point3D_id, point] : model.Points3D()) {
    std::map<point3D_t, size_t> votes;
    for (const TrackElement& element : point.track.elements) ++votes[true_point_of(element)];
    point3D_t majority = kInvalidPoint3DId;
    size_t majority_votes = 0;
    for (const auto& [truth_id, count] : votes) {
      if (truth_id != kInvalidPoint3DId && count > majority_votes) {
        majority = truth_id;
        majority_votes = count;
      }
    }
    num_right += majority_votes;
    num_wrong += point.track.Length() - majority_votes;
    ++num_points;
    if (majority != kInvalidPoint3DId) ++points_per_truth[majority];
  }
  const size_t num_observations = num_right + num_wrong;
  std::cout << "{\"registered\": " << model.NumRegImages() << ", \"images\": " << truth.NumImages()
            << ", \"points3D\": " << num_points << ", \"observations\": " << num_observations
            << ", \"true_observations_recovered\": "
            << (num_true ? static_cast<double>(num_right) / num_true : 0.0)
            << ", \"wrong_observations\": "
            << (num_observations ? static_cast<double>(num_wrong) / num_observations : 0.0)
            << ", \"points_per_true_point\": "
            << (points_per_truth.empty()
                    ? 0.0
                    : static_cast<double>(num_points) / points_per_truth.size())
            << ", \"mean_track_length\": " << model.ComputeMeanTrackLength() << "}\n";
  return 0;
}

int Usage() {
  std::cerr << "usage: track_recovery make OUT [--images N] [--points N] [--drop F] "
               "[--wrong F] [--seed S]\n       track_recovery score OUT MODEL\n";
  return 2;
}

}  // namespace
}  // namespace parallax

int main(int argc, char** argv) {
  using namespace parallax;
  if (argc < 3) return Usage();
  const std::string command = argv[1];
  if (command == "score") return argc == 4 ? Score(argv[2], argv[3]) : Usage();
  if (command != "make") return Usage();
  SyntheticDatasetOptions scene;
  scene.num_images = 36;
  scene.num_points3D = 3000;
  scene.point2D_noise_stddev = 0.5;
  scene.min_track_length = 2;
  DamageOptions damage;
  for (int i = 3; i + 1 < argc; i += 2) {
    const std::string flag = argv[i];
    const char* value = argv[i + 1];
    if (flag == "--images") {
      scene.num_images = std::atoi(value);
    } else if (flag == "--points") {
      scene.num_points3D = std::atoi(value);
    } else if (flag == "--drop") {
      damage.drop = std::atof(value);
    } else if (flag == "--wrong") {
      damage.wrong = std::atof(value);
    } else if (flag == "--seed") {
      scene.seed = damage.seed = std::strtoull(value, nullptr, 10);
    } else {
      return Usage();
    }
  }
  return Make(argv[2], scene, damage);
}
