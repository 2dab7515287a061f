#pragma once

#include <filesystem>
#include <iosfwd>
#include <string>

#include "parallax/scene/camera.h"

namespace parallax {

// A calibrated camera as stored in camera.json (format: docs/camera-json.md):
//   {"model": "OPENCV", "width": 1280, "height": 960, "fx": ..., "fy": ..., "cx": ..., "cy": ...,
//    "k1": ..., "k2": ..., "p1": ..., "p2": ..., "k3": 0, "rms": 0.58, "num_images": 12,
//    "colmap": "1 OPENCV 1280 960 fx fy cx cy k1 k2 p1 p2"}
struct CalibratedCamera {
  // OPENCV model: fx, fy, cx, cy, k1, k2, p1, p2.
  Camera camera;
  // OpenCV's sixth-order radial term, which COLMAP's OPENCV model lacks (0 when not fitted).
  double k3 = 0;
  // Root-mean-square reprojection error of the calibration in pixels (0: unknown).
  double rms_error = 0;
  // Number of images the calibration used (0: unknown).
  int num_images = 0;
};

// The camera as one line of COLMAP's cameras.txt: "CAMERA_ID MODEL WIDTH HEIGHT PARAMS...",
// numbers in their shortest exact decimal form. An invalid camera_id is written as 1.
std::string CameraToColmapLine(const Camera& camera);

// Largest shift, in pixels, that k3 causes anywhere in the image (at the farthest corner from
// the principal point): how much is lost by dropping it.
double K3ShiftPixels(const CalibratedCamera& calibrated);

void WriteCameraJson(const CalibratedCamera& calibrated, std::ostream& stream);
// Written atomically; throws InputError naming the path when it cannot be written.
void WriteCameraJson(const CalibratedCamera& calibrated, const std::filesystem::path& path);

// Parses camera.json text; `source` (the file name) starts every InputError message: malformed
// JSON, missing or mistyped fields, a model other than OPENCV, non-positive sizes or focal
// lengths. Unknown fields and "colmap" (derived from the others) are ignored; k3, rms and
// num_images are optional.
CalibratedCamera ParseCameraJson(const std::string& text, const std::string& source);
CalibratedCamera ReadCalibratedCameraJson(const std::filesystem::path& path);

// The camera of a camera.json file, ready for the pipeline (has_prior_focal_length set).
// Refuses, with an InputError naming the file, a k3 that would shift some pixel by more than
// max_k3_shift_px, since the OPENCV model would silently drop it.
Camera ReadCameraJson(const std::filesystem::path& path, double max_k3_shift_px = 0.1);

}  // namespace parallax
