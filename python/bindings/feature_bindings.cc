// extract_sift: the pipeline's SIFT (OpenCV's detector, RootSIFT descriptors) on a numpy image.
#include <pybind11/numpy.h>
#include <pybind11/stl/filesystem.h>

#include <opencv2/imgproc.hpp>

#include "bindings.h"
#include "parallax/feature/sift.h"
#include "parallax/image/image_reader.h"
#include "parallax/pipeline/extraction_stage.h"

namespace py = pybind11;

namespace parallax::python {
namespace {

// An H x W (grey), H x W x 3 (RGB) or H x W x 4 (RGBA) array, uint8 or float in [0, 1], as the
// 8-bit grey image SIFT takes.
cv::Mat GrayImage(const py::array& image) {
  py::object source = image;
  if (image.dtype().kind() == 'f') {
    const py::module_ numpy = py::module_::import("numpy");
    source = numpy.attr("clip")(numpy.attr("rint")(image.attr("__mul__")(255.0)), 0, 255);
  }
  const auto pixels =
      py::array_t<uint8_t, py::array::c_style | py::array::forcecast>::ensure(source);
  const char* kShapeError =
      "image: expected an H x W, H x W x 3 or H x W x 4 array of at least 16 x 16 pixels";
  if (!pixels) throw py::value_error(kShapeError);
  const py::ssize_t channels = pixels.ndim() == 3 ? pixels.shape(2) : 1;
  if ((pixels.ndim() != 2 && pixels.ndim() != 3) ||
      (channels != 1 && channels != 3 && channels != 4) || pixels.shape(0) < 16 ||
      pixels.shape(1) < 16) {
    throw py::value_error(kShapeError);
  }
  const int rows = static_cast<int>(pixels.shape(0));
  const int cols = static_cast<int>(pixels.shape(1));
  const cv::Mat wrapped(rows, cols, CV_8UC(static_cast<int>(channels)),
                        const_cast<uint8_t*>(pixels.data()));
  cv::Mat gray;
  if (channels == 1) {
    gray = wrapped.clone();
  } else {
    cv::cvtColor(wrapped, gray, channels == 3 ? cv::COLOR_RGB2GRAY : cv::COLOR_RGBA2GRAY);
  }
  return gray;
}

py::tuple ExtractSift(const py::array& image, const std::string& sift, int max_features,
                      int max_image_size, int max_upsampled_size, double sift_contrast,
                      double sift_edge, bool root_sift) {
  SiftExtractionOptions options = ExtractionStageOptions().sift;
  const std::optional<SiftImplementation> implementation = SiftImplementationFromName(sift);
  if (!implementation) {
    throw py::value_error("sift must be 'native' or 'opencv', not '" + sift + "'");
  }
  options.implementation = *implementation;
  options.max_num_features = max_features;
  options.max_image_size = max_image_size;
  options.max_upsampled_image_size = max_upsampled_size;
  options.contrast_threshold = sift_contrast;
  options.edge_threshold = sift_edge;
  options.root_sift = root_sift;
  options.Check();
  const cv::Mat gray = GrayImage(image);
  FeatureKeypoints keypoints;
  FeatureDescriptors descriptors;
  {
    py::gil_scoped_release release;
    CreateSiftExtractor(options)->Extract(gray, &keypoints, &descriptors);
  }
  py::array_t<float> frames({static_cast<py::ssize_t>(keypoints.size()), py::ssize_t{4}});
  auto frame = frames.mutable_unchecked<2>();
  for (size_t i = 0; i < keypoints.size(); ++i) {
    frame(i, 0) = keypoints[i].x;
    frame(i, 1) = keypoints[i].y;
    frame(i, 2) = keypoints[i].ComputeScale();
    frame(i, 3) = keypoints[i].ComputeOrientation();
  }
  py::array_t<uint8_t> rows(
      {static_cast<py::ssize_t>(descriptors.rows()), static_cast<py::ssize_t>(descriptors.cols())});
  std::copy(descriptors.data(), descriptors.data() + descriptors.size(), rows.mutable_data());
  return py::make_tuple(frames, rows);
}

// An image file as the pipeline reads it (by content, EXIF orientation applied): H x W x 3 RGB,
// or H x W grey.
py::array_t<uint8_t> ReadImage(const std::filesystem::path& path, bool grayscale) {
  Bitmap bitmap;
  {
    py::gil_scoped_release release;
    bitmap = ReadBitmap(path);
  }
  cv::Mat pixels;
  if (grayscale) {
    pixels = bitmap.gray;
  } else {
    cv::cvtColor(bitmap.color, pixels, cv::COLOR_BGR2RGB);
  }
  std::vector<py::ssize_t> shape = {pixels.rows, pixels.cols};
  if (!grayscale) shape.push_back(3);
  py::array_t<uint8_t> array(shape);
  const size_t row_bytes = static_cast<size_t>(pixels.cols) * pixels.channels();
  for (int row = 0; row < pixels.rows; ++row) {
    std::copy(pixels.ptr<uint8_t>(row), pixels.ptr<uint8_t>(row) + row_bytes,
              array.mutable_data() + row * row_bytes);
  }
  return array;
}

}  // namespace

void BindFeatures(py::module_& m) {
  const SiftExtractionOptions defaults = ExtractionStageOptions().sift;
  m.def("extract_sift", &ExtractSift, py::arg("image"), py::kw_only(),
        py::arg("sift") = std::string(SiftImplementationName(defaults.implementation)),
        py::arg("max_features") = defaults.max_num_features,
        py::arg("max_image_size") = defaults.max_image_size,
        py::arg("max_upsampled_size") = defaults.max_upsampled_image_size,
        py::arg("sift_contrast") = defaults.contrast_threshold,
        py::arg("sift_edge") = defaults.edge_threshold, py::arg("root_sift") = defaults.root_sift,
        "SIFT features of an image (H x W grey, H x W x 3 RGB or H x W x 4 RGBA; uint8, or "
        "float in [0, 1]) as the pipeline extracts them. Returns (keypoints, descriptors): "
        "keypoints N x 4 float32 (x, y, scale, orientation in radians; pixel centres at +0.5, "
        "COLMAP's convention), descriptors N x 128 uint8 (RootSIFT unless root_sift=False). "
        "The keywords are the flags of `parallax features`.");
  m.def("read_image", &ReadImage, py::arg("path"), py::kw_only(), py::arg("grayscale") = false,
        "Reads a JPEG, PNG, TIFF or BMP file as the pipeline does (by content, EXIF orientation "
        "applied): H x W x 3 RGB uint8, or H x W with grayscale=True.");
}

}  // namespace parallax::python
