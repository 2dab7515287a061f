// The faults users cause (issue 22), end to end on the command line: a photo edited or
// replaced between runs, a photo removed, a second run on the same output or database, and a
// file-size limit reached in the middle of a run. Ctrl-C and SIGTERM are in resume_test.cc.
#include <gtest/gtest.h>
#include <unistd.h>

#include <nlohmann/json.hpp>

#include "parallax/cli/cli_test_inputs.h"
#include "parallax/cli/cli_test_process.h"
#include "parallax/scene/database.h"
#include "parallax/util/content_hash.h"
#include "parallax/util/run_lock.h"

namespace parallax {
namespace {

namespace fs = std::filesystem;

using test::ProcessResult;

constexpr int kNumViews = 8;

// PRAGMA integrity_check of a database file: "ok" for a valid one.
std::string IntegrityCheck(const fs::path& database) {
  return test::QueryFirstValue(database, "PRAGMA integrity_check;").value_or("cannot open");
}

class UserFaultsTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    if (test::ParallaxBinary().empty()) return;
    scene_ = new test::ScopedTestDir("parallax_user_faults_scene");
    test::RenderSyntheticScene(scene_->path() / "images", kNumViews, 480, 360, scene_->path(),
                               "sequence");
  }
  static void TearDownTestSuite() {
    delete scene_;
    scene_ = nullptr;
  }
  void SetUp() override {
    if (test::ParallaxBinary().empty()) GTEST_SKIP() << "PARALLAX_BINARY not set";
    ASSERT_NE(scene_, nullptr);
    dir_ = std::make_unique<test::ScopedTestDir>("parallax_user_faults");
    images_ = dir_->path() / "images";
    fs::copy(scene_->path() / "images", images_);
    out_ = dir_->path() / "out";
  }

  std::vector<std::string> Reconstruct() const {
    return {"reconstruct", "--images", images_.string(), "--output", out_.string(),
            "--threads",   "2",        "--seed",         "5"};
  }
  ProcessResult Run(const std::vector<std::string>& arguments) const {
    return test::RunParallax(arguments, dir_->path(), 300);
  }
  nlohmann::json Summary() const {
    return nlohmann::json::parse(test::ReadBytes(out_ / "summary.json"));
  }

  static test::ScopedTestDir* scene_;
  std::unique_ptr<test::ScopedTestDir> dir_;
  fs::path images_, out_;
};

test::ScopedTestDir* UserFaultsTest::scene_ = nullptr;

TEST_F(UserFaultsTest, ReplacedPhotoIsExtractedAgainWithItsPairs) {
  ASSERT_TRUE(Run(Reconstruct()).ExitedWith(0));
  // Another view under the same name, as a user who swaps or re-exports a photo.
  fs::copy_file(images_ / "view_0007.png", images_ / "view_0003.png",
                fs::copy_options::overwrite_existing);
  const ProcessResult rerun = Run(Reconstruct());
  ASSERT_TRUE(rerun.ExitedWith(0)) << rerun.err;
  test::ExpectOneWarningNaming(rerun.err, images_ / "view_0003.png",
                               "changed since its features were stored");
  const nlohmann::json summary = Summary();
  EXPECT_EQ(summary["features"]["images_extracted"], 1);
  EXPECT_EQ(summary["features"]["images_skipped_already_stored"], kNumViews - 1);
  // Only the pairs of the new photo are matched again (exhaustive: one with each other image).
  EXPECT_EQ(summary["matching"]["pairs_matched"], kNumViews - 1);
  EXPECT_EQ(summary["matching"]["pairs_skipped_already_stored"],
            (kNumViews - 1) * (kNumViews - 2) / 2);
  Database database(out_ / "database.db");
  const auto image_id = database.ImageIdByName("view_0003.png");
  ASSERT_TRUE(image_id.has_value());
  const auto fingerprint = database.ReadImageFileFingerprint(*image_id);
  ASSERT_TRUE(fingerprint.has_value());
  EXPECT_EQ(fingerprint->content_hash, HashFile(images_ / "view_0003.png"));
  EXPECT_EQ(fingerprint->size, fs::file_size(images_ / "view_0003.png"));
}

TEST_F(UserFaultsTest, TouchedPhotoWithTheSameContentIsNotExtractedAgain) {
  ASSERT_TRUE(Run(Reconstruct()).ExitedWith(0));
  fs::last_write_time(images_ / "view_0002.png",
                      fs::last_write_time(images_ / "view_0002.png") + std::chrono::hours(1));
  const ProcessResult rerun = Run(Reconstruct());
  ASSERT_TRUE(rerun.ExitedWith(0)) << rerun.err;
  EXPECT_EQ(rerun.err.find("changed since"), std::string::npos) << rerun.err;
  EXPECT_EQ(Summary()["features"]["images_extracted"], 0);
  EXPECT_EQ(Summary()["matching"]["pairs_matched"], 0);
}

TEST_F(UserFaultsTest, RemovedPhotoIsReportedAndLeftOut) {
  ASSERT_TRUE(Run(Reconstruct()).ExitedWith(0));
  fs::remove(images_ / "view_0008.png");
  const ProcessResult rerun = Run(Reconstruct());
  ASSERT_TRUE(rerun.ExitedWith(0)) << rerun.err;
  test::ExpectOneWarningNaming(rerun.err, images_ / "view_0008.png",
                               "no longer an image of the folder");
  EXPECT_EQ(Summary()["images_registered"], kNumViews - 1);
  Database database(out_ / "database.db");
  EXPECT_FALSE(database.ImageIdByName("view_0008.png").has_value());
  EXPECT_EQ(database.NumImages(), static_cast<size_t>(kNumViews - 1));
}

// A second run while another holds the output folder (here this test process, which takes
// the same flock a running parallax holds) stops before it writes anything, in one line that
// names the folder and the holder.
TEST_F(UserFaultsTest, SecondRunOnTheSameOutputStopsBeforeTouchingAnything) {
  fs::create_directories(out_);
  const RunLock held(OutputLockPath(out_), "test");
  const ProcessResult second = Run(Reconstruct());
  test::ExpectFailsWithOneLineError(second,
                                    out_.string() + ": in use by another parallax run (process " +
                                        std::to_string(getpid()) +
                                        "); wait for it to finish or stop it",
                                    "then run this command again");
  EXPECT_EQ(std::count(second.err.begin(), second.err.end(), '\n'), 1) << second.err;
  EXPECT_FALSE(fs::exists(out_ / "database.db"));
}

TEST_F(UserFaultsTest, SecondRunOnTheSameDatabaseStopsBeforeTouchingIt) {
  ASSERT_TRUE(Run(Reconstruct()).ExitedWith(0));
  const fs::path database = out_ / "database.db";
  const std::string before = test::ReadBytes(database);
  const RunLock held(DatabaseLockPath(database), "test");
  for (const std::vector<std::string>& command :
       {std::vector<std::string>{"features", "--images", images_.string(), "--database",
                                 database.string()},
        std::vector<std::string>{"match", "--database", database.string()},
        std::vector<std::string>{"reconstruct", "--images", images_.string(), "--output",
                                 (dir_->path() / "other").string(), "--database",
                                 database.string()}}) {
    SCOPED_TRACE(command[0]);
    test::ExpectFailsWithOneLineError(Run(command),
                                      database.string() + ": in use by another parallax run",
                                      "wait for it to finish or stop it");
  }
  EXPECT_TRUE(test::ReadBytes(database) == before);
}

// A file-size limit (ulimit -f, as a full disk) reached while the database grows: one line
// naming the database, a valid database, and the same command without the limit resumes.
TEST_F(UserFaultsTest, FileSizeLimitDuringExtractionLeavesAValidDatabase) {
  const ProcessResult limited =
      test::RunParallaxAfter("ulimit -f 400", Reconstruct(), dir_->path());
  test::ExpectFailsWithOneLineError(limited, (out_ / "database.db").string(),
                                    "is the disk full, or a file-size limit reached?");
  test::ExpectNoPartialOutput(out_);
  EXPECT_EQ(IntegrityCheck(out_ / "database.db"), "ok");
  size_t stored = 0;
  {
    Database database(out_ / "database.db");
    stored = database.NumImages();
  }
  EXPECT_LT(stored, static_cast<size_t>(kNumViews));
  const ProcessResult rerun = Run(Reconstruct());
  ASSERT_TRUE(rerun.ExitedWith(0)) << rerun.err;
  EXPECT_EQ(Summary()["features"]["images_skipped_already_stored"], stored);
  EXPECT_EQ(Summary()["images_registered"], kNumViews);
}

// The limit reached while the model is written: one line naming the file, and the model of the
// earlier run is still there whole (outputs are replaced as a whole, or not at all).
TEST_F(UserFaultsTest, FileSizeLimitWhileWritingTheModelKeepsTheEarlierModel) {
  ASSERT_TRUE(Run(Reconstruct()).ExitedWith(0));
  const std::string points_before = test::ReadBytes(out_ / "sparse" / "0" / "points3D.bin");
  const ProcessResult limited =
      test::RunParallaxAfter("ulimit -f 100", Reconstruct(), dir_->path());
  // 100 KB: the database opens and needs no write; a model file is the first to pass it.
  test::ExpectFailsWithOneLineError(limited, (out_ / "sparse").string(), "write failed");
  EXPECT_TRUE(test::ReadBytes(out_ / "sparse" / "0" / "points3D.bin") == points_before);
  test::ExpectNoTemporaryFiles(out_);
  EXPECT_EQ(IntegrityCheck(out_ / "database.db"), "ok");
}

}  // namespace
}  // namespace parallax
