// The dense and the hash index fuse and raycast the same frames into the same model.
//
// They differ by design in one way only: the hash stores nothing far from surfaces, so a voxel whose
// block is allocated late has missed the free-space (+1) updates that earlier frames gave it in the
// dense grid. The test makes that exact: (1) every update of a frame that carries information
// (SDF below +1) falls into a block of that frame's visible list; (2) the hash equals, bit for bit at
// every voxel of the dense extent, a dense grid that took each frame's updates only inside that
// frame's visible blocks; (3) raycasts agree with the plain dense grid.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <set>
#include <tuple>
#include <vector>

#include "DeviceTestSupport.h"
#include "SyntheticViews.h"
#include "voxfuse/engines/AllocationEngine.h"
#include "voxfuse/engines/IntegrationEngine.h"
#include "voxfuse/engines/RaycastEngine.h"
#include "voxfuse/objects/Voxel.h"
#include "voxfuse/shared/VoxelAccess.h"

namespace voxfuse {
namespace {

using Key = std::tuple<int, int, int>;

using test::sameVoxel;

template <class TVoxel>
class HashDenseParityTest : public ::testing::Test {
protected:
    HashDenseParityTest()
        : dense_(params(), PlainVoxelArray(kOffset, kSize), Device::CPU),
          dense_visible_only_(params(), PlainVoxelArray(kOffset, kSize), Device::CPU),
          hash_(params(), VoxelBlockHash(), Device::CPU) {}

    static SceneParams params() {
        SceneParams p;
        p.voxel_size_m = 0.01f;
        p.mu_m = 0.04f;
        p.view_frustum_max_m = 2.2f;
        return p;
    }

    // Fuses one frame into the three models; returns the informative updates outside the visible list.
    int fuse(const Mat4f& pose) {
        const View view = test::renderView(world_, intr_, pose);
        allocation_->allocate(hash_, view, pose);
        hash_integration_->integrate(hash_, view, pose);
        dense_integration_->integrate(dense_, view, pose);

        std::set<Key> visible;
        const VoxelBlockHash& h = hash_.index();
        for (int k = 0; k < h.visibleCount(); ++k) {
            const HashEntry& e = h.entry(h.visibleEntries()[k]);
            visible.insert({e.pos.x, e.pos.y, e.pos.z});
        }
        const IntegrationFrame frame =
            makeIntegrationFrame(params(), view, pose, view.depth.host(), view.rgb.host(), view.labels.host(),
                                 dense_visible_only_.takeIntegrationNumber());
        int uncovered = 0;
        TVoxel* ref = dense_visible_only_.voxels().host();
        forEachDenseVoxel([&](Vec3i p, std::size_t i) {
            const bool in_visible_block = visible.count({p.x >> 3, p.y >> 3, p.z >> 3}) > 0;
            if (in_visible_block) {
                integrateVoxel(ref[i], p, frame);
                return;
            }
            TVoxel probe = TVoxel::initial();
            const float eta = integrateVoxel(probe, p, frame);
            uncovered += eta >= -params().mu_m && eta < params().mu_m;
        });
        return uncovered;
    }

    template <class F>
    void forEachDenseVoxel(F&& f) {
        std::size_t i = 0;
        for (int z = 0; z < kSize.z; ++z)
            for (int y = 0; y < kSize.y; ++y)
                for (int x = 0; x < kSize.x; ++x, ++i) f(Vec3i{x, y, z} + kOffset, i);
    }

    // Holds the cameras, so that the dense raycast starts its rays where the hash raycast anchors them.
    static constexpr Vec3i kOffset{-60, -90, -10};
    static constexpr Vec3i kSize{190, 170, 100};
    const synth::SyntheticScene world_ = synth::SyntheticScene::boxAndSphere();
    const Intrinsics intr_ = test::kinectIntrinsics(160, 120);
    Scene<TVoxel, PlainVoxelArray> dense_, dense_visible_only_;
    Scene<TVoxel, VoxelBlockHash> hash_;
    std::unique_ptr<AllocationEngine<TVoxel, VoxelBlockHash>> allocation_ =
        makeAllocationEngine<TVoxel, VoxelBlockHash>(Device::CPU);
    std::unique_ptr<IntegrationEngine<TVoxel, VoxelBlockHash>> hash_integration_ =
        cpu::makeIntegrationEngine<TVoxel, VoxelBlockHash>();
    std::unique_ptr<IntegrationEngine<TVoxel, PlainVoxelArray>> dense_integration_ =
        cpu::makeIntegrationEngine<TVoxel, PlainVoxelArray>();
};

using VoxelTypes = ::testing::Types<VoxelS, VoxelF, VoxelSRgb, VoxelFRgb, VoxelSLabel, VoxelSRgbLabel>;
TYPED_TEST_SUITE(HashDenseParityTest, VoxelTypes);

std::vector<Mat4f> cameraPath() {
    std::vector<Mat4f> poses;
    for (int k = 0; k < 5; ++k)
        poses.push_back(test::lookAt({1.0f + 0.05f * k, -0.8f + 0.12f * k, 0.7f - 0.03f * k}, {0.3f, 0.f, 0.1f}));
    return poses;
}

TYPED_TEST(HashDenseParityTest, SameSdfAtEveryVoxelOfTheDenseExtent) {
    using TVoxel = TypeParam;
    for (const Mat4f& pose : cameraPath())
        EXPECT_EQ(this->fuse(pose), 0) << "an informative update fell outside the visible blocks";

    const VoxelBlockHash::Data h = this->hash_.index().data();
    const TVoxel* hash_voxels = this->hash_.voxels().host();
    const TVoxel* ref = this->dense_visible_only_.voxels().host();
    const TVoxel* dense = this->dense_.voxels().host();
    int mismatches = 0, informative = 0, late = 0;
    this->forEachDenseVoxel([&](Vec3i p, std::size_t i) {
        bool found;
        const TVoxel hv = readVoxel(hash_voxels, h, p, found);
        if (!sameVoxel(hv, ref[i])) ++mismatches;
        // Against the plain dense grid: where the SDF carries information, the hash has the same value
        // unless the block came late (then the dense one also averaged in earlier +1 observations).
        if (dense[i].w_depth == 0 || TVoxel::sdfToFloat(dense[i].sdf) >= 1.f) return;
        ++informative;
        if (hv.w_depth == dense[i].w_depth)
            EXPECT_EQ(hv.sdf, dense[i].sdf);
        else
            ++late;
    });
    EXPECT_EQ(mismatches, 0);
    EXPECT_GT(informative, 50000);
    EXPECT_LT(late, informative / 50) << "voxels whose block was allocated after they were seen as free space";
}

// Pixels where exactly one of two raycasts hit, and the largest distances between the two hits of a
// pixel (along the surface normal, and in all), over the pixels whose true surface and hits lie well
// inside the dense extent (the hash also holds surfaces beyond it).
struct RaycastComparison {
    int compared = 0, mask_differs = 0;
    float max_normal_distance_m = 0.f, max_distance_m = 0.f;
};

RaycastComparison compareRaycasts(const RenderState& dense, const RenderState& hash, const View& truth,
                                  const Mat4f& pose, const SceneParams& p, Vec3i offset, Vec3i size) {
    RaycastComparison c;
    const float margin = p.mu_m + 2.f * p.voxel_size_m;
    const Vec3f lo = toFloat(offset) * p.voxel_size_m + Vec3f{margin, margin, margin};
    const Vec3f hi = toFloat(offset + size) * p.voxel_size_m - Vec3f{margin, margin, margin};
    auto inside = [&](Vec3f s) {
        return s.x >= lo.x && s.y >= lo.y && s.z >= lo.z && s.x <= hi.x && s.y <= hi.y && s.z <= hi.z;
    };
    for (int y = 0; y < truth.depth.height(); ++y)
        for (int x = 0; x < truth.depth.width(); ++x) {
            const float d = truth.depth.at(x, y);
            const Vec4f a = dense.points_world.at(x, y), b = hash.points_world.at(x, y);
            if (!(d > 0.f) || !inside(transformPoint(pose, truth.calib.depth.unproject(float(x), float(y), d))))
                continue;
            if ((a.w > 0.f && !inside(a.xyz())) || (b.w > 0.f && !inside(b.xyz()))) continue;
            ++c.compared;
            if ((a.w > 0.f) != (b.w > 0.f)) {
                ++c.mask_differs;
                continue;
            }
            if (a.w <= 0.f) continue;
            c.max_distance_m = std::max(c.max_distance_m, length(a.xyz() - b.xyz()));
            c.max_normal_distance_m = std::max(c.max_normal_distance_m,
                                               std::fabs(dot(dense.normals_world.at(x, y).xyz(), a.xyz() - b.xyz())));
        }
    return c;
}

TYPED_TEST(HashDenseParityTest, SameRaycastFromTheLastPoseAndFromANewOne) {
    using TVoxel = TypeParam;
    const std::vector<Mat4f> path = cameraPath();
    for (const Mat4f& pose : path) this->fuse(pose);
    auto dense_raycast = makeRaycastEngine<TVoxel, PlainVoxelArray>(Device::CPU);
    auto hash_raycast = makeRaycastEngine<TVoxel, VoxelBlockHash>(Device::CPU);

    // The tracking raycast (visible list of the last frame) and a free viewpoint (all allocated blocks).
    const Mat4f novel = test::lookAt({1.1f, -0.5f, 0.8f}, {0.2f, 0.05f, 0.15f});
    for (const Mat4f& pose : {path.back(), novel}) {
        RenderState dense_rs, hash_rs;
        dense_raycast->raycast(this->dense_, this->intr_, pose, dense_rs);
        hash_raycast->raycast(this->hash_, this->intr_, pose, hash_rs);
        const View truth = test::renderView(this->world_, this->intr_, pose, false);
        const RaycastComparison c =
            compareRaycasts(dense_rs, hash_rs, truth, pose, this->params(), this->kOffset, this->kSize);
        EXPECT_GT(c.compared, 10000);
        // The hash sees no free space outside its blocks: a ray that enters a block straight into negative
        // values is on the wrong side for it, while the dense grid may have seen free space before.
        EXPECT_LE(c.mask_differs, 5) << "pixels hit by one raycast only";
        const float voxel = this->params().voxel_size_m;
        EXPECT_LT(c.max_normal_distance_m, 0.01f * voxel) << "hits of one pixel off the same surface";
        EXPECT_LT(c.max_distance_m, 0.1f * voxel)
            << "hits of one pixel apart (grazing rays amplify rounding along the surface)";

        Image<Vec4u8> image;
        hash_raycast->render(this->hash_, hash_rs, RenderMode::Color, image);
        EXPECT_EQ(image.size(), this->intr_.size());
    }
}

}  // namespace
}  // namespace voxfuse
