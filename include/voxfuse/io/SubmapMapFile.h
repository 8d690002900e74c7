#pragma once
// A map of submaps (MainEngineSettings::submaps) in one map file: the map's own header, the pose
// graph that places the submaps, and each submap's map in the single-map format (io/MapFile.h).
//
// The format, version 1, little-endian:
//   magic  "VFSUBMAP" (8 bytes), u32 version
//   header the map's fields as a single map's header holds them (voxel type, the index settings of the
//          map as a whole, from which each submap's derive, scene settings, the last camera pose in
//          the world, the world origin, the depth camera; the record count is the submap count);
//          u32 the active submap (tracked against when the run resumes); per submap its pose in the
//          world and i32 the submap it started from (-1 for the first); u32 edge count and per edge
//          i32 from, i32 to, the measured pose of `to` in `from`'s frame, f32 sigmas of translation
//          (m) and rotation (rad), u8 loop; u32 CRC-32 of the header from the version on
//   maps   one map per submap, in the single-map format, its poses in the submap's frame
//   end    "VFSUBEND"
// Read and written with the map files' checks: IoError naming the file and what is wrong.

#include <vector>

#include "voxfuse/io/MapFile.h"
#include "voxfuse/mapping/PoseGraph.h"

namespace voxfuse {

constexpr std::uint32_t kSubmapMapFileVersion = 1;

struct SubmapMapInfo {
    MapFileInfo map;  // the map as a whole; submap_count tells how many submaps follow
    int active = 0;
    std::vector<Mat4f> T_world_submap;  // per submap
    std::vector<int> parent;            // per submap
    std::vector<PoseGraphEdge> edges;   // odometry and loop edges between submaps
};

// The header; the submaps' maps follow (writeMap per submap), then writeSubmapMapEnd.
void writeSubmapMapHeader(MapFileWriter& file, const SubmapMapInfo& info);
void writeSubmapMapEnd(MapFileWriter& file);
// Reads and checks the header (IoError for a file that is not a map of submaps); the submaps' maps
// are read next (MapFileReader::nextMapInfo and readMap per submap), then readSubmapMapEnd.
SubmapMapInfo readSubmapMapHeader(MapFileReader& file);
void readSubmapMapEnd(MapFileReader& file);

}  // namespace voxfuse
