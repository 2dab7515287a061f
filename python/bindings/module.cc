#include "bindings.h"

PYBIND11_MODULE(_parallax, m) {
  m.doc() =
      "Parallax's C++ core: incremental Structure from Motion. Import `parallax`, which "
      "re-exports everything here.";
  parallax::python::BindErrors(m);
  parallax::python::BindScene(m);
  parallax::python::BindGeometry(m);
  parallax::python::BindFeatures(m);
  parallax::python::BindPipeline(m);
  parallax::python::BindTools(m);
}
