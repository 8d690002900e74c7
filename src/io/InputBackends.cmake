# Included by src/CMakeLists.txt: what the input front-ends (src/io) need beyond the core library.
#  - libpng, TurboJPEG and libtiff: the image codecs (src/io/ImageCodecs.h). TurboJPEG reports a
#    damaged or truncated JPEG, which libjpeg alone decodes into a partly grey image with a warning.
#  - The video module, voxfuse_video: OpenCV's videoio for the colour video of iPhone captures. It
#    brings FFmpeg, GStreamer and OpenCV's codecs (with GDAL, Poppler, GDCM): 63 MB of memory that
#    every process linking them paid. As a module beside libvoxfuse, loaded the first time a video is
#    opened (src/io/VideoDecoder.h), only runs that read a video pay for it.
#  - OpenNI2, optional: live cameras and .oni playback. VOXFUSE_OPENNI2 defaults to ON when it is
#    found (Debian: libopenni2-dev); without it OpenNISource throws an IoError saying so.

find_package(PNG REQUIRED)
find_package(TIFF REQUIRED)
find_package(PkgConfig REQUIRED)
pkg_check_modules(TURBOJPEG REQUIRED IMPORTED_TARGET GLOBAL libturbojpeg)  # GLOBAL: the tests use it too
target_link_libraries(voxfuse PRIVATE PNG::PNG TIFF::TIFF PkgConfig::TURBOJPEG ${CMAKE_DL_LIBS})

find_package(OpenCV REQUIRED COMPONENTS core imgproc videoio)
add_library(voxfuse_video MODULE ${CMAKE_CURRENT_LIST_DIR}/VideoDecoderOpenCV.cpp)
target_link_libraries(voxfuse_video PRIVATE voxfuse_core opencv_core opencv_imgproc opencv_videoio)
target_compile_options(voxfuse_video PRIVATE ${VOXFUSE_WARNINGS})
# Built beside libvoxfuse (a MODULE's default folder is this one's too), where the library looks.
target_compile_definitions(voxfuse PRIVATE VOXFUSE_VIDEO_MODULE="$<TARGET_FILE_NAME:voxfuse_video>")
add_dependencies(voxfuse voxfuse_video)  # whatever builds the library builds its module
install(TARGETS voxfuse_video LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR})

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
