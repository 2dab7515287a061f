#pragma once

#include <filesystem>
#include <iosfwd>
#include <string>
#include <utility>
#include <vector>

#include "parallax/geometry/rigid3.h"
#include "parallax/scene/camera.h"
#include "parallax/scene/reconstruction.h"

namespace parallax {

// One ground-truth view: the image it belongs to, its intrinsics and its pose.
struct GroundTruthImage {
  std::string name;
  // PINHOLE from K (skew and distortion dropped); width/height are 0 when the format
  // does not give them (Middlebury).
  Camera camera;
  Rigid3d cam_from_world;
};

struct GroundTruth {
  // The file or folder it was read from (for messages).
  std::string source;
  std::vector<GroundTruthImage> images;
};

// Middlebury `*_par.txt`: first line the number of views, then per line
// `name k11 .. k33 r11 .. r33 t1 t2 t3` with projection K [R | t] (world to camera).
// Throws InputError "<source>:<line>: <reason>" on malformed input.
GroundTruth ReadMiddleburyGroundTruth(std::istream& stream, const std::string& source);
GroundTruth ReadMiddleburyGroundTruth(const std::filesystem::path& path);

// One Strecha `NAME.camera` file: K (3 rows), distortion (1 row), R (3 rows, camera axes in
// world: R_cam_from_world = Rᵀ), camera centre C (1 row), `width height`.
GroundTruthImage ReadStrechaCamera(std::istream& stream, const std::string& source,
                                   const std::string& image_name);
// Every `*.camera` file of a folder, sorted by name; the image name is the file name
// without `.camera` (`0000.jpg.camera` -> `0000.jpg`).
GroundTruth ReadStrechaGroundTruth(const std::filesystem::path& dir);

// A COLMAP model folder (cameras/images/points3D, .bin or .txt); registered images only.
GroundTruth ReadColmapGroundTruth(const std::filesystem::path& dir);
// The registered images of a model in memory as a ground truth; `source` names it in messages.
GroundTruth GroundTruthOfModel(const Reconstruction& model, const std::string& source);

// Camera centres only (rotations identity), for aligning a model by its centres: a GPS
// survey, COLMAP's model_aligner reference positions. `positions`: image name and centre.
GroundTruth GroundTruthOfPositions(
    const std::vector<std::pair<std::string, Eigen::Vector3d>>& positions,
    const std::string& source);
// COLMAP's model_aligner --ref_images_path file: per line `image_name X Y Z` ('#' comments).
// Throws InputError "<file>:<line>: <reason>".
GroundTruth ReadPositionsGroundTruth(const std::filesystem::path& path);

// Detects the format: a file is Middlebury; a folder with *.camera files is Strecha; a
// folder with cameras.bin or cameras.txt is COLMAP. Throws InputError otherwise.
GroundTruth ReadGroundTruth(const std::filesystem::path& path);

}  // namespace parallax
