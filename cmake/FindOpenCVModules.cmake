# Debian's per-module OpenCV packages (libopencv-core-dev, ...) ship no OpenCVConfig.cmake; that
# comes only with libopencv-dev and its GUI stack. Find the modules we use directly instead.
find_path(OpenCV_INCLUDE_DIRS opencv2/core.hpp PATH_SUFFIXES opencv4 REQUIRED)
set(OpenCV_LIBS "")
foreach(module core imgproc imgcodecs videoio)
  find_library(OpenCV_${module}_LIBRARY opencv_${module} REQUIRED)
  if(NOT TARGET OpenCV::${module})
    add_library(OpenCV::${module} SHARED IMPORTED)
    set_target_properties(OpenCV::${module} PROPERTIES
      IMPORTED_LOCATION ${OpenCV_${module}_LIBRARY}
      INTERFACE_SYSTEM_INCLUDE_DIRECTORIES ${OpenCV_INCLUDE_DIRS}
      INTERFACE_INCLUDE_DIRECTORIES ${OpenCV_INCLUDE_DIRS})
  endif()
  list(APPEND OpenCV_LIBS OpenCV::${module})
endforeach()
