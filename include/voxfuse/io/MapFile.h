#pragma once
// Map files (.vfm): a fused map saved at the end of a run (or from the viewer) and loaded to continue
// fusing, to relocalise a new recording of the same place in it, or to write meshes, clouds and
// renders without any frames. A map of submaps is a file of its own kind that holds a map of this
// format per submap (io/SubmapMapFile.h).
//
// The format, version 2, little-endian, every field written on its own (no struct padding):
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
//   keyframes (version 2) u32 count; when not 0, the fern settings their codes were made with (ferns,
//          tests per fern, code image width, depth range, intensity tests allowed, seed), whether the
//          codes have intensity tests, the depth frame's size; then per keyframe i32 frame index, its
//          pose and its code (one byte per fern). Version 1 files have none.
//   end    u32 CRC-32 of the body and the keyframes, "VFMAPEND"
// A voxel record holds the voxel's fields in declaration order (sdf as int16 or float32, weights,
// class id and colour). A map saved, loaded and saved again gives the same bytes.
//
// Writing goes to a temporary file beside the target, renamed over it only once complete. Reading
// streams the body in chunks (bounded memory) and refuses a file that is not a map, of a newer
// version, truncated, corrupt (checksums) or that does not fit the scene, with an IoError naming the
// file and what is wrong.

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "voxfuse/core/Math.h"
#include "voxfuse/engines/FernEncoder.h"
#include "voxfuse/engines/KeyframeDatabase.h"
#include "voxfuse/objects/HashTableTypes.h"
#include "voxfuse/objects/Intrinsics.h"
#include "voxfuse/objects/SceneParams.h"
#include "voxfuse/objects/Voxel.h"

namespace voxfuse {

template <class TVoxel, class TIndex>
class Scene;
class GlobalCache;

constexpr std::uint32_t kMapFileVersion = 2;

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
    std::uint64_t record_count = 0;            // blocks (hash) or voxels (dense); submaps for a map of submaps
    int submap_count = 0;                      // a map of submaps: how many it holds; 0 for a single map
};

// The relocaliser's keyframes (engines/Relocaliser.h), saved with a map so that a later run can find
// the camera in it. Codes compare only with codes of the same fern settings, kind and frame size.
struct MapKeyframes {
    FernSettings ferns;
    bool with_intensity = false;
    Vec2i frame_size{0, 0};
    std::vector<Keyframe> keyframes;  // oldest first
};

// Reads and checks the header only: a single map's, or for a map of submaps the map's as a whole
// (io/SubmapMapFile.h; its hash settings are the map's, from which each submap's derive). IoError
// naming the file for anything that is not a map of a version this build reads.
MapFileInfo readMapFileInfo(const std::string& path);

// A map file being written: one map, or a map of submaps (its header, then one map per submap).
// Everything goes to a temporary file beside the target, renamed over it by commit(); without a
// commit (an exception on the way) the target is untouched and the temporary file removed.
class MapFileWriter {
public:
    explicit MapFileWriter(const std::string& path);
    ~MapFileWriter();
    MapFileWriter(const MapFileWriter&) = delete;
    MapFileWriter& operator=(const MapFileWriter&) = delete;
    void commit();
    struct Stream;  // the fields (src/io/MapFileFields.h)
    Stream& stream() { return *stream_; }

private:
    std::unique_ptr<Stream> stream_;
};

// A map file being read, map after map.
class MapFileReader {
public:
    // IoError naming the file when it cannot be opened (or is a folder).
    explicit MapFileReader(const std::string& path);
    ~MapFileReader();
    MapFileReader(const MapFileReader&) = delete;
    MapFileReader& operator=(const MapFileReader&) = delete;
    const std::string& path() const;
    // Whether the file is a map of submaps (its signature; nothing is read).
    bool holdsSubmaps();
    // The header of the next map, read and checked; readMap() then reads that map's voxels.
    const MapFileInfo& nextMapInfo();
    // IoError when bytes follow what was read.
    void requireEnd();
    struct Stream;
    Stream& stream() { return *stream_; }

private:
    std::unique_ptr<Stream> stream_;
};

// Writes `scene` (in host memory) with the pose and camera fields of `info`; the others come from the
// scene. A hash with swapped blocks needs its global cache: stored blocks are read from it and copies
// waiting to be merged are merged on the way (engines/SwappingEngine.h). With `keyframes` they are
// saved too.
template <class TVoxel, class TIndex>
void writeMap(MapFileWriter& file, const Scene<TVoxel, TIndex>& scene, const MapFileInfo& info,
              const GlobalCache* cache = nullptr, const MapKeyframes* keyframes = nullptr);
// The same as a file of its own.
template <class TVoxel, class TIndex>
void writeMapFile(const std::string& path, const Scene<TVoxel, TIndex>& scene, const MapFileInfo& info,
                  const GlobalCache* cache = nullptr, const MapKeyframes* keyframes = nullptr);

// Reads the next map into `scene` (in host memory, empty, with the map's voxel type, index settings
// and voxel size: see readMapFileInfo) and returns its header. With a global cache (a hash with
// swapping), every block goes into the cache, stored, whatever the size of the voxel array. The
// keyframes saved with it go into `keyframes` (none from a version 1 file).
template <class TVoxel, class TIndex>
MapFileInfo readMap(MapFileReader& file, Scene<TVoxel, TIndex>& scene, GlobalCache* cache = nullptr,
                    MapKeyframes* keyframes = nullptr);
// The same for a file that holds one map and nothing else.
template <class TVoxel, class TIndex>
MapFileInfo readMapFile(const std::string& path, Scene<TVoxel, TIndex>& scene, GlobalCache* cache = nullptr,
                        MapKeyframes* keyframes = nullptr);

}  // namespace voxfuse
