// The tracker factory and the quality rules every tracker shares.

#include "voxfuse/engines/Tracker.h"

#include <algorithm>

#include "voxfuse/core/Error.h"

#include "voxfuse/engines/ColorTracker.h"
#include "voxfuse/engines/DepthTracker.h"
#include "voxfuse/engines/LowLevelEngine.h"

namespace voxfuse {

std::unique_ptr<Tracker> makeTracker(const TrackerSettings& settings, Device device) {
    validateTrackerSettings(settings);
    if (settings.kind == TrackerKind::Color) return makeColorTracker(settings, device);
    return makeDepthTracker(settings, device);
}

bool hasTrackableSurface(const RenderState& model, LowLevelEngine& low_level) {
    const Vec2i size = model.intrinsics.size();
    if (!model.intrinsics.valid() || model.points_world.size() != size || model.normals_world.size() != size)
        return false;
    return low_level.countValidPoints(model.points_world) > 0;
}

TrackingQuality assessTrackingQuality(const TrackerSettings& s, const TrackingMeasures& m) {
    // Written as !(x >= threshold) so that a NaN fails.
    if (m.inliers < s.min_inliers || !(m.inlier_ratio >= s.failed_inlier_ratio) ||
        !(m.condition >= s.failed_condition) || !(m.color_rms <= s.failed_color_residual) ||
        !(m.motion_m <= s.max_motion_m) || !(m.motion_deg <= s.max_motion_deg))
        return TrackingQuality::Failed;
    if (m.inlier_ratio < s.good_inlier_ratio || m.condition < s.good_condition ||
        m.translation_constraint < s.poor_translation_constraint || !(m.depth_rms_m <= s.poor_residual_m))
        return TrackingQuality::Poor;
    return TrackingQuality::Good;
}

}  // namespace voxfuse
