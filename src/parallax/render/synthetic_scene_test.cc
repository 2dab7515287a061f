#include "parallax/render/synthetic_scene.h"

#include <gtest/gtest.h>

#include "parallax/util/eigen_matchers.h"

#include <unistd.h>
#include <filesystem>
#include <fstream>
#include <opencv2/imgcodecs.hpp>
#include <sstream>

#include "parallax/calibration/exif.h"
#include "parallax/render/covisibility.h"
#include "parallax/render/hard_layouts.h"
#include "parallax/scene/colmap_io.h"
#include "parallax/util/check.h"
#include "parallax/util/file.h"

namespace parallax {
namespace {

using test::EigenMatrixNear;

using Layout = SyntheticSceneOptions::Layout;

class SyntheticSceneTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = std::filesystem::temp_directory_path() /
           ("parallax_synthetic_scene_test_" + std::to_string(::getpid()));
    std::filesystem::remove_all(dir_);
  }
  void TearDown() override { std::filesystem::remove_all(dir_); }
  std::filesystem::path dir_;
};

TEST(SyntheticSceneViews, EveryLayoutLooksAtTheScene) {
  for (const Layout layout : {Layout::kRing, Layout::kHemisphere, Layout::kSequence}) {
    SyntheticSceneOptions options;
    options.layout = layout;
    options.num_views = 40;
    const Reconstruction views = SyntheticSceneViews(options);
    ASSERT_EQ(views.NumRegImages(), 40u);
    const Camera& camera = views.GetCamera(1);
    EXPECT_EQ(camera.ModelName(), "PINHOLE");
    EXPECT_DOUBLE_EQ(camera.FocalLengthX(), 576.0);
    EXPECT_EQ(views.GetImage(1).name, "view_0001.png");
    EXPECT_EQ(views.GetImage(40).name, "view_0040.png");
    const SceneModel scene(SyntheticSceneModelOptions(options));
    double max_step = 0;
    for (const auto& [image_id, image] : views.Images()) {
      // The ray through the image centre hits a temple or the plaza near one.
      SurfaceHit hit;
      const Eigen::Vector3d direction = image.ViewingDirection();
      ASSERT_TRUE(scene.Intersect(image.ProjectionCenter(), direction, 1e9, &hit));
      EXPECT_LT(hit.distance, 40.0);
      EXPECT_GT(image.ProjectionCenter().z(), 1.0);
      if (image_id > 1) {
        max_step = std::max(
            max_step,
            (image.ProjectionCenter() - views.GetImage(image_id - 1).ProjectionCenter()).norm());
      }
    }
    // Consecutive views stay close, so that sequential matching works.
    EXPECT_LT(max_step, layout == Layout::kSequence ? 1.5 : 7.0);
  }
}

TEST(SyntheticSceneViews, LongSequencesWalkPastARowOfTemples) {
  SyntheticSceneOptions options;
  options.layout = Layout::kSequence;
  options.num_views = 500;
  EXPECT_GE(SyntheticSceneModelOptions(options).num_temples, 15);
  const Reconstruction views = SyntheticSceneViews(options);
  const double length =
      (views.GetImage(500).ProjectionCenter() - views.GetImage(1).ProjectionCenter()).norm();
  EXPECT_GT(length, 250.0);
}

// Whether the point projects into the view, in front of it.
bool InView(const Reconstruction& views, const Image& image, const Eigen::Vector3d& point) {
  const Eigen::Vector3d point_in_cam = image.cam_from_world * point;
  if (point_in_cam.z() <= 0) return false;
  const Camera& camera = views.GetCamera(image.camera_id);
  const Eigen::Vector2d xy = camera.ImgFromCam(point_in_cam);
  return xy.x() >= 0 && xy.y() >= 0 && xy.x() < camera.width && xy.y() < camera.height;
}

TEST(SyntheticSceneViews, StreetWalksForwardAtEyeHeight) {
  SyntheticSceneOptions options;
  options.layout = Layout::kStreet;
  options.num_views = 30;
  const Reconstruction views = SyntheticSceneViews(options);
  ASSERT_EQ(views.NumRegImages(), 30u);
  const SceneModel scene(SyntheticSceneModelOptions(options));
  EXPECT_EQ(scene.Options().num_rows, 2);
  // The rows reach well past the last view.
  EXPECT_GT(scene.TempleCenter(scene.Options().num_temples - 1).x(),
            views.GetImage(30).ProjectionCenter().x() + 60.0);
  for (const auto& [image_id, image] : views.Images()) {
    const Eigen::Vector3d center = image.ProjectionCenter();
    EXPECT_NEAR(center.z(), 1.6, 0.2);
    EXPECT_NEAR(center.y(), 0.5 * scene.Options().row_spacing, 0.5);
    const Eigen::Vector3d direction = image.ViewingDirection();
    EXPECT_GT(direction.x(), 0.98);  // Forward, down the street.
    EXPECT_LT(direction.z(), 0.0);
    // Facades on both sides and the ground are in view: a temple of each row some way ahead.
    for (const int row : {0, 1}) {
      int num_seen = 0;
      for (int k = 0; k < scene.Options().num_temples; ++k) {
        const Eigen::Vector3d temple = scene.TempleCenter(row * scene.Options().num_temples + k);
        num_seen += InView(views, image, temple + Eigen::Vector3d(0, 0, 3));
      }
      EXPECT_GE(num_seen, 1) << image.name << " row " << row;
    }
    SurfaceHit hit;
    ASSERT_TRUE(scene.Intersect(center, direction, 1e9, &hit));
    EXPECT_EQ(hit.material, Material::kGround);
    if (image_id == 1) continue;
    // Consecutive views: about 1 m apart, mostly along the viewing direction.
    const Eigen::Vector3d step = center - views.GetImage(image_id - 1).ProjectionCenter();
    EXPECT_NEAR(step.norm(), 1.0, 0.4);
    EXPECT_GT(step.normalized().dot(direction), 0.85) << image.name;
  }
}

TEST(SyntheticSceneViews, TwinOrbitPassesBothIdenticalTemples) {
  SyntheticSceneOptions options;
  options.layout = Layout::kTwin;
  options.num_views = 40;
  const Reconstruction views = SyntheticSceneViews(options);
  const SceneModel scene(SyntheticSceneModelOptions(options));
  ASSERT_EQ(scene.NumTemples(), 2);
  EXPECT_TRUE(scene.Options().identical_temples);
  const Eigen::Vector3d temple0 = scene.TempleCenter(0), temple1 = scene.TempleCenter(1);
  // Most views see one temple or the other; the few half way along the straight sides see
  // the ground between them.
  int num_seeing[2] = {0, 0}, num_seeing_none = 0;
  double max_step = 0;
  for (const auto& [image_id, image] : views.Images()) {
    const Eigen::Vector3d center = image.ProjectionCenter();
    const bool sees0 = InView(views, image, temple0 + Eigen::Vector3d(0, 0, 3));
    const bool sees1 = InView(views, image, temple1 + Eigen::Vector3d(0, 0, 3));
    num_seeing[0] += sees0;
    num_seeing[1] += sees1;
    num_seeing_none += !sees0 && !sees1;
    SurfaceHit hit;
    ASSERT_TRUE(scene.Intersect(center, image.ViewingDirection(), 1e9, &hit));
    EXPECT_LT(hit.distance, 40.0);
    if (image_id > 1) {
      max_step =
          std::max(max_step, (center - views.GetImage(image_id - 1).ProjectionCenter()).norm());
    }
  }
  EXPECT_GE(num_seeing[0], 15);
  EXPECT_GE(num_seeing[1], 15);
  EXPECT_LE(num_seeing_none, 8);
  EXPECT_LT(max_step, 7.0);
}

TEST(SyntheticSceneViews, WeakLayoutJoinsTwoPartsByAFewViews) {
  SyntheticSceneOptions options;
  options.layout = Layout::kWeak;
  options.num_views = 30;
  const Reconstruction views = SyntheticSceneViews(options);
  const SceneModel scene(SyntheticSceneModelOptions(options));
  ASSERT_EQ(scene.NumTemples(), 2);
  const int num_bridge = WeakBridgeViewCount(options.num_views);
  EXPECT_EQ(num_bridge, 3);
  // Views 1..14 orbit temple 0, 15..17 see both, 18..30 orbit temple 1.
  const auto part = [&](image_t image_id) {
    return image_id <= 14 ? 0 : (image_id <= 14 + static_cast<image_t>(num_bridge) ? 2 : 1);
  };
  for (const auto& [image_id, image] : views.Images()) {
    const bool sees0 = InView(views, image, scene.TempleCenter(0) + Eigen::Vector3d(0, 0, 3));
    const bool sees1 = InView(views, image, scene.TempleCenter(1) + Eigen::Vector3d(0, 0, 3));
    EXPECT_EQ(sees0, part(image_id) != 1) << image.name;
    EXPECT_EQ(sees1, part(image_id) != 0) << image.name;
  }
  // The ground truth view graph: no pair of views across the parts but through the bridge.
  CovisibilityOptions covisibility_options;
  covisibility_options.num_threads = 2;
  int num_bridged[2] = {0, 0};
  for (const CovisiblePair& pair : ComputeCovisiblePairs(scene, views, covisibility_options)) {
    const int part1 = part(pair.image_id1), part2 = part(pair.image_id2);
    EXPECT_FALSE(part1 + part2 == 1) << pair.image_id1 << " " << pair.image_id2;
    if (part1 == 2 && part2 != 2) ++num_bridged[part2];
    if (part2 == 2 && part1 != 2) ++num_bridged[part1];
  }
  EXPECT_GE(num_bridged[0], 1);
  EXPECT_GE(num_bridged[1], 1);
}

TEST(SyntheticSceneViews, DeterministicForASeed) {
  SyntheticSceneOptions options;
  options.layout = Layout::kHemisphere;
  options.seed = 3;
  const Reconstruction a = SyntheticSceneViews(options), b = SyntheticSceneViews(options);
  options.seed = 4;
  const Reconstruction c = SyntheticSceneViews(options);
  EXPECT_EQ(a.GetImage(7).cam_from_world.translation, b.GetImage(7).cam_from_world.translation);
  EXPECT_NE(a.GetImage(7).cam_from_world.translation, c.GetImage(7).cam_from_world.translation);
  options.lighting_variation = 1.0;
  EXPECT_NE(SyntheticSceneRenderOptions(options, 0).sun_direction,
            SyntheticSceneRenderOptions(options, 1).sun_direction);
  EXPECT_EQ(SyntheticSceneRenderOptions(options, 1).exposure,
            SyntheticSceneRenderOptions(options, 1).exposure);
  options.lighting_variation = 2.0;
  EXPECT_THROW(SyntheticSceneViews(options), CheckError);
  EXPECT_THROW(SyntheticSceneLayoutFromName("spiral"), InputError);
  EXPECT_EQ(SyntheticSceneLayoutFromName("street"), Layout::kStreet);
  EXPECT_EQ(SyntheticSceneLayoutFromName("twin"), Layout::kTwin);
  EXPECT_EQ(SyntheticSceneLayoutFromName("weak"), Layout::kWeak);
}

TEST_F(SyntheticSceneTest, WritesImagesAndExactCameras) {
  SyntheticSceneOptions options;
  options.num_views = 4;
  options.width = 160;
  options.height = 120;
  options.noise_stddev = 1.0;
  options.lighting_variation = 0.5;
  options.name = "temple";
  const Reconstruction views = GenerateSyntheticScene(options, dir_);
  ASSERT_EQ(views.NumImages(), 4u);
  for (const auto& [image_id, image] : views.Images()) {
    const cv::Mat decoded = cv::imread((dir_ / image.name).string(), cv::IMREAD_COLOR);
    ASSERT_FALSE(decoded.empty()) << image.name;
    EXPECT_EQ(decoded.size(), cv::Size(160, 120));
  }

  // Middlebury-style: count, then name K R t per line; K [R | t] must be the exact camera.
  const std::vector<std::string> lines = SplitLines(ReadFileToString(dir_ / "temple_par.txt"));
  ASSERT_GE(lines.size(), 5u);
  EXPECT_EQ(lines[0], "4");
  const Eigen::Matrix3d K_expected = views.GetCamera(1).CalibrationMatrix();
  for (size_t i = 1; i <= 4; ++i) {
    std::istringstream stream(lines[i]);
    std::string name;
    Eigen::Matrix3d K, R;
    Eigen::Vector3d t;
    stream >> name;
    for (int k = 0; k < 9; ++k) stream >> K(k / 3, k % 3);
    for (int k = 0; k < 9; ++k) stream >> R(k / 3, k % 3);
    stream >> t.x() >> t.y() >> t.z();
    ASSERT_FALSE(stream.fail()) << lines[i];
    const Image& image = views.GetImage(static_cast<image_t>(i));
    EXPECT_EQ(name, image.name);
    EXPECT_THAT(K, EigenMatrixNear(K_expected, 1e-12));
    EXPECT_THAT(R, EigenMatrixNear(image.cam_from_world.rotation.toRotationMatrix(), 1e-14));
    EXPECT_THAT(t, EigenMatrixNear(image.cam_from_world.translation, 1e-12));
  }
  std::istringstream k_file(ReadFileToString(dir_ / "K.txt"));
  Eigen::Matrix3d K;
  for (int k = 0; k < 9; ++k) k_file >> K(k / 3, k % 3);
  EXPECT_THAT(K, EigenMatrixNear(K_expected, 1e-12));

  // The COLMAP model reads back with the project's reader.
  const Reconstruction gt = ReadReconstruction(dir_ / "gt");
  EXPECT_EQ(gt.NumImages(), 4u);
  EXPECT_EQ(gt.NumPoints3D(), 0u);
  EXPECT_EQ(gt.GetCamera(1).params, views.GetCamera(1).params);
  for (const auto& [image_id, image] : views.Images()) {
    const Image& read = gt.GetImage(image_id);
    EXPECT_EQ(read.name, image.name);
    EXPECT_LT(RotationAngleDegrees(read.cam_from_world.rotation, image.cam_from_world.rotation),
              1e-9);
    EXPECT_THAT(read.cam_from_world.translation,
                EigenMatrixNear(image.cam_from_world.translation, 1e-12));
  }

  // The same options write the same bytes.
  const std::string first = ReadFileToString(dir_ / "view_0003.png");
  GenerateSyntheticScene(options, dir_);
  EXPECT_EQ(ReadFileToString(dir_ / "view_0003.png"), first);
}

}  // namespace
}  // namespace parallax

namespace parallax {
namespace {

TEST(SyntheticSceneViews, AerialSurveyFliesStripsOverTheTown) {
  SyntheticSceneOptions options;
  options.layout = SyntheticSceneOptions::Layout::kAerial;
  options.num_views = 120;
  options.oblique_fraction = 0.25;
  const Reconstruction views = SyntheticSceneViews(options);
  ASSERT_EQ(views.NumRegImages(), 120u);
  const SceneModel scene(SyntheticSceneModelOptions(options));
  EXPECT_EQ(scene.Options().kind, SceneModelOptions::Kind::kTown);
  int oblique = 0;
  std::vector<Eigen::Vector3d> centers;
  for (const auto& [image_id, image] : views.Images()) {
    EXPECT_EQ(image.name.substr(0, 4), "IMG_");
    const Eigen::Vector3d direction = image.ViewingDirection();
    EXPECT_LT(direction.z(), -0.8);  // Nadir or 30 degrees off it, with gimbal error.
    if (direction.z() > -0.95) ++oblique;
    EXPECT_NEAR(image.ProjectionCenter().z(), 60.0, 5.0);
    SurfaceHit hit;
    ASSERT_TRUE(scene.Intersect(image.ProjectionCenter(), direction, 1e9, &hit));
    centers.push_back(image.ProjectionCenter());
  }
  EXPECT_GT(oblique, 15);
  EXPECT_LT(oblique, 50);
  // Names say nothing about position: name order is not flight order.
  double step_sum = 0;
  for (size_t i = 1; i < centers.size(); ++i) step_sum += (centers[i] - centers[i - 1]).norm();
  EXPECT_GT(step_sum / (centers.size() - 1), 40.0);  // Flight order steps are 10 m.
}

TEST(SyntheticScene, AerialJpegsCarryExifFocalAndGps) {
  const std::filesystem::path dir = std::filesystem::temp_directory_path() /
                                    ("parallax_aerial_scene_test_" + std::to_string(::getpid()));
  std::filesystem::remove_all(dir);
  SyntheticSceneOptions options;
  options.layout = SyntheticSceneOptions::Layout::kAerial;
  options.num_views = 8;
  options.width = 160;
  options.height = 120;
  options.num_threads = 2;
  const Reconstruction views = GenerateSyntheticScene(options, dir);
  for (const auto& [image_id, image] : views.Images()) {
    const std::optional<ExifData> exif = ReadExif(dir / image.name);
    ASSERT_TRUE(exif.has_value()) << image.name;
    EXPECT_NEAR(*FocalLengthPixelsFromExif(*exif, 160, 120), 144.0, 0.01);
    ASSERT_TRUE(exif->gps_latitude && exif->gps_longitude && exif->gps_altitude);
    const Eigen::Vector3d enu = EnuFromGeodetic(
        {*exif->gps_latitude, *exif->gps_longitude, *exif->gps_altitude}, SyntheticSurveyOrigin());
    // 3 m of noise horizontally, 6 m vertically: well within 20 m.
    EXPECT_LT((enu - image.ProjectionCenter()).norm(), 20.0) << image.name;
    EXPECT_FALSE(cv::imread((dir / image.name).string()).empty());
  }
  std::ifstream pairs(dir / "gt" / "overlap_pairs.txt");
  std::string name1, name2;
  int shared = 0, count = 0;
  while (pairs >> name1 >> name2 >> shared) {
    EXPECT_LT(name1, name2);
    EXPECT_GE(shared, 30);
    EXPECT_TRUE(std::filesystem::exists(dir / name1));
    ++count;
  }
  EXPECT_GT(count, 0);
  std::filesystem::remove_all(dir);
}

// Any lens: the views are rendered through the model, the ground truth names it, EXIF tells
// its focal length, and no pinhole K.txt is written for a reconstruction to mistake.
TEST_F(SyntheticSceneTest, AFisheyeSceneCarriesItsModelAndExifFocal) {
  SyntheticSceneOptions options;
  options.num_views = 3;
  options.width = 160;
  options.height = 160;
  options.camera_model = CameraModelId::kOpenCVFisheye;
  options.field_of_view = 190;
  options.write_exif = true;
  options.num_threads = 2;
  const double focal = 80 / (95 * M_PI / 180);
  EXPECT_NEAR(options.EffectiveFocalLength(), focal, 1e-9);
  const Reconstruction views = GenerateSyntheticScene(options, dir_);
  EXPECT_FALSE(std::filesystem::exists(dir_ / "K.txt"));
  EXPECT_FALSE(std::filesystem::exists(dir_ / "synth_par.txt"));
  const Reconstruction gt = ReadReconstruction(dir_ / "gt");
  ASSERT_EQ(gt.NumCameras(), 1u);
  EXPECT_EQ(gt.GetCamera(1).model_id, CameraModelId::kOpenCVFisheye);
  EXPECT_NEAR(gt.GetCamera(1).FocalLengthX(), focal, 1e-9);
  for (const auto& [image_id, image] : views.Images()) {
    EXPECT_EQ(std::filesystem::path(image.name).extension(), ".jpg");
    const std::optional<ExifData> exif = ReadExif(dir_ / image.name);
    ASSERT_TRUE(exif.has_value()) << image.name;
    EXPECT_NEAR(*FocalLengthPixelsFromExif(*exif, 160, 160), focal, 0.01);
    EXPECT_FALSE(exif->gps_latitude.has_value());
  }
  // Parameters that do not fit the model, and a perspective field of view past 170, fail.
  options.camera_params = {100, 80, 80};
  EXPECT_THROW(options.Check(), InputError);
  options.camera_params.clear();
  options.camera_model = CameraModelId::kPinhole;
  EXPECT_THROW(options.Check(), InputError);
}

}  // namespace
}  // namespace parallax
