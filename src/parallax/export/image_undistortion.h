#pragma once

#include <filesystem>
#include <map>
#include <opencv2/core.hpp>

#include "parallax/scene/reconstruction.h"

namespace parallax {

// Undistortion as multi-view stereo, NeRF and Gaussian splatting want it: every camera becomes
// PINHOLE with the same focal lengths, the images are resampled into it, and the model is
// restated in undistorted coordinates (COLMAP's image_undistorter).
struct UndistortionOptions {
  // Which part of the undistorted view is kept: 0 crops to pixels that all come from the
  // photo (no blank border; COLMAP's default), 1 keeps everything the photo shows, with blank
  // (black) pixels where it shows nothing; values between interpolate.
  double blank_pixels = 0.0;
  // Longest side of the undistorted images; larger ones are scaled down (focal lengths too).
  // <= 0: no limit.
  int max_image_size = -1;
  int jpeg_quality = 95;  // Of images written as JPEG (other formats are lossless).
  int num_threads = -1;   // Images undistorted in parallel; -1: all cores.
  void Check() const;
};

// The PINHOLE camera of `camera`'s undistorted images, as COLMAP's image_undistorter makes it:
// the same focal lengths, the image scaled about the principal point (kept at the same
// relative position) so that blank_pixels 0 shows only pixels from the photo and 1 all of it;
// then everything scaled down to max_image_size.
Camera UndistortedCamera(const Camera& camera, const UndistortionOptions& options);

// `image` (taken by `camera`, of its size) resampled into `undistorted` by bilinear
// interpolation, as COLMAP does; pixels that fall outside the photo are black.
cv::Mat UndistortImage(const cv::Mat& image, const Camera& camera, const Camera& undistorted);

// `model` in undistorted coordinates: `undistorted_cameras` (by camera id) replace its
// cameras, and every keypoint moves to where the PINHOLE camera sees its ray. Poses and points
// are unchanged, so a point reprojects as it did.
Reconstruction UndistortReconstruction(const Reconstruction& model,
                                       const std::map<camera_t, Camera>& undistorted_cameras);

struct UndistortionResult {
  size_t num_images = 0;
  double seconds = 0;
};

// COLMAP's dense workspace for the registered images of `model`, photos read from
// `image_dir`: OUT/images/ (undistorted, same names and formats), OUT/sparse/ (the undistorted
// model, binary), OUT/stereo/ (patch-match.cfg, fusion.cfg, and the empty folders COLMAP's
// patch_match_stereo fills). Each file is written atomically and sparse/ last, so an
// interrupted or failed run leaves no model over a partial image set; a rerun writes
// everything again. A missing photo is a MissingFileError naming it, raised before anything
// is written; a photo whose size is not its camera's an InputError naming it. Photos that are
// neither JPEG nor PNG are written as PNG, with ".png" added to their names.
UndistortionResult WriteUndistortedWorkspace(const Reconstruction& model,
                                             const std::filesystem::path& image_dir,
                                             const std::filesystem::path& output_dir,
                                             const UndistortionOptions& options);

}  // namespace parallax
