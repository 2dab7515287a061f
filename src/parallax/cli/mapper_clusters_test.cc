// Partitioned mapping from the command line (issue 15): `parallax mapper --mapper
// hierarchical` writes its clusters as files and maps the whole scene from them, and
// `parallax mapper --cluster FILE` maps one cluster alone, the unit of work a distributed run
// hands out. Runs on a synthetic database with exact ground truth.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include "parallax/cli/cli_test_inputs.h"
#include "parallax/cli/cli_test_process.h"
#include "parallax/scene/colmap_io.h"
#include "parallax/scene/database.h"
#include "parallax/scene/synthetic_dataset.h"
#include "parallax/sfm/image_cluster.h"
#include "parallax/util/test_dir.h"

namespace parallax {
namespace {

namespace fs = std::filesystem;

class MapperClustersTest : public ::testing::Test {
 protected:
  void SetUp() override {
    if (test::ParallaxBinary().empty()) GTEST_SKIP() << "PARALLAX_BINARY not set";
    SyntheticDatasetOptions options;
    options.layout = SyntheticDatasetOptions::Layout::kSequence;
    options.num_images = 40;
    options.num_points3D = 4000;
    options.min_track_length = 3;
    options.point2D_noise_stddev = 0.3;
    options.seed = 9;
    SynthesizeDataset(options, &truth_);
    Database database(database_path_);
    WriteSyntheticDatabase(truth_, &database);
  }

  std::vector<std::string> MapperArguments(const fs::path& output) const {
    return {"mapper",      "--database", database_path_.string(), "--image-path",
            dir_.string(), "--output",   output.string(),         "--ba-threads",
            "1",           "-q"};
  }

  const test::ScopedTestDir scoped_dir_{"parallax_mapper_clusters_test"};
  const fs::path dir_ = scoped_dir_.path();
  const fs::path database_path_ = dir_ / "database.db";
  Reconstruction truth_;
};

TEST_F(MapperClustersTest, HierarchicalRunWritesClustersAndMapsEveryImage) {
  std::vector<std::string> arguments = MapperArguments(dir_ / "out");
  for (const char* argument :
       {"--mapper", "hierarchical", "--cluster-max-images", "15", "--cluster-overlap", "4"}) {
    arguments.push_back(argument);
  }
  const test::ProcessResult result = test::RunParallax(arguments, dir_, 300);
  ASSERT_TRUE(result.ExitedWith(0)) << result.err;

  std::vector<fs::path> cluster_files;
  for (const auto& entry : fs::directory_iterator(dir_ / "out" / "clusters"))
    cluster_files.push_back(entry.path());
  ASSERT_GE(cluster_files.size(), 2u);
  for (const fs::path& file : cluster_files) {
    const ImageCluster cluster = ReadImageCluster(file);
    // At most 15 of its own, and 4 from each other cluster it borders.
    EXPECT_LE(cluster.image_names.size(), 15u + 4u * (cluster_files.size() - 1)) << file;
    EXPECT_FALSE(cluster.pairs.empty()) << file;
  }
  const Reconstruction model = ReadReconstruction(dir_ / "out" / "sparse" / "0");
  EXPECT_EQ(model.NumRegImages(), truth_.NumImages());
  const nlohmann::json summary =
      nlohmann::json::parse(ReadFileToString(dir_ / "out" / "summary.json"));
  EXPECT_EQ(summary["mapper"]["hierarchical"]["clusters"].size(), cluster_files.size());

  // One cluster alone: its images, no others.
  const fs::path cluster_file = dir_ / "out" / "clusters" / "cluster-0.txt";
  const ImageCluster cluster = ReadImageCluster(cluster_file);
  std::vector<std::string> cluster_arguments = MapperArguments(dir_ / "cluster-0");
  cluster_arguments.push_back("--cluster");
  cluster_arguments.push_back(cluster_file.string());
  const test::ProcessResult cluster_result = test::RunParallax(cluster_arguments, dir_, 300);
  ASSERT_TRUE(cluster_result.ExitedWith(0)) << cluster_result.err;
  const Reconstruction cluster_model = ReadReconstruction(dir_ / "cluster-0" / "sparse" / "0");
  EXPECT_EQ(cluster_model.NumRegImages(), cluster.image_names.size());
  const std::set<std::string> names(cluster.image_names.begin(), cluster.image_names.end());
  for (const image_t image_id : cluster_model.RegImageIds()) {
    EXPECT_TRUE(names.count(cluster_model.GetImage(image_id).name))
        << cluster_model.GetImage(image_id).name;
  }
}

// --ba-loss reaches the final adjustment only; the log names each adjustment's loss.
TEST_F(MapperClustersTest, BaLossFlagSetsTheFinalAdjustmentsLoss) {
  std::vector<std::string> arguments = MapperArguments(dir_ / "huber");
  arguments.back() = "-v";
  arguments.push_back("--ba-loss");
  arguments.push_back("huber");
  const test::ProcessResult result = test::RunParallax(arguments, dir_, 300);
  ASSERT_TRUE(result.ExitedWith(0)) << result.err;
  size_t num_huber = 0, num_squared = 0, num_cauchy = 0;
  for (const std::string& line : test::LinesStartingWith(result.err, "debug: mapper: BA over")) {
    num_huber += line.find("huber loss") != std::string::npos;
    num_squared += line.find("squared loss") != std::string::npos;
    num_cauchy += line.find("cauchy loss") != std::string::npos;
  }
  EXPECT_GE(num_huber, 1u);
  EXPECT_GE(num_squared, 1u);
  EXPECT_EQ(num_cauchy, 0u);
}

TEST_F(MapperClustersTest, ClusterFileWithAnUnknownImageIsAOneLineError) {
  const fs::path cluster_file = dir_ / "cluster.txt";
  WriteTextFileAtomically(cluster_file, "image image0001.png\nimage holiday.jpg\n");
  std::vector<std::string> arguments = MapperArguments(dir_ / "out");
  arguments.push_back("--cluster");
  arguments.push_back(cluster_file.string());
  test::ExpectFailsWithOneLineError(test::RunParallax(arguments, dir_), cluster_file.string(),
                                    "image 'holiday.jpg' is not in the database");
  EXPECT_FALSE(fs::exists(dir_ / "out" / "sparse"));

  WriteTextFileAtomically(cluster_file, "image image0001.png\npair image0001.png image0002.png\n");
  test::ExpectFailsWithOneLineError(test::RunParallax(arguments, dir_),
                                    cluster_file.string() + ": line 2",
                                    "pair needs two image names separated by a tab");
  test::ExpectFailsWithOneLineError(
      test::RunParallax(
          {"mapper", "--database", database_path_.string(), "--image-path", dir_.string(),
           "--output", (dir_ / "out").string(), "--cluster", (dir_ / "missing.txt").string()},
          dir_),
      (dir_ / "missing.txt").string(), "");
}

}  // namespace
}  // namespace parallax
