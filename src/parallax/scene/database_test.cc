#include "parallax/scene/database.h"

#include <gtest/gtest.h>

#include <signal.h>
#include <sqlite3.h>
#include <sys/wait.h>
#include <unistd.h>
#include "parallax/util/eigen_matchers.h"

#include <Eigen/LU>
#include <cstring>
#include <fstream>
#include <map>
#include <tuple>

#include "parallax/math/random.h"
#include "parallax/scene/testing/random_features.h"
#include "parallax/util/check.h"
#include "parallax/util/test_dir.h"

namespace parallax {
namespace {

using test::EigenMatrixNear;
using test::RandomDescriptors;
using test::RandomKeypoints;
using test::RandomMatches;
using test::Rigid3dNear;

namespace fs = std::filesystem;

// A fresh database path in a per-test temporary folder.
class DatabaseTest : public ::testing::Test {
 protected:
  void SetUp() override { path_ = dir_ / "database.db"; }

  const test::ScopedTestDir scoped_dir_{"parallax_database_test"};
  const fs::path dir_ = scoped_dir_.path();
  fs::path path_;
};

TwoViewGeometry RandomGeometry(size_t num_inliers) {
  TwoViewGeometry geometry;
  geometry.config = TwoViewGeometry::kCalibrated;
  geometry.F = Eigen::Matrix3d::Random();
  geometry.E = Eigen::Matrix3d::Random();
  geometry.H = Eigen::Matrix3d::Random() + 3 * Eigen::Matrix3d::Identity();
  geometry.cam2_from_cam1 = Rigid3d(Eigen::Quaterniond(Eigen::Vector4d::Random()).normalized(),
                                    Eigen::Vector3d::Random());
  geometry.inlier_matches = RandomMatches(num_inliers);
  return geometry;
}

void ExpectKeypointsEqual(const FeatureKeypoints& a, const FeatureKeypoints& b) {
  ASSERT_EQ(a.size(), b.size());
  for (size_t i = 0; i < a.size(); ++i) {
    EXPECT_EQ(a[i].x, b[i].x);
    EXPECT_EQ(a[i].y, b[i].y);
    EXPECT_EQ(a[i].a11, b[i].a11);
    EXPECT_EQ(a[i].a12, b[i].a12);
    EXPECT_EQ(a[i].a21, b[i].a21);
    EXPECT_EQ(a[i].a22, b[i].a22);
  }
}

void ExpectGeometryNear(const TwoViewGeometry& a, const TwoViewGeometry& b) {
  EXPECT_EQ(a.config, b.config);
  EXPECT_THAT(a.F, EigenMatrixNear(b.F, 1e-12));
  EXPECT_THAT(a.E, EigenMatrixNear(b.E, 1e-12));
  EXPECT_THAT(a.H, EigenMatrixNear(b.H, 1e-12));
  EXPECT_THAT(a.cam2_from_cam1, Rigid3dNear(b.cam2_from_cam1, 1e-12, 1e-12));
  EXPECT_EQ(a.inlier_matches, b.inlier_matches);
}

// Plain sqlite3 access for checking what is on disk.
class RawDatabase {
 public:
  explicit RawDatabase(const fs::path& path) {
    EXPECT_EQ(
        sqlite3_open_v2(path.c_str(), &db_, SQLITE_OPEN_READWRITE | SQLITE_OPEN_CREATE, nullptr),
        SQLITE_OK);
  }
  ~RawDatabase() { sqlite3_close_v2(db_); }
  void Exec(const std::string& sql) {
    char* error = nullptr;
    ASSERT_EQ(sqlite3_exec(db_, sql.c_str(), nullptr, nullptr, &error), SQLITE_OK)
        << (error ? error : "");
  }
  // Every row of a query, each column as text (blobs as raw bytes).
  std::vector<std::vector<std::string>> Query(const std::string& sql) {
    sqlite3_stmt* stmt = nullptr;
    EXPECT_EQ(sqlite3_prepare_v2(db_, sql.c_str(), -1, &stmt, nullptr), SQLITE_OK) << sql;
    std::vector<std::vector<std::string>> rows;
    while (sqlite3_step(stmt) == SQLITE_ROW) {
      std::vector<std::string> row;
      for (int c = 0; c < sqlite3_column_count(stmt); ++c) {
        const char* data = static_cast<const char*>(sqlite3_column_blob(stmt, c));
        row.emplace_back(data == nullptr ? "" : std::string(data, sqlite3_column_bytes(stmt, c)));
      }
      rows.push_back(row);
    }
    sqlite3_finalize(stmt);
    return rows;
  }
  sqlite3* db() { return db_; }

 private:
  sqlite3* db_ = nullptr;
};

template <typename T>
std::vector<T> BlobAs(const std::string& blob) {
  std::vector<T> values(blob.size() / sizeof(T));
  std::memcpy(values.data(), blob.data(), values.size() * sizeof(T));
  EXPECT_EQ(blob.size() % sizeof(T), 0u);
  return values;
}

TEST_F(DatabaseTest, CamerasRoundTrip) {
  Database database(path_);
  Camera camera1 = Camera::Create(kInvalidCameraId, CameraModelId::kSimpleRadial, 768, 640, 480);
  camera1.params[3] = -0.05;
  Camera camera2 = Camera::Create(7, CameraModelId::kPinhole, 1000, 1280, 960);
  camera2.params[1] = 1010;
  camera2.has_prior_focal_length = true;
  const camera_t id1 = database.WriteCamera(camera1);
  const camera_t id2 = database.WriteCamera(camera2, /*use_camera_id=*/true);
  EXPECT_EQ(id1, 1u);
  EXPECT_EQ(id2, 7u);
  EXPECT_TRUE(database.ExistsCamera(7));
  EXPECT_FALSE(database.ExistsCamera(2));
  EXPECT_EQ(database.NumCameras(), 2u);

  const Camera read1 = database.ReadCamera(id1);
  EXPECT_EQ(read1.camera_id, id1);
  EXPECT_EQ(read1.model_id, CameraModelId::kSimpleRadial);
  EXPECT_EQ(read1.width, 640u);
  EXPECT_EQ(read1.height, 480u);
  EXPECT_EQ(read1.params, camera1.params);
  EXPECT_FALSE(read1.has_prior_focal_length);

  camera2.params[0] = 1234.5;
  camera2.width = 1281;
  database.UpdateCamera(camera2);
  const std::vector<Camera> cameras = database.ReadAllCameras();
  ASSERT_EQ(cameras.size(), 2u);
  EXPECT_EQ(cameras[1].camera_id, 7u);
  EXPECT_EQ(cameras[1].params, camera2.params);
  EXPECT_EQ(cameras[1].width, 1281u);
  EXPECT_TRUE(cameras[1].has_prior_focal_length);
  EXPECT_THROW(database.ReadCamera(3), CheckError);
}

// COLMAP's prior_focal_length is 1 for a focal length from EXIF or the user, which its
// mapper still refines; Parallax's known (fixed) intrinsics are written as 2, which COLMAP
// reads as its prior too. So a COLMAP database's cameras are refined, Parallax's known ones
// stay fixed.
TEST_F(DatabaseTest, KnownIntrinsicsAndColmapsFocalPriorAreTold) {
  {
    Database database(path_);
    Camera known = Camera::Create(kInvalidCameraId, CameraModelId::kPinhole, 1000, 640, 480);
    known.has_prior_focal_length = true;
    database.WriteCamera(known);
    database.WriteCamera(
        Camera::Create(kInvalidCameraId, CameraModelId::kOpenCVFisheye, 230, 640, 640));
    Camera from_exif =
        Camera::Create(kInvalidCameraId, CameraModelId::kSimpleRadial, 700, 640, 480);
    from_exif.focal_length_from_exif = true;
    database.WriteCamera(from_exif);
  }
  {
    RawDatabase raw(path_);
    const auto flags = raw.Query("SELECT prior_focal_length FROM cameras ORDER BY camera_id;");
    ASSERT_EQ(flags.size(), 3u);
    EXPECT_EQ(flags[0][0], "2");
    EXPECT_EQ(flags[1][0], "0");
    EXPECT_EQ(flags[2][0], "1");  // As COLMAP writes an EXIF focal length.
    raw.Exec("UPDATE cameras SET prior_focal_length = 1 WHERE camera_id = 2;");  // COLMAP's EXIF.
  }
  Database database(path_);
  EXPECT_TRUE(database.ReadCamera(1).has_prior_focal_length);
  EXPECT_FALSE(database.ReadCamera(1).focal_length_from_exif);
  EXPECT_FALSE(database.ReadCamera(2).has_prior_focal_length);
  EXPECT_TRUE(database.ReadCamera(2).focal_length_from_exif);
  EXPECT_FALSE(database.ReadCamera(3).has_prior_focal_length);
  EXPECT_TRUE(database.ReadCamera(3).focal_length_from_exif);
}

TEST_F(DatabaseTest, ImagesRoundTrip) {
  Database database(path_);
  const camera_t camera_id =
      database.WriteCamera(Camera::Create(kInvalidCameraId, CameraModelId::kPinhole, 500, 64, 48));
  const image_t id1 = database.WriteImage("a.png", camera_id);
  const image_t id2 = database.WriteImage("sub/b.png", camera_id);
  EXPECT_EQ(id1, 1u);
  EXPECT_EQ(id2, 2u);
  EXPECT_EQ(database.ImageIdByName("sub/b.png"), std::optional<image_t>(id2));
  EXPECT_FALSE(database.ImageIdByName("c.png").has_value());
  EXPECT_TRUE(database.ExistsImage(id1));
  EXPECT_FALSE(database.ExistsImage(3));
  const Image image = database.ReadImage(id2);
  EXPECT_EQ(image.image_id, id2);
  EXPECT_EQ(image.name, "sub/b.png");
  EXPECT_EQ(image.camera_id, camera_id);
  EXPECT_TRUE(image.points2D.empty());
  EXPECT_EQ(database.ReadAllImages().size(), 2u);
  EXPECT_EQ(database.NumImages(), 2u);
  // Names are unique and cameras must exist (COLMAP's constraints).
  EXPECT_THROW(database.WriteImage("a.png", camera_id), InputError);
  EXPECT_THROW(database.WriteImage("d.png", 99), InputError);
  EXPECT_EQ(database.NumImages(), 2u);
}

// After a checkpoint the file alone holds the database: a copy of it without the
// write-ahead log (what a reader on another machine may see) has every row.
TEST_F(DatabaseTest, CheckpointLeavesEverythingInTheFile) {
  Database database(path_);
  const camera_t camera_id =
      database.WriteCamera(Camera::Create(kInvalidCameraId, CameraModelId::kPinhole, 500, 64, 48));
  database.WriteImage("a.png", camera_id);
  const fs::path wal = path_.string() + "-wal";
  ASSERT_TRUE(fs::exists(wal));
  EXPECT_GT(fs::file_size(wal), 0u);
  database.Checkpoint();
  EXPECT_EQ(fs::file_size(wal), 0u);
  const fs::path copy = dir_ / "copy.db";
  fs::copy_file(path_, copy);
  const Database reader(copy);
  EXPECT_EQ(reader.NumImages(), 1u);
  EXPECT_EQ(reader.NumCameras(), 1u);
}

TEST_F(DatabaseTest, FeaturesRoundTrip) {
  const FeatureKeypoints keypoints = RandomKeypoints(300);
  const FeatureDescriptors descriptors = RandomDescriptors(300);
  {
    Database database(path_);
    const camera_t camera_id = database.WriteCamera(
        Camera::Create(kInvalidCameraId, CameraModelId::kPinhole, 500, 64, 48));
    EXPECT_EQ(database.WriteImageWithFeatures("a.png", camera_id, keypoints, descriptors), 1u);
    const image_t id2 = database.WriteImage("b.png", camera_id);
    EXPECT_FALSE(database.ExistsKeypoints(id2));
    database.WriteKeypoints(id2, {});
    database.WriteDescriptors(id2, FeatureDescriptors(0, 128));
    // Writing features twice is an error, as in COLMAP.
    EXPECT_THROW(database.WriteKeypoints(id2, keypoints), InputError);
    EXPECT_THROW(
        database.WriteImageWithFeatures("c.png", camera_id, keypoints, RandomDescriptors(3)),
        CheckError);
  }
  Database database(path_);
  EXPECT_TRUE(database.ExistsKeypoints(1));
  EXPECT_TRUE(database.ExistsDescriptors(1));
  EXPECT_EQ(database.NumKeypoints(1), 300u);
  ExpectKeypointsEqual(database.ReadKeypoints(1), keypoints);
  EXPECT_EQ(database.ReadDescriptors(1), descriptors);
  EXPECT_EQ(database.NumKeypoints(2), 0u);
  EXPECT_TRUE(database.ReadKeypoints(2).empty());
  EXPECT_EQ(database.ReadDescriptors(2).rows(), 0);
  EXPECT_FALSE(database.ImageIdByName("c.png").has_value());
  EXPECT_EQ(database.NumKeypoints(3), 0u);
}

TEST_F(DatabaseTest, FingerprintsRoundTripAndGoWithTheirImage) {
  Database database(path_);
  const camera_t shared =
      database.WriteCamera(Camera::Create(kInvalidCameraId, CameraModelId::kPinhole, 500, 64, 48));
  const camera_t own =
      database.WriteCamera(Camera::Create(kInvalidCameraId, CameraModelId::kPinhole, 600, 64, 48));
  const ImageFileFingerprint fingerprint{12345, 1700000000123456789, "00ff"};
  const image_t a = database.WriteImageWithFeatures("a.png", shared, RandomKeypoints(5),
                                                    RandomDescriptors(5), fingerprint);
  const image_t b =
      database.WriteImageWithFeatures("b.png", shared, RandomKeypoints(5), RandomDescriptors(5));
  const image_t c = database.WriteImageWithFeatures("c.png", own, RandomKeypoints(5),
                                                    RandomDescriptors(5), fingerprint);
  const auto read = database.ReadImageFileFingerprint(a);
  ASSERT_TRUE(read.has_value());
  EXPECT_EQ(read->size, 12345u);
  EXPECT_EQ(read->mtime_ns, 1700000000123456789);
  EXPECT_EQ(read->content_hash, "00ff");
  EXPECT_FALSE(database.ReadImageFileFingerprint(b).has_value());
  database.WriteImageFileFingerprint(b, {1, 2, "ab"});
  EXPECT_EQ(database.ReadImageFileFingerprint(b)->content_hash, "ab");
  for (const auto& [first, second] : {std::pair{a, b}, std::pair{c, a}, std::pair{b, c}}) {
    database.WriteMatches(first, second, RandomMatches(10));
    database.WriteTwoViewGeometry(first, second, RandomGeometry(8));
  }

  // Deleting c takes its features, fingerprint, both of its pairs and its own camera.
  database.DeleteImage(c);
  EXPECT_FALSE(database.ImageIdByName("c.png").has_value());
  EXPECT_FALSE(database.ExistsKeypoints(c));
  EXPECT_FALSE(database.ExistsDescriptors(c));
  EXPECT_FALSE(database.ReadImageFileFingerprint(c).has_value());
  EXPECT_FALSE(database.ExistsMatches(a, c));
  EXPECT_FALSE(database.ExistsTwoViewGeometry(b, c));
  EXPECT_TRUE(database.ExistsMatches(a, b));
  EXPECT_TRUE(database.ExistsTwoViewGeometry(a, b));
  EXPECT_FALSE(database.ExistsCamera(own));
  // Deleting a leaves the camera b still uses.
  database.DeleteImage(a);
  EXPECT_FALSE(database.ExistsMatches(a, b));
  EXPECT_TRUE(database.ExistsCamera(shared));
  EXPECT_EQ(database.NumImages(), 1u);
  EXPECT_NO_THROW(database.DeleteImage(a));  // Already gone: nothing to do.
}

TEST_F(DatabaseTest, KeypointColorsRoundTripAndGoWithTheirImage) {
  const KeypointColors colors = {255, 0, 1, 10, 20, 30, 7, 8, 9};
  image_t a = kInvalidImageId, b = kInvalidImageId;
  {
    Database database(path_);
    const camera_t camera_id = database.WriteCamera(
        Camera::Create(kInvalidCameraId, CameraModelId::kPinhole, 500, 64, 48));
    a = database.WriteImageWithFeatures("a.png", camera_id, RandomKeypoints(3),
                                        RandomDescriptors(3), std::nullopt, std::nullopt, colors);
    b = database.WriteImageWithFeatures("b.png", camera_id, RandomKeypoints(2),
                                        RandomDescriptors(2));
  }
  Database database(path_);
  EXPECT_EQ(database.ReadKeypointColors(a), colors);
  EXPECT_FALSE(database.ReadKeypointColors(b).has_value());  // As COLMAP stores an image.
  database.WriteKeypointColors(b, {1, 2, 3, 4, 5, 6});
  EXPECT_EQ(database.ReadKeypointColors(b), (KeypointColors{1, 2, 3, 4, 5, 6}));
  database.DeleteImage(a);
  EXPECT_FALSE(database.ReadKeypointColors(a).has_value());
}

TEST_F(DatabaseTest, MalformedKeypointColorsNameTheDatabase) {
  image_t image_id = kInvalidImageId;
  {
    Database database(path_);
    const camera_t camera_id = database.WriteCamera(
        Camera::Create(kInvalidCameraId, CameraModelId::kPinhole, 500, 64, 48));
    image_id = database.WriteImageWithFeatures("a.png", camera_id, RandomKeypoints(2),
                                               RandomDescriptors(2), std::nullopt, std::nullopt,
                                               KeypointColors{1, 2, 3, 4, 5, 6});
  }
  sqlite3* db = nullptr;
  ASSERT_EQ(sqlite3_open(path_.c_str(), &db), SQLITE_OK);
  ASSERT_EQ(
      sqlite3_exec(db, "UPDATE parallax_keypoint_colors SET rows = 3;", nullptr, nullptr, nullptr),
      SQLITE_OK);
  sqlite3_close(db);
  Database database(path_);
  try {
    database.ReadKeypointColors(image_id);
    FAIL() << "no error";
  } catch (const InputError& error) {
    EXPECT_THAT(error.what(), ::testing::HasSubstr(path_.string()));
    EXPECT_THAT(error.what(), ::testing::HasSubstr("malformed keypoint colours"));
  }
}

TEST_F(DatabaseTest, ATwoViewGeometryCanBeDeletedAndWrittenAnew) {
  Database database(path_);
  database.WriteTwoViewGeometry(3, 2, RandomGeometry(8));
  database.WriteTwoViewGeometry(1, 2, RandomGeometry(6));
  EXPECT_ANY_THROW(database.WriteTwoViewGeometry(2, 3, RandomGeometry(5)));
  database.DeleteTwoViewGeometry(2, 3);
  EXPECT_FALSE(database.ExistsTwoViewGeometry(3, 2));
  EXPECT_TRUE(database.ExistsTwoViewGeometry(1, 2));
  database.WriteTwoViewGeometry(2, 3, RandomGeometry(5));
  EXPECT_EQ(database.ReadTwoViewGeometry(2, 3).inlier_matches.size(), 5u);
  EXPECT_NO_THROW(database.DeleteTwoViewGeometry(4, 5));  // Nothing stored: nothing to do.
}

TEST_F(DatabaseTest, MatchesAreStoredWithSmallerIdFirst) {
  Database database(path_);
  const FeatureMatches matches12 = RandomMatches(50);
  const FeatureMatches matches32 = RandomMatches(20);
  database.WriteMatches(1, 2, matches12);
  database.WriteMatches(3, 2, matches32);
  EXPECT_TRUE(database.ExistsMatches(2, 3));
  EXPECT_TRUE(database.ExistsMatches(2, 1));
  EXPECT_FALSE(database.ExistsMatches(1, 3));
  EXPECT_EQ(database.ReadMatches(1, 2), matches12);
  EXPECT_EQ(database.ReadMatches(3, 2), matches32);
  FeatureMatches swapped = matches32;
  for (FeatureMatch& match : swapped) std::swap(match.point2D_idx1, match.point2D_idx2);
  EXPECT_EQ(database.ReadMatches(2, 3), swapped);
  EXPECT_TRUE(database.ReadMatches(1, 3).empty());
  EXPECT_THROW(database.WriteMatches(2, 1, matches12), InputError);

  const auto all = database.ReadAllMatches();
  ASSERT_EQ(all.size(), 2u);
  EXPECT_EQ(all[0].first, ImagePairToPairId(1, 2));
  EXPECT_EQ(all[0].second, matches12);
  EXPECT_EQ(all[1].first, ImagePairToPairId(2, 3));
  EXPECT_EQ(all[1].second, swapped);
  EXPECT_EQ(database.NumMatchedPairs(), 2u);
}

TEST_F(DatabaseTest, TwoViewGeometryIsInvertedWhenSwapped) {
  Database database(path_);
  const TwoViewGeometry geometry = RandomGeometry(40);
  database.WriteTwoViewGeometry(5, 2, geometry);
  EXPECT_TRUE(database.ExistsTwoViewGeometry(2, 5));
  ExpectGeometryNear(database.ReadTwoViewGeometry(5, 2), geometry);

  // Seen from image 2: F and E transposed, H inverted, the pose inverted, matches swapped.
  const TwoViewGeometry inverted = database.ReadTwoViewGeometry(2, 5);
  EXPECT_TRUE(inverted.F.isApprox(geometry.F.transpose(), 1e-12));
  EXPECT_TRUE(inverted.E.isApprox(geometry.E.transpose(), 1e-12));
  EXPECT_TRUE((inverted.H * geometry.H).isApprox(Eigen::Matrix3d::Identity(), 1e-9));
  const Rigid3d identity = inverted.cam2_from_cam1 * geometry.cam2_from_cam1;
  EXPECT_LT(identity.rotation.angularDistance(Eigen::Quaterniond::Identity()), 1e-12);
  EXPECT_LT(identity.translation.norm(), 1e-12);
  ASSERT_EQ(inverted.inlier_matches.size(), 40u);
  EXPECT_EQ(inverted.inlier_matches[7].point2D_idx1, geometry.inlier_matches[7].point2D_idx2);
  EXPECT_EQ(inverted.inlier_matches[7].point2D_idx2, geometry.inlier_matches[7].point2D_idx1);

  // The stored order is (2, 5): ReadTwoViewGeometries returns the inverted one.
  const auto all = database.ReadTwoViewGeometries();
  ASSERT_EQ(all.size(), 1u);
  EXPECT_EQ(all[0].first, ImagePairToPairId(2, 5));
  ExpectGeometryNear(all[0].second, inverted);
}

TEST_F(DatabaseTest, DegeneratePairsAndNumInliers) {
  Database database(path_);
  TwoViewGeometry degenerate;
  degenerate.config = TwoViewGeometry::kDegenerate;
  database.WriteTwoViewGeometry(1, 2, degenerate);
  TwoViewGeometry planar = RandomGeometry(25);
  planar.config = TwoViewGeometry::kPlanar;
  database.WriteTwoViewGeometry(1, 3, planar);
  database.WriteTwoViewGeometry(2, 3, RandomGeometry(30));

  const TwoViewGeometry read = database.ReadTwoViewGeometry(2, 1);
  EXPECT_EQ(read.config, TwoViewGeometry::kDegenerate);
  EXPECT_TRUE(read.inlier_matches.empty());
  EXPECT_TRUE(read.F.isZero(0));
  EXPECT_TRUE(read.H.isZero(0));
  EXPECT_EQ(database.NumVerifiedPairs(), 3u);
  const auto num_inliers = database.ReadTwoViewGeometryNumInliers();
  ASSERT_EQ(num_inliers.size(), 2u);
  EXPECT_EQ(num_inliers[0], std::make_pair(ImagePairToPairId(1, 3), 25));
  EXPECT_EQ(num_inliers[1], std::make_pair(ImagePairToPairId(2, 3), 30));
}

TEST_F(DatabaseTest, RejectsFilesThatAreNotDatabases) {
  const fs::path text_path = dir_ / "notes.txt";
  std::ofstream(text_path) << "this is not an SQLite database, just a long enough text file to "
                              "have a header that SQLite reads and rejects.\n";
  try {
    Database database(text_path);
    FAIL() << "expected InputError";
  } catch (const InputError& error) {
    EXPECT_EQ(std::string(error.what()).rfind(text_path.string(), 0), 0u) << error.what();
  }
  EXPECT_THROW(Database(dir_ / "missing_folder" / "x.db"), InputError);
}

TEST_F(DatabaseTest, RejectsIncompatibleSchema) {
  {
    RawDatabase raw(path_);
    raw.Exec("CREATE TABLE images (image_id INTEGER PRIMARY KEY, filename TEXT);");
  }
  try {
    Database database(path_);
    FAIL() << "expected InputError";
  } catch (const InputError& error) {
    const std::string message = error.what();
    EXPECT_EQ(message.rfind(path_.string(), 0), 0u) << message;
    EXPECT_NE(message.find("'images'"), std::string::npos) << message;
  }
}

// The schema and the blobs as COLMAP 3.8 has them, checked through plain SQL.
TEST_F(DatabaseTest, ColmapCompatibleLayout) {
  const FeatureKeypoints keypoints = RandomKeypoints(10);
  const FeatureDescriptors descriptors = RandomDescriptors(10);
  TwoViewGeometry geometry = RandomGeometry(4);
  {
    Database database(path_);
    Camera camera = Camera::Create(kInvalidCameraId, CameraModelId::kSimpleRadial, 700, 640, 480);
    camera.params[3] = 0.01;
    const camera_t camera_id = database.WriteCamera(camera);
    database.WriteImageWithFeatures("a.png", camera_id, keypoints, descriptors);
    database.WriteImage("b.png", camera_id);
    database.WriteImage("c.png", camera_id);
    database.WriteMatches(3, 2, {{4, 5}, {6, 7}});
    database.WriteTwoViewGeometry(2, 3, geometry);
  }
  RawDatabase raw(path_);

  // (name, declared type, not null, primary key) of each column, in COLMAP 3.8's order.
  using Column = std::tuple<std::string, std::string, int, int>;
  const std::map<std::string, std::vector<Column>> expected = {
      {"cameras",
       {{"camera_id", "INTEGER", 1, 1},
        {"model", "INTEGER", 1, 0},
        {"width", "INTEGER", 1, 0},
        {"height", "INTEGER", 1, 0},
        {"params", "BLOB", 0, 0},
        {"prior_focal_length", "INTEGER", 1, 0}}},
      {"images",
       {{"image_id", "INTEGER", 1, 1},
        {"name", "TEXT", 1, 0},
        {"camera_id", "INTEGER", 1, 0},
        {"prior_qw", "REAL", 0, 0},
        {"prior_qx", "REAL", 0, 0},
        {"prior_qy", "REAL", 0, 0},
        {"prior_qz", "REAL", 0, 0},
        {"prior_tx", "REAL", 0, 0},
        {"prior_ty", "REAL", 0, 0},
        {"prior_tz", "REAL", 0, 0}}},
      {"keypoints",
       {{"image_id", "INTEGER", 1, 1},
        {"rows", "INTEGER", 1, 0},
        {"cols", "INTEGER", 1, 0},
        {"data", "BLOB", 0, 0}}},
      {"descriptors",
       {{"image_id", "INTEGER", 1, 1},
        {"rows", "INTEGER", 1, 0},
        {"cols", "INTEGER", 1, 0},
        {"data", "BLOB", 0, 0}}},
      {"matches",
       {{"pair_id", "INTEGER", 1, 1},
        {"rows", "INTEGER", 1, 0},
        {"cols", "INTEGER", 1, 0},
        {"data", "BLOB", 0, 0}}},
      {"two_view_geometries",
       {{"pair_id", "INTEGER", 1, 1},
        {"rows", "INTEGER", 1, 0},
        {"cols", "INTEGER", 1, 0},
        {"data", "BLOB", 0, 0},
        {"config", "INTEGER", 1, 0},
        {"F", "BLOB", 0, 0},
        {"E", "BLOB", 0, 0},
        {"H", "BLOB", 0, 0},
        {"qvec", "BLOB", 0, 0},
        {"tvec", "BLOB", 0, 0}}},
  };
  std::vector<std::string> tables;
  for (const auto& row : raw.Query("SELECT name FROM sqlite_master WHERE type='table' AND "
                                   "name NOT LIKE 'sqlite_%' ORDER BY name;")) {
    tables.push_back(row[0]);
  }
  // COLMAP's six, and Parallax's own tables of image file fingerprints and keypoint colours,
  // which COLMAP ignores.
  EXPECT_EQ(tables, (std::vector<std::string>{"cameras", "descriptors", "images", "keypoints",
                                              "matches", "parallax_image_files",
                                              "parallax_keypoint_colors", "two_view_geometries"}));
  for (const auto& [table, columns] : expected) {
    std::vector<Column> actual;
    for (const auto& row : raw.Query("PRAGMA table_info(" + table + ");")) {
      actual.emplace_back(row[1], row[2], std::stoi(row[3]), std::stoi(row[5]));
    }
    EXPECT_EQ(actual, columns) << table;
  }
  // AUTOINCREMENT ids, the image id range check, the unique name index, foreign keys.
  const auto sql = [&](const std::string& name) {
    return raw.Query("SELECT sql FROM sqlite_master WHERE name='" + name + "';").at(0).at(0);
  };
  EXPECT_NE(sql("cameras").find("AUTOINCREMENT"), std::string::npos);
  EXPECT_NE(sql("images").find("AUTOINCREMENT"), std::string::npos);
  EXPECT_NE(sql("images").find("CHECK(image_id >= 0 and image_id < 2147483647)"),
            std::string::npos);
  EXPECT_NE(sql("images").find("UNIQUE"), std::string::npos);
  EXPECT_EQ(raw.Query("SELECT name FROM sqlite_master WHERE type='index' AND tbl_name='images' "
                      "AND name='index_name';")
                .size(),
            1u);
  EXPECT_EQ(raw.Query("SELECT COUNT(*) FROM sqlite_master WHERE type='trigger';")[0][0], "0");
  const auto keypoint_fk = raw.Query("PRAGMA foreign_key_list(keypoints);");
  ASSERT_EQ(keypoint_fk.size(), 1u);
  EXPECT_EQ(keypoint_fk[0][2], "images");
  EXPECT_EQ(keypoint_fk[0][6], "CASCADE");
  EXPECT_EQ(raw.Query("PRAGMA foreign_key_list(images);").at(0).at(2), "cameras");
  EXPECT_EQ(raw.Query("PRAGMA user_version;")[0][0], "3800");
  EXPECT_EQ(raw.Query("PRAGMA integrity_check;")[0][0], "ok");

  // cameras: model id, size, params as float64, prior flag.
  const auto camera = raw.Query(
      "SELECT camera_id, model, width, height, params, "
      "prior_focal_length FROM cameras;");
  ASSERT_EQ(camera.size(), 1u);
  EXPECT_EQ(camera[0][1], "2");  // SIMPLE_RADIAL
  EXPECT_EQ(camera[0][2], "640");
  EXPECT_EQ(camera[0][3], "480");
  EXPECT_EQ(BlobAs<double>(camera[0][4]), (std::vector<double>{700, 320, 240, 0.01}));
  EXPECT_EQ(camera[0][5], "0");
  const auto image = raw.Query(
      "SELECT image_id, name, camera_id, prior_qw FROM images "
      "WHERE name='a.png';");
  ASSERT_EQ(image.size(), 1u);
  EXPECT_EQ(image[0][0], "1");
  EXPECT_EQ(image[0][2], "1");
  EXPECT_EQ(raw.Query("SELECT COUNT(*) FROM images WHERE prior_qw IS NULL;")[0][0], "3");

  // keypoints: rows x 6 float32 (x, y, a11, a12, a21, a22).
  const auto keypoint_row = raw.Query("SELECT rows, cols, data FROM keypoints WHERE image_id=1;");
  ASSERT_EQ(keypoint_row.size(), 1u);
  EXPECT_EQ(keypoint_row[0][0], "10");
  EXPECT_EQ(keypoint_row[0][1], "6");
  const std::vector<float> keypoint_blob = BlobAs<float>(keypoint_row[0][2]);
  ASSERT_EQ(keypoint_blob.size(), 60u);
  for (size_t i = 0; i < keypoints.size(); ++i) {
    const float* row = keypoint_blob.data() + 6 * i;
    EXPECT_EQ(row[0], keypoints[i].x);
    EXPECT_EQ(row[1], keypoints[i].y);
    EXPECT_EQ(row[2], keypoints[i].a11);
    EXPECT_EQ(row[3], keypoints[i].a12);
    EXPECT_EQ(row[4], keypoints[i].a21);
    EXPECT_EQ(row[5], keypoints[i].a22);
  }
  // descriptors: rows x 128 uint8, row-major.
  const auto descriptor_row = raw.Query("SELECT rows, cols, data FROM descriptors;");
  ASSERT_EQ(descriptor_row.size(), 1u);
  EXPECT_EQ(descriptor_row[0][0], "10");
  EXPECT_EQ(descriptor_row[0][1], "128");
  const std::vector<uint8_t> descriptor_blob = BlobAs<uint8_t>(descriptor_row[0][2]);
  ASSERT_EQ(descriptor_blob.size(), 1280u);
  EXPECT_EQ(descriptor_blob[3 * 128 + 17], descriptors(3, 17));

  // matches: pair_id = 2147483647 * 2 + 3, rows x 2 uint32 with the columns swapped.
  const auto match_row = raw.Query("SELECT pair_id, rows, cols, data FROM matches;");
  ASSERT_EQ(match_row.size(), 1u);
  EXPECT_EQ(match_row[0][0], std::to_string(2147483647LL * 2 + 3));
  EXPECT_EQ(match_row[0][1], "2");
  EXPECT_EQ(match_row[0][2], "2");
  EXPECT_EQ(BlobAs<uint32_t>(match_row[0][3]), (std::vector<uint32_t>{5, 4, 7, 6}));

  // two_view_geometries: inliers, config, row-major F/E/H, qvec (w, x, y, z), tvec.
  const auto geometry_row = raw.Query(
      "SELECT pair_id, rows, cols, data, config, F, E, H, qvec, tvec "
      "FROM two_view_geometries;");
  ASSERT_EQ(geometry_row.size(), 1u);
  EXPECT_EQ(geometry_row[0][0], std::to_string(2147483647LL * 2 + 3));
  EXPECT_EQ(geometry_row[0][1], "4");
  EXPECT_EQ(geometry_row[0][2], "2");
  const std::vector<uint32_t> inliers = BlobAs<uint32_t>(geometry_row[0][3]);
  ASSERT_EQ(inliers.size(), 8u);
  EXPECT_EQ(inliers[2], geometry.inlier_matches[1].point2D_idx1);
  EXPECT_EQ(inliers[3], geometry.inlier_matches[1].point2D_idx2);
  EXPECT_EQ(geometry_row[0][4], "2");
  const auto check_row_major = [](const std::string& blob, const Eigen::Matrix3d& matrix) {
    const std::vector<double> values = BlobAs<double>(blob);
    ASSERT_EQ(values.size(), 9u);
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 3; ++c) EXPECT_EQ(values[3 * r + c], matrix(r, c));
    }
  };
  check_row_major(geometry_row[0][5], geometry.F);
  check_row_major(geometry_row[0][6], geometry.E);
  check_row_major(geometry_row[0][7], geometry.H);
  const std::vector<double> qvec = BlobAs<double>(geometry_row[0][8]);
  ASSERT_EQ(qvec.size(), 4u);
  EXPECT_EQ(qvec[0], geometry.cam2_from_cam1.rotation.w());
  EXPECT_EQ(qvec[1], geometry.cam2_from_cam1.rotation.x());
  EXPECT_EQ(qvec[3], geometry.cam2_from_cam1.rotation.z());
  const std::vector<double> tvec = BlobAs<double>(geometry_row[0][9]);
  ASSERT_EQ(tvec.size(), 3u);
  EXPECT_EQ(tvec[1], geometry.cam2_from_cam1.translation.y());
}

// A database written by another program through plain SQL: older 4-column keypoints and a
// two_view_geometries table from before COLMAP added F/E/H/qvec/tvec.
TEST_F(DatabaseTest, ReadsOlderColmapLayouts) {
  {
    RawDatabase raw(path_);
    raw.Exec(
        "CREATE TABLE two_view_geometries (pair_id INTEGER PRIMARY KEY NOT NULL, rows INTEGER "
        "NOT NULL, cols INTEGER NOT NULL, data BLOB, config INTEGER NOT NULL);");
    raw.Exec("INSERT INTO two_view_geometries VALUES (2147483649, 0, 2, x'', 1);");
  }
  {
    Database database(path_);
    const camera_t camera_id = database.WriteCamera(
        Camera::Create(kInvalidCameraId, CameraModelId::kPinhole, 500, 64, 48));
    database.WriteImage("a.png", camera_id);
    EXPECT_EQ(database.ReadTwoViewGeometry(1, 2).config, TwoViewGeometry::kDegenerate);
    database.WriteTwoViewGeometry(1, 3, RandomGeometry(3));
  }
  RawDatabase raw(path_);
  const float blob[8] = {10.5f, 20.5f, 2.0f, 0.5f, 30.5f, 40.5f, 1.0f, 0.0f};
  sqlite3_stmt* stmt = nullptr;
  ASSERT_EQ(sqlite3_prepare_v2(raw.db(), "INSERT INTO keypoints VALUES (1, 2, 4, ?);", -1, &stmt,
                               nullptr),
            SQLITE_OK);
  sqlite3_bind_blob(stmt, 1, blob, sizeof(blob), SQLITE_STATIC);
  ASSERT_EQ(sqlite3_step(stmt), SQLITE_DONE);
  sqlite3_finalize(stmt);

  Database database(path_);
  const FeatureKeypoints keypoints = database.ReadKeypoints(1);
  ASSERT_EQ(keypoints.size(), 2u);
  EXPECT_EQ(keypoints[0].x, 10.5f);
  EXPECT_NEAR(keypoints[0].ComputeScale(), 2.0f, 1e-5);
  EXPECT_NEAR(keypoints[0].ComputeOrientation(), 0.5f, 1e-5);
  EXPECT_NEAR(keypoints[1].ComputeScale(), 1.0f, 1e-5);
  EXPECT_EQ(database.ReadTwoViewGeometry(1, 3).inlier_matches.size(), 3u);
}

// A database as COLMAP 4 writes it: rigs and frames, no pose priors in images (they are in
// pose_priors), a descriptor type column, camera blobs in two_view_geometries.
TEST_F(DatabaseTest, ReadsAndMatchesColmap4Layout) {
  {
    RawDatabase raw(path_);
    raw.Exec(
        "CREATE TABLE rigs (rig_id INTEGER PRIMARY KEY AUTOINCREMENT NOT NULL, ref_sensor_id "
        "INTEGER NOT NULL, ref_sensor_type INTEGER NOT NULL);"
        "CREATE TABLE frames (frame_id INTEGER PRIMARY KEY AUTOINCREMENT NOT NULL, rig_id INTEGER "
        "NOT NULL);"
        "CREATE TABLE frame_data (frame_id INTEGER NOT NULL, data_id INTEGER NOT NULL, sensor_id "
        "INTEGER NOT NULL, sensor_type INTEGER NOT NULL);"
        "CREATE TABLE cameras (camera_id INTEGER PRIMARY KEY AUTOINCREMENT NOT NULL, model "
        "INTEGER NOT NULL, width INTEGER NOT NULL, height INTEGER NOT NULL, params BLOB, "
        "prior_focal_length INTEGER NOT NULL);"
        "CREATE TABLE images (image_id INTEGER PRIMARY KEY AUTOINCREMENT NOT NULL, name TEXT NOT "
        "NULL UNIQUE, camera_id INTEGER NOT NULL);"
        "CREATE TABLE pose_priors (pose_prior_id INTEGER PRIMARY KEY NOT NULL, corr_data_id "
        "INTEGER NOT NULL, corr_sensor_id INTEGER NOT NULL, corr_sensor_type INTEGER NOT NULL, "
        "position BLOB, position_covariance BLOB, gravity BLOB, coordinate_system INTEGER NOT "
        "NULL);"
        "CREATE TABLE keypoints (image_id INTEGER PRIMARY KEY NOT NULL, rows INTEGER NOT NULL, "
        "cols INTEGER NOT NULL, data BLOB);"
        "CREATE TABLE descriptors (image_id INTEGER PRIMARY KEY NOT NULL, type INTEGER NOT NULL, "
        "rows INTEGER NOT NULL, cols INTEGER NOT NULL, data BLOB);"
        "CREATE TABLE matches (pair_id INTEGER PRIMARY KEY NOT NULL, rows INTEGER NOT NULL, cols "
        "INTEGER NOT NULL, data BLOB);"
        "CREATE TABLE two_view_geometries (pair_id INTEGER PRIMARY KEY NOT NULL, rows INTEGER NOT "
        "NULL, cols INTEGER NOT NULL, data BLOB, config INTEGER NOT NULL, F BLOB, E BLOB, H BLOB, "
        "qvec BLOB, tvec BLOB, camera1 BLOB, camera2 BLOB);"
        "INSERT INTO cameras VALUES (1, 1, 64, 48, x'', 1);"
        "INSERT INTO images VALUES (1, 'a.png', 1), (2, 'b.png', 1), (3, 'c.png', 1);"
        "INSERT INTO descriptors VALUES (1, 0, 1, 4, x'01020304');");
    // Image 1 in WGS84, image 2 in a local Cartesian frame (not a GPS position).
    const double wgs84[3] = {46.5, 6.5, 400.0}, cartesian[3] = {1.0, 2.0, 3.0};
    for (const auto& [image_id, position, system] :
         {std::tuple{1, wgs84, 0}, std::tuple{2, cartesian, 1}}) {
      sqlite3_stmt* stmt = nullptr;
      ASSERT_EQ(sqlite3_prepare_v2(raw.db(),
                                   "INSERT INTO pose_priors VALUES (?1, ?1, 1, 0, ?2, NULL, NULL, "
                                   "?3);",
                                   -1, &stmt, nullptr),
                SQLITE_OK);
      sqlite3_bind_int(stmt, 1, image_id);
      sqlite3_bind_blob(stmt, 2, position, 3 * sizeof(double), SQLITE_STATIC);
      sqlite3_bind_int(stmt, 3, system);
      ASSERT_EQ(sqlite3_step(stmt), SQLITE_DONE);
      sqlite3_finalize(stmt);
    }
  }
  {
    Database database(path_);
    EXPECT_EQ(database.ReadAllImages().size(), 3u);
    EXPECT_EQ(database.ReadDescriptors(1), (FeatureDescriptors(1, 4) << 1, 2, 3, 4).finished());
    const auto priors = database.ReadImageGpsPriors();
    ASSERT_EQ(priors.size(), 1u);
    EXPECT_EQ(priors[0].first, 1u);
    EXPECT_EQ(priors[0].second.latitude, 46.5);
    EXPECT_EQ(priors[0].second.longitude, 6.5);
    EXPECT_EQ(priors[0].second.altitude, 400.0);
    // Matching writes its results; the geometry reads back.
    database.WriteTwoViewGeometry(1, 2, RandomGeometry(5));
    EXPECT_EQ(database.ReadTwoViewGeometry(1, 2).inlier_matches.size(), 5u);
    // New cameras and images would need COLMAP 4's rigs and frames: refused in one line.
    try {
      database.WriteImage("d.png", 1);
      ADD_FAILURE() << "a COLMAP 4 database took a new image";
    } catch (const InputError& error) {
      const std::string message = error.what();
      EXPECT_NE(message.find(path_.string()), std::string::npos) << message;
      EXPECT_NE(message.find("COLMAP 4"), std::string::npos) << message;
      EXPECT_EQ(message.find('\n'), std::string::npos) << message;
    }
    EXPECT_THROW(database.WriteCamera(
                     Camera::Create(kInvalidCameraId, CameraModelId::kPinhole, 500, 64, 48)),
                 InputError);
  }
  // Opening it changed none of COLMAP 4's tables: images has no pose prior columns.
  RawDatabase raw(path_);
  for (const auto& column : raw.Query("SELECT name FROM pragma_table_info('images');")) {
    EXPECT_EQ(column[0].rfind("prior_", 0), std::string::npos) << column[0];
  }
  EXPECT_EQ(raw.Query("SELECT COUNT(*) FROM images;")[0][0], "3");
}

// A writer killed at a random moment leaves a valid database with only complete images.
TEST_F(DatabaseTest, SurvivesKilledWriter) {
  int ready[2];
  ASSERT_EQ(pipe(ready), 0);
  const pid_t child = fork();
  ASSERT_GE(child, 0);
  if (child == 0) {
    close(ready[0]);
    try {
      Database database(path_);
      const camera_t camera_id = database.WriteCamera(
          Camera::Create(kInvalidCameraId, CameraModelId::kPinhole, 500, 64, 48));
      for (int i = 0;; ++i) {
        // Large blobs so that the kill likely lands inside a write.
        const size_t count = 2000 + 37 * (i % 50);
        database.WriteImageWithFeatures("image" + std::to_string(i), camera_id,
                                        RandomKeypoints(count), RandomDescriptors(count));
        if (i == 5) (void)!write(ready[1], "x", 1);
      }
    } catch (...) {
    }
    _exit(1);
  }
  close(ready[1]);
  char byte = 0;
  ASSERT_EQ(read(ready[0], &byte, 1), 1);
  close(ready[0]);
  usleep(static_cast<useconds_t>(RandomUniformReal(0.0, 200000.0)));
  kill(child, SIGKILL);
  int status = 0;
  waitpid(child, &status, 0);
  ASSERT_TRUE(WIFSIGNALED(status));

  Database database(path_);
  const std::vector<Image> images = database.ReadAllImages();
  EXPECT_GE(images.size(), 6u);
  for (const Image& image : images) {
    const size_t count = 2000 + 37 * (std::stoi(image.name.substr(5)) % 50);
    EXPECT_EQ(database.NumKeypoints(image.image_id), count) << image.name;
    EXPECT_EQ(database.ReadKeypoints(image.image_id).size(), count);
    EXPECT_EQ(static_cast<size_t>(database.ReadDescriptors(image.image_id).rows()), count);
  }
  RawDatabase raw(path_);
  EXPECT_EQ(raw.Query("PRAGMA integrity_check;")[0][0], "ok");
  EXPECT_EQ(raw.Query("SELECT COUNT(*) FROM images WHERE image_id NOT IN "
                      "(SELECT image_id FROM descriptors);")[0][0],
            "0");
}

}  // namespace
}  // namespace parallax
