#pragma once
// Map files (.vfm): a fused map saved at the end of a run (or from the viewer) and loaded to continue
// fusing or to write meshes, clouds and renders without any frames.
//
// The format, version 1, little-endian, every field written on its own (no struct padding):
//   magic  "VFMAP\r\n\x1a" (8 bytes: catches text-mode transfers and truncation to a text line)
//   u32    version, u32 header bytes (the fields up to and including the header checksum)
//   header voxel type name (16 bytes, zero padded), u32 bytes per voxel record, u32 index (0 dense,
//          1 hash), the index settings (hash: buckets, entries per bucket, excess entries, maximum
//          blocks; dense: offset and size), the scene settings (voxel size, mu, maximum weight, depth
//          range, class update rule), the world frame (the camera pose where tracking resumes, and
//          when the run used ground truth, the source's pose of the world origin), the depth camera's
//          intrinsics (renders of a map without frames), the scene's integration count, u64 record
//          count, u32 CRC-32 of the header
//   body   hash: one record per block, sorted by (z, y, x): i16 x, y, z and its 512 voxel records;
//          dense: every voxel record of the array in memory order
//   end    u32 CRC-32 of the body, "VFMAPEND"
// A voxel record holds the voxel's fields in declaration order (sdf as int16 or float32, weights,
// class id and colour). A map saved, loaded and saved again gives the same bytes.
//
// Writing goes to a temporary file beside the target, renamed over it only once complete. Reading
// streams the body in chunks (bounded memory) and refuses a file that is not a map, of a newer
// version, truncated, corrupt (checksums) or that does not fit the scene, with an IoError naming the
// file and what is wrong.

#include <cstdint>
#include <string>

#include "voxfuse/core/Math.h"
#include "voxfuse/objects/HashTableTypes.h"
#include "voxfuse/objects/Intrinsics.h"
#include "voxfuse/objects/SceneParams.h"
#include "voxfuse/objects/Voxel.h"

namespace voxfuse {

template <class TVoxel, class TIndex>
class Scene;
class GlobalCache;

constexpr std::uint32_t kMapFileVersion = 1;

// What a map file's header says.
struct MapFileInfo {
    std::uint32_t version = kMapFileVersion;
    std::string voxel_type;  // "s", "s_rgb", ... (the voxel struct's name)
    bool hash = true;        // the voxel block hash, else the dense array
    VoxelBlockHashSettings hash_settings;
    Vec3i dense_offset{0, 0, 0}, dense_size{0, 0, 0};
    SceneParams scene;
    Mat4f T_world_camera = Mat4f::identity();  // where tracking resumes: the last pose of the run
    bool has_origin = false;                   // the run took its poses from the source's ground truth:
    Mat4f T_source_world = Mat4f::identity();  // the world frame's pose in the source's frame
    Intrinsics camera;                         // the run's depth camera (invalid when unknown)
    std::uint32_t integration_count = 0;       // Scene::takeIntegrationNumber() continues from here
    std::uint64_t record_count = 0;            // blocks (hash) or voxels (dense)
};

// Reads and checks the header only. IoError naming the file for anything that is not a map of a
// version this build reads.
MapFileInfo readMapFileInfo(const std::string& path);

// Writes `scene` (in host memory) with the pose and camera fields of `info`; the others come from the
// scene. A hash with swapped blocks needs its global cache: stored blocks are read from it and copies
// waiting to be merged are merged on the way (engines/SwappingEngine.h).
template <class TVoxel, class TIndex>
void writeMapFile(const std::string& path, const Scene<TVoxel, TIndex>& scene, const MapFileInfo& info,
                  const GlobalCache* cache = nullptr);

// Reads the map into `scene` (in host memory, empty, with the file's voxel type, index settings and
// voxel size: see readMapFileInfo) and returns the header. With a global cache (a hash with swapping),
// every block goes into the cache, stored, whatever the size of the voxel array.
template <class TVoxel, class TIndex>
MapFileInfo readMapFile(const std::string& path, Scene<TVoxel, TIndex>& scene, GlobalCache* cache = nullptr);

}  // namespace voxfuse
