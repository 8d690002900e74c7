# Included by src/CMakeLists.txt: what the input front-ends (src/io) need beyond the core library.
#  - OpenCV videoio (the colour video of iPhone captures) and calib3d (lens undistortion maps).
#  - TurboJPEG: JPEG colour images, whose damage it reports.
#  - OpenNI2, optional: live cameras and .oni playback. VOXFUSE_OPENNI2 defaults to ON when it is
#    found (Debian: libopenni2-dev); without it OpenNISource throws an IoError saying so.

find_package(OpenCV REQUIRED COMPONENTS videoio calib3d)
target_link_libraries(voxfuse PRIVATE opencv_videoio opencv_calib3d)

# TurboJPEG (Debian: libturbojpeg0-dev) decodes JPEG colour so that a damaged or truncated file is an
# error naming it; OpenCV would decode it into a partly grey image with only a warning on stderr.
find_package(PkgConfig REQUIRED)
pkg_check_modules(TURBOJPEG REQUIRED IMPORTED_TARGET libturbojpeg)
target_link_libraries(voxfuse PRIVATE PkgConfig::TURBOJPEG)

pkg_check_modules(OPENNI2 QUIET libopenni2)
if(NOT OPENNI2_FOUND)
  find_path(OPENNI2_INCLUDE_DIRS OpenNI.h PATH_SUFFIXES openni2)
  find_library(OPENNI2_LINK_LIBRARIES OpenNI2)
  if(OPENNI2_INCLUDE_DIRS AND OPENNI2_LINK_LIBRARIES)
    set(OPENNI2_FOUND TRUE)
  endif()
endif()

option(VOXFUSE_OPENNI2 "OpenNI2 input: live cameras and .oni recordings" ${OPENNI2_FOUND})
if(VOXFUSE_OPENNI2 AND NOT OPENNI2_FOUND)
  message(FATAL_ERROR "VOXFUSE_OPENNI2=ON but OpenNI2 was not found (Debian: apt-get install libopenni2-dev)")
endif()
message(STATUS "VoxFuse: OpenNI2 ${VOXFUSE_OPENNI2}")

if(VOXFUSE_OPENNI2)
  target_sources(voxfuse PRIVATE ${CMAKE_CURRENT_LIST_DIR}/OpenNISource.cpp)
  # SYSTEM: OpenNI2's headers are not warning-clean under -Wpedantic.
  target_include_directories(voxfuse SYSTEM PRIVATE ${OPENNI2_INCLUDE_DIRS})
  target_link_libraries(voxfuse PRIVATE ${OPENNI2_LINK_LIBRARIES})
else()
  target_sources(voxfuse PRIVATE ${CMAKE_CURRENT_LIST_DIR}/OpenNISource_NoOpenNI.cpp)
endif()
