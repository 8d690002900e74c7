// Tests of the synthetic data generator: exact ray casting and distances,
// semantic class labels, the Kinect depth model's noise and holes, the camera
// path, and the tool's Kinect-raw PGM output and label images against the
// exact geometry.
#include "CameraPath.h"
#include "KinectDepthModel.h"
#include "SyntheticScene.h"

#include "voxfuse/io/ImageIO.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <random>
#include <set>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

using namespace voxfuse::synth;
using Eigen::Vector3f;
namespace fs = std::filesystem;

namespace {

constexpr float kDegree = 3.14159265f / 180.0f;

// Largest depth error from rounding the raw value (half a disparity step),
// which is larger on the far side because depth ~ 1 / disparity.
float halfStepDepthError(const KinectDepthModel& model, float z) {
    const float d = model.depthToDisparity(z);
    return model.disparityToDepth(d - 0.5f * model.params().disparityStep) - z;
}

float standardDeviation(const std::vector<float>& values) {
    double mean = 0.0, sq = 0.0;
    for (float v : values) mean += v;
    mean /= values.size();
    for (float v : values) sq += (v - mean) * (v - mean);
    return static_cast<float>(std::sqrt(sq / (values.size() - 1)));
}

}  // namespace

TEST(SyntheticScene, PlaneHitHasAnalyticDepthAndNormal) {
    const SyntheticScene scene = SyntheticScene::singlePlane(Vector3f::Zero(), Vector3f::UnitZ());
    const Vector3f origin(0.3f, -0.2f, 2.0f);
    const Vector3f dir = Vector3f(0.1f, 0.2f, -1.0f).normalized();
    Hit hit;
    ASSERT_TRUE(scene.intersect(origin, dir, hit));
    EXPECT_NEAR(hit.t, 2.0f / -dir.z(), 1e-5f);
    EXPECT_NEAR((hit.normal - Vector3f::UnitZ()).norm(), 0.0f, 1e-6f);
    EXPECT_EQ(hit.primitive, 0);

    // Seen from below, the normal faces the viewer.
    ASSERT_TRUE(scene.intersect(Vector3f(0, 0, -1.5f), Vector3f::UnitZ(), hit));
    EXPECT_NEAR(hit.t, 1.5f, 1e-6f);
    EXPECT_NEAR((hit.normal + Vector3f::UnitZ()).norm(), 0.0f, 1e-6f);

    // Parallel and receding rays miss.
    EXPECT_FALSE(scene.intersect(origin, Vector3f::UnitX(), hit));
    EXPECT_FALSE(scene.intersect(origin, Vector3f::UnitZ(), hit));
}

TEST(SyntheticScene, TiltedPlaneHitAndDistance) {
    const Vector3f point(1, 2, 3), normal = Vector3f(1, 1, 1).normalized();
    const SyntheticScene scene = SyntheticScene::singlePlane(point, normal);
    Hit hit;
    ASSERT_TRUE(scene.intersect(Vector3f::Zero(), Vector3f::UnitX(), hit));
    EXPECT_NEAR(hit.t, 6.0f, 1e-5f);  // x + y + z = 6
    EXPECT_NEAR(std::abs(hit.normal.dot(normal)), 1.0f, 1e-6f);
    EXPECT_NEAR(scene.distanceToSurface(Vector3f(6, 0, 0)), 0.0f, 1e-5f);
    EXPECT_NEAR(scene.distanceToSurface(Vector3f::Zero()), 6.0f / std::sqrt(3.0f), 1e-5f);
    EXPECT_NEAR(scene.distanceToSurface(point + 0.25f * normal), 0.25f, 1e-5f);
}

TEST(SyntheticScene, SphereHitHasAnalyticDepthAndNormal) {
    const Vector3f center(0, 0, 3);
    const SyntheticScene scene = SyntheticScene::singleSphere(center, 1.0f);
    Hit hit;
    ASSERT_TRUE(scene.intersect(Vector3f::Zero(), Vector3f::UnitZ(), hit));
    EXPECT_NEAR(hit.t, 2.0f, 1e-6f);
    EXPECT_NEAR((hit.normal - Vector3f(0, 0, -1)).norm(), 0.0f, 1e-6f);

    // Off-axis ray at x = 0.5: enters at z = 3 - sqrt(0.75).
    ASSERT_TRUE(scene.intersect(Vector3f(0.5f, 0, 0), Vector3f::UnitZ(), hit));
    EXPECT_NEAR(hit.t, 3.0f - std::sqrt(0.75f), 1e-5f);
    EXPECT_NEAR((hit.normal - Vector3f(0.5f, 0, -std::sqrt(0.75f))).norm(), 0.0f, 1e-5f);

    // A non-unit direction scales t accordingly.
    ASSERT_TRUE(scene.intersect(Vector3f::Zero(), Vector3f(0, 0, 2), hit));
    EXPECT_NEAR(hit.t, 1.0f, 1e-6f);

    EXPECT_FALSE(scene.intersect(Vector3f(1.5f, 0, 0), Vector3f::UnitZ(), hit));
}

TEST(SyntheticScene, SphereDistanceIsAnalytic) {
    const Vector3f center(0.2f, -0.1f, 3.0f);
    const SyntheticScene scene = SyntheticScene::singleSphere(center, 0.5f);
    Hit hit;
    ASSERT_TRUE(scene.intersect(Vector3f::Zero(), center.normalized(), hit));
    EXPECT_NEAR(scene.distanceToSurface(hit.t * center.normalized()), 0.0f, 1e-5f);
    EXPECT_NEAR(scene.distanceToSurface(Vector3f::Zero()), center.norm() - 0.5f, 1e-5f);
    EXPECT_NEAR(scene.distanceToSurface(center), 0.5f, 1e-6f);
    EXPECT_NEAR(scene.distanceToSurface(center + Vector3f(0, 0.3f, 0)), 0.2f, 1e-6f);
}

TEST(SyntheticScene, BoxAndSphereDistances) {
    const SyntheticScene scene = SyntheticScene::boxAndSphere();
    EXPECT_EQ(scene.primitives().size(), 3u);
    Hit hit;
    ASSERT_TRUE(scene.intersect(Vector3f(0, 0, 2), -Vector3f::UnitZ(), hit));
    EXPECT_NEAR(hit.t, 1.6f, 1e-6f);  // box top at z = 0.4
    EXPECT_EQ(hit.primitive, 1);
    EXPECT_NEAR(scene.distanceToSurface(Vector3f(0, 0, 0.5f)), 0.1f, 1e-6f);
    // Inside the box: nearest face 0.05 away (the floor is 0.15 away).
    EXPECT_NEAR(scene.distanceToSurface(Vector3f(0.15f, 0, 0.15f)), 0.05f, 1e-6f);
}

TEST(SyntheticScene, DefaultRoomIsClosedAndHitsLieOnSurfaces) {
    const SyntheticScene room = SyntheticScene::defaultRoom();
    std::mt19937 rng(3);
    std::normal_distribution<float> gaussian;
    std::uniform_real_distribution<float> unit(0.0f, 1.0f);
    for (int i = 0; i < 2000; ++i) {
        const Vector3f origin(-2.0f + 4.0f * unit(rng), -1.6f + 3.2f * unit(rng), 1.2f + 1.2f * unit(rng));
        const Vector3f dir = Vector3f(gaussian(rng), gaussian(rng), gaussian(rng)).normalized();
        if (room.distanceToSurface(origin) < 1e-3f) continue;
        Hit hit;
        ASSERT_TRUE(room.intersect(origin, dir, hit)) << "ray escaped the room";
        EXPECT_LT(hit.t, 7.0f);  // the room's diagonal
        EXPECT_LT(room.distanceToSurface(origin + hit.t * dir), 2e-5f);
        EXPECT_LT(hit.normal.dot(dir), 0.0f);
        EXPECT_TRUE((hit.albedo_rgb.array() >= 0.0f).all() && (hit.albedo_rgb.array() <= 1.0f).all());
    }
}

TEST(SyntheticScene, SceneFileRoundTripIsExact) {
    const SyntheticScene room = SyntheticScene::defaultRoom();
    const std::string path = ::testing::TempDir() + "voxfuse_synth_scene_roundtrip.txt";
    room.write(path);
    const SyntheticScene back = SyntheticScene::read(path);
    ASSERT_EQ(back.primitives().size(), room.primitives().size());
    ASSERT_EQ(back.lights().size(), room.lights().size());
    EXPECT_EQ(back.ambient(), room.ambient());
    std::mt19937 rng(5);
    std::normal_distribution<float> gaussian;
    for (int i = 0; i < 500; ++i) {
        const Vector3f origin(0.3f, -0.2f, 1.4f);
        const Vector3f dir(gaussian(rng), gaussian(rng), gaussian(rng));
        Hit a, b;
        ASSERT_TRUE(room.intersect(origin, dir, a));
        ASSERT_TRUE(back.intersect(origin, dir, b));
        EXPECT_EQ(a.t, b.t);
        EXPECT_EQ(a.primitive, b.primitive);
        EXPECT_EQ(a.albedo_rgb, b.albedo_rgb);
    }
    for (std::size_t i = 0; i < room.primitives().size(); ++i)
        EXPECT_EQ(back.primitives()[i].classId, room.primitives()[i].classId) << "primitive " << i;
    ASSERT_EQ(back.classes().size(), room.classes().size());
    for (std::size_t i = 0; i < room.classes().size(); ++i) {
        EXPECT_EQ(back.classes()[i].id, room.classes()[i].id);
        EXPECT_EQ(back.classes()[i].name, room.classes()[i].name);
    }
    const SyntheticScene plane = SyntheticScene::singlePlane(Vector3f::Zero(), Vector3f::UnitZ());
    plane.write(path);  // infinite extents survive as "inf"
    Hit hit;
    EXPECT_TRUE(SyntheticScene::read(path).intersect(Vector3f(1e3f, 0, 1), -Vector3f::UnitZ(), hit));
    std::remove(path.c_str());
}

TEST(SyntheticScene, SceneFileClassesAreOptionalAndChecked) {
    const std::string path = ::testing::TempDir() + "voxfuse_synth_scene_classes.txt";
    const auto readText = [&](const std::string& text) {
        std::ofstream(path) << text;
        return SyntheticScene::read(path);
    };
    const std::string sphere = "sphere 0.5 pose 0 0 3 0 0 0 1 texture solid 0.5 0.5 0.5 0 0 0 1 0";
    // Files written before labels existed: the primitive is unlabelled.
    const SyntheticScene old = readText(sphere + "\n");
    ASSERT_EQ(old.primitives().size(), 1u);
    EXPECT_EQ(old.primitives()[0].classId, kUnlabelled);
    EXPECT_TRUE(old.classes().empty());

    const SyntheticScene labelled = readText("class 9 vase\nclass 300 lamp\n" + sphere + " class 300\n");
    EXPECT_EQ(labelled.primitives()[0].classId, 300);
    ASSERT_EQ(labelled.classes().size(), 2u);
    EXPECT_EQ(labelled.classes()[0].id, 9);
    EXPECT_EQ(labelled.classes()[1].name, "lamp");

    EXPECT_THROW(readText(sphere + " class\n"), std::runtime_error);
    EXPECT_THROW(readText(sphere + " class -1\n"), std::runtime_error);
    EXPECT_THROW(readText(sphere + " class 65536\n"), std::runtime_error);
    EXPECT_THROW(readText(sphere + " klass 2\n"), std::runtime_error);
    EXPECT_THROW(readText(sphere + " class 2 extra\n"), std::runtime_error);
    EXPECT_THROW(readText("class 0 nothing\n"), std::runtime_error);
    EXPECT_THROW(readText("class 4\n"), std::runtime_error);
    std::remove(path.c_str());
}

TEST(SyntheticScene, DefaultRoomGivesEveryPrimitiveANamedClass) {
    const SyntheticScene room = SyntheticScene::defaultRoom();
    std::map<std::uint16_t, std::string> names;
    for (const SemanticClass& c : room.classes()) {
        EXPECT_GE(c.id, 1);
        EXPECT_TRUE(names.emplace(c.id, c.name).second) << "class " << c.id << " named twice";
    }
    const std::map<std::uint16_t, std::string> expected{
        {room_class::kFloor, "floor"}, {room_class::kWall, "wall"},    {room_class::kCeiling, "ceiling"},
        {room_class::kTable, "table"}, {room_class::kBall, "ball"},    {room_class::kCylinder, "cylinder"},
        {room_class::kBox, "box"},     {room_class::kPoster, "poster"}};
    EXPECT_EQ(names, expected);

    std::set<std::uint16_t> used;
    for (const Primitive& p : room.primitives()) {
        EXPECT_TRUE(names.count(p.classId)) << "class " << p.classId << " has no name";
        EXPECT_LE(p.classId, 255) << "label images are 8-bit";
        used.insert(p.classId);
        if (p.kind == PrimitiveKind::Sphere) {
            EXPECT_EQ(p.classId, room_class::kBall);
        }
        if (p.kind == PrimitiveKind::Cylinder) {
            EXPECT_EQ(p.classId, room_class::kCylinder);
        }
    }
    EXPECT_EQ(used.size(), names.size()) << "every class is used";

    // Spot checks by geometry: straight down onto the floor, up to the
    // ceiling, sideways onto a wall, down onto the table top.
    Hit hit;
    const auto classAlong = [&](const Vector3f& origin, const Vector3f& dir) {
        EXPECT_TRUE(room.intersect(origin, dir, hit));
        return room.primitives()[hit.primitive].classId;
    };
    EXPECT_EQ(classAlong(Vector3f(1.8f, 1.5f, 1.5f), -Vector3f::UnitZ()), room_class::kFloor);
    EXPECT_EQ(classAlong(Vector3f(1.8f, 1.5f, 1.5f), Vector3f::UnitZ()), room_class::kCeiling);
    EXPECT_EQ(classAlong(Vector3f(1.8f, 1.5f, 2.2f), Vector3f::UnitX()), room_class::kWall);
    EXPECT_EQ(classAlong(Vector3f(0.6f, 0.35f, 1.5f), -Vector3f::UnitZ()), room_class::kTable);
    EXPECT_EQ(classAlong(Vector3f(2.0f, 0.3f, 1.2f), Vector3f::UnitX()), room_class::kPoster);
}

TEST(SyntheticScene, RenderedLabelIsTheClassOfThePrimitiveTheExactRayHits) {
    const SyntheticScene room = SyntheticScene::defaultRoom();
    const CameraPath path;
    const PinholeCamera camera = PinholeCamera::kinectV1(160, 120);
    std::set<std::uint16_t> seen;
    for (int i : {0, 50, 99}) {
        const Eigen::Isometry3f pose = path.pose(i);
        const RenderedFrame frame = room.render(camera, pose, 1);
        ASSERT_EQ(frame.label.size(), frame.depth.size());
        for (int v = 0; v < camera.height; ++v)
            for (int u = 0; u < camera.width; ++u) {
                const std::size_t idx = static_cast<std::size_t>(v) * camera.width + u;
                const Vector3f dir = pose.linear() * camera.ray(static_cast<float>(u), static_cast<float>(v));
                Hit hit;
                ASSERT_TRUE(room.intersect(pose.translation(), dir, hit)) << "the room is closed";
                ASSERT_EQ(frame.label[idx], room.primitives()[hit.primitive].classId)
                    << "frame " << i << " pixel " << u << "," << v;
                // Aligned with depth: the label comes from the ray that gave the depth.
                ASSERT_EQ(frame.depth[idx], hit.t);
                ASSERT_GT(frame.label[idx], kUnlabelled) << "surface without a class at " << u << "," << v;
                seen.insert(frame.label[idx]);
            }
    }
    EXPECT_GE(seen.size(), 6u) << "the views see most classes";
}

TEST(SyntheticScene, PixelsWithoutASurfaceAreUnlabelled) {
    const SyntheticScene scene = SyntheticScene::singleSphere(Vector3f(0, 0, 3), 0.5f);
    const PinholeCamera camera = PinholeCamera::kinectV1(64, 48);
    const RenderedFrame frame = scene.render(camera, Eigen::Isometry3f::Identity(), 1);
    int empty = 0, ball = 0;
    for (std::size_t i = 0; i < frame.depth.size(); ++i) {
        if (frame.depth[i] == 0.0f) {
            EXPECT_EQ(frame.label[i], kUnlabelled) << "pixel " << i;
            ++empty;
        } else {
            EXPECT_EQ(frame.label[i], room_class::kBall) << "pixel " << i;
            ++ball;
        }
    }
    EXPECT_GT(empty, 0);
    EXPECT_GT(ball, 0);
    // An unlabelled primitive renders as 0 too, though it has depth.
    SyntheticScene plain;
    plain.addSphere(Vector3f(0, 0, 3), 0.5f);
    const RenderedFrame unlabelled = plain.render(camera, Eigen::Isometry3f::Identity(), 1);
    EXPECT_EQ(std::count(unlabelled.label.begin(), unlabelled.label.end(), kUnlabelled),
              static_cast<std::ptrdiff_t>(unlabelled.label.size()));
    EXPECT_EQ(unlabelled.depth, frame.depth);
}

TEST(KinectDepthModel, NoiseGrowsWithSquaredDepth) {
    KinectDepthModel model(KinectDepthModel::Params(), 7);
    std::mt19937 rng(11);
    std::uniform_real_distribution<float> jitter(-0.02f, 0.02f);  // averages the quantisation phase
    const auto errorsAt = [&](float z) {
        std::vector<float> errors;
        for (int i = 0; i < 20000; ++i) {
            const float truth = z + jitter(rng);
            const float measured = model.measure(truth);
            EXPECT_GT(measured, 0.0f);
            errors.push_back(measured - truth);
        }
        return errors;
    };
    const float sigma1 = standardDeviation(errorsAt(1.0f));
    const float sigma2 = standardDeviation(errorsAt(2.0f));
    EXPECT_GT(sigma1, 0.0010f);
    EXPECT_LT(sigma1, 0.0025f);
    EXPECT_GT(sigma2, 0.0045f);
    EXPECT_LT(sigma2, 0.0090f);
    EXPECT_NEAR(sigma2 / sigma1, 4.0f, 0.8f);
    // One quantisation step: 1/8 px of disparity.
    EXPECT_NEAR(model.depthStepAt(2.0f), 4.0f * model.depthStepAt(1.0f), 1e-4f);
}

TEST(KinectDepthModel, ImageNoiseKeepsThePerPixelSigma) {
    // A fronto-parallel wall near 2 m; the slight ramp averages the quantisation phase.
    const int w = 200, h = 200;
    std::vector<float> depth(w * h), cosine(w * h, 1.0f);
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) depth[y * w + x] = 1.98f + 0.04f * x / w;
    KinectDepthModel::Params params;
    params.dropoutProbability = 0.0f;
    for (int radius : {0, 2}) {
        params.noiseCorrelationRadius = radius;
        KinectDepthModel model(params, 3);
        const std::vector<float> out = model.apply(depth, cosine, w, h);
        std::vector<float> errors;
        for (int i = 0; i < w * h; ++i) {
            ASSERT_GT(out[i], 0.0f);
            errors.push_back(out[i] - depth[i]);
        }
        const float sigma = standardDeviation(errors);
        EXPECT_GT(sigma, 0.0045f) << "radius " << radius;
        EXPECT_LT(sigma, 0.0090f) << "radius " << radius;
    }
}

TEST(KinectDepthModel, HolesAtGrazingAnglesEdgesAndOutOfRange) {
    const int w = 8, h = 1;
    //                         near   grazing far-edge  far    far    too-far too-near none
    std::vector<float> depth{1.00f, 1.00f, 2.00f, 2.00f, 2.00f, 4.80f, 0.30f, 0.00f};
    std::vector<float> cosine{1.0f, std::cos(85.0f * kDegree), 1.0f, 1.0f, 1.0f, 1.0f, 1.0f, 0.0f};
    KinectDepthModel::Params params;
    params.dropoutProbability = 0.0f;
    KinectDepthModel model(params, 1);
    const std::vector<float> out = model.apply(depth, cosine, w, h);
    EXPECT_NEAR(out[0], 1.0f, 0.02f);  // near side of the edge stays
    EXPECT_EQ(out[1], 0.0f);
    EXPECT_EQ(out[2], 0.0f);  // far side of a 1 m jump
    EXPECT_NEAR(out[3], 2.0f, 0.05f);
    EXPECT_NEAR(out[4], 2.0f, 0.05f);
    EXPECT_EQ(out[5], 0.0f);
    EXPECT_EQ(out[6], 0.0f);
    EXPECT_EQ(out[7], 0.0f);
}

TEST(KinectDepthModel, IsRepeatableForAFixedSeed) {
    std::vector<float> depth(64 * 48), cosine(64 * 48, 0.9f);
    for (std::size_t i = 0; i < depth.size(); ++i) depth[i] = 0.8f + 0.001f * i;
    KinectDepthModel a(KinectDepthModel::Params(), 99), b(KinectDepthModel::Params(), 99);
    EXPECT_EQ(a.apply(depth, cosine, 64, 48), b.apply(depth, cosine, 64, 48));
}

// Sequences reuse one output and the model's scratch; a model that drew or kept anything differently
// for a reused buffer (a stale pixel of the last frame, a smaller image after a larger one) would
// differ from the fresh output of a model with the same seed.
TEST(KinectDepthModel, ApplyingIntoAReusedBufferGivesTheFreshResult) {
    KinectDepthModel fresh(KinectDepthModel::Params(), 7), reused(KinectDepthModel::Params(), 7);
    std::vector<float> out;
    for (const auto& [w, h] : {std::pair{64, 48}, std::pair{64, 48}, std::pair{32, 20}}) {
        std::vector<float> depth(std::size_t(w) * h), cosine(depth.size(), 0.9f);
        for (std::size_t i = 0; i < depth.size(); ++i) depth[i] = i % 7 == 0 ? 0.f : 0.8f + 0.001f * float(i % 500);
        reused.apply(depth, cosine, w, h, out);
        EXPECT_EQ(out, fresh.apply(depth, cosine, w, h)) << w << "x" << h;
    }
}

TEST(SyntheticScene, RenderingIntoAReusedFrameGivesTheFreshFrame) {
    const SyntheticScene room = SyntheticScene::defaultRoom();
    const CameraPath path;
    RenderedFrame reused;
    for (const auto& [width, frame] : {std::pair{80, 10}, std::pair{80, 20}, std::pair{40, 30}}) {
        const PinholeCamera camera = PinholeCamera::kinectV1(width, width * 3 / 4);
        const Eigen::Isometry3f pose = path.pose(frame);
        room.render(camera, pose, 1, reused);
        const RenderedFrame fresh = room.render(camera, pose, 1);
        EXPECT_EQ(reused.width, fresh.width);
        EXPECT_EQ(reused.height, fresh.height);
        EXPECT_EQ(reused.depth, fresh.depth);
        EXPECT_EQ(reused.cosIncidence, fresh.cosIncidence);
        EXPECT_EQ(reused.label, fresh.label);
        EXPECT_TRUE(reused.rgb == fresh.rgb);
    }
}

TEST(KinectDepthModel, KinectRawRoundTripsWithinOneStep) {
    const KinectDepthModel model;
    for (float z = 0.4f; z <= 4.5f; z += 0.01f) {
        const std::uint16_t raw = model.depthToKinectRaw(z);
        ASSERT_GT(raw, 0);
        EXPECT_LE(std::abs(model.kinectRawToDepth(raw) - z), halfStepDepthError(model, z) + 1e-5f);
    }
    EXPECT_EQ(model.depthToKinectRaw(0.0f), 0);
    EXPECT_EQ(model.kinectRawToDepth(0), 0.0f);
}

TEST(CameraPath, IsSmoothAtThirtyFps) {
    const CameraPath path;
    float maxStep = 0.0f, maxTurn = 0.0f;
    for (int i = 1; i < 900; ++i) {  // 30 s: more than one lap of the room
        const Eigen::Isometry3f a = path.pose(i - 1), b = path.pose(i);
        const float step = (b.translation() - a.translation()).norm();
        const float turn = Eigen::AngleAxisf(a.linear().transpose() * b.linear()).angle();
        maxStep = std::max(maxStep, step);
        maxTurn = std::max(maxTurn, turn);
        ASSERT_LT(step, 0.02f) << "frame " << i;
        ASSERT_LT(turn, 2.0f * kDegree) << "frame " << i;
        ASSERT_NEAR(b.linear().determinant(), 1.0f, 1e-5f);
    }
    EXPECT_GT(maxStep, 0.005f);  // it does move like a hand-held camera
    EXPECT_GT(maxTurn, 0.2f * kDegree);
}

TEST(CameraPath, KeepsTheObjectsInView) {
    const SyntheticScene room = SyntheticScene::defaultRoom();
    const CameraPath path;
    const PinholeCamera camera = PinholeCamera::kinectV1(80, 60);
    for (int i = 0; i < 900; i += 15) {
        const Eigen::Isometry3f pose = path.pose(i);
        const RenderedFrame frame = room.render(camera, pose, 1);
        int objectPixels = 0, tooClose = 0;
        for (int v = 0; v < camera.height; ++v)
            for (int u = 0; u < camera.width; ++u) {
                const float z = frame.depth[v * camera.width + u];
                ASSERT_GT(z, 0.0f);
                tooClose += z < 0.5f;
                const Vector3f p = pose * (z * camera.ray(u, v));
                // Inside the room, off the floor and away from the walls: an object.
                objectPixels += std::abs(p.x()) < 2.3f && std::abs(p.y()) < 1.8f && p.z() > 0.01f && p.z() < 2.0f;
            }
        EXPECT_EQ(tooClose, 0) << "frame " << i;
        EXPECT_GT(objectPixels, camera.width * camera.height / 6) << "frame " << i;
    }
}

// The end-to-end tests need the tool's path: compile with
// VOXFUSE_SYNTH_EXE="$<TARGET_FILE:voxfuse_synth>"; otherwise they skip visibly.
#ifdef VOXFUSE_SYNTH_EXE
namespace {

std::vector<std::uint16_t> readPgm16(const fs::path& path, int& width, int& height) {
    std::ifstream in(path, std::ios::binary);
    std::string magic;
    int maxValue = 0;
    in >> magic >> width >> height >> maxValue;
    in.get();
    EXPECT_EQ(magic, "P5");
    EXPECT_EQ(maxValue, 65535);
    std::vector<unsigned char> bytes(static_cast<std::size_t>(width) * height * 2);
    in.read(reinterpret_cast<char*>(bytes.data()), static_cast<std::streamsize>(bytes.size()));
    EXPECT_TRUE(in.good());
    std::vector<std::uint16_t> values(bytes.size() / 2);
    for (std::size_t i = 0; i < values.size(); ++i)
        values[i] = static_cast<std::uint16_t>(bytes[2 * i] << 8 | bytes[2 * i + 1]);
    return values;
}

std::vector<Eigen::Isometry3f> readGroundTruth(const fs::path& path) {
    std::ifstream in(path);
    std::vector<Eigen::Isometry3f> poses;
    for (std::string line; std::getline(in, line);) {
        if (line.empty() || line[0] == '#') continue;
        std::istringstream s(line);
        double ts, tx, ty, tz, qx, qy, qz, qw;
        s >> ts >> tx >> ty >> tz >> qx >> qy >> qz >> qw;
        Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
        pose.linear() = Eigen::Quaterniond(qw, qx, qy, qz).normalized().toRotationMatrix();
        pose.translation() = Eigen::Vector3d(tx, ty, tz);
        poses.push_back(pose.cast<float>());
    }
    return poses;
}

// Runs the tool in PPM mode and compares its Kinect-raw depth with the exact
// depth of the scene and poses it wrote.
void checkPpmOutput(bool noise) {
    const fs::path dir =
        fs::path(::testing::TempDir()) / (noise ? "voxfuse_synth_ppm_noisy" : "voxfuse_synth_ppm_exact");
    fs::remove_all(dir);
    const std::string command = std::string("\"") + VOXFUSE_SYNTH_EXE + "\" --out \"" + dir.string() +
                                "\" --format ppm --frames 3 --width 160 --height 120" + (noise ? "" : " --no-noise") +
                                " > /dev/null";
    ASSERT_EQ(std::system(command.c_str()), 0) << command;

    std::ifstream calib(dir / "calib.txt");
    std::vector<std::string> lines;
    for (std::string line; std::getline(calib, line);) lines.push_back(line);
    ASSERT_EQ(lines.size(), 13u);
    EXPECT_EQ(lines[0], "160 120");
    EXPECT_EQ(lines[12], "kinect 1090 0.075");

    const SyntheticScene scene = SyntheticScene::read((dir / "scene.txt").string());
    const std::vector<Eigen::Isometry3f> poses = readGroundTruth(dir / "groundtruth.txt");
    ASSERT_EQ(poses.size(), 3u);
    const PinholeCamera camera = PinholeCamera::kinectV1(160, 120);
    KinectDepthModel::Params params;
    params.fx = camera.fx;
    const KinectDepthModel model(params);

    int width = 0, height = 0;
    const std::vector<std::uint16_t> raw = readPgm16(dir / "0002.pgm", width, height);
    ASSERT_EQ(width, 160);
    ASSERT_EQ(height, 120);
    const RenderedFrame truth = scene.render(camera, poses[2], 1);
    int valid = 0, withinOneStep = 0;
    for (std::size_t i = 0; i < raw.size(); ++i) {
        if (raw[i] == 0) continue;
        ++valid;
        const float z = truth.depth[i];
        const float error = std::abs(model.kinectRawToDepth(raw[i]) - z);
        if (!noise) {
            EXPECT_LE(error, halfStepDepthError(model, z) + 1e-4f) << "pixel " << i << " at " << z << " m";
        }
        withinOneStep += error <= model.depthStepAt(z);
    }
    if (noise) {
        EXPECT_GT(valid, static_cast<int>(raw.size() * 6 / 10));  // some holes, mostly valid
        EXPECT_LT(valid, static_cast<int>(raw.size()));
        EXPECT_GT(withinOneStep, valid * 9 / 10);
    } else {
        EXPECT_GT(valid, static_cast<int>(raw.size() * 99 / 100));
    }
    fs::remove_all(dir);
}

// "timestamp filename" lines of a TUM list, '#' lines skipped.
std::vector<std::pair<std::string, std::string>> readTumList(const fs::path& path) {
    std::ifstream in(path);
    EXPECT_TRUE(in.good()) << path;
    std::vector<std::pair<std::string, std::string>> entries;
    for (std::string line; std::getline(in, line);) {
        if (line.empty() || line[0] == '#') continue;
        std::istringstream s(line);
        std::string timestamp, file, extra;
        s >> timestamp >> file;
        EXPECT_FALSE(file.empty()) << line;
        EXPECT_FALSE(s >> extra) << line;
        entries.emplace_back(timestamp, file);
    }
    return entries;
}

// Bit depth and colour type from a PNG's IHDR chunk (colour type 0: greyscale).
void readPngFormat(const fs::path& path, int& bitDepth, int& colorType) {
    std::ifstream in(path, std::ios::binary);
    unsigned char header[26] = {};
    in.read(reinterpret_cast<char*>(header), sizeof(header));
    ASSERT_TRUE(in.good()) << path;
    ASSERT_EQ(std::string(reinterpret_cast<char*>(header) + 12, 4), "IHDR") << path;
    bitDepth = header[24];
    colorType = header[25];
}

}  // namespace

TEST(VoxfuseSynthTool, ExactPpmDepthConvertsBackWithinHalfAStep) { checkPpmOutput(false); }
TEST(VoxfuseSynthTool, NoisyPpmDepthStaysNearTheTruth) { checkPpmOutput(true); }

// TUM layout: labels/<timestamp>.png, labels.txt and classes.txt exist and
// parse, and every label pixel is the class of the exact render, 0 nowhere
// a depth was measured.
TEST(VoxfuseSynthTool, TumLabelImagesAreTheExactClasses) {
    const fs::path dir = fs::path(::testing::TempDir()) / "voxfuse_synth_tum_labels";
    fs::remove_all(dir);
    const std::string command = std::string("\"") + VOXFUSE_SYNTH_EXE + "\" --out \"" + dir.string() +
                                "\" --frames 2 --width 160 --height 120 --color-samples 1 > /dev/null";
    ASSERT_EQ(std::system(command.c_str()), 0) << command;

    const SyntheticScene scene = SyntheticScene::read((dir / "scene.txt").string());
    std::ifstream classesFile(dir / "classes.txt");
    ASSERT_TRUE(classesFile.good());
    std::vector<SemanticClass> classes;
    for (std::string line; std::getline(classesFile, line);) {
        if (line.empty() || line[0] == '#') continue;
        std::istringstream s(line);
        SemanticClass c;
        std::string extra;
        ASSERT_TRUE(s >> c.id >> c.name) << line;
        EXPECT_FALSE(s >> extra) << line;
        classes.push_back(c);
    }
    ASSERT_EQ(classes.size(), scene.classes().size());
    ASSERT_EQ(classes.size(), SyntheticScene::defaultRoom().classes().size());
    for (std::size_t i = 0; i < classes.size(); ++i) {
        EXPECT_EQ(classes[i].id, scene.classes()[i].id);
        EXPECT_EQ(classes[i].name, scene.classes()[i].name);
    }

    const auto rgb = readTumList(dir / "rgb.txt");
    const auto depth = readTumList(dir / "depth.txt");
    const auto labels = readTumList(dir / "labels.txt");
    ASSERT_EQ(labels.size(), 2u);
    ASSERT_EQ(rgb.size(), labels.size());
    const std::vector<Eigen::Isometry3f> poses = readGroundTruth(dir / "groundtruth.txt");
    ASSERT_EQ(poses.size(), labels.size());
    const PinholeCamera camera = PinholeCamera::kinectV1(160, 120);
    for (std::size_t f = 0; f < labels.size(); ++f) {
        EXPECT_EQ(labels[f].first, rgb[f].first);
        EXPECT_EQ(labels[f].second, "labels/" + labels[f].first + ".png");
        const fs::path labelPath = dir / labels[f].second;
        ASSERT_TRUE(fs::exists(labelPath)) << labelPath;
        int bitDepth = 0, colorType = -1;
        readPngFormat(labelPath, bitDepth, colorType);
        EXPECT_EQ(bitDepth, 8);
        EXPECT_EQ(colorType, 0) << "single-channel greyscale";

        const voxfuse::Image<voxfuse::Vec4u8> image = voxfuse::readColorImage(labelPath.string());
        const voxfuse::Image<std::uint16_t> depthImage = voxfuse::readDepthPNG((dir / depth[f].second).string());
        ASSERT_EQ(image.width(), camera.width);
        ASSERT_EQ(image.height(), camera.height);
        const RenderedFrame truth = scene.render(camera, poses[f], 1);
        int measured = 0;
        for (int v = 0; v < camera.height; ++v)
            for (int u = 0; u < camera.width; ++u) {
                const voxfuse::Vec4u8 p = image.at(u, v);
                ASSERT_TRUE(p.x == p.y && p.y == p.z) << "greyscale";
                ASSERT_EQ(p.x, truth.label[static_cast<std::size_t>(v) * camera.width + u])
                    << "frame " << f << " pixel " << u << "," << v;
                if (depthImage.at(u, v) > 0) {
                    ++measured;
                    ASSERT_GT(p.x, 0) << "depth without a label at " << u << "," << v;
                }
            }
        EXPECT_GT(measured, camera.width * camera.height / 2);
    }

    // --no-labels leaves them out.
    fs::remove_all(dir);
    ASSERT_EQ(std::system((std::string("\"") + VOXFUSE_SYNTH_EXE + "\" --out \"" + dir.string() +
                           "\" --frames 1 --width 80 --height 60 --color-samples 1 --no-labels > /dev/null")
                              .c_str()),
              0);
    EXPECT_TRUE(fs::exists(dir / "depth.txt"));
    EXPECT_FALSE(fs::exists(dir / "labels"));
    EXPECT_FALSE(fs::exists(dir / "labels.txt"));
    EXPECT_FALSE(fs::exists(dir / "classes.txt"));

    // An existing sequence is never written into: refused without --overwrite, replaced whole with it.
    auto frameLines = [&] {
        std::ifstream list(dir / "depth.txt");
        int count = 0;
        for (std::string line; std::getline(list, line);) count += !line.empty() && line[0] != '#';
        return count;
    };
    const std::string twoFrames = std::string("\"") + VOXFUSE_SYNTH_EXE + "\" --out \"" + dir.string() +
                                  "\" --frames 2 --width 80 --height 60 --color-samples 1 --no-labels";
    EXPECT_NE(std::system((twoFrames + " > /dev/null 2>&1").c_str()), 0);
    EXPECT_EQ(frameLines(), 1);
    EXPECT_EQ(std::system((twoFrames + " --overwrite > /dev/null").c_str()), 0);
    EXPECT_EQ(frameLines(), 2);
    for (const auto& entry : fs::directory_iterator(dir.parent_path()))
        EXPECT_EQ(entry.path().filename().string().find(".voxfuse_synth_tum_labels.partial-"), std::string::npos)
            << "a staging folder was left";
    fs::remove_all(dir);
}
#else
TEST(VoxfuseSynthTool, ExactPpmDepthConvertsBackWithinHalfAStep) {
    GTEST_SKIP() << "VOXFUSE_SYNTH_EXE (path of voxfuse_synth) not defined for this test binary";
}
TEST(VoxfuseSynthTool, NoisyPpmDepthStaysNearTheTruth) {
    GTEST_SKIP() << "VOXFUSE_SYNTH_EXE (path of voxfuse_synth) not defined for this test binary";
}
TEST(VoxfuseSynthTool, TumLabelImagesAreTheExactClasses) {
    GTEST_SKIP() << "VOXFUSE_SYNTH_EXE (path of voxfuse_synth) not defined for this test binary";
}
#endif
