#include "parallax/calibration/checkerboard_calibration.h"

#include <algorithm>
#include <cctype>
#include <cfloat>
#include <cmath>
#include <map>
#include <opencv2/calib3d.hpp>
#include <opencv2/imgproc.hpp>
#include <set>

#include "parallax/calibration/exif.h"
#include "parallax/image/image_reader.h"
#include "parallax/util/check.h"
#include "parallax/util/logging.h"
#include "parallax/util/threading.h"

namespace parallax {
namespace {

std::string SizeString(int width, int height) {
  return std::to_string(width) + "x" + std::to_string(height);
}

// The image as a viewer shows it for EXIF orientation 1-8 (rotations and mirrorings).
cv::Mat ApplyExifOrientation(const cv::Mat& image, int orientation) {
  cv::Mat out;
  switch (orientation) {
    case 2:
      cv::flip(image, out, 1);
      return out;
    case 3:
      cv::rotate(image, out, cv::ROTATE_180);
      return out;
    case 4:
      cv::flip(image, out, 0);
      return out;
    case 5:
      cv::transpose(image, out);
      return out;
    case 6:
      cv::rotate(image, out, cv::ROTATE_90_CLOCKWISE);
      return out;
    case 7:
      cv::transpose(image, out);
      cv::rotate(out, out, cv::ROTATE_180);
      return out;
    case 8:
      cv::rotate(image, out, cv::ROTATE_90_COUNTERCLOCKWISE);
      return out;
    default:
      return image;
  }
}

// 8-bit gray with EXIF orientation applied; empty when the file cannot be decoded.
cv::Mat DecodeGray(const std::filesystem::path& path, std::string* reason) {
  std::error_code error;
  if (!std::filesystem::is_regular_file(path, error)) {
    *reason = "not a readable file";
    return {};
  }
  cv::Mat gray;
  try {
    gray = ReadBitmap(path).gray;
    const std::optional<ExifData> exif = ReadExif(path);
    if (exif && exif->orientation) gray = ApplyExifOrientation(gray, *exif->orientation);
  } catch (const std::exception&) {
    gray.release();
  }
  if (gray.empty()) *reason = "cannot be decoded as an image";
  return gray;
}

// Smallest distance between neighbouring corners of the grid (a square's side in pixels).
double MinCornerSpacing(const std::vector<cv::Point2f>& corners, int cols, int rows) {
  double min_spacing = std::numeric_limits<double>::max();
  for (int row = 0; row < rows; ++row) {
    for (int col = 0; col < cols; ++col) {
      const cv::Point2f& corner = corners[row * cols + col];
      if (col + 1 < cols)
        min_spacing =
            std::min<double>(min_spacing, cv::norm(corners[row * cols + col + 1] - corner));
      if (row + 1 < rows)
        min_spacing =
            std::min<double>(min_spacing, cv::norm(corners[(row + 1) * cols + col] - corner));
    }
  }
  return min_spacing;
}

std::vector<cv::Point3f> BoardPoints(const CheckerboardCalibrationOptions& options) {
  std::vector<cv::Point3f> points;
  points.reserve(options.pattern_cols * options.pattern_rows);
  for (int row = 0; row < options.pattern_rows; ++row) {
    for (int col = 0; col < options.pattern_cols; ++col) {
      points.emplace_back(static_cast<float>(col * options.square_size),
                          static_cast<float>(row * options.square_size), 0.f);
    }
  }
  return points;
}

}  // namespace

void CheckerboardCalibrationOptions::Check() const {
  PARALLAX_CHECK_GE(pattern_cols, 2);
  PARALLAX_CHECK_GE(pattern_rows, 2);
  PARALLAX_CHECK(std::isfinite(square_size));
  PARALLAX_CHECK_GT(square_size, 0);
  PARALLAX_CHECK_GE(required_width, 0);
  PARALLAX_CHECK_GE(required_height, 0);
  PARALLAX_CHECK_MSG((required_width == 0) == (required_height == 0),
                     "set both required_width and required_height, or neither");
  PARALLAX_CHECK_GE(subpixel_window_radius, 1);
  PARALLAX_CHECK_GE(detection_max_image_size, 0);
  PARALLAX_CHECK_GE(min_num_images, 1);
}

std::string CheckerboardImageStatusName(CheckerboardImageStatus status) {
  switch (status) {
    case CheckerboardImageStatus::kUsed:
      return "used";
    case CheckerboardImageStatus::kBoardNotFound:
      return "board not found";
    case CheckerboardImageStatus::kWrongSize:
      return "wrong size";
    case CheckerboardImageStatus::kUnreadable:
      return "unreadable";
  }
  return "unknown";
}

std::optional<std::vector<Eigen::Vector2d>> DetectCheckerboardCorners(
    const CheckerboardCalibrationOptions& options, const cv::Mat& gray) {
  options.Check();
  PARALLAX_CHECK_EQ(gray.type(), CV_8UC1);
  if (gray.empty()) return std::nullopt;
  const cv::Size pattern(options.pattern_cols, options.pattern_rows);

  // Detection cost grows quickly with image size; corners found on a smaller copy are
  // refined at full resolution below.
  const int max_side = std::max(gray.cols, gray.rows);
  double scale = 1;
  cv::Mat detection_image = gray;
  if (options.detection_max_image_size > 0 && max_side > options.detection_max_image_size) {
    scale = static_cast<double>(options.detection_max_image_size) / max_side;
    cv::resize(gray, detection_image, cv::Size(), scale, scale, cv::INTER_AREA);
  }

  std::vector<cv::Point2f> corners;
  bool found = false;
  if (options.use_sector_based_detector) {
    found = cv::findChessboardCornersSB(detection_image, pattern, corners,
                                        cv::CALIB_CB_NORMALIZE_IMAGE);
  } else {
    found = cv::findChessboardCorners(detection_image, pattern, corners,
                                      cv::CALIB_CB_ADAPTIVE_THRESH | cv::CALIB_CB_NORMALIZE_IMAGE);
  }
  if (!found || corners.size() != static_cast<size_t>(pattern.area())) return std::nullopt;

  if (scale != 1) {
    // Pixel centres: x_full + 0.5 = (x_small + 0.5) / scale.
    for (cv::Point2f& corner : corners) {
      corner.x = static_cast<float>((corner.x + 0.5) / scale - 0.5);
      corner.y = static_cast<float>((corner.y + 0.5) / scale - 0.5);
    }
  }
  // Refined at full resolution for both detectors (the sector-based one alone is off by up to
  // a quarter pixel on rendered boards). A window wider than about half a square would reach
  // the neighbouring corners.
  const double spacing = MinCornerSpacing(corners, pattern.width, pattern.height);
  const int radius =
      std::clamp(static_cast<int>(0.4 * spacing), 2, std::max(2, options.subpixel_window_radius));
  cv::cornerSubPix(gray, corners, cv::Size(radius, radius), cv::Size(-1, -1),
                   cv::TermCriteria(cv::TermCriteria::EPS + cv::TermCriteria::COUNT, 100, 1e-4));

  std::vector<Eigen::Vector2d> result;
  result.reserve(corners.size());
  for (const cv::Point2f& corner : corners) result.emplace_back(corner.x, corner.y);
  return result;
}

CheckerboardCalibrationResult CalibrateFromCheckerboardCorners(
    const CheckerboardCalibrationOptions& options, int width, int height,
    const std::vector<std::vector<Eigen::Vector2d>>& corners_per_view,
    std::vector<double>* per_view_rms_errors) {
  options.Check();
  PARALLAX_CHECK_GT(width, 0);
  PARALLAX_CHECK_GT(height, 0);
  CheckerboardCalibrationResult result;
  result.width = width;
  result.height = height;
  result.num_used_images = static_cast<int>(corners_per_view.size());
  if (static_cast<int>(corners_per_view.size()) < options.min_num_images) {
    result.message = "the board was found in " + std::to_string(corners_per_view.size()) +
                     " image(s) of " + SizeString(width, height) + "; at least " +
                     std::to_string(options.min_num_images) + " are needed";
    return result;
  }

  const std::vector<cv::Point3f> board_points = BoardPoints(options);
  std::vector<std::vector<cv::Point3f>> object_points;
  std::vector<std::vector<cv::Point2f>> image_points;
  for (const auto& corners : corners_per_view) {
    PARALLAX_CHECK_EQ(corners.size(), board_points.size());
    std::vector<cv::Point2f> view;
    view.reserve(corners.size());
    for (const Eigen::Vector2d& corner : corners) {
      view.emplace_back(static_cast<float>(corner.x()), static_cast<float>(corner.y()));
    }
    image_points.push_back(std::move(view));
    object_points.push_back(board_points);
  }

  cv::Mat camera_matrix, distortion, std_dev_intrinsics, std_dev_extrinsics, per_view_errors;
  std::vector<cv::Mat> rotations, translations;
  const int flags = options.fit_k3 ? 0 : cv::CALIB_FIX_K3;
  try {
    cv::calibrateCamera(
        object_points, image_points, cv::Size(width, height), camera_matrix, distortion, rotations,
        translations, std_dev_intrinsics, std_dev_extrinsics, per_view_errors, flags,
        cv::TermCriteria(cv::TermCriteria::COUNT + cv::TermCriteria::EPS, 100, DBL_EPSILON));
  } catch (const cv::Exception& exception) {
    result.message = std::string("calibrateCamera failed: ") + exception.what();
    return result;
  }

  // RMS of the 2D reprojection distances, per view and overall (OpenCV's definition).
  double total_squared_error = 0;
  size_t total_points = 0;
  std::vector<double> view_rms(image_points.size());
  for (size_t i = 0; i < image_points.size(); ++i) {
    std::vector<cv::Point2f> projected;
    cv::projectPoints(object_points[i], rotations[i], translations[i], camera_matrix, distortion,
                      projected);
    double squared_error = 0;
    for (size_t j = 0; j < projected.size(); ++j) {
      const cv::Point2f delta = projected[j] - image_points[i][j];
      squared_error +=
          static_cast<double>(delta.x) * delta.x + static_cast<double>(delta.y) * delta.y;
    }
    view_rms[i] = std::sqrt(squared_error / projected.size());
    total_squared_error += squared_error;
    total_points += projected.size();
  }
  if (per_view_rms_errors != nullptr) *per_view_rms_errors = view_rms;
  result.rms_error = std::sqrt(total_squared_error / total_points);

  const auto at = [](const cv::Mat& mat, int i) {
    return i < static_cast<int>(mat.total()) ? mat.at<double>(i) : 0.0;
  };
  result.fx = camera_matrix.at<double>(0, 0);
  result.fy = camera_matrix.at<double>(1, 1);
  result.cx = camera_matrix.at<double>(0, 2);
  result.cy = camera_matrix.at<double>(1, 2);
  result.fx_std_dev = at(std_dev_intrinsics, 0);
  result.fy_std_dev = at(std_dev_intrinsics, 1);
  result.cx_std_dev = at(std_dev_intrinsics, 2);
  result.cy_std_dev = at(std_dev_intrinsics, 3);
  result.distortion.resize(5);
  for (int i = 0; i < 5; ++i) result.distortion[i] = at(distortion, i);

  Camera& camera = result.camera;
  camera.camera_id = 1;
  camera.model_id = CameraModelId::kOpenCV;
  camera.width = static_cast<size_t>(width);
  camera.height = static_cast<size_t>(height);
  camera.params = {result.fx,
                   result.fy,
                   result.cx,
                   result.cy,
                   result.distortion[0],
                   result.distortion[1],
                   result.distortion[2],
                   result.distortion[3]};
  camera.has_prior_focal_length = true;
  if (!camera.VerifyParams() || !std::isfinite(result.rms_error)) {
    result.message = "calibrateCamera returned invalid intrinsics";
    return result;
  }
  if (options.fit_k3) {
    PARALLAX_LOG(Warning) << "k3 = " << result.distortion[4]
                          << " was fitted; COLMAP's OPENCV camera cannot represent it";
  }
  result.success = true;
  return result;
}

CheckerboardCalibrationResult CalibrateFromCheckerboards(
    const CheckerboardCalibrationOptions& options,
    const std::vector<std::filesystem::path>& image_paths) {
  options.Check();
  const int num_threads = EffectiveNumThreads(options.num_threads);
  std::vector<CheckerboardImageResult> images(image_paths.size());
  for (size_t i = 0; i < image_paths.size(); ++i) images[i].path = image_paths[i];

  // 1. Image sizes: photos of different sizes cannot share intrinsics.
  ParallelFor(0, images.size(), num_threads, [&](size_t i) {
    CheckerboardImageResult& image = images[i];
    const cv::Mat gray = DecodeGray(image.path, &image.reason);
    if (gray.empty()) return;
    image.width = gray.cols;
    image.height = gray.rows;
  });
  std::map<std::pair<int, int>, int> size_counts;
  for (const CheckerboardImageResult& image : images) {
    if (image.width > 0) ++size_counts[{image.width, image.height}];
  }

  // 2. The size to calibrate: the required one, else the most common (ties: the larger).
  std::pair<int, int> size(options.required_width, options.required_height);
  if (size.first == 0) {
    int best_count = 0;
    for (const auto& [candidate, count] : size_counts) {
      const int64_t area = static_cast<int64_t>(candidate.first) * candidate.second;
      const int64_t best_area = static_cast<int64_t>(size.first) * size.second;
      if (count > best_count || (count == best_count && area > best_area)) {
        size = candidate;
        best_count = count;
      }
    }
  }
  const std::string size_string = SizeString(size.first, size.second);
  std::vector<size_t> candidates;
  for (size_t i = 0; i < images.size(); ++i) {
    CheckerboardImageResult& image = images[i];
    if (image.width == 0) {
      image.status = CheckerboardImageStatus::kUnreadable;
    } else if (std::make_pair(image.width, image.height) != size) {
      image.status = CheckerboardImageStatus::kWrongSize;
      image.reason = SizeString(image.width, image.height) + " differs from the calibrated size " +
                     size_string;
    } else {
      candidates.push_back(i);
    }
  }

  // 3. Board corners, in parallel (each image decoded again to keep memory flat).
  ParallelFor(0, candidates.size(), num_threads, [&](size_t k) {
    CheckerboardImageResult& image = images[candidates[k]];
    const cv::Mat gray = DecodeGray(image.path, &image.reason);
    if (gray.empty()) {
      image.status = CheckerboardImageStatus::kUnreadable;
      return;
    }
    if (auto corners = DetectCheckerboardCorners(options, gray)) {
      image.status = CheckerboardImageStatus::kUsed;
      image.corners = std::move(*corners);
    } else {
      image.status = CheckerboardImageStatus::kBoardNotFound;
      image.reason =
          "no complete " + SizeString(options.pattern_cols, options.pattern_rows) + " board found";
    }
  });
  std::vector<size_t> used;
  std::vector<std::vector<Eigen::Vector2d>> corners_per_view;
  for (size_t i : candidates) {
    if (images[i].status != CheckerboardImageStatus::kUsed) continue;
    used.push_back(i);
    corners_per_view.push_back(images[i].corners);
  }
  PARALLAX_LOG(Info) << "Checkerboard found in " << used.size() << " of " << candidates.size()
                     << " images of " << size_string << " (" << images.size() << " given)";

  // 4. Zhang's calibration on the images of the chosen size.
  CheckerboardCalibrationResult result;
  if (size.first == 0) {
    result.message = "no readable image";
  } else if (candidates.empty()) {
    result.message = "no image is " + size_string;
    result.width = size.first;
    result.height = size.second;
  } else {
    std::vector<double> view_rms;
    result = CalibrateFromCheckerboardCorners(options, size.first, size.second, corners_per_view,
                                              &view_rms);
    for (size_t k = 0; k < view_rms.size(); ++k) images[used[k]].rms_error = view_rms[k];
  }
  result.images = std::move(images);
  return result;
}

CalibratedCamera CalibratedCameraFromResult(const CheckerboardCalibrationResult& result) {
  PARALLAX_CHECK_MSG(result.success, "calibration failed: " << result.message);
  CalibratedCamera calibrated;
  calibrated.camera = result.camera;
  calibrated.k3 = result.distortion.size() > 4 ? result.distortion[4] : 0.0;
  calibrated.rms_error = result.rms_error;
  calibrated.num_images = result.num_used_images;
  return calibrated;
}

std::vector<std::filesystem::path> ListCalibrationImages(const std::filesystem::path& dir) {
  static const std::set<std::string> kExtensions = {".jpg", ".jpeg", ".png",
                                                    ".tif", ".tiff", ".bmp"};
  if (!std::filesystem::is_directory(dir)) {
    throw MissingFileError(dir.string() + ": image folder does not exist");
  }
  std::vector<std::filesystem::path> paths;
  for (const auto& entry : std::filesystem::directory_iterator(dir)) {
    if (!entry.is_regular_file()) continue;
    std::string extension = entry.path().extension().string();
    std::transform(extension.begin(), extension.end(), extension.begin(),
                   [](unsigned char c) { return std::tolower(c); });
    if (kExtensions.count(extension)) paths.push_back(entry.path());
  }
  if (paths.empty()) {
    throw InputError(dir.string() + ": no images (.jpg, .jpeg, .png, .tif, .tiff, .bmp)");
  }
  std::sort(paths.begin(), paths.end());
  return paths;
}

}  // namespace parallax
