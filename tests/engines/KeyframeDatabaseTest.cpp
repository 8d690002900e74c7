// The keyframe database: novel codes only, bounded, nearest first; and on exact synthetic views a
// revisited place finds the keyframe taken nearest to it, with that keyframe's pose.

#include <gtest/gtest.h>

#include <cmath>

#include "SyntheticViews.h"
#include "TrackingTestSupport.h"
#include "voxfuse/core/Error.h"
#include "voxfuse/engines/KeyframeDatabase.h"

namespace voxfuse {
namespace {

// A code whose ferns are all `value`, with the first `changed` of them set to `other`.
FernCode code(std::uint8_t value, int changed = 0, std::uint8_t other = 15) {
    FernCode c(100, value);
    for (int i = 0; i < changed; ++i) c[std::size_t(i)] = other;
    return c;
}

Mat4f at(float x_m) {
    Mat4f T = Mat4f::identity();
    T(0, 3) = x_m;
    return T;
}

TEST(KeyframeDatabaseTest, StoresOnlyCodesUnlikeEveryKeyframe) {
    KeyframeDatabase db(10);
    EXPECT_TRUE(db.addIfNovel(code(1), at(0.f), 0, 0.2f));
    EXPECT_FALSE(db.addIfNovel(code(1), at(1.f), 1, 0.2f)) << "the same view twice";
    EXPECT_FALSE(db.addIfNovel(code(1, 19), at(1.f), 2, 0.2f)) << "19% of the ferns differ: too alike";
    EXPECT_TRUE(db.addIfNovel(code(1, 20), at(2.f), 3, 0.2f)) << "20% differ: a new view";
    EXPECT_TRUE(db.addIfNovel(code(7), at(3.f), 4, 0.2f));
    ASSERT_EQ(db.size(), 3);
    EXPECT_EQ(db.keyframe(1).frame_index, 3);
    EXPECT_EQ(db.keyframe(1).T_world_camera(0, 3), 2.f);
}

TEST(KeyframeDatabaseTest, NearestComeFirstAndEquallyNearInStoredOrder) {
    KeyframeDatabase db(10);
    db.addIfNovel(code(1), at(0.f), 0, 0.f);
    db.addIfNovel(code(1, 50, 3), at(1.f), 1, 0.f);
    db.addIfNovel(code(1, 30, 5), at(2.f), 2, 0.f);
    db.addIfNovel(code(1, 50, 9), at(3.f), 3, 0.f);
    const std::vector<KeyframeMatch> m = db.nearest(code(1, 10), 3);
    ASSERT_EQ(m.size(), 3u);
    EXPECT_EQ(m[0].keyframe, 0);
    EXPECT_FLOAT_EQ(m[0].dissimilarity, 0.1f);
    EXPECT_EQ(m[1].keyframe, 2);
    EXPECT_EQ(m[2].keyframe, 1) << "1 and 3 are equally near: the older first";
    EXPECT_EQ(db.nearest(code(1), 10).size(), 4u);
    EXPECT_TRUE(KeyframeDatabase(3).nearest(code(1), 2).empty());
}

TEST(KeyframeDatabaseTest, IsBoundedAndReplacesTheOldest) {
    KeyframeDatabase db(3);
    for (std::uint8_t v = 0; v < 5; ++v) EXPECT_TRUE(db.addIfNovel(code(v), at(float(v)), v, 0.2f));
    EXPECT_EQ(db.size(), 3);
    EXPECT_EQ(db.capacity(), 3);
    EXPECT_GT(db.nearest(code(0), 1).front().dissimilarity, 0.f) << "the oldest two made room";
    EXPECT_GT(db.nearest(code(1), 1).front().dissimilarity, 0.f);
    for (std::uint8_t v = 2; v < 5; ++v) {
        const KeyframeMatch m = db.nearest(code(v), 1).front();
        EXPECT_EQ(m.dissimilarity, 0.f);
        EXPECT_EQ(db.keyframe(m.keyframe).frame_index, v);
    }
    // Equally near keyframes come oldest first also after the slots wrapped around.
    const std::vector<KeyframeMatch> all = db.nearest(code(9), 3);
    EXPECT_EQ(db.keyframe(all[0].keyframe).frame_index, 2);
    EXPECT_EQ(db.keyframe(all[2].keyframe).frame_index, 4);
    db.clear();
    EXPECT_EQ(db.size(), 0);
    EXPECT_THROW(KeyframeDatabase(0), ConfigError);
}

// The room from `degrees` along a circle around its objects (exact depth and colour).
struct RoomView {
    Mat4f T_world_camera;
    View view;
};
RoomView roomView(float degrees) {
    static const synth::SyntheticScene room = synth::SyntheticScene::defaultRoom();
    const Eigen::Vector3f target{0.1f, 0.05f, 0.6f};
    const float a = degrees * float(EIGEN_PI) / 180.f;
    const Mat4f T = test::lookAt(target + Eigen::Vector3f(1.6f * std::cos(a), 1.6f * std::sin(a), 0.85f), target);
    return {T, test::renderView(room, test::kinectIntrinsics(160, 120), T)};
}

TEST(KeyframeDatabaseTest, ARevisitedViewFindsTheKeyframeTakenNearestToIt) {
    // Half a lap in 2-degree steps: keyframes wherever the view has changed enough.
    FernEncoder encoder(FernSettings{}, {160, 120}, true);
    KeyframeDatabase db(1000);
    for (int step = 0; step < 90; ++step) {
        const RoomView v = roomView(180.f + 2.f * float(step));
        db.addIfNovel(encoder.encode(v.view.depth, v.view.rgb), v.T_world_camera, step, 0.2f);
    }
    std::printf("[ keyframes] half a lap of 90 views: %d keyframes\n", db.size());
    EXPECT_GT(db.size(), 10) << "half a lap shows many different views";
    EXPECT_LT(db.size(), 60) << "neighbouring views are alike";

    // Views between those of the way, all along it: the best match is the keyframe nearest in pose.
    int nearest_found = 0, queries = 0;
    for (float degrees = 185.f; degrees < 358.f; degrees += 15.f, ++queries) {
        const RoomView q = roomView(degrees);
        const KeyframeMatch best = db.nearest(encoder.encode(q.view.depth, q.view.rgb), 1).front();
        float nearest_m = 1e9f;
        for (int i = 0; i < db.size(); ++i)
            nearest_m = std::min(nearest_m, test::translationErrorM(db.keyframe(i).T_world_camera, q.T_world_camera));
        const float found_m = test::translationErrorM(db.keyframe(best.keyframe).T_world_camera, q.T_world_camera);
        nearest_found += found_m <= nearest_m + 1e-4f;
        EXPECT_LT(found_m, 0.25f) << "at " << degrees << " degrees: the match lies " << found_m << " m away";
        EXPECT_LT(best.dissimilarity, 0.5f);
    }
    EXPECT_GE(nearest_found, queries - 2) << "nearly always the very nearest keyframe";
}

TEST(KeyframeDatabaseTest, BuildingTheSameDatabaseTwiceGivesTheSameKeyframes) {
    std::vector<RoomView> views;
    for (int step = 0; step < 20; ++step) views.push_back(roomView(180.f + 3.f * float(step)));
    auto build = [&] {
        FernEncoder encoder(FernSettings{}, {160, 120}, true);
        KeyframeDatabase db(8);
        for (std::size_t i = 0; i < views.size(); ++i)
            db.addIfNovel(encoder.encode(views[i].view.depth, views[i].view.rgb), views[i].T_world_camera, int(i),
                          0.2f);
        return db;
    };
    const KeyframeDatabase a = build(), b = build();
    ASSERT_EQ(a.size(), b.size());
    for (int i = 0; i < a.size(); ++i) {
        EXPECT_EQ(a.keyframe(i).frame_index, b.keyframe(i).frame_index);
        EXPECT_EQ(a.keyframe(i).code, b.keyframe(i).code);
    }
}

}  // namespace
}  // namespace voxfuse
