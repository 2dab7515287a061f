#include "parallax/report/ground_truth.h"

#include <Eigen/Core>
#include <Eigen/SVD>
#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <sstream>

#include "parallax/scene/colmap_io.h"
#include "parallax/util/check.h"
#include "parallax/util/file.h"
#include "parallax/util/logging.h"

namespace parallax {
namespace {

// Rotation matrices in the data sets carry 6 to 20 digits; anything further from
// orthonormal than this is a broken file, not rounding.
constexpr double kMaxRotationDeviation = 1e-3;
// Bounds that keep the conversions of parsed doubles to integers defined (a cast of 1e300 to
// size_t is undefined behaviour), far above any real data set.
constexpr double kMaxNumViews = 1e7;
constexpr double kMaxImageSide = 1e6;

[[noreturn]] void ThrowAt(const std::string& source, size_t line_number,
                          const std::string& reason) {
  throw InputError(source + ":" + std::to_string(line_number) + ": " + reason);
}

std::vector<std::string> Tokenize(const std::string& line) {
  std::istringstream stream(line);
  std::vector<std::string> tokens;
  std::string token;
  while (stream >> token) tokens.push_back(token);
  return tokens;
}

double ParseFinite(const std::string& token, const std::string& source, size_t line_number) {
  char* end = nullptr;
  const double value = std::strtod(token.c_str(), &end);
  if (token.empty() || end != token.c_str() + token.size() || !std::isfinite(value)) {
    ThrowAt(source, line_number, "not a finite number: '" + token + "'");
  }
  return value;
}

// The nearest rotation to a matrix that must already be one up to rounding.
Eigen::Matrix3d CheckedRotation(const Eigen::Matrix3d& matrix, const std::string& source,
                                size_t line_number) {
  const double deviation = (matrix.transpose() * matrix - Eigen::Matrix3d::Identity()).norm();
  // Written so that NaN (from huge entries: inf - inf) fails too.
  if (!(deviation <= kMaxRotationDeviation) || !(matrix.determinant() > 0)) {
    ThrowAt(source, line_number,
            "R is not a rotation matrix (|RᵀR - I| = " + std::to_string(deviation) +
                ", det = " + std::to_string(matrix.determinant()) + ")");
  }
  const Eigen::JacobiSVD<Eigen::Matrix3d> svd(matrix, Eigen::ComputeFullU | Eigen::ComputeFullV);
  return svd.matrixU() * svd.matrixV().transpose();
}

Camera CameraFromK(const Eigen::Matrix3d& K, size_t width, size_t height, const std::string& source,
                   size_t line_number) {
  if (K(0, 0) <= 0 || K(1, 1) <= 0 || K(1, 0) != 0 || K(2, 0) != 0 || K(2, 1) != 0 ||
      K(2, 2) != 1) {
    ThrowAt(source, line_number,
            "K must be upper triangular with positive focal lengths and K33 = 1");
  }
  if (K(0, 1) != 0) {
    PARALLAX_LOG(Warning) << source << ":" << line_number << ": ignoring skew " << K(0, 1);
  }
  Camera camera;
  camera.model_id = CameraModelId::kPinhole;
  camera.width = width;
  camera.height = height;
  camera.params = {K(0, 0), K(1, 1), K(0, 2), K(1, 2)};
  camera.has_prior_focal_length = true;
  return camera;
}

// Reads the next non-empty line into `tokens`; false at the end of the stream.
bool NextTokens(std::istream& stream, size_t* line_number, std::vector<std::string>* tokens) {
  std::string line;
  while (std::getline(stream, line)) {
    ++*line_number;
    *tokens = Tokenize(line);
    if (!tokens->empty()) return true;
  }
  return false;
}

}  // namespace

GroundTruth ReadMiddleburyGroundTruth(std::istream& stream, const std::string& source) {
  GroundTruth truth;
  truth.source = source;
  size_t line_number = 0;
  std::vector<std::string> tokens;
  if (!NextTokens(stream, &line_number, &tokens)) ThrowAt(source, 1, "empty file");
  if (tokens.size() != 1) ThrowAt(source, line_number, "expected the number of views alone");
  const double count_value = ParseFinite(tokens[0], source, line_number);
  if (count_value < 0 || count_value != std::floor(count_value)) {
    ThrowAt(source, line_number, "the number of views must be a non-negative integer");
  }
  if (count_value > kMaxNumViews) {
    ThrowAt(source, line_number, "the number of views " + tokens[0] + " is too large");
  }
  const size_t count = static_cast<size_t>(count_value);
  while (NextTokens(stream, &line_number, &tokens)) {
    if (tokens.size() != 22) {
      ThrowAt(source, line_number,
              "expected 22 fields (name, K, R, t), found " + std::to_string(tokens.size()));
    }
    if (truth.images.size() == count) {
      ThrowAt(source, line_number, "more views than the " + std::to_string(count) + " announced");
    }
    double values[21];
    for (int i = 0; i < 21; ++i) values[i] = ParseFinite(tokens[i + 1], source, line_number);
    const Eigen::Matrix3d K =
        Eigen::Map<const Eigen::Matrix<double, 3, 3, Eigen::RowMajor>>(values);
    const Eigen::Matrix3d R =
        Eigen::Map<const Eigen::Matrix<double, 3, 3, Eigen::RowMajor>>(values + 9);
    const Eigen::Vector3d t(values[18], values[19], values[20]);
    GroundTruthImage image;
    image.name = tokens[0];
    image.camera = CameraFromK(K, 0, 0, source, line_number);
    image.cam_from_world = Rigid3d(CheckedRotation(R, source, line_number), t);
    truth.images.push_back(std::move(image));
  }
  if (truth.images.size() != count) {
    ThrowAt(source, line_number,
            "expected " + std::to_string(count) + " views, found " +
                std::to_string(truth.images.size()));
  }
  return truth;
}

GroundTruth ReadMiddleburyGroundTruth(const std::filesystem::path& path) {
  std::istringstream stream(ReadFileToString(path));
  return ReadMiddleburyGroundTruth(stream, path.string());
}

GroundTruthImage ReadStrechaCamera(std::istream& stream, const std::string& source,
                                   const std::string& image_name) {
  // Rows in file order and how many numbers each holds.
  constexpr int kRowSizes[9] = {3, 3, 3, 3, 3, 3, 3, 3, 2};
  double rows[9][3] = {};
  size_t row_lines[9] = {};
  size_t line_number = 0;
  std::vector<std::string> tokens;
  for (int row = 0; row < 9; ++row) {
    if (!NextTokens(stream, &line_number, &tokens)) {
      ThrowAt(source, line_number + 1,
              "unexpected end of file (expected 9 rows: K, distortion, R, C, size)");
    }
    if (static_cast<int>(tokens.size()) != kRowSizes[row]) {
      ThrowAt(source, line_number,
              "expected " + std::to_string(kRowSizes[row]) + " numbers, found " +
                  std::to_string(tokens.size()));
    }
    row_lines[row] = line_number;
    for (int col = 0; col < kRowSizes[row]; ++col) {
      rows[row][col] = ParseFinite(tokens[col], source, line_number);
    }
  }
  if (NextTokens(stream, &line_number, &tokens)) ThrowAt(source, line_number, "trailing data");

  Eigen::Matrix3d K, world_from_cam_rotation;
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) {
      K(r, c) = rows[r][c];
      world_from_cam_rotation(r, c) = rows[4 + r][c];
    }
  }
  const Eigen::Vector3d center(rows[7][0], rows[7][1], rows[7][2]);
  const double width = rows[8][0], height = rows[8][1];
  if (width < 1 || height < 1 || width != std::floor(width) || height != std::floor(height) ||
      width > kMaxImageSide || height > kMaxImageSide) {
    ThrowAt(source, row_lines[8], "image size must be two positive integers up to 1000000");
  }
  if (rows[3][0] != 0 || rows[3][1] != 0 || rows[3][2] != 0) {
    PARALLAX_LOG(Warning) << source << ": ignoring non-zero distortion";
  }
  GroundTruthImage image;
  image.name = image_name;
  image.camera =
      CameraFromK(K, static_cast<size_t>(width), static_cast<size_t>(height), source, row_lines[0]);
  const Eigen::Matrix3d cam_from_world_rotation =
      CheckedRotation(world_from_cam_rotation, source, row_lines[4]).transpose();
  image.cam_from_world = Rigid3d(cam_from_world_rotation, -cam_from_world_rotation * center);
  return image;
}

GroundTruth ReadStrechaGroundTruth(const std::filesystem::path& dir) {
  std::vector<std::filesystem::path> files;
  std::error_code error;
  for (const auto& entry : std::filesystem::directory_iterator(dir, error)) {
    if (entry.is_regular_file() && entry.path().extension() == ".camera") {
      files.push_back(entry.path());
    }
  }
  if (error) throw InputError(dir.string() + ": cannot list folder: " + error.message());
  if (files.empty()) throw InputError(dir.string() + ": no *.camera files");
  std::sort(files.begin(), files.end());
  GroundTruth truth;
  truth.source = dir.string();
  for (const auto& file : files) {
    std::istringstream stream(ReadFileToString(file));
    truth.images.push_back(ReadStrechaCamera(stream, file.string(), file.stem().string()));
  }
  return truth;
}

GroundTruth ReadColmapGroundTruth(const std::filesystem::path& dir) {
  return GroundTruthOfModel(ReadReconstruction(dir), dir.string());
}

GroundTruth GroundTruthOfModel(const Reconstruction& model, const std::string& source) {
  GroundTruth truth;
  truth.source = source;
  for (const auto& [image_id, image] : model.Images()) {
    if (!image.registered) continue;
    GroundTruthImage view;
    view.name = image.name;
    view.camera = model.GetCamera(image.camera_id);
    view.cam_from_world = image.cam_from_world;
    truth.images.push_back(std::move(view));
  }
  return truth;
}

GroundTruth GroundTruthOfPositions(
    const std::vector<std::pair<std::string, Eigen::Vector3d>>& positions,
    const std::string& source) {
  GroundTruth truth;
  truth.source = source;
  for (const auto& [name, center] : positions) {
    GroundTruthImage view;
    view.name = name;
    view.cam_from_world.translation = -center;  // Identity rotation: the centre is `center`.
    truth.images.push_back(std::move(view));
  }
  return truth;
}

GroundTruth ReadPositionsGroundTruth(const std::filesystem::path& path) {
  std::ifstream stream(path);
  if (!stream) throw MissingFileError(path.string() + ": cannot open the reference positions");
  std::vector<std::pair<std::string, Eigen::Vector3d>> positions;
  std::string line;
  for (int line_number = 1; std::getline(stream, line); ++line_number) {
    std::istringstream fields(line);
    std::string name, extra;
    Eigen::Vector3d center;
    if (!(fields >> name) || name[0] == '#') continue;
    if (!(fields >> center.x() >> center.y() >> center.z()) || (fields >> extra) ||
        !center.allFinite()) {
      throw InputError(path.string() + ":" + std::to_string(line_number) +
                       ": expected `image_name X Y Z`");
    }
    positions.emplace_back(name, center);
  }
  return GroundTruthOfPositions(positions, path.string());
}

GroundTruth ReadGroundTruth(const std::filesystem::path& path) {
  std::error_code error;
  if (std::filesystem::is_regular_file(path, error)) return ReadMiddleburyGroundTruth(path);
  if (!std::filesystem::is_directory(path, error)) {
    throw MissingFileError(path.string() + ": no such file or folder");
  }
  if (HasColmapModel(path)) return ReadColmapGroundTruth(path);
  for (const auto& entry : std::filesystem::directory_iterator(path, error)) {
    if (entry.path().extension() == ".camera") return ReadStrechaGroundTruth(path);
  }
  throw InputError(path.string() +
                   ": not a ground truth (expected a *_par.txt file, a folder of *.camera files "
                   "or a COLMAP model folder)");
}

}  // namespace parallax
