#pragma once

#include <Eigen/Core>
#include <map>
#include <unordered_map>
#include <unordered_set>
#include <vector>

#include "parallax/geometry/sim3.h"
#include "parallax/scene/camera.h"
#include "parallax/scene/image.h"
#include "parallax/scene/point3d.h"
#include "parallax/util/types.h"

namespace parallax {

// The scene: cameras, images with poses and keypoints, and 3D points with their tracks.
// Keeps the two directions of every observation (Point2D::point3D_id and Point3D::track)
// consistent; all edits go through these methods. Ordered maps keep output and iteration
// deterministic.
class Reconstruction {
 public:
  Reconstruction() = default;
  Reconstruction(const Reconstruction& other);
  Reconstruction& operator=(const Reconstruction& other);
  Reconstruction(Reconstruction&&) = default;  // Map nodes move with the map: the index holds.
  Reconstruction& operator=(Reconstruction&&) = default;

  const std::map<camera_t, Camera>& Cameras() const { return cameras_; }
  const std::map<image_t, Image>& Images() const { return images_; }
  const std::map<point3D_t, Point3D>& Points3D() const { return points3D_; }

  bool ExistsCamera(camera_t camera_id) const { return cameras_.count(camera_id) > 0; }
  bool ExistsImage(image_t image_id) const { return images_.count(image_id) > 0; }
  bool ExistsPoint3D(point3D_t point3D_id) const { return FindPoint3D(point3D_id) != nullptr; }

  const Camera& GetCamera(camera_t camera_id) const;
  Camera& GetCamera(camera_t camera_id);
  const Image& GetImage(image_t image_id) const;
  Image& GetImage(image_t image_id);
  const Point3D& GetPoint3D(point3D_t point3D_id) const;
  Point3D& GetPoint3D(point3D_t point3D_id);

  void AddCamera(Camera camera);
  // The image's points2D must not reference 3D points yet.
  void AddImage(Image image);
  // Adds a point and links every track element to it. Returns the new id.
  point3D_t AddPoint3D(
      const Eigen::Vector3d& xyz, Track track,
      const Eigen::Matrix<uint8_t, 3, 1>& color = Eigen::Matrix<uint8_t, 3, 1>::Zero());
  // Adds the preset id (for reading models); the next generated id is kept above it.
  void AddPoint3DWithId(point3D_t point3D_id, Point3D point);
  void AddObservation(point3D_t point3D_id, const TrackElement& element);
  // Removes one observation; a point left with fewer than two observations is deleted.
  void DeleteObservation(image_t image_id, point2D_t point2D_idx);
  void DeletePoint3D(point3D_t point3D_id);
  // Merges two points into one at the track-weighted mean position; returns the merged id.
  point3D_t MergePoints3D(point3D_t point3D_id1, point3D_t point3D_id2);

  // An observation that left its point: filtered out, its image deregistered, or its point
  // deleted or merged away (the point may still exist).
  struct RemovedObservation {
    TrackElement element;
    point3D_t point3D_id = kInvalidPoint3DId;
  };
  // From now on, every removed observation is kept until taken: for state held beside the
  // model that must follow its points (the mapper's next-view scores). Copies do not keep.
  void KeepRemovedObservations() { keep_removed_observations_ = true; }
  // The observations removed since the last call, oldest first.
  std::vector<RemovedObservation> TakeRemovedObservations();

  void RegisterImage(image_t image_id);
  // Unregisters and removes every observation the image has.
  void DeRegisterImage(image_t image_id);
  bool IsImageRegistered(image_t image_id) const;
  std::vector<image_t> RegImageIds() const;

  size_t NumCameras() const { return cameras_.size(); }
  size_t NumImages() const { return images_.size(); }
  size_t NumRegImages() const;
  size_t NumPoints3D() const { return points3D_.size(); }
  size_t NumObservations() const;
  double ComputeMeanTrackLength() const;
  // Number of points by track length (images per point).
  std::map<size_t, size_t> ComputeTrackLengthHistogram() const;
  double ComputeMeanObservationsPerRegImage() const;

  // Reprojection error in pixels of one observation, or +inf when behind the camera.
  double ReprojectionError(image_t image_id, point2D_t point2D_idx) const;
  // The same for any world point `xyz` seen in that keypoint (a candidate position while
  // triangulating, or a point being tested against a new view).
  double ReprojectionError(image_t image_id, point2D_t point2D_idx,
                           const Eigen::Vector3d& xyz) const;
  // Recomputes Point3D::error for every point; returns the mean over all observations.
  double UpdatePointErrors();
  // Mean reprojection error over all observations of one image (0 with none).
  double MeanReprojectionErrorOfImage(image_t image_id) const;

  // Applies new_from_old to every point and camera pose.
  void Transform(const Sim3d& new_from_old);

 private:
  // The point with this id, or nullptr: O(1) for indexed ids, else a map lookup.
  Point3D* FindPoint3D(point3D_t point3D_id) const;
  // Makes point_index_ cover ids below `end`, filling the new slots from the map.
  void IndexPoints3DBelow(size_t end);
  // After a point was emplaced: index it when its id is within a few times the point count
  // (ids from AddPoint3D always are; a stray huge id read from a file is not worth the memory).
  void IndexPoint3D(point3D_t point3D_id, Point3D* point);

  std::map<camera_t, Camera> cameras_;
  std::map<image_t, Image> images_;
  std::map<point3D_t, Point3D> points3D_;
  // Pointers into points3D_ by id (nullptr: no such point), so that the mapper's many
  // existence checks and lookups do not walk the tree. std::map nodes never move, so the
  // pointers stay valid until their point is erased; copies rebuild them.
  std::vector<Point3D*> point_index_;
  point3D_t next_point3D_id_ = 1;
  bool keep_removed_observations_ = false;
  std::vector<RemovedObservation> removed_observations_;
};

// Reprojection error in pixels of keypoint `point2D_idx` of `image`, taken with `camera`, for
// the world point `xyz`, or +inf when behind the camera: Reconstruction::ReprojectionError
// for callers that hold the image and its camera already.
double ReprojectionError(const Image& image, const Camera& camera, point2D_t point2D_idx,
                         const Eigen::Vector3d& xyz);

}  // namespace parallax
