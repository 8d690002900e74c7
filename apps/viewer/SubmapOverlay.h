#pragma once
// Where the submaps and the edges joining them appear over the model panel: each submap's origin (the
// camera that started it), a line to the submap it started from (odometry), and one for each loop
// closure the pose graph kept (those it rejected are left out). Pure geometry, header-only, so that
// tests check it without a window.

#include <vector>

#include "PanelLayout.h"
#include "voxfuse/engines/MainEngine.h"

namespace voxfuse::viewer {

struct OverlaySegment {
    Vec2f from, to;  // window pixels
    bool loop = false;
};

struct SubmapOverlay {
    std::vector<Vec2f> origins;  // window pixels of the origins in front of the camera
    std::vector<OverlaySegment> segments;
};

// Points nearer the camera than this (or behind it) are not drawn: a line through the camera has no
// picture.
constexpr float kOverlayNearM = 0.05f;

// `image` is where the panel shows a render of `camera` from T_world_camera (fitAspect of the panel).
inline SubmapOverlay projectSubmaps(const std::vector<SubmapPose>& submaps, const std::vector<LoopClosure>& loops,
                                    const Mat4f& T_world_camera, const Intrinsics& camera, const PanelRect& image) {
    SubmapOverlay overlay;
    const Mat4f T_camera_world = rigidInverse(T_world_camera);
    const float sx = float(image.width) / float(camera.width), sy = float(image.height) / float(camera.height);
    std::vector<char> visible(submaps.size(), 0);
    std::vector<Vec2f> at(submaps.size());
    for (std::size_t i = 0; i < submaps.size(); ++i) {
        const Vec3f p = transformPoint(T_camera_world, submaps[i].T_world_submap.translation());
        if (p.z < kOverlayNearM) continue;
        const Vec2f uv = camera.project(p);
        // Pixel centres: pixel u covers [u - 0.5, u + 0.5) of the image, [x + u sx, x + (u + 1) sx) of the panel.
        at[i] = Vec2f{float(image.x) + (uv.x + 0.5f) * sx, float(image.y) + (uv.y + 0.5f) * sy};
        visible[i] = 1;
        overlay.origins.push_back(at[i]);
    }
    const auto join = [&](int a, int b, bool loop) {
        if (a < 0 || b < 0 || a >= int(submaps.size()) || b >= int(submaps.size())) return;
        if (visible[std::size_t(a)] && visible[std::size_t(b)])
            overlay.segments.push_back({at[std::size_t(a)], at[std::size_t(b)], loop});
    };
    for (std::size_t i = 0; i < submaps.size(); ++i) join(submaps[i].parent, int(i), false);
    for (const LoopClosure& l : loops)
        if (!l.rejected) join(l.from_submap, l.to_submap, true);
    return overlay;
}

}  // namespace voxfuse::viewer
