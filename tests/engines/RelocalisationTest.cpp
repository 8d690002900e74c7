// Loss and relocalisation in the whole pipeline, on exact synthetic views of the room along the
// synthetic camera path: a jump back to a place seen before is found again at its exact pose, a
// jump to a place never seen stays lost and fuses nothing.

#include <gtest/gtest.h>

#include <algorithm>

#include "DeviceTestSupport.h"
#include "SyntheticViews.h"
#include "TrackingTestSupport.h"
#include "CameraPath.h"
#include "voxfuse/core/EigenInterop.h"
#include "voxfuse/engines/MainEngine.h"

namespace voxfuse {
namespace {

const Intrinsics kCamera = test::kinectIntrinsics(320, 240);

// The pipeline on 1 cm voxels seeing through kCamera.
std::unique_ptr<MainEngine> makeEngine(Device device, VoxelType voxel, const RelocalisationSettings& relocalisation) {
    MainEngineSettings s;
    s.device = device;
    s.voxel_type = voxel;
    s.scene = test::centimetreSceneParams(4.f);
    s.relocalisation = relocalisation;
    RGBDCalib calib;
    calib.depth = calib.rgb = kCamera;
    calib.disparity = DisparityCalib::affine(0.001f);
    return MainEngine::create(s, calib);
}

class RelocalisationTest : public ::testing::TestWithParam<Device> {
protected:
    void SetUp() override {
        VF_SKIP_IF_UNAVAILABLE(GetParam());
        engine_ = makeEngine(RelocalisationSettings());
    }

    std::unique_ptr<MainEngine> makeEngine(const RelocalisationSettings& relocalisation) const {
        return voxfuse::makeEngine(GetParam(), VoxelType::S, relocalisation);
    }

    // The room seen from the synthetic camera path at `path_frame` (30 per second, ~1 cm apart).
    static Mat4f pathPose(int path_frame) { return toMat4f(synth::CameraPath().pose(path_frame).matrix()); }

    FrameResult process(int path_frame) {
        static const synth::SyntheticScene room = synth::SyntheticScene::defaultRoom();
        const Mat4f T_world_camera = pathPose(path_frame);
        if (!have_origin_) {
            T_origin_world_ = rigidInverse(T_world_camera);  // the engine's world is the first camera
            have_origin_ = true;
        }
        truth_.push_back(T_origin_world_ * T_world_camera);
        results_.push_back(engine_->processFrame(
            test::toRgbdFrame(test::renderView(room, kCamera, T_world_camera), int(results_.size())), nullptr));
        return results_.back();
    }

    // The first 2 s of the path, every third frame: 21 frames, 0.6 m along the room's long side.
    void walkTheFirstStretch() {
        for (int f = 0; f <= 60; f += 3) {
            const FrameResult r = process(f);
            ASSERT_EQ(r.status, TrackingStatus::Tracking) << "path frame " << f;
            ASSERT_TRUE(r.fused);
        }
        ASSERT_GT(results_.back().keyframes, 1);
        EXPECT_LT(results_.back().keyframes, 21);
    }

    // Frames with a pose are within `max_m` and `max_deg` of the truth; frames without one were not fused.
    void expectNothingFusedWrongly(float max_m, float max_deg) {
        for (std::size_t i = 0; i < results_.size(); ++i) {
            const FrameResult& r = results_[i];
            if (r.status == TrackingStatus::Lost) {
                EXPECT_FALSE(r.fused) << "frame " << i;
                continue;
            }
            EXPECT_LT(test::translationErrorM(r.T_world_camera, truth_[i]), max_m)
                << "frame " << i << " (" << toString(r.status) << ")";
            EXPECT_LT(test::rotationErrorDeg(r.T_world_camera, truth_[i]), max_deg) << "frame " << i;
        }
    }

    std::unique_ptr<MainEngine> engine_;
    std::vector<FrameResult> results_;
    std::vector<Mat4f> truth_;
    bool have_origin_ = false;
    Mat4f T_origin_world_ = Mat4f::identity();
};

// The index (from `from`) of the first relocalised frame, or -1.
int firstRelocalised(const std::vector<FrameResult>& results, std::size_t from) {
    for (std::size_t i = from; i < results.size(); ++i)
        if (results[i].status == TrackingStatus::Relocalised) return int(i);
    return -1;
}

TEST_P(RelocalisationTest, LostAtAPlaceNeverSeenAndFoundAgainAtASeenOne) {
    walkTheFirstStretch();
    const int blocks_before = engine_->allocationStats().blocks_allocated;

    // The far side of the room, looking at the wall that was behind the camera: nothing to find.
    const std::size_t unseen = results_.size();
    for (int f = 480; f <= 492; f += 3) process(f);
    for (std::size_t i = unseen; i < results_.size(); ++i) {
        EXPECT_EQ(results_[i].status, TrackingStatus::Lost) << "frame " << i;
        EXPECT_FALSE(results_[i].fused);
        EXPECT_TRUE(results_[i].relocalisation_tried);
    }
    EXPECT_EQ(engine_->allocationStats().blocks_allocated, blocks_before) << "a lost frame allocates nothing";

    // Back to 0.4 m behind where tracking was lost, between two frames seen on the way (a view never
    // rendered before): found again from the keyframes, at the exact pose, and tracked on from there.
    const std::size_t back = results_.size();
    for (int f = 22; f <= 34; f += 3) process(f);
    const int found = firstRelocalised(results_, back);
    ASSERT_GE(found, 0) << "never relocalised";
    EXPECT_LE(found - int(back), 2) << "frames back at a seen place before the camera was found";
    const FrameResult& r = results_[std::size_t(found)];
    std::printf("[ reloc    ] found %d frames after coming back: error %.2f mm %.3f deg, inliers %.3f\n",
                found - int(back), 1000 * test::translationErrorM(r.T_world_camera, truth_[std::size_t(found)]),
                test::rotationErrorDeg(r.T_world_camera, truth_[std::size_t(found)]), r.tracking.inlier_ratio);
    EXPECT_TRUE(r.fused);
    for (std::size_t i = std::size_t(found) + 1; i < results_.size(); ++i)
        EXPECT_EQ(results_[i].status, TrackingStatus::Tracking)
            << "frame " << i << ": tracking goes on from the found pose";
    expectNothingFusedWrongly(0.005f, 0.5f);
}

// The same way back, but at a speed limit the jump breaks: the frames come 1/30 s apart (no
// timestamps), so within the five frames back the camera could have moved 0.1-0.17 m at 0.5 m/s, and
// the seen place is 0.3-0.4 m from where tracking was lost. The keyframes there are no candidates,
// and a nearer one that the refinement slides to the seen place is not taken either: the frames stay
// lost and nothing is fused.
TEST_P(RelocalisationTest, AKeyframeFartherThanTheCameraCouldHaveMovedIsNoCandidate) {
    RelocalisationSettings slow;
    slow.max_speed_m_per_s = 0.5f;
    engine_ = makeEngine(slow);
    walkTheFirstStretch();
    for (int f = 480; f <= 492; f += 3) process(f);
    const std::size_t back = results_.size();
    for (int f = 22; f <= 34; f += 3) process(f);
    for (std::size_t i = back; i < results_.size(); ++i) {
        EXPECT_EQ(results_[i].status, TrackingStatus::Lost) << "frame " << i;
        EXPECT_TRUE(results_[i].relocalisation_tried);
    }
    expectNothingFusedWrongly(0.005f, 0.5f);
}

INSTANTIATE_TEST_SUITE_P(Devices, RelocalisationTest, test::kAllDevices, test::DeviceName());

// A room whose shape is the same turned half about its vertical axis (x, y -> -x, -y), and whose two
// halves are coloured differently: a camera turned so, at the other end, sees the same depth and other
// colours. Pure albedo (ambient light only), so that the colours are the textures.
synth::SyntheticScene halfTurnRoom() {
    using V = Eigen::Vector3f;
    const auto texture = synth::makeTexture;
    synth::SyntheticScene room;
    room.addRectangle(V(0, 0, 0), V(0, 0, 1), 2.f, 1.5f,
                      texture(synth::TextureKind::Noise, V(0.8f, 0.7f, 0.6f), V(0.3f, 0.25f, 0.2f), 0.15f, 1));
    room.addRectangle(V(0, 0, 2.5f), V(0, 0, -1), 2.f, 1.5f,
                      texture(synth::TextureKind::Noise, V(0.9f, 0.9f, 0.9f), V(0.6f, 0.6f, 0.6f), 0.3f, 2));
    for (const float side : {1.f, -1.f}) {
        const std::uint32_t seed = side > 0 ? 10 : 20;
        const V tint = side > 0 ? V(0.9f, 0.4f, 0.3f) : V(0.3f, 0.5f, 0.9f);
        room.addRectangle(V(2.f * side, 0, 1.25f), V(-side, 0, 0), 1.5f, 1.25f,
                          texture(synth::TextureKind::Noise, tint, V(0.2f, 0.2f, 0.2f), 0.12f, seed));
        room.addRectangle(
            V(0, 1.5f * side, 1.25f), V(0, -side, 0), 2.f, 1.25f,
            texture(synth::TextureKind::Stripes, tint, V(0.9f, 0.9f, 0.8f), 0.1f + 0.05f * side, seed + 1));
        room.addBox(
            V(1.3f * side, 0.4f * side, 0.3f), Eigen::Quaternionf::Identity(), V(0.3f, 0.25f, 0.3f),
            texture(synth::TextureKind::Checker, tint, V(0.95f, 0.95f, 0.9f), side > 0 ? 0.08f : 0.13f, seed + 2));
        room.addSphere(V(1.5f * side, -0.8f * side, 0.9f), 0.25f,
                       texture(synth::TextureKind::Noise, V(0.2f, 0.8f, 0.3f), tint, 0.05f, seed + 3));
    }
    room.setAmbient(1.f);
    return room;
}

// Turned half about the room's vertical axis.
Mat4f halfTurn(const Mat4f& T_world_camera) {
    Eigen::Matrix4f turn = Eigen::Matrix4f::Identity();
    turn(0, 0) = turn(1, 1) = -1.f;
    return toMat4f(turn * toEigen(T_world_camera));
}

class ColorRelocalisationTest : public ::testing::TestWithParam<Device> {
protected:
    void SetUp() override { VF_SKIP_IF_UNAVAILABLE(GetParam()); }

    // Tracks 8 frames looking at the +x end, loses the camera behind a covered lens, then shows the
    // same view turned half (the -x end), then the +x end again. The statuses of the last 8 frames.
    std::vector<TrackingStatus> run(const RelocalisationSettings& relocalisation) {
        auto engine = makeEngine(GetParam(), VoxelType::SRgb, relocalisation);
        static const synth::SyntheticScene room = halfTurnRoom();
        const Mat4f start = test::lookAt({0.2f, 0.1f, 1.4f}, {2.f, 0.2f, 0.8f});
        const Mat4f T_origin_world = rigidInverse(start);  // the engine's world is the first camera
        int index = 0;
        // The frame seen from T_world_camera; the pose it is given, if any, is checked in the engine's world.
        const auto process = [&](const Mat4f& T_world_camera, bool covered = false) {
            View view = test::renderView(room, kCamera, T_world_camera);
            if (covered) std::fill(view.depth.host(), view.depth.host() + view.depth.pixelCount(), 0.f);
            const FrameResult r = engine->processFrame(test::toRgbdFrame(view, index++), nullptr);
            error_m_ = test::translationErrorM(r.T_world_camera, T_origin_world * T_world_camera);
            return r;
        };
        for (int i = 0; i < 8; ++i) {
            const FrameResult r =
                process(test::moveInCamera(start, {0.f, 1.f, 0.f}, 0.5f * float(i), {0.01f * float(i), 0.f, 0.f}));
            EXPECT_EQ(r.status, TrackingStatus::Tracking) << "frame " << i;
        }
        for (int i = 0; i < 3; ++i) EXPECT_EQ(process(start, true).status, TrackingStatus::Lost) << "a covered lens";
        std::vector<TrackingStatus> statuses;
        for (int i = 0; i < 4; ++i) {
            const Mat4f T_world_camera =
                halfTurn(test::moveInCamera(start, {0.f, 1.f, 0.f}, 0.5f * float(i), {0.01f * float(i), 0.f, 0.f}));
            const FrameResult r = process(T_world_camera);
            statuses.push_back(r.status);
            if (r.status != TrackingStatus::Lost) {
                EXPECT_GT(error_m_, 0.3f) << "taken for the other end";
            }
        }
        for (int i = 0; i < 4; ++i) {
            const Mat4f T_world_camera = test::moveInCamera(start, {0.f, 1.f, 0.f}, 2.f + 0.5f * float(i),
                                                            {0.04f + 0.01f * float(i), 0.f, 0.01f});
            const FrameResult r = process(T_world_camera);
            statuses.push_back(r.status);
            if (r.status != TrackingStatus::Lost) {
                EXPECT_LT(error_m_, 0.005f);
            }
        }
        return statuses;
    }

    float error_m_ = 0.f;  // of the last frame's pose
};

// Depth alone takes the other end for the seen one (the first frame there is "found" at the pose the
// camera was lost at); the colours do not agree, so with the colour test the frames there stay lost,
// and the camera is found on coming back.
TEST_P(ColorRelocalisationTest, APlaceShapedLikeASeenOneButColoredOtherwiseIsNotTakenForIt) {
    RelocalisationSettings depth_only;
    depth_only.min_color_correlation = -1.f;
    const std::vector<TrackingStatus> fooled = run(depth_only);
    EXPECT_NE(std::find(fooled.begin(), fooled.begin() + 4, TrackingStatus::Relocalised), fooled.begin() + 4)
        << "the scene no longer fools depth alone: the test shows nothing";

    const std::vector<TrackingStatus> statuses = run(RelocalisationSettings());
    for (int i = 0; i < 4; ++i)
        EXPECT_EQ(statuses[std::size_t(i)], TrackingStatus::Lost) << "frame " << i << " at the other end";
    EXPECT_EQ(statuses[4], TrackingStatus::Relocalised) << "back at the seen end";
    for (int i = 5; i < 8; ++i) EXPECT_EQ(statuses[std::size_t(i)], TrackingStatus::Tracking);
}

INSTANTIATE_TEST_SUITE_P(Devices, ColorRelocalisationTest, test::kAllDevices, test::DeviceName());

TEST(RelocalisationSettingsTest, OffKeepsNoKeyframesAndNeverRelocalises) {
    RelocalisationSettings off;
    off.enabled = false;
    auto engine = makeEngine(Device::CPU, VoxelType::S, off);
    const synth::SyntheticScene room = synth::SyntheticScene::defaultRoom();
    for (int f : {0, 3, 6, 480}) {
        const FrameResult r = engine->processFrame(
            test::toRgbdFrame(test::renderView(room, kCamera, toMat4f(synth::CameraPath().pose(f).matrix())), f),
            nullptr);
        EXPECT_EQ(r.keyframes, 0);
        EXPECT_FALSE(r.relocalisation_tried);
        EXPECT_NE(r.status, TrackingStatus::Relocalised);
        for (const StageTime& st : r.stages) EXPECT_STRNE(st.stage, "keyframes");
    }
}

}  // namespace
}  // namespace voxfuse
