// Interruption (issue 8): `parallax reconstruct` is killed with SIGKILL in the middle of
// feature extraction and, separately, of matching; the same command run again resumes from
// the database (what was stored is not computed again, as summary.json counts) and ends with
// the model an uninterrupted run gives. The stage is read from the database and the log, not
// guessed from timing; a run that got past the stage before the kill is repeated.
#include <gtest/gtest.h>
#include <signal.h>

#include <iostream>
#include <nlohmann/json.hpp>
#include <optional>
#include <regex>

#include "parallax/cli/cli_test_inputs.h"
#include "parallax/cli/cli_test_process.h"
#include "parallax/scene/colmap_io.h"
#include "parallax/scene/database.h"

namespace parallax {
namespace {

namespace fs = std::filesystem;

using test::ChildProcess;
using test::ProcessResult;

constexpr int kNumViews = 12;
constexpr int kNumPairs = kNumViews * (kNumViews - 1) / 2;

// COUNT(*) of a table, read without writing (the run being watched holds the database open);
// nullopt while the database or its schema does not exist yet.
std::optional<int64_t> CountRows(const fs::path& database, const std::string& table) {
  const auto count = test::QueryFirstValue(database, "SELECT COUNT(*) FROM " + table + ";");
  if (!count) return std::nullopt;
  return std::stoll(*count);
}

nlohmann::json ReadSummary(const fs::path& out) {
  return nlohmann::json::parse(test::ReadBytes(out / "summary.json"));
}

class ResumeTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    if (test::ParallaxBinary().empty()) return;
    scene_ = new test::ScopedTestDir("parallax_resume_scene");
    test::RenderSyntheticScene(scene_->path() / "images", kNumViews, 480, 360, scene_->path(),
                               "sequence");
    // The uninterrupted run every resumed run is compared with.
    const ProcessResult result =
        test::RunParallax(Command(scene_->path() / "reference"), scene_->path(), 300);
    ASSERT_TRUE(result.ExitedWith(0)) << result.err;
    reference_summary_ = new nlohmann::json(ReadSummary(scene_->path() / "reference"));
  }
  static void TearDownTestSuite() {
    delete scene_;
    delete reference_summary_;
    scene_ = nullptr;
    reference_summary_ = nullptr;
  }
  void SetUp() override {
    if (test::ParallaxBinary().empty()) GTEST_SKIP() << "PARALLAX_BINARY not set";
    ASSERT_NE(reference_summary_, nullptr);
    dir_ = std::make_unique<test::ScopedTestDir>("parallax_resume");
  }

  static std::vector<std::string> Command(const fs::path& out) {
    return {"reconstruct", "--images",   (scene_->path() / "images").string(),
            "--output",    out.string(), "--threads",
            "2",           "--seed",     "3"};
  }

  // Starts the command and sends it `signal` once `ready(out, stderr)` holds; retries (a
  // fresh output folder each time) when the run got past the wanted stage before the signal.
  // Returns the output folder of the signalled run; `*result` (when given) is how it ended.
  template <typename Ready, typename StillInStage>
  fs::path RunAndKill(const std::string& name, Ready ready, StillInStage still_in_stage,
                      int signal = SIGKILL, ProcessResult* signalled_result = nullptr) {
    for (int attempt = 0; attempt < 5; ++attempt) {
      const fs::path out = dir_->path() / (name + std::to_string(attempt));
      std::vector<std::string> argv = {test::ParallaxBinary()};
      const std::vector<std::string> command = Command(out);
      argv.insert(argv.end(), command.begin(), command.end());
      ChildProcess child(argv, dir_->path() / "killed_stdout.txt",
                         dir_->path() / "killed_stderr.txt");
      const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(300);
      bool killed = false;
      while (child.Running() && std::chrono::steady_clock::now() < deadline) {
        if (ready(out, child.Stderr())) {
          child.KillAndReap(signal);
          killed = true;
          break;
        }
        std::this_thread::sleep_for(std::chrono::milliseconds(2));
      }
      const ProcessResult result = child.Wait(1);
      if (killed && still_in_stage(out, result.err)) {
        if (signal == SIGKILL) {
          EXPECT_EQ(result.signal, SIGKILL);
        }
        if (signalled_result != nullptr) *signalled_result = result;
        return out;
      }
      if (!killed && (result.timed_out || result.signal != 0 || result.exit_code != 0)) {
        ADD_FAILURE() << "the run failed before it could be killed:\n" << result.err;
        return {};
      }
      // Too late (the stage was over) or finished: try again.
    }
    ADD_FAILURE() << "could not kill the run inside the stage in 5 attempts";
    return {};
  }

  // Runs the same command again to the end; returns its summary.
  nlohmann::json Rerun(const fs::path& out) {
    const ProcessResult result = test::RunParallax(Command(out), dir_->path(), 300);
    EXPECT_TRUE(result.ExitedWith(0)) << result.err;
    test::ExpectNoTemporaryFiles(out);
    return ReadSummary(out);
  }

  // Same quality as the uninterrupted run.
  static void ExpectSameQuality(const nlohmann::json& summary) {
    const nlohmann::json& reference = *reference_summary_;
    EXPECT_EQ(summary["images_registered"], reference["images_registered"]);
    EXPECT_EQ(summary["images_registered"], kNumViews);
    const double error = summary["mean_reprojection_error_px"].get<double>();
    const double reference_error = reference["mean_reprojection_error_px"].get<double>();
    EXPECT_NEAR(error, reference_error, 0.05 * reference_error + 0.01);
    const double points = summary["points3D"].get<double>();
    EXPECT_NEAR(points, reference["points3D"].get<double>(), 0.05 * points);
  }

  static test::ScopedTestDir* scene_;
  static nlohmann::json* reference_summary_;
  std::unique_ptr<test::ScopedTestDir> dir_;
};

test::ScopedTestDir* ResumeTest::scene_ = nullptr;
nlohmann::json* ResumeTest::reference_summary_ = nullptr;

TEST_F(ResumeTest, KilledDuringExtractionResumesWithoutExtractingAgain) {
  // Killed once some images, but not all, have their features committed (one transaction
  // per image).
  const fs::path out = RunAndKill(
      "killed_in_extraction",
      [](const fs::path& out, const std::string&) {
        const auto count = CountRows(out / "database.db", "descriptors");
        return count && *count >= 2 && *count < kNumViews;
      },
      [](const fs::path& out, const std::string&) {
        const auto count = CountRows(out / "database.db", "descriptors");
        return count && *count < kNumViews;
      });
  ASSERT_FALSE(out.empty());
  test::ExpectNoPartialOutput(out);
  size_t stored = 0;
  {
    Database database(out / "database.db");  // Still a valid database.
    for (const Image& image : database.ReadAllImages()) {
      EXPECT_TRUE(database.ExistsKeypoints(image.image_id));
      EXPECT_TRUE(database.ExistsDescriptors(image.image_id));
      ++stored;
    }
    EXPECT_EQ(database.NumMatchedPairs(), 0u);
  }
  ASSERT_GE(stored, 2u);
  ASSERT_LT(stored, static_cast<size_t>(kNumViews));
  std::cout << "killed with " << stored << " of " << kNumViews << " images stored\n";

  const nlohmann::json summary = Rerun(out);
  EXPECT_EQ(summary["features"]["images_skipped_already_stored"], stored);
  EXPECT_EQ(summary["features"]["images_extracted"], kNumViews - stored);
  EXPECT_EQ(summary["matching"]["pairs_matched"], kNumPairs);
  ExpectSameQuality(summary);
}

TEST_F(ResumeTest, KilledDuringMatchingResumesWithoutRedoingStoredWork) {
  // Killed once the progress line shows pairs done, before the stage's closing log line.
  const std::regex progress("matching: [1-9][0-9]*/[0-9]+");
  const fs::path out = RunAndKill(
      "killed_in_matching",
      [&](const fs::path&, const std::string& err) { return std::regex_search(err, progress); },
      [](const fs::path&, const std::string& err) {
        return err.find("pairs matched") == std::string::npos;
      });
  ASSERT_FALSE(out.empty());
  test::ExpectNoPartialOutput(out);
  size_t stored_pairs = 0;
  {
    Database database(out / "database.db");
    EXPECT_EQ(database.NumImages(), static_cast<size_t>(kNumViews));
    stored_pairs = database.ReadTwoViewGeometries().size();
  }
  ASSERT_LT(stored_pairs, static_cast<size_t>(kNumPairs));
  // Pairs are committed in batches (MatchingStageOptions::batch_size): a kill loses
  // the batch in progress, so with fewer pairs than a batch none are stored yet.
  std::cout << "killed with " << stored_pairs << " of " << kNumPairs << " pairs stored\n";

  const nlohmann::json summary = Rerun(out);
  EXPECT_EQ(summary["features"]["images_skipped_already_stored"], kNumViews);
  EXPECT_EQ(summary["features"]["images_extracted"], 0);
  EXPECT_EQ(summary["matching"]["pairs_skipped_already_stored"], stored_pairs);
  EXPECT_EQ(summary["matching"]["pairs_matched"], kNumPairs - stored_pairs);
  ExpectSameQuality(summary);
}

// Ctrl-C (issue 22): the run stops once the images extracted so far are stored, says so in
// one line, exits 130, and the same command resumes from there.
TEST_F(ResumeTest, CtrlCDuringExtractionStopsAtASafePointAndSaysHowToResume) {
  ProcessResult interrupted;
  const fs::path out = RunAndKill(
      "interrupted_in_extraction",
      [](const fs::path& out, const std::string&) {
        const auto count = CountRows(out / "database.db", "descriptors");
        return count && *count >= 1 && *count < kNumViews;
      },
      [](const fs::path&, const std::string& err) {
        return err.find("Feature extraction: 12 extracted") == std::string::npos;
      },
      SIGINT, &interrupted);
  ASSERT_FALSE(out.empty());
  EXPECT_TRUE(interrupted.ExitedWith(130)) << interrupted.err;
  const std::regex said(
      "\ninterrupted \\(SIGINT\\): features of ([0-9]+) of 12 images are stored in [^\n]*"
      "database\\.db; run the same command again to resume\n$");
  std::smatch match;
  ASSERT_TRUE(std::regex_search(interrupted.err, match, said)) << interrupted.err;
  test::ExpectNoPartialOutput(out);
  const size_t said_stored = std::stoul(match[1]);
  size_t stored = 0;
  {
    Database database(out / "database.db");
    stored = database.NumImages();
    for (const Image& image : database.ReadAllImages()) {
      EXPECT_TRUE(database.ExistsDescriptors(image.image_id));
    }
  }
  EXPECT_EQ(stored, said_stored);
  const nlohmann::json summary = Rerun(out);
  EXPECT_EQ(summary["features"]["images_skipped_already_stored"], stored);
  EXPECT_EQ(summary["features"]["images_extracted"], kNumViews - stored);
  ExpectSameQuality(summary);
}

// kill (SIGTERM) during matching: the finished pairs are stored, exit status 143.
TEST_F(ResumeTest, SigtermDuringMatchingKeepsTheFinishedPairs) {
  const std::regex progress("matching: [1-9][0-9]*/[0-9]+");
  ProcessResult interrupted;
  const fs::path out = RunAndKill(
      "interrupted_in_matching",
      [&](const fs::path&, const std::string& err) { return std::regex_search(err, progress); },
      [](const fs::path&, const std::string& err) {
        return err.find("pairs matched") == std::string::npos;
      },
      SIGTERM, &interrupted);
  ASSERT_FALSE(out.empty());
  EXPECT_TRUE(interrupted.ExitedWith(143)) << interrupted.err;
  EXPECT_NE(interrupted.err.find("interrupted (SIGTERM): "), std::string::npos) << interrupted.err;
  EXPECT_NE(interrupted.err.find(" pairs are matched and verified in "), std::string::npos);
  test::ExpectNoPartialOutput(out);
  size_t stored_pairs = 0;
  {
    Database database(out / "database.db");
    stored_pairs = database.ReadTwoViewGeometries().size();
  }
  // Unlike a kill, the pairs finished before the signal were committed.
  EXPECT_GT(stored_pairs, 0u);
  const nlohmann::json summary = Rerun(out);
  EXPECT_EQ(summary["matching"]["pairs_skipped_already_stored"], stored_pairs);
  EXPECT_EQ(summary["matching"]["pairs_matched"], kNumPairs - stored_pairs);
  ExpectSameQuality(summary);
}

TEST_F(ResumeTest, RerunOfAFinishedRunRedoesNothingButTheMapping) {
  const fs::path out = dir_->path() / "finished";
  const ProcessResult first = test::RunParallax(Command(out), dir_->path(), 300);
  ASSERT_TRUE(first.ExitedWith(0)) << first.err;
  const nlohmann::json summary = Rerun(out);
  EXPECT_EQ(summary["features"]["images_extracted"], 0);
  EXPECT_EQ(summary["features"]["images_skipped_already_stored"], kNumViews);
  EXPECT_EQ(summary["matching"]["pairs_matched"], 0);
  EXPECT_EQ(summary["matching"]["pairs_skipped_already_stored"], kNumPairs);
  ExpectSameQuality(summary);
  // The outputs were replaced as a whole: one model folder, written by the second run.
  EXPECT_TRUE(fs::exists(out / "sparse" / "0" / "points3D.txt"));
  EXPECT_FALSE(fs::exists(out / "sparse" / "1"));
}

}  // namespace
}  // namespace parallax
