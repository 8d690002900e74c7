// Map files: a saved map loads back voxel for voxel and saves to the same bytes; a loaded map meshes
// as the original and carries a run on; bad files are refused with the file and the reason named.

#include <gtest/gtest.h>

#include <zlib.h>

#include <cstdint>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include "DeviceTestSupport.h"
#include "IoTestUtil.h"
#include "SyntheticViews.h"
#include "voxfuse/core/Error.h"
#include "voxfuse/engines/AllocationEngine.h"
#include "voxfuse/engines/IntegrationEngine.h"
#include "voxfuse/engines/MainEngine.h"
#include "voxfuse/engines/MeshingEngine.h"
#include "voxfuse/io/AtomicFile.h"
#include "voxfuse/io/MapFile.h"
#include "voxfuse/io/SubmapMapFile.h"
#include "voxfuse/objects/Voxel.h"

namespace fs = std::filesystem;

namespace voxfuse {
namespace {

std::vector<char> bytesOf(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    return std::vector<char>(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}
void writeBytes(const std::string& path, const std::vector<char>& bytes) {
    std::ofstream out(path, std::ios::binary | std::ios::trunc);
    out.write(bytes.data(), std::streamsize(bytes.size()));
}

// A small fused scene: a few views of the box-and-sphere world, classes and colour included.
template <class TVoxel, class TIndex>
Scene<TVoxel, TIndex> fusedScene(TIndex index) {
    Scene<TVoxel, TIndex> scene(test::centimetreSceneParams(), std::move(index), Device::CPU);
    auto allocation = makeAllocationEngine<TVoxel, TIndex>(Device::CPU);
    auto integration = makeIntegrationEngine<TVoxel, TIndex>(Device::CPU);
    const synth::SyntheticScene world = synth::SyntheticScene::boxAndSphere();
    for (int k = 0; k < 3; ++k) {
        const Mat4f pose = test::lookAt({1.0f - 0.3f * k, -0.8f + 0.5f * k, 0.7f}, {0.3f, 0.f, 0.1f});
        const View view = test::labelledView(world, test::kinectIntrinsics(160, 120), pose, k);
        allocation->allocate(scene, view, pose);
        integration->integrate(scene, view, pose);
    }
    return scene;
}

MapFileInfo somePose() {
    MapFileInfo pose;
    pose.T_world_camera = test::lookAt({0.5f, 0.2f, 0.9f}, {0.f, 0.f, 0.f});
    pose.has_origin = true;
    pose.T_source_world = test::lookAt({2.f, 1.f, 1.5f}, {0.f, 0.f, 0.f});
    pose.camera = test::kinectIntrinsics(160, 120);
    return pose;
}

template <class TVoxel>
class MapFileRoundTrip : public ::testing::Test {};
using VoxelTypes = ::testing::Types<VoxelS, VoxelF, VoxelSRgb, VoxelFRgb, VoxelSLabel, VoxelSRgbLabel>;
TYPED_TEST_SUITE(MapFileRoundTrip, VoxelTypes);

TYPED_TEST(MapFileRoundTrip, HashMapLoadsVoxelForVoxelAndSavesToTheSameBytes) {
    const test::ScratchDir scratch;
    using TVoxel = TypeParam;
    const auto scene = fusedScene<TVoxel>(VoxelBlockHash());
    const std::string first = scratch.file(std::string("hash_") + TVoxel::name + ".vfm"), second = first + ".again";
    writeMapFile(first, scene, somePose());

    const MapFileInfo info = readMapFileInfo(first);
    EXPECT_EQ(info.voxel_type, TVoxel::name);
    EXPECT_TRUE(info.hash);
    EXPECT_EQ(info.record_count, std::uint64_t(scene.index().blocksInUse()));
    EXPECT_EQ(info.integration_count, 3u);
    EXPECT_TRUE(info.has_origin);
    EXPECT_EQ(info.camera.width, 160);

    Scene<TVoxel, VoxelBlockHash> loaded(test::centimetreSceneParams(), VoxelBlockHash(), Device::CPU);
    const MapFileInfo read = readMapFile(first, loaded);
    EXPECT_EQ(0, std::memcmp(read.T_world_camera.m, somePose().T_world_camera.m, sizeof(Mat4f)));
    EXPECT_EQ(loaded.integrationCount(), 3u);
    ASSERT_EQ(loaded.index().blocksInUse(), scene.index().blocksInUse());
    const VoxelBlockHash& a = scene.index();
    const VoxelBlockHash& b = loaded.index();
    for (int i = 0; i < a.entryCount(); ++i) {
        const HashEntry& e = a.entry(i);
        if (e.ptr < 0) continue;
        const int j = b.findEntry({e.pos.x, e.pos.y, e.pos.z});
        ASSERT_GE(j, 0);
        for (int v = 0; v < kBlockVoxelCount; ++v)
            ASSERT_TRUE(test::sameVoxel(scene.voxels().host()[std::size_t(e.ptr) * kBlockVoxelCount + v],
                                        loaded.voxels().host()[std::size_t(b.entry(j).ptr) * kBlockVoxelCount + v]));
    }
    writeMapFile(second, loaded, read);
    EXPECT_EQ(bytesOf(first), bytesOf(second)) << "save, load, save gives the same bytes";
}

TEST(MapFileTest, DenseMapRoundTripsAndMeshesLikeTheOriginal) {
    const test::ScratchDir scratch;
    const PlainVoxelArray index({-60, -60, -20}, {140, 120, 80});
    const auto scene = fusedScene<VoxelSRgb>(index);
    const std::string path = scratch.file("dense.vfm");
    writeMapFile(path, scene, somePose());
    Scene<VoxelSRgb, PlainVoxelArray> loaded(test::centimetreSceneParams(), index, Device::CPU);
    readMapFile(path, loaded);
    ASSERT_EQ(test::firstDifferentVoxel(scene.voxels(), loaded.voxels()), -1);
    auto meshing = makeMeshingEngine<VoxelSRgb, PlainVoxelArray>(Device::CPU);
    Mesh original, again;
    meshing->extractMesh(scene, original);
    meshing->extractMesh(loaded, again);
    ASSERT_GT(original.triangles.size(), 1000u);
    EXPECT_EQ(original.vertices.size(), again.vertices.size());
    EXPECT_EQ(original.triangles.size(), again.triangles.size());
    for (std::size_t i = 0; i < original.vertices.size(); ++i) ASSERT_TRUE(original.vertices[i] == again.vertices[i]);
}

// The error a bad file gets, or "" when it loads.
std::string loadError(const std::string& path) {
    Scene<VoxelS, VoxelBlockHash> scene(test::centimetreSceneParams(), VoxelBlockHash(), Device::CPU);
    try {
        readMapFile(path, scene);
    } catch (const IoError& e) {
        EXPECT_EQ(e.file(), path);
        return e.what();
    }
    return "";
}

TEST(MapFileTest, BadFilesAreRefusedWithTheReason) {
    const test::ScratchDir scratch;
    const auto scene = fusedScene<VoxelS>(VoxelBlockHash());
    const std::string good = scratch.file("good.vfm"), bad = scratch.file("bad.vfm");
    writeMapFile(good, scene, somePose());
    const std::vector<char> bytes = bytesOf(good);
    ASSERT_GT(bytes.size(), 10000u);
    EXPECT_EQ(loadError(good), "");

    auto expectRefused = [&](std::vector<char> b, const std::string& reason) {
        writeBytes(bad, b);
        const std::string error = loadError(bad);
        EXPECT_NE(error.find(reason), std::string::npos) << "expected '" << reason << "', got '" << error << "'";
    };
    for (std::size_t cut :
         {std::size_t(0), std::size_t(5), std::size_t(100), bytes.size() / 2, bytes.size() - 9, bytes.size() - 1}) {
        std::vector<char> b(bytes.begin(), bytes.begin() + std::ptrdiff_t(cut));
        expectRefused(b, "truncated");
    }
    {
        std::vector<char> b = bytes;
        b[bytes.size() / 2] ^= 0x10;
        expectRefused(b, "checksum of the map's voxels does not match");
    }
    {
        std::vector<char> b = bytes;
        b[40] ^= 0x01;  // inside the header
        expectRefused(b, "header's checksum does not match");
    }
    {
        std::vector<char> b = bytes;
        b[0] = 'X';
        expectRefused(b, "not a VoxFuse map file");
    }
    {
        std::vector<char> b = bytes;
        b[8] = 99;  // version
        expectRefused(b, "map file version 99");
    }
    {
        std::vector<char> b = bytes;
        b.push_back('!');
        expectRefused(b, "bytes after the end marker");
    }
    writeBytes(bad, std::vector<char>{'h', 'e', 'l', 'l', 'o'});
    EXPECT_NE(loadError(bad).find("truncated"), std::string::npos);
    EXPECT_NE(loadError(fs::temp_directory_path().string()).find("is a folder"), std::string::npos);
    EXPECT_NE(loadError(scratch.file("missing.vfm")).find("cannot open"), std::string::npos);
}

// A header that lists more blocks than the file holds (its checksum made to match) is refused before
// memory is reserved for them: a few hundred bytes must not make the reader allocate gigabytes.
TEST(MapFileTest, AHeaderListingMoreBlocksThanTheFileHoldsIsRefusedAtOnce) {
    const test::ScratchDir scratch;
    const auto scene = fusedScene<VoxelS>(VoxelBlockHash());
    const std::string good = scratch.file("good.vfm"), bad = scratch.file("bad.vfm");
    writeMapFile(good, scene, somePose());
    std::vector<char> b = bytesOf(good);
    // magic (8), version (4), header size (4), then the header: its fields, the last of them the record
    // count, and their CRC (4).
    std::uint32_t header_bytes;
    std::memcpy(&header_bytes, b.data() + 12, 4);
    const std::size_t crc_at = 16 + header_bytes - 4, count_at = crc_at - 8;
    const std::uint64_t blocks = std::uint64_t(1) << 20;
    std::memcpy(b.data() + count_at, &blocks, 8);
    const auto crc =
        std::uint32_t(crc32(crc32(0L, Z_NULL, 0), reinterpret_cast<const Bytef*>(b.data() + 16), uInt(crc_at - 16)));
    std::memcpy(b.data() + crc_at, &crc, 4);
    writeBytes(bad, b);
    const std::string error = loadError(bad);
    EXPECT_NE(error.find("truncated: the header lists 1048576 blocks"), std::string::npos) << error;
    try {
        readMapFileInfo(bad);
        ADD_FAILURE() << "the header alone was accepted";
    } catch (const IoError& e) {
        EXPECT_NE(std::string(e.what()).find("the header lists"), std::string::npos) << e.what();
    }
}

TEST(MapFileTest, AMapOfOtherSettingsIsRefusedByName) {
    const test::ScratchDir scratch;
    const auto scene = fusedScene<VoxelSRgb>(VoxelBlockHash());
    const std::string path = scratch.file("rgb.vfm");
    writeMapFile(path, scene, somePose());
    EXPECT_NE(loadError(path).find("holds 's_rgb' voxels, not 's'"), std::string::npos);
    VoxelBlockHashSettings other;
    other.bucket_count = 4096;
    Scene<VoxelSRgb, VoxelBlockHash> smaller(test::centimetreSceneParams(), VoxelBlockHash(other), Device::CPU);
    try {
        readMapFile(path, smaller);
        ADD_FAILURE() << "other hash settings were accepted";
    } catch (const IoError& e) {
        EXPECT_NE(std::string(e.what()).find("hash table settings differ"), std::string::npos) << e.what();
    }
}

// Found by fuzzing: a map whose resume pose was finite but no rotation (3e38 in it) loaded, and the
// raycast from it cast -inf to int.
TEST(MapFileTest, AResumePoseThatIsNoCameraIsRefused) {
    const test::ScratchDir scratch;
    const auto scene = fusedScene<VoxelS>(VoxelBlockHash());
    for (auto [what, change] :
         {std::pair{"a shear", std::pair{1, 3e38f}}, {"a position 10^7 m away", std::pair{3, 1e7f}}}) {
        SCOPED_TRACE(what);
        MapFileInfo pose = somePose();
        pose.T_world_camera.m[change.first] = change.second;
        const std::string path = scratch.file("bad_pose.vfm");
        writeMapFile(path, scene, pose);
        const std::string error = loadError(path);
        EXPECT_NE(error.find("corrupt: the resume pose"), std::string::npos) << error;
    }
}

TEST(MapFileTest, AFailedWriteLeavesNothingBehind) {
    const test::ScratchDir scratch;
    const auto scene = fusedScene<VoxelS>(VoxelBlockHash());
    const std::string nowhere = scratch.path() + "/no_such_folder/map.vfm";
    try {
        writeMapFile(nowhere, scene, somePose());
        ADD_FAILURE() << "wrote into a missing folder";
    } catch (const IoError& e) {
        EXPECT_NE(std::string(e.what()).find("no such folder"), std::string::npos) << e.what();
    }
    const std::string kept = scratch.file("kept.vfm");
    writeBytes(kept, {'o', 'l', 'd'});
    const fs::path folder = fs::path(scratch.path()) / "a_folder";
    fs::create_directories(folder);
    EXPECT_THROW(writeMapFile(folder.string(), scene, somePose()), IoError) << "a folder is no map file";
    EXPECT_EQ(bytesOf(kept), (std::vector<char>{'o', 'l', 'd'})) << "a file beside the failed write is untouched";
    for (const auto& entry : fs::directory_iterator(scratch.path()))
        EXPECT_FALSE(isPartialFileName(entry.path().filename().string())) << "temporary file left: " << entry.path();
}

MapKeyframes someKeyframes(int count) {
    MapKeyframes k;
    k.ferns.fern_count = 50;
    k.ferns.tests_per_fern = 4;
    k.with_intensity = true;
    k.frame_size = {160, 120};
    for (int i = 0; i < count; ++i) {
        Keyframe kf;
        kf.frame_index = 10 * i + 3;
        kf.T_world_camera = test::lookAt({0.2f * float(i), 0.1f, 0.9f}, {0.f, 0.f, 0.f});
        for (int f = 0; f < k.ferns.fern_count; ++f) kf.code.push_back(std::uint8_t((f * 7 + i) % 16));
        k.keyframes.push_back(kf);
    }
    return k;
}

// Keyframes (version 2) come back as saved; a version 1 file (no keyframes) still loads.
TEST(MapFileTest, KeyframesLoadAsSavedAndAVersion1MapStillLoads) {
    const test::ScratchDir scratch;
    const auto scene = fusedScene<VoxelS>(VoxelBlockHash());
    const std::string path = scratch.file("keyframes.vfm"), again = scratch.file("again.vfm");
    const MapKeyframes saved = someKeyframes(3);
    writeMapFile(path, scene, somePose(), nullptr, &saved);
    Scene<VoxelS, VoxelBlockHash> loaded(test::centimetreSceneParams(), VoxelBlockHash(), Device::CPU);
    MapKeyframes read;
    EXPECT_EQ(readMapFile(path, loaded, nullptr, &read).version, 2u);
    ASSERT_EQ(read.keyframes.size(), 3u);
    EXPECT_EQ(read.ferns.fern_count, 50);
    EXPECT_EQ(read.ferns.seed, saved.ferns.seed);
    EXPECT_TRUE(read.with_intensity);
    EXPECT_TRUE(read.frame_size == saved.frame_size);
    for (std::size_t i = 0; i < 3; ++i) {
        EXPECT_EQ(read.keyframes[i].frame_index, saved.keyframes[i].frame_index);
        EXPECT_EQ(read.keyframes[i].code, saved.keyframes[i].code);
        EXPECT_EQ(0,
                  std::memcmp(read.keyframes[i].T_world_camera.m, saved.keyframes[i].T_world_camera.m, sizeof(Mat4f)));
    }
    writeMapFile(again, loaded, somePose(), nullptr, &read);
    EXPECT_EQ(bytesOf(path), bytesOf(again));

    // Version 1: the same map without the keyframe count, its voxels' checksum over the voxels alone.
    writeMapFile(path, scene, somePose());
    std::vector<char> b = bytesOf(path);
    std::uint32_t header_bytes;
    std::memcpy(&header_bytes, b.data() + 12, 4);
    const std::size_t body = 16 + header_bytes, count_at = b.size() - 12 - 4;
    b.erase(b.begin() + std::ptrdiff_t(count_at), b.begin() + std::ptrdiff_t(count_at + 4));
    b[8] = 1;
    const auto crc = std::uint32_t(
        crc32(crc32(0L, Z_NULL, 0), reinterpret_cast<const Bytef*>(b.data() + body), uInt(count_at - body)));
    std::memcpy(b.data() + count_at, &crc, 4);
    writeBytes(path, b);
    Scene<VoxelS, VoxelBlockHash> old(test::centimetreSceneParams(), VoxelBlockHash(), Device::CPU);
    read = saved;
    EXPECT_EQ(readMapFile(path, old, nullptr, &read).version, 1u);
    EXPECT_TRUE(read.keyframes.empty());
    EXPECT_EQ(old.index().blocksInUse(), scene.index().blocksInUse());
}

TEST(MapFileTest, BadKeyframesAreRefusedWithTheReason) {
    const test::ScratchDir scratch;
    const auto scene = fusedScene<VoxelS>(VoxelBlockHash());
    const std::string path = scratch.file("keyframes.vfm");
    MapKeyframes k = someKeyframes(2);
    k.keyframes[1].code[5] = 16;  // a 4-test fern's code is below 16
    writeMapFile(path, scene, somePose(), nullptr, &k);
    EXPECT_NE(loadError(path).find("keyframe 1's code has a fern out of range"), std::string::npos) << loadError(path);
    k = someKeyframes(2);
    k.keyframes[0].T_world_camera.m[1] = 3.f;
    writeMapFile(path, scene, somePose(), nullptr, &k);
    EXPECT_NE(loadError(path).find("keyframe 0's pose"), std::string::npos) << loadError(path);
    k = someKeyframes(2);
    k.ferns.tests_per_fern = 9;
    writeMapFile(path, scene, somePose(), nullptr, &k);
    EXPECT_NE(loadError(path).find("fern settings or frame size are out of range"), std::string::npos);
    k = someKeyframes(2);
    k.keyframes[0].code.pop_back();
    EXPECT_THROW(writeMapFile(path, scene, somePose(), nullptr, &k), Error);
}

// A map of submaps: its header and each submap's map; readMapFileInfo tells how many; damage anywhere
// is refused with the reason.
void writeSubmapMap(const std::string& path, const Scene<VoxelS, VoxelBlockHash>& scene, const SubmapMapInfo& info) {
    MapFileWriter file(path);
    writeSubmapMapHeader(file, info);
    for (std::size_t i = 0; i < info.T_world_submap.size(); ++i) writeMap(file, scene, somePose());
    writeSubmapMapEnd(file);
    file.commit();
}

std::string submapLoadError(const std::string& path) {
    try {
        MapFileReader file(path);
        const SubmapMapInfo info = readSubmapMapHeader(file);
        for (std::size_t i = 0; i < info.T_world_submap.size(); ++i) {
            Scene<VoxelS, VoxelBlockHash> scene(test::centimetreSceneParams(), VoxelBlockHash(), Device::CPU);
            readMap(file, scene);
        }
        readSubmapMapEnd(file);
    } catch (const IoError& e) {
        EXPECT_EQ(e.file(), path);
        return e.what();
    }
    return "";
}

TEST(MapFileTest, AMapOfSubmapsHoldsItsGraphAndEverySubmapAndRefusesDamage) {
    const test::ScratchDir scratch;
    const auto scene = fusedScene<VoxelS>(VoxelBlockHash());
    SubmapMapInfo info;
    info.map.voxel_type = "s";
    info.map.scene = scene.params();
    info.map.camera = test::kinectIntrinsics(160, 120);
    info.active = 1;
    info.T_world_submap = {Mat4f::identity(), test::lookAt({0.5f, 0.f, 0.f}, {0.f, 0.f, 1.f})};
    info.parent = {-1, 0};
    PoseGraphEdge edge;
    edge.from = 0;
    edge.to = 1;
    edge.T_from_to = info.T_world_submap[1];
    edge.loop = true;
    info.edges = {edge};
    const std::string path = scratch.file("submaps.vfm"), bad = scratch.file("bad.vfm");
    writeSubmapMap(path, scene, info);
    const MapFileInfo whole = readMapFileInfo(path);
    EXPECT_EQ(whole.submap_count, 2);
    EXPECT_EQ(whole.voxel_type, "s");
    EXPECT_EQ(submapLoadError(path), "");
    {
        MapFileReader file(path);
        EXPECT_TRUE(file.holdsSubmaps());
        const SubmapMapInfo read = readSubmapMapHeader(file);
        EXPECT_EQ(read.active, 1);
        ASSERT_EQ(read.edges.size(), 1u);
        EXPECT_TRUE(read.edges[0].loop);
        EXPECT_EQ(read.parent, info.parent);
        EXPECT_EQ(0, std::memcmp(read.T_world_submap[1].m, info.T_world_submap[1].m, sizeof(Mat4f)));
    }
    // A single-map reader names what the file is.
    EXPECT_NE(loadError(path).find("holds a map of submaps"), std::string::npos) << loadError(path);

    const std::vector<char> bytes = bytesOf(path);
    auto expectRefused = [&](std::vector<char> b, const std::string& reason) {
        writeBytes(bad, b);
        const std::string error = submapLoadError(bad);
        EXPECT_NE(error.find(reason), std::string::npos) << "expected '" << reason << "', got '" << error << "'";
    };
    for (std::size_t cut : {std::size_t(20), std::size_t(400), bytes.size() / 2, bytes.size() - 4})
        expectRefused(std::vector<char>(bytes.begin(), bytes.begin() + std::ptrdiff_t(cut)), "truncated");
    std::vector<char> b = bytes;
    b[60] ^= 0x01;
    expectRefused(b, "checksum of the submaps' header does not match");
    b = bytes;
    b.push_back('!');
    expectRefused(b, "bytes after the end marker");
    b = bytes;
    b[bytes.size() - 1] = 'X';
    expectRefused(b, "no end marker after the submaps");

    SubmapMapInfo wrong = info;
    wrong.edges[0].to = 2;
    writeSubmapMap(bad, scene, wrong);
    EXPECT_NE(submapLoadError(bad).find("edge 0 joins submaps 0 and 2"), std::string::npos) << submapLoadError(bad);
    wrong = info;
    wrong.parent[1] = 1;
    writeSubmapMap(bad, scene, wrong);
    EXPECT_NE(submapLoadError(bad).find("submap 1 starts from submap 1"), std::string::npos);
    wrong = info;
    wrong.edges[0].sigma_rotation_rad = 0.f;
    writeSubmapMap(bad, scene, wrong);
    EXPECT_NE(submapLoadError(bad).find("uncertainty is not positive"), std::string::npos);
}

// The main engine: a run saved half way and continued from the file tracks and fuses on; on each device.
class MapFileEngineTest : public ::testing::TestWithParam<Device> {
protected:
    void SetUp() override { VF_SKIP_IF_UNAVAILABLE(GetParam()); }
};

TEST_P(MapFileEngineTest, ARunContinuedFromItsMapTracksOn) {
    const test::ScratchDir scratch;
    MainEngineSettings s;
    s.device = GetParam();
    s.voxel_type = VoxelType::SRgb;
    s.scene = test::centimetreSceneParams();
    const Intrinsics intr = test::kinectIntrinsics(160, 120);
    RGBDCalib calib;
    calib.depth = calib.rgb = intr;
    calib.disparity = DisparityCalib::affine(0.001f);
    const synth::SyntheticScene world = synth::SyntheticScene::boxAndSphere();
    auto pose = [](int k) { return test::lookAt({1.0f + 0.01f * k, -0.8f + 0.02f * k, 0.7f}, {0.3f, 0.f, 0.1f}); };
    const std::string path = scratch.file(std::string("engine_") + deviceName(GetParam()) + ".vfm");

    auto first = MainEngine::create(s, calib);
    for (int k = 0; k < 8; ++k)
        first->processFrame(test::toRgbdFrame(test::renderView(world, intr, pose(k)), k), nullptr);
    first->saveMap(path);
    Mesh saved_mesh;
    first->extractMesh(saved_mesh);

    const MainEngineSettings loading = settingsForMap(readMapFileInfo(path), s);
    EXPECT_EQ(loading.hash.max_bucket_count, s.hash.max_bucket_count) << "the loaded table grows as the engine's";
    EXPECT_EQ(loading.hash.bucket_count, s.hash.bucket_count) << "8 small frames: the table has not grown";
    auto second = MainEngine::create(loading, calib);
    second->loadMap(path);
    Mesh loaded_mesh;
    second->extractMesh(loaded_mesh);
    EXPECT_EQ(saved_mesh.triangles.size(), loaded_mesh.triangles.size());
    // Tracking resumes at the saved pose: the next frames track against the loaded map.
    for (int k = 8; k < 14; ++k) {
        const FrameResult r =
            second->processFrame(test::toRgbdFrame(test::renderView(world, intr, pose(k)), k), nullptr);
        EXPECT_TRUE(r.fused) << "frame " << k;
        // The world is the first frame's camera: the truth is pose(0)^-1 * pose(k).
        const Mat4f truth = rigidInverse(pose(0)) * pose(k);
        EXPECT_LT(length(r.T_world_camera.translation() - truth.translation()), 0.005f) << "frame " << k;
    }
}

INSTANTIATE_TEST_SUITE_P(Devices, MapFileEngineTest, test::kAllDevices, test::DeviceName());

}  // namespace
}  // namespace voxfuse
