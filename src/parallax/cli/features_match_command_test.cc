// End-to-end tests of `parallax features` and `parallax match`: the built binary runs as a
// subprocess (its path comes from PARALLAX_BINARY, set by CTest).
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "parallax/math/random.h"
#include "parallax/scene/database.h"
#include "parallax/util/file.h"
#include "parallax/util/test_dir.h"

namespace parallax {
namespace {

namespace fs = std::filesystem;

struct CommandResult {
  int exit_code = -1;
  std::string out;
  std::string err;
};

class FeaturesMatchCommandTest : public ::testing::Test {
 protected:
  void SetUp() override {
    const char* binary = std::getenv("PARALLAX_BINARY");
    if (binary == nullptr || !fs::exists(binary)) GTEST_SKIP() << "PARALLAX_BINARY not set";
    binary_ = binary;
    fs::create_directories(dir_ / "images");
  }

  CommandResult Run(const std::string& arguments) {
    const fs::path out_path = dir_ / "stdout.txt", err_path = dir_ / "stderr.txt";
    const std::string command = "'" + binary_ + "' " + arguments + " >'" + out_path.string() +
                                "' 2>'" + err_path.string() + "'";
    const int status = std::system(command.c_str());
    CommandResult result;
    result.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
    result.out = ReadFileToString(out_path);
    result.err = ReadFileToString(err_path);
    return result;
  }

  std::string binary_;
  const test::ScopedTestDir scoped_dir_{"parallax_features_match_test"};
  const fs::path dir_ = scoped_dir_.path();
};

// A textured image and views of it under small homographies: matchable, with exact geometry.
void WriteWarpedViews(const fs::path& dir, int num_views) {
  cv::Mat base(300, 400, CV_8UC3, cv::Scalar(120, 120, 120));
  for (int k = 0; k < 1500; ++k) {
    const cv::Point center(static_cast<int>(RandomUniformInteger(0, 399)),
                           static_cast<int>(RandomUniformInteger(0, 299)));
    const int level = static_cast<int>(RandomUniformInteger(0, 255));
    cv::circle(base, center, static_cast<int>(RandomUniformInteger(2, 10)),
               cv::Scalar(level, 255 - level, level), cv::FILLED);
  }
  for (int v = 0; v < num_views; ++v) {
    const double angle = 0.05 * v, scale = 1.0 - 0.03 * v;
    cv::Mat H =
        (cv::Mat_<double>(3, 3) << scale * std::cos(angle), -scale * std::sin(angle), 10.0 * v,
         scale * std::sin(angle), scale * std::cos(angle), -5.0 * v, 1e-5 * v, 0.0, 1.0);
    cv::Mat view;
    cv::warpPerspective(base, view, H, base.size(), cv::INTER_LINEAR, cv::BORDER_REFLECT);
    ASSERT_TRUE(cv::imwrite((dir / ("view" + std::to_string(v) + ".png")).string(), view));
  }
}

TEST_F(FeaturesMatchCommandTest, FeaturesThenMatchWithStats) {
  WriteWarpedViews(dir_ / "images", 3);
  const std::string database = (dir_ / "database.db").string();
  const CommandResult features =
      Run("features --images '" + (dir_ / "images").string() + "' --database '" + database +
          "' --max-features 1000 --threads 2");
  ASSERT_EQ(features.exit_code, 0) << features.err;
  EXPECT_NE(features.out.find("3 images, 3 extracted"), std::string::npos) << features.out;

  const CommandResult match = Run("match --database '" + database + "' --stats --threads 2");
  ASSERT_EQ(match.exit_code, 0) << match.err;
  EXPECT_NE(match.out.find("3 pairs, 3 matched"), std::string::npos) << match.out;
  // Per image keypoints and per pair counts: 3 images and 3 pairs under two header lines.
  const std::vector<std::string> lines = SplitLines(match.out);
  size_t image_lines = 0, pair_lines = 0;
  for (const std::string& line : lines) {
    if (line.find("view") == std::string::npos) continue;
    (line.find("view", line.find("view") + 1) != std::string::npos ? pair_lines : image_lines)++;
  }
  EXPECT_EQ(image_lines, 3u) << match.out;
  EXPECT_EQ(pair_lines, 3u) << match.out;
  {
    Database db(database);
    EXPECT_EQ(db.NumVerifiedPairs(), 3u);
    EXPECT_EQ(db.ReadTwoViewGeometryNumInliers().size(), 3u);
    for (const auto& [pair_id, num_inliers] : db.ReadTwoViewGeometryNumInliers()) {
      EXPECT_GT(num_inliers, 50) << match.out;
    }
  }

  // Rerunning both resumes: nothing left to do.
  const CommandResult features_again = Run("features --images '" + (dir_ / "images").string() +
                                           "' --database '" + database + "' -q");
  ASSERT_EQ(features_again.exit_code, 0) << features_again.err;
  EXPECT_NE(features_again.out.find("3 already in the database"), std::string::npos);
  EXPECT_TRUE(features_again.err.empty()) << features_again.err;  // -q: no progress lines.
  const CommandResult match_again =
      Run("match --database '" + database + "' --pairs sequential --overlap 1");
  ASSERT_EQ(match_again.exit_code, 0) << match_again.err;
  EXPECT_NE(match_again.out.find("2 pairs, 0 matched, 2 already verified"), std::string::npos)
      << match_again.out;
}

TEST_F(FeaturesMatchCommandTest, BadInputGivesOneLineErrors) {
  const std::string missing = (dir_ / "no_such_folder").string();
  const CommandResult no_images =
      Run("features --images '" + missing + "' --database '" + (dir_ / "a.db").string() + "'");
  EXPECT_EQ(no_images.exit_code, 1);
  EXPECT_EQ(no_images.err.rfind("error: " + missing, 0), 0u) << no_images.err;

  const fs::path not_a_database = dir_ / "text.db";
  std::ofstream(not_a_database) << "plain text, long enough to be read as a (bad) header......\n";
  const CommandResult bad_database = Run("match --database '" + not_a_database.string() + "'");
  EXPECT_EQ(bad_database.exit_code, 1);
  EXPECT_EQ(bad_database.err.rfind("error: " + not_a_database.string(), 0), 0u) << bad_database.err;
  EXPECT_EQ(SplitLines(bad_database.err).size(), 1u) << bad_database.err;

  const CommandResult no_database = Run("match --database '" + (dir_ / "none.db").string() + "'");
  EXPECT_EQ(no_database.exit_code, 1);
  EXPECT_FALSE(fs::exists(dir_ / "none.db"));

  const CommandResult bad_mode =
      Run("match --database '" + (dir_ / "a.db").string() + "' --pairs vocab_tree");
  EXPECT_NE(bad_mode.exit_code, 0);

  // A confidence of 1 would ask RANSAC for infinitely many trials: refused as an option error.
  for (const char* confidence : {"1", "0.2"}) {
    const CommandResult bad_confidence =
        Run("match --database '" + (dir_ / "a.db").string() + "' --confidence " + confidence);
    EXPECT_NE(bad_confidence.exit_code, 0) << confidence;
    EXPECT_GE(bad_confidence.exit_code, 0) << "killed by a signal: " << bad_confidence.err;
    EXPECT_NE(bad_confidence.err.find("--confidence"), std::string::npos) << bad_confidence.err;
  }

  const fs::path bad_k = dir_ / "K.txt";
  std::ofstream(bad_k) << "1 2 3\n";
  WriteWarpedViews(dir_ / "images", 1);
  const CommandResult bad_intrinsics =
      Run("features --images '" + (dir_ / "images").string() + "' --database '" +
          (dir_ / "b.db").string() + "' --intrinsics '" + bad_k.string() + "'");
  EXPECT_EQ(bad_intrinsics.exit_code, 1);
  EXPECT_EQ(bad_intrinsics.err.rfind("error: " + bad_k.string(), 0), 0u) << bad_intrinsics.err;
}

// templeRing, first 4 views (skipped without the data set).
TEST_F(FeaturesMatchCommandTest, TempleRingFirstViews) {
  const fs::path temple = DataRoot() / "templeRing" / "images";
  if (!fs::exists(temple / "templeR0001.png")) GTEST_SKIP() << "no templeRing at " << temple;
  for (int i = 1; i <= 4; ++i) {
    const std::string name = "templeR000" + std::to_string(i) + ".png";
    fs::create_symlink(temple / name, dir_ / "images" / name);
  }
  const std::string database = (dir_ / "database.db").string();
  const CommandResult features = Run("features --images '" + (dir_ / "images").string() +
                                     "' --database '" + database + "' --threads 2");
  ASSERT_EQ(features.exit_code, 0) << features.err;
  const CommandResult match = Run("match --database '" + database + "' --threads 2");
  ASSERT_EQ(match.exit_code, 0) << match.err;
  Database db(database);
  EXPECT_EQ(db.NumImages(), 4u);
  EXPECT_EQ(db.NumCameras(), 1u);
  // Neighbouring views (about 8 degrees apart) verify with many inliers.
  const auto num_inliers = db.ReadTwoViewGeometryNumInliers();
  int adjacent_verified = 0;
  for (const auto& [pair_id, count] : num_inliers) {
    const auto [id1, id2] = PairIdToImagePair(pair_id);
    if (id2 == id1 + 1 && count >= 100) ++adjacent_verified;
  }
  EXPECT_EQ(adjacent_verified, 3) << match.out;
}

}  // namespace
}  // namespace parallax
