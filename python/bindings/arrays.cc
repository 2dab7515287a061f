#include "arrays.h"

#include <string>

namespace py = pybind11;

namespace parallax::python {
namespace {

template <int kDims>
std::vector<Eigen::Matrix<double, kDims, 1>> ToPoints(const py::handle& handle, const char* name) {
  const auto array = py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(handle);
  if (!array || array.ndim() != 2 || array.shape(1) != kDims) {
    std::string shape = "not an array";
    if (array) shape = py::str(array.attr("shape")).cast<std::string>();
    throw py::value_error(std::string(name) + ": expected an N x " + std::to_string(kDims) +
                          " array, got shape " + shape);
  }
  const auto view = array.unchecked<2>();
  std::vector<Eigen::Matrix<double, kDims, 1>> points(static_cast<size_t>(array.shape(0)));
  for (py::ssize_t i = 0; i < array.shape(0); ++i) {
    for (int d = 0; d < kDims; ++d) points[i][d] = view(i, d);
  }
  return points;
}

template <int kDims>
py::array_t<double> FromPointsOf(const std::vector<Eigen::Matrix<double, kDims, 1>>& points) {
  py::array_t<double> array({static_cast<py::ssize_t>(points.size()), py::ssize_t{kDims}});
  auto view = array.mutable_unchecked<2>();
  for (size_t i = 0; i < points.size(); ++i) {
    for (int d = 0; d < kDims; ++d) view(i, d) = points[i][d];
  }
  return array;
}

}  // namespace

std::vector<Eigen::Vector2d> ToPoints2D(const py::handle& array, const char* name) {
  return ToPoints<2>(array, name);
}

std::vector<Eigen::Vector3d> ToPoints3D(const py::handle& array, const char* name) {
  return ToPoints<3>(array, name);
}

py::array_t<double> FromPoints(const std::vector<Eigen::Vector2d>& points) {
  return FromPointsOf<2>(points);
}

py::array_t<double> FromPoints(const std::vector<Eigen::Vector3d>& points) {
  return FromPointsOf<3>(points);
}

py::array_t<bool> FromMask(const std::vector<char>& mask) {
  py::array_t<bool> array(static_cast<py::ssize_t>(mask.size()));
  auto view = array.mutable_unchecked<1>();
  for (size_t i = 0; i < mask.size(); ++i) view(i) = mask[i] != 0;
  return array;
}

py::object FromJson(const nlohmann::json& json) {
  switch (json.type()) {
    case nlohmann::json::value_t::object: {
      py::dict dict;
      for (const auto& [key, value] : json.items()) dict[py::str(key)] = FromJson(value);
      return dict;
    }
    case nlohmann::json::value_t::array: {
      py::list list;
      for (const nlohmann::json& value : json) list.append(FromJson(value));
      return list;
    }
    case nlohmann::json::value_t::string:
      return py::str(json.get<std::string>());
    case nlohmann::json::value_t::boolean:
      return py::bool_(json.get<bool>());
    case nlohmann::json::value_t::number_integer:
      return py::int_(json.get<int64_t>());
    case nlohmann::json::value_t::number_unsigned:
      return py::int_(json.get<uint64_t>());
    case nlohmann::json::value_t::number_float:
      return py::float_(json.get<double>());
    default:
      return py::none();
  }
}

}  // namespace parallax::python
