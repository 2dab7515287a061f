// Camera, Image, Point3D, Track, Rigid3d and Reconstruction, with numpy views of their
// arrays and COLMAP model files in and out.
#include <pybind11/eigen.h>
#include <pybind11/numpy.h>
#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

#include <functional>
#include <sstream>

#include "arrays.h"
#include "bindings.h"
#include "parallax/report/evaluation.h"
#include "parallax/scene/colmap_io.h"
#include "parallax/scene/reconstruction.h"

namespace py = pybind11;

namespace parallax::python {
namespace {

using ReturnPolicy = py::return_value_policy;

// A dict-like view of one of a reconstruction's maps (cameras, images, points3D), by id. Items
// are the reconstruction's own objects, so edits through them change the model.
template <typename Id, typename Value>
class MapView {
 public:
  using Map = std::map<Id, Value>;
  using MapGetter = const Map& (Reconstruction::*)() const;
  using ItemGetter = Value& (Reconstruction::*)(Id);

  MapView(Reconstruction* model, MapGetter map, ItemGetter item)
      : model_(model), map_(map), item_(item) {}
  const Map& Items() const { return (model_->*map_)(); }
  Value& At(Id id) const {
    if (Items().count(id) == 0) throw py::key_error(std::to_string(id));
    return (model_->*item_)(id);
  }

 private:
  Reconstruction* model_;
  MapGetter map_;
  ItemGetter item_;
};

template <typename Id, typename Value>
void BindMapView(py::module_& m, const char* name) {
  using View = MapView<Id, Value>;
  py::class_<View>(m, name, "Dict-like view of a reconstruction's items by id.")
      .def("__len__", [](const View& view) { return view.Items().size(); })
      .def("__contains__", [](const View& view, Id id) { return view.Items().count(id) > 0; })
      .def("__getitem__", &View::At, ReturnPolicy::reference_internal)
      .def(
          "__iter__",
          [](const View& view) {
            return py::make_key_iterator(view.Items().begin(), view.Items().end());
          },
          py::keep_alive<0, 1>())
      .def("keys",
           [](const View& view) {
             std::vector<Id> ids;
             for (const auto& entry : view.Items()) ids.push_back(entry.first);
             return ids;
           })
      .def("values",
           [](const py::object& self) {
             py::list values;
             for (const auto& entry : self.cast<const View&>().Items()) {
               values.append(py::cast(&entry.second, ReturnPolicy::reference_internal, self));
             }
             return values;
           })
      .def("items", [](const py::object& self) {
        py::list items;
        for (const auto& entry : self.cast<const View&>().Items()) {
          items.append(py::make_tuple(
              entry.first, py::cast(&entry.second, ReturnPolicy::reference_internal, self)));
        }
        return items;
      });
}

Eigen::Vector4d QuaternionWxyz(const Eigen::Quaterniond& q) { return {q.w(), q.x(), q.y(), q.z()}; }

void BindRigid3d(py::module_& m) {
  py::class_<Rigid3d>(m, "Rigid3d",
                      "A rigid transform y = R x + t, e.g. an image's cam_from_world.")
      .def(py::init<>())
      .def(
          py::init([](const Eigen::Matrix3d& rotation, const Eigen::Vector3d& translation) {
            if (!(rotation.transpose() * rotation).isIdentity(1e-6) || rotation.determinant() < 0) {
              throw py::value_error("rotation: not a rotation matrix (R^T R = I, det R = 1)");
            }
            return Rigid3d(rotation, translation);
          }),
          py::arg("rotation"), py::arg("translation"))
      .def_property(
          "rotation",
          [](const Rigid3d& t) { return Eigen::Matrix3d(t.rotation.toRotationMatrix()); },
          [](Rigid3d& t, const Eigen::Matrix3d& rotation) {
            t.rotation = Eigen::Quaterniond(rotation).normalized();
          },
          "3x3 rotation matrix R.")
      .def_property(
          "quaternion", [](const Rigid3d& t) { return QuaternionWxyz(t.rotation); },
          [](Rigid3d& t, const Eigen::Vector4d& wxyz) {
            t.rotation = Eigen::Quaterniond(wxyz[0], wxyz[1], wxyz[2], wxyz[3]).normalized();
          },
          "Unit quaternion of R as (w, x, y, z), COLMAP's order in images.txt.")
      .def_property(
          "translation", [](const Rigid3d& t) { return Eigen::Vector3d(t.translation); },
          [](Rigid3d& t, const Eigen::Vector3d& translation) { t.translation = translation; },
          "Translation t.")
      .def(
          "matrix", [](const Rigid3d& t) { return Eigen::Matrix<double, 3, 4>(t.ToMatrix()); },
          "The 3x4 matrix [R | t].")
      .def("inverse", &Rigid3d::Inverse)
      .def("__mul__", [](const Rigid3d& a, const Rigid3d& b) { return a * b; })
      .def(
          "__mul__",
          [](const Rigid3d& t, const py::array& points) {
            std::vector<Eigen::Vector3d> transformed = ToPoints3D(points, "points");
            for (Eigen::Vector3d& point : transformed) point = t * point;
            return FromPoints(transformed);
          },
          "Applies the transform to N x 3 points.")
      .def("__repr__", [](const Rigid3d& t) {
        std::ostringstream text;
        text << "Rigid3d(quaternion=" << QuaternionWxyz(t.rotation).transpose()
             << ", translation=" << t.translation.transpose() << ")";
        return text.str();
      });
}

// Sets a camera's parameters, refusing a count its model does not take or a value that is not
// finite (Camera::VerifyParams), with the reason.
void SetCameraParams(Camera* camera, const std::vector<double>& params) {
  const int expected = CameraModelNumParams(camera->model_id);
  if (params.size() != static_cast<size_t>(expected)) {
    throw py::value_error("params: " + camera->ModelName() + " takes " + std::to_string(expected) +
                          " parameters, got " + std::to_string(params.size()));
  }
  Camera candidate = *camera;
  candidate.params = params;
  if (!candidate.VerifyParams()) throw py::value_error("params: not all finite");
  camera->params = params;
}

void BindCamera(py::module_& m) {
  py::class_<Camera>(m, "Camera", "Intrinsics of one camera, in COLMAP's camera models.")
      .def(py::init([](const std::string& model, size_t width, size_t height,
                       const std::vector<double>& params) {
             Camera camera;
             camera.model_id = CameraModelIdFromName(model);
             if (camera.model_id == CameraModelId::kInvalid) {
               throw py::value_error("model: unknown camera model '" + model + "'");
             }
             camera.width = width;
             camera.height = height;
             SetCameraParams(&camera, params);
             return camera;
           }),
           py::arg("model"), py::arg("width"), py::arg("height"), py::arg("params"))
      .def_readwrite("camera_id", &Camera::camera_id)
      .def_property_readonly(
          "model", &Camera::ModelName,
          "COLMAP's model name: SIMPLE_PINHOLE, PINHOLE, SIMPLE_RADIAL, RADIAL, OPENCV, "
          "OPENCV_FISHEYE, FULL_OPENCV, FOV, SIMPLE_RADIAL_FISHEYE, "
          "RADIAL_FISHEYE, THIN_PRISM_FISHEYE, RAD_TAN_THIN_PRISM_FISHEYE, "
          "SIMPLE_DIVISION, DIVISION, SIMPLE_FISHEYE, FISHEYE, EUCM or "
          "EQUIRECTANGULAR.")
      .def_readwrite("width", &Camera::width)
      .def_readwrite("height", &Camera::height)
      .def_property(
          "params", [](const Camera& camera) { return camera.params; },
          [](Camera& camera, const std::vector<double>& params) {
            SetCameraParams(&camera, params);
          },
          "Parameters in the model's order (COLMAP's).")
      .def_readwrite("has_prior_focal_length", &Camera::has_prior_focal_length)
      .def_property_readonly("K", &Camera::CalibrationMatrix, "3x3 calibration matrix.")
      .def_property_readonly("focal_length", &Camera::MeanFocalLength)
      .def_property_readonly("principal_point",
                             [](const Camera& camera) {
                               return Eigen::Vector2d(camera.PrincipalPointX(),
                                                      camera.PrincipalPointY());
                             })
      .def(
          "img_from_cam",
          [](const Camera& camera, const py::array& points) {
            const py::ssize_t columns = points.ndim() == 2 ? points.shape(1) : 0;
            std::vector<Eigen::Vector2d> pixels;
            if (columns == 3) {
              for (const Eigen::Vector3d& point : ToPoints3D(points, "points")) {
                pixels.push_back(camera.ImgFromCam(point));
              }
            } else {
              for (const Eigen::Vector2d& xy : ToPoints2D(points, "points")) {
                pixels.push_back(camera.ImgFromCam(xy.homogeneous()));
              }
            }
            return FromPoints(pixels);
          },
          py::arg("points"),
          "Pixels (N x 2) of normalised image points (N x 2, z = 1) or of points in the camera "
          "frame (N x 3), through the distortion.")
      .def(
          "cam_from_img",
          [](const Camera& camera, const py::array& pixels) {
            std::vector<Eigen::Vector2d> points = ToPoints2D(pixels, "pixels");
            for (Eigen::Vector2d& point : points) point = camera.CamFromImg(point);
            return FromPoints(points);
          },
          py::arg("pixels"), "Normalised image points (N x 2, z = 1) of pixels (N x 2).")
      .def(
          "cam_ray_from_img",
          [](const Camera& camera, const py::array& pixels) {
            std::vector<Eigen::Vector3d> rays;
            for (const Eigen::Vector2d& xy : ToPoints2D(pixels, "pixels")) {
              rays.push_back(camera.CamRayFromImg(xy));
            }
            return FromPoints(rays);
          },
          py::arg("pixels"),
          "Unit rays (N x 3) of pixels (N x 2) in the camera frame, behind the image plane too "
          "(fisheyes wider than 180 degrees, EQUIRECTANGULAR).")
      .def_property_readonly(
          "projection",
          [](const Camera& camera) {
            switch (camera.Projection()) {
              case CameraProjection::kFisheye:
                return "fisheye";
              case CameraProjection::kSpherical:
                return "spherical";
              default:
                return "perspective";
            }
          },
          "The model's family: perspective, fisheye or spherical.")
      .def("__repr__", [](const Camera& camera) {
        std::ostringstream text;
        text << "Camera(camera_id=" << camera.camera_id << ", model=" << camera.ModelName()
             << ", width=" << camera.width << ", height=" << camera.height << ", params=[";
        for (size_t i = 0; i < camera.params.size(); ++i) {
          text << (i ? ", " : "") << camera.params[i];
        }
        text << "])";
        return text.str();
      });
}

void BindImage(py::module_& m) {
  py::class_<Image>(m, "Image", "One photo: its name, camera, pose and keypoints.")
      .def_readwrite("image_id", &Image::image_id)
      .def_readwrite("camera_id", &Image::camera_id)
      .def_readwrite("name", &Image::name)
      .def_readonly("registered", &Image::registered)
      .def_readwrite("cam_from_world", &Image::cam_from_world,
                     "World-to-camera transform: x_cam = R x_world + t.")
      .def("projection_center", &Image::ProjectionCenter, "Camera centre in world coordinates.")
      .def("viewing_direction", &Image::ViewingDirection)
      .def_property_readonly(
          "keypoints",
          [](const Image& image) {
            std::vector<Eigen::Vector2d> xy;
            xy.reserve(image.points2D.size());
            for (const Point2D& point : image.points2D) xy.push_back(point.xy);
            return FromPoints(xy);
          },
          "N x 2 keypoint positions in pixels (COLMAP's convention: pixel centres at +0.5).")
      .def_property_readonly(
          "point3D_ids",
          [](const Image& image) {
            py::array_t<int64_t> ids(static_cast<py::ssize_t>(image.points2D.size()));
            auto view = ids.mutable_unchecked<1>();
            for (size_t i = 0; i < image.points2D.size(); ++i) {
              view(i) = image.points2D[i].HasPoint3D()
                            ? static_cast<int64_t>(image.points2D[i].point3D_id)
                            : -1;
            }
            return ids;
          },
          "The 3D point of each keypoint, -1 where none.")
      .def_property_readonly("num_points2D", &Image::NumPoints2D)
      .def_readonly("num_points3D", &Image::num_points3D)
      .def("__repr__", [](const Image& image) {
        return "Image(image_id=" + std::to_string(image.image_id) + ", name='" + image.name +
               "', registered=" + (image.registered ? "True" : "False") + ")";
      });
}

void BindPoint3D(py::module_& m) {
  py::class_<TrackElement>(m, "TrackElement", "One observation: an image and its keypoint.")
      .def_readonly("image_id", &TrackElement::image_id)
      .def_readonly("point2D_idx", &TrackElement::point2D_idx)
      .def("__repr__", [](const TrackElement& element) {
        return "TrackElement(image_id=" + std::to_string(element.image_id) +
               ", point2D_idx=" + std::to_string(element.point2D_idx) + ")";
      });
  py::class_<Track>(m, "Track", "The observations of one 3D point.")
      .def_readonly("elements", &Track::elements)
      .def("__len__", &Track::Length)
      .def_property_readonly("image_ids",
                             [](const Track& track) {
                               std::vector<image_t> ids;
                               for (const TrackElement& e : track.elements)
                                 ids.push_back(e.image_id);
                               return py::array(py::cast(ids));
                             })
      .def_property_readonly("point2D_idxs", [](const Track& track) {
        std::vector<point2D_t> idxs;
        for (const TrackElement& e : track.elements) idxs.push_back(e.point2D_idx);
        return py::array(py::cast(idxs));
      });
  py::class_<Point3D>(m, "Point3D", "A triangulated point with its colour, error and track.")
      .def_property(
          "xyz", [](const Point3D& point) { return Eigen::Vector3d(point.xyz); },
          [](Point3D& point, const Eigen::Vector3d& xyz) { point.xyz = xyz; })
      .def_property(
          "color", [](const Point3D& point) { return Eigen::Matrix<uint8_t, 3, 1>(point.color); },
          [](Point3D& point, const Eigen::Matrix<uint8_t, 3, 1>& rgb) { point.color = rgb; },
          "RGB, 0-255.")
      .def_readonly("error", &Point3D::error, "Mean reprojection error in pixels.")
      .def_readonly("track", &Point3D::track)
      .def("__repr__", [](const Point3D& point) {
        std::ostringstream text;
        text << "Point3D(xyz=" << point.xyz.transpose() << ", track length " << point.track.Length()
             << ")";
        return text.str();
      });
}

template <typename Column>
py::array_t<Column> PointColumn(
    const Reconstruction& model, int width,
    const std::function<void(point3D_t, const Point3D&, Column*)>& fill) {
  std::vector<py::ssize_t> shape = {static_cast<py::ssize_t>(model.NumPoints3D())};
  if (width > 1) shape.push_back(width);
  py::array_t<Column> array(shape);
  Column* data = array.mutable_data();
  for (const auto& [id, point] : model.Points3D()) {
    fill(id, point, data);
    data += width;
  }
  return array;
}

void BindReconstruction(py::module_& m) {
  BindMapView<camera_t, Camera>(m, "CameraMap");
  BindMapView<image_t, Image>(m, "ImageMap");
  BindMapView<point3D_t, Point3D>(m, "Point3DMap");
  using CameraView = MapView<camera_t, Camera>;
  using ImageView = MapView<image_t, Image>;
  using PointView = MapView<point3D_t, Point3D>;

  py::class_<Reconstruction>(m, "Reconstruction",
                             "A sparse model: cameras, posed images and 3D points (COLMAP's).")
      .def(py::init<>())
      .def(py::init([](const std::filesystem::path& dir) { return ReadReconstruction(dir); }),
           py::arg("path"), "Reads a COLMAP model folder (.bin or .txt), as pycolmap's does.")
      // `read` itself is defined in parallax/__init__.py: on the class it returns a new model,
      // on a model it reads into it (pycolmap's habit).
      .def(
          "_read_into",
          [](Reconstruction& model, const std::filesystem::path& dir) {
            model = ReadReconstruction(dir);
          },
          py::arg("path"))
      .def(
          "write",
          [](const Reconstruction& model, const std::filesystem::path& dir) {
            WriteReconstructionBinary(model, dir);
          },
          py::arg("path"), "Writes cameras.bin, images.bin, points3D.bin into a folder.")
      .def(
          "write_binary",
          [](const Reconstruction& model, const std::filesystem::path& dir) {
            WriteReconstructionBinary(model, dir);
          },
          py::arg("path"), "As write (pycolmap's name).")
      .def(
          "write_text",
          [](const Reconstruction& model, const std::filesystem::path& dir) {
            WriteReconstructionText(model, dir);
          },
          py::arg("path"), "Writes cameras.txt, images.txt, points3D.txt into a folder.")
      .def(
          "export_ply",
          [](const Reconstruction& model, const std::filesystem::path& path) {
            WritePointsPly(model, path);
          },
          py::arg("path"), "Writes the points with their colours as a binary PLY.")
      .def_property_readonly(
          "cameras",
          [](Reconstruction& model) {
            return CameraView(
                &model, &Reconstruction::Cameras,
                static_cast<Camera& (Reconstruction::*)(camera_t)>(&Reconstruction::GetCamera));
          },
          py::keep_alive<0, 1>())
      .def_property_readonly(
          "images",
          [](Reconstruction& model) {
            return ImageView(
                &model, &Reconstruction::Images,
                static_cast<Image& (Reconstruction::*)(image_t)>(&Reconstruction::GetImage));
          },
          py::keep_alive<0, 1>())
      .def_property_readonly(
          "points3D",
          [](Reconstruction& model) {
            return PointView(
                &model, &Reconstruction::Points3D,
                static_cast<Point3D& (Reconstruction::*)(point3D_t)>(&Reconstruction::GetPoint3D));
          },
          py::keep_alive<0, 1>())
      .def("num_cameras", &Reconstruction::NumCameras)
      .def("num_images", &Reconstruction::NumImages)
      .def("num_reg_images", &Reconstruction::NumRegImages)
      .def("num_points3D", &Reconstruction::NumPoints3D)
      .def("num_observations", &Reconstruction::NumObservations)
      .def("mean_track_length", &Reconstruction::ComputeMeanTrackLength)
      .def("reg_image_ids", &Reconstruction::RegImageIds, "Registered image ids, ascending.")
      .def(
          "projection_centers",
          [](const Reconstruction& model) {
            std::vector<Eigen::Vector3d> centers;
            for (const image_t id : model.RegImageIds()) {
              centers.push_back(model.GetImage(id).ProjectionCenter());
            }
            return FromPoints(centers);
          },
          "N x 3 centres of the registered images, in reg_image_ids() order.")
      .def(
          "point3D_ids",
          [](const Reconstruction& model) {
            return PointColumn<uint64_t>(
                model, 1, [](point3D_t id, const Point3D&, uint64_t* row) { *row = id; });
          },
          "Point ids, ascending (the row order of the other point arrays).")
      .def(
          "point3D_xyz",
          [](const Reconstruction& model) {
            return PointColumn<double>(model, 3, [](point3D_t, const Point3D& point, double* row) {
              for (int d = 0; d < 3; ++d) row[d] = point.xyz[d];
            });
          },
          "M x 3 point positions.")
      .def(
          "point3D_colors",
          [](const Reconstruction& model) {
            return PointColumn<uint8_t>(model, 3,
                                        [](point3D_t, const Point3D& point, uint8_t* row) {
                                          for (int d = 0; d < 3; ++d) row[d] = point.color[d];
                                        });
          },
          "M x 3 RGB colours, 0-255.")
      .def(
          "point3D_errors",
          [](const Reconstruction& model) {
            return PointColumn<double>(
                model, 1, [](point3D_t, const Point3D& point, double* row) { *row = point.error; });
          },
          "Mean reprojection error of each point, pixels.")
      .def(
          "track_lengths",
          [](const Reconstruction& model) {
            return PointColumn<uint32_t>(model, 1,
                                         [](point3D_t, const Point3D& point, uint32_t* row) {
                                           *row = static_cast<uint32_t>(point.track.Length());
                                         });
          },
          "Images that see each point.")
      .def("update_point_errors", &Reconstruction::UpdatePointErrors,
           "Recomputes every point's error; returns the mean over observations, pixels.")
      .def(
          "summary",
          [](const Reconstruction& model) { return FromJson(ModelStatisticsToJson(model)); },
          "Counts, mean track length, track-length histogram and mean reprojection error.")
      .def("__repr__", [](const Reconstruction& model) {
        return "Reconstruction(" + std::to_string(model.NumRegImages()) + "/" +
               std::to_string(model.NumImages()) + " images registered, " +
               std::to_string(model.NumPoints3D()) + " points)";
      });
}

}  // namespace

void BindScene(py::module_& m) {
  BindRigid3d(m);
  BindCamera(m);
  BindImage(m);
  BindPoint3D(m);
  BindReconstruction(m);
}

}  // namespace parallax::python
