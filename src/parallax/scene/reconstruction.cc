#include "parallax/scene/reconstruction.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "parallax/util/check.h"

namespace parallax {

void Track::DeleteElement(image_t image_id, point2D_t point2D_idx) {
  for (size_t i = 0; i < elements.size(); ++i) {
    if (elements[i].image_id == image_id && elements[i].point2D_idx == point2D_idx) {
      DeleteElement(i);
      return;
    }
  }
}

const Camera& Reconstruction::GetCamera(camera_t camera_id) const {
  const auto it = cameras_.find(camera_id);
  PARALLAX_CHECK_MSG(it != cameras_.end(), "no camera " << camera_id);
  return it->second;
}
Camera& Reconstruction::GetCamera(camera_t camera_id) {
  return const_cast<Camera&>(static_cast<const Reconstruction*>(this)->GetCamera(camera_id));
}
const Image& Reconstruction::GetImage(image_t image_id) const {
  const auto it = images_.find(image_id);
  PARALLAX_CHECK_MSG(it != images_.end(), "no image " << image_id);
  return it->second;
}
Image& Reconstruction::GetImage(image_t image_id) {
  return const_cast<Image&>(static_cast<const Reconstruction*>(this)->GetImage(image_id));
}
Reconstruction::Reconstruction(const Reconstruction& other)
    : cameras_(other.cameras_),
      images_(other.images_),
      points3D_(other.points3D_),
      next_point3D_id_(other.next_point3D_id_) {
  IndexPoints3DBelow(other.point_index_.size());
}

Reconstruction& Reconstruction::operator=(const Reconstruction& other) {
  if (this == &other) return *this;
  cameras_ = other.cameras_;
  images_ = other.images_;
  points3D_ = other.points3D_;
  next_point3D_id_ = other.next_point3D_id_;
  point_index_.clear();
  IndexPoints3DBelow(other.point_index_.size());
  return *this;
}

Point3D* Reconstruction::FindPoint3D(point3D_t point3D_id) const {
  if (point3D_id < point_index_.size()) return point_index_[point3D_id];
  const auto it = points3D_.find(point3D_id);
  return it == points3D_.end() ? nullptr : const_cast<Point3D*>(&it->second);
}

void Reconstruction::IndexPoints3DBelow(size_t end) {
  const size_t begin = point_index_.size();
  if (end <= begin) return;
  point_index_.resize(end, nullptr);
  for (auto it = points3D_.lower_bound(static_cast<point3D_t>(begin));
       it != points3D_.end() && it->first < end; ++it) {
    point_index_[it->first] = &it->second;
  }
}

void Reconstruction::IndexPoint3D(point3D_t point3D_id, Point3D* point) {
  if (point3D_id < point_index_.size()) {
    point_index_[point3D_id] = point;
  } else if (IdsFitFlatTable(point3D_id, points3D_.size())) {
    IndexPoints3DBelow(std::max<size_t>(point3D_id + 1, 2 * point_index_.size()));
  }
}

const Point3D& Reconstruction::GetPoint3D(point3D_t point3D_id) const {
  const Point3D* point = FindPoint3D(point3D_id);
  PARALLAX_CHECK_MSG(point != nullptr, "no 3D point " << point3D_id);
  return *point;
}
Point3D& Reconstruction::GetPoint3D(point3D_t point3D_id) {
  return const_cast<Point3D&>(static_cast<const Reconstruction*>(this)->GetPoint3D(point3D_id));
}

void Reconstruction::AddCamera(Camera camera) {
  PARALLAX_CHECK(!ExistsCamera(camera.camera_id));
  PARALLAX_CHECK_MSG(camera.VerifyParams(), "invalid parameters for camera " << camera.camera_id);
  cameras_.emplace(camera.camera_id, std::move(camera));
}

void Reconstruction::AddImage(Image image) {
  PARALLAX_CHECK(!ExistsImage(image.image_id));
  PARALLAX_CHECK_MSG(ExistsCamera(image.camera_id),
                     "image " << image.image_id << " refers to missing camera " << image.camera_id);
  image.num_points3D = 0;
  for (const Point2D& point : image.points2D) {
    if (point.HasPoint3D()) ++image.num_points3D;
  }
  images_.emplace(image.image_id, std::move(image));
}

point3D_t Reconstruction::AddPoint3D(const Eigen::Vector3d& xyz, Track track,
                                     const Eigen::Matrix<uint8_t, 3, 1>& color) {
  const point3D_t point3D_id = next_point3D_id_++;
  for (const TrackElement& element : track.elements) {
    Image& image = GetImage(element.image_id);
    PARALLAX_CHECK_LT(element.point2D_idx, image.points2D.size());
    Point2D& point2D = image.points2D[element.point2D_idx];
    PARALLAX_CHECK_MSG(!point2D.HasPoint3D(), "observation already has a 3D point");
    point2D.point3D_id = point3D_id;
    ++image.num_points3D;
  }
  Point3D point;
  point.xyz = xyz;
  point.color = color;
  point.track = std::move(track);
  Point3D* added = &points3D_.emplace(point3D_id, std::move(point)).first->second;
  IndexPoint3D(point3D_id, added);
  return point3D_id;
}

void Reconstruction::AddPoint3DWithId(point3D_t point3D_id, Point3D point) {
  PARALLAX_CHECK(!ExistsPoint3D(point3D_id));
  for (const TrackElement& element : point.track.elements) {
    PARALLAX_CHECK_MSG(ExistsImage(element.image_id), "3D point " << point3D_id
                                                                  << " observed in missing image "
                                                                  << element.image_id);
    Image& image = GetImage(element.image_id);
    PARALLAX_CHECK_MSG(element.point2D_idx < image.points2D.size(),
                       "3D point " << point3D_id << " refers to missing keypoint "
                                   << element.point2D_idx << " of image " << element.image_id);
    Point2D& point2D = image.points2D[element.point2D_idx];
    if (!point2D.HasPoint3D()) ++image.num_points3D;
    point2D.point3D_id = point3D_id;
  }
  Point3D* added = &points3D_.emplace(point3D_id, std::move(point)).first->second;
  IndexPoint3D(point3D_id, added);
  next_point3D_id_ = std::max(next_point3D_id_, point3D_id + 1);
}

void Reconstruction::AddObservation(point3D_t point3D_id, const TrackElement& element) {
  Image& image = GetImage(element.image_id);
  PARALLAX_CHECK_LT(element.point2D_idx, image.points2D.size());
  Point2D& point2D = image.points2D[element.point2D_idx];
  PARALLAX_CHECK_MSG(!point2D.HasPoint3D(), "observation already has a 3D point");
  Point3D& point = GetPoint3D(point3D_id);
  point2D.point3D_id = point3D_id;
  ++image.num_points3D;
  point.track.elements.push_back(element);
}

void Reconstruction::DeleteObservation(image_t image_id, point2D_t point2D_idx) {
  Image& image = GetImage(image_id);
  Point2D& point2D = image.points2D.at(point2D_idx);
  if (!point2D.HasPoint3D()) return;
  const point3D_t point3D_id = point2D.point3D_id;
  Point3D& point = GetPoint3D(point3D_id);
  if (point.track.Length() <= 2) {
    DeletePoint3D(point3D_id);
    return;
  }
  point.track.DeleteElement(image_id, point2D_idx);
  point2D.point3D_id = kInvalidPoint3DId;
  --image.num_points3D;
  if (keep_removed_observations_) {
    removed_observations_.push_back({{image_id, point2D_idx}, point3D_id});
  }
}

void Reconstruction::DeletePoint3D(point3D_t point3D_id) {
  const auto it = points3D_.find(point3D_id);
  PARALLAX_CHECK(it != points3D_.end());
  for (const TrackElement& element : it->second.track.elements) {
    Image& image = GetImage(element.image_id);
    image.points2D[element.point2D_idx].point3D_id = kInvalidPoint3DId;
    --image.num_points3D;
    if (keep_removed_observations_) removed_observations_.push_back({element, point3D_id});
  }
  if (point3D_id < point_index_.size()) point_index_[point3D_id] = nullptr;
  points3D_.erase(it);
}

point3D_t Reconstruction::MergePoints3D(point3D_t point3D_id1, point3D_t point3D_id2) {
  const Point3D& point1 = GetPoint3D(point3D_id1);
  const Point3D& point2 = GetPoint3D(point3D_id2);
  const double weight1 = static_cast<double>(point1.track.Length());
  const double weight2 = static_cast<double>(point2.track.Length());
  const Eigen::Vector3d xyz = (weight1 * point1.xyz + weight2 * point2.xyz) / (weight1 + weight2);
  const Eigen::Vector3d color =
      (weight1 * point1.color.cast<double>() + weight2 * point2.color.cast<double>()) /
      (weight1 + weight2);
  Track track = point1.track;
  track.elements.insert(track.elements.end(), point2.track.elements.begin(),
                        point2.track.elements.end());
  DeletePoint3D(point3D_id1);
  DeletePoint3D(point3D_id2);
  return AddPoint3D(xyz, std::move(track), color.array().round().cast<uint8_t>());
}

std::vector<Reconstruction::RemovedObservation> Reconstruction::TakeRemovedObservations() {
  std::vector<RemovedObservation> removed;
  removed.swap(removed_observations_);
  return removed;
}

void Reconstruction::RegisterImage(image_t image_id) { GetImage(image_id).registered = true; }

void Reconstruction::DeRegisterImage(image_t image_id) {
  Image& image = GetImage(image_id);
  for (point2D_t idx = 0; idx < image.points2D.size(); ++idx) {
    if (image.points2D[idx].HasPoint3D()) DeleteObservation(image_id, idx);
  }
  image.registered = false;
}

bool Reconstruction::IsImageRegistered(image_t image_id) const {
  return GetImage(image_id).registered;
}

std::vector<image_t> Reconstruction::RegImageIds() const {
  std::vector<image_t> ids;
  for (const auto& [image_id, image] : images_) {
    if (image.registered) ids.push_back(image_id);
  }
  return ids;
}

size_t Reconstruction::NumRegImages() const { return RegImageIds().size(); }

size_t Reconstruction::NumObservations() const {
  size_t count = 0;
  for (const auto& [id, point] : points3D_) count += point.track.Length();
  return count;
}

double Reconstruction::ComputeMeanTrackLength() const {
  return points3D_.empty() ? 0.0 : static_cast<double>(NumObservations()) / points3D_.size();
}

std::map<size_t, size_t> Reconstruction::ComputeTrackLengthHistogram() const {
  std::map<size_t, size_t> histogram;
  for (const auto& [point3D_id, point] : points3D_) ++histogram[point.track.Length()];
  return histogram;
}

double Reconstruction::ComputeMeanObservationsPerRegImage() const {
  const size_t num_reg = NumRegImages();
  return num_reg == 0 ? 0.0 : static_cast<double>(NumObservations()) / num_reg;
}

double Reconstruction::ReprojectionError(image_t image_id, point2D_t point2D_idx) const {
  const Point2D& point2D = GetImage(image_id).points2D.at(point2D_idx);
  PARALLAX_CHECK(point2D.HasPoint3D());
  return ReprojectionError(image_id, point2D_idx, GetPoint3D(point2D.point3D_id).xyz);
}

double Reconstruction::ReprojectionError(image_t image_id, point2D_t point2D_idx,
                                         const Eigen::Vector3d& xyz) const {
  const Image& image = GetImage(image_id);
  return parallax::ReprojectionError(image, GetCamera(image.camera_id), point2D_idx, xyz);
}

double Reconstruction::UpdatePointErrors() {
  double sum = 0;
  size_t count = 0;
  for (auto& [point3D_id, point] : points3D_) {
    double point_sum = 0;
    for (const TrackElement& element : point.track.elements) {
      point_sum += ReprojectionError(element.image_id, element.point2D_idx);
    }
    point.error = point.track.Length() > 0 ? point_sum / point.track.Length() : 0.0;
    sum += point_sum;
    count += point.track.Length();
  }
  return count > 0 ? sum / count : 0.0;
}

double Reconstruction::MeanReprojectionErrorOfImage(image_t image_id) const {
  const Image& image = GetImage(image_id);
  double sum = 0;
  size_t count = 0;
  for (point2D_t idx = 0; idx < image.points2D.size(); ++idx) {
    if (!image.points2D[idx].HasPoint3D()) continue;
    sum += ReprojectionError(image_id, idx);
    ++count;
  }
  return count > 0 ? sum / count : 0.0;
}

void Reconstruction::Transform(const Sim3d& new_from_old) {
  for (auto& [point3D_id, point] : points3D_) point.xyz = new_from_old * point.xyz;
  for (auto& [image_id, image] : images_) {
    image.cam_from_world = TransformCameraPose(new_from_old, image.cam_from_world);
  }
}

double ReprojectionError(const Image& image, const Camera& camera, point2D_t point2D_idx,
                         const Eigen::Vector3d& xyz) {
  const Eigen::Vector3d point_in_cam = image.cam_from_world * xyz;
  if (point_in_cam.z() <= std::numeric_limits<double>::epsilon()) {
    return std::numeric_limits<double>::infinity();
  }
  return (camera.ImgFromCam(point_in_cam) - image.points2D[point2D_idx].xy).norm();
}

}  // namespace parallax
