// Determinism (issue 8): two `parallax reconstruct` runs with the same images, options and
// --seed give byte-identical models, although the threads of extraction and matching finish
// their work in a different order from run to run. With --ba-threads 1 that holds for either
// bundle adjuster; Parallax's dense Schur LM (up to 150 images) also with more BA threads,
// since it sums one partial system per thread in a fixed order. Ceres' threaded Schur
// elimination adds its blocks in arrival order (the command-line help says so).
#include <gtest/gtest.h>

#include "parallax/cli/cli_test_inputs.h"
#include "parallax/cli/cli_test_process.h"
#include "parallax/scene/database.h"

namespace parallax {
namespace {

namespace fs = std::filesystem;

using test::ProcessResult;

class DeterminismTest : public ::testing::Test {
 protected:
  void SetUp() override {
    if (test::ParallaxBinary().empty()) GTEST_SKIP() << "PARALLAX_BINARY not set";
    dir_ = std::make_unique<test::ScopedTestDir>("parallax_determinism");
  }

  // Runs reconstruct into `out`; fails the test when it does not succeed.
  // Returns the run's stderr (the log; -v adds the debug lines).
  std::string Reconstruct(const fs::path& images, const fs::path& out, const std::string& seed,
                          const std::string& threads, const std::string& ba_threads = "1",
                          const std::string& ba_solver = "auto",
                          const std::string& verbosity = "-q") {
    const ProcessResult result = test::RunParallax(
        {"reconstruct", "--images", images.string(), "--output", out.string(), "--threads", threads,
         "--ba-threads", ba_threads, "--ba-solver", ba_solver, "--seed", seed, verbosity},
        dir_->path(), 300);
    EXPECT_TRUE(result.ExitedWith(0)) << result.err;
    return result.err;
  }

  // Every model file of run `a` is byte for byte the one of run `b`.
  void ExpectIdenticalModels(const std::string& a, const std::string& b) {
    for (const char* file : {"cameras.txt", "images.txt", "points3D.txt", "cameras.bin",
                             "images.bin", "points3D.bin"}) {
      const fs::path path_a = dir_->path() / a / "sparse" / "0" / file;
      const fs::path path_b = dir_->path() / b / "sparse" / "0" / file;
      ASSERT_TRUE(fs::exists(path_a)) << path_a;
      ASSERT_TRUE(fs::exists(path_b)) << path_b;
      // EXPECT_TRUE rather than EXPECT_EQ: the models are long.
      EXPECT_TRUE(test::ReadBytes(path_a) == test::ReadBytes(path_b)) << file << " differs";
    }
    EXPECT_TRUE(test::ReadBytes(dir_->path() / a / "points.ply") ==
                test::ReadBytes(dir_->path() / b / "points.ply"));
  }

  std::unique_ptr<test::ScopedTestDir> dir_;
};

TEST_F(DeterminismTest, SameInputsOptionsAndSeedGiveIdenticalModels) {
  const fs::path images = dir_->path() / "images";
  test::RenderSyntheticScene(images, 10, 480, 360, dir_->path(), "sequence");
  // More threads than cores: the work of each stage is spread over the threads differently
  // in each run.
  Reconstruct(images, dir_->path() / "a", "11", "4");
  Reconstruct(images, dir_->path() / "b", "11", "4");
  ExpectIdenticalModels("a", "b");
  EXPECT_FALSE(fs::exists(dir_->path() / "a" / "sparse" / "1"));
  EXPECT_FALSE(fs::exists(dir_->path() / "b" / "sparse" / "1"));

  // Two BA threads: still bit for bit with the dense Schur LM, which the debug log names.
  const std::string log_c = Reconstruct(images, dir_->path() / "c", "11", "4", "2", "auto", "-v");
  Reconstruct(images, dir_->path() / "d", "11", "4", "2");
  ExpectIdenticalModels("c", "d");
  EXPECT_NE(log_c.find("dense Schur LM"), std::string::npos);
  EXPECT_EQ(log_c.find("Ceres"), std::string::npos);
}

// --seed reaches every RANSAC: verification of each pair (a seed derived from it and the
// pair) and registration (one per image). Another seed draws other samples, which shows in
// the verified geometries' bits and in the model's, not in what was found.
TEST_F(DeterminismTest, AnotherSeedDrawsOtherSamples) {
  const fs::path images = dir_->path() / "images";
  test::RenderSyntheticScene(images, 10, 480, 360, dir_->path(), "sequence");
  Reconstruct(images, dir_->path() / "a", "11", "2");
  Reconstruct(images, dir_->path() / "b", "12", "2");
  const auto geometries_a = Database(dir_->path() / "a" / "database.db").ReadTwoViewGeometries();
  const auto geometries_b = Database(dir_->path() / "b" / "database.db").ReadTwoViewGeometries();
  ASSERT_EQ(geometries_a.size(), geometries_b.size());
  size_t num_different = 0;
  for (size_t k = 0; k < geometries_a.size(); ++k) {
    ASSERT_EQ(geometries_a[k].first, geometries_b[k].first);
    const TwoViewGeometry& a = geometries_a[k].second;
    const TwoViewGeometry& b = geometries_b[k].second;
    num_different += a.E != b.E || a.F != b.F;
  }
  EXPECT_GT(num_different, 0u);
  EXPECT_FALSE(test::ReadBytes(dir_->path() / "a" / "sparse" / "0" / "images.bin") ==
               test::ReadBytes(dir_->path() / "b" / "sparse" / "0" / "images.bin"));
  for (const char* run : {"a", "b"}) {
    const ProcessResult evaluate =
        test::RunParallax({"evaluate", (dir_->path() / run / "sparse" / "0").string(), "--gt",
                           (images / "synth_par.txt").string()},
                          dir_->path());
    ASSERT_TRUE(evaluate.ExitedWith(0)) << evaluate.err;
    EXPECT_NE(evaluate.out.find("registered / in ground truth          10 / 10"), std::string::npos)
        << run << "\n"
        << evaluate.out;
  }
}

// `parallax match` takes --seed as reconstruct does: the same seed twice stores the same
// geometries bit for bit, another seed other ones; `parallax mapper` takes it too.
TEST_F(DeterminismTest, MatchAndMapperTakeTheSeedToo) {
  const fs::path images = dir_->path() / "images";
  test::RenderSyntheticScene(images, 8, 480, 360, dir_->path(), "sequence");
  const auto geometries_of = [&](const std::string& name, const std::string& seed) {
    const fs::path database = dir_->path() / (name + ".db");
    const ProcessResult features = test::RunParallax(
        {"features", "--images", images.string(), "--database", database.string(), "-q"},
        dir_->path());
    EXPECT_TRUE(features.ExitedWith(0)) << features.err;
    const ProcessResult match = test::RunParallax(
        {"match", "--database", database.string(), "--threads", "3", "--seed", seed, "-q"},
        dir_->path());
    EXPECT_TRUE(match.ExitedWith(0)) << match.err;
    return Database(database).ReadTwoViewGeometries();
  };
  const auto same_a = geometries_of("a", "1");
  const auto same_b = geometries_of("b", "1");
  const auto other = geometries_of("c", "2");
  ASSERT_EQ(same_a.size(), same_b.size());
  ASSERT_EQ(same_a.size(), other.size());
  ASSERT_FALSE(same_a.empty());
  size_t num_same_differ = 0, num_other_differ = 0;
  for (size_t k = 0; k < same_a.size(); ++k) {
    num_same_differ +=
        same_a[k].second.E != same_b[k].second.E || same_a[k].second.F != same_b[k].second.F ||
        same_a[k].second.inlier_matches.size() != same_b[k].second.inlier_matches.size();
    num_other_differ +=
        same_a[k].second.E != other[k].second.E || same_a[k].second.F != other[k].second.F;
  }
  EXPECT_EQ(num_same_differ, 0u);
  EXPECT_GT(num_other_differ, 0u);

  const auto map = [&](const std::string& out, const std::string& seed) {
    const ProcessResult result = test::RunParallax(
        {"mapper", "--database", (dir_->path() / "a.db").string(), "--image-path", images.string(),
         "--output", (dir_->path() / out).string(), "--ba-threads", "1", "--seed", seed, "-q"},
        dir_->path(), 300);
    EXPECT_TRUE(result.ExitedWith(0)) << result.err;
    return test::ReadBytes(dir_->path() / out / "sparse" / "0" / "images.bin");
  };
  // The same seed, the same model bit for bit. (Another seed draws other PnP samples, but on
  // these clean views every draw finds the same inliers and the refinement the same pose.)
  EXPECT_TRUE(map("m1", "1") == map("m1again", "1"));
}

// --ba-solver ceres hands every adjustment to Ceres, which reaches a model as good.
TEST_F(DeterminismTest, BaSolverFlagSelectsCeres) {
  const fs::path images = dir_->path() / "images";
  test::RenderSyntheticScene(images, 10, 480, 360, dir_->path(), "sequence");
  const std::string log =
      Reconstruct(images, dir_->path() / "ceres", "11", "2", "1", "ceres", "-v");
  EXPECT_NE(log.find("Ceres DENSE_SCHUR"), std::string::npos);
  EXPECT_EQ(log.find("dense Schur LM"), std::string::npos);
  const ProcessResult evaluate =
      test::RunParallax({"evaluate", (dir_->path() / "ceres" / "sparse" / "0").string(), "--gt",
                         (images / "synth_par.txt").string()},
                        dir_->path());
  ASSERT_TRUE(evaluate.ExitedWith(0)) << evaluate.err;
  EXPECT_NE(evaluate.out.find("registered / in ground truth          10 / 10"), std::string::npos)
      << evaluate.out;
}

}  // namespace
}  // namespace parallax
