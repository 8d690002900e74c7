// Semantic label fusion (shared/LabelFusion.h): the per-voxel update rules in closed form, then the
// whole pipeline on a synthetic box and sphere on a floor, fed label images with noise or with a
// competing class, checked against the objects' true classes.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <random>
#include <vector>

#include "SyntheticViews.h"
#include "voxfuse/core/EigenInterop.h"
#include "voxfuse/core/Error.h"
#include "voxfuse/engines/MainEngine.h"
#include "voxfuse/engines/RaycastEngine.h"
#include "voxfuse/shared/LabelFusion.h"
#include "voxfuse/shared/Render.h"

namespace voxfuse {
namespace {

// ---- The update rule, one voxel at a time ----

TEST(LabelFusionRule, FirstObservationSetsTheClassAndAgreementCountsUpToTheCap) {
    for (LabelUpdate rule : {LabelUpdate::Probabilistic, LabelUpdate::Vote}) {
        ClassId label = kNoLabel;
        std::uint8_t weight = 0;
        fuseLabel(label, weight, 7, rule, 5, 0.f);
        EXPECT_EQ(label, 7);
        EXPECT_EQ(weight, 1);
        for (int k = 0; k < 10; ++k) fuseLabel(label, weight, 7, rule, 5, 0.f);
        EXPECT_EQ(label, 7);
        EXPECT_EQ(weight, 5) << "the weight stops at max_weight";
    }
}

TEST(LabelFusionRule, ProbabilisticSwitchesWithProbabilityNewOverOldPlusNew) {
    // Weight 3: a different class wins when random < 1 / (3 + 1).
    ClassId label = 2;
    std::uint8_t weight = 3;
    fuseLabel(label, weight, 9, LabelUpdate::Probabilistic, 100, 0.26f);
    EXPECT_EQ(label, 2);
    EXPECT_EQ(weight, 3) << "a kept class keeps its count";
    fuseLabel(label, weight, 9, LabelUpdate::Probabilistic, 100, 0.24f);
    EXPECT_EQ(label, 9);
    EXPECT_EQ(weight, 1) << "a new class starts counting from one";
}

TEST(LabelFusionRule, VoteDecrementsAndTheNewerClassWinsATie) {
    ClassId label = 2;
    std::uint8_t weight = 2;
    fuseLabel(label, weight, 9, LabelUpdate::Vote, 100, 0.f);
    EXPECT_EQ(label, 2);
    EXPECT_EQ(weight, 1);
    fuseLabel(label, weight, 9, LabelUpdate::Vote, 100, 0.f);
    EXPECT_EQ(label, 9);
    EXPECT_EQ(weight, 1);
}

TEST(LabelFusionRule, RandomNumbersAreUniformAndDependOnPositionAndSeed) {
    constexpr int kBins = 10;
    int counts[kBins] = {};
    int n = 0;
    for (int z = -10; z < 10; ++z)
        for (int y = -10; y < 10; ++y)
            for (int x = -10; x < 15; ++x) {
                const float r = labelRandom({x, y, z}, 42u);
                ASSERT_GE(r, 0.f);
                ASSERT_LT(r, 1.f);
                ++counts[int(r * kBins)];
                ++n;
            }
    double chi2 = 0.0;
    for (int c : counts) chi2 += (c - n / double(kBins)) * (c - n / double(kBins)) / (n / double(kBins));
    EXPECT_LT(chi2, 27.9) << "chi-square, 9 degrees of freedom, p = 0.001";
    EXPECT_EQ(labelRandom({1, 2, 3}, 5u), labelRandom({1, 2, 3}, 5u));
    EXPECT_NE(labelRandom({1, 2, 3}, 5u), labelRandom({1, 2, 3}, 6u));
    EXPECT_NE(labelRandom({1, 2, 3}, 5u), labelRandom({1, 2, 4}, 5u));
}

// ---- The pipeline on a synthetic scene ----

constexpr ClassId kFloor = 2, kBox = 4, kSphere = 5;
constexpr ClassId kPrimitiveClass[3] = {kFloor, kBox, kSphere};  // synth::SyntheticScene::boxAndSphere()'s order
constexpr ClassId kLargestClass = 8;

// Exact class image: the primitive each pixel's ray hits first.
Image<ClassId> trueLabels(const synth::SyntheticScene& scene, const Intrinsics& intr, const Mat4f& T_world_camera) {
    const Eigen::Matrix4f T = toEigen(T_world_camera);
    const Eigen::Vector3f origin = T.block<3, 1>(0, 3);
    Image<ClassId> labels(intr.size());
    for (int v = 0; v < intr.height; ++v)
        for (int u = 0; u < intr.width; ++u) {
            const Eigen::Vector3f dir =
                T.block<3, 3>(0, 0) * Eigen::Vector3f((u - intr.cx) / intr.fx, (v - intr.cy) / intr.fy, 1.f);
            synth::Hit hit;
            labels.at(u, v) = scene.intersect(origin, dir, hit) ? kPrimitiveClass[hit.primitive] : kNoLabel;
        }
    return labels;
}

// The true class of a surface point: the nearest primitive's, or kNoLabel where two primitives are
// about equally near (where the box and the sphere meet the floor).
ClassId trueClassAt(const Eigen::Vector3f& p, float ambiguous_within_m) {
    const Eigen::Vector3f box_q = (p - Eigen::Vector3f(0.f, 0.f, 0.2f)).cwiseAbs() - Eigen::Vector3f::Constant(0.2f);
    const float box = box_q.cwiseMax(0.f).norm() + std::min(box_q.maxCoeff(), 0.f);
    const float d[3] = {std::fabs(p.z()), std::fabs(box),
                        std::fabs((p - Eigen::Vector3f(0.6f, 0.f, 0.15f)).norm() - 0.15f)};
    const int best = int(std::min_element(d, d + 3) - d);
    for (int k = 0; k < 3; ++k)
        if (k != best && d[k] < d[best] + ambiguous_within_m) return kNoLabel;
    return kPrimitiveClass[best];
}

struct LabelledSequence {
    std::vector<Mat4f> poses;
    std::vector<View> views;
    std::vector<Image<ClassId>> labels;  // exact
};

const LabelledSequence& boxAndSphereSequence() {
    static const LabelledSequence seq = [] {
        LabelledSequence s;
        const synth::SyntheticScene world = synth::SyntheticScene::boxAndSphere();
        const Intrinsics intr = test::kinectIntrinsics(160, 120);
        constexpr int kFrames = 60;
        for (int k = 0; k < kFrames; ++k) {
            const float a = -1.0f + 2.0f * float(k) / float(kFrames - 1);  // an arc of about 115 degrees
            const Mat4f pose = test::lookAt({0.3f + 1.2f * std::cos(a), 1.2f * std::sin(a), 0.8f}, {0.3f, 0.f, 0.1f});
            s.poses.push_back(pose);
            s.views.push_back(test::renderView(world, intr, pose, false));
            s.labels.push_back(trueLabels(world, intr, pose));
        }
        return s;
    }();
    return seq;
}

Image<ClassId> copyOf(const Image<ClassId>& image) {
    Image<ClassId> copy(image.size());
    std::copy_n(image.host(), image.pixelCount(), copy.host());
    return copy;
}

RGBDFrame toFrame(const View& view, const Image<ClassId>& labels, int index) {
    RGBDFrame f;
    f.index = index;
    f.depth_raw.resize(view.depth.size());
    for (std::size_t i = 0; i < view.depth.pixelCount(); ++i)
        f.depth_raw.host()[i] = std::uint16_t(std::lround(view.depth.host()[i] * 1000.f));
    f.labels = copyOf(labels);
    f.labels_path = "frame " + std::to_string(index);
    return f;
}

// How a frame's true label image is corrupted before it is fused.
using Corruption = std::function<void(int frame, Image<ClassId>& labels)>;

// Each pixel independently replaced, with probability p, by another class drawn uniformly.
Corruption pixelNoise(double p, unsigned seed) {
    return [p, seed](int frame, Image<ClassId>& labels) {
        std::mt19937 rng(seed + unsigned(frame));
        std::uniform_real_distribution<double> coin(0.0, 1.0);
        std::uniform_int_distribution<int> other(1, kLargestClass - 1);
        for (std::size_t i = 0; i < labels.pixelCount(); ++i) {
            ClassId& c = labels.host()[i];
            if (c == kNoLabel || coin(rng) >= p) continue;
            const int o = other(rng);
            c = ClassId(o >= c ? o + 1 : o);  // uniform over the classes other than c
        }
    };
}

// In how many of the first `frames` frames the surface point p is seen (in the image, not occluded).
int framesSeeing(const LabelledSequence& seq, int frames, Vec3f p) {
    int seen = 0;
    for (int k = 0; k < frames; ++k) {
        const View& view = seq.views[std::size_t(k)];
        const Vec3f q = transformPoint(rigidInverse(seq.poses[std::size_t(k)]), p);
        if (q.z <= 0.f) continue;
        const Vec2f px = view.calib.depth.project(q);
        const int u = int(std::lround(px.x)), v = int(std::lround(px.y));
        if (u < 0 || v < 0 || u >= view.depth.width() || v >= view.depth.height()) continue;
        seen += std::fabs(view.depth.at(u, v) - q.z) < 0.01f;
    }
    return seen;
}

struct Score {
    double correct = 0.0;           // share of the checked vertices with their true class
    double floor_with_class = 0.0;  // share of the floor's vertices with the class asked for
    int checked = 0;
};

// Fuses the sequence (exact poses and depth, corrupted labels) and scores the mesh vertices' classes
// against the true ones.

Score fuseAndScore(LabelUpdate rule, int frames, const Corruption& corrupt, ClassId count_on_floor = kNoLabel) {
    const LabelledSequence& seq = boxAndSphereSequence();
    MainEngineSettings s;
    s.voxel_type = VoxelType::SLabel;
    s.index_type = IndexType::Hash;
    s.scene.voxel_size_m = 0.01f;
    s.scene.mu_m = 0.04f;
    s.scene.label_update = rule;
    s.hash.bucket_count = 1 << 14;
    s.hash.excess_entry_count = 1 << 12;
    s.hash.max_block_count = 1 << 14;
    auto engine = MainEngine::create(s, seq.views[0].calib);
    for (int k = 0; k < frames; ++k) {
        Image<ClassId> labels = copyOf(seq.labels[std::size_t(k)]);
        corrupt(k, labels);
        // Every frame has index 0: the random numbers must not depend on how the caller numbers frames.
        EXPECT_TRUE(
            engine->processFrame(toFrame(seq.views[std::size_t(k)], labels, 0), &seq.poses[std::size_t(k)]).fused);
    }
    Mesh mesh;
    engine->extractMesh(mesh);
    EXPECT_EQ(mesh.labels.size(), mesh.vertices.size());
    Score score;
    int correct = 0, floor = 0, floor_with_class = 0;
    for (std::size_t i = 0; i < mesh.vertices.size(); ++i) {
        const Vec3f v = mesh.vertices[i];
        const ClassId truth = trueClassAt({v.x, v.y, v.z}, 0.02f);
        // Only surface seen in (almost) every frame: elsewhere the frames' votes are not the ones the
        // test counts on.
        if (truth == kNoLabel || mesh.labels[i] == kNoLabel || framesSeeing(seq, frames, v) < frames * 9 / 10) continue;
        ++score.checked;
        correct += mesh.labels[i] == truth;
        if (truth == kFloor) {
            ++floor;
            floor_with_class += mesh.labels[i] == count_on_floor;
        }
    }
    score.correct = double(correct) / std::max(1, score.checked);
    score.floor_with_class = double(floor_with_class) / std::max(1, floor);
    return score;
}

TEST(LabelFusionPipeline, ExactLabelsGiveEveryVertexItsClass) {
    const Score exact = fuseAndScore(LabelUpdate::Probabilistic, 20, [](int, Image<ClassId>&) {});
    EXPECT_GT(exact.checked, 2000);
    EXPECT_GT(exact.correct, 0.995);
}

TEST(LabelFusionPipeline, ConvergesToTheTrueClassUnderThirtyPercentLabelNoise) {
    // Probabilistic: each voxel's class is wrong for a while after a noisy observation wins, less
    // often as its count grows, so the share of right classes rises with the number of frames.
    const Score early = fuseAndScore(LabelUpdate::Probabilistic, 8, pixelNoise(0.3, 11));
    const Score late = fuseAndScore(LabelUpdate::Probabilistic, 60, pixelNoise(0.3, 11));
    EXPECT_GT(late.checked, 2000);
    EXPECT_GT(late.correct, early.correct + 0.03) << "more frames, more right classes";
    EXPECT_GT(late.correct, 0.90);
    // Vote: the true class is seen in 70% of the frames, a clear majority.
    const Score vote = fuseAndScore(LabelUpdate::Vote, 60, pixelNoise(0.3, 11));
    EXPECT_GT(vote.correct, 0.99);
    std::printf(
        "[ info ] right classes under 30%% pixel noise: probabilistic %.3f after 8 frames, %.3f after 60; vote %.4f "
        "after 60\n",
        early.correct, late.correct, vote.correct);
}

// The segmentation calls the whole floor class 7 in 30% of the frames.
TEST(LabelFusionPipeline, AClassSeenInFewerFramesDoesNotWin) {
    constexpr ClassId kRival = 7;
    auto rival_in = [](std::vector<bool> rival_frames) {
        return [rival_frames](int frame, Image<ClassId>& labels) {
            if (!rival_frames[std::size_t(frame)]) return;
            for (std::size_t i = 0; i < labels.pixelCount(); ++i)
                if (labels.host()[i] == kFloor) labels.host()[i] = kRival;
        };
    };
    std::vector<bool> shuffled(60, false), last(60, false);
    for (int k = 0; k < 18; ++k) last[std::size_t(42 + k)] = true;
    std::mt19937 rng(3);
    for (int k = 0; k < 18; ++k) shuffled[std::size_t(k)] = true;
    std::shuffle(shuffled.begin(), shuffled.end(), rng);

    const Score p_mixed = fuseAndScore(LabelUpdate::Probabilistic, 60, rival_in(shuffled), kRival);
    const Score v_mixed = fuseAndScore(LabelUpdate::Vote, 60, rival_in(shuffled), kRival);
    const Score p_last = fuseAndScore(LabelUpdate::Probabilistic, 60, rival_in(last), kRival);
    const Score v_last = fuseAndScore(LabelUpdate::Vote, 60, rival_in(last), kRival);
    std::printf(
        "[ info ] floor vertices ending with the rival class (seen in 18 of 60 frames): probabilistic %.3f shuffled, "
        "%.3f when last; vote %.3f shuffled, %.3f when last\n",
        p_mixed.floor_with_class, p_last.floor_with_class, v_mixed.floor_with_class, v_last.floor_with_class);
    EXPECT_LT(p_mixed.floor_with_class, 0.2);
    EXPECT_LT(v_mixed.floor_with_class, 0.01);
    // When the rival comes last, the probabilistic rule keeps the floor with probability about
    // (42 / 43)^18 = 0.65 per voxel; the vote always does.
    EXPECT_LT(p_last.floor_with_class, 0.45);
    EXPECT_EQ(v_last.floor_with_class, 0.0);
}

TEST(LabelFusionPipeline, ClassRenderShowsTheFusedClasses) {
    const LabelledSequence& seq = boxAndSphereSequence();
    MainEngineSettings s;
    s.voxel_type = VoxelType::SLabel;
    s.scene.voxel_size_m = 0.01f;
    s.scene.mu_m = 0.04f;
    auto engine = MainEngine::create(s, seq.views[0].calib);
    for (int k = 0; k < 10; ++k)
        engine->processFrame(toFrame(seq.views[std::size_t(k)], seq.labels[std::size_t(k)], k),
                             &seq.poses[std::size_t(k)]);
    Image<Vec4u8> image;
    engine->renderLast(RenderMode::Class, image);
    // Unshaded, a pixel's colour is classColor() times one intensity: its hue identifies the class.
    auto hue_matches = [](Vec4u8 pixel, ClassId c) {
        const Vec3f ref = classColor(c);
        const Vec3f got{float(pixel.x), float(pixel.y), float(pixel.z)};
        const float scale = dot(got, ref) / dot(ref, ref);
        return scale > 0.f && length(got - ref * scale) < 12.f;
    };
    const Image<ClassId>& truth = seq.labels[9];
    int checked = 0, matching = 0;
    for (std::size_t i = 0; i < image.pixelCount(); ++i) {
        if (truth.host()[i] == kNoLabel || image.host()[i].xyz() == kBackground.xyz()) continue;
        ++checked;
        matching += hue_matches(image.host()[i], truth.host()[i]);
    }
    EXPECT_GT(checked, int(image.pixelCount() / 2));
    EXPECT_GT(matching, int(0.97 * checked));
}

TEST(LabelFusionPipeline, LabelImagesOfAnotherAspectRatioAreRejected) {
    const LabelledSequence& seq = boxAndSphereSequence();
    MainEngineSettings s;
    s.voxel_type = VoxelType::SLabel;
    auto engine = MainEngine::create(s, seq.views[0].calib);
    RGBDFrame f = toFrame(seq.views[0], Image<ClassId>(Vec2i{100, 100}), 0);
    f.labels_path = "labels/000000.png";
    try {
        engine->processFrame(f, &seq.poses[0]);
        FAIL() << "a square label image for a 4:3 camera was accepted";
    } catch (const IoError& e) {
        EXPECT_NE(std::string(e.what()).find("labels/000000.png"), std::string::npos) << e.what();
    }
}

}  // namespace
}  // namespace voxfuse
