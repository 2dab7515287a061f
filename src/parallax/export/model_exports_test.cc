#include "parallax/export/model_exports.h"

#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <sstream>

#include "parallax/export/model_export_format.h"
#include "parallax/export/test_models.h"
#include "parallax/util/check.h"
#include "parallax/util/file.h"
#include "parallax/util/test_dir.h"

namespace parallax {
namespace {

namespace fs = std::filesystem;
using test::BarrelCamera;
using test::ExactModel;

// OPENCV's projection with nerfstudio's parameter names.
Eigen::Vector2d ProjectOpenCv(const nlohmann::json& intrinsics, const Eigen::Vector3d& in_cam) {
  const double u = in_cam.x() / in_cam.z(), v = in_cam.y() / in_cam.z();
  const double k1 = intrinsics["k1"], k2 = intrinsics["k2"];
  const double p1 = intrinsics["p1"], p2 = intrinsics["p2"];
  const double r2 = u * u + v * v, radial = k1 * r2 + k2 * r2 * r2;
  const double du = u * radial + 2 * p1 * u * v + p2 * (r2 + 2 * u * u);
  const double dv = v * radial + 2 * p2 * u * v + p1 * (r2 + 2 * v * v);
  return {intrinsics["fl_x"].get<double>() * (u + du) + intrinsics["cx"].get<double>(),
          intrinsics["fl_y"].get<double>() * (v + dv) + intrinsics["cy"].get<double>()};
}

// Every observation reprojected through the exported cameras: the model's own error.
TEST(Nerfstudio, CamerasReprojectWithTheModelsErrors) {
  const test::ScopedTestDir dir("nerfstudio");
  const Reconstruction model = ExactModel();
  WriteNerfstudio(model, dir.path() / "transforms.json");
  const nlohmann::json transforms =
      nlohmann::json::parse(ReadFileToString(dir.path() / "transforms.json"));
  EXPECT_EQ(transforms["camera_model"], "OPENCV");
  EXPECT_EQ(transforms["w"], 640);
  EXPECT_DOUBLE_EQ(transforms["k1"].get<double>(), -0.2);
  EXPECT_TRUE(fs::exists(dir.path() / transforms["ply_file_path"].get<std::string>()));
  ASSERT_EQ(transforms["frames"].size(), 3u);
  size_t checked = 0;
  for (const nlohmann::json& frame : transforms["frames"]) {
    const image_t image_id = frame["colmap_im_id"];
    EXPECT_EQ(frame["file_path"], "images/" + model.GetImage(image_id).name);
    Eigen::Matrix4d cam_to_world;
    for (int r = 0; r < 4; ++r) {
      for (int c = 0; c < 4; ++c) cam_to_world(r, c) = frame["transform_matrix"][r][c];
    }
    cam_to_world.block<3, 2>(0, 1) *= -1;  // OpenGL axes back to OpenCV's.
    const Eigen::Matrix4d world_to_cam = cam_to_world.inverse();
    const Image& image = model.GetImage(image_id);
    for (const Point2D& point2D : image.points2D) {
      if (!point2D.HasPoint3D()) continue;
      const Eigen::Vector3d xyz = model.GetPoint3D(point2D.point3D_id).xyz;
      const Eigen::Vector3d in_cam = (world_to_cam * xyz.homogeneous()).head<3>();
      const double error = (ProjectOpenCv(transforms, in_cam) - point2D.xy).norm();
      const point2D_t idx = static_cast<point2D_t>(&point2D - image.points2D.data());
      EXPECT_NEAR(error, model.ReprojectionError(image_id, idx), 1e-9);
      ++checked;
    }
  }
  EXPECT_EQ(checked, 120u);
}

TEST(Nerfstudio, IntrinsicsPerFrameWhenImagesHaveTheirOwnCameras) {
  Reconstruction model = ExactModel();
  Camera second = BarrelCamera();
  second.camera_id = 2;
  second.params[0] = 510;
  model.AddCamera(second);
  model.GetImage(3).camera_id = 2;
  const nlohmann::json transforms = NerfstudioTransforms(model, {.image_prefix = "rgb/"});
  EXPECT_FALSE(transforms.contains("fl_x"));
  EXPECT_EQ(transforms["frames"][2]["fl_x"], 510.0);
  EXPECT_EQ(transforms["frames"][0]["fl_x"], 500.0);
  EXPECT_EQ(transforms["frames"][0]["file_path"], "rgb/view1.png");
}

// Reads the PLY header's element counts and the vertex records.
struct PlyContents {
  size_t num_vertices = 0, num_edges = 0;
  std::vector<Eigen::Vector3f> vertices;
  std::vector<std::array<int32_t, 2>> edges;
};

PlyContents ReadPly(const fs::path& path) {
  std::ifstream stream(path, std::ios::binary);
  PlyContents ply;
  std::string line;
  while (std::getline(stream, line) && line != "end_header") {
    std::istringstream words(line);
    std::string keyword, element;
    size_t count = 0;
    if (words >> keyword >> element >> count && keyword == "element") {
      (element == "vertex" ? ply.num_vertices : ply.num_edges) = count;
    }
  }
  for (size_t i = 0; i < ply.num_vertices; ++i) {
    Eigen::Vector3f xyz;
    uint8_t rgb[3];
    stream.read(reinterpret_cast<char*>(xyz.data()), 12);
    stream.read(reinterpret_cast<char*>(rgb), 3);
    ply.vertices.push_back(xyz);
  }
  for (size_t i = 0; i < ply.num_edges; ++i) {
    std::array<int32_t, 2> edge;
    uint8_t rgb[3];
    stream.read(reinterpret_cast<char*>(edge.data()), 8);
    stream.read(reinterpret_cast<char*>(rgb), 3);
    ply.edges.push_back(edge);
  }
  EXPECT_TRUE(stream.good());
  return ply;
}

// A fisheye goes out as nerfstudio's OPENCV_FISHEYE with k1..k4, and nerfstudio's fisheye
// projection (OpenCV's: theta (1 + k1 theta^2 + ... + k4 theta^8) from the axis) puts every
// observation where the model does; the sphere as EQUIRECTANGULAR; a lens no format in the
// family describes is a one-line error naming it.
TEST(Nerfstudio, FisheyeAndSphericalCamerasKeepTheirModels) {
  Camera fisheye = Camera::Create(1, CameraModelId::kOpenCVFisheye, 250, 640, 480);
  fisheye.params = {250, 252, 321, 239, 0.03, -0.01, 0.002, -0.0003};
  const Reconstruction model = ExactModel(fisheye);
  const nlohmann::json transforms = NerfstudioTransforms(model, {});
  EXPECT_EQ(transforms["camera_model"], "OPENCV_FISHEYE");
  EXPECT_FALSE(transforms.contains("p1"));
  size_t checked = 0;
  for (const nlohmann::json& frame : transforms["frames"]) {
    const Image& image = model.GetImage(frame["colmap_im_id"].get<image_t>());
    for (const Point2D& point2D : image.points2D) {
      if (!point2D.HasPoint3D()) continue;
      const Eigen::Vector3d in_cam =
          image.cam_from_world * model.GetPoint3D(point2D.point3D_id).xyz;
      const double r = in_cam.head<2>().norm(), theta = std::atan2(r, in_cam.z());
      const double t2 = theta * theta;
      const double theta_d = theta * (1 + transforms["k1"].get<double>() * t2 +
                                      transforms["k2"].get<double>() * t2 * t2 +
                                      transforms["k3"].get<double>() * t2 * t2 * t2 +
                                      transforms["k4"].get<double>() * t2 * t2 * t2 * t2);
      const Eigen::Vector2d xy(transforms["fl_x"].get<double>() * theta_d * in_cam.x() / r +
                                   transforms["cx"].get<double>(),
                               transforms["fl_y"].get<double>() * theta_d * in_cam.y() / r +
                                   transforms["cy"].get<double>());
      EXPECT_LT((xy - fisheye.ImgFromCam(in_cam)).norm(), 1e-9);
      ++checked;
    }
  }
  EXPECT_GT(checked, 20u);

  const Reconstruction sphere =
      ExactModel(Camera::Create(1, CameraModelId::kEquirectangular, 0, 2048, 1024));
  const nlohmann::json equirect = NerfstudioTransforms(sphere, {});
  EXPECT_EQ(equirect["camera_model"], "EQUIRECTANGULAR");
  EXPECT_EQ(equirect["w"], 2048);
  EXPECT_DOUBLE_EQ(equirect["cx"].get<double>(), 1024);
  try {
    WriteNvm(sphere, test::ScopedTestDir("nvm_sphere").path() / "model.nvm");
    ADD_FAILURE() << "a sphere was exported to NVM";
  } catch (const InputError& error) {
    // No advice to undistort: undistort refuses the sphere too.
    EXPECT_EQ(std::string(error.what()).find("undistort"), std::string::npos) << error.what();
  }

  Camera fov = Camera::Create(1, CameraModelId::kFOV, 500, 640, 480);
  const Reconstruction fov_model = ExactModel(fov);
  try {
    NerfstudioTransforms(fov_model, {});
    ADD_FAILURE() << "a FOV camera was exported to nerfstudio";
  } catch (const InputError& error) {
    EXPECT_NE(std::string(error.what()).find("camera 1 is FOV"), std::string::npos) << error.what();
  }
  const test::ScopedTestDir dir("bundler_fisheye");
  EXPECT_THROW(WriteBundler(model, dir.path() / "bundle.out", dir.path() / "list.txt"), InputError);
  EXPECT_THROW(WriteNvm(model, dir.path() / "model.nvm"), InputError);
}

TEST(PlyWithCameras, PointsThenAFrustumPerCamera) {
  const test::ScopedTestDir dir("ply_cameras");
  const Reconstruction model = ExactModel();
  WritePlyWithCameras(model, dir.path() / "model.ply", 2.0);
  const PlyContents ply = ReadPly(dir.path() / "model.ply");
  ASSERT_EQ(ply.num_vertices, 40u + 3 * 5);
  ASSERT_EQ(ply.num_edges, 3u * 8);
  EXPECT_TRUE(ply.vertices[0].isApprox(model.Points3D().begin()->second.xyz.cast<float>()));
  for (image_t image_id = 1; image_id <= 3; ++image_id) {
    const Image& image = model.GetImage(image_id);
    const size_t centre = 40 + 5 * (image_id - 1);
    EXPECT_TRUE(ply.vertices[centre].isApprox(image.ProjectionCenter().cast<float>(), 1e-6f));
    // The corners lie at depth 2 in front of the camera.
    for (size_t corner = 1; corner <= 4; ++corner) {
      const Eigen::Vector3d in_cam =
          image.cam_from_world * ply.vertices[centre + corner].cast<double>();
      EXPECT_NEAR(in_cam.z(), 2.0, 1e-5);
    }
  }
  for (const auto& edge : ply.edges) {
    EXPECT_GE(edge[0], 40);
    EXPECT_LT(edge[1], 55);
  }
}

// Bundler's projection as its documentation gives it: P = R X + t, p = -P / P.z,
// p' = f (1 + k1 |p|^2 + k2 |p|^4) p, pixels from the image centre with y up.
TEST(Bundler, ViewsReprojectByBundlersPublishedModel) {
  const test::ScopedTestDir dir("bundler");
  const Reconstruction model = ExactModel();
  WriteBundler(model, dir.path() / "bundle.out", dir.path() / "list.txt");
  EXPECT_EQ(ReadFileToString(dir.path() / "list.txt"), "view1.png\nview2.png\nview3.png\n");
  std::istringstream bundle(ReadFileToString(dir.path() / "bundle.out"));
  std::string header;
  std::getline(bundle, header);
  EXPECT_EQ(header, "# Bundle file v0.3");
  size_t num_cameras = 0, num_points = 0;
  bundle >> num_cameras >> num_points;
  ASSERT_EQ(num_cameras, 3u);
  ASSERT_EQ(num_points, 40u);
  struct BundlerCamera {
    double f, k1, k2;
    Eigen::Matrix3d R;
    Eigen::Vector3d t;
  };
  std::vector<BundlerCamera> cameras(num_cameras);
  for (BundlerCamera& camera : cameras) {
    bundle >> camera.f >> camera.k1 >> camera.k2;
    for (int r = 0; r < 3; ++r) bundle >> camera.R(r, 0) >> camera.R(r, 1) >> camera.R(r, 2);
    bundle >> camera.t[0] >> camera.t[1] >> camera.t[2];
  }
  EXPECT_DOUBLE_EQ(cameras[0].f, 500);
  EXPECT_DOUBLE_EQ(cameras[0].k1, -0.2);
  size_t checked = 0;
  for (size_t p = 0; p < num_points; ++p) {
    Eigen::Vector3d X;
    int red, green, blue;
    size_t num_views = 0;
    bundle >> X[0] >> X[1] >> X[2] >> red >> green >> blue >> num_views;
    for (size_t v = 0; v < num_views; ++v) {
      int camera_index = 0, key = 0;
      double x = 0, y = 0;
      bundle >> camera_index >> key >> x >> y;
      const BundlerCamera& camera = cameras.at(camera_index);
      const Eigen::Vector3d P = camera.R * X + camera.t;
      const Eigen::Vector2d projected = -P.head<2>() / P.z();
      const double r2 = projected.squaredNorm();
      const Eigen::Vector2d pixel =
          camera.f * (1 + camera.k1 * r2 + camera.k2 * r2 * r2) * projected;
      const double error = (pixel - Eigen::Vector2d(x, y)).norm();
      EXPECT_NEAR(error, model.ReprojectionError(camera_index + 1, key), 1e-6);
      ++checked;
    }
  }
  EXPECT_EQ(checked, 120u);
}

// NVM_V3 as VisualSfM documents it: cameras with focal length, quaternion (w, x, y, z) of R
// and centre C (x_cam = R (X - C)), measurements from the principal point.
TEST(Nvm, MeasurementsReprojectThroughTheCameras) {
  const test::ScopedTestDir dir("nvm");
  const Camera pinhole = Camera::Create(1, CameraModelId::kSimplePinhole, 500, 640, 480);
  const Reconstruction model = ExactModel(pinhole);
  WriteNvm(model, dir.path() / "model.nvm");
  std::istringstream nvm(ReadFileToString(dir.path() / "model.nvm"));
  std::string header;
  nvm >> header;
  EXPECT_EQ(header, "NVM_V3");
  size_t num_cameras = 0;
  nvm >> num_cameras;
  ASSERT_EQ(num_cameras, 3u);
  struct NvmCamera {
    std::string name;
    double f, r;
    Eigen::Quaterniond q;
    Eigen::Vector3d C;
  };
  std::vector<NvmCamera> cameras(num_cameras);
  for (NvmCamera& camera : cameras) {
    int zero = -1;
    nvm >> camera.name >> camera.f >> camera.q.w() >> camera.q.x() >> camera.q.y() >>
        camera.q.z() >> camera.C[0] >> camera.C[1] >> camera.C[2] >> camera.r >> zero;
    EXPECT_EQ(zero, 0);
    EXPECT_EQ(camera.r, 0.0);
  }
  EXPECT_EQ(cameras[1].name, "view2.png");
  size_t num_points = 0;
  nvm >> num_points;
  ASSERT_EQ(num_points, 40u);
  size_t checked = 0;
  for (size_t p = 0; p < num_points; ++p) {
    Eigen::Vector3d X;
    int red, green, blue;
    size_t num_measurements = 0;
    nvm >> X[0] >> X[1] >> X[2] >> red >> green >> blue >> num_measurements;
    for (size_t m = 0; m < num_measurements; ++m) {
      int camera_index = 0, key = 0;
      double x = 0, y = 0;
      nvm >> camera_index >> key >> x >> y;
      const NvmCamera& camera = cameras.at(camera_index);
      const Eigen::Vector3d P = camera.q.normalized() * (X - camera.C);
      const Eigen::Vector2d pixel = camera.f * P.head<2>() / P.z();
      EXPECT_NEAR((pixel - Eigen::Vector2d(x, y)).norm(),
                  model.ReprojectionError(camera_index + 1, key), 1e-6);
      ++checked;
    }
  }
  EXPECT_EQ(checked, 120u);
  // SIMPLE_RADIAL's k becomes VisualSfM's r on pixels, to first order: r = -k / f^2.
  WriteNvm(ExactModel(), dir.path() / "radial.nvm");
  std::istringstream radial(ReadFileToString(dir.path() / "radial.nvm"));
  std::string name;
  double values[8], r = 0;  // f, the quaternion, the centre
  radial >> header >> num_cameras >> name;
  for (double& value : values) radial >> value;
  radial >> r;
  EXPECT_NEAR(r, 0.2 / (500.0 * 500.0), 1e-15);
}

// Every format into a folder that is a file or read-only: one line naming the path, no file.
TEST(ExportModel, UnwritableOutputIsAOneLineErrorAndWritesNothing) {
  const test::ScopedTestDir dir("export_unwritable");
  WriteFileAtomically(
      dir.path() / "a_file", [](std::ostream& stream) { stream << "not a folder\n"; }, true);
  std::vector<fs::path> folders = {dir.path() / "a_file"};
  const std::optional<fs::path> unwritable = test::UnwritableFolder(dir);
  if (unwritable) folders.push_back(*unwritable);
  const Reconstruction model = ExactModel();
  for (const fs::path& folder : folders) {
    for (const std::string format : {"nerfstudio", "ply", "bundler", "nvm"}) {
      const fs::path path = folder / ("model." + format);
      try {
        ExportModel(model, format, path, {});
        FAIL() << "no error for " << format << " into " << folder;
      } catch (const InputError& error) {
        const std::string message = error.what();
        EXPECT_EQ(message.find('\n'), std::string::npos) << message;
        EXPECT_NE(message.find(folder.string()), std::string::npos) << message;
      }
      EXPECT_FALSE(fs::exists(path)) << path;
    }
  }
}

}  // namespace
}  // namespace parallax
