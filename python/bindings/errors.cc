// C++ exceptions cross into Python with their one-line messages: a missing file is
// FileNotFoundError, other bad input (and options a check refuses) ValueError, a run stopped
// by Ctrl-C KeyboardInterrupt. Anything else is RuntimeError (pybind11's default).
#include <pybind11/pybind11.h>

#include "bindings.h"
#include "parallax/util/check.h"
#include "parallax/util/interrupt.h"

namespace py = pybind11;

namespace parallax::python {

void BindErrors(py::module_& m) {
  py::register_exception_translator([](std::exception_ptr pointer) {
    try {
      if (pointer) std::rethrow_exception(pointer);
    } catch (const MissingFileError& error) {
      PyErr_SetString(PyExc_FileNotFoundError, error.what());
    } catch (const InputError& error) {
      PyErr_SetString(PyExc_ValueError, error.what());
    } catch (const CheckError& error) {
      PyErr_SetString(PyExc_ValueError, error.what());
    } catch (const Interrupted& error) {
      PyErr_SetString(PyExc_KeyboardInterrupt, error.what());
    }
  });
}

}  // namespace parallax::python
