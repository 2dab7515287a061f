#pragma once

#include <opencv2/core.hpp>

namespace parallax {

// The CV_32F image upsampled twice in each direction by bilinear interpolation between pixel
// centres, the same floats as cv::resize(src, dst, 2 x size, 0, 0, INTER_LINEAR): output
// pixel X lies at input coordinate (X + 0.5) / 2 - 0.5, so it weighs the two inputs around it
// by 3/4 and 1/4; the edge columns repeat the input's, and the edge rows weigh one input row
// twice, as OpenCV does. The native SIFT's doubled first octave starts here, faster than
// cv::resize (docs/performance.md, "Upsampling for the doubled first octave"). `dst` must not
// share `src`'s data.
void UpsampleTwice(const cv::Mat& src, cv::Mat* dst);

// Every other pixel of every other row of a CV_32F image, from (0, 0): each octave after the
// first starts from the previous one's layer S so sampled (cv::resize with INTER_NEAREST to
// half the size picks the same pixels, in a third more time). `dst` must not share `src`'s
// data.
void SampleEveryOther(const cv::Mat& src, cv::Mat* dst);

}  // namespace parallax
