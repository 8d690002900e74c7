# Included by src/CMakeLists.txt: the pose graph's solve (mapping/PoseGraph) in voxfuse_core, with Ceres
# (Debian: libceres-dev) when found. Without it PoseGraph::optimise throws a ConfigError saying what to
# install (the GPU bundle builds so: the lent machine has no -dev packages). Ceres is linked privately
# and stays out of the public headers.

find_package(Ceres QUIET)

target_sources(voxfuse_core PRIVATE ${CMAKE_CURRENT_LIST_DIR}/PoseGraph.cpp)
if(Ceres_FOUND)
  message(STATUS "VoxFuse: Ceres ${Ceres_VERSION} (pose graph optimisation)")
  target_sources(voxfuse_core PRIVATE ${CMAKE_CURRENT_LIST_DIR}/PoseGraphSolve_Ceres.cpp)
  target_link_libraries(voxfuse_core PRIVATE Ceres::ceres)
  target_compile_definitions(voxfuse_core PUBLIC VOXFUSE_WITH_CERES=1)
else()
  message(STATUS "VoxFuse: Ceres not found, no pose graph optimisation (Debian: apt-get install libceres-dev)")
  target_sources(voxfuse_core PRIVATE ${CMAKE_CURRENT_LIST_DIR}/PoseGraphSolve_NoCeres.cpp)
endif()
