// Map files (.vfm): the header, and for maps small enough to load quickly, the whole map into an
// engine, saved again. The first byte's low bit asks for the checksums to be recomputed, so that
// mutations reach the fields behind them instead of stopping at the CRC.

#include <zlib.h>

#include <cstring>
#include <vector>

#include "FuzzInput.h"
#include "voxfuse/core/Error.h"
#include "voxfuse/engines/MainEngine.h"
#include "voxfuse/io/MapFile.h"

namespace {

// A single map's layout (io/MapFile.h): magic, version and header size (16 bytes), 255 bytes of fields,
// their CRC, the body (from version 2 with the keyframes), its CRC and the 8-byte end marker. (The
// header-size field counts the CRC too: 259.) A map of submaps (io/SubmapMapFile.h) is read as it is:
// its checksums are not recomputed.
constexpr std::size_t kHeaderStart = 16, kHeaderBytes = 255, kBodyStart = kHeaderStart + kHeaderBytes + 4;

void putCrc(std::vector<std::uint8_t>& bytes, std::size_t begin, std::size_t end) {
    const std::uint32_t crc = std::uint32_t(crc32(crc32(0L, Z_NULL, 0), bytes.data() + begin, unsigned(end - begin)));
    for (int i = 0; i < 4; ++i) bytes[end + std::size_t(i)] = std::uint8_t(crc >> (8 * i));
}

bool smallEnough(const voxfuse::MapFileInfo& info) {
    if (!info.hash) return std::uint64_t(info.dense_size.x) * info.dense_size.y * info.dense_size.z <= (1u << 18);
    const auto& h = info.hash_settings;
    return (long long)h.bucket_count * h.entries_per_bucket + h.excess_entry_count <= (1 << 16) &&
           h.max_block_count <= (1 << 12);
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    using namespace voxfuse;
    if (size < 1) return 0;
    std::vector<std::uint8_t> bytes(data + 1, data + size);
    if ((data[0] & 1) && bytes.size() >= kBodyStart + 12) {
        putCrc(bytes, kHeaderStart, kHeaderStart + kHeaderBytes);
        putCrc(bytes, kBodyStart, bytes.size() - 12);
    }
    const std::string path = fuzz::writeInput(bytes.data(), bytes.size(), "map.vfm");
    MapFileInfo info;
    try {
        info = readMapFileInfo(path);
    } catch (const Error&) {
        return 0;
    }
    if (!smallEnough(info)) return 0;
    RGBDCalib calib;
    calib.depth = calib.rgb = Intrinsics{16, 12, 12.f, 12.f, 7.5f, 5.5f};
    std::unique_ptr<MainEngine> engine;
    try {
        engine = MainEngine::create(settingsForMap(info, MainEngineSettings{}), calib);
        engine->loadMap(path);
    } catch (const Error&) {
        return 0;
    }
    // A map that loaded saves and loads again: an exception here escapes, as the finding it is.
    engine->saveMap(fuzz::scratchFolder() + "/map_written.vfm");
    engine->loadMap(fuzz::scratchFolder() + "/map_written.vfm");
    return 0;
}
