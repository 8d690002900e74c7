// The tracker factory and the quality rules every tracker shares.

#include "voxfuse/engines/Tracker.h"

#include "voxfuse/engines/ColorTracker.h"
#include "voxfuse/engines/DepthTracker.h"

namespace voxfuse {

std::unique_ptr<Tracker> makeTracker(const TrackerSettings& settings, Device device) {
    validateTrackerSettings(settings);
    // Every tracker runs its loops on the CPU until CUDA layers land (the host side is device-agnostic).
    if (settings.kind == TrackerKind::Color) return makeColorTracker(settings, device);
    return makeDepthTracker(settings, device);
}

TrackingQuality assessTrackingQuality(const TrackerSettings& s, const TrackingMeasures& m) {
    // Written as !(x >= threshold) so that a NaN fails.
    if (m.inliers < s.min_inliers || !(m.inlier_ratio >= s.failed_inlier_ratio) || !(m.condition >= s.failed_condition) ||
        !(m.color_rms <= s.failed_color_residual) || !(m.motion_m <= s.max_motion_m) || !(m.motion_deg <= s.max_motion_deg))
        return TrackingQuality::Failed;
    if (m.inlier_ratio < s.good_inlier_ratio || m.condition < s.good_condition || !(m.depth_rms_m <= s.poor_residual_m))
        return TrackingQuality::Poor;
    return TrackingQuality::Good;
}

}  // namespace voxfuse
