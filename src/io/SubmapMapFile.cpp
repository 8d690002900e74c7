// Maps of submaps: the format of io/SubmapMapFile.h, in the map files' fields (MapFileFields.h).

#include "voxfuse/io/SubmapMapFile.h"

#include <cmath>
#include <string>

#include "MapFileFields.h"
#include "TextParsing.h"

namespace voxfuse {
using namespace mapfile;
namespace {

constexpr char kSubmapsEndMagic[8] = {'V', 'F', 'S', 'U', 'B', 'E', 'N', 'D'};
// More submaps than any run makes (a 1.5 m submap each, the far side of a city block): a count beyond
// it is a damaged file, refused before anything is reserved for it.
constexpr std::uint64_t kMaxSubmaps = 1 << 16;
constexpr std::uint32_t kMaxEdgesPerSubmap = 64;

void requirePose(FieldReader& r, const Mat4f& T, const std::string& what) {
    const std::string problem = text::rigidPoseProblem(T.m);
    if (!problem.empty()) r.fail("corrupt: " + what + ": " + problem);
}

}  // namespace

void writeSubmapMapHeader(MapFileWriter& file, const SubmapMapInfo& info) {
    const std::size_t n = info.T_world_submap.size();
    if (n == 0 || info.parent.size() != n || info.active < 0 || std::size_t(info.active) >= n)
        throw Error("writeSubmapMapHeader: " + std::to_string(n) + " submaps, " + std::to_string(info.parent.size()) +
                    " parents, active " + std::to_string(info.active));
    FieldWriter& w = file.stream().fields;
    w.raw(kSubmapsMagic, 8);
    w.flush(false);
    w.resetCrc();
    w.u32(kSubmapMapFileVersion);
    MapFileInfo map = info.map;
    map.record_count = n;
    writeHeaderFields(w, map, voxelRecordBytesByName(map.voxel_type));
    w.u32(std::uint32_t(info.active));
    for (std::size_t i = 0; i < n; ++i) {
        writeMat(w, info.T_world_submap[i]);
        w.i32(info.parent[i]);
    }
    w.u32(std::uint32_t(info.edges.size()));
    for (const PoseGraphEdge& e : info.edges) {
        w.i32(e.from);
        w.i32(e.to);
        writeMat(w, e.T_from_to);
        w.f32(e.sigma_translation_m);
        w.f32(e.sigma_rotation_rad);
        w.u8(e.loop ? 1 : 0);
    }
    w.flush();
    w.u32(w.crc());
    w.flush(false);
}

void writeSubmapMapEnd(MapFileWriter& file) {
    FieldWriter& w = file.stream().fields;
    w.raw(kSubmapsEndMagic, 8);
    w.flush(false);
}

SubmapMapInfo readSubmapMapHeader(MapFileReader& file) {
    FieldReader& r = file.stream().fields;
    char magic[8];
    r.raw(magic, 8);
    if (std::memcmp(magic, kSubmapsMagic, 8) != 0)
        r.fail("holds a single map, not a map of submaps (no VFSUBMAP signature)");
    r.resetCrc();
    const std::uint32_t version = r.u32();
    if (version == 0 || version > kSubmapMapFileVersion)
        r.fail("map of submaps version " + std::to_string(version) + " is not one this VoxFuse reads (up to " +
               std::to_string(kSubmapMapFileVersion) + ")");
    SubmapMapInfo info;
    info.map = readHeaderFields(r);
    if (!info.map.hash) r.fail("corrupt: a map of submaps is of voxel block hashes, the header says dense");
    if (info.map.record_count < 1 || info.map.record_count > kMaxSubmaps)
        r.fail("corrupt: " + std::to_string(info.map.record_count) + " submaps");
    const int n = int(info.map.record_count);
    info.map.submap_count = n;
    info.active = int(r.u32());
    if (info.active < 0 || info.active >= n)
        r.fail("corrupt: the active submap is not one of the " + std::to_string(n));
    for (int i = 0; i < n; ++i) {
        info.T_world_submap.push_back(readMat(r));
        requirePose(r, info.T_world_submap.back(), "submap " + std::to_string(i) + "'s pose");
        info.parent.push_back(r.i32());
        if (info.parent.back() < -1 || info.parent.back() >= i || (i > 0) != (info.parent.back() >= 0))
            r.fail("corrupt: submap " + std::to_string(i) + " starts from submap " +
                   std::to_string(info.parent.back()));
    }
    const std::uint32_t edges = r.u32();
    if (edges > kMaxEdgesPerSubmap * std::uint32_t(n)) r.fail("corrupt: " + std::to_string(edges) + " edges");
    for (std::uint32_t k = 0; k < edges; ++k) {
        PoseGraphEdge e;
        e.from = r.i32();
        e.to = r.i32();
        e.T_from_to = readMat(r);
        e.sigma_translation_m = r.f32();
        e.sigma_rotation_rad = r.f32();
        e.loop = r.u8() != 0;
        const std::string edge = "edge " + std::to_string(k);
        if (e.from < 0 || e.from >= n || e.to < 0 || e.to >= n || e.from == e.to)
            r.fail("corrupt: " + edge + " joins submaps " + std::to_string(e.from) + " and " + std::to_string(e.to));
        if (!(e.sigma_translation_m > 0.f) || !(e.sigma_rotation_rad > 0.f) || !std::isfinite(e.sigma_translation_m) ||
            !std::isfinite(e.sigma_rotation_rad))
            r.fail("corrupt: " + edge + "'s uncertainty is not positive");
        requirePose(r, e.T_from_to, edge + "'s measurement");
        info.edges.push_back(e);
    }
    const std::uint32_t computed = r.crc();
    if (r.u32() != computed) r.fail("corrupt: the checksum of the submaps' header does not match");
    return info;
}

void readSubmapMapEnd(MapFileReader& file) {
    FieldReader& r = file.stream().fields;
    char end[8];
    r.raw(end, 8);
    if (std::memcmp(end, kSubmapsEndMagic, 8) != 0) r.fail("corrupt: no end marker after the submaps");
    file.requireEnd();
}

}  // namespace voxfuse
