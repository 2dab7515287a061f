#include "parallax/scene/database.h"

#include <sqlite3.h>

#include <cmath>
#include <cstring>

#include "parallax/scene/database_internal.h"
#include "parallax/util/check.h"

// Database: cameras, images, and what is stored per image (keypoints, descriptors, GPS priors,
// file fingerprints, keypoint colours).

namespace parallax {

using internal::ReadDoubles;
using internal::Statement;

namespace {

// cameras.prior_focal_length: COLMAP writes 1 for a focal length from EXIF or the user and
// still refines it; Camera::has_prior_focal_length means known and held fixed. Parallax
// writes 2 for that (COLMAP reads any non-zero value as its prior) and 1 for an EXIF focal
// length, so a COLMAP database's 1 is read as a starting value that bundle adjustment
// refines, as COLMAP's mapper does.
constexpr int64_t kKnownIntrinsicsFlag = 2;
constexpr int64_t kFocalLengthPriorFlag = 1;

int64_t PriorFocalLengthFlag(const Camera& camera) {
  if (camera.has_prior_focal_length) return kKnownIntrinsicsFlag;
  return camera.focal_length_from_exif ? kFocalLengthPriorFlag : 0;
}

// Keypoint blobs are rows x 6 float32 (x, y, a11, a12, a21, a22); COLMAP also reads the older
// 2-column (x, y) and 4-column (x, y, scale, orientation) layouts, and so do we.
constexpr int kKeypointCols = 6;

FeatureKeypoints KeypointsFromBlob(const float* data, size_t rows, size_t cols,
                                   const std::filesystem::path& path, image_t image_id) {
  if (cols != 2 && cols != 4 && cols != 6) {
    throw InputError(path.string() + ": keypoints of image " + std::to_string(image_id) + " have " +
                     std::to_string(cols) + " columns (expected 2, 4 or 6)");
  }
  FeatureKeypoints keypoints(rows);
  for (size_t i = 0; i < rows; ++i) {
    const float* row = data + i * cols;
    if (cols == 2) {
      keypoints[i] = FeatureKeypoint(row[0], row[1]);
    } else if (cols == 4) {
      keypoints[i] = FeatureKeypoint(row[0], row[1], row[2], row[3]);
    } else {
      FeatureKeypoint& keypoint = keypoints[i];
      keypoint.x = row[0];
      keypoint.y = row[1];
      keypoint.a11 = row[2];
      keypoint.a12 = row[3];
      keypoint.a21 = row[4];
      keypoint.a22 = row[5];
    }
  }
  return keypoints;
}

Camera CameraFromRow(const Statement& statement, const std::filesystem::path& path) {
  Camera camera;
  camera.camera_id = static_cast<camera_t>(statement.Int64(0));
  const int model = static_cast<int>(statement.Int64(1));
  if (!ExistsCameraModel(model)) {
    throw InputError(path.string() + ": camera " + std::to_string(camera.camera_id) +
                     " has unsupported model id " + std::to_string(model));
  }
  camera.model_id = static_cast<CameraModelId>(model);
  camera.width = static_cast<size_t>(statement.Int64(2));
  camera.height = static_cast<size_t>(statement.Int64(3));
  const size_t num_bytes = statement.NumBytes(4);
  if (num_bytes != CameraModelNumParams(camera.model_id) * sizeof(double)) {
    throw InputError(path.string() + ": camera " + std::to_string(camera.camera_id) + " has " +
                     std::to_string(num_bytes / sizeof(double)) + " params, " + camera.ModelName() +
                     " needs " + std::to_string(CameraModelNumParams(camera.model_id)));
  }
  camera.params.resize(num_bytes / sizeof(double));
  if (num_bytes > 0) std::memcpy(camera.params.data(), statement.Blob(4), num_bytes);
  camera.has_prior_focal_length = statement.Int64(5) == kKnownIntrinsicsFlag;
  camera.focal_length_from_exif = statement.Int64(5) == kFocalLengthPriorFlag;
  return camera;
}

Image ImageFromRow(const Statement& statement) {
  Image image;
  image.image_id = static_cast<image_t>(statement.Int64(0));
  image.name = statement.Text(1);
  image.camera_id = static_cast<camera_t>(statement.Int64(2));
  return image;
}

}  // namespace

// ----- Cameras ------------------------------------------------------------------------------

void Database::RefuseNewImagesInColmap4Layout() const {
  if (!colmap4_layout_) return;
  throw InputError(path_.string() +
                   ": a COLMAP 4 database; Parallax reads its features and matches (match, "
                   "mapper) but does not add cameras or images to it: extract into a new database");
}

camera_t Database::WriteCamera(const Camera& camera, bool use_camera_id) {
  RefuseNewImagesInColmap4Layout();
  PARALLAX_CHECK_MSG(camera.VerifyParams(), "camera " << camera.camera_id << " has invalid params");
  Statement statement(db_, path_,
                      "INSERT INTO cameras(camera_id, model, width, height, params, "
                      "prior_focal_length) VALUES(?, ?, ?, ?, ?, ?);");
  if (use_camera_id) {
    PARALLAX_CHECK_NE(camera.camera_id, kInvalidCameraId);
    statement.BindInt64(1, camera.camera_id);
  } else {
    statement.BindNull(1);
  }
  statement.BindInt64(2, static_cast<int>(camera.model_id));
  statement.BindInt64(3, static_cast<int64_t>(camera.width));
  statement.BindInt64(4, static_cast<int64_t>(camera.height));
  statement.BindBlob(5, camera.params.data(), camera.params.size() * sizeof(double));
  statement.BindInt64(6, PriorFocalLengthFlag(camera));
  statement.Step("cannot write camera");
  return static_cast<camera_t>(sqlite3_last_insert_rowid(db_));
}

void Database::UpdateCamera(const Camera& camera) {
  PARALLAX_CHECK_MSG(camera.VerifyParams(), "camera " << camera.camera_id << " has invalid params");
  Statement statement(db_, path_,
                      "UPDATE cameras SET model=?, width=?, height=?, params=?, "
                      "prior_focal_length=? WHERE camera_id=?;");
  statement.BindInt64(1, static_cast<int>(camera.model_id));
  statement.BindInt64(2, static_cast<int64_t>(camera.width));
  statement.BindInt64(3, static_cast<int64_t>(camera.height));
  statement.BindBlob(4, camera.params.data(), camera.params.size() * sizeof(double));
  statement.BindInt64(5, PriorFocalLengthFlag(camera));
  statement.BindInt64(6, camera.camera_id);
  statement.Step("cannot update camera");
  PARALLAX_CHECK_MSG(sqlite3_changes(db_) == 1, "no camera " << camera.camera_id);
}

bool Database::ExistsCamera(camera_t camera_id) const {
  Statement statement(db_, path_, "SELECT 1 FROM cameras WHERE camera_id=?;");
  statement.BindInt64(1, camera_id);
  return statement.Step();
}

Camera Database::ReadCamera(camera_t camera_id) const {
  Statement statement(db_, path_,
                      "SELECT camera_id, model, width, height, params, prior_focal_length "
                      "FROM cameras WHERE camera_id=?;");
  statement.BindInt64(1, camera_id);
  PARALLAX_CHECK_MSG(statement.Step(), "no camera " << camera_id << " in " << path_.string());
  return CameraFromRow(statement, path_);
}

std::vector<Camera> Database::ReadAllCameras() const {
  Statement statement(db_, path_,
                      "SELECT camera_id, model, width, height, params, prior_focal_length "
                      "FROM cameras ORDER BY camera_id;");
  std::vector<Camera> cameras;
  while (statement.Step()) cameras.push_back(CameraFromRow(statement, path_));
  return cameras;
}

// ----- Images -------------------------------------------------------------------------------

image_t Database::WriteImage(const std::string& name, camera_t camera_id) {
  RefuseNewImagesInColmap4Layout();
  // Pose priors are left NULL, as COLMAP writes them when unknown.
  Statement statement(db_, path_,
                      "INSERT INTO images(image_id, name, camera_id) VALUES(NULL, ?, ?);");
  statement.BindText(1, name);
  statement.BindInt64(2, camera_id);
  statement.Step(("cannot write image '" + name + "'").c_str());
  return static_cast<image_t>(sqlite3_last_insert_rowid(db_));
}

bool Database::ExistsImage(image_t image_id) const {
  Statement statement(db_, path_, "SELECT 1 FROM images WHERE image_id=?;");
  statement.BindInt64(1, image_id);
  return statement.Step();
}

std::optional<image_t> Database::ImageIdByName(const std::string& name) const {
  Statement statement(db_, path_, "SELECT image_id FROM images WHERE name=?;");
  statement.BindText(1, name);
  if (!statement.Step()) return std::nullopt;
  return static_cast<image_t>(statement.Int64(0));
}

Image Database::ReadImage(image_t image_id) const {
  Statement statement(db_, path_, "SELECT image_id, name, camera_id FROM images WHERE image_id=?;");
  statement.BindInt64(1, image_id);
  PARALLAX_CHECK_MSG(statement.Step(), "no image " << image_id << " in " << path_.string());
  return ImageFromRow(statement);
}

std::vector<Image> Database::ReadAllImages() const {
  Statement statement(db_, path_,
                      "SELECT image_id, name, camera_id FROM images ORDER BY image_id;");
  std::vector<Image> images;
  while (statement.Step()) images.push_back(ImageFromRow(statement));
  return images;
}

// ----- Keypoints and descriptors ------------------------------------------------------------

void Database::WriteKeypoints(image_t image_id, const FeatureKeypoints& keypoints) {
  std::vector<float> blob(kKeypointCols * keypoints.size());
  for (size_t i = 0; i < keypoints.size(); ++i) {
    const FeatureKeypoint& keypoint = keypoints[i];
    float* row = blob.data() + kKeypointCols * i;
    row[0] = keypoint.x;
    row[1] = keypoint.y;
    row[2] = keypoint.a11;
    row[3] = keypoint.a12;
    row[4] = keypoint.a21;
    row[5] = keypoint.a22;
  }
  Statement statement(db_, path_,
                      "INSERT INTO keypoints(image_id, rows, cols, data) VALUES(?, ?, ?, ?);");
  statement.BindInt64(1, image_id);
  statement.BindInt64(2, static_cast<int64_t>(keypoints.size()));
  statement.BindInt64(3, kKeypointCols);
  statement.BindBlob(4, blob.data(), blob.size() * sizeof(float));
  statement.Step(("cannot write keypoints of image " + std::to_string(image_id)).c_str());
}

void Database::WriteDescriptors(image_t image_id, const FeatureDescriptors& descriptors) {
  Statement statement(db_, path_,
                      "INSERT INTO descriptors(image_id, rows, cols, data) VALUES(?, ?, ?, ?);");
  statement.BindInt64(1, image_id);
  statement.BindInt64(2, descriptors.rows());
  statement.BindInt64(3, descriptors.cols());
  // Row-major, one byte per element: the blob is the matrix memory.
  statement.BindBlob(4, descriptors.data(), static_cast<size_t>(descriptors.size()));
  statement.Step(("cannot write descriptors of image " + std::to_string(image_id)).c_str());
}

image_t Database::WriteImageWithFeatures(const std::string& name, camera_t camera_id,
                                         const FeatureKeypoints& keypoints,
                                         const FeatureDescriptors& descriptors,
                                         const std::optional<ImageFileFingerprint>& fingerprint,
                                         const std::optional<GeodeticPosition>& gps_prior,
                                         const std::optional<KeypointColors>& colors) {
  PARALLAX_CHECK_EQ(keypoints.size(), static_cast<size_t>(descriptors.rows()));
  DatabaseTransaction transaction(this, DatabaseTransaction::Nesting::kJoin);
  const image_t image_id = WriteImage(name, camera_id);
  WriteKeypoints(image_id, keypoints);
  WriteDescriptors(image_id, descriptors);
  if (fingerprint) WriteImageFileFingerprint(image_id, *fingerprint);
  if (gps_prior) WriteImageGpsPrior(image_id, *gps_prior);
  if (colors) WriteKeypointColors(image_id, *colors);
  transaction.Commit();
  return image_id;
}

void Database::WriteImageGpsPrior(image_t image_id, const GeodeticPosition& position) {
  Statement statement(
      db_, path_, "UPDATE images SET prior_tx = ?, prior_ty = ?, prior_tz = ? WHERE image_id = ?;");
  statement.BindDouble(1, position.latitude);
  statement.BindDouble(2, position.longitude);
  statement.BindDouble(3, position.altitude);
  statement.BindInt64(4, image_id);
  statement.Step("cannot write an image's GPS prior");
}

std::vector<std::pair<image_t, GeodeticPosition>> Database::ReadImageGpsPriors() const {
  if (colmap4_layout_) return ReadColmap4GpsPriors();
  Statement statement(db_, path_,
                      "SELECT image_id, prior_tx, prior_ty, prior_tz FROM images WHERE prior_tx IS "
                      "NOT NULL AND prior_ty IS NOT NULL ORDER BY image_id;");
  std::vector<std::pair<image_t, GeodeticPosition>> priors;
  while (statement.Step()) {
    const GeodeticPosition position{statement.Double(1), statement.Double(2), statement.Double(3)};
    priors.emplace_back(static_cast<image_t>(statement.Int64(0)), position);
  }
  return priors;
}

std::vector<std::pair<image_t, GeodeticPosition>> Database::ReadColmap4GpsPriors() const {
  // COLMAP 4: a camera image's prior (sensor type 0, data id = image id) in WGS84
  // (coordinate system 0) is latitude, longitude and altitude as three doubles.
  Statement statement(db_, path_,
                      "SELECT corr_data_id, position FROM pose_priors WHERE corr_sensor_type = 0 "
                      "AND coordinate_system = 0 ORDER BY corr_data_id;");
  std::vector<std::pair<image_t, GeodeticPosition>> priors;
  while (statement.Step()) {
    const auto position = ReadDoubles<3>(statement, 1, path_, "pose prior position");
    if (!position || !std::isfinite(position->x()) || !std::isfinite(position->y())) continue;
    priors.emplace_back(static_cast<image_t>(statement.Int64(0)),
                        GeodeticPosition{position->x(), position->y(), position->z()});
  }
  return priors;
}

void Database::WriteImageFileFingerprint(image_t image_id,
                                         const ImageFileFingerprint& fingerprint) {
  Statement statement(db_, path_,
                      "INSERT OR REPLACE INTO parallax_image_files(image_id, size, mtime_ns, "
                      "content_hash) VALUES(?, ?, ?, ?);");
  statement.BindInt64(1, image_id);
  statement.BindInt64(2, static_cast<int64_t>(fingerprint.size));
  statement.BindInt64(3, fingerprint.mtime_ns);
  statement.BindText(4, fingerprint.content_hash);
  statement.Step("cannot write an image file fingerprint");
}

std::optional<ImageFileFingerprint> Database::ReadImageFileFingerprint(image_t image_id) const {
  Statement statement(
      db_, path_,
      "SELECT size, mtime_ns, content_hash FROM parallax_image_files WHERE image_id=?;");
  statement.BindInt64(1, image_id);
  if (!statement.Step()) return std::nullopt;
  ImageFileFingerprint fingerprint;
  fingerprint.size = static_cast<uint64_t>(statement.Int64(0));
  fingerprint.mtime_ns = statement.Int64(1);
  fingerprint.content_hash = statement.Text(2);
  return fingerprint;
}

void Database::WriteKeypointColors(image_t image_id, const KeypointColors& colors) {
  PARALLAX_CHECK_EQ(colors.size() % 3, 0u);
  Statement statement(db_, path_,
                      "INSERT OR REPLACE INTO parallax_keypoint_colors(image_id, rows, data) "
                      "VALUES(?, ?, ?);");
  statement.BindInt64(1, image_id);
  statement.BindInt64(2, static_cast<int64_t>(colors.size() / 3));
  statement.BindBlob(3, colors.data(), colors.size());
  statement.Step(("cannot write keypoint colours of image " + std::to_string(image_id)).c_str());
}

std::optional<KeypointColors> Database::ReadKeypointColors(image_t image_id) const {
  Statement statement(db_, path_,
                      "SELECT rows, data FROM parallax_keypoint_colors WHERE image_id=?;");
  statement.BindInt64(1, image_id);
  if (!statement.Step()) return std::nullopt;
  const int64_t rows = statement.Int64(0);
  const size_t num_bytes = statement.NumBytes(1);
  if (rows < 0 || num_bytes != 3 * static_cast<size_t>(rows)) {
    throw InputError(path_.string() + ": malformed keypoint colours of image " +
                     std::to_string(image_id) + " (" + std::to_string(num_bytes) + " bytes for " +
                     std::to_string(rows) + " keypoints)");
  }
  const auto* data = static_cast<const uint8_t*>(statement.Blob(1));
  return KeypointColors(data, data + num_bytes);
}

void Database::DeleteImage(image_t image_id) {
  DatabaseTransaction transaction(this, DatabaseTransaction::Nesting::kJoin);
  camera_t camera_id = kInvalidCameraId;
  {
    Statement statement(db_, path_, "SELECT camera_id FROM images WHERE image_id=?;");
    statement.BindInt64(1, image_id);
    if (!statement.Step()) return;  // Nothing stored.
    camera_id = static_cast<camera_t>(statement.Int64(0));
  }
  // Pairs hold the image as either id of pair_id = id1 * kMaxNumImages + id2 (ImagePairToPairId).
  for (const std::string table : {"matches", "two_view_geometries"}) {
    const std::string sql =
        "DELETE FROM " + table + " WHERE pair_id / ?2 = ?1 OR pair_id % ?2 = ?1;";
    Statement statement(db_, path_, sql.c_str());
    statement.BindInt64(1, image_id);
    statement.BindInt64(2, static_cast<int64_t>(kMaxNumImages));
    statement.Step("cannot delete the pairs of an image");
  }
  for (const std::string table :
       {"keypoints", "descriptors", "parallax_image_files", "parallax_keypoint_colors", "images"}) {
    const std::string sql = "DELETE FROM " + table + " WHERE image_id = ?1;";
    Statement statement(db_, path_, sql.c_str());
    statement.BindInt64(1, image_id);
    statement.Step("cannot delete an image");
  }
  // A camera of its own goes with it; a shared one stays.
  Statement camera(db_, path_,
                   "DELETE FROM cameras WHERE camera_id = ?1 AND NOT EXISTS "
                   "(SELECT 1 FROM images WHERE camera_id = ?1);");
  camera.BindInt64(1, camera_id);
  camera.Step("cannot delete an unused camera");
  transaction.Commit();
}

bool Database::ExistsKeypoints(image_t image_id) const {
  Statement statement(db_, path_, "SELECT 1 FROM keypoints WHERE image_id=?;");
  statement.BindInt64(1, image_id);
  return statement.Step();
}

bool Database::ExistsDescriptors(image_t image_id) const {
  Statement statement(db_, path_, "SELECT 1 FROM descriptors WHERE image_id=?;");
  statement.BindInt64(1, image_id);
  return statement.Step();
}

FeatureKeypoints Database::ReadKeypoints(image_t image_id) const {
  Statement statement(db_, path_, "SELECT rows, cols, data FROM keypoints WHERE image_id=?;");
  statement.BindInt64(1, image_id);
  if (!statement.Step()) return {};
  const size_t rows = static_cast<size_t>(statement.Int64(0));
  const size_t cols = static_cast<size_t>(statement.Int64(1));
  const size_t num_bytes = statement.NumBytes(2);
  if (num_bytes != rows * cols * sizeof(float)) {
    throw InputError(path_.string() + ": keypoints of image " + std::to_string(image_id) +
                     ": blob of " + std::to_string(num_bytes) + " bytes for " +
                     std::to_string(rows) + "x" + std::to_string(cols) + " floats");
  }
  if (rows == 0) return {};
  std::vector<float> blob(rows * cols);
  std::memcpy(blob.data(), statement.Blob(2), num_bytes);
  return KeypointsFromBlob(blob.data(), rows, cols, path_, image_id);
}

FeatureDescriptors Database::ReadDescriptors(image_t image_id) const {
  Statement statement(db_, path_, "SELECT rows, cols, data FROM descriptors WHERE image_id=?;");
  statement.BindInt64(1, image_id);
  if (!statement.Step()) return FeatureDescriptors(0, 128);
  const Eigen::Index rows = statement.Int64(0);
  const Eigen::Index cols = statement.Int64(1);
  const size_t num_bytes = statement.NumBytes(2);
  if (rows < 0 || cols < 0 || num_bytes != static_cast<size_t>(rows * cols)) {
    throw InputError(path_.string() + ": descriptors of image " + std::to_string(image_id) +
                     ": blob of " + std::to_string(num_bytes) + " bytes for " +
                     std::to_string(rows) + "x" + std::to_string(cols) + " uint8");
  }
  FeatureDescriptors descriptors(rows, cols);
  if (num_bytes > 0) std::memcpy(descriptors.data(), statement.Blob(2), num_bytes);
  return descriptors;
}

size_t Database::NumKeypoints(image_t image_id) const {
  Statement statement(db_, path_, "SELECT rows FROM keypoints WHERE image_id=?;");
  statement.BindInt64(1, image_id);
  return statement.Step() ? static_cast<size_t>(statement.Int64(0)) : 0;
}

}  // namespace parallax
