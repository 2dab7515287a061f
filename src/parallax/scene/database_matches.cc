#include "parallax/scene/database.h"

#include <sqlite3.h>

#include <Eigen/LU>
#include <cstring>
#include <utility>

#include "parallax/scene/database_internal.h"
#include "parallax/util/check.h"

// Database: matches and two-view geometries, stored per pair with the smaller image id first.

namespace parallax {

using internal::ReadDoubles;
using internal::Statement;

namespace {

// Matches as a rows x 2 uint32 blob, with the columns swapped when the pair is.
std::vector<uint32_t> MatchesToBlob(const FeatureMatches& matches, bool swap) {
  std::vector<uint32_t> blob(2 * matches.size());
  for (size_t i = 0; i < matches.size(); ++i) {
    blob[2 * i + 0] = swap ? matches[i].point2D_idx2 : matches[i].point2D_idx1;
    blob[2 * i + 1] = swap ? matches[i].point2D_idx1 : matches[i].point2D_idx2;
  }
  return blob;
}

// Reads (rows, cols, data) starting at `column` as matches.
FeatureMatches MatchesFromRow(const Statement& statement, int column, bool swap,
                              const std::filesystem::path& path) {
  const size_t rows = static_cast<size_t>(statement.Int64(column));
  const size_t cols = static_cast<size_t>(statement.Int64(column + 1));
  const size_t num_bytes = statement.NumBytes(column + 2);
  if ((rows > 0 && cols != 2) || num_bytes != rows * cols * sizeof(uint32_t)) {
    throw InputError(path.string() + ": malformed matches blob (" + std::to_string(rows) + "x" +
                     std::to_string(cols) + ", " + std::to_string(num_bytes) + " bytes)");
  }
  FeatureMatches matches(rows);
  if (rows == 0) return matches;
  std::vector<uint32_t> blob(2 * rows);
  std::memcpy(blob.data(), statement.Blob(column + 2), num_bytes);
  for (size_t i = 0; i < rows; ++i) {
    matches[i].point2D_idx1 = blob[2 * i + (swap ? 1 : 0)];
    matches[i].point2D_idx2 = blob[2 * i + (swap ? 0 : 1)];
  }
  return matches;
}

Eigen::Matrix3d MatrixFromRowMajor(const std::optional<Eigen::Matrix<double, 9, 1>>& values) {
  if (!values) return Eigen::Matrix3d::Zero();
  return Eigen::Map<const Eigen::Matrix<double, 3, 3, Eigen::RowMajor>>(values->data());
}

// The geometry of the pair seen from the other image: COLMAP's TwoViewGeometry::Invert.
TwoViewGeometry InvertTwoViewGeometry(const TwoViewGeometry& geometry) {
  TwoViewGeometry inverted = geometry;
  inverted.F = geometry.F.transpose();
  inverted.E = geometry.E.transpose();
  // A zero (unset) H stays zero rather than becoming NaN.
  if (!geometry.H.isZero(0)) inverted.H = geometry.H.inverse();
  inverted.cam2_from_cam1 = geometry.cam2_from_cam1.Inverse();
  for (FeatureMatch& match : inverted.inlier_matches) {
    std::swap(match.point2D_idx1, match.point2D_idx2);
  }
  return inverted;
}

// Reads columns (rows, cols, data, config, F, E, H, qvec, tvec) starting at `column`.
TwoViewGeometry TwoViewGeometryFromRow(const Statement& statement, int column,
                                       const std::filesystem::path& path) {
  TwoViewGeometry geometry;
  geometry.inlier_matches = MatchesFromRow(statement, column, false, path);
  geometry.config = static_cast<int>(statement.Int64(column + 3));
  geometry.F = MatrixFromRowMajor(ReadDoubles<9>(statement, column + 4, path));
  geometry.E = MatrixFromRowMajor(ReadDoubles<9>(statement, column + 5, path));
  geometry.H = MatrixFromRowMajor(ReadDoubles<9>(statement, column + 6, path));
  if (const auto qvec = ReadDoubles<4>(statement, column + 7, path); qvec && !qvec->isZero(0)) {
    geometry.cam2_from_cam1.rotation =
        Eigen::Quaterniond((*qvec)(0), (*qvec)(1), (*qvec)(2), (*qvec)(3));
  }
  if (const auto tvec = ReadDoubles<3>(statement, column + 8, path)) {
    geometry.cam2_from_cam1.translation = *tvec;
  }
  return geometry;
}

}  // namespace

// ----- Matches ------------------------------------------------------------------------------

void Database::WriteMatches(image_t image_id1, image_t image_id2, const FeatureMatches& matches) {
  PARALLAX_CHECK_NE(image_id1, image_id2);
  const std::vector<uint32_t> blob = MatchesToBlob(matches, SwapImagePair(image_id1, image_id2));
  Statement statement(db_, path_,
                      "INSERT INTO matches(pair_id, rows, cols, data) VALUES(?, ?, ?, ?);");
  statement.BindInt64(1, static_cast<int64_t>(ImagePairToPairId(image_id1, image_id2)));
  statement.BindInt64(2, static_cast<int64_t>(matches.size()));
  statement.BindInt64(3, 2);
  statement.BindBlob(4, blob.data(), blob.size() * sizeof(uint32_t));
  statement.Step(("cannot write matches of pair (" + std::to_string(image_id1) + ", " +
                  std::to_string(image_id2) + ")")
                     .c_str());
}

bool Database::ExistsMatches(image_t image_id1, image_t image_id2) const {
  Statement statement(db_, path_, "SELECT 1 FROM matches WHERE pair_id=?;");
  statement.BindInt64(1, static_cast<int64_t>(ImagePairToPairId(image_id1, image_id2)));
  return statement.Step();
}

FeatureMatches Database::ReadMatches(image_t image_id1, image_t image_id2) const {
  Statement statement(db_, path_, "SELECT rows, cols, data FROM matches WHERE pair_id=?;");
  statement.BindInt64(1, static_cast<int64_t>(ImagePairToPairId(image_id1, image_id2)));
  if (!statement.Step()) return {};
  return MatchesFromRow(statement, 0, SwapImagePair(image_id1, image_id2), path_);
}

std::vector<std::pair<image_pair_t, FeatureMatches>> Database::ReadAllMatches() const {
  Statement statement(db_, path_,
                      "SELECT pair_id, rows, cols, data FROM matches ORDER BY pair_id;");
  std::vector<std::pair<image_pair_t, FeatureMatches>> all_matches;
  while (statement.Step()) {
    all_matches.emplace_back(static_cast<image_pair_t>(statement.Int64(0)),
                             MatchesFromRow(statement, 1, false, path_));
  }
  return all_matches;
}

// ----- Two-view geometries ------------------------------------------------------------------

void Database::DeleteTwoViewGeometry(image_t image_id1, image_t image_id2) {
  Statement statement(db_, path_, "DELETE FROM two_view_geometries WHERE pair_id = ?;");
  statement.BindInt64(1, static_cast<int64_t>(ImagePairToPairId(image_id1, image_id2)));
  statement.Step("cannot delete a two-view geometry");
}

void Database::WriteTwoViewGeometry(image_t image_id1, image_t image_id2,
                                    const TwoViewGeometry& geometry) {
  PARALLAX_CHECK_NE(image_id1, image_id2);
  const TwoViewGeometry stored =
      SwapImagePair(image_id1, image_id2) ? InvertTwoViewGeometry(geometry) : geometry;
  const std::vector<uint32_t> blob = MatchesToBlob(stored.inlier_matches, false);
  // Row-major 3x3 blobs, as COLMAP transposes its column-major Eigen matrices before writing.
  const Eigen::Matrix<double, 3, 3, Eigen::RowMajor> F = stored.F;
  const Eigen::Matrix<double, 3, 3, Eigen::RowMajor> E = stored.E;
  const Eigen::Matrix<double, 3, 3, Eigen::RowMajor> H = stored.H;
  const Eigen::Vector4d qvec(stored.cam2_from_cam1.rotation.w(), stored.cam2_from_cam1.rotation.x(),
                             stored.cam2_from_cam1.rotation.y(),
                             stored.cam2_from_cam1.rotation.z());
  const Eigen::Vector3d tvec = stored.cam2_from_cam1.translation;

  Statement statement(db_, path_,
                      "INSERT INTO two_view_geometries(pair_id, rows, cols, data, config, F, E, "
                      "H, qvec, tvec) VALUES(?, ?, ?, ?, ?, ?, ?, ?, ?, ?);");
  statement.BindInt64(1, static_cast<int64_t>(ImagePairToPairId(image_id1, image_id2)));
  statement.BindInt64(2, static_cast<int64_t>(stored.inlier_matches.size()));
  statement.BindInt64(3, 2);
  statement.BindBlob(4, blob.data(), blob.size() * sizeof(uint32_t));
  statement.BindInt64(5, stored.config);
  // COLMAP stores the matrices and pose only for pairs with inliers (empty blobs otherwise).
  const bool has_inliers = !stored.inlier_matches.empty();
  statement.BindBlob(6, F.data(), has_inliers ? 9 * sizeof(double) : 0);
  statement.BindBlob(7, E.data(), has_inliers ? 9 * sizeof(double) : 0);
  statement.BindBlob(8, H.data(), has_inliers ? 9 * sizeof(double) : 0);
  statement.BindBlob(9, qvec.data(), has_inliers ? 4 * sizeof(double) : 0);
  statement.BindBlob(10, tvec.data(), has_inliers ? 3 * sizeof(double) : 0);
  statement.Step(("cannot write two-view geometry of pair (" + std::to_string(image_id1) + ", " +
                  std::to_string(image_id2) + ")")
                     .c_str());
}

bool Database::ExistsTwoViewGeometry(image_t image_id1, image_t image_id2) const {
  Statement statement(db_, path_, "SELECT 1 FROM two_view_geometries WHERE pair_id=?;");
  statement.BindInt64(1, static_cast<int64_t>(ImagePairToPairId(image_id1, image_id2)));
  return statement.Step();
}

TwoViewGeometry Database::ReadTwoViewGeometry(image_t image_id1, image_t image_id2) const {
  Statement statement(db_, path_,
                      "SELECT rows, cols, data, config, F, E, H, qvec, tvec "
                      "FROM two_view_geometries WHERE pair_id=?;");
  statement.BindInt64(1, static_cast<int64_t>(ImagePairToPairId(image_id1, image_id2)));
  if (!statement.Step()) return TwoViewGeometry();
  const TwoViewGeometry geometry = TwoViewGeometryFromRow(statement, 0, path_);
  return SwapImagePair(image_id1, image_id2) ? InvertTwoViewGeometry(geometry) : geometry;
}

std::vector<std::pair<image_pair_t, TwoViewGeometry>> Database::ReadTwoViewGeometries() const {
  Statement statement(db_, path_,
                      "SELECT pair_id, rows, cols, data, config, F, E, H, qvec, tvec "
                      "FROM two_view_geometries ORDER BY pair_id;");
  std::vector<std::pair<image_pair_t, TwoViewGeometry>> geometries;
  while (statement.Step()) {
    geometries.emplace_back(static_cast<image_pair_t>(statement.Int64(0)),
                            TwoViewGeometryFromRow(statement, 1, path_));
  }
  return geometries;
}

std::vector<std::pair<image_pair_t, int>> Database::ReadTwoViewGeometryNumInliers() const {
  Statement statement(db_, path_,
                      "SELECT pair_id, rows FROM two_view_geometries "
                      "WHERE rows > 0 AND config NOT IN (0, 1) ORDER BY pair_id;");
  std::vector<std::pair<image_pair_t, int>> num_inliers;
  while (statement.Step()) {
    num_inliers.emplace_back(static_cast<image_pair_t>(statement.Int64(0)),
                             static_cast<int>(statement.Int64(1)));
  }
  return num_inliers;
}

}  // namespace parallax
