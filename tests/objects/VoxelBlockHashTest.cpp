// The voxel block hash as a table: hashing, insertion, lookup, removal and growth, checked against a
// std::map model with a tiny bucket count that forces long excess-list chains.

#include <gtest/gtest.h>

#include <algorithm>
#include <map>
#include <random>
#include <set>
#include <tuple>
#include <vector>

#include "voxfuse/core/Error.h"
#include "voxfuse/objects/Scene.h"
#include "voxfuse/objects/VoxelBlockHash.h"
#include "voxfuse/objects/Voxel.h"
#include "voxfuse/shared/VoxelAccess.h"

namespace voxfuse {
namespace {

using Key = std::tuple<int, int, int>;
Key key(Vec3i b) { return {b.x, b.y, b.z}; }
Vec3i blockOf(const Key& k) { return {std::get<0>(k), std::get<1>(k), std::get<2>(k)}; }

using HashScene = Scene<VoxelF, VoxelBlockHash>;

HashScene makeScene(int buckets, int per_bucket, int excess, int max_blocks, int growth = 4096) {
    VoxelBlockHashSettings s;
    s.bucket_count = buckets;
    s.entries_per_bucket = per_bucket;
    s.excess_entry_count = excess;
    s.max_block_count = max_blocks;
    s.blocks_per_growth = growth;
    return HashScene(SceneParams(), VoxelBlockHash(s), Device::CPU);
}

// A value that identifies a block, written into its first voxel to check that entries keep pointing at
// the right voxel block when other entries move.
float tagOf(Vec3i b) { return float(b.x * 10000 + b.y * 100 + b.z) * 1e-5f; }

// Walks the whole table and checks every structural invariant against the model.
void expectConsistent(const HashScene& scene, const std::map<Key, float>& model) {
    const VoxelBlockHash& hash = scene.index();
    const VoxelBlockHash::Data h = hash.data();
    std::set<int> ptrs, reached_excess;
    int stored = 0;
    for (int bucket = 0; bucket < h.bucket_count; ++bucket) {
        const int first = bucket * h.entries_per_bucket;
        bool bucket_full = true;
        for (int k = 0; k < h.entries_per_bucket; ++k) {
            const HashEntry& e = h.entries[first + k];
            if (e.ptr == kEntryFree) {
                bucket_full = false;
                continue;
            }
            EXPECT_EQ(hashBucket({e.pos.x, e.pos.y, e.pos.z}, h.bucket_count), bucket);
            EXPECT_TRUE(ptrs.insert(e.ptr).second) << "voxel block " << e.ptr << " used twice";
            ++stored;
        }
        for (int k = 0; k + 1 < h.entries_per_bucket; ++k)
            EXPECT_EQ(h.entries[first + k].next, kEndOfChain) << "only the last entry links";
        const int head = h.entries[first + h.entries_per_bucket - 1].next;
        if (head != kEndOfChain) {
            EXPECT_TRUE(bucket_full) << "bucket " << bucket << " has a chain but a free entry";
        }
        for (int next = head; next != kEndOfChain; next = h.entries[h.ordered_entry_count + next].next) {
            ASSERT_TRUE(next >= 0 && next < h.excess_entry_count);
            ASSERT_TRUE(reached_excess.insert(next).second)
                << "excess entry " << next << " reached twice (loop or shared)";
            const HashEntry& e = h.entries[h.ordered_entry_count + next];
            ASSERT_GE(e.ptr, 0);
            EXPECT_EQ(hashBucket({e.pos.x, e.pos.y, e.pos.z}, h.bucket_count), bucket);
            EXPECT_TRUE(ptrs.insert(e.ptr).second);
            ++stored;
        }
    }
    for (int i = 0; i < h.excess_entry_count; ++i)
        EXPECT_TRUE(reached_excess.count(i) || h.entries[h.ordered_entry_count + i].ptr == kEntryFree)
            << "unreachable excess entry in use";
    EXPECT_EQ(stored, int(model.size()));
    EXPECT_EQ(hash.blocksInUse(), int(model.size()));
    EXPECT_EQ(hash.stats().blocks_allocated, int(model.size()));
    EXPECT_EQ(hash.freeExcessEntries(), h.excess_entry_count - int(reached_excess.size()));
    for (int p : ptrs) EXPECT_LT(p, hash.blockCapacity());

    // Every model block is found, through the host API and through readVoxel, with its own voxels.
    for (const auto& [k, tag] : model) {
        const Vec3i b = blockOf(k);
        ASSERT_GE(hash.findEntry(b), 0);
        bool found;
        const VoxelF v = readVoxel(scene.voxels().host(), h, b * kBlockSide, found);
        ASSERT_TRUE(found);
        EXPECT_EQ(v.sdf, tag);
    }
}

class VoxelBlockHashModelTest : public ::testing::TestWithParam<int> {};

// Random inserts and removals over a small box of block positions, four buckets: chains of hundreds.
TEST_P(VoxelBlockHashModelTest, RandomInsertFindRemoveMatchesAMap) {
    const int per_bucket = GetParam();
    HashScene scene = makeScene(4, per_bucket, 700, 1000, 64);
    VoxelBlockHash& hash = scene.index();
    std::map<Key, float> model;
    std::mt19937 rng(1234 + per_bucket);
    std::uniform_int_distribution<int> coord(-5, 5);  // 1331 positions, some negative
    std::uniform_int_distribution<int> op(0, 99);
    int refusals = 0;

    for (int step = 0; step < 6000; ++step) {
        const Vec3i b{coord(rng), coord(rng), coord(rng)};
        // Phases: mostly inserting, then mostly removing, then mixed.
        const int insert_percent = step < 2000 ? 80 : step < 4000 ? 30 : 55;
        if (op(rng) < insert_percent) {
            int entry = -1;
            VoxelBlockHash::InsertResult r = hash.insert(b, &entry);
            if (r == VoxelBlockHash::InsertResult::NoVoxelBlock && hash.canGrow()) {
                scene.reserveVoxelBlocks(hash.blocksInUse() + 1);
                r = hash.insert(b, &entry);
            }
            if (model.count(key(b))) {
                EXPECT_EQ(r, VoxelBlockHash::InsertResult::AlreadyPresent);
            } else if (r == VoxelBlockHash::InsertResult::Inserted) {
                model[key(b)] = tagOf(b);
                scene.voxels().host()[hash.entry(entry).ptr * kBlockVoxelCount] = VoxelF{tagOf(b), 1};
            } else {
                ++refusals;
                // Only a full table may refuse, and it must say which capacity ran out.
                const bool no_excess = hash.freeExcessEntries() == 0;
                const bool no_blocks = hash.freeBlocks() == 0 && !hash.canGrow();
                EXPECT_TRUE((r == VoxelBlockHash::InsertResult::NoHashEntry && no_excess) ||
                            (r == VoxelBlockHash::InsertResult::NoVoxelBlock && no_blocks))
                    << "step " << step;
            }
        } else {
            const int removed = hash.removeBlocks({b});
            EXPECT_EQ(removed, int(model.erase(key(b)))) << "step " << step;
        }
        EXPECT_EQ(hash.findEntry(b) >= 0, model.count(key(b)) == 1) << "step " << step;
        if (step % 500 == 499) {
            SCOPED_TRACE("step " + std::to_string(step));
            expectConsistent(scene, model);
        }
    }
    EXPECT_GT(hash.stats().blocks_removed_total, 1000);
    EXPECT_GT(refusals, 50) << "the excess list must have filled up at times";
}

INSTANTIATE_TEST_SUITE_P(EntriesPerBucket, VoxelBlockHashModelTest, ::testing::Values(1, 2));

TEST(VoxelBlockHashTest, HashIsTheReportsFormulaModuloTheBucketCount) {
    for (const Vec3i b : {Vec3i{0, 0, 0}, Vec3i{1, 2, 3}, Vec3i{-1, -7, 12}, Vec3i{32767, -32767, 5}}) {
        const long long h =
            (((long long)b.x * 73856093) ^ ((long long)b.y * 19349669) ^ ((long long)b.z * 83492791)) & 0xffffffffLL;
        EXPECT_EQ(hashBucket(b, 0x100000), int(h % 0x100000));
        EXPECT_EQ(hashBucket(b, 1000), int(h % 1000));
        EXPECT_EQ(hashBucket(b, 4), int(h % 4));
    }
}

TEST(VoxelBlockHashTest, VoxelsMapToBlocksRoundingDown) {
    EXPECT_EQ(blockOfVoxel({-1, -8, -9}), (Vec3i{-1, -1, -2}));
    EXPECT_EQ(blockOfVoxel({7, 8, 0}), (Vec3i{0, 1, 0}));
    EXPECT_EQ(voxelIndexInBlock({-1, -1, -1}), 511);
    EXPECT_EQ(voxelIndexInBlock({9, 2, 17}), 1 + 2 * 8 + 1 * 64);
}

TEST(VoxelBlockHashTest, RemovingABucketEntryMovesItsChainHeadIntoTheBucket) {
    HashScene scene = makeScene(1, 1, 4, 10);
    scene.reserveVoxelBlocks(10);
    VoxelBlockHash& hash = scene.index();
    const Vec3i a{1, 0, 0}, b{2, 0, 0}, c{3, 0, 0};
    for (const Vec3i& x : {a, b, c}) ASSERT_EQ(hash.insert(x), VoxelBlockHash::InsertResult::Inserted);
    ASSERT_EQ(hash.entry(0).pos.x, 1);
    const int ptr_b = hash.entry(hash.findEntry(b)).ptr;
    EXPECT_EQ(hash.freeExcessEntries(), 2);

    ASSERT_EQ(hash.removeBlocks({a}), 1);
    EXPECT_EQ(hash.entry(0).pos.x, 2) << "b, the chain head, moves into the bucket";
    EXPECT_EQ(hash.entry(0).ptr, ptr_b) << "and keeps its voxel block";
    EXPECT_EQ(hash.findEntry(a), -1);
    EXPECT_GE(hash.findEntry(c), 0);
    EXPECT_EQ(hash.freeExcessEntries(), 3);

    ASSERT_EQ(hash.removeBlocks({c}), 1);  // an excess entry: unlinked
    EXPECT_EQ(hash.entry(0).next, kEndOfChain);
    EXPECT_EQ(hash.freeExcessEntries(), 4);
    EXPECT_EQ(hash.blocksInUse(), 1);
}

TEST(VoxelBlockHashTest, FullTableAndFullBlockArrayAreReportedNotCrashed) {
    HashScene scene = makeScene(2, 2, 3, 100);
    scene.reserveVoxelBlocks(100);
    VoxelBlockHash& hash = scene.index();
    int inserted = 0, refused = 0;
    for (int x = 0; x < 50; ++x) {
        const VoxelBlockHash::InsertResult r = hash.insert({x, 0, 0});
        inserted += r == VoxelBlockHash::InsertResult::Inserted;
        refused += r == VoxelBlockHash::InsertResult::NoHashEntry;
    }
    EXPECT_EQ(inserted, 2 * 2 + 3);
    EXPECT_EQ(refused, 50 - 7);

    HashScene small = makeScene(64, 1, 64, 5, 2);
    for (int x = 0; x < 20; ++x) {
        if (small.index().freeBlocks() == 0) small.reserveVoxelBlocks(small.index().blocksInUse() + 1);
        const VoxelBlockHash::InsertResult r = small.index().insert({x, 1, 2});
        EXPECT_EQ(r, x < 5 ? VoxelBlockHash::InsertResult::Inserted : VoxelBlockHash::InsertResult::NoVoxelBlock) << x;
    }
    EXPECT_EQ(small.index().blockCapacity(), 5);
    EXPECT_EQ(small.voxels().size(), 5u * kBlockVoxelCount);
    EXPECT_EQ(small.index().insert({1 << 16, 0, 0}), VoxelBlockHash::InsertResult::OutOfRange);
}

TEST(VoxelBlockHashTest, AGrowingTableKeepsItsBlocksStoredCopiesAndVisibleList) {
    VoxelBlockHashSettings s;
    s.bucket_count = 16;
    s.excess_entry_count = 4;
    s.max_bucket_count = 64;
    s.max_block_count = 100;
    s.blocks_per_growth = 64;
    HashScene scene(SceneParams(), VoxelBlockHash(s), Device::CPU);
    VoxelBlockHash& hash = scene.index();
    scene.reserveVoxelBlocks(10);
    std::vector<Vec3i> blocks;
    for (int x = 0; x < 7; ++x) blocks.push_back({x, 1, -2});
    std::vector<int> ptrs;
    for (const Vec3i& b : blocks) {
        int entry = -1;
        ASSERT_EQ(hash.insert(b, &entry), VoxelBlockHash::InsertResult::Inserted);
        ptrs.push_back(hash.entry(entry).ptr);
    }
    ASSERT_EQ(hash.insertStored({500, 0, 0}, 5), VoxelBlockHash::InsertResult::Inserted);
    EXPECT_TRUE(hash.wantsMoreBuckets()) << "8 blocks in 16 buckets: past 0.4";
    hash.setVisibleEntries({hash.findEntry(blocks[1]), hash.findEntry(blocks[4])}, Mat4f::identity(), Intrinsics());

    hash.growBuckets();
    EXPECT_EQ(hash.settings().bucket_count, 32);
    EXPECT_EQ(hash.settings().excess_entry_count, 8);
    EXPECT_EQ(hash.entryCount(), 40);
    EXPECT_FALSE(hash.wantsMoreBuckets());
    for (std::size_t k = 0; k < blocks.size(); ++k) {
        const int e = hash.findEntry(blocks[k]);
        ASSERT_GE(e, 0) << k;
        EXPECT_EQ(hash.entry(e).ptr, ptrs[k]) << "a block keeps its voxels";
    }
    const int stored = hash.findEntry({500, 0, 0});
    ASSERT_GE(stored, 0);
    EXPECT_EQ(hash.entry(stored).ptr, kEntrySwappedOut);
    EXPECT_EQ(hash.storedSlots()[stored], 5);
    EXPECT_EQ(hash.blocksInUse(), 7);
    EXPECT_EQ(hash.storedBlocks(), 1);
    std::vector<int> visible{hash.findEntry(blocks[1]), hash.findEntry(blocks[4])};
    std::sort(visible.begin(), visible.end());
    ASSERT_EQ(hash.visibleCount(), 2);
    EXPECT_EQ(std::vector<int>(hash.visibleEntries(), hash.visibleEntries() + 2), visible) << "in entry order";
    for (int e : visible) EXPECT_EQ(hash.entryVisibility()[e], kEntryVisible);
    int marked = 0;
    for (int e = 0; e < hash.entryCount(); ++e) marked += hash.entryVisibility()[e] == kEntryVisible ? 1 : 0;
    EXPECT_EQ(marked, 2);

    // New blocks go into the grown table; it grows no further than its maximum.
    EXPECT_EQ(hash.insert({3, 3, 3}), VoxelBlockHash::InsertResult::Inserted);
    hash.growBuckets();
    hash.growBuckets();
    EXPECT_EQ(hash.settings().bucket_count, 64);
    EXPECT_EQ(hash.settings().excess_entry_count, 16);
    EXPECT_FALSE(hash.wantsMoreBuckets());
    for (const Vec3i& b : blocks) EXPECT_GE(hash.findEntry(b), 0);
    EXPECT_GE(hash.findEntry({3, 3, 3}), 0);
    const VoxelBlockHashSettings largest = VoxelBlockHash::fullyGrown(s);
    EXPECT_EQ(largest.bucket_count, 64);
    EXPECT_EQ(largest.excess_entry_count, 16);
}

TEST(VoxelBlockHashTest, VoxelArrayGrowsInChunksAndKeepsItsContents) {
    HashScene scene = makeScene(1024, 1, 1024, 100, 8);
    EXPECT_EQ(scene.voxels().size(), 0u) << "an empty map holds no voxels";
    scene.reserveVoxelBlocks(3);
    EXPECT_EQ(scene.index().blockCapacity(), 8);
    for (std::size_t i = 0; i < scene.voxels().size(); ++i) scene.voxels().host()[i] = VoxelF{float(i), 7};
    scene.reserveVoxelBlocks(9);
    EXPECT_EQ(scene.index().blockCapacity(), 16);
    ASSERT_EQ(scene.voxels().size(), 16u * kBlockVoxelCount);
    for (std::size_t i = 0; i < 8u * kBlockVoxelCount; ++i) ASSERT_EQ(scene.voxels().host()[i].sdf, float(i));
    EXPECT_EQ(scene.index().freeBlocks(), 16);
    scene.reserveVoxelBlocks(1000);
    EXPECT_EQ(scene.index().blockCapacity(), 100) << "capped at the maximum";
    EXPECT_FALSE(scene.index().canGrow());
    scene.clearVoxelBlocks();
    EXPECT_EQ(scene.voxels().size(), 0u);
    EXPECT_EQ(scene.index().blocksInUse(), 0);
}

TEST(VoxelBlockHashTest, RemovalKeepsTheVisibleListPointingAtTheSameBlocks) {
    HashScene scene = makeScene(1, 1, 16, 32);
    scene.reserveVoxelBlocks(32);
    VoxelBlockHash& hash = scene.index();
    std::vector<int> entries;
    for (int x = 0; x < 10; ++x) {
        int e;
        ASSERT_EQ(hash.insert({x, 0, 0}, &e), VoxelBlockHash::InsertResult::Inserted);
        entries.push_back(e);
    }
    hash.setVisibleEntries({entries[0], entries[3], entries[7]}, Mat4f::identity(), Intrinsics());
    hash.removeBlocks({{0, 0, 0}, {5, 0, 0}});  // the bucket entry goes: chain entries move
    ASSERT_EQ(hash.visibleCount(), 2);
    EXPECT_EQ(hash.entry(hash.visibleEntries()[0]).pos.x, 3);
    EXPECT_EQ(hash.entry(hash.visibleEntries()[1]).pos.x, 7);
}

// A raycast at half resolution from the listed view sees nothing the list's camera does not: it may use
// the list. Any other camera or pose may not.
TEST(VoxelBlockHashTest, TheVisibleListCoversItsCameraAndItsDownsampledCamerasOnly) {
    HashScene scene = makeScene(1, 1, 16, 32);
    VoxelBlockHash& hash = scene.index();
    const Intrinsics camera{640, 480, 525.f, 525.f, 319.5f, 239.5f};
    Mat4f T_world_camera = Mat4f::identity();
    T_world_camera.m[3] = 0.25f;
    EXPECT_FALSE(hash.visibleListCovers(T_world_camera, camera)) << "no list built yet";
    hash.setVisibleEntries({}, T_world_camera, camera);
    EXPECT_TRUE(hash.visibleListCovers(T_world_camera, camera));
    EXPECT_TRUE(hash.visibleListCovers(T_world_camera, camera.downsampled(2)));
    EXPECT_TRUE(hash.visibleListCovers(T_world_camera, camera.downsampled(4)));
    EXPECT_FALSE(hash.visibleListCovers(Mat4f::identity(), camera)) << "another pose";
    EXPECT_FALSE(hash.visibleListCovers(T_world_camera, camera.resized(1280, 960))) << "a larger image";
    Intrinsics wider = camera.downsampled(2);
    wider.fx *= 0.9f;
    EXPECT_FALSE(hash.visibleListCovers(T_world_camera, wider)) << "a wider field of view";
    Intrinsics shifted = camera;
    shifted.cx += 4.f;
    EXPECT_FALSE(hash.visibleListCovers(T_world_camera, shifted)) << "another principal point";
}

// What create() checks against the machine's memory before allocating is what the index allocates.
TEST(VoxelBlockHashTest, TableBytesFromTheSettingsAreWhatTheIndexAllocates) {
    for (const auto& [buckets, per_bucket, excess, max_blocks] :
         {std::tuple{1, 1, 16, 32}, std::tuple{1 << 12, 2, 1 << 10, 1 << 14}}) {
        VoxelBlockHashSettings s;
        s.bucket_count = buckets;
        s.entries_per_bucket = per_bucket;
        s.excess_entry_count = excess;
        s.max_block_count = max_blocks;
        EXPECT_EQ(VoxelBlockHash::tableBytesFor(s), VoxelBlockHash(s).tableBytes());
    }
}

TEST(VoxelBlockHashTest, RejectsSizesOutOfRange) {
    VoxelBlockHashSettings s;
    s.entries_per_bucket = 3;
    EXPECT_THROW(VoxelBlockHash{s}, ConfigError);
    s = VoxelBlockHashSettings();
    s.bucket_count = 0;
    EXPECT_THROW(VoxelBlockHash{s}, ConfigError);
    s = VoxelBlockHashSettings();
    s.max_block_count = (1 << 22) + 1;
    EXPECT_THROW(VoxelBlockHash{s}, ConfigError);
}

}  // namespace
}  // namespace voxfuse
