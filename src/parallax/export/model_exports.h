#pragma once

#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>

#include "parallax/scene/reconstruction.h"

namespace parallax {

// A model in the formats other tools read (`parallax export`). Each writer writes its files
// atomically and keeps the model's world frame.

struct NerfstudioExportOptions {
  // Prefix of every frame's file_path, relative to transforms.json (nerfstudio's layout puts
  // the images in images/ beside it).
  std::string image_prefix = "images/";
};

// nerfstudio's transforms.json: camera_model OPENCV with fl_x, fl_y, cx, cy, k1, k2, p1, p2
// (zeros where the model has none), w, h; shared at the top when all images have one camera,
// else per frame; one frame per registered image, in id order, with its camera-to-world
// matrix in nerfstudio's (OpenGL) axes: x right, y up, z back. "ply_file_path" names the
// points written beside it (sparse_pc.ply, world frame), which splatfacto starts from.
nlohmann::json NerfstudioTransforms(const Reconstruction& model,
                                    const NerfstudioExportOptions& options = {});
// transforms.json at `path` and sparse_pc.ply beside it.
void WriteNerfstudio(const Reconstruction& model, const std::filesystem::path& path,
                     const NerfstudioExportOptions& options = {});

// A binary PLY of the points (x, y, z, red, green, blue) and of every registered camera as a
// red frustum: its centre and image corners at `frustum_depth` as vertices, 8 edges between
// them (element edge: vertex1, vertex2, red, green, blue). frustum_depth <= 0: a twentieth of
// the spread of the camera centres.
void WritePlyWithCameras(const Reconstruction& model, const std::filesystem::path& path,
                         double frustum_depth = 0);

// Bundler v0.3 (bundle.out) and its image list: one camera per image of `list` (f, k1, k2;
// R, t with the camera looking down -z and y up; zeros for unregistered images), points with
// their colour and views (image index, keypoint index, x and y relative to the principal
// point with y up). Bundler's camera has one focal length, the principal point at the image
// centre and radial k1, k2 (on |p|^2 in focal units): PINHOLE's fx and fy are averaged and
// OPENCV's tangential terms dropped, with a warning.
void WriteBundler(const Reconstruction& model, const std::filesystem::path& bundle_path,
                  const std::filesystem::path& list_path);

// VisualSfM's NVM_V3: per registered camera its file name, focal length, rotation quaternion
// (w, x, y, z of R, world to camera), centre and radial distortion (VisualSfM's r: undistorted
// = measured * (1 + r |measured|^2), measured in pixels from the principal point); per point
// its position, colour and measurements (camera index, keypoint index, x, y from the
// principal point). Distortion is converted from SIMPLE_RADIAL's k as r = -k / f^2 (first
// order); other models are written with r = 0 and a warning.
void WriteNvm(const Reconstruction& model, const std::filesystem::path& path);

}  // namespace parallax
