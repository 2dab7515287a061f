#pragma once

#include <filesystem>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "parallax/feature/types.h"
#include "parallax/geometry/gps.h"
#include "parallax/scene/camera.h"
#include "parallax/scene/image.h"
#include "parallax/scene/two_view_geometry.h"
#include "parallax/util/types.h"

struct sqlite3;

namespace parallax {

// What an image's features were computed from: the file's size and modification time (cheap
// to compare) and the XXH3-128 digest of its bytes (util/content_hash.h), which decides when
// the first two differ. Stored in Parallax's own table; COLMAP ignores it.
struct ImageFileFingerprint {
  uint64_t size = 0;
  int64_t mtime_ns = 0;
  std::string content_hash;
};

// The feature and match store: SQLite with COLMAP 3.8's schema (tables cameras, images,
// keypoints, descriptors, matches, two_view_geometries; the same blob layouts and pair_id
// encoding), so `colmap mapper` reads a Parallax database and Parallax reads COLMAP's.
// A COLMAP 4 database (rigs and frames, pose priors in their own table) is read, matched and
// mapped as it is; adding cameras or images to one is refused (InputError).
// Every write is one transaction, so a run killed at any moment leaves a valid database; a
// DatabaseTransaction (below) makes many writes one, and is the only way to open one.
// Not thread-safe: one Database per thread, or serialise access.
// Written in database.cc (open, schema, transactions), database_features.cc (cameras, images,
// features) and database_matches.cc (matches, two-view geometries).
class Database {
 public:
  // Opens or creates the file (and its schema). Throws InputError naming the path when the
  // file is not a database or the schema is not COLMAP's.
  explicit Database(const std::filesystem::path& path);
  ~Database();
  Database(const Database&) = delete;
  Database& operator=(const Database&) = delete;

  // Cameras. WriteCamera returns the new id (the camera's own id is ignored when
  // use_camera_id is false).
  camera_t WriteCamera(const Camera& camera, bool use_camera_id = false);
  void UpdateCamera(const Camera& camera);
  bool ExistsCamera(camera_t camera_id) const;
  Camera ReadCamera(camera_t camera_id) const;
  std::vector<Camera> ReadAllCameras() const;

  // Images (name, camera id; poses are not stored, as in COLMAP 3.8's priors we ignore).
  image_t WriteImage(const std::string& name, camera_t camera_id);
  bool ExistsImage(image_t image_id) const;
  std::optional<image_t> ImageIdByName(const std::string& name) const;
  // Image with empty points2D (load keypoints separately).
  Image ReadImage(image_t image_id) const;
  std::vector<Image> ReadAllImages() const;

  void WriteKeypoints(image_t image_id, const FeatureKeypoints& keypoints);
  void WriteDescriptors(image_t image_id, const FeatureDescriptors& descriptors);
  // Writes image row, keypoints and descriptors in one transaction (resumable extraction).
  image_t WriteImageWithFeatures(const std::string& name, camera_t camera_id,
                                 const FeatureKeypoints& keypoints,
                                 const FeatureDescriptors& descriptors,
                                 const std::optional<ImageFileFingerprint>& fingerprint = {},
                                 const std::optional<GeodeticPosition>& gps_prior = {},
                                 const std::optional<KeypointColors>& colors = {});
  // The image's GPS position (EXIF), where COLMAP keeps it: prior_tx, prior_ty, prior_tz hold
  // latitude, longitude and altitude, so COLMAP's spatial matcher reads it too.
  void WriteImageGpsPrior(image_t image_id, const GeodeticPosition& position);
  // Every image with a GPS prior.
  std::vector<std::pair<image_t, GeodeticPosition>> ReadImageGpsPriors() const;
  void WriteImageFileFingerprint(image_t image_id, const ImageFileFingerprint& fingerprint);
  // Nullopt for images stored by COLMAP or by a Parallax before fingerprints.
  std::optional<ImageFileFingerprint> ReadImageFileFingerprint(image_t image_id) const;
  // The colours under the image's keypoints (Parallax's own table, like the fingerprint),
  // 3 bytes per keypoint. Nullopt for images stored by COLMAP or by a Parallax before them.
  // A blob that is not 3 bytes per row throws InputError naming the database.
  void WriteKeypointColors(image_t image_id, const KeypointColors& colors);
  std::optional<KeypointColors> ReadKeypointColors(image_t image_id) const;
  // Deletes the image and everything computed from it, in one transaction: keypoints,
  // descriptors, fingerprint, keypoint colours, the matches and geometries of every pair it is in,
  // and its camera when no other image uses that camera.
  void DeleteImage(image_t image_id);
  bool ExistsKeypoints(image_t image_id) const;
  bool ExistsDescriptors(image_t image_id) const;
  FeatureKeypoints ReadKeypoints(image_t image_id) const;
  FeatureDescriptors ReadDescriptors(image_t image_id) const;
  size_t NumKeypoints(image_t image_id) const;

  // Matches of a pair; stored with the smaller image id first, swapped as needed.
  void WriteMatches(image_t image_id1, image_t image_id2, const FeatureMatches& matches);
  bool ExistsMatches(image_t image_id1, image_t image_id2) const;
  FeatureMatches ReadMatches(image_t image_id1, image_t image_id2) const;
  std::vector<std::pair<image_pair_t, FeatureMatches>> ReadAllMatches() const;

  // Verified geometry; F, E, H are transposed/inverted as COLMAP does when the pair is
  // stored swapped.
  void WriteTwoViewGeometry(image_t image_id1, image_t image_id2, const TwoViewGeometry& geometry);
  bool ExistsTwoViewGeometry(image_t image_id1, image_t image_id2) const;
  // Removes the pair's geometry (nothing when none is stored), so that it can be written anew.
  void DeleteTwoViewGeometry(image_t image_id1, image_t image_id2);
  TwoViewGeometry ReadTwoViewGeometry(image_t image_id1, image_t image_id2) const;
  // (pair_id, geometry) for every stored pair, ids in stored order (image_id1 < image_id2).
  std::vector<std::pair<image_pair_t, TwoViewGeometry>> ReadTwoViewGeometries() const;
  // Number of inlier matches per pair with config other than degenerate/undefined.
  std::vector<std::pair<image_pair_t, int>> ReadTwoViewGeometryNumInliers() const;

  size_t NumCameras() const;
  size_t NumImages() const;
  size_t NumMatchedPairs() const;
  size_t NumVerifiedPairs() const;

  // Moves everything in the write-ahead log into the database file and empties the log, so
  // that the file alone holds the database (for readers on other machines of a cluster).
  void Checkpoint();

  const std::filesystem::path& Path() const { return path_; }

 private:
  friend class DatabaseTransaction;
  void Execute(const std::string& sql) const;
  void RefuseNewImagesInColmap4Layout() const;
  std::vector<std::pair<image_t, GeodeticPosition>> ReadColmap4GpsPriors() const;
  std::filesystem::path path_;
  sqlite3* db_ = nullptr;
  bool colmap4_layout_ = false;
};

// Many writes as one transaction (faster than one each, and all or nothing), opened and closed
// by scope: the constructor begins it, Commit() makes it durable, and the destructor rolls it
// back when Commit() was not reached, so a throw between the writes leaves nothing half
// written and the database usable (docs/style.md, habit 15; COLMAP's DatabaseTransaction).
//
//   DatabaseTransaction transaction(&database);
//   for (...) database.WriteMatches(...);
//   transaction.Commit();
//
// Writes inside it that are one transaction on their own (WriteImageWithFeatures, DeleteImage)
// join it. Nesting is refused: a second DatabaseTransaction on a database with one open throws
// CheckError. It must not outlive its Database.
class DatabaseTransaction {
 public:
  // Begins an IMMEDIATE transaction, which takes the write lock now (waiting for another
  // writer as any write does) rather than at the first write. Throws CheckError when a
  // transaction is already open on `database`, InputError when SQLite cannot begin one.
  explicit DatabaseTransaction(Database* database);
  // Rolls back unless committed.
  ~DatabaseTransaction();
  DatabaseTransaction(const DatabaseTransaction&) = delete;
  DatabaseTransaction& operator=(const DatabaseTransaction&) = delete;

  // Commits (InputError when SQLite cannot; the destructor then rolls back). Once only.
  void Commit();

 private:
  friend class Database;
  // kJoin: a write of Database's own that must be atomic; it joins an open transaction
  // (which then decides) instead of refusing it.
  enum class Nesting { kRefuse, kJoin };
  DatabaseTransaction(Database* database, Nesting nesting);

  Database* database_;
  // False when it joined an open transaction: Commit() and the destructor leave that one be.
  bool owns_ = false;
  bool committed_ = false;
};

}  // namespace parallax
