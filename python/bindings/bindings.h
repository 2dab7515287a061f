#pragma once

// The pieces of the extension module `parallax._parallax`, one file each (module.cc calls
// them in order). Everything is a thin layer over the C++ library: no second implementation.

#include <pybind11/pybind11.h>

namespace parallax::python {

void BindErrors(pybind11::module_& m);    // errors.cc: C++ exceptions -> Python ones
void BindScene(pybind11::module_& m);     // scene_bindings.cc: Camera, Image, Reconstruction
void BindGeometry(pybind11::module_& m);  // geometry_bindings.cc: the estimators on arrays
void BindFeatures(pybind11::module_& m);  // feature_bindings.cc: extract_sift
void BindPipeline(pybind11::module_& m);  // pipeline_bindings.cc: the stages with their flags
void BindTools(pybind11::module_& m);     // tools_bindings.cc: evaluate, report, synth, calibrate

}  // namespace parallax::python
