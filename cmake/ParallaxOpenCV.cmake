# OpenCV from Debian's per-module -dev packages. Their CMake package files ship only with
# libopencv-dev, which pulls in every module (contrib, viz, VTK: hundreds of MB), so when no
# OpenCVConfig.cmake is installed the modules we use are found directly and given the
# target names OpenCV's own config defines (opencv_core, ...).
#
#   parallax_find_opencv(core imgcodecs imgproc features2d calib3d)

function(parallax_find_opencv)
  find_package(OpenCV 4 QUIET COMPONENTS ${ARGN})
  if(OpenCV_FOUND)
    message(STATUS "OpenCV ${OpenCV_VERSION} from ${OpenCV_DIR}")
    return()
  endif()
  find_path(PARALLAX_OPENCV_INCLUDE_DIR opencv2/core/version.hpp PATH_SUFFIXES opencv4)
  if(NOT PARALLAX_OPENCV_INCLUDE_DIR)
    message(FATAL_ERROR "OpenCV 4 headers not found: run scripts/install-deps.sh")
  endif()
  foreach(module ${ARGN})
    find_library(PARALLAX_OPENCV_${module}_LIBRARY opencv_${module})
    if(NOT PARALLAX_OPENCV_${module}_LIBRARY)
      message(FATAL_ERROR "OpenCV module ${module} not found: run scripts/install-deps.sh")
    endif()
    if(NOT TARGET opencv_${module})
      add_library(opencv_${module} SHARED IMPORTED GLOBAL)
      set_target_properties(opencv_${module} PROPERTIES
        IMPORTED_LOCATION "${PARALLAX_OPENCV_${module}_LIBRARY}"
        INTERFACE_INCLUDE_DIRECTORIES "${PARALLAX_OPENCV_INCLUDE_DIR}")
    endif()
  endforeach()
  message(STATUS "OpenCV modules ${ARGN} from ${PARALLAX_OPENCV_INCLUDE_DIR}")
endfunction()
