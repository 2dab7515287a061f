#pragma once

// Conversions between numpy arrays and the C++ types, checked: a wrong shape is a ValueError
// naming the argument.

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <Eigen/Core>
#include <nlohmann/json.hpp>
#include <vector>

namespace parallax::python {

// N x 2 (or N x 3) float array -> points; `name` goes in the error message.
std::vector<Eigen::Vector2d> ToPoints2D(const pybind11::handle& array, const char* name);
std::vector<Eigen::Vector3d> ToPoints3D(const pybind11::handle& array, const char* name);

// Points -> N x 2 / N x 3 float64 arrays.
pybind11::array_t<double> FromPoints(const std::vector<Eigen::Vector2d>& points);
pybind11::array_t<double> FromPoints(const std::vector<Eigen::Vector3d>& points);

// 0/1 flags -> bool array.
pybind11::array_t<bool> FromMask(const std::vector<char>& mask);

// JSON -> dict / list / str / int / float / bool / None.
pybind11::object FromJson(const nlohmann::json& json);

}  // namespace parallax::python
