// Determinism (issue 8): two `parallax reconstruct` runs with the same images, options and
// --seed give byte-identical models, although the threads of extraction and matching finish
// their work in a different order from run to run. Bundle adjustment runs on one thread:
// Ceres' threaded Schur elimination adds its blocks in arrival order, which changes the last
// bits of the model (the command-line help says so).
#include <gtest/gtest.h>

#include "parallax/cli/cli_test_inputs.h"
#include "parallax/cli/cli_test_process.h"

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
  void Reconstruct(const fs::path& images, const fs::path& out, const std::string& seed,
                   const std::string& threads) {
    const ProcessResult result = test::RunParallax(
        {"reconstruct", "--images", images.string(), "--output", out.string(), "--threads",
         threads, "--ba-threads", "1", "--seed", seed, "-q"},
        dir_->path(), 300);
    ASSERT_TRUE(result.ExitedWith(0)) << result.err;
  }

  std::unique_ptr<test::ScopedTestDir> dir_;
};

TEST_F(DeterminismTest, SameInputsOptionsAndSeedGiveIdenticalModels) {
  const fs::path images = dir_->path() / "images";
  test::RenderSyntheticScene(images, 10, 480, 360, dir_->path(), "sequence");
  // More threads than cores: the work of each stage is spread over the threads differently
  // in each run.
  ASSERT_NO_FATAL_FAILURE(Reconstruct(images, dir_->path() / "a", "11", "4"));
  ASSERT_NO_FATAL_FAILURE(Reconstruct(images, dir_->path() / "b", "11", "4"));
  for (const char* file : {"cameras.txt", "images.txt", "points3D.txt", "cameras.bin",
                           "images.bin", "points3D.bin"}) {
    const fs::path a = dir_->path() / "a" / "sparse" / "0" / file;
    const fs::path b = dir_->path() / "b" / "sparse" / "0" / file;
    ASSERT_TRUE(fs::exists(a)) << a;
    ASSERT_TRUE(fs::exists(b)) << b;
    // EXPECT_TRUE rather than EXPECT_EQ: the models are long.
    EXPECT_TRUE(test::ReadBytes(a) == test::ReadBytes(b)) << file << " differs between runs";
  }
  EXPECT_TRUE(test::ReadBytes(dir_->path() / "a" / "points.ply") ==
              test::ReadBytes(dir_->path() / "b" / "points.ply"));
  EXPECT_FALSE(fs::exists(dir_->path() / "a" / "sparse" / "1"));
  EXPECT_FALSE(fs::exists(dir_->path() / "b" / "sparse" / "1"));
}

}  // namespace
}  // namespace parallax
