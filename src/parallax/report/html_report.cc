#include "parallax/report/html_report.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <opencv2/imgproc.hpp>
#include <tuple>
#include <unordered_map>

#include "parallax/image/image_codecs.h"
#include "parallax/math/dense_decompositions.h"
#include "parallax/report/html_report_assets.h"
#include "parallax/util/check.h"
#include "parallax/util/file.h"
#include "parallax/util/logging.h"

namespace parallax {
namespace {

using nlohmann::json;

std::string Base64Encode(const uint8_t* data, size_t size) {
  static constexpr char kAlphabet[] =
      "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  out.reserve((size + 2) / 3 * 4);
  for (size_t i = 0; i < size; i += 3) {
    const uint32_t b0 = data[i];
    const uint32_t b1 = i + 1 < size ? data[i + 1] : 0;
    const uint32_t b2 = i + 2 < size ? data[i + 2] : 0;
    const uint32_t triple = (b0 << 16) | (b1 << 8) | b2;
    out.push_back(kAlphabet[(triple >> 18) & 63]);
    out.push_back(kAlphabet[(triple >> 12) & 63]);
    out.push_back(i + 1 < size ? kAlphabet[(triple >> 6) & 63] : '=');
    out.push_back(i + 2 < size ? kAlphabet[triple & 63] : '=');
  }
  return out;
}

// Rounds to one decimal so that the embedded JSON stays short.
double Round1(double value) { return std::round(value * 10.0) / 10.0; }
double Round4(double value) { return std::round(value * 1e4) / 1e4; }

// A downscaled JPEG of an image as a data URL ("" when it cannot be read) and the size of
// the original.
struct EmbeddedImage {
  std::string data_url;
  int width = 0;
  int height = 0;
};

EmbeddedImage EmbedImage(const std::filesystem::path& path, const HtmlReportOptions& options) {
  EmbeddedImage embedded;
  std::error_code error;
  if (path.empty() || !std::filesystem::is_regular_file(path, error)) return embedded;
  cv::Mat image;
  try {
    image = ReadBitmap(path).color;
  } catch (const std::exception& exception) {
    PARALLAX_LOG(Warning) << path.string() << ": cannot decode image for the report ("
                          << exception.what() << ")";
    return embedded;
  }
  embedded.width = image.cols;
  embedded.height = image.rows;
  cv::Mat resized = image;
  const int longest = std::max(image.cols, image.rows);
  if (longest > options.max_image_size) {
    const double factor = static_cast<double>(options.max_image_size) / longest;
    cv::resize(image, resized, cv::Size(), factor, factor, cv::INTER_AREA);
  }
  const std::string bytes = EncodeJpeg(resized, options.jpeg_quality);
  embedded.data_url = "data:image/jpeg;base64," +
                      Base64Encode(reinterpret_cast<const uint8_t*>(bytes.data()), bytes.size());
  return embedded;
}

// Everything known about one image, merged from the database, the model and summary.json.
struct ImageRecord {
  image_t image_id = kInvalidImageId;
  std::string name;
  // Id in the reconstruction (kInvalidImageId when not in it).
  image_t model_image_id = kInvalidImageId;
  bool registered = false;
  long num_keypoints = -1;
  long num_observations = -1;
  std::optional<double> error_before_ba;
  std::optional<double> error_after_ba;
  std::string reason;
  const Camera* camera = nullptr;
};

std::optional<double> OptionalNumber(const json& object, const char* key) {
  if (!object.is_object() || !object.contains(key) || !object[key].is_number()) return std::nullopt;
  return object[key].get<double>();
}

class ReportBuilder {
 public:
  ReportBuilder(const HtmlReportInputs& inputs, const HtmlReportOptions& options)
      : inputs_(inputs), options_(options) {}

  json Build() {
    CollectImages();
    json data;
    data["title"] = inputs_.title;
    data["summary"] = inputs_.summary.is_object() ? inputs_.summary : json::object();
    data["images"] = ImagesJson();
    data["pairs"] = PairsJson();
    data["frames"] = FramesJson();
    data["best_pair"] = best_pair_;
    data["scene"] = SceneJson();
    data["evaluation"] = inputs_.evaluation ? MetricsToJson(*inputs_.evaluation) : json();
    data["has_database"] = inputs_.database != nullptr;
    data["has_images"] = !inputs_.image_dir.empty();
    return data;
  }

 private:
  ImageRecord& RecordByName(const std::string& name) {
    const auto it = index_by_name_.find(name);
    if (it != index_by_name_.end()) return records_[it->second];
    index_by_name_[name] = records_.size();
    records_.emplace_back();
    records_.back().name = name;
    return records_.back();
  }

  void CollectImages() {
    if (inputs_.database != nullptr) {
      for (const Camera& camera : inputs_.database->ReadAllCameras()) {
        database_cameras_[camera.camera_id] = camera;
      }
      for (const Image& image : inputs_.database->ReadAllImages()) {
        ImageRecord& record = RecordByName(image.name);
        record.image_id = image.image_id;
        record.num_keypoints = static_cast<long>(inputs_.database->NumKeypoints(image.image_id));
        const auto camera = database_cameras_.find(image.camera_id);
        if (camera != database_cameras_.end()) record.camera = &camera->second;
      }
    }
    if (inputs_.reconstruction != nullptr) {
      const Reconstruction& model = *inputs_.reconstruction;
      for (const auto& [image_id, image] : model.Images()) {
        ImageRecord& record = RecordByName(image.name);
        if (record.image_id == kInvalidImageId) record.image_id = image_id;
        record.model_image_id = image_id;
        record.registered = image.registered;
        record.camera = &model.GetCamera(image.camera_id);
        if (record.num_keypoints < 0) record.num_keypoints = static_cast<long>(image.NumPoints2D());
        if (image.registered) {
          record.num_observations = static_cast<long>(image.num_points3D);
          record.error_after_ba = model.MeanReprojectionErrorOfImage(image_id);
        }
      }
    }
    const json& summary = inputs_.summary;
    if (summary.is_object() && summary.contains("images") && summary["images"].is_array()) {
      for (const json& entry : summary["images"]) {
        if (!entry.is_object() || !entry.contains("name") || !entry["name"].is_string()) continue;
        ImageRecord& record = RecordByName(entry["name"].get<std::string>());
        if (record.image_id == kInvalidImageId && entry.contains("image_id") &&
            entry["image_id"].is_number_unsigned()) {
          record.image_id = entry["image_id"].get<image_t>();
        }
        if (record.model_image_id == kInvalidImageId && entry.contains("registered") &&
            entry["registered"].is_boolean()) {
          record.registered = entry["registered"].get<bool>();
        }
        if (const auto value = OptionalNumber(entry, "num_keypoints");
            value && record.num_keypoints < 0) {
          record.num_keypoints = static_cast<long>(*value);
        }
        if (const auto value = OptionalNumber(entry, "num_observations");
            value && record.num_observations < 0) {
          record.num_observations = static_cast<long>(*value);
        }
        if (const auto value = OptionalNumber(entry, "reprojection_error_before_ba_px")) {
          record.error_before_ba = value;
        }
        if (const auto value = OptionalNumber(entry, "reprojection_error_after_ba_px")) {
          record.error_after_ba = value;
        }
        if (entry.contains("reason") && entry["reason"].is_string()) {
          record.reason = entry["reason"].get<std::string>();
        }
      }
    }
    std::stable_sort(records_.begin(), records_.end(),
                     [](const ImageRecord& a, const ImageRecord& b) {
                       return std::tie(a.image_id, a.name) < std::tie(b.image_id, b.name);
                     });
    index_by_name_.clear();
    for (size_t i = 0; i < records_.size(); ++i) {
      index_by_name_[records_[i].name] = i;
      if (records_[i].image_id != kInvalidImageId) index_by_id_[records_[i].image_id] = i;
    }
  }

  json ImagesJson() const {
    json images = json::array();
    for (const ImageRecord& record : records_) {
      json entry = {{"id", record.image_id == kInvalidImageId ? -1L : long(record.image_id)},
                    {"name", record.name},
                    {"registered", record.registered},
                    {"keypoints", record.num_keypoints},
                    {"observations", record.num_observations},
                    {"error_before_ba",
                     record.error_before_ba ? json(Round4(*record.error_before_ba)) : json()},
                    {"error_after_ba",
                     record.error_after_ba ? json(Round4(*record.error_after_ba)) : json()}};
      if (!record.reason.empty()) entry["reason"] = record.reason;
      images.push_back(std::move(entry));
    }
    return images;
  }

  // [index1, index2, putative matches, verified inliers] per pair with any match.
  json PairsJson() {
    json pairs = json::array();
    if (inputs_.database == nullptr) return pairs;
    std::map<std::pair<size_t, size_t>, std::pair<long, long>> counts;
    auto indices = [&](image_pair_t pair_id) -> std::optional<std::pair<size_t, size_t>> {
      const auto [image_id1, image_id2] = PairIdToImagePair(pair_id);
      const auto it1 = index_by_id_.find(image_id1), it2 = index_by_id_.find(image_id2);
      if (it1 == index_by_id_.end() || it2 == index_by_id_.end()) return std::nullopt;
      return std::pair{it1->second, it2->second};
    };
    for (const auto& [pair_id, matches] : inputs_.database->ReadAllMatches()) {
      if (const auto pair = indices(pair_id))
        counts[*pair].first = static_cast<long>(matches.size());
    }
    size_t best_inliers = 0;
    image_pair_t best_pair_id = 0;
    for (const auto& [pair_id, geometry] : inputs_.database->ReadTwoViewGeometries()) {
      if (geometry.config == TwoViewGeometry::kUndefined ||
          geometry.config == TwoViewGeometry::kDegenerate) {
        continue;
      }
      const auto pair = indices(pair_id);
      if (!pair) continue;
      counts[*pair].second = static_cast<long>(geometry.inlier_matches.size());
      if (geometry.inlier_matches.size() > best_inliers) {
        best_inliers = geometry.inlier_matches.size();
        best_pair_id = pair_id;
      }
    }
    for (const auto& [pair, count] : counts) {
      pairs.push_back({pair.first, pair.second, count.first, count.second});
    }
    if (best_inliers > 0) BuildBestPair(best_pair_id);
    return pairs;
  }

  void BuildBestPair(image_pair_t pair_id) {
    const auto [image_id1, image_id2] = PairIdToImagePair(pair_id);
    const TwoViewGeometry geometry = inputs_.database->ReadTwoViewGeometry(image_id1, image_id2);
    const FeatureKeypoints keypoints1 = inputs_.database->ReadKeypoints(image_id1);
    const FeatureKeypoints keypoints2 = inputs_.database->ReadKeypoints(image_id2);
    const size_t num_matches = geometry.inlier_matches.size();
    const size_t step = std::max<size_t>(1, (num_matches + options_.max_matches_drawn - 1) /
                                                static_cast<size_t>(options_.max_matches_drawn));
    json lines = json::array();
    for (size_t i = 0; i < num_matches; i += step) {
      const FeatureMatch& match = geometry.inlier_matches[i];
      if (match.point2D_idx1 >= keypoints1.size() || match.point2D_idx2 >= keypoints2.size())
        continue;
      const FeatureKeypoint& a = keypoints1[match.point2D_idx1];
      const FeatureKeypoint& b = keypoints2[match.point2D_idx2];
      for (double value : {a.x, a.y, b.x, b.y}) lines.push_back(Round1(value));
    }
    best_pair_ = {{"frame1", FrameIndex(index_by_id_.at(image_id1), nullptr)},
                  {"frame2", FrameIndex(index_by_id_.at(image_id2), nullptr)},
                  {"num_inliers", num_matches},
                  {"config", geometry.config},
                  {"lines", std::move(lines)}};
  }

  // Index into frames_ of an image, embedding it on first use; `keypoints` (optional) are
  // drawn on it.
  size_t FrameIndex(size_t record_index, const FeatureKeypoints* keypoints) {
    const auto it = frame_by_record_.find(record_index);
    size_t frame_index;
    if (it != frame_by_record_.end()) {
      frame_index = it->second;
    } else {
      const ImageRecord& record = records_[record_index];
      const EmbeddedImage embedded = inputs_.image_dir.empty()
                                         ? EmbeddedImage()
                                         : EmbedImage(inputs_.image_dir / record.name, options_);
      json frame = {{"image", record_index}, {"url", embedded.data_url}};
      double width = embedded.width, height = embedded.height;
      if (embedded.data_url.empty() && record.camera != nullptr) {
        width =
            record.camera->width > 0 ? record.camera->width : 2 * record.camera->PrincipalPointX();
        height = record.camera->height > 0 ? record.camera->height
                                           : 2 * record.camera->PrincipalPointY();
      }
      frame["width"] = width;
      frame["height"] = height;
      frame_index = frames_.size();
      frames_.push_back(std::move(frame));
      frame_by_record_[record_index] = frame_index;
    }
    if (keypoints != nullptr) {
      json flat = json::array();
      const size_t step =
          std::max<size_t>(1, (keypoints->size() + options_.max_keypoints_drawn - 1) /
                                  static_cast<size_t>(options_.max_keypoints_drawn));
      for (size_t i = 0; i < keypoints->size(); i += step) {
        const FeatureKeypoint& keypoint = (*keypoints)[i];
        flat.push_back(Round1(keypoint.x));
        flat.push_back(Round1(keypoint.y));
        flat.push_back(Round1(keypoint.ComputeScale()));
      }
      frames_[frame_index]["keypoints"] = std::move(flat);
      frames_[frame_index]["num_keypoints"] = keypoints->size();
    }
    return frame_index;
  }

  FeatureKeypoints KeypointsOf(size_t record_index) const {
    const ImageRecord& record = records_[record_index];
    if (inputs_.database != nullptr && record.image_id != kInvalidImageId &&
        inputs_.database->ExistsKeypoints(record.image_id)) {
      return inputs_.database->ReadKeypoints(record.image_id);
    }
    FeatureKeypoints keypoints;
    if (inputs_.reconstruction != nullptr && record.model_image_id != kInvalidImageId) {
      for (const Point2D& point :
           inputs_.reconstruction->GetImage(record.model_image_id).points2D) {
        keypoints.emplace_back(static_cast<float>(point.xy.x()), static_cast<float>(point.xy.y()));
      }
    }
    return keypoints;
  }

  // The keypoint frames are the first and the middle image; the best pair's frames were
  // added by PairsJson.
  json FramesJson() {
    std::vector<size_t> record_indices;
    if (!records_.empty()) record_indices.push_back(0);
    if (records_.size() > 1) record_indices.push_back(records_.size() / 2);
    json keypoint_frames = json::array();
    for (size_t record_index : record_indices) {
      const FeatureKeypoints keypoints = KeypointsOf(record_index);
      keypoint_frames.push_back(FrameIndex(record_index, &keypoints));
    }
    return {{"list", frames_}, {"keypoint_frames", keypoint_frames}};
  }

  json SceneJson() const;

  const HtmlReportInputs& inputs_;
  const HtmlReportOptions& options_;
  std::vector<ImageRecord> records_;
  std::unordered_map<std::string, size_t> index_by_name_;
  std::unordered_map<image_t, size_t> index_by_id_;
  std::map<camera_t, Camera> database_cameras_;
  std::vector<json> frames_;
  std::unordered_map<size_t, size_t> frame_by_record_;
  json best_pair_;
};

// Scene framing: a robust centre, a radius that holds the cameras and most points, an up
// vector and a "front" direction (see the page text for their definitions).
json ReportBuilder::SceneJson() const {
  json scene;
  if (inputs_.reconstruction == nullptr) return json();
  const Reconstruction& model = *inputs_.reconstruction;
  std::vector<const Image*> cameras;
  for (const auto& [image_id, image] : model.Images()) {
    if (image.registered) cameras.push_back(&image);
  }
  std::sort(cameras.begin(), cameras.end(),
            [](const Image* a, const Image* b) { return a->name < b->name; });
  std::vector<Eigen::Vector3d> points;
  std::vector<Eigen::Matrix<uint8_t, 3, 1>> colors;
  for (const auto& [point3D_id, point] : model.Points3D()) {
    points.push_back(point.xyz);
    colors.push_back(point.color);
  }
  if (cameras.empty() && points.empty()) return json();

  // Centre: per-axis median of the points (of the cameras without points).
  const std::vector<Eigen::Vector3d>* source = &points;
  std::vector<Eigen::Vector3d> centers;
  for (const Image* image : cameras) centers.push_back(image->ProjectionCenter());
  if (points.empty()) source = &centers;
  Eigen::Vector3d center;
  for (int axis = 0; axis < 3; ++axis) {
    std::vector<double> values;
    for (const auto& p : *source) values.push_back(p[axis]);
    std::nth_element(values.begin(), values.begin() + values.size() / 2, values.end());
    center[axis] = values[values.size() / 2];
  }
  // Radius: the 95th percentile of point distances, or the farthest camera.
  double radius = 0;
  if (!points.empty()) {
    std::vector<double> distances;
    for (const auto& p : points) distances.push_back((p - center).norm());
    const size_t k = std::min(distances.size() - 1, distances.size() * 95 / 100);
    std::nth_element(distances.begin(), distances.begin() + k, distances.end());
    radius = distances[k];
  }
  const double points_radius = radius;
  for (const auto& c : centers) radius = std::max(radius, (c - center).norm());
  if (!(radius > 0)) radius = 1.0;

  // Up: opposite the mean image "down" axis; when those cancel out on a ring of cameras
  // (templeRing's views are turned by 90 degrees, some upside down) the normal of the camera
  // plane.
  Eigen::Vector3d up = Eigen::Vector3d::Zero(), forward = Eigen::Vector3d::Zero();
  for (const Image* image : cameras) {
    const Eigen::Matrix3d R = image->cam_from_world.rotation.toRotationMatrix();
    up -= R.row(1).transpose();
    forward += R.row(2).transpose();
  }
  if (!cameras.empty()) {
    up /= cameras.size();
    forward /= cameras.size();
  }
  if (centers.size() >= 4) {
    Eigen::MatrixXd centered(centers.size(), 3);
    Eigen::Vector3d mean = Eigen::Vector3d::Zero();
    for (const auto& c : centers) mean += c;
    mean /= centers.size();
    for (size_t i = 0; i < centers.size(); ++i) centered.row(i) = (centers[i] - mean).transpose();
    Eigen::VectorXd s;
    Eigen::MatrixXd V;
    RightSingularSystem(centered, &s, &V);
    const bool ring = s[1] > 0.3 * s[0] && s[2] < 0.3 * s[1];
    if (ring && up.norm() < 0.7) {
      // Cameras around an object usually look slightly down at it; else side with the images.
      Eigen::Vector3d normal = V.col(2);
      const double look = forward.dot(normal);
      if (std::abs(look) > 0.05 ? look > 0 : normal.dot(up) < 0) normal = -normal;
      up = normal;
    }
  }
  up = up.norm() > 1e-6 ? up.normalized() : Eigen::Vector3d(0, -1, 0);
  forward -= forward.dot(up) * up;
  if (forward.norm() < 0.3 && !cameras.empty()) {
    forward = cameras.front()->ViewingDirection();
    forward -= forward.dot(up) * up;
  }
  if (forward.norm() < 1e-6) forward = up.unitOrthogonal();
  forward.normalize();

  // Frustum depth: a fraction of the typical spacing of neighbouring cameras.
  double spacing = 0;
  for (size_t i = 1; i < centers.size(); ++i) spacing += (centers[i] - centers[i - 1]).norm();
  spacing = centers.size() > 1 ? spacing / (centers.size() - 1) : radius;
  const double depth = std::clamp(0.8 * spacing, 0.03 * radius, 0.12 * radius);

  json camera_list = json::array();
  for (const Image* image : cameras) {
    const Camera& camera = model.GetCamera(image->camera_id);
    const double width = camera.width > 0 ? camera.width : 2 * camera.PrincipalPointX();
    const double height = camera.height > 0 ? camera.height : 2 * camera.PrincipalPointY();
    const Rigid3d world_from_cam = image->cam_from_world.Inverse();
    json corners = json::array();
    for (const auto& [u, v] : {std::pair{0.0, 0.0}, {width, 0.0}, {width, height}, {0.0, height}}) {
      const Eigen::Vector2d normalized = camera.CamFromImg(Eigen::Vector2d(u, v));
      const Eigen::Vector3d corner = world_from_cam * (depth * normalized.homogeneous()) - center;
      for (int axis = 0; axis < 3; ++axis) corners.push_back(corner[axis]);
    }
    const Eigen::Vector3d c = image->ProjectionCenter() - center;
    camera_list.push_back({{"name", image->name}, {"c", {c.x(), c.y(), c.z()}}, {"k", corners}});
  }

  const size_t step = std::max<size_t>(
      1, (points.size() + options_.max_points3D - 1) / static_cast<size_t>(options_.max_points3D));
  std::vector<float> xyz;
  std::vector<uint8_t> rgb;
  for (size_t i = 0; i < points.size(); i += step) {
    for (int axis = 0; axis < 3; ++axis) {
      xyz.push_back(static_cast<float>(points[i][axis] - center[axis]));
      rgb.push_back(colors[i][axis]);
    }
  }
  scene["num_points"] = xyz.size() / 3;
  scene["num_points_total"] = points.size();
  scene["points"] =
      Base64Encode(reinterpret_cast<const uint8_t*>(xyz.data()), xyz.size() * sizeof(float));
  scene["colors"] = Base64Encode(rgb.data(), rgb.size());
  scene["cameras"] = std::move(camera_list);
  scene["center"] = {center.x(), center.y(), center.z()};
  scene["radius"] = radius;
  scene["points_radius"] = points_radius;
  scene["up"] = {up.x(), up.y(), up.z()};
  scene["forward"] = {forward.x(), forward.y(), forward.z()};
  return scene;
}

std::string EscapeHtml(const std::string& text) {
  std::string out;
  for (char c : text) {
    switch (c) {
      case '&':
        out += "&amp;";
        break;
      case '<':
        out += "&lt;";
        break;
      case '>':
        out += "&gt;";
        break;
      case '"':
        out += "&quot;";
        break;
      default:
        out.push_back(c);
    }
  }
  return out;
}

// JSON that is safe inside <script>: '<' (only ever inside strings) becomes \u003c, so no
// "</script>" or "<!--" can end or confuse the element.
std::string JsonForScript(const json& data) {
  const std::string text = data.dump(-1, ' ', false, json::error_handler_t::replace);
  std::string out;
  out.reserve(text.size());
  for (char c : text) {
    if (c == '<') {
      out += "\\u003c";
    } else {
      out.push_back(c);
    }
  }
  return out;
}

}  // namespace

void HtmlReportOptions::Check() const {
  PARALLAX_CHECK_GE(max_image_size, 16);
  PARALLAX_CHECK_GE(jpeg_quality, 1);
  PARALLAX_CHECK_LE(jpeg_quality, 100);
  PARALLAX_CHECK_GT(max_keypoints_drawn, 0);
  PARALLAX_CHECK_GT(max_matches_drawn, 0);
  PARALLAX_CHECK_GT(max_points3D, 0);
}

std::string BuildHtmlReport(const HtmlReportInputs& inputs, const HtmlReportOptions& options) {
  options.Check();
  const json data = ReportBuilder(inputs, options).Build();
  std::string html;
  html += "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n";
  html += "<meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">\n";
  html += "<link rel=\"icon\" href=\"data:,\">\n";
  html += "<title>" + EscapeHtml(inputs.title) + "</title>\n";
  html += "<script>\n" + std::string(internal::HtmlReportErrorTrapScript()) + "</script>\n";
  html += "<style>\n" + std::string(internal::HtmlReportStyle()) + "</style>\n</head>\n<body>\n";
  html += "<div id=\"report-status\" hidden>pending</div>\n";
  html += "<div id=\"report-pixels\" hidden>-1</div>\n";
  html += "<div id=\"report\"></div>\n";
  html += "<div id=\"tooltip\" class=\"tooltip\"></div>\n";
  html +=
      "<script type=\"application/json\" id=\"report-data\">" + JsonForScript(data) + "</script>\n";
  for (const char* script : {internal::HtmlReportPlotsScript(), internal::HtmlReportViewerScript(),
                             internal::HtmlReportMainScript()}) {
    html += "<script>\n" + std::string(script) + "</script>\n";
  }
  html += "</body>\n</html>\n";
  return html;
}

void WriteHtmlReport(const HtmlReportInputs& inputs, const std::filesystem::path& path,
                     const HtmlReportOptions& options) {
  WriteTextFileAtomically(path, BuildHtmlReport(inputs, options));
}

}  // namespace parallax
