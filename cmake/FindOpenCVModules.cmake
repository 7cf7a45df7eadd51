# Debian's per-module OpenCV packages (libopencv-core-dev, ...) ship no OpenCVConfig.cmake; that
# comes only with libopencv-dev and its GUI stack. Find the modules we use directly instead.
# OpenCV_LIBS: what every part links (calib3d for the synthetic stereo rig's lens model, video for
# the optical flow the deformation starts from); OpenCV_PREPARE_LIBS: what worker/prepare adds
# (corner features).
find_path(OpenCV_INCLUDE_DIRS opencv2/core.hpp PATH_SUFFIXES opencv4 REQUIRED)
set(OpenCV_LIBS "")
set(OpenCV_PREPARE_LIBS "")
foreach(module core imgproc imgcodecs videoio calib3d features2d video)
  find_library(OpenCV_${module}_LIBRARY opencv_${module} REQUIRED)
  if(NOT TARGET OpenCV::${module})
    add_library(OpenCV::${module} SHARED IMPORTED)
    set_target_properties(OpenCV::${module} PROPERTIES
      IMPORTED_LOCATION ${OpenCV_${module}_LIBRARY}
      INTERFACE_SYSTEM_INCLUDE_DIRECTORIES ${OpenCV_INCLUDE_DIRS}
      INTERFACE_INCLUDE_DIRECTORIES ${OpenCV_INCLUDE_DIRS})
  endif()
  if(module STREQUAL "features2d")
    list(APPEND OpenCV_PREPARE_LIBS OpenCV::${module})
  else()
    list(APPEND OpenCV_LIBS OpenCV::${module})
  endif()
endforeach()
