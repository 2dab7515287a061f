#include "parallax/export/model_exports.h"

#include "parallax/export/model_export_format.h"

#include <Eigen/Geometry>
#include <array>
#include <iomanip>
#include <limits>
#include <map>
#include <set>
#include <sstream>

#include "parallax/scene/colmap_io.h"
#include "parallax/util/byte_order.h"
#include "parallax/util/check.h"
#include "parallax/util/file.h"
#include "parallax/util/logging.h"

namespace parallax {
namespace {

namespace fs = std::filesystem;

// OPENCV's (fx, fy, cx, cy, k1, k2, p1, p2) of any of Parallax's models: the model's own
// values, zeros where it has none.
// Whether a model's extra parameters are the first ones of OPENCV's k1, k2, p1, p2
// (SIMPLE_RADIAL's k, RADIAL's k1, k2), or of OPENCV_FISHEYE's k1..k4 (SIMPLE_RADIAL_FISHEYE's k,
// RADIAL_FISHEYE's k1, k2; none for SIMPLE_FISHEYE and FISHEYE).
bool IsOpenCvFamily(CameraModelId model_id) {
  return model_id == CameraModelId::kSimplePinhole || model_id == CameraModelId::kPinhole ||
         model_id == CameraModelId::kSimpleRadial || model_id == CameraModelId::kRadial ||
         model_id == CameraModelId::kOpenCV;
}
bool IsOpenCvFisheyeFamily(CameraModelId model_id) {
  return model_id == CameraModelId::kSimpleFisheye || model_id == CameraModelId::kFisheye ||
         model_id == CameraModelId::kSimpleRadialFisheye ||
         model_id == CameraModelId::kRadialFisheye || model_id == CameraModelId::kOpenCVFisheye;
}

// A camera's focal lengths, principal point and the four coefficients of OPENCV (or, for the
// fisheye family, of OPENCV_FISHEYE): its own values, zeros where it has none. Any other model
// has no such form: an InputError names the format and the camera.
void RequireModelFamily(const Camera& camera, const std::string& format, bool fisheye_allowed) {
  if (!IsOpenCvFamily(camera.model_id) &&
      !(fisheye_allowed && IsOpenCvFisheyeFamily(camera.model_id))) {
    // A sphere has no pinhole view to undistort into: no advice to give.
    const bool spherical = camera.Projection() == CameraProjection::kSpherical;
    throw InputError(format + ": camera " + std::to_string(camera.camera_id) + " is " +
                     camera.ModelName() + ", which " + format + " cannot describe" +
                     (spherical ? "" : "; write undistorted images first (parallax undistort)"));
  }
}

std::array<double, 8> OpenCvParams(const Camera& camera, const std::string& format,
                                   bool fisheye_allowed = false) {
  RequireModelFamily(camera, format, fisheye_allowed);
  std::array<double, 8> opencv = {camera.FocalLengthX(),
                                  camera.FocalLengthY(),
                                  camera.PrincipalPointX(),
                                  camera.PrincipalPointY(),
                                  0,
                                  0,
                                  0,
                                  0};
  const std::vector<int> extra = CameraModelExtraIdxs(camera.model_id);
  for (size_t i = 0; i < extra.size(); ++i) opencv[4 + i] = camera.params[extra[i]];
  return opencv;
}

// nerfstudio's name for a camera's projection: OPENCV, OPENCV_FISHEYE or EQUIRECTANGULAR.
std::string NerfstudioCameraModel(const Camera& camera) {
  if (camera.model_id == CameraModelId::kEquirectangular) return "EQUIRECTANGULAR";
  return IsOpenCvFisheyeFamily(camera.model_id) ? "OPENCV_FISHEYE" : "OPENCV";
}

void AddIntrinsics(const Camera& camera, nlohmann::json* json) {
  (*json)["w"] = camera.width;
  (*json)["h"] = camera.height;
  if (camera.model_id == CameraModelId::kEquirectangular) {
    // nerfstudio's equirectangular rays: azimuth pi (x - cx) / fl_x over [-pi, pi] and
    // elevation from (y - cy) / fl_y over [-1/2, 1/2].
    (*json)["fl_x"] = camera.params[0] / 2;
    (*json)["fl_y"] = camera.params[1];
    (*json)["cx"] = camera.params[0] / 2;
    (*json)["cy"] = camera.params[1] / 2;
    return;
  }
  const std::array<double, 8> p = OpenCvParams(camera, "nerfstudio", /*fisheye_allowed=*/true);
  (*json)["fl_x"] = p[0];
  (*json)["fl_y"] = p[1];
  (*json)["cx"] = p[2];
  (*json)["cy"] = p[3];
  if (IsOpenCvFisheyeFamily(camera.model_id)) {
    (*json)["k1"] = p[4];
    (*json)["k2"] = p[5];
    (*json)["k3"] = p[6];
    (*json)["k4"] = p[7];
  } else {
    (*json)["k1"] = p[4];
    (*json)["k2"] = p[5];
    (*json)["p1"] = p[6];
    (*json)["p2"] = p[7];
  }
}

// The 4 x 4 camera-to-world matrix in OpenGL axes (x right, y up, z back).
Eigen::Matrix4d OpenGlCamToWorld(const Rigid3d& cam_from_world) {
  Eigen::Matrix4d cam_to_world = Eigen::Matrix4d::Identity();
  const Rigid3d world_from_cam = cam_from_world.Inverse();
  cam_to_world.topLeftCorner<3, 3>() = world_from_cam.rotation.toRotationMatrix();
  cam_to_world.topRightCorner<3, 1>() = world_from_cam.translation;
  cam_to_world.block<3, 2>(0, 1) *= -1;  // OpenCV's y down, z forward -> OpenGL's.
  return cam_to_world;
}

nlohmann::json MatrixToJson(const Eigen::Matrix4d& matrix) {
  nlohmann::json rows = nlohmann::json::array();
  for (int r = 0; r < 4; ++r)
    rows.push_back({matrix(r, 0), matrix(r, 1), matrix(r, 2), matrix(r, 3)});
  return rows;
}

// Numbers as text that read back to the same double.
std::ostream& Exact(std::ostream& stream) {
  return stream << std::setprecision(std::numeric_limits<double>::max_digits10);
}

}  // namespace

nlohmann::json NerfstudioTransforms(const Reconstruction& model,
                                    const NerfstudioExportOptions& options) {
  nlohmann::json transforms;
  std::set<camera_t> cameras;
  std::set<std::string> camera_models;
  for (const image_t image_id : model.RegImageIds()) {
    const camera_t camera_id = model.GetImage(image_id).camera_id;
    cameras.insert(camera_id);
    camera_models.insert(NerfstudioCameraModel(model.GetCamera(camera_id)));
  }
  // transforms.json has one camera_model for all frames.
  if (camera_models.size() > 1) {
    throw InputError("nerfstudio: the model mixes " + *camera_models.begin() + " and " +
                     *camera_models.rbegin() +
                     " cameras, and transforms.json has one camera model for all frames");
  }
  transforms["camera_model"] = camera_models.empty() ? "OPENCV" : *camera_models.begin();
  const bool shared = cameras.size() == 1;
  if (shared) AddIntrinsics(model.GetCamera(*cameras.begin()), &transforms);
  nlohmann::json frames = nlohmann::json::array();
  for (const image_t image_id : model.RegImageIds()) {
    const Image& image = model.GetImage(image_id);
    nlohmann::json frame;
    frame["file_path"] = options.image_prefix + image.name;
    frame["transform_matrix"] = MatrixToJson(OpenGlCamToWorld(image.cam_from_world));
    frame["colmap_im_id"] = image_id;
    if (!shared) AddIntrinsics(model.GetCamera(image.camera_id), &frame);
    frames.push_back(frame);
  }
  transforms["frames"] = frames;
  transforms["ply_file_path"] = "sparse_pc.ply";
  return transforms;
}

void WriteNerfstudio(const Reconstruction& model, const fs::path& path,
                     const NerfstudioExportOptions& options) {
  const fs::path folder = path.parent_path().empty() ? fs::path(".") : path.parent_path();
  CreateDirectoryOrThrow(folder);
  WritePointsPly(model, folder / "sparse_pc.ply");
  WriteTextFileAtomically(path, NerfstudioTransforms(model, options).dump(2) + "\n");
}

void WritePlyWithCameras(const Reconstruction& model, const fs::path& path, double frustum_depth) {
  const std::vector<image_t> image_ids = model.RegImageIds();
  if (frustum_depth <= 0) {
    Eigen::Vector3d mean = Eigen::Vector3d::Zero();
    for (const image_t id : image_ids) mean += model.GetImage(id).ProjectionCenter();
    if (!image_ids.empty()) mean /= static_cast<double>(image_ids.size());
    double spread = 0;
    for (const image_t id : image_ids) {
      spread = std::max(spread, (model.GetImage(id).ProjectionCenter() - mean).norm());
    }
    frustum_depth = spread > 0 ? spread / 20 : 1.0;
  }
  // Per camera: its centre and the four image corners at frustum_depth, in the world.
  std::vector<Eigen::Vector3d> frustum_vertices;
  for (const image_t id : image_ids) {
    const Image& image = model.GetImage(id);
    const Camera& camera = model.GetCamera(image.camera_id);
    const Rigid3d world_from_cam = image.cam_from_world.Inverse();
    frustum_vertices.push_back(image.ProjectionCenter());
    const double w = static_cast<double>(camera.width), h = static_cast<double>(camera.height);
    for (const Eigen::Vector2d& corner : {Eigen::Vector2d(0, 0), Eigen::Vector2d(w, 0),
                                          Eigen::Vector2d(w, h), Eigen::Vector2d(0, h)}) {
      frustum_vertices.push_back(world_from_cam *
                                 (frustum_depth * camera.CamFromImg(corner).homogeneous()));
    }
  }
  WriteFileAtomically(
      path,
      [&](std::ostream& stream) {
        stream << "ply\nformat binary_little_endian 1.0\n"
               << "element vertex " << model.NumPoints3D() + frustum_vertices.size() << "\n"
               << "property float x\nproperty float y\nproperty float z\n"
               << "property uchar red\nproperty uchar green\nproperty uchar blue\n"
               << "element edge " << 8 * image_ids.size() << "\n"
               << "property int vertex1\nproperty int vertex2\n"
               << "property uchar red\nproperty uchar green\nproperty uchar blue\n"
               << "end_header\n";
        const auto vertex = [&](const Eigen::Vector3d& xyz, uint8_t r, uint8_t g, uint8_t b) {
          for (int c = 0; c < 3; ++c) WriteBinary<float>(stream, static_cast<float>(xyz[c]));
          WriteBinary<uint8_t>(stream, r);
          WriteBinary<uint8_t>(stream, g);
          WriteBinary<uint8_t>(stream, b);
        };
        for (const auto& [id, point] : model.Points3D()) {
          vertex(point.xyz, point.color[0], point.color[1], point.color[2]);
        }
        for (const Eigen::Vector3d& xyz : frustum_vertices) vertex(xyz, 255, 0, 0);
        const int first = static_cast<int>(model.NumPoints3D());
        for (size_t camera = 0; camera < image_ids.size(); ++camera) {
          const int centre = first + static_cast<int>(5 * camera);
          // Centre to each corner, then around the image rectangle.
          for (int corner = 1; corner <= 4; ++corner) {
            for (const auto& [a, b] : {std::pair{centre, centre + corner},
                                       std::pair{centre + corner, centre + corner % 4 + 1}}) {
              WriteBinary<int32_t>(stream, a);
              WriteBinary<int32_t>(stream, b);
              for (int c = 0; c < 3; ++c) WriteBinary<uint8_t>(stream, c == 0 ? 255 : 0);
            }
          }
        }
      },
      true);
}

void WriteBundler(const Reconstruction& model, const fs::path& bundle_path,
                  const fs::path& list_path) {
  // Every image of the model in id order: Bundler's camera index is the list's line.
  std::map<image_t, int> index_of;
  std::ostringstream list;
  for (const auto& [image_id, image] : model.Images()) {
    index_of[image_id] = static_cast<int>(index_of.size());
    list << image.name << "\n";
  }
  std::ostringstream bundle;
  Exact(bundle) << "# Bundle file v0.3\n"
                << model.NumImages() << " " << model.NumPoints3D() << "\n";
  bool approximated = false;
  // Bundler's axes: x right, y up, z back (the camera looks down -z).
  const Eigen::Matrix3d flip = Eigen::Vector3d(1, -1, -1).asDiagonal();
  for (const auto& [image_id, image] : model.Images()) {
    if (!image.registered) {
      bundle << "0 0 0\n0 0 0\n0 0 0\n0 0 0\n0 0 0\n";
      continue;
    }
    const Camera& camera = model.GetCamera(image.camera_id);
    const std::array<double, 8> p = OpenCvParams(camera, "Bundler");
    approximated |= p[0] != p[1] || p[6] != 0 || p[7] != 0;
    bundle << (p[0] + p[1]) / 2 << " " << p[4] << " " << p[5] << "\n";
    const Eigen::Matrix3d R = flip * image.cam_from_world.rotation.toRotationMatrix();
    const Eigen::Vector3d t = flip * image.cam_from_world.translation;
    for (int r = 0; r < 3; ++r) bundle << R(r, 0) << " " << R(r, 1) << " " << R(r, 2) << "\n";
    bundle << t[0] << " " << t[1] << " " << t[2] << "\n";
  }
  for (const auto& [point_id, point] : model.Points3D()) {
    bundle << point.xyz[0] << " " << point.xyz[1] << " " << point.xyz[2] << "\n"
           << int{point.color[0]} << " " << int{point.color[1]} << " " << int{point.color[2]}
           << "\n"
           << point.track.Length();
    for (const TrackElement& element : point.track.elements) {
      const Image& image = model.GetImage(element.image_id);
      const Camera& camera = model.GetCamera(image.camera_id);
      const Eigen::Vector2d& xy = image.points2D[element.point2D_idx].xy;
      bundle << " " << index_of.at(element.image_id) << " " << element.point2D_idx << " "
             << xy.x() - camera.PrincipalPointX() << " " << camera.PrincipalPointY() - xy.y();
    }
    bundle << "\n";
  }
  if (approximated) {
    PARALLAX_LOG(Warning) << bundle_path.string()
                          << ": Bundler has one focal length and no tangential distortion: "
                             "fx and fy averaged, p1 and p2 dropped";
  }
  WriteTextFileAtomically(list_path, list.str());
  WriteTextFileAtomically(bundle_path, bundle.str());
}

void WriteNvm(const Reconstruction& model, const fs::path& path) {
  const std::vector<image_t> image_ids = model.RegImageIds();
  std::map<image_t, int> index_of;
  for (const image_t id : image_ids) index_of[id] = static_cast<int>(index_of.size());
  std::ostringstream nvm;
  Exact(nvm) << "NVM_V3\n\n" << image_ids.size() << "\n";
  bool approximated = false;
  for (const image_t id : image_ids) {
    const Image& image = model.GetImage(id);
    const Camera& camera = model.GetCamera(image.camera_id);
    RequireModelFamily(camera, "NVM", /*fisheye_allowed=*/false);
    const double f = camera.MeanFocalLength();
    double r = 0;
    if (camera.model_id == CameraModelId::kSimpleRadial) {
      r = -camera.params[3] / (f * f);
    } else if (camera.model_id != CameraModelId::kSimplePinhole) {
      approximated |= camera.model_id != CameraModelId::kPinhole ||
                      camera.FocalLengthX() != camera.FocalLengthY();
    }
    const Eigen::Quaterniond& q = image.cam_from_world.rotation;
    const Eigen::Vector3d center = image.ProjectionCenter();
    nvm << image.name << " " << f << " " << q.w() << " " << q.x() << " " << q.y() << " " << q.z()
        << " " << center[0] << " " << center[1] << " " << center[2] << " " << r << " 0\n";
  }
  nvm << "\n" << model.NumPoints3D() << "\n";
  for (const auto& [point_id, point] : model.Points3D()) {
    nvm << point.xyz[0] << " " << point.xyz[1] << " " << point.xyz[2] << " " << int{point.color[0]}
        << " " << int{point.color[1]} << " " << int{point.color[2]} << " " << point.track.Length();
    for (const TrackElement& element : point.track.elements) {
      const Image& image = model.GetImage(element.image_id);
      const Camera& camera = model.GetCamera(image.camera_id);
      const Eigen::Vector2d& xy = image.points2D[element.point2D_idx].xy;
      nvm << " " << index_of.at(element.image_id) << " " << element.point2D_idx << " "
          << xy.x() - camera.PrincipalPointX() << " " << xy.y() - camera.PrincipalPointY();
    }
    nvm << "\n";
  }
  if (approximated) {
    PARALLAX_LOG(Warning) << path.string()
                          << ": NVM has one focal length and one radial term: only "
                             "SIMPLE_RADIAL's distortion is kept, fx and fy are averaged";
  }
  WriteTextFileAtomically(path, nvm.str());
}

void ExportModel(const Reconstruction& model, const std::string& format, const fs::path& path,
                 const NerfstudioExportOptions& nerfstudio) {
  const fs::path folder = path.parent_path().empty() ? fs::path(".") : path.parent_path();
  if (format != "nerfstudio" && format != "ply" && format != "bundler" && format != "nvm") {
    throw InputError("--format: unknown export format '" + format +
                     "' (expected nerfstudio, ply, bundler or nvm)");
  }
  CreateDirectoryOrThrow(folder);
  if (format == "nerfstudio") {
    WriteNerfstudio(model, path, nerfstudio);
  } else if (format == "ply") {
    WritePlyWithCameras(model, path);
  } else if (format == "bundler") {
    WriteBundler(model, path, folder / "list.txt");
  } else {
    WriteNvm(model, path);
  }
}

}  // namespace parallax
