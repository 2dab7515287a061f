#pragma once

#include <memory>
#include <opencv2/core.hpp>
#include <vector>

namespace parallax {

// Parallax's own SIFT (Lowe 2004, with VLFeat's choices where Lowe leaves one open: the
// orientation histogram smoothed six times, up to `max_num_orientations` frames per extremum,
// a Gaussian descriptor window of two bins). Two things set it apart from OpenCV's:
//  - descriptors stay float until the caller quantises them, so RootSIFT's square root is
//    taken of exact values (OpenCV rounds each component to an integer of a 512-scaled unit
//    vector first, and the square root magnifies that rounding in the small components);
//  - positions are exact in every octave (OpenCV's doubled image puts them a quarter pixel off).
struct NativeSiftOptions {
  bool double_first_octave = true;  // Start from the image upsampled 2x (Lowe's octave -1).
  int num_octave_layers = 3;        // Layers per octave (S).
  // Smallest |DoG| of an extremum, in OpenCV's convention: divided by S, intensities in [0, 1].
  double contrast_threshold = 0.02;
  double edge_threshold = 10.0;  // Largest ratio of principal curvatures.
  double sigma = 1.6;            // Blur of each octave's first layer, in that octave's pixels.
  int max_num_orientations = 2;  // Frames per extremum, strongest orientation first.
  // Keep the frames of largest response, before descriptors are computed (0: all).
  int max_num_features = 0;
  void Check() const;
};

// A detected frame in the coordinates of the image given (COLMAP's convention: the top-left
// pixel's centre is (0.5, 0.5)); scale is the Gaussian sigma in pixels, orientation in radians
// from the x axis towards y (down).
struct SiftFrame {
  float x = 0, y = 0, scale = 0, orientation = 0;
  float response = 0;  // |DoG| at the refined extremum.
};

// The order frames are ranked and cut in: strongest response first; ties by position (y,
// then x), scale and orientation, so that the order is total and never a scan's.
bool FrameRanksBefore(const SiftFrame& a, const SiftFrame& b);

// The scale space and scratch one extraction works in (S + 2 float layers the size of the
// first octave, a third as much for the other octaves, and rings of gradient rows). Defined in
// native_sift_internal.h.
struct NativeSiftScaleSpace;

// Buffers for ComputeNativeSift: passing the same object to successive calls reuses them,
// since fresh pages cost more to fault in than the blurs take to compute. One call at a time
// per object; its memory goes with it.
class NativeSiftBuffers {
 public:
  NativeSiftBuffers();
  ~NativeSiftBuffers();
  NativeSiftBuffers(const NativeSiftBuffers&) = delete;
  NativeSiftBuffers& operator=(const NativeSiftBuffers&) = delete;
  NativeSiftScaleSpace& ScaleSpace() { return *space_; }

 private:
  std::unique_ptr<NativeSiftScaleSpace> space_;
};

// Detects SIFT frames in an 8-bit gray image and computes one descriptor per frame:
// descriptors->size() == 128 * frames->size(), each a unit-L2 vector clamped at 0.2 and
// renormalised (Lowe's), in frame order. Frames come in FrameRanksBefore's order.
// Without `buffers`, the call allocates its own and frees them when it returns.
void ComputeNativeSift(const cv::Mat& gray, const NativeSiftOptions& options,
                       std::vector<SiftFrame>* frames, std::vector<float>* descriptors,
                       NativeSiftBuffers* buffers = nullptr);

}  // namespace parallax
