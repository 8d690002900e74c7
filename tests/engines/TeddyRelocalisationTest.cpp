// Loss and relocalisation on real frames: TUM fr3/teddy (motion-capture ground truth) with frames cut
// out, or their depth replaced by zeros (a covered lens).
//
// The recorded camera circles the teddy once and never comes back (12 mm and 0.8 degrees per frame),
// so a 40-frame cut in the recording ends at a view ~0.4 m and 30 degrees on from the last one seen,
// never near a seen view. For a cut that ends where the camera has been, the sequence is played out
// and back: out on the even frames 0, 2, .., 120, back on the odd frames 119, .., 1 (different images
// of the same places, 12 mm from the way out), with 40 frames cut from the way back. A covered lens
// needs no such help: 20 frames on, the camera still sees much of the map.

#include <gtest/gtest.h>

#include <filesystem>

#include "EditedSequence.h"

namespace voxfuse {
namespace {

const std::string& teddyDir() {
    static const std::string dir = std::string(VOXFUSE_SHARED_DATA_DIR) + "/tum_fr3_teddy_200";
    return dir;
}

struct Teddy {
    std::unique_ptr<ImageSource> source;
    std::vector<RGBDFrame> frames;
};

// Read once for all the tests (the runs take frames out of order).
const Teddy& teddy() {
    static const Teddy t = [] {
        Teddy read{openImageSource(teddyDir()), {}};
        read.frames = test::readAllFrames(*read.source);
        return read;
    }();
    return t;
}

#define SKIP_WITHOUT_TEDDY()                               \
    if (!std::filesystem::exists(teddyDir() + "/rgb.txt")) \
    GTEST_SKIP() << "../shared/data not found at " << teddyDir() << ": skipping"

struct TeddyRun {
    std::vector<test::PlayedResult> frames;
    TrajectoryError error;        // over the frames with a pose
    std::vector<float> errors_m;  // per frame, after the ATE alignment; -1 without pose or ground truth
    int lost = 0, attempts = 0, relocalised = 0;
};

// The default pipeline (colour voxels: relocalisation compares colours too) with coarse 1 cm voxels
// (quick, and the ATE is the same as at 5 mm).
TeddyRun play(const std::vector<test::PlayedFrame>& script, const char* name) {
    MainEngineSettings s;
    s.voxel_type = VoxelType::SRgb;
    s.scene.voxel_size_m = 0.01f;
    s.scene.mu_m = 0.04f;
    const Teddy& t = teddy();
    auto engine = MainEngine::create(s, t.source->calib());
    TeddyRun run;
    run.frames = test::play(*engine, t.frames, script);
    run.error = evaluateTrajectory(test::posedTrajectory(run.frames, t.frames), t.source->groundTruth());
    run.errors_m = test::alignedErrorsM(run.frames, run.error);
    for (const test::PlayedResult& f : run.frames) {
        run.lost += f.result.status == TrackingStatus::Lost;
        run.attempts += f.result.relocalisation_tried;
        run.relocalised += f.result.status == TrackingStatus::Relocalised;
    }
    std::printf(
        "[ teddy    ] %s: %zu frames, %d lost, %d relocalisation attempts, %d relocalised; ATE RMSE %.2f mm (max %.2f, "
        "%d poses)\n",
        name, run.frames.size(), run.lost, run.attempts, run.relocalised, 1000 * run.error.ate_rmse_m,
        1000 * run.error.ate_max_m, run.error.pairs);
    return run;
}

// Every frame is fused only with a pose near the truth (lost frames never), and from `from` on the
// camera is found within `within` frames. Returns how many frames after `from` it was found.
int expectRecovered(const TeddyRun& run, std::size_t from, int within) {
    int found_after = -1;
    for (std::size_t i = from; i < run.frames.size() && found_after < 0; ++i)
        if (run.frames[i].result.status != TrackingStatus::Lost) found_after = int(i - from);
    const test::PlayedResult* found = found_after >= 0 ? &run.frames[from + std::size_t(found_after)] : nullptr;
    if (found)
        std::printf(
            "[ teddy    ]   found %d frames after the camera came back (recorded frame %d, %s): inliers %.3f, residual "
            "%.2f mm, "
            "error %.1f mm\n",
            found_after, found->played.frame, toString(found->result.status), found->result.tracking.inlier_ratio,
            1000 * found->result.tracking.residual_m, 1000 * run.errors_m[from + std::size_t(found_after)]);
    EXPECT_GE(found_after, 0) << "never found again";
    EXPECT_LE(found_after, within);
    return found_after;
}

void expectNothingFusedWrongly(const TeddyRun& run) {
    for (std::size_t i = 0; i < run.frames.size(); ++i) {
        const FrameResult& r = run.frames[i].result;
        if (r.status == TrackingStatus::Lost) {
            EXPECT_FALSE(r.fused) << "frame " << i;
        } else if (r.fused && run.errors_m[i] >= 0.f) {
            EXPECT_LT(run.errors_m[i], 0.03f) << "frame " << i << " was fused at a wrong pose";
        }
    }
}

TEST(TeddyRelocalisationTest, FortyFramesCutOnTheWayBackAreFoundAgain) {
    SKIP_WITHOUT_TEDDY();
    std::vector<test::PlayedFrame> script;
    for (int f = 0; f <= 120; f += 2) script.push_back({f, false});
    for (int f = 119; f >= 1; f -= 2) script.push_back({f, false});
    // 40 frames cut from the way back: after recorded frame 101 comes 19, 1 m and 60 degrees back, near the way out's
    // 18 and 20.
    const std::size_t cut = 61 + 10;
    script.erase(script.begin() + std::ptrdiff_t(cut), script.begin() + std::ptrdiff_t(cut + 40));
    const TeddyRun run = play(script, "40 frames cut on the way back");
    expectRecovered(run, cut, 10);
    expectNothingFusedWrongly(run);
    EXPECT_LT(run.error.ate_rmse_m, 0.010);
    EXPECT_GE(run.error.pairs, int(script.size()) - 10 - 4)
        << "frames without a pose: at most the 10 allowed (and 4 without ground truth)";
}

TEST(TeddyRelocalisationTest, TwentyFramesOfACoveredLensAreBridged) {
    SKIP_WITHOUT_TEDDY();
    std::vector<test::PlayedFrame> script;
    for (int f = 40; f < 120; ++f) script.push_back({f, f >= 80 && f < 100});
    const TeddyRun run = play(script, "20 frames of a covered lens");
    for (std::size_t i = 40; i < 60; ++i)
        EXPECT_EQ(run.frames[i].result.status, TrackingStatus::Lost) << "covered frame " << i;
    expectRecovered(run, 60, 10);
    expectNothingFusedWrongly(run);
    EXPECT_LT(run.error.ate_rmse_m, 0.010);
}

// The cut of the issue, in the recording as it is: the camera never comes back near a seen view. The
// tracker cannot bridge 0.4 m and 30 degrees and no keyframe lies near, so the frames stay lost;
// should a better tracker bridge it, they must at least be fused at the right poses.
TEST(TeddyRelocalisationTest, FortyFramesCutInTheRecordingAreNeverFusedWrongly) {
    SKIP_WITHOUT_TEDDY();
    std::vector<test::PlayedFrame> script;
    for (int f = 50; f < 128; ++f)
        if (f < 80 || f >= 120) script.push_back({f, false});
    const TeddyRun run = play(script, "40 frames cut in the recording");
    expectNothingFusedWrongly(run);
    EXPECT_LT(run.error.ate_rmse_m, 0.010);
}

// A slower camera, or one that drops frames regularly: every third (10 Hz, 36 mm and 2.4 degrees a
// step) or fourth frame (7.5 Hz) alone is tracked throughout, none lost, the ATE about as at 30 Hz.
// At 5 mm voxels (`voxfuse` on the same frames) 30, 15, 10, 7.5 and 5 Hz give 7.16, 7.10, 7.06, 6.99
// and 7.16 mm; InfiniTAM's CPU build 6.61, 7.06, 7.08, 6.77 and 7.10. At 5 Hz these 1 cm voxels let
// one frame's error reach 30 mm, so the test stops at 7.5 Hz.
TEST(TeddyRelocalisationTest, EveryThirdOrFourthFrameAloneIsTrackedThroughout) {
    SKIP_WITHOUT_TEDDY();
    for (const int step : {3, 4}) {
        std::vector<test::PlayedFrame> script;
        for (int f = 0; f < int(teddy().frames.size()); f += step) script.push_back({f, false});
        const TeddyRun run = play(script, ("every " + std::to_string(step) + " frames").c_str());
        EXPECT_EQ(run.lost, 0) << "every " << step << " frames";
        EXPECT_LT(run.error.ate_rmse_m, 0.010) << "every " << step << " frames";
        expectNothingFusedWrongly(run);
    }
}

// A jump that no tracker bridges, 0.8 m and 55 degrees round the teddy: reported lost, never fused.
TEST(TeddyRelocalisationTest, AJumpToAViewNeverSeenStaysLost) {
    SKIP_WITHOUT_TEDDY();
    std::vector<test::PlayedFrame> script;
    for (int f = 30; f < 60; ++f) script.push_back({f, false});
    for (int f = 150; f < 156; ++f) script.push_back({f, false});
    const TeddyRun run = play(script, "a jump to a view never seen");
    for (std::size_t i = 30; i < run.frames.size(); ++i) {
        EXPECT_EQ(run.frames[i].result.status, TrackingStatus::Lost) << "frame " << i;
        EXPECT_TRUE(run.frames[i].result.relocalisation_tried);
    }
    expectNothingFusedWrongly(run);
}

}  // namespace
}  // namespace voxfuse
