// The whole per-frame pipeline on synthetic frames with exact poses, for every voxel type and device.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <memory>
#include <tuple>
#include <vector>

#include "DeviceTestSupport.h"
#include "SyntheticViews.h"
#include "voxfuse/core/Error.h"
#include "voxfuse/engines/MainEngine.h"
#include "voxfuse/objects/Mesh.h"
#include "voxfuse/objects/VoxelBlockHash.h"

namespace voxfuse {
namespace {

class MainEngineVoxelTest : public ::testing::TestWithParam<std::tuple<Device, VoxelType>> {
protected:
    void SetUp() override { VF_SKIP_IF_UNAVAILABLE(std::get<0>(GetParam())); }

    // 1 cm voxels on the parameter's device and voxel type; a dense array holding the box and sphere.
    MainEngineSettings settings() const {
        MainEngineSettings s;
        s.device = std::get<0>(GetParam());
        s.voxel_type = std::get<1>(GetParam());
        s.scene.voxel_size_m = 0.01f;
        s.scene.mu_m = 0.04f;
        s.dense_offset = {-80, -80, -10};
        s.dense_size = {160, 160, 100};
        return s;
    }
    static std::unique_ptr<MainEngine> makeEngine(const MainEngineSettings& s) {
        RGBDCalib calib;
        calib.depth = calib.rgb = kCamera;
        calib.disparity = DisparityCalib::affine(0.001f);
        return MainEngine::create(s, calib);
    }
    // Frame k of a camera moving past the box and sphere.
    static Mat4f pathPose(int k) { return test::lookAt({1.0f + 0.05f * k, -0.8f + 0.1f * k, 0.7f}, {0.3f, 0.f, 0.1f}); }
    static const synth::SyntheticScene& world() {
        static const synth::SyntheticScene scene = synth::SyntheticScene::boxAndSphere();
        return scene;
    }
    // Pixels where some channel of two renders differs by more than 2 levels.
    static int pixelsDiffering(const Image<Vec4u8>& a, const Image<Vec4u8>& b) {
        int differ = 0;
        for (std::size_t i = 0; i < a.pixelCount(); ++i) {
            const Vec4u8 p = a.host()[i], q = b.host()[i];
            differ += std::abs(int(p.x) - int(q.x)) > 2 || std::abs(int(p.y) - int(q.y)) > 2 ||
                      std::abs(int(p.z) - int(q.z)) > 2;
        }
        return differ;
    }
    static inline const Intrinsics kCamera = test::kinectIntrinsics(160, 120);
};

TEST_P(MainEngineVoxelTest, RaycastReproducesTheLastFrameDepth) {
    const Intrinsics intr = kCamera;
    auto engine = makeEngine(settings());
    Mat4f pose;
    View last;
    for (int k = 0; k < 5; ++k) {
        pose = pathPose(k);
        last = test::renderView(world(), intr, pose);
        const FrameResult r = engine->processFrame(test::toRgbdFrame(last, k), &pose);
        EXPECT_TRUE(r.fused);
        ASSERT_EQ(r.stages.size(), 5u);
        EXPECT_GT(r.total_ms, 0.0);
    }
    Image<float> depth;
    raycastDepth(engine->renderState(), depth);
    std::vector<float> errors;
    for (std::size_t i = 0; i < depth.pixelCount(); ++i)
        if (depth.host()[i] > 0.f && last.depth.host()[i] > 0.f)
            errors.push_back(std::fabs(depth.host()[i] - last.depth.host()[i]));
    ASSERT_GT(errors.size(), 0.5 * depth.pixelCount()) << "the floor beyond the small volume is not in the model";
    std::nth_element(errors.begin(), errors.begin() + errors.size() / 2, errors.end());
    EXPECT_LT(errors[errors.size() / 2], 0.003f) << "median raycast depth error (mm depth quantisation, 1 cm voxels)";

    // The render of the last frame starts its rays near the depth that frame fused; a free view from
    // the same pose searches every ray whole. They must show the same model.
    Image<Vec4u8> image, whole;
    engine->renderLast(RenderMode::Color, image);
    EXPECT_EQ(image.size(), intr.size());
    engine->renderFromPose(pose, intr, RenderMode::Color, whole);
    EXPECT_LE(pixelsDiffering(image, whole), int(image.pixelCount() / 200))
        << "pixels where the last frame's render and a whole search disagree";
    engine->renderFromPose(test::lookAt({-0.5f, -1.0f, 1.0f}, {0.3f, 0.f, 0.1f}), intr, RenderMode::Shaded, image);
    int lit = 0;
    for (std::size_t i = 0; i < image.pixelCount(); ++i) lit += image.host()[i].x > 0;
    EXPECT_GT(lit, int(image.pixelCount() / 4)) << "a free viewpoint sees the fused surfaces";
}

// The hash table's growth moves entries, never blocks: a map whose table starts at 16 buckets and
// doubles tracks and fuses bit for bit as one whose table has its final size from the start.
TEST_P(MainEngineVoxelTest, AGrowingHashTableMakesTheMapAFixedOneMakes) {
    MainEngineSettings growing = settings();
    growing.index_type = IndexType::Hash;
    growing.hash.bucket_count = 16;
    growing.hash.excess_entry_count = 2;
    growing.hash.max_bucket_count = 1 << 14;
    MainEngineSettings fixed = growing;
    fixed.hash = VoxelBlockHash::fullyGrown(growing.hash);
    fixed.hash.max_bucket_count = 0;
    auto a = makeEngine(growing), b = makeEngine(fixed);
    for (int k = 0; k < 6; ++k) {
        const Mat4f pose = pathPose(k);
        const RGBDFrame frame = test::toRgbdFrame(test::renderView(world(), kCamera, pose), k);
        const FrameResult ra = a->processFrame(frame, k == 0 ? &pose : nullptr);
        const FrameResult rb = b->processFrame(frame, k == 0 ? &pose : nullptr);
        EXPECT_EQ(0, std::memcmp(ra.T_world_camera.m, rb.T_world_camera.m, sizeof(ra.T_world_camera.m))) << k;
    }
    const AllocationStats sa = a->allocationStats(), sb = b->allocationStats();
    EXPECT_GT(sa.blocks_allocated, 100) << "far more blocks than 16 buckets and 2 excess entries hold";
    EXPECT_EQ(sa.blocks_allocated, sb.blocks_allocated);
    EXPECT_EQ(sa.allocation_failures_total, 0);
    Mesh ma, mb;
    a->extractMesh(ma);
    b->extractMesh(mb);
    ASSERT_GT(ma.vertices.size(), 1000u);
    // The same surface; vertices come in entry order, which the tables do not share.
    const auto sorted = [](std::vector<Vec3f> v) {
        std::sort(v.begin(), v.end(),
                  [](const Vec3f& p, const Vec3f& q) { return std::tie(p.x, p.y, p.z) < std::tie(q.x, q.y, q.z); });
        return v;
    };
    const std::vector<Vec3f> va = sorted(ma.vertices), vb = sorted(mb.vertices);
    ASSERT_EQ(va.size(), vb.size());
    EXPECT_EQ(0, std::memcmp(va.data(), vb.data(), va.size() * sizeof(Vec3f)));
}

// Releasing the frame buffers keeps the map and the pose: the render still shows the map from the
// last pose, and tracking goes on where it was, as closely as an engine that kept them (which
// predicts the motion, where the released one starts from the last pose).
TEST_P(MainEngineVoxelTest, AReleasedEngineTracksOnFromItsMap) {
    MainEngineSettings s = settings();
    s.index_type = IndexType::Hash;
    auto released = makeEngine(s), kept = makeEngine(s);
    for (int k = 0; k < 8; ++k) {
        const Mat4f pose = pathPose(k);
        const RGBDFrame frame = test::toRgbdFrame(test::renderView(world(), kCamera, pose), k);
        const FrameResult a = released->processFrame(frame, k == 0 ? &pose : nullptr);
        const FrameResult b = kept->processFrame(frame, k == 0 ? &pose : nullptr);
        ASSERT_NE(a.quality, TrackingQuality::Failed) << k;
        EXPECT_LT(length(a.T_world_camera.translation() - b.T_world_camera.translation()), 0.001f) << k;
        if (k == 3) {
            released->releaseFrameMemory();
            EXPECT_TRUE(released->view().depth.empty());
            const RenderState& model = released->renderState();  // raycast again, from the last pose
            int surface = 0;
            for (std::size_t i = 0; i < model.points_world.pixelCount(); ++i)
                surface += model.points_world.host()[i].w > 0.f;
            EXPECT_GT(surface, int(kCamera.width * kCamera.height) / 4);
        }
    }
    Mesh ma, mb;
    released->extractMesh(ma);
    kept->extractMesh(mb);
    ASSERT_GT(mb.vertices.size(), 1000u);
    EXPECT_NEAR(double(ma.vertices.size()), double(mb.vertices.size()), 0.02 * double(mb.vertices.size()));
}

// A revisit seen from a pose only roughly known (a few centimetres and degrees off, as a loop's prior
// from drifting odometry) is aligned to the map and accepted; from a prior far off it is refused,
// and the engine's own pose stays either way.
TEST_P(MainEngineVoxelTest, LocateNearAlignsAFrameFromARoughPoseAndRefusesAWrongOne) {
    MainEngineSettings s = settings();
    auto engine = makeEngine(s);
    for (int k = 0; k < 4; ++k) {
        const Mat4f pose = pathPose(k);
        engine->processFrame(test::toRgbdFrame(test::renderView(world(), kCamera, pose), k), &pose);
    }
    const Mat4f engine_pose = engine->trackingState().T_world_camera;
    // A view of frame 2's place, converted by an engine of the same settings.
    auto converter = makeEngine(s);
    const Mat4f truth = pathPose(2);
    converter->processFrame(test::toRgbdFrame(test::renderView(world(), kCamera, truth), 2), &truth);
    const View& view = converter->view();

    Mat4f rough = truth;
    rough.m[3] += 0.02f;  // 2 cm off along x, and turned 3 degrees about the camera's y axis
    const float c = std::cos(3.f * float(M_PI) / 180.f), sn = std::sin(3.f * float(M_PI) / 180.f);
    Mat4f turn = Mat4f::identity();
    turn.m[0] = c;
    turn.m[2] = sn;
    turn.m[8] = -sn;
    turn.m[10] = c;
    rough = rough * turn;
    TrackingState found;
    ASSERT_TRUE(engine->locateNear(view, rough, found));
    EXPECT_LT(length(found.T_world_camera.translation() - truth.translation()), 0.003f);

    Mat4f wrong = truth;
    wrong.m[3] += 0.5f;  // half a metre off: the model seen from there explains nothing of the frame
    TrackingState refused;
    EXPECT_FALSE(engine->locateNear(view, wrong, refused));
    EXPECT_EQ(0, std::memcmp(engine->trackingState().T_world_camera.m, engine_pose.m, sizeof(engine_pose.m)));
}

// After a frame that failed tracking (not fused), the view holds that frame's depth, which says
// nothing about the model's pose: the render of the last fused pose must not start its rays there.
TEST_P(MainEngineVoxelTest, TheLastRenderIgnoresTheDepthOfAFrameNotFused) {
    MainEngineSettings s = settings();
    s.relocalisation.enabled = false;
    auto engine = makeEngine(s);
    Mat4f pose;
    for (int k = 0; k < 3; ++k) {
        pose = pathPose(k);
        ASSERT_TRUE(engine->processFrame(test::toRgbdFrame(test::renderView(world(), kCamera, pose), k), &pose).fused);
    }
    // The same view with every depth 30 cm too far: not trackable, and rays started there would miss
    // every surface.
    View far = test::renderView(world(), kCamera, pose);
    for (std::size_t i = 0; i < far.depth.pixelCount(); ++i)
        far.depth.host()[i] = far.depth.host()[i] > 0.f ? far.depth.host()[i] + 0.3f : 0.f;
    const FrameResult r = engine->processFrame(test::toRgbdFrame(far, 3), nullptr);
    ASSERT_FALSE(r.fused) << "the test needs a frame that is not fused";

    Image<Vec4u8> last, whole;
    engine->renderLast(RenderMode::Shaded, last);
    engine->renderFromPose(pose, kCamera, RenderMode::Shaded, whole);
    int lit = 0;
    for (std::size_t i = 0; i < whole.pixelCount(); ++i) lit += whole.host()[i].x > 0;
    EXPECT_GT(lit, int(last.pixelCount() / 2));
    EXPECT_LE(pixelsDiffering(last, whole), int(last.pixelCount() / 200));
}

INSTANTIATE_TEST_SUITE_P(
    AllVoxelTypes, MainEngineVoxelTest,
    ::testing::Combine(test::kAllDevices, ::testing::Values(VoxelType::S, VoxelType::F, VoxelType::SRgb,
                                                            VoxelType::FRgb, VoxelType::SLabel, VoxelType::SRgbLabel)),
    [](const auto& info) {
        return std::string(deviceName(std::get<0>(info.param))) + "_" + toString(std::get<1>(info.param));
    });

TEST(MainEngineTest, RejectsBadSettingsWithClearErrors) {
    RGBDCalib calib;
    calib.depth = calib.rgb = test::kinectIntrinsics(160, 120);
    MainEngineSettings s;
    s.dense_size = {16, 16, 16};
    s.scene.mu_m = s.scene.voxel_size_m / 2;
    EXPECT_THROW(MainEngine::create(s, calib), ConfigError);
    s.scene.mu_m = 65 * s.scene.voxel_size_m;  // every pixel would allocate a band of 130 voxels
    try {
        MainEngine::create(s, calib);
        ADD_FAILURE() << "a truncation band of 65 voxels was accepted";
    } catch (const ConfigError& e) {
        EXPECT_NE(std::string(e.what()).find("is more than 64 voxels"), std::string::npos) << e.what();
    }
    s.scene.mu_m = 0.02f;
    EXPECT_THROW(MainEngine::create(s, RGBDCalib{}), ConfigError);
    EXPECT_THROW(parseVoxelType("double"), ConfigError);
    auto engine = MainEngine::create(s, calib);
    RGBDFrame frame;
    frame.depth_raw.resize({10, 10});
    const Mat4f pose = Mat4f::identity();
    EXPECT_THROW(engine->processFrame(frame, &pose), IoError) << "depth size disagrees with the calibration";
    // A given pose must be a camera's: a scale or a shear is refused before anything is fused.
    frame.depth_raw.resize({160, 120});
    Mat4f scaled = Mat4f::identity();
    scaled(0, 0) = scaled(1, 1) = scaled(2, 2) = 3.f;
    try {
        engine->processFrame(frame, &scaled);
        ADD_FAILURE() << "a scaled pose was fused";
    } catch (const ConfigError& e) {
        EXPECT_NE(std::string(e.what()).find("no camera pose"), std::string::npos) << e.what();
    }
    Image<Vec4u8> image;
    EXPECT_THROW(engine->renderFromPose(scaled, calib.depth, RenderMode::Shaded, image), ConfigError);
}

}  // namespace
}  // namespace voxfuse
