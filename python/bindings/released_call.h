#pragma once

#include <pybind11/pybind11.h>

#include <functional>

namespace parallax::python {

// Runs `work` (C++ only: it must not touch Python objects) on a worker thread with the GIL
// released, while the calling thread waits. Meanwhile the calling thread passes the stages'
// progress counts to `progress` (a callable taking (stage, done, total), or None), so the
// callback runs on the caller's thread as notebooks expect, and it polls for Ctrl-C. On
// Ctrl-C, or an exception in the callback, the work is asked to stop at its next safe point
// (util/interrupt.h: what it committed stays, and a rerun resumes), waited for, and the
// Python exception is raised. An exception of `work` is rethrown on the calling thread.
void RunReleasingGil(const std::function<void()>& work, const pybind11::object& progress);

}  // namespace parallax::python
