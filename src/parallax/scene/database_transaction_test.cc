// DatabaseTransaction (scene/database.h): many writes as one, committed or rolled back by scope.
#include <gtest/gtest.h>

#include <filesystem>
#include <stdexcept>

#include "parallax/scene/database.h"
#include "parallax/scene/testing/random_features.h"
#include "parallax/util/check.h"
#include "parallax/util/test_dir.h"

namespace parallax {
namespace {

using test::RandomDescriptors;
using test::RandomKeypoints;
using test::RandomMatches;

// A fresh database path in a per-test temporary folder.
class DatabaseTransactionTest : public ::testing::Test {
 protected:
  const test::ScopedTestDir scoped_dir_{"parallax_database_transaction_test"};
  const std::filesystem::path path_ = scoped_dir_.path() / "database.db";
};

TEST_F(DatabaseTransactionTest, BatchesWritesUntilCommit) {
  Database database(path_);
  const camera_t camera_id =
      database.WriteCamera(Camera::Create(kInvalidCameraId, CameraModelId::kPinhole, 500, 64, 48));
  {
    DatabaseTransaction transaction(&database);
    // Writes that are one transaction on their own join it.
    database.WriteImageWithFeatures("a.png", camera_id, RandomKeypoints(5), RandomDescriptors(5));
    for (image_t i = 1; i <= 20; ++i) database.WriteMatches(i, i + 1, RandomMatches(3));
    {
      // Another connection does not see uncommitted writes.
      Database reader(path_);
      EXPECT_EQ(reader.NumMatchedPairs(), 0u);
      EXPECT_EQ(reader.NumImages(), 0u);
    }
    transaction.Commit();
    EXPECT_THROW(transaction.Commit(), CheckError);
  }
  Database reader(path_);
  EXPECT_EQ(reader.NumMatchedPairs(), 20u);
  EXPECT_EQ(reader.NumKeypoints(1), 5u);
}

TEST_F(DatabaseTransactionTest, RefusesNesting) {
  Database database(path_);
  DatabaseTransaction transaction(&database);
  EXPECT_THROW(DatabaseTransaction nested(&database), CheckError);
  // The refused one touched nothing: the open one still writes and commits.
  database.WriteMatches(1, 2, RandomMatches(4));
  transaction.Commit();
  EXPECT_EQ(Database(path_).NumMatchedPairs(), 1u);
}

TEST_F(DatabaseTransactionTest, AThrowRollsBackEverythingAndTheDatabaseGoesOn) {
  Database database(path_);
  const camera_t camera_id =
      database.WriteCamera(Camera::Create(kInvalidCameraId, CameraModelId::kPinhole, 500, 64, 48));
  EXPECT_THROW(
      {
        DatabaseTransaction transaction(&database);
        database.WriteImageWithFeatures("a.png", camera_id, RandomKeypoints(5),
                                        RandomDescriptors(5));
        database.WriteMatches(1, 2, RandomMatches(3));
        throw std::runtime_error("a stage fails between two writes");
      },
      std::runtime_error);
  // Nothing of it was written, on this connection or another.
  EXPECT_EQ(database.NumImages(), 0u);
  EXPECT_EQ(database.NumMatchedPairs(), 0u);
  EXPECT_FALSE(database.ExistsKeypoints(1));
  EXPECT_EQ(Database(path_).NumImages(), 0u);
  // What was committed before it stays.
  EXPECT_EQ(database.NumCameras(), 1u);

  // The database is usable afterwards: a write on its own, and a new transaction.
  database.WriteMatches(3, 4, RandomMatches(2));
  {
    DatabaseTransaction transaction(&database);
    database.WriteMatches(5, 6, RandomMatches(2));
    transaction.Commit();
  }
  Database reader(path_);
  EXPECT_EQ(reader.NumMatchedPairs(), 2u);
  EXPECT_TRUE(reader.ExistsMatches(3, 4));
  EXPECT_TRUE(reader.ExistsMatches(5, 6));
}

TEST_F(DatabaseTransactionTest, AFailedWriteRollsBackTheEarlierWrites) {
  Database database(path_);
  database.WriteMatches(1, 2, RandomMatches(3));
  {
    DatabaseTransaction transaction(&database);
    database.WriteMatches(2, 3, RandomMatches(3));
    // The pair is stored already: SQLite refuses the row (InputError naming the file).
    EXPECT_THROW(database.WriteMatches(2, 1, RandomMatches(3)), InputError);
    // Left without Commit(), as a caller that does not catch leaves it.
  }
  EXPECT_FALSE(database.ExistsMatches(2, 3));
  EXPECT_EQ(Database(path_).NumMatchedPairs(), 1u);
}

TEST_F(DatabaseTransactionTest, AtomicWritesJoinAnOpenTransaction) {
  Database database(path_);
  const camera_t camera_id =
      database.WriteCamera(Camera::Create(kInvalidCameraId, CameraModelId::kPinhole, 500, 64, 48));
  const image_t kept = database.WriteImageWithFeatures("kept.png", camera_id, RandomKeypoints(3),
                                                       RandomDescriptors(3));
  {
    DatabaseTransaction transaction(&database);
    // Each would begin its own transaction; inside this one they join it, so rolling it back
    // undoes them too.
    database.WriteImageWithFeatures("new.png", camera_id, RandomKeypoints(4), RandomDescriptors(4));
    database.DeleteImage(kept);
    EXPECT_EQ(database.NumImages(), 1u);
  }
  EXPECT_EQ(database.NumImages(), 1u);
  EXPECT_TRUE(database.ExistsImage(kept));
  EXPECT_FALSE(database.ImageIdByName("new.png").has_value());
  EXPECT_EQ(database.NumKeypoints(kept), 3u);
}

}  // namespace
}  // namespace parallax
