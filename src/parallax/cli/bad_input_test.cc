// What `parallax` does with the inputs users really feed it (issue 8): broken, odd and
// hostile image files, folders that cannot work, malformed intrinsics. Every input is made in a
// temp folder at test time. The rules: a clear one-line error naming the file and the reason
// and a non-zero exit where the run cannot go on; a warning naming the file and a skip where it
// can; never a crash (death by signal), a hang (time limit) or a partial output. Ground truth
// and COLMAP model files are in bad_input_files_test.cc.
#include <gtest/gtest.h>
#include <unistd.h>

#include <fstream>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "parallax/cli/cli_test_inputs.h"
#include "parallax/cli/cli_test_process.h"
#include "parallax/scene/database.h"

namespace parallax {
namespace {

namespace fs = std::filesystem;

using test::ExpectFailsWithOneLineError;
using test::ExpectNoPartialOutput;
using test::ExpectOneWarningNaming;
using test::ProcessResult;
using test::Replace;
using test::WriteBytes;

class BadInputTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    if (test::ParallaxBinary().empty()) return;
    // Textured stand-ins for photos (instant to make, even under the sanitizers): every case
    // but one needs readable images, not a scene that reconstructs.
    scene_dir_ = new test::ScopedTestDir("parallax_bad_input_views");
    for (int i = 1; i <= 4; ++i) {
      ASSERT_TRUE(cv::imwrite(SceneView(i).string(), test::RandomTexture(320, 240, 100 + i)));
    }
    WriteBytes(scene_dir_->path() / "K.txt", "288 0 160\n0 288 120\n0 0 1\n");
  }
  static void TearDownTestSuite() {
    delete scene_dir_;
    scene_dir_ = nullptr;
  }
  void SetUp() override {
    if (test::ParallaxBinary().empty()) GTEST_SKIP() << "PARALLAX_BINARY not set";
    dir_ = std::make_unique<test::ScopedTestDir>("parallax_bad_input");
    images_ = dir_->path() / "images";
    fs::create_directories(images_);
  }

  // view_0001.png ... view_0004.png: textured images, no common scene.
  static fs::path SceneView(int index) {
    char name[32];
    std::snprintf(name, sizeof(name), "view_%04d.png", index);
    return scene_dir_->path() / name;
  }
  void CopyViews(int count) {
    for (int i = 1; i <= count; ++i) fs::copy_file(SceneView(i), images_ / SceneView(i).filename());
  }
  // Three rendered views of a synthetic scene that reconstruct (with their K.txt), in `dir`.
  // Four views: with three, the best pair's baseline (about 4 degrees) sits at the mapper's
  // lowest initial-pair bar, and the seed of the verification decides whether it passes.
  void RenderScene(const fs::path& dir) {
    test::RenderSyntheticScene(dir, 4, 320, 240, dir_->path(), "sequence");
  }

  ProcessResult Run(const std::vector<std::string>& arguments, double timeout_seconds = 120) {
    return test::RunParallax(arguments, dir_->path(), timeout_seconds);
  }
  ProcessResult Features(std::vector<std::string> extra = {}) {
    std::vector<std::string> arguments = {"features",   "--images",          images_.string(),
                                          "--database", Database().string(), "--threads",
                                          "2"};
    arguments.insert(arguments.end(), extra.begin(), extra.end());
    return Run(arguments);
  }
  ProcessResult Reconstruct(std::vector<std::string> extra = {}) {
    std::vector<std::string> arguments = {
        "reconstruct", "--images", images_.string(), "--output", Out().string(), "--threads", "2"};
    arguments.insert(arguments.end(), extra.begin(), extra.end());
    return Run(arguments, 300);
  }
  fs::path Database() const { return dir_->path() / "database.db"; }
  fs::path Out() const { return dir_->path() / "out"; }

  // Names (and keypoint counts) of the images the database holds.
  std::map<std::string, size_t> StoredImages() const {
    std::map<std::string, size_t> stored;
    parallax::Database database(Database());
    for (const Image& image : database.ReadAllImages()) {
      stored[image.name] = database.NumKeypoints(image.image_id);
    }
    return stored;
  }

  static test::ScopedTestDir* scene_dir_;
  std::unique_ptr<test::ScopedTestDir> dir_;
  fs::path images_;
};

test::ScopedTestDir* BadInputTest::scene_dir_ = nullptr;

// ---------------------------------------------------------------------------------------
// Image files: skipped with one warning each, the good images are used.

TEST_F(BadInputTest, ZeroByteFileNamedJpgIsSkippedWithWarning) {
  CopyViews(2);
  WriteBytes(images_ / "empty.jpg", "");
  const ProcessResult result = Features();
  ASSERT_TRUE(result.ExitedWith(0)) << result.err;
  ExpectOneWarningNaming(result.err, images_ / "empty.jpg", "empty file");
  EXPECT_EQ(StoredImages().size(), 2u);
  EXPECT_NE(result.out.find("2 extracted"), std::string::npos) << result.out;
  EXPECT_NE(result.out.find("1 failed"), std::string::npos) << result.out;
}

TEST_F(BadInputTest, TextFileNamedJpgIsSkippedWithWarning) {
  CopyViews(2);
  WriteBytes(images_ / "notes.jpg", "these are my holiday notes, not a photo\n");
  WriteBytes(images_ / "readme.txt", "not named like an image: ignored silently\n");
  const ProcessResult result = Features();
  ASSERT_TRUE(result.ExitedWith(0)) << result.err;
  ExpectOneWarningNaming(result.err, images_ / "notes.jpg", "not a PNG, JPEG, TIFF or BMP image");
  EXPECT_EQ(result.err.find("readme.txt"), std::string::npos) << result.err;
  EXPECT_EQ(StoredImages().size(), 2u);
}

TEST_F(BadInputTest, TruncatedPngIsSkippedWithWarning) {
  CopyViews(2);
  const std::string png = test::ReadBytes(SceneView(3));
  WriteBytes(images_ / "cut.png", png.substr(0, png.size() / 2));
  const ProcessResult result = Features();
  ASSERT_TRUE(result.ExitedWith(0)) << result.err;
  ExpectOneWarningNaming(result.err, images_ / "cut.png", "truncated PNG");
  EXPECT_EQ(StoredImages().count("cut.png"), 0u);
  EXPECT_EQ(StoredImages().size(), 2u);
}

TEST_F(BadInputTest, TruncatedJpegIsSkippedWithWarning) {
  CopyViews(2);
  const std::string jpeg = test::EncodeImage(".jpg", cv::imread(SceneView(3).string()));
  // Cut inside the entropy-coded data, and also right after the headers.
  WriteBytes(images_ / "cut.jpg", jpeg.substr(0, jpeg.size() / 2));
  WriteBytes(images_ / "headers_only.jpg", jpeg.substr(0, 700));
  const ProcessResult result = Features();
  ASSERT_TRUE(result.ExitedWith(0)) << result.err;
  ExpectOneWarningNaming(result.err, images_ / "cut.jpg", "truncated JPEG");
  ExpectOneWarningNaming(result.err, images_ / "headers_only.jpg", "JPEG");
  EXPECT_EQ(StoredImages().size(), 2u);
}

TEST_F(BadInputTest, PngNamedJpgIsReadByContent) {
  CopyViews(1);
  fs::copy_file(SceneView(2), images_ / "actually_a_png.jpg");
  const ProcessResult result = Features();
  ASSERT_TRUE(result.ExitedWith(0)) << result.err;
  EXPECT_EQ(result.err.find("warning"), std::string::npos) << result.err;
  const auto stored = StoredImages();
  ASSERT_EQ(stored.count("actually_a_png.jpg"), 1u);
  EXPECT_GT(stored.at("actually_a_png.jpg"), 100u);
}

TEST_F(BadInputTest, HugeImageIsRefusedFromItsHeaderBeforeDecoding) {
  CopyViews(2);
  // Real small images whose headers claim 100000 x 100000 (PNG) and 65535 x 65535 (JPEG):
  // decoding them would allocate 30 GB and 12 GB.
  const cv::Mat small = cv::imread(SceneView(3).string());
  WriteBytes(images_ / "huge.png",
             test::WithPngSize(test::EncodeImage(".png", small), 100000, 100000));
  WriteBytes(images_ / "huge.jpg",
             test::WithJpegSize(test::EncodeImage(".jpg", small), 65535, 65535));
  const ProcessResult result = Features();
  ASSERT_TRUE(result.ExitedWith(0)) << result.err;
  ExpectOneWarningNaming(result.err, images_ / "huge.png",
                         "image is 100000x100000 pixels, more than max_image_pixels");
  ExpectOneWarningNaming(result.err, images_ / "huge.jpg",
                         "image is 65535x65535 pixels, more than max_image_pixels");
  EXPECT_EQ(StoredImages().size(), 2u);
}

TEST_F(BadInputTest, MaxImagePixelsOptionIsHonoured) {
  CopyViews(3);
  const ProcessResult result = Features({"--max-image-pixels", "1000"});
  // Nothing readable: the command fails, and says why for each file.
  EXPECT_TRUE(result.ExitedWith(1)) << result.err;
  for (int i = 1; i <= 3; ++i) {
    ExpectOneWarningNaming(result.err, images_ / SceneView(i).filename(),
                           "320x240 pixels, more than max_image_pixels = 1000");
  }
}

TEST_F(BadInputTest, SixteenBitAndRgbaImagesAreConverted) {
  const cv::Mat view = cv::imread(SceneView(1).string());
  cv::Mat view16, rgba, gray16;
  view.convertTo(view16, CV_16UC3, 257.0);
  cv::cvtColor(view, rgba, cv::COLOR_BGR2BGRA);
  cv::cvtColor(view16, gray16, cv::COLOR_BGR2GRAY);
  ASSERT_TRUE(cv::imwrite((images_ / "sixteen_bit.png").string(), view16));
  ASSERT_TRUE(cv::imwrite((images_ / "rgba.png").string(), rgba));
  ASSERT_TRUE(cv::imwrite((images_ / "gray16.tif").string(), gray16));
  ASSERT_TRUE(cv::imwrite((images_ / "eight_bit.png").string(), view));
  const ProcessResult result = Features();
  ASSERT_TRUE(result.ExitedWith(0)) << result.err;
  EXPECT_EQ(result.err.find("warning"), std::string::npos) << result.err;
  const auto stored = StoredImages();
  ASSERT_EQ(stored.size(), 4u);
  // The same picture in every format: about the same features.
  const double reference = static_cast<double>(stored.at("eight_bit.png"));
  EXPECT_GT(reference, 100);
  for (const char* name : {"sixteen_bit.png", "rgba.png", "gray16.tif"}) {
    EXPECT_NEAR(static_cast<double>(stored.at(name)), reference, 0.1 * reference) << name;
  }
}

TEST_F(BadInputTest, MixedSizesGetOneCameraPerSizeOrAreSkippedForSingleCamera) {
  CopyViews(2);
  cv::Mat half;
  cv::resize(cv::imread(SceneView(3).string()), half, cv::Size(160, 120), 0, 0, cv::INTER_AREA);
  // Named to come last: the single camera takes the size of the first image.
  ASSERT_TRUE(cv::imwrite((images_ / "z_small.png").string(), half));
  {
    const ProcessResult result = Features();
    ASSERT_TRUE(result.ExitedWith(0)) << result.err;
    parallax::Database database(Database());
    EXPECT_EQ(database.NumImages(), 3u);
    EXPECT_EQ(database.NumCameras(), 2u);
  }
  fs::remove(Database());
  const ProcessResult single = Features({"--single-camera"});
  ASSERT_TRUE(single.ExitedWith(0)) << single.err;
  ExpectOneWarningNaming(single.err, images_ / "z_small.png",
                         "image is 160x120 but the single camera is 320x240");
  parallax::Database database(Database());
  EXPECT_EQ(database.NumImages(), 2u);
  EXPECT_EQ(database.NumCameras(), 1u);
}

// ---------------------------------------------------------------------------------------
// Folders and scenes that cannot give a model: one error line, non-zero exit, nothing half
// written (the database stays for a later resume).

TEST_F(BadInputTest, EmptyFolderFailsBeforeCreatingAnything) {
  const ProcessResult result = Reconstruct();
  ExpectFailsWithOneLineError(result, images_.string(), "no images found");
  EXPECT_FALSE(fs::exists(Out()));
  // Files that are not images do not count.
  WriteBytes(images_ / "notes.txt", "hello\n");
  WriteBytes(images_ / "empty.jpg", "");
  const ProcessResult only_junk = Reconstruct();
  ExpectFailsWithOneLineError(only_junk, images_.string(), "no images found");
  EXPECT_FALSE(fs::exists(Out()));
}

TEST_F(BadInputTest, MissingImageFolderFails) {
  const fs::path missing = dir_->path() / "no_such_folder";
  const ProcessResult result =
      Run({"reconstruct", "--images", missing.string(), "--output", Out().string()});
  ExpectFailsWithOneLineError(result, missing.string(), "does not exist");
  EXPECT_FALSE(fs::exists(Out()));
}

TEST_F(BadInputTest, SingleImageFailsBeforeCreatingAnything) {
  CopyViews(1);
  const ProcessResult result = Reconstruct();
  ExpectFailsWithOneLineError(result, images_.string(), "only one image");
  EXPECT_FALSE(fs::exists(Out()));
}

TEST_F(BadInputTest, OneReadableImageOfTwoFailsWithoutPartialOutput) {
  CopyViews(1);
  WriteBytes(images_ / "cut.png", test::ReadBytes(SceneView(2)).substr(0, 1000));
  const ProcessResult result = Reconstruct();
  ExpectFailsWithOneLineError(result, images_.string(), "fewer than two readable images");
  ExpectOneWarningNaming(result.err, images_ / "cut.png", "truncated PNG");
  ExpectNoPartialOutput(Out());
}

TEST_F(BadInputTest, TwoImagesWithoutOverlapFailWithoutPartialOutput) {
  WriteBytes(images_ / "a.png", test::EncodeImage(".png", test::RandomTexture(320, 240, 1)));
  WriteBytes(images_ / "b.png", test::EncodeImage(".png", test::RandomTexture(320, 240, 2)));
  const ProcessResult result = Reconstruct();
  ExpectFailsWithOneLineError(result, images_.string(), "no model could be started");
  ExpectNoPartialOutput(Out());
  EXPECT_TRUE(fs::exists(Out() / "database.db"));  // Kept: a rerun resumes from it.
}

TEST_F(BadInputTest, TexturelessImagesOnlyFailWithoutPartialOutput) {
  for (const char* name : {"gray.png", "white.png"}) {
    const cv::Mat flat(240, 320, CV_8UC3, cv::Scalar::all(name[0] == 'g' ? 128 : 255));
    ASSERT_TRUE(cv::imwrite((images_ / name).string(), flat));
  }
  const ProcessResult result = Reconstruct();
  ExpectFailsWithOneLineError(result, images_.string(), "no model could be started");
  ExpectOneWarningNaming(result.err, images_ / "gray.png", "no features found");
  ExpectOneWarningNaming(result.err, images_ / "white.png", "no features found");
  ExpectNoPartialOutput(Out());
}

TEST_F(BadInputTest, TexturelessDuplicateAndOddImagesAmongGoodOnesStillGiveAModel) {
  // One run for the cases that must not stop a reconstruction: a textureless image, a
  // duplicate of a view under another name, junk named .jpg, into an output folder whose
  // parents do not exist yet.
  const fs::path scene = dir_->path() / "scene";
  RenderScene(scene);
  for (int i = 1; i <= 4; ++i) {
    const std::string name = "view_000" + std::to_string(i) + ".png";
    fs::copy_file(scene / name, images_ / name);
  }
  const cv::Mat flat(240, 320, CV_8UC3, cv::Scalar::all(128));
  ASSERT_TRUE(cv::imwrite((images_ / "flat.png").string(), flat));
  fs::copy_file(scene / "view_0002.png", images_ / "view_0002_copy.png");
  WriteBytes(images_ / "junk.jpg", "junk");
  const fs::path out = dir_->path() / "new" / "nested" / "out";
  const ProcessResult result =
      Run({"reconstruct", "--images", images_.string(), "--output", out.string(), "--threads", "2",
           "--intrinsics", (scene / "K.txt").string()},
          300);
  ASSERT_TRUE(result.ExitedWith(0)) << result.err;
  ExpectOneWarningNaming(result.err, images_ / "junk.jpg", "not a PNG, JPEG, TIFF or BMP image");
  ExpectOneWarningNaming(result.err, images_ / "flat.png", "no features found");
  const nlohmann::json summary = nlohmann::json::parse(test::ReadBytes(out / "summary.json"));
  EXPECT_EQ(summary["images_total"], 6);
  EXPECT_EQ(summary["features"]["unreadable"], 1);
  std::map<std::string, bool> registered;
  for (const auto& image : summary["images"]) {
    registered[image["name"].get<std::string>()] = image["registered"].get<bool>();
    if (!image["registered"].get<bool>()) {
      EXPECT_FALSE(image["reason"].get<std::string>().empty());
    }
  }
  for (const char* name : {"view_0001.png", "view_0002.png", "view_0003.png", "view_0004.png"}) {
    EXPECT_TRUE(registered[name]) << name << "\n" << summary.dump(2);
  }
  EXPECT_FALSE(registered["flat.png"]);
  EXPECT_TRUE(fs::exists(out / "sparse" / "0" / "cameras.bin"));
  EXPECT_TRUE(fs::exists(out / "sparse" / "0" / "points3D.txt"));
  test::ExpectNoTemporaryFiles(out);
}

// ---------------------------------------------------------------------------------------
// Output folders.

TEST_F(BadInputTest, OutputFolderThatCannotBeCreatedFailsBeforeAnyWork) {
  CopyViews(2);
  WriteBytes(dir_->path() / "a_file", "not a folder\n");
  const fs::path out = dir_->path() / "a_file" / "out";
  const ProcessResult result =
      Run({"reconstruct", "--images", images_.string(), "--output", out.string()});
  ExpectFailsWithOneLineError(result, out.string(), "cannot create output folder");
  // The same for an output path that is an existing file.
  const ProcessResult onto_file = Run({"reconstruct", "--images", images_.string(), "--output",
                                       (dir_->path() / "a_file").string()});
  ExpectFailsWithOneLineError(onto_file, (dir_->path() / "a_file").string(),
                              "cannot create output folder");
  EXPECT_EQ(test::ReadBytes(dir_->path() / "a_file"), "not a folder\n");
}

TEST_F(BadInputTest, UnwritableOutputFolderFailsWithOneLine) {
  CopyViews(2);
  const std::optional<fs::path> unwritable = test::UnwritableFolder(*dir_);
  if (!unwritable) GTEST_SKIP() << "no read-only folder for root";
  const fs::path parent = *unwritable;
  // The output folder exists but is read-only: the run's lock file, the first thing it
  // writes there, cannot be created.
  const ProcessResult existing =
      Run({"reconstruct", "--images", images_.string(), "--output", parent.string()});
  ExpectFailsWithOneLineError(existing, (parent / ".parallax.lock").string(),
                              "cannot create the lock file");
  // It does not exist and cannot be created.
  const fs::path out = parent / "parallax_out";
  const ProcessResult missing =
      Run({"reconstruct", "--images", images_.string(), "--output", out.string()});
  ExpectFailsWithOneLineError(missing, out.string(), "cannot create output folder");
}

// ---------------------------------------------------------------------------------------
// Intrinsics files: refused before anything is created, the error names the file.

TEST_F(BadInputTest, MalformedIntrinsicsFailBeforeCreatingAnything) {
  CopyViews(2);
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"", "found 0 numbers"},
      {"1520.4 0 302.32\n0 1525.9 246.87\n", "expected a 3x3 matrix (9 numbers), found 6"},
      {"1520.4 0 302.32\n0 1525.9 246.87\n0 0 1 7\n", "found 10 numbers"},
      {"1520.4 0 302.32\n0 f 246.87\n0 0 1\n", "'f' is not a number"},
      {"1520.4 0 302.32\n0 1525.9 246.87\n0 0 nan\n", "'nan' is not a number"},
      {"1520.4 0 302.32\n0 1525.9 246.87\n0 0 1e999\n", "'1e999' is not a number"},
      {"1520.4 0 0\n0 1525.9 0\n302.32 246.87 1\n", "not a calibration matrix"},
      {"-1520.4 0 302.32\n0 1525.9 246.87\n0 0 1\n", "focal lengths must be positive"},
      {"\xff\xfe\x00\x01 binary", "is not a number"},
  };
  for (size_t k = 0; k < cases.size(); ++k) {
    const fs::path K = dir_->path() / ("intrinsics_" + std::to_string(k) + ".txt");
    WriteBytes(K, cases[k].first);
    const ProcessResult result = Reconstruct({"--intrinsics", K.string()});
    ExpectFailsWithOneLineError(result, K.string(), cases[k].second);
    EXPECT_FALSE(fs::exists(Out())) << cases[k].first;
  }
  const fs::path missing = dir_->path() / "no_K.txt";
  ExpectFailsWithOneLineError(Reconstruct({"--intrinsics", missing.string()}), missing.string(),
                              "cannot open");
  // A camera.json where K.txt is expected, and a malformed one: named, not crashed on.
  const fs::path json = dir_->path() / "camera.json";
  WriteBytes(json, "{\"model\": \"OPENCV\", \"width\": 320, \"height\": 240, \"fx\": [}");
  ExpectFailsWithOneLineError(Reconstruct({"--intrinsics", json.string()}), json.string(), "");
  EXPECT_FALSE(fs::exists(Out()));
}

TEST_F(BadInputTest, MalformedCameraJsonFailsBeforeCreatingAnything) {
  CopyViews(2);
  const std::string fields =
      "\"width\": 320, \"height\": 240, \"fx\": 288, \"fy\": 288, \"cx\": 160, \"cy\": 120, "
      "\"k1\": 0, \"k2\": 0, \"p1\": 0, \"p2\": 0";
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"", "not valid JSON"},
      {"{\"model\": \"OPENCV\", " + fields, "not valid JSON"},
      {"[1, 2, 3]", "expected a JSON object"},
      {"{\"model\": \"PINHOLE\", " + fields + "}", "model \"PINHOLE\" is not supported"},
      {"{\"model\": \"OPENCV\", " + Replace(fields, "\"fx\": 288, ", "") + "}",
       "missing field \"fx\""},
      {"{\"model\": \"OPENCV\", " + Replace(fields, "\"fx\": 288", "\"fx\": \"288\"") + "}",
       "field \"fx\" is not a number"},
      {"{\"model\": \"OPENCV\", " + Replace(fields, "\"fy\": 288", "\"fy\": -288") + "}",
       "focal lengths fx and fy must be positive"},
      {"{\"model\": \"OPENCV\", " + Replace(fields, "\"width\": 320", "\"width\": 0") + "}",
       "width and height must be positive"},
      {"{\"model\": \"OPENCV\", " + Replace(fields, "\"height\": 240", "\"height\": 1e400") + "}",
       "not valid JSON"},
      {"{\"model\": \"OPENCV\", \"k3\": 0.5, " + fields + "}", "has no k3"},
  };
  for (size_t k = 0; k < cases.size(); ++k) {
    const fs::path json = dir_->path() / ("camera_" + std::to_string(k) + ".json");
    WriteBytes(json, cases[k].first);
    SCOPED_TRACE(cases[k].first);
    ExpectFailsWithOneLineError(Reconstruct({"--camera", json.string()}), json.string(),
                                cases[k].second);
    EXPECT_FALSE(fs::exists(Out()));
  }
  const fs::path missing = dir_->path() / "no_camera.json";
  ExpectFailsWithOneLineError(Reconstruct({"--camera", missing.string()}), missing.string(),
                              "cannot open");
  // Two sources of intrinsics at once.
  const fs::path json = dir_->path() / "camera.json";
  WriteBytes(json, "{\"model\": \"OPENCV\", " + fields + "}");
  const ProcessResult both = Reconstruct(
      {"--camera", json.string(), "--intrinsics", (scene_dir_->path() / "K.txt").string()});
  EXPECT_EQ(both.signal, 0);
  EXPECT_NE(both.exit_code, 0);
  EXPECT_NE(both.err.find("--intrinsics excludes --camera"), std::string::npos) << both.err;
  EXPECT_FALSE(fs::exists(Out()));
}

TEST_F(BadInputTest, CameraJsonOfAnotherImageSizeSkipsThoseImages) {
  CopyViews(2);
  cv::Mat half;
  cv::resize(cv::imread(SceneView(3).string()), half, cv::Size(160, 120), 0, 0, cv::INTER_AREA);
  ASSERT_TRUE(cv::imwrite((images_ / "z_small.png").string(), half));
  const fs::path json = dir_->path() / "camera.json";
  WriteBytes(json,
             "{\"model\": \"OPENCV\", \"width\": 320, \"height\": 240, \"fx\": 288, \"fy\": 288, "
             "\"cx\": 160, \"cy\": 120, \"k1\": 0, \"k2\": 0, \"p1\": 0, \"p2\": 0}");
  const ProcessResult result = Features({"--camera", json.string()});
  ASSERT_TRUE(result.ExitedWith(0)) << result.err;
  ExpectOneWarningNaming(result.err, images_ / "z_small.png", "160x120");
  parallax::Database database(Database());
  EXPECT_EQ(database.NumImages(), 2u);
  EXPECT_EQ(database.NumCameras(), 1u);
}

TEST_F(BadInputTest, WrongNumberOfCameraParamsFailsBeforeAnyWork) {
  CopyViews(2);
  const ProcessResult result =
      Reconstruct({"--camera-model", "PINHOLE", "--camera-params", "300,300,160"});
  ExpectFailsWithOneLineError(result, "--camera-params", "3 values, but PINHOLE takes 4");
  EXPECT_FALSE(fs::exists(Out()));
  const ProcessResult unknown = Reconstruct({"--camera-model", "FISHEYE_42"});
  ExpectFailsWithOneLineError(unknown, "--camera-model", "unknown camera model");
}

}  // namespace
}  // namespace parallax
