#include "parallax/report/html_report.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <regex>

#include "parallax/math/random.h"
#include "parallax/report/ground_truth.h"
#include "parallax/scene/synthetic_dataset.h"
#include "parallax/util/check.h"
#include "parallax/util/file.h"

namespace parallax {
namespace {

namespace fs = std::filesystem;

// A synthetic scene written out as a `parallax reconstruct` output would be: database,
// images, model, summary, and ground truth for the evaluation section.
class ReportFixture : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("parallax_html_report_test_" + std::to_string(getpid()));
    fs::remove_all(dir_);
    fs::create_directories(dir_ / "images");

    SyntheticDatasetOptions options;
    options.num_images = 10;
    options.num_points3D = 400;
    SynthesizeDataset(options, &truth_);
    database_ = std::make_unique<Database>(dir_ / "database.db");
    WriteSyntheticDatabase(truth_, database_.get());

    model_ = truth_;
    // Colour points by position so that the cloud shows on the dark 3D view.
    for (const auto& [point3D_id, point] : truth_.Points3D()) {
      const Eigen::Vector3d t = (point.xyz.array() + 1.0).matrix() * 0.5 * 255.0;
      model_.GetPoint3D(point3D_id).color = t.cwiseMax(40.0).cwiseMin(255.0).cast<uint8_t>();
    }
    unregistered_id_ = model_.RegImageIds().back();
    model_.DeRegisterImage(unregistered_id_);
    // Small pose errors, so that the ground-truth section has something to show.
    for (const image_t image_id : model_.RegImageIds()) {
      Rigid3d& cam_from_world = model_.GetImage(image_id).cam_from_world;
      const Eigen::Vector3d axis = Eigen::Vector3d::Random().normalized();
      const double angle = RandomUniformReal(0.0, 0.5) * M_PI / 180.0;
      cam_from_world.rotation =
          (Eigen::Quaterniond(Eigen::AngleAxisd(angle, axis)) * cam_from_world.rotation)
              .normalized();
      cam_from_world.translation += 0.02 * Eigen::Vector3d::Random();
    }

    // Images: a gradient with a dot at every keypoint.
    for (const auto& [image_id, image] : truth_.Images()) {
      cv::Mat pixels(options.height, options.width, CV_8UC3);
      for (int y = 0; y < pixels.rows; ++y) {
        for (int x = 0; x < pixels.cols; ++x) {
          pixels.at<cv::Vec3b>(y, x) = cv::Vec3b(90 + x / 8, 120, 80 + y / 6);
        }
      }
      for (const Point2D& point : image.points2D) {
        cv::circle(pixels, cv::Point(point.xy.x(), point.xy.y()), 3, cv::Scalar(255, 255, 255), -1);
      }
      cv::imwrite((dir_ / "images" / image.name).string(), pixels);
    }

    summary_ = {
        {"images_total", truth_.NumImages()},
        {"images_registered", model_.NumRegImages()},
        {"points3D", model_.NumPoints3D()},
        {"mean_track_length", model_.ComputeMeanTrackLength()},
        {"track_length_histogram",
         {{{"length", 2}, {"points", 40}},
          {{"length", 3}, {"points", 25}},
          {{"length", 5}, {"points", 7}}}},
        {"mean_reprojection_error_px", 0.42},
        {"timings_s", {{"features", 1.5}, {"matching", 2.25}, {"mapping", 3.0}, {"total", 6.9}}},
        {"models",
         {{{"path", "sparse/0"},
           {"images_registered", model_.NumRegImages()},
           {"points3D", model_.NumPoints3D()}}}}};
    for (const auto& [image_id, image] : model_.Images()) {
      nlohmann::json entry = {{"image_id", image_id},
                              {"name", image.name},
                              {"registered", image.registered},
                              {"num_keypoints", image.NumPoints2D()},
                              {"num_observations", image.num_points3D}};
      if (image.registered) {
        entry["reprojection_error_before_ba_px"] = 0.5 + 0.05 * image_id;
        entry["reprojection_error_after_ba_px"] = 0.3 + 0.01 * image_id;
      } else {
        entry["reprojection_error_before_ba_px"] = nullptr;
        entry["reprojection_error_after_ba_px"] = nullptr;
        entry["reason"] = "too few 2D-3D correspondences";
      }
      summary_["images"].push_back(entry);
    }

    GroundTruth gt;
    for (const auto& [image_id, image] : truth_.Images()) {
      gt.images.push_back({image.name, truth_.GetCamera(image.camera_id), image.cam_from_world});
    }
    evaluation_ = EvaluateReconstruction(model_, gt);
  }

  void TearDown() override {
    database_.reset();
    fs::remove_all(dir_);
  }

  HtmlReportInputs Inputs() const {
    HtmlReportInputs inputs;
    inputs.reconstruction = &model_;
    inputs.database = database_.get();
    inputs.image_dir = dir_ / "images";
    inputs.summary = summary_;
    inputs.evaluation = evaluation_;
    return inputs;
  }

  fs::path dir_;
  Reconstruction truth_;
  Reconstruction model_;
  image_t unregistered_id_ = kInvalidImageId;
  std::unique_ptr<Database> database_;
  nlohmann::json summary_;
  EvaluationMetrics evaluation_;
};

nlohmann::json EmbeddedData(const std::string& html) {
  const std::string open = "<script type=\"application/json\" id=\"report-data\">";
  const size_t begin = html.find(open);
  EXPECT_NE(begin, std::string::npos);
  const size_t end = html.find("</script>", begin);
  return nlohmann::json::parse(html.substr(begin + open.size(), end - begin - open.size()));
}

// Nothing is loaded from the network: no external scripts, styles, images or fonts.
void ExpectSelfContained(const std::string& html) {
  for (const char* pattern : {"src=\"http", "href=\"http", "src='http", "href='http", "url(http",
                              "@import", "<link rel=\"stylesheet\"", "<script src"}) {
    EXPECT_EQ(html.find(pattern), std::string::npos) << pattern;
  }
}

TEST_F(ReportFixture, EmbedsEveryDataSet) {
  const std::string html = BuildHtmlReport(Inputs());
  ExpectSelfContained(html);
  const nlohmann::json data = EmbeddedData(html);

  ASSERT_EQ(data["images"].size(), truth_.NumImages());
  size_t num_unregistered = 0;
  for (const auto& image : data["images"]) {
    if (!image["registered"].get<bool>()) {
      ++num_unregistered;
      EXPECT_EQ(image["reason"], "too few 2D-3D correspondences");
      EXPECT_TRUE(image["error_after_ba"].is_null());
    } else {
      EXPECT_GT(image["error_before_ba"].get<double>(), image["error_after_ba"].get<double>());
    }
    EXPECT_GT(image["keypoints"].get<long>(), 0);
  }
  EXPECT_EQ(num_unregistered, 1u);

  // One pair entry per matched pair, with the database's counts; the best pair is the one
  // with the most inliers.
  const auto geometries = database_->ReadTwoViewGeometryNumInliers();
  ASSERT_EQ(data["pairs"].size(), database_->NumMatchedPairs());
  long max_inliers = 0;
  for (const auto& [pair_id, num_inliers] : geometries)
    max_inliers = std::max<long>(max_inliers, num_inliers);
  long max_in_pairs = 0;
  for (const auto& pair : data["pairs"]) {
    EXPECT_GE(pair[2].get<long>(), pair[3].get<long>());
    max_in_pairs = std::max(max_in_pairs, pair[3].get<long>());
  }
  EXPECT_EQ(max_in_pairs, max_inliers);
  EXPECT_EQ(data["best_pair"]["num_inliers"].get<long>(), max_inliers);
  EXPECT_EQ(data["best_pair"]["lines"].size() % 4, 0u);
  EXPECT_GT(data["best_pair"]["lines"].size(), 0u);

  // Frames: embedded JPEGs at most 720 px wide, keypoints in original pixels.
  ASSERT_EQ(data["frames"]["keypoint_frames"].size(), 2u);
  for (const auto& frame : data["frames"]["list"]) {
    EXPECT_EQ(frame["url"].get<std::string>().rfind("data:image/jpeg;base64,", 0), 0u);
    EXPECT_EQ(frame["width"], 640);
    EXPECT_EQ(frame["height"], 480);
  }
  const auto& first = data["frames"]["list"][data["frames"]["keypoint_frames"][0].get<size_t>()];
  EXPECT_EQ(first["keypoints"].size(), 3 * first["num_keypoints"].get<size_t>());

  // Scene: every point and every registered camera.
  EXPECT_EQ(data["scene"]["num_points"], model_.NumPoints3D());
  EXPECT_EQ(data["scene"]["cameras"].size(), model_.NumRegImages());
  EXPECT_EQ(data["scene"]["points"].get<std::string>().size(),
            (model_.NumPoints3D() * 12 + 2) / 3 * 4);
  EXPECT_EQ(data["evaluation"]["images_registered_in_gt"], model_.NumRegImages());
  EXPECT_EQ(data["summary"]["timings_s"]["mapping"], 3.0);
}

TEST_F(ReportFixture, WorksWithTheModelAlone) {
  HtmlReportInputs inputs;
  inputs.reconstruction = &model_;
  const std::string html = BuildHtmlReport(inputs);
  const nlohmann::json data = EmbeddedData(html);
  EXPECT_FALSE(data["has_database"].get<bool>());
  EXPECT_TRUE(data["pairs"].empty());
  EXPECT_TRUE(data["best_pair"].is_null());
  EXPECT_TRUE(data["evaluation"].is_null());
  // Keypoints come from the model's points2D; no image file, so no picture.
  const auto& frame = data["frames"]["list"][0];
  EXPECT_EQ(frame["url"], "");
  EXPECT_EQ(frame["width"], 640);
  EXPECT_GT(frame["num_keypoints"].get<size_t>(), 0u);
  // Errors after BA come from the model when summary.json is missing.
  for (const auto& image : data["images"]) {
    EXPECT_EQ(image["error_after_ba"].is_null(), !image["registered"].get<bool>());
  }
}

TEST_F(ReportFixture, EscapesNamesThatCouldCloseTheScript) {
  HtmlReportInputs inputs = Inputs();
  inputs.title = "evil </script><script>alert(1)</script>";
  const std::string html = BuildHtmlReport(inputs);
  EXPECT_EQ(html.find("<script>alert(1)"), std::string::npos);
  EXPECT_EQ(EmbeddedData(html)["title"], inputs.title);
  EXPECT_NE(html.find("<title>evil &lt;/script&gt;"), std::string::npos);
}

TEST_F(ReportFixture, WritesTheFile) {
  const fs::path path = dir_ / "report.html";
  WriteHtmlReport(Inputs(), path);
  const std::string html = ReadFileToString(path);
  EXPECT_EQ(html.rfind("<!DOCTYPE html>", 0), 0u);
  EXPECT_NE(html.find("</html>"), std::string::npos);
  EXPECT_THROW(WriteHtmlReport(Inputs(), dir_ / "missing" / "report.html"), InputError);
}

// Chromium from $PARALLAX_CHROMIUM or the PATH; empty when there is none.
std::string FindChromium() {
  if (const char* path = std::getenv("PARALLAX_CHROMIUM")) return path;
  for (const char* name : {"chromium", "chromium-browser", "google-chrome"}) {
    if (std::system(("command -v " + std::string(name) + " >/dev/null 2>&1").c_str()) == 0)
      return name;
  }
  return "";
}

// Where the test binary lives (the build folder): the pages and screenshots stay there.
fs::path OutputFolder() {
  std::error_code error;
  const fs::path executable = fs::read_symlink("/proc/self/exe", error);
  return error ? fs::temp_directory_path() : executable.parent_path();
}

// The scene framing on real cameras: the templeRing ground truth (a ring of 47 views, 16 of
// them upside down) with points filling the temple's bounding box.
TEST(HtmlReport, FramesTheTempleRing) {
  const fs::path data = DataRoot() / "templeRing";
  if (!fs::exists(data / "templeR_par.txt")) GTEST_SKIP() << data << " missing";
  const GroundTruth gt = ReadGroundTruth(data / "templeR_par.txt");
  Reconstruction model;
  Camera camera = gt.images[0].camera;
  camera.camera_id = 1;
  camera.width = 640;
  camera.height = 480;
  model.AddCamera(camera);
  for (size_t i = 0; i < gt.images.size(); ++i) {
    Image image;
    image.image_id = static_cast<image_t>(i + 1);
    image.camera_id = 1;
    image.name = gt.images[i].name;
    image.cam_from_world = gt.images[i].cam_from_world;
    model.AddImage(image);
    model.RegisterImage(image.image_id);
  }
  const Eigen::Vector3d box_min(-0.023121, -0.038009, -0.091940),
      box_max(0.078626, 0.121636, -0.017395);
  for (int i = 0; i < 3000; ++i) {
    const Eigen::Vector3d t(RandomUniformReal(0, 1), RandomUniformReal(0, 1),
                            RandomUniformReal(0, 1));
    const Eigen::Vector3d xyz = box_min + t.cwiseProduct(box_max - box_min);
    model.AddPoint3D(xyz, Track(), (Eigen::Vector3d(200, 170, 120) + 55 * t).cast<uint8_t>());
  }
  HtmlReportInputs inputs;
  inputs.title = "templeRing ground truth";
  inputs.reconstruction = &model;
  inputs.image_dir = data / "images";
  const std::string html = BuildHtmlReport(inputs);
  const nlohmann::json scene = EmbeddedData(html)["scene"];
  const Eigen::Vector3d up(scene["up"][0], scene["up"][1], scene["up"][2]);
  const Eigen::Vector3d forward(scene["forward"][0], scene["forward"][1], scene["forward"][2]);
  EXPECT_NEAR(up.norm(), 1.0, 1e-9);
  EXPECT_NEAR(forward.norm(), 1.0, 1e-9);
  EXPECT_NEAR(up.dot(forward), 0.0, 1e-9);
  // The images are turned by 90 degrees, so their "up" axes cancel out; up is then the axis
  // of the ring of cameras (every centre at about the same height) on the side the cameras
  // look down from: world +y, along which the temple's columns stand (the bounding box's
  // longest side).
  EXPECT_GT(up.y(), 0.99);
  double min_height = 1e9, max_height = -1e9;
  for (const GroundTruthImage& image : gt.images) {
    const double height = up.dot(ProjectionCenter(image.cam_from_world));
    min_height = std::min(min_height, height);
    max_height = std::max(max_height, height);
  }
  EXPECT_LT(max_height - min_height, 0.1 * scene["radius"].get<double>());
  // The views embed the real pictures.
  for (const auto& frame : EmbeddedData(html)["frames"]["list"]) {
    EXPECT_EQ(frame["url"].get<std::string>().rfind("data:image/jpeg;base64,", 0), 0u);
  }
  // For a human: the same page as rendered by a browser.
  const std::string chromium = FindChromium();
  if (chromium.empty()) return;
  const fs::path html_path = OutputFolder() / "html_report_temple.html";
  WriteHtmlReport(inputs, html_path);
  const fs::path png_path = OutputFolder() / "html_report_temple.png";
  const std::string command =
      "timeout 180 " + chromium +
      " --headless --no-sandbox --disable-gpu --enable-unsafe-swiftshader --hide-scrollbars"
      " --user-data-dir=" +
      (fs::temp_directory_path() / ("parallax_chromium_" + std::to_string(getpid()))).string() +
      " --window-size=1400,2000 --screenshot=" + png_path.string() + " file://" +
      fs::absolute(html_path).string() + " > /dev/null 2>&1";
  EXPECT_EQ(std::system(command.c_str()), 0);
  fs::remove_all(fs::temp_directory_path() / ("parallax_chromium_" + std::to_string(getpid())));
}

// The browser test: the page must run without any error, draw the 3D view, and look right
// (the screenshot is kept under the build folder for a human to see).
TEST_F(ReportFixture, RunsInHeadlessChromiumWithoutErrors) {
  const std::string chromium = FindChromium();
  if (chromium.empty()) GTEST_SKIP() << "chromium is not installed";
  const fs::path out = OutputFolder();
  const fs::path html_path = out / "html_report_test.html";
  const fs::path png_path = out / "html_report_test.png";
  WriteHtmlReport(Inputs(), html_path);

  const std::string flags =
      " --headless --no-sandbox --disable-gpu --enable-unsafe-swiftshader --no-first-run"
      " --disable-dev-shm-usage --hide-scrollbars --enable-logging=stderr --v=0"
      " --virtual-time-budget=5000 --user-data-dir=" +
      (dir_ / "profile").string();
  const fs::path dom_path = dir_ / "dom.html", log_path = dir_ / "chromium.log";
  const std::string url = "file://" + fs::absolute(html_path).string();
  ASSERT_EQ(std::system(("timeout 180 " + chromium + flags + " --dump-dom " + url +
                         "?selftest=1 > " + dom_path.string() + " 2> " + log_path.string())
                            .c_str()),
            0)
      << ReadFileToString(log_path);
  const std::string dom = ReadFileToString(dom_path);
  std::smatch match;
  ASSERT_TRUE(std::regex_search(dom, match, std::regex("id=\"report-status\"[^>]*>([^<]*)<")));
  EXPECT_EQ(match[1].str(), "ok");
  ASSERT_TRUE(std::regex_search(dom, match, std::regex("id=\"report-pixels\"[^>]*>([^<]*)<")));
  // The 3D view drew the cloud, frustums and trajectory over a good part of the canvas.
  EXPECT_GT(std::stol(match[1].str()), 2000) << "3D view looks empty";
  // The page logs nothing at all; the browser's own performance notes about software
  // WebGL are the only console lines allowed.
  for (const std::string& line : SplitLines(ReadFileToString(log_path))) {
    if (line.find(":CONSOLE") == std::string::npos) continue;
    EXPECT_NE(line.find("GL Driver Message"), std::string::npos) << line;
  }
  // Every section was built.
  for (const char* id : {"overview", "scene", "features", "matching", "reprojection", "evaluation",
                         "timings", "images"}) {
    EXPECT_NE(dom.find("id=\"" + std::string(id) + "\""), std::string::npos) << id;
  }
  EXPECT_NE(dom.find("Track lengths"), std::string::npos);

  fs::remove(png_path);
  ASSERT_EQ(std::system(("timeout 180 " + chromium + flags +
                         " --window-size=1400,7000 --screenshot=" + png_path.string() + " " + url +
                         " > /dev/null 2>&1")
                            .c_str()),
            0);
  ASSERT_TRUE(fs::exists(png_path));
  EXPECT_GT(fs::file_size(png_path), 50000u);
  std::cerr << "screenshot: " << png_path.string() << "\n";
}

}  // namespace
}  // namespace parallax
