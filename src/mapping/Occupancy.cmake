# Included by src/CMakeLists.txt: the OctoMap occupancy map (mapping/OccupancyMapper) of voxfuse_core, optional.
# With OctoMap found (Debian: liboctomap-dev) the library defines VOXFUSE_WITH_OCTOMAP=1 for itself
# and its users; without it OccupancyMapper's constructor throws a ConfigError saying so. OctoMap is
# linked privately and stays out of the public headers, so consumers need no OctoMap headers.

find_package(octomap QUIET)

if(octomap_FOUND)
  message(STATUS "VoxFuse: OctoMap ${OCTOMAP_VERSION} (occupancy maps)")
  target_sources(voxfuse_core PRIVATE ${CMAKE_CURRENT_LIST_DIR}/OccupancyMapper.cpp)
  target_include_directories(voxfuse_core SYSTEM PRIVATE ${OCTOMAP_INCLUDE_DIRS})
  target_link_libraries(voxfuse_core PRIVATE ${OCTOMAP_LIBRARIES})
  target_compile_definitions(voxfuse_core PUBLIC VOXFUSE_WITH_OCTOMAP=1)
else()
  message(STATUS "VoxFuse: OctoMap not found, no occupancy maps (Debian: apt-get install liboctomap-dev)")
  target_sources(voxfuse_core PRIVATE ${CMAKE_CURRENT_LIST_DIR}/OccupancyMapper_NoOctomap.cpp)
endif()
