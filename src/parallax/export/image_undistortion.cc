#include "parallax/export/image_undistortion.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <limits>
#include <opencv2/imgproc.hpp>
#include <string>

#include "parallax/image/image_codecs.h"
#include "parallax/image/image_reader.h"
#include "parallax/scene/colmap_io.h"
#include "parallax/util/check.h"
#include "parallax/util/file.h"
#include "parallax/util/progress.h"
#include "parallax/util/threading.h"
#include "parallax/util/timer.h"

namespace parallax {
namespace {

namespace fs = std::filesystem;

// Where each pixel of `undistorted` reads from in a photo of `camera` (cv::remap's maps).
struct UndistortionMaps {
  cv::Mat map_x;
  cv::Mat map_y;
};

UndistortionMaps MakeUndistortionMaps(const Camera& camera, const Camera& undistorted) {
  UndistortionMaps maps;
  const int width = static_cast<int>(undistorted.width);
  const int height = static_cast<int>(undistorted.height);
  maps.map_x.create(height, width, CV_32FC1);
  maps.map_y.create(height, width, CV_32FC1);
  for (int row = 0; row < height; ++row) {
    float* map_x = maps.map_x.ptr<float>(row);
    float* map_y = maps.map_y.ptr<float>(row);
    for (int col = 0; col < width; ++col) {
      // Pixel centres are at +0.5 (COLMAP's convention), array indices at +0.
      const Eigen::Vector2d ray = undistorted.CamFromImg(Eigen::Vector2d(col + 0.5, row + 0.5));
      const Eigen::Vector2d source = camera.ImgFromCam(ray.homogeneous());
      map_x[col] = static_cast<float>(source.x() - 0.5);
      map_y[col] = static_cast<float>(source.y() - 0.5);
    }
  }
  return maps;
}

cv::Mat Remap(const cv::Mat& image, const UndistortionMaps& maps) {
  cv::Mat undistorted;
  cv::remap(image, undistorted, maps.map_x, maps.map_y, cv::INTER_LINEAR, cv::BORDER_CONSTANT,
            cv::Scalar::all(0));
  return undistorted;
}

std::string LowerExtension(const std::string& name) {
  std::string extension = fs::path(name).extension().string();
  std::transform(extension.begin(), extension.end(), extension.begin(),
                 [](unsigned char c) { return std::tolower(c); });
  return extension;
}

bool IsJpegName(const std::string& name) {
  const std::string extension = LowerExtension(name);
  return extension == ".jpg" || extension == ".jpeg";
}

// The name of the undistorted image: the photo's, unless it cannot hold PNG or JPEG bytes.
std::string UndistortedImageName(const std::string& name) {
  return IsJpegName(name) || LowerExtension(name) == ".png" ? name : name + ".png";
}

void WriteStereoConfig(const Reconstruction& model, const fs::path& stereo_dir) {
  std::string patch_match, fusion;
  for (const image_t image_id : model.RegImageIds()) {
    const std::string& name = model.GetImage(image_id).name;
    // COLMAP picks each image's source images itself (__auto__) among 20 candidates.
    patch_match += name + "\n__auto__, 20\n";
    fusion += name + "\n";
  }
  for (const char* folder : {"depth_maps", "normal_maps", "consistency_graphs"}) {
    CreateDirectoryOrThrow(stereo_dir / folder);
  }
  WriteTextFileAtomically(stereo_dir / "patch-match.cfg", patch_match);
  WriteTextFileAtomically(stereo_dir / "fusion.cfg", fusion);
}

// COLMAP's two scripts beside the workspace: its dense steps with geometric or photometric
// consistency, then its meshers, each a command of its own.
void WriteDenseScripts(const fs::path& workspace) {
  for (const bool geometric : {true, false}) {
    const std::string script =
        std::string(
            "# Dense reconstruction of this workspace with COLMAP: set $COLMAP_EXE_PATH\n"
            "# to the folder of the colmap executable.\n"
            "$COLMAP_EXE_PATH/colmap patch_match_stereo \\\n"
            "  --workspace_path \".\" \\\n"
            "  --workspace_format COLMAP \\\n"
            "  --PatchMatchStereo.max_image_size 2000 \\\n"
            "  --PatchMatchStereo.geom_consistency ") +
        (geometric ? "true" : "false") +
        "\n$COLMAP_EXE_PATH/colmap stereo_fusion \\\n"
        "  --workspace_path \".\" \\\n"
        "  --workspace_format COLMAP \\\n"
        "  --input_type " +
        (geometric ? "geometric" : "photometric") +
        " \\\n"
        "  --output_path \"./fused.ply\"\n"
        "$COLMAP_EXE_PATH/colmap poisson_mesher \\\n"
        "  --input_path \"./fused.ply\" \\\n"
        "  --output_path \"./meshed-poisson.ply\"\n"
        "$COLMAP_EXE_PATH/colmap delaunay_mesher \\\n"
        "  --input_path \"./\" \\\n"
        "  --input_type dense \\\n"
        "  --output_path \"./meshed-delaunay.ply\"\n";
    WriteTextFileAtomically(
        workspace / (geometric ? "run-colmap-geometric.sh" : "run-colmap-photometric.sh"), script);
  }
}

}  // namespace

void UndistortionOptions::Check() const {
  PARALLAX_CHECK(blank_pixels >= 0.0 && blank_pixels <= 1.0);
  PARALLAX_CHECK(jpeg_quality >= 1 && jpeg_quality <= 100);
}

Camera UndistortedCamera(const Camera& camera, const UndistortionOptions& options) {
  options.Check();
  if (camera.Projection() == CameraProjection::kSpherical) {
    throw InputError("camera " + std::to_string(camera.camera_id) + " is " + camera.ModelName() +
                     ": a sphere has no single pinhole view (perspective faces are not written "
                     "yet)");
  }
  const double fx = camera.FocalLengthX(), fy = camera.FocalLengthY();
  const double cx = camera.PrincipalPointX(), cy = camera.PrincipalPointY();
  const double width = static_cast<double>(camera.width);
  const double height = static_cast<double>(camera.height);
  // Where the centres of the photo's border pixels land in a PINHOLE view with its focal
  // lengths and principal point: the outline of what the photo shows, undistorted.
  constexpr double kInfinity = std::numeric_limits<double>::infinity();
  // A pixel whose ray is at or behind the image plane (a fisheye wider than 180 degrees)
  // lands infinitely far out, on its side: it never limits a crop (blank_pixels 0), and a
  // view keeping all of the photo (blank_pixels 1) is then as large as allowed. (COLMAP's
  // unprojection falls back to the pixel's fisheye coordinates there, which gives an outline
  // that is neither.)
  const auto undistort = [&](double x, double y) {
    if (camera.Projection() != CameraProjection::kPerspective) {
      const Eigen::Vector3d ray = camera.CamRayFromImg(Eigen::Vector2d(x, y));
      if (ray.z() <= 1e-9) {
        const auto far = [&](double side, double centre) {
          return side == 0 ? centre : std::copysign(kInfinity, side);
        };
        return Eigen::Vector2d(far(ray.x(), cx), far(ray.y(), cy));
      }
    }
    const Eigen::Vector2d ray = camera.CamFromImg(Eigen::Vector2d(x, y));
    return Eigen::Vector2d(fx * ray.x() + cx, fy * ray.y() + cy);
  };
  double left_min = kInfinity, left_max = -kInfinity, right_min = kInfinity, right_max = -kInfinity,
         top_min = kInfinity, top_max = -kInfinity, bottom_min = kInfinity, bottom_max = -kInfinity;
  for (size_t row = 0; row < camera.height; ++row) {
    const double left = undistort(0.5, row + 0.5).x();
    const double right = undistort(width - 0.5, row + 0.5).x();
    left_min = std::min(left_min, left);
    left_max = std::max(left_max, left);
    right_min = std::min(right_min, right);
    right_max = std::max(right_max, right);
  }
  for (size_t col = 0; col < camera.width; ++col) {
    const double top = undistort(col + 0.5, 0.5).y();
    const double bottom = undistort(col + 0.5, height - 0.5).y();
    top_min = std::min(top_min, top);
    top_max = std::max(top_max, top);
    bottom_min = std::min(bottom_min, bottom);
    bottom_max = std::max(bottom_max, bottom);
  }
  // The view keeps the principal point where it is relative to the image and scales the image
  // about it, as COLMAP's image_undistorter does (so its workspaces and ours agree): the
  // smallest scale on any side keeps all of the photo (blank_pixels 1), the largest keeps
  // only pixels from it (blank_pixels 0).
  const double min_scale_x = std::min(cx / (cx - left_min), (width - 0.5 - cx) / (right_max - cx));
  const double max_scale_x = std::max(cx / (cx - left_max), (width - 0.5 - cx) / (right_min - cx));
  const double min_scale_y = std::min(cy / (cy - top_min), (height - 0.5 - cy) / (bottom_max - cy));
  const double max_scale_y = std::max(cy / (cy - top_max), (height - 0.5 - cy) / (bottom_min - cy));
  const double blank = options.blank_pixels;
  // Never more than 5 times smaller or 2 times larger than the photo.
  const double scale_x =
      std::clamp(1.0 / (min_scale_x * blank + max_scale_x * (1.0 - blank)), 0.2, 2.0);
  const double scale_y =
      std::clamp(1.0 / (min_scale_y * blank + max_scale_y * (1.0 - blank)), 0.2, 2.0);
  PARALLAX_CHECK_MSG(std::isfinite(scale_x) && std::isfinite(scale_y),
                     "camera " << camera.camera_id << ": its principal point is outside the image");

  Camera pinhole;
  pinhole.camera_id = camera.camera_id;
  pinhole.model_id = CameraModelId::kPinhole;
  pinhole.width = static_cast<size_t>(std::max(1.0, scale_x * width));
  pinhole.height = static_cast<size_t>(std::max(1.0, scale_y * height));
  pinhole.params = {fx, fy, cx * static_cast<double>(pinhole.width) / width,
                    cy * static_cast<double>(pinhole.height) / height};
  // Longer than max_image_size: everything scaled down together.
  const size_t longest = std::max(pinhole.width, pinhole.height);
  if (options.max_image_size > 0 && longest > static_cast<size_t>(options.max_image_size)) {
    const double scale = static_cast<double>(options.max_image_size) / longest;
    const size_t scaled_width = std::max<size_t>(1, std::lround(scale * pinhole.width));
    const size_t scaled_height = std::max<size_t>(1, std::lround(scale * pinhole.height));
    pinhole.params = {fx * scaled_width / pinhole.width, fy * scaled_height / pinhole.height,
                      pinhole.params[2] * scaled_width / pinhole.width,
                      pinhole.params[3] * scaled_height / pinhole.height};
    pinhole.width = scaled_width;
    pinhole.height = scaled_height;
  }
  pinhole.has_prior_focal_length = true;
  return pinhole;
}

cv::Mat UndistortImage(const cv::Mat& image, const Camera& camera, const Camera& undistorted) {
  return Remap(image, MakeUndistortionMaps(camera, undistorted));
}

Reconstruction UndistortReconstruction(const Reconstruction& model,
                                       const std::map<camera_t, Camera>& undistorted_cameras) {
  Reconstruction undistorted = model;
  for (const auto& [camera_id, camera] : undistorted_cameras) {
    undistorted.GetCamera(camera_id) = camera;
  }
  for (const auto& [image_id, image] : model.Images()) {
    const Camera& camera = model.GetCamera(image.camera_id);
    const Camera& pinhole = undistorted.GetCamera(image.camera_id);
    Image& moved = undistorted.GetImage(image_id);
    for (Point2D& point : moved.points2D) {
      point.xy = pinhole.ImgFromCam(camera.CamFromImg(point.xy).homogeneous());
    }
    moved.name = UndistortedImageName(image.name);
  }
  return undistorted;
}

UndistortionResult WriteUndistortedWorkspace(const Reconstruction& model, const fs::path& image_dir,
                                             const fs::path& output_dir,
                                             const UndistortionOptions& options) {
  options.Check();
  const Timer timer;
  const std::vector<image_t> image_ids = model.RegImageIds();
  for (const image_t image_id : image_ids) {
    const fs::path path = image_dir / model.GetImage(image_id).name;
    std::error_code error;
    if (!fs::is_regular_file(path, error)) {
      throw MissingFileError(path.string() + ": photo of the model not found");
    }
  }
  std::map<camera_t, Camera> cameras;
  std::map<camera_t, UndistortionMaps> maps;
  for (const image_t image_id : image_ids) {
    const camera_t camera_id = model.GetImage(image_id).camera_id;
    if (cameras.count(camera_id)) continue;
    cameras[camera_id] = UndistortedCamera(model.GetCamera(camera_id), options);
    maps[camera_id] = MakeUndistortionMaps(model.GetCamera(camera_id), cameras[camera_id]);
  }
  const Reconstruction undistorted = UndistortReconstruction(model, cameras);

  CreateDirectoryOrThrow(output_dir / "images");
  ProgressReporter progress("undistort", image_ids.size());
  ParallelFor(0, image_ids.size(), options.num_threads, [&](size_t index) {
    const Image& image = model.GetImage(image_ids[index]);
    const Camera& camera = model.GetCamera(image.camera_id);
    const fs::path source = image_dir / image.name;
    const Bitmap bitmap = ReadBitmap(source);
    if (bitmap.Width() != static_cast<int>(camera.width) ||
        bitmap.Height() != static_cast<int>(camera.height)) {
      throw InputError(source.string() + ": image is " + std::to_string(bitmap.Width()) + "x" +
                       std::to_string(bitmap.Height()) + " but its camera " +
                       std::to_string(camera.camera_id) + " is " + std::to_string(camera.width) +
                       "x" + std::to_string(camera.height));
    }
    const cv::Mat pixels = Remap(bitmap.color, maps.at(image.camera_id));
    const std::string name = UndistortedImageName(image.name);
    const std::string bytes =
        IsJpegName(name) ? EncodeJpeg(pixels, options.jpeg_quality) : EncodePng(pixels);
    const fs::path target = output_dir / "images" / name;
    CreateDirectoryOrThrow(target.parent_path());
    WriteFileAtomically(
        target, [&](std::ostream& stream) { stream << bytes; }, true);
    progress.Increment();
  });
  progress.Finish();
  WriteStereoConfig(undistorted, output_dir / "stereo");
  WriteDenseScripts(output_dir);
  WriteReconstructionBinary(undistorted, output_dir / "sparse");
  UndistortionResult result;
  result.num_images = image_ids.size();
  result.seconds = timer.ElapsedSeconds();
  return result;
}

}  // namespace parallax
