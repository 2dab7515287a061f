// Bad ground-truth and model files given to `parallax evaluate` and `parallax report`
// (issue 8): Middlebury *_par.txt, Strecha *.camera folders and COLMAP models with dangling
// ids, made at test time from a rendered scene's exact cameras. Each must end in one error
// line "error: <file>:<line>: <reason>" and exit code 1, never a crash or a hang.
#include <gtest/gtest.h>

#include <fstream>

#include "parallax/cli/cli_test_inputs.h"
#include "parallax/cli/cli_test_process.h"

namespace parallax {
namespace {

namespace fs = std::filesystem;

using test::ExpectFailsWithOneLineError;
using test::ProcessResult;
using test::Replace;
using test::WriteBytes;

class BadInputFilesTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    if (test::ParallaxBinary().empty()) return;
    scene_ = new test::ScopedTestDir("parallax_bad_files_scene");
    test::RenderSyntheticScene(scene_->path(), 3, 64, 48, scene_->path());
  }
  static void TearDownTestSuite() {
    delete scene_;
    scene_ = nullptr;
  }
  void SetUp() override {
    if (test::ParallaxBinary().empty()) GTEST_SKIP() << "PARALLAX_BINARY not set";
    dir_ = std::make_unique<test::ScopedTestDir>("parallax_bad_files");
    // A valid model with a point: the scene's exact cameras, one keypoint per image.
    model_ = dir_->path() / "model";
    fs::create_directories(model_);
    fs::copy_file(Gt() / "cameras.txt", model_ / "cameras.txt");
    std::string images;
    for (const std::string& line : SplitLines(test::ReadBytes(Gt() / "images.txt"))) {
      if (line.empty() || line[0] == '#') continue;
      images += line + "\n10.5 20.5 1\n";
    }
    WriteBytes(model_ / "images.txt", images);
    WriteBytes(model_ / "points3D.txt", "1 0 0 0 10 20 30 0.5 1 0 2 0 3 0\n");
  }

  static fs::path Gt() { return scene_->path() / "gt"; }
  static fs::path Par() { return scene_->path() / "synth_par.txt"; }

  ProcessResult Evaluate(const fs::path& model, const fs::path& gt) {
    return test::RunParallax({"evaluate", model.string(), "--gt", gt.string()}, dir_->path(), 60);
  }
  // A copy of the model folder with one file replaced.
  fs::path ModelWith(const std::string& name, const std::string& file, const std::string& text) {
    const fs::path dir = dir_->path() / name;
    fs::create_directories(dir);
    for (const char* each : {"cameras.txt", "images.txt", "points3D.txt"}) {
      fs::copy_file(model_ / each, dir / each);
    }
    WriteBytes(dir / file, text);
    return dir;
  }
  std::string ModelFile(const std::string& file) { return test::ReadBytes(model_ / file); }

  static test::ScopedTestDir* scene_;
  std::unique_ptr<test::ScopedTestDir> dir_;
  fs::path model_;
};

test::ScopedTestDir* BadInputFilesTest::scene_ = nullptr;

TEST_F(BadInputFilesTest, ValidFilesEvaluate) {
  // The unbroken inputs the other cases start from do work.
  const ProcessResult with_par = Evaluate(model_, Par());
  ASSERT_TRUE(with_par.ExitedWith(0)) << with_par.err;
  const ProcessResult with_model = Evaluate(model_, Gt());
  ASSERT_TRUE(with_model.ExitedWith(0)) << with_model.err;
}

TEST_F(BadInputFilesTest, MalformedMiddleburyParFiles) {
  const std::vector<std::string> lines = SplitLines(test::ReadBytes(Par()));
  ASSERT_EQ(lines.size(), 4u);
  const std::string views = lines[1] + "\n" + lines[2] + "\n" + lines[3] + "\n";
  const std::vector<std::tuple<std::string, std::string, std::string>> cases = {
      {"", ":1:", "empty file"},
      {"3 4\n" + views, ":1:", "expected the number of views alone"},
      {"three\n" + views, ":1:", "not a finite number: 'three'"},
      {"-3\n" + views, ":1:", "non-negative integer"},
      {"1e300\n" + views, ":1:", "the number of views 1e300 is too large"},
      {"4\n" + views, ":4:", "expected 4 views, found 3"},
      {"2\n" + views, ":4:", "more views than the 2 announced"},
      {"3\n" + lines[1] + " 7\n" + lines[2] + "\n" + lines[3] + "\n", ":2:", "expected 22 fields"},
      {"3\n" + Replace(lines[1], " 0 0 1 ", " 0 0 inf ") + "\n" + lines[2] + "\n" + lines[3] + "\n",
       ":2:", "not a finite number: 'inf'"},
      {"3\nview_0001.png 1 0 0 0 1 0 0 0 1 2 0 0 0 2 0 0 0 2 0 0 0\n" + lines[2] + "\n" + lines[3] +
           "\n",
       ":2:", "R is not a rotation matrix"},
      {"3\nview_0001.png -1 0 0 0 1 0 0 0 1 1 0 0 0 1 0 0 0 1 0 0 0\n" + lines[2] + "\n" +
           lines[3] + "\n",
       ":2:", "positive focal lengths"},
      {"3\nview_0001.png 1 0 0 0 1 0 0 0 1 1e200 1e200 0 1e200 1e200 0 0 0 1 0 0 0\n" + lines[2] +
           "\n" + lines[3] + "\n",
       ":2:", "R is not a rotation matrix"},
  };
  for (size_t k = 0; k < cases.size(); ++k) {
    const auto& [text, line, reason] = cases[k];
    const fs::path par = dir_->path() / ("bad" + std::to_string(k) + "_par.txt");
    WriteBytes(par, text);
    SCOPED_TRACE(text.substr(0, 60));
    ExpectFailsWithOneLineError(Evaluate(model_, par), par.string() + line, reason);
  }
}

TEST_F(BadInputFilesTest, MalformedStrechaCameraFiles) {
  const std::string valid =
      "300 0 32\n0 300 24\n0 0 1\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n0 0 -5\n64 48\n";
  const std::vector<std::tuple<std::string, std::string, std::string>> cases = {
      {"", ":1:", "unexpected end of file"},
      {"300 0 32\n0 300 24\n0 0 1\n", ":4:", "unexpected end of file"},
      {Replace(valid, "0 300 24", "0 300"), ":2:", "expected 3 numbers, found 2"},
      {Replace(valid, "64 48", "64 x"), ":9:", "not a finite number: 'x'"},
      {Replace(valid, "64 48", "0 48"), ":9:", "image size must be two positive integers"},
      {Replace(valid, "64 48", "1e300 48"),
       ":9:", "image size must be two positive integers up to"},
      {Replace(valid, "64 48", "64.5 48"), ":9:", "image size"},
      {Replace(valid, "1 0 0\n0 1 0", "1 0 0\n1 0 0"), ":5:", "R is not a rotation matrix"},
      {valid + "1 2 3\n", ":10:", "trailing data"},
  };
  for (size_t k = 0; k < cases.size(); ++k) {
    const auto& [text, line, reason] = cases[k];
    const fs::path folder = dir_->path() / ("strecha" + std::to_string(k));
    fs::create_directories(folder);
    WriteBytes(folder / "view_0001.png.camera", valid);
    WriteBytes(folder / "view_0002.png.camera", text);
    SCOPED_TRACE(text);
    ExpectFailsWithOneLineError(Evaluate(model_, folder),
                                (folder / "view_0002.png.camera").string() + line, reason);
  }
}

TEST_F(BadInputFilesTest, ModelWithDanglingIds) {
  const std::string images = ModelFile("images.txt");
  const std::string first_line = SplitLines(images)[0];
  // Image 1 with camera 9 (there is only camera 1).
  const std::string bad_camera = first_line.substr(0, first_line.rfind(" 1 ")) + " 9 " +
                                 first_line.substr(first_line.rfind(" 1 ") + 3);
  const std::vector<std::tuple<std::string, std::string, std::string, std::string>> cases = {
      {"images.txt", Replace(images, first_line, bad_camera),
       ":1:", "image 1 refers to missing camera 9"},
      {"points3D.txt", "1 0 0 0 10 20 30 0.5 1 0 42 0\n",
       ":1:", "3D point 1 observed in missing image 42"},
      {"points3D.txt", "1 0 0 0 10 20 30 0.5 1 0 2 7\n",
       ":1:", "refers to missing keypoint 7 of image 2"},
      {"points3D.txt", "1 0 0 0 10 20 30 0.5 1 0 1 0\n",
       ":1:", "keypoint 0 of image 1 observes two 3D points"},
      {"points3D.txt", "1 0 0 0 10 20 30 0.5 1 0 2 0\n1 0 0 0 1 2 3 0.5 3 0\n",
       ":2:", "duplicate 3D point id 1"},
      {"images.txt", images + images, ":7:", "duplicate image id 1"},
      {"cameras.txt", "1 PINHOLE 64 48 -57 57 32 24\n", ":1:", "invalid parameters for camera 1"},
      {"cameras.txt", "1 FISHEYE_42 64 48 57 57 32 24\n",
       ":1:", "unknown camera model 'FISHEYE_42'"},
      {"cameras.txt", "1 PINHOLE 64 48 57 57 32\n", ":1:", "PINHOLE takes 4 parameters, got 3"},
      {"images.txt", Replace(images, "10.5 20.5 1", "10.5 20.5"), ":2:", "triplets"},
  };
  for (size_t k = 0; k < cases.size(); ++k) {
    const auto& [file, text, line, reason] = cases[k];
    const fs::path model = ModelWith("model" + std::to_string(k), file, text);
    SCOPED_TRACE(text.substr(0, 80));
    ExpectFailsWithOneLineError(Evaluate(model, Par()), (model / file).string() + line, reason);
    // The same model as ground truth, and in the report.
    ExpectFailsWithOneLineError(Evaluate(model_, model), (model / file).string() + line, reason);
  }
}

TEST_F(BadInputFilesTest, IncompleteAndBinaryModels) {
  // A folder with cameras.txt only.
  const fs::path partial = dir_->path() / "partial";
  fs::create_directories(partial);
  fs::copy_file(model_ / "cameras.txt", partial / "cameras.txt");
  ExpectFailsWithOneLineError(Evaluate(partial, Par()), (partial / "images.txt").string(),
                              "cannot open for reading");
  // No model at all, and a folder that does not exist.
  const fs::path empty = dir_->path() / "empty";
  fs::create_directories(empty);
  ExpectFailsWithOneLineError(Evaluate(empty, Par()), empty.string(), "no COLMAP model here");
  const fs::path missing = dir_->path() / "missing";
  ExpectFailsWithOneLineError(Evaluate(missing, Par()), missing.string(), "does not exist");
  // Binary files that are truncated or lie about their counts.
  const fs::path binary = dir_->path() / "binary";
  fs::create_directories(binary);
  // One PINHOLE camera (id 1, 64 x 48) whose record stops after two of its four parameters.
  std::string camera = std::string("\x01\0\0\0\0\0\0\0", 8) + std::string("\x01\0\0\0", 4) +
                       std::string("\x01\0\0\0", 4) + std::string("\x40\0\0\0\0\0\0\0", 8) +
                       std::string("\x30\0\0\0\0\0\0\0", 8) + std::string(16, '\0');
  WriteBytes(binary / "cameras.bin", camera);
  ExpectFailsWithOneLineError(
      Evaluate(binary, Par()),
      (binary / "cameras.bin").string() + ":byte 48:", "truncated: cannot read camera parameter");
  WriteBytes(binary / "cameras.bin", std::string(8, '\xff'));
  ExpectFailsWithOneLineError(Evaluate(binary, Par()), (binary / "cameras.bin").string() + ":byte",
                              "exceeds what the remaining");
  // report with a model of dangling ids.
  const fs::path out = dir_->path() / "out";
  fs::create_directories(out / "sparse");
  fs::copy(ModelWith("dangling", "points3D.txt", "1 0 0 0 10 20 30 0.5 1 0 42 0\n"),
           out / "sparse" / "0");
  const ProcessResult report = test::RunParallax({"report", out.string()}, dir_->path(), 60);
  ExpectFailsWithOneLineError(
      report, (out / "sparse" / "0" / "points3D.txt").string() + ":1:", "missing image 42");
  EXPECT_FALSE(fs::exists(out / "report.html"));
}

}  // namespace
}  // namespace parallax
