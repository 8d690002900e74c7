// Map files: the format of io/MapFile.h, written field by field in little-endian order.

#include "voxfuse/io/MapFile.h"

#include <zlib.h>

#include <algorithm>
#include <cerrno>
#include <climits>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <utility>
#include <vector>

#include "MapFileFields.h"
#include "voxfuse/io/SubmapMapFile.h"
#include "TextParsing.h"
#include "voxfuse/core/Error.h"
#include "voxfuse/engines/EnginePairs.h"
#include "voxfuse/io/AtomicFile.h"
#include "voxfuse/objects/GlobalCache.h"
#include "voxfuse/objects/Scene.h"
#include "voxfuse/shared/HashAccess.h"
#include "voxfuse/shared/HashUpdate.h"
#include "voxfuse/shared/Swapping.h"

namespace voxfuse {
using namespace mapfile;
namespace {

constexpr char kEndMagic[8] = {'V', 'F', 'M', 'A', 'P', 'E', 'N', 'D'};
constexpr std::size_t kVoxelTypeNameBytes = 16;
// Version 1's header: the voxel type name, 26 four-byte fields, 3 flags, 2 matrices, the record count.
constexpr std::uint32_t kHeaderBytes = kVoxelTypeNameBytes + 4 * 26 + 3 + 2 * 64 + 8;

// ---- Voxel records ----

template <class TVoxel>
constexpr std::uint32_t voxelRecordBytes() {
    return std::uint32_t(sizeof(TVoxel::initial().sdf)) + 1 + (TVoxel::hasColor ? 4 : 0) + (TVoxel::hasLabel ? 3 : 0);
}

template <class TVoxel>
void writeVoxelRecord(FieldWriter& w, const TVoxel& v) {
    if constexpr (sizeof(v.sdf) == 2)
        w.i16(v.sdf);
    else
        w.f32(v.sdf);
    w.u8(v.w_depth);
    if constexpr (TVoxel::hasColor) {
        w.u8(v.w_color);
        w.u8(v.clr.x);
        w.u8(v.clr.y);
        w.u8(v.clr.z);
    }
    if constexpr (TVoxel::hasLabel) {
        w.u16(v.label);
        w.u8(v.w_label);
    }
}

template <class TVoxel>
TVoxel readVoxelRecord(FieldReader& r) {
    TVoxel v = TVoxel::initial();
    if constexpr (sizeof(v.sdf) == 2) {
        v.sdf = r.i16();
    } else {
        v.sdf = r.f32();
        if (!(std::fabs(v.sdf) <= 1.f)) r.fail("corrupt: a voxel's signed distance is not in [-1, 1]");
    }
    v.w_depth = r.u8();
    if constexpr (TVoxel::hasColor) {
        v.w_color = r.u8();
        const std::uint8_t red = r.u8(), green = r.u8(), blue = r.u8();
        v.clr = Vec3u8{red, green, blue};
    }
    if constexpr (TVoxel::hasLabel) {
        v.label = r.u16();
        v.w_label = r.u8();
    }
    return v;
}

// ---- Header ----

bool finite(const Mat4f& m) {
    return std::all_of(std::begin(m.m), std::end(m.m), [](float x) { return std::isfinite(x); });
}

}  // namespace

namespace mapfile {

void writeHeaderFields(FieldWriter& w, const MapFileInfo& info, std::uint32_t voxel_bytes) {
    char name[kVoxelTypeNameBytes] = {};
    std::strncpy(name, info.voxel_type.c_str(), kVoxelTypeNameBytes - 1);
    w.raw(name, kVoxelTypeNameBytes);
    w.u32(voxel_bytes);
    w.u32(info.hash ? 1 : 0);
    w.i32(info.hash_settings.bucket_count);
    w.i32(info.hash_settings.entries_per_bucket);
    w.i32(info.hash_settings.excess_entry_count);
    w.i32(info.hash_settings.max_block_count);
    w.i32(info.hash_settings.blocks_per_growth);
    for (int a = 0; a < 3; ++a) w.i32(info.dense_offset[a]);
    for (int a = 0; a < 3; ++a) w.i32(info.dense_size[a]);
    w.f32(info.scene.voxel_size_m);
    w.f32(info.scene.mu_m);
    w.i32(info.scene.max_weight);
    w.f32(info.scene.view_frustum_min_m);
    w.f32(info.scene.view_frustum_max_m);
    w.u8(info.scene.stop_integrating_at_max_weight ? 1 : 0);
    w.u8(info.scene.label_update == LabelUpdate::Vote ? 1 : 0);
    writeMat(w, info.T_world_camera);
    w.u8(info.has_origin ? 1 : 0);
    writeMat(w, info.T_source_world);
    w.i32(info.camera.width);
    w.i32(info.camera.height);
    w.f32(info.camera.fx);
    w.f32(info.camera.fy);
    w.f32(info.camera.cx);
    w.f32(info.camera.cy);
    w.u32(info.integration_count);
    w.u64(info.record_count);
}

MapFileInfo readHeaderFields(FieldReader& r) {
    MapFileInfo info;
    char name[kVoxelTypeNameBytes + 1] = {};
    r.raw(name, kVoxelTypeNameBytes);
    info.voxel_type = name;
    const std::uint32_t voxel_bytes = r.u32();
    const std::uint32_t index = r.u32();
    info.hash = index == 1;
    info.hash_settings.bucket_count = r.i32();
    info.hash_settings.entries_per_bucket = r.i32();
    info.hash_settings.excess_entry_count = r.i32();
    info.hash_settings.max_block_count = r.i32();
    info.hash_settings.blocks_per_growth = r.i32();
    for (int a = 0; a < 3; ++a) info.dense_offset[a] = r.i32();
    for (int a = 0; a < 3; ++a) info.dense_size[a] = r.i32();
    info.scene.voxel_size_m = r.f32();
    info.scene.mu_m = r.f32();
    info.scene.max_weight = r.i32();
    info.scene.view_frustum_min_m = r.f32();
    info.scene.view_frustum_max_m = r.f32();
    info.scene.stop_integrating_at_max_weight = r.u8() != 0;
    info.scene.label_update = r.u8() != 0 ? LabelUpdate::Vote : LabelUpdate::Probabilistic;
    info.T_world_camera = readMat(r);
    info.has_origin = r.u8() != 0;
    info.T_source_world = readMat(r);
    info.camera.width = r.i32();
    info.camera.height = r.i32();
    info.camera.fx = r.f32();
    info.camera.fy = r.f32();
    info.camera.cx = r.f32();
    info.camera.cy = r.f32();
    info.integration_count = r.u32();
    info.record_count = r.u64();
    if (index > 1) r.fail("corrupt: unknown index type " + std::to_string(index));
    bool known = false;
#define VF_KNOWN_VOXEL(TVoxel, TIndex) \
    if (info.voxel_type == TVoxel::name) known = known || voxel_bytes == voxelRecordBytes<TVoxel>();
    VF_FOR_EACH_ENGINE_PAIR(VF_KNOWN_VOXEL)
#undef VF_KNOWN_VOXEL
    if (!known)
        r.fail("unknown voxel type '" + info.voxel_type + "' with " + std::to_string(voxel_bytes) + "-byte records");
    if (!(info.scene.voxel_size_m > 0.f) || !(info.scene.mu_m > info.scene.voxel_size_m) || info.scene.max_weight < 1 ||
        info.scene.max_weight > 255 || !finite(info.T_world_camera) || !finite(info.T_source_world) ||
        info.camera.width < 0 || info.camera.height < 0 || info.camera.width > 1 << 16 ||
        info.camera.height > 1 << 16 ||
        !(std::isfinite(info.camera.fx) && std::isfinite(info.camera.fy) && std::isfinite(info.camera.cx) &&
          std::isfinite(info.camera.cy)))
        r.fail("corrupt: the scene settings, poses or camera are out of range");
    // Rays are cast from the resume pose as soon as the map is loaded: it must be a camera's.
    for (const Mat4f* pose : {&info.T_world_camera, &info.T_source_world}) {
        const std::string problem = text::rigidPoseProblem(pose->m);
        if (!problem.empty())
            r.fail("corrupt: " +
                   std::string(pose == &info.T_world_camera ? "the resume pose: " : "the world origin: ") + problem);
    }
    // What a map of this version can hold; the engine's own checks would refuse the rest without
    // naming the file.
    const VoxelBlockHashSettings& h = info.hash_settings;
    if (info.hash &&
        (h.bucket_count < 1 || (h.entries_per_bucket != 1 && h.entries_per_bucket != 2) || h.excess_entry_count < 0 ||
         (long long)h.bucket_count * h.entries_per_bucket + h.excess_entry_count > INT_MAX || h.max_block_count < 1 ||
         h.max_block_count > (1 << 22) || h.blocks_per_growth < 1))
        r.fail("corrupt: the hash settings are out of range (" + std::to_string(h.bucket_count) + " buckets of " +
               std::to_string(h.entries_per_bucket) + ", " + std::to_string(h.excess_entry_count) +
               " excess entries, at most " + std::to_string(h.max_block_count) + " blocks)");
    if (!info.hash)
        for (int a = 0; a < 3; ++a)
            if (info.dense_size[a] < 1 || info.dense_size[a] > (1 << 16) ||
                std::abs((long long)info.dense_offset[a]) > (1 << 24))
                r.fail("corrupt: the dense volume is out of range (offset " + std::to_string(info.dense_offset[a]) +
                       ", size " + std::to_string(info.dense_size[a]) + " on axis " + "xyz"[a] + ")");
    return info;
}

std::uint32_t voxelRecordBytesByName(const std::string& voxel_type) {
#define VF_RECORD_BYTES(TVoxel, TIndex) \
    if (voxel_type == TVoxel::name) return voxelRecordBytes<TVoxel>();
    VF_FOR_EACH_ENGINE_PAIR(VF_RECORD_BYTES)
#undef VF_RECORD_BYTES
    return 0;
}

}  // namespace mapfile

namespace {

// Reads magic, version and header, checking each; leaves the reader at the body.
MapFileInfo readHeader(FieldReader& r) {
    char magic[8];
    r.raw(magic, 8);
    if (std::memcmp(magic, kSubmapsMagic, 8) == 0) r.fail("holds a map of submaps: load it with submaps on");
    if (std::memcmp(magic, kMapMagic, 8) != 0) r.fail("not a VoxFuse map file (no VFMAP signature)");
    const std::uint32_t version = r.u32();
    if (version == 0 || version > kMapFileVersion)
        r.fail("map file version " + std::to_string(version) + " is not one this VoxFuse reads (up to " +
               std::to_string(kMapFileVersion) + ")");
    const std::uint32_t header_bytes = r.u32();
    r.resetCrc();
    MapFileInfo info = readHeaderFields(r);
    info.version = version;
    const std::uint32_t computed = r.crc();
    if (r.u32() != computed) r.fail("corrupt: the header's checksum does not match");
    if (header_bytes != kHeaderBytes)
        r.fail("corrupt: header size " + std::to_string(header_bytes) + " is not version 1's");
    if (!info.hash && info.record_count != std::uint64_t(info.dense_size.x) * std::uint64_t(info.dense_size.y) *
                                               std::uint64_t(info.dense_size.z))
        r.fail("corrupt: " + std::to_string(info.record_count) + " voxels for a " + std::to_string(info.dense_size.x) +
               "x" + std::to_string(info.dense_size.y) + "x" + std::to_string(info.dense_size.z) + " volume");
    if (info.hash && info.record_count > std::uint64_t(1) << 22)
        r.fail("corrupt: " + std::to_string(info.record_count) + " blocks, more than a map can hold (" +
               std::to_string(1 << 22) + ")");
    // The file must hold what the header lists before memory is reserved for it: a short or damaged
    // file is refused here, not after gigabytes were allocated for blocks that are not there.
    const std::uint64_t voxel_bytes = voxelRecordBytesByName(info.voxel_type);
    const std::uint64_t record_bytes = info.hash ? 6 + std::uint64_t(kBlockVoxelCount) * voxel_bytes : voxel_bytes;
    const std::uint64_t expected =
        r.taken() + info.record_count * record_bytes + 4 + 8;  // records, checksum, end marker
    const std::int64_t actual = r.fileBytes();
    if (actual >= 0 && std::uint64_t(actual) < expected)
        r.fail("truncated: the header lists " + std::to_string(info.record_count) +
               (info.hash ? " blocks" : " voxels") + " (" + std::to_string(expected) + " bytes in all), the file has " +
               std::to_string(actual) + " bytes");
    return info;
}

// ---- Index-specific bodies ----

// Every block of a hash map, active or stored, as (key, entry) in (z, y, x) order.
template <class TVoxel>
std::vector<std::pair<std::uint64_t, int>> mapBlocks(const Scene<TVoxel, VoxelBlockHash>& scene,
                                                     const GlobalCache* cache) {
    const VoxelBlockHash& hash = scene.index();
    if (hash.storedBlocks() > 0 && !cache)
        throw Error("writeMapFile: the map has swapped blocks; give its global cache");
    std::vector<std::pair<std::uint64_t, int>> blocks;
    for (int i = 0; i < hash.entryCount(); ++i) {
        const HashEntry& e = hash.entry(i);
        if (e.ptr >= 0 || e.ptr == kEntrySwappedOut) blocks.push_back({blockKey({e.pos.x, e.pos.y, e.pos.z}), i});
    }
    std::sort(blocks.begin(), blocks.end());
    return blocks;
}

template <class TVoxel>
void writeBody(FieldWriter& w, const Scene<TVoxel, VoxelBlockHash>& scene, const GlobalCache* cache) {
    const VoxelBlockHash& hash = scene.index();
    const TVoxel* voxels = scene.voxels().host();
    const int* stored_slot = hash.storedSlots();
    std::vector<TVoxel> block(kBlockVoxelCount), stored(kBlockVoxelCount);
    for (const auto& [key, entry] : mapBlocks(scene, cache)) {
        const Vec3i b = blockFromKey(key);
        w.i16(std::int16_t(b.x));
        w.i16(std::int16_t(b.y));
        w.i16(std::int16_t(b.z));
        const int ptr = hash.entry(entry).ptr, slot = stored_slot[entry];
        if (ptr >= 0)
            std::copy(voxels + std::size_t(ptr) * kBlockVoxelCount, voxels + std::size_t(ptr + 1) * kBlockVoxelCount,
                      block.begin());
        else
            std::fill(block.begin(), block.end(), TVoxel::initial());
        if (slot != kNoStoredCopy) {
            cache->read(slot, stored.data());
            for (int v = 0; v < kBlockVoxelCount; ++v)
                mergeStoredVoxel(block[std::size_t(v)], stored[std::size_t(v)], scene.params().max_weight);
        }
        for (const TVoxel& v : block) writeVoxelRecord(w, v);
        w.flushIfFull();
    }
}

template <class TVoxel>
void writeBody(FieldWriter& w, const Scene<TVoxel, PlainVoxelArray>& scene, const GlobalCache*) {
    const TVoxel* voxels = scene.voxels().host();
    for (std::size_t i = 0; i < scene.voxels().size(); ++i) {
        writeVoxelRecord(w, voxels[i]);
        w.flushIfFull();
    }
}

template <class TVoxel>
std::uint64_t recordCount(const Scene<TVoxel, VoxelBlockHash>& scene, const GlobalCache* cache) {
    return std::uint64_t(mapBlocks(scene, cache).size());
}
template <class TVoxel>
std::uint64_t recordCount(const Scene<TVoxel, PlainVoxelArray>& scene, const GlobalCache*) {
    return std::uint64_t(scene.voxels().size());
}

template <class TVoxel>
void readBody(FieldReader& r, const MapFileInfo& info, Scene<TVoxel, VoxelBlockHash>& scene, GlobalCache* cache) {
    VoxelBlockHash& hash = scene.index();
    if (!cache && info.record_count > std::uint64_t(hash.settings().max_block_count))
        r.fail(std::to_string(info.record_count) + " blocks, more than the voxel array's maximum of " +
               std::to_string(hash.settings().max_block_count) +
               " (continue it with swapping, or a larger --max-blocks)");
    if (!cache) scene.reserveVoxelBlocks(int(info.record_count));
    std::vector<TVoxel> block(kBlockVoxelCount);
    std::uint64_t previous_key = 0;
    for (std::uint64_t k = 0; k < info.record_count; ++k) {
        Vec3i b;
        b.x = r.i16();
        b.y = r.i16();
        b.z = r.i16();
        const std::uint64_t key = blockKey(b);
        if (key == kOutOfRangeBlockKey)
            r.fail("corrupt: block " + std::to_string(k) + " lies outside the storable coordinates");
        if (k > 0 && key <= previous_key) r.fail("corrupt: blocks are not in (z, y, x) order, or one is listed twice");
        previous_key = key;
        for (TVoxel& v : block) v = readVoxelRecord<TVoxel>(r);
        int entry;
        if (cache) {
            int slot;
            cache->store(block.data(), 1, &slot);
            if (hash.insertStored(b, slot, &entry) != VoxelBlockHash::InsertResult::Inserted)
                r.fail("the map's blocks do not fit its hash settings (block " + std::to_string(k) + ")");
        } else {
            if (hash.insert(b, &entry) != VoxelBlockHash::InsertResult::Inserted)
                r.fail("the map's blocks do not fit its hash settings (block " + std::to_string(k) + ")");
            std::copy(block.begin(), block.end(),
                      scene.voxels().host() + std::size_t(hash.entry(entry).ptr) * kBlockVoxelCount);
        }
    }
    hash.stats().blocks_allocated = hash.blocksInUse();
    hash.stats().block_capacity = hash.blockCapacity();
    hash.stats().blocks_stored = hash.storedBlocks();
}

template <class TVoxel>
void readBody(FieldReader& r, const MapFileInfo& info, Scene<TVoxel, PlainVoxelArray>& scene, GlobalCache*) {
    if (info.record_count != scene.voxels().size())
        r.fail("corrupt: " + std::to_string(info.record_count) + " voxels for a " +
               std::to_string(scene.voxels().size()) + "-voxel volume");
    TVoxel* voxels = scene.voxels().host();
    for (std::size_t i = 0; i < scene.voxels().size(); ++i) voxels[i] = readVoxelRecord<TVoxel>(r);
}

template <class TVoxel>
void describeIndex(MapFileInfo& info, const Scene<TVoxel, VoxelBlockHash>& scene) {
    info.hash = true;
    info.hash_settings = scene.index().settings();
}
template <class TVoxel>
void describeIndex(MapFileInfo& info, const Scene<TVoxel, PlainVoxelArray>& scene) {
    info.hash = false;
    info.dense_offset = scene.index().data().offset;
    info.dense_size = scene.index().data().size;
}

// The header fields a scene must agree with before its map is read into it.
template <class TVoxel, class TIndex>
void requireFits(FieldReader& r, const MapFileInfo& file, const Scene<TVoxel, TIndex>& scene) {
    MapFileInfo mine;
    describeIndex(mine, scene);
    if (file.voxel_type != TVoxel::name)
        r.fail("the map holds '" + file.voxel_type + "' voxels, not '" + TVoxel::name + "'");
    if (file.hash != mine.hash) r.fail(std::string("the map uses the ") + (file.hash ? "hash" : "dense") + " index");
    if (file.hash) {
        const VoxelBlockHashSettings &a = file.hash_settings, &b = mine.hash_settings;
        // The table's shape must match; the voxel array's size need not (a map can outgrow it, with swapping).
        if (a.bucket_count != b.bucket_count || a.entries_per_bucket != b.entries_per_bucket ||
            a.excess_entry_count != b.excess_entry_count)
            r.fail("the map's hash table settings differ from the scene's");
    } else if (file.dense_offset != mine.dense_offset || file.dense_size != mine.dense_size) {
        r.fail("the map's dense volume differs from the scene's");
    }
    if (file.scene.voxel_size_m != scene.params().voxel_size_m || file.scene.mu_m != scene.params().mu_m)
        r.fail("the map's voxel size and mu differ from the scene's");
}

// ---- Keyframes (version 2) ----

void writeKeyframes(FieldWriter& w, const MapKeyframes* k) {
    const std::size_t count = k ? k->keyframes.size() : 0;
    w.u32(std::uint32_t(count));
    if (count == 0) return;
    const FernSettings& f = k->ferns;
    w.i32(f.fern_count);
    w.i32(f.tests_per_fern);
    w.i32(f.image_width);
    w.f32(f.min_depth_m);
    w.f32(f.max_depth_m);
    w.u8(f.use_intensity ? 1 : 0);
    w.u32(f.seed);
    w.u8(k->with_intensity ? 1 : 0);
    w.i32(k->frame_size.x);
    w.i32(k->frame_size.y);
    for (const Keyframe& kf : k->keyframes) {
        if (kf.code.size() != std::size_t(f.fern_count))
            throw Error("writeMapFile: a keyframe's code has " + std::to_string(kf.code.size()) + " ferns, not " +
                        std::to_string(f.fern_count));
        w.i32(kf.frame_index);
        writeMat(w, kf.T_world_camera);
        w.raw(reinterpret_cast<const char*>(kf.code.data()), kf.code.size());
        w.flushIfFull();
    }
}

void readKeyframes(FieldReader& r, MapKeyframes& k) {
    const std::uint32_t count = r.u32();
    if (count == 0) return;
    FernSettings& f = k.ferns;
    f.fern_count = r.i32();
    f.tests_per_fern = r.i32();
    f.image_width = r.i32();
    f.min_depth_m = r.f32();
    f.max_depth_m = r.f32();
    f.use_intensity = r.u8() != 0;
    f.seed = r.u32();
    k.with_intensity = r.u8() != 0;
    k.frame_size.x = r.i32();
    k.frame_size.y = r.i32();
    if (f.fern_count < 1 || f.fern_count > (1 << 16) || f.tests_per_fern < 1 || f.tests_per_fern > 8 ||
        f.image_width < 1 || f.image_width > (1 << 16) || !(f.min_depth_m >= 0.f) || !(f.max_depth_m > f.min_depth_m) ||
        !std::isfinite(f.max_depth_m) || k.frame_size.x < 1 || k.frame_size.y < 1 || k.frame_size.x > (1 << 16) ||
        k.frame_size.y > (1 << 16))
        r.fail("corrupt: the keyframes' fern settings or frame size are out of range");
    // Checked before anything is reserved for them, as the voxels are.
    const std::uint64_t bytes = std::uint64_t(count) * (4 + 64 + std::uint64_t(f.fern_count));
    const std::int64_t actual = r.fileBytes();
    if (actual >= 0 && r.taken() + bytes > std::uint64_t(actual))
        r.fail("truncated: " + std::to_string(count) + " keyframes are listed, the file ends before them");
    k.keyframes.resize(count);
    for (std::uint32_t i = 0; i < count; ++i) {
        Keyframe& kf = k.keyframes[i];
        kf.frame_index = r.i32();
        kf.T_world_camera = readMat(r);
        const std::string problem = text::rigidPoseProblem(kf.T_world_camera.m);
        if (!problem.empty()) r.fail("corrupt: keyframe " + std::to_string(i) + "'s pose: " + problem);
        kf.code.resize(std::size_t(f.fern_count));
        r.raw(reinterpret_cast<char*>(kf.code.data()), kf.code.size());
        for (const std::uint8_t c : kf.code)
            if (c >> f.tests_per_fern)
                r.fail("corrupt: keyframe " + std::to_string(i) + "'s code has a fern out of range");
    }
}

}  // namespace

MapFileInfo readMapFileInfo(const std::string& path) {
    MapFileReader file(path);
    if (file.holdsSubmaps()) return readSubmapMapHeader(file).map;
    return file.nextMapInfo();
}

MapFileWriter::MapFileWriter(const std::string& path) : stream_(std::make_unique<Stream>(path)) {}
MapFileWriter::~MapFileWriter() = default;
void MapFileWriter::commit() { stream_->file.commit(); }

MapFileReader::MapFileReader(const std::string& path) {
    if (std::filesystem::is_directory(path)) throw IoError(path, "is a folder, not a map file");
    std::ifstream in(path, std::ios::binary);
    if (!in) throw IoError(path, std::string("cannot open the map file: ") + std::strerror(errno));
    stream_ = std::make_unique<Stream>(path, std::move(in));
}
MapFileReader::~MapFileReader() = default;
const std::string& MapFileReader::path() const { return stream_->path; }
bool MapFileReader::holdsSubmaps() { return stream_->fields.nextBytesAre(kSubmapsMagic, 8); }
const MapFileInfo& MapFileReader::nextMapInfo() {
    if (!stream_->pending) {
        stream_->info = readHeader(stream_->fields);
        stream_->pending = true;
    }
    return stream_->info;
}
void MapFileReader::requireEnd() {
    if (!stream_->fields.atEnd()) stream_->fields.fail("corrupt: bytes after the end marker");
}

template <class TVoxel, class TIndex>
void writeMap(MapFileWriter& file, const Scene<TVoxel, TIndex>& scene, const MapFileInfo& pose,
              const GlobalCache* cache, const MapKeyframes* keyframes) {
    if (scene.location() != Device::CPU)
        throw DeviceError("writeMapFile: the scene must be in host memory (Scene::copyTo(Device::CPU))");
    MapFileInfo info = pose;
    info.version = kMapFileVersion;
    info.voxel_type = TVoxel::name;
    describeIndex(info, scene);
    info.scene = scene.params();
    info.integration_count = scene.integrationCount();
    info.record_count = recordCount(scene, cache);
    info.submap_count = 0;

    FieldWriter& w = file.stream().fields;
    w.raw(kMapMagic, 8);
    w.u32(info.version);
    w.u32(kHeaderBytes);
    w.flush(false);
    w.resetCrc();
    writeHeaderFields(w, info, voxelRecordBytes<TVoxel>());
    w.flush();
    w.u32(w.crc());
    w.flush(false);
    w.resetCrc();
    writeBody(w, scene, cache);
    writeKeyframes(w, keyframes);
    w.flush();
    w.u32(w.crc());
    w.raw(kEndMagic, 8);
    w.flush(false);
}

template <class TVoxel, class TIndex>
void writeMapFile(const std::string& path, const Scene<TVoxel, TIndex>& scene, const MapFileInfo& pose,
                  const GlobalCache* cache, const MapKeyframes* keyframes) {
    MapFileWriter file(path);
    writeMap(file, scene, pose, cache, keyframes);
    file.commit();
}

template <class TVoxel, class TIndex>
MapFileInfo readMap(MapFileReader& file, Scene<TVoxel, TIndex>& scene, GlobalCache* cache, MapKeyframes* keyframes) {
    if (scene.location() != Device::CPU) throw DeviceError("readMapFile: the scene must be in host memory");
    const MapFileInfo info = file.nextMapInfo();
    file.stream().pending = false;
    FieldReader& r = file.stream().fields;
    requireFits(r, info, scene);
    r.resetCrc();
    readBody(r, info, scene, cache);
    MapKeyframes read;
    if (info.version >= 2) readKeyframes(r, read);
    const std::uint32_t computed = r.crc();
    if (r.u32() != computed) r.fail("corrupt: the checksum of the map's voxels does not match");
    char end[8];
    r.raw(end, 8);
    if (std::memcmp(end, kEndMagic, 8) != 0) r.fail("corrupt: no end marker after the voxels");
    scene.setIntegrationCount(info.integration_count);
    if (keyframes) *keyframes = std::move(read);
    return info;
}

template <class TVoxel, class TIndex>
MapFileInfo readMapFile(const std::string& path, Scene<TVoxel, TIndex>& scene, GlobalCache* cache,
                        MapKeyframes* keyframes) {
    MapFileReader file(path);
    const MapFileInfo info = readMap(file, scene, cache, keyframes);
    file.requireEnd();
    return info;
}

#define VF_INSTANTIATE(TVoxel, TIndex)                                                                                 \
    template void writeMap<TVoxel, TIndex>(MapFileWriter&, const Scene<TVoxel, TIndex>&, const MapFileInfo&,           \
                                           const GlobalCache*, const MapKeyframes*);                                   \
    template void writeMapFile<TVoxel, TIndex>(const std::string&, const Scene<TVoxel, TIndex>&, const MapFileInfo&,   \
                                               const GlobalCache*, const MapKeyframes*);                               \
    template MapFileInfo readMap<TVoxel, TIndex>(MapFileReader&, Scene<TVoxel, TIndex>&, GlobalCache*, MapKeyframes*); \
    template MapFileInfo readMapFile<TVoxel, TIndex>(const std::string&, Scene<TVoxel, TIndex>&, GlobalCache*,         \
                                                     MapKeyframes*);
VF_FOR_EACH_ENGINE_PAIR(VF_INSTANTIATE)
#undef VF_INSTANTIATE

}  // namespace voxfuse
