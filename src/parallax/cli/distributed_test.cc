// Distributed runs (issue 19): `mpirun --oversubscribe -np 3 parallax reconstruct` on a small
// synthetic aerial survey, over loopback on this machine, gives the database of a one-process
// run (keypoints, descriptors, matches and verified geometries identical) and a model within
// 1e-3 of the scene scale of its model; a rank killed during matching loses nothing stored,
// and the rerun matches only what no shard held. Skipped where mpirun is missing or Parallax
// was built without MPI.
#include <gtest/gtest.h>
#include <signal.h>
#include <unistd.h>

#include <nlohmann/json.hpp>
#include <set>

#include "parallax/cli/cli_test_inputs.h"
#include "parallax/cli/cli_test_process.h"
#include "parallax/pipeline/feature_shards.h"
#include "parallax/scene/database.h"

namespace parallax {
namespace {

namespace fs = std::filesystem;

using test::ChildProcess;
using test::ProcessResult;

constexpr int kNumViews = 20;
constexpr int kNumRanks = 3;
constexpr size_t kNumPairs = kNumViews * (kNumViews - 1) / 2;

std::string MpiRunPath() {
  for (const char* path : {"/usr/bin/mpirun", "/usr/local/bin/mpirun"}) {
    if (fs::exists(path)) return path;
  }
  return "";
}

// Every run matches approximately, as large collections are matched: each rank trains the
// descriptor cells itself, and they must be the same cells for the ranks' matches to be the
// one-process run's.
const std::string kApproximateMatching = "--approximate-matching=on";

// mpirun -np 3 parallax reconstruct ... (one thread per rank: three ranks share two cores).
std::vector<std::string> MpiReconstruct(const fs::path& images, const fs::path& out,
                                        const std::vector<std::string>& extra = {}) {
  std::vector<std::string> argv = {MpiRunPath(), "--oversubscribe", "-np",
                                   std::to_string(kNumRanks)};
  // CI runs as root, which OpenMPI refuses unless told.
  if (geteuid() == 0) argv.push_back("--allow-run-as-root");
  for (const std::string& arg :
       {test::ParallaxBinary(), std::string("reconstruct"), std::string("--images"),
        images.string(), std::string("--output"), out.string(), std::string("--threads"),
        std::string("1"), kApproximateMatching}) {
    argv.push_back(arg);
  }
  argv.insert(argv.end(), extra.begin(), extra.end());
  return argv;
}

ProcessResult RunToEnd(const std::vector<std::string>& argv, const fs::path& log_dir) {
  ChildProcess child(argv, log_dir / "stdout.txt", log_dir / "stderr.txt");
  return child.Wait(300);
}

std::set<image_pair_t> StoredPairIds(const fs::path& database) {
  std::set<image_pair_t> ids;
  if (!fs::exists(database)) return ids;
  const Database db(database);
  for (const auto& [pair_id, geometry] : db.ReadTwoViewGeometries()) ids.insert(pair_id);
  return ids;
}

// Pairs whose geometry the run's database or one of its pair shards holds.
std::set<image_pair_t> PairsStoredAnywhere(const fs::path& out) {
  std::set<image_pair_t> ids = StoredPairIds(out / "database.db");
  for (const fs::path& shard : ListShardDatabases(out / "shards" / "pairs")) {
    const std::set<image_pair_t> in_shard = StoredPairIds(shard);
    ids.insert(in_shard.begin(), in_shard.end());
  }
  return ids;
}

// Every table a later stage reads, compared row by row.
void ExpectSameDatabase(const fs::path& expected_path, const fs::path& actual_path) {
  const Database expected(expected_path), actual(actual_path);
  const std::vector<Image> expected_images = expected.ReadAllImages();
  const std::vector<Image> actual_images = actual.ReadAllImages();
  ASSERT_EQ(expected_images.size(), actual_images.size());
  for (size_t k = 0; k < expected_images.size(); ++k) {
    const image_t image_id = expected_images[k].image_id;
    EXPECT_EQ(actual_images[k].image_id, image_id);
    EXPECT_EQ(actual_images[k].name, expected_images[k].name);
    EXPECT_EQ(actual_images[k].camera_id, expected_images[k].camera_id);
    const FeatureKeypoints expected_keypoints = expected.ReadKeypoints(image_id);
    const FeatureKeypoints actual_keypoints = actual.ReadKeypoints(image_id);
    ASSERT_EQ(actual_keypoints.size(), expected_keypoints.size());
    for (size_t i = 0; i < expected_keypoints.size(); ++i) {
      const FeatureKeypoint& a = actual_keypoints[i];
      const FeatureKeypoint& e = expected_keypoints[i];
      ASSERT_TRUE(a.x == e.x && a.y == e.y && a.a11 == e.a11 && a.a12 == e.a12 && a.a21 == e.a21 &&
                  a.a22 == e.a22)
          << image_id << " keypoint " << i;
    }
    EXPECT_TRUE(actual.ReadDescriptors(image_id) == expected.ReadDescriptors(image_id)) << image_id;
    // The keypoints' colours come through the shards too (the model's colours need them).
    const std::optional<KeypointColors> colors = actual.ReadKeypointColors(image_id);
    ASSERT_TRUE(colors.has_value()) << image_id;
    EXPECT_EQ(colors, expected.ReadKeypointColors(image_id)) << image_id;
  }
  EXPECT_EQ(actual.ReadAllCameras().size(), expected.ReadAllCameras().size());
  const auto expected_geometries = expected.ReadTwoViewGeometries();
  const auto actual_geometries = actual.ReadTwoViewGeometries();
  ASSERT_EQ(actual_geometries.size(), expected_geometries.size());
  for (size_t k = 0; k < expected_geometries.size(); ++k) {
    const auto& [pair_id, geometry] = expected_geometries[k];
    EXPECT_EQ(actual_geometries[k].first, pair_id);
    EXPECT_EQ(actual_geometries[k].second.config, geometry.config) << pair_id;
    EXPECT_EQ(actual_geometries[k].second.inlier_matches, geometry.inlier_matches) << pair_id;
    EXPECT_EQ(actual_geometries[k].second.E, geometry.E) << pair_id;
    EXPECT_EQ(actual_geometries[k].second.F, geometry.F) << pair_id;
    EXPECT_EQ(actual_geometries[k].second.H, geometry.H) << pair_id;
  }
  EXPECT_EQ(actual.ReadAllMatches(), expected.ReadAllMatches());
}

class DistributedTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    if (test::ParallaxBinary().empty() || MpiRunPath().empty()) return;
    scene_ = new test::ScopedTestDir("parallax_distributed_scene");
    const ProcessResult version = test::RunParallax({"version"}, scene_->path());
    if (version.out.find("yes, MPI") == std::string::npos) return;
    built_with_mpi_ = true;
    test::RenderSyntheticScene(scene_->path() / "images", kNumViews, 480, 360, scene_->path(),
                               "aerial");
    // The one-process run every distributed run is compared with.
    const ProcessResult result = test::RunParallax(
        {"reconstruct", "--images", (scene_->path() / "images").string(), "--output",
         (scene_->path() / "reference").string(), "--threads", "2", kApproximateMatching, "-q"},
        scene_->path(), 300);
    ASSERT_TRUE(result.ExitedWith(0)) << result.err;
  }
  static void TearDownTestSuite() {
    delete scene_;
    scene_ = nullptr;
  }
  void SetUp() override {
    if (test::ParallaxBinary().empty()) GTEST_SKIP() << "PARALLAX_BINARY not set";
    if (MpiRunPath().empty()) GTEST_SKIP() << "mpirun not installed";
    if (!built_with_mpi_) GTEST_SKIP() << "parallax built without MPI";
  }
  static fs::path Images() { return scene_->path() / "images"; }
  static fs::path Reference() { return scene_->path() / "reference"; }

  const test::ScopedTestDir dir_{"parallax_distributed"};
  static test::ScopedTestDir* scene_;
  static bool built_with_mpi_;
};

test::ScopedTestDir* DistributedTest::scene_ = nullptr;
bool DistributedTest::built_with_mpi_ = false;

TEST_F(DistributedTest, ThreeRanksGiveTheDatabaseAndModelOfOneProcess) {
  const fs::path out = dir_.path() / "out";
  const ProcessResult result = RunToEnd(MpiReconstruct(Images(), out), dir_.path());
  ASSERT_TRUE(result.ExitedWith(0)) << result.err;
  // The coordinator alone reports.
  EXPECT_NE(result.out.find("model 0: 20/20 images registered"), std::string::npos) << result.out;
  EXPECT_NE(result.err.find("distributed run: 3 ranks"), std::string::npos) << result.err;
  // What it did alone while the others waited, choosing the pairs among it.
  EXPECT_NE(result.err.find("rank 0 alone: storing the features"), std::string::npos) << result.err;
  EXPECT_NE(result.err.find("choosing pairs"), std::string::npos) << result.err;

  ExpectSameDatabase(Reference() / "database.db", out / "database.db");
  // Every rank extracted a share into its own shard, and the shards hold every image once.
  const std::vector<fs::path> shards = ListShardDatabases(out / "shards" / "features");
  ASSERT_EQ(shards.size(), static_cast<size_t>(kNumRanks));
  size_t images_in_shards = 0;
  for (const fs::path& shard : shards) {
    const size_t count = Database(shard).NumImages();
    EXPECT_GT(count, 0u) << shard;
    images_in_shards += count;
  }
  EXPECT_EQ(images_in_shards, static_cast<size_t>(kNumViews));
  EXPECT_EQ(ListShardDatabases(out / "shards" / "pairs").size(), static_cast<size_t>(kNumRanks));

  // The model, aligned to the one-process model, within 1e-3 of the scene scale.
  const ProcessResult evaluation =
      test::RunParallax({"evaluate", (out / "sparse" / "0").string(), "--gt",
                         (Reference() / "sparse" / "0").string(), "--json"},
                        dir_.path());
  ASSERT_TRUE(evaluation.ExitedWith(0)) << evaluation.err;
  const nlohmann::json metrics = nlohmann::json::parse(evaluation.out);
  EXPECT_EQ(metrics["images_registered"], kNumViews);
  EXPECT_LT(metrics["center_error_relative"]["max"].get<double>(), 1e-3);
  EXPECT_LT(metrics["rotation_error_deg"]["max"].get<double>(), 0.05);
}

TEST_F(DistributedTest, ARankKilledDuringMatchingLosesNothingStored) {
  // Small batches, so that ranks store pairs while others still match. A run that got past
  // matching before the kill is repeated.
  for (int attempt = 0; attempt < 3; ++attempt) {
    const fs::path out = dir_.path() / ("attempt-" + std::to_string(attempt));
    ChildProcess job(MpiReconstruct(Images(), out, {"--match-batch-size", "2", "-q"}),
                     dir_.path() / "killed_out.txt", dir_.path() / "killed_err.txt");
    bool killed = false;
    while (job.Running() && !killed) {
      size_t in_shards = 0;
      for (const fs::path& shard : ListShardDatabases(out / "shards" / "pairs")) {
        in_shards +=
            std::stoul(test::QueryFirstValue(shard, "SELECT COUNT(*) FROM two_view_geometries;")
                           .value_or("0"));
      }
      if (in_shards >= 4 && in_shards < kNumPairs / 2) {
        // One rank (a process running parallax on this output folder) dies at once.
        for (const auto& entry : fs::directory_iterator("/proc")) {
          const pid_t pid = static_cast<pid_t>(std::atoi(entry.path().filename().c_str()));
          if (pid <= 0 || pid == job.Pid()) continue;
          std::error_code error;
          if (!fs::exists(entry.path() / "cmdline", error)) continue;
          std::string cmdline = test::ReadBytes(entry.path() / "cmdline");
          std::replace(cmdline.begin(), cmdline.end(), '\0', ' ');
          if (cmdline.rfind(test::ParallaxBinary() + " reconstruct", 0) == 0 &&
              cmdline.find(out.string()) != std::string::npos) {
            kill(pid, SIGKILL);
            killed = true;
            break;
          }
        }
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(2));
    }
    const ProcessResult first = job.Wait(300);
    if (!killed) continue;
    EXPECT_FALSE(first.ExitedWith(0)) << "the job went on without a rank";

    const std::set<image_pair_t> stored = PairsStoredAnywhere(out);
    ASSERT_GT(stored.size(), 0u);
    ASSERT_LT(stored.size(), kNumPairs);
    const ProcessResult rerun = RunToEnd(MpiReconstruct(Images(), out, {"-q"}), dir_.path());
    ASSERT_TRUE(rerun.ExitedWith(0)) << rerun.err;
    const nlohmann::json summary = nlohmann::json::parse(test::ReadBytes(out / "summary.json"));
    // Every image's features were stored before matching began, and every pair a shard held
    // was taken as it was: only the others were matched.
    EXPECT_EQ(summary["features"]["images_extracted"], 0);
    EXPECT_EQ(summary["matching"]["pairs_skipped_already_stored"], stored.size());
    EXPECT_EQ(summary["matching"]["pairs_matched"], kNumPairs - stored.size());
    // No --mapper: the run chose the hierarchical mapper, and says why.
    EXPECT_EQ(summary["mapper"]["type"], "hierarchical");
    EXPECT_NE(summary["mapper"]["type_reason"].get<std::string>().find("distributed"),
              std::string::npos);
    ExpectSameDatabase(Reference() / "database.db", out / "database.db");
    return;
  }
  FAIL() << "no attempt was killed during matching";
}

}  // namespace
}  // namespace parallax
