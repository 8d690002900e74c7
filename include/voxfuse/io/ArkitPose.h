#pragma once
// Camera poses from Apple's ARKit (iPhone/iPad LiDAR captures) in VoxFuse's camera convention.
//
// ARKit's camera looks along its -z axis with x to the right and y up; ours looks along +z with x
// to the right and y down (the OpenCV/pinhole convention of the intrinsics). Both cameras share
// their centre, so only the camera axes differ: y and z flip. The world frame stays ARKit's (metres,
// y up against gravity, origin where the session started).

#include "voxfuse/core/Math.h"

namespace voxfuse {

// T_world_camera in our camera convention from an ARKit camera-to-world pose given as a position
// and a rotation quaternion (x, y, z, w), as in Stray Scanner's odometry.csv. The quaternion is
// normalised; the caller rejects zero-length or non-finite ones.
Mat4f poseFromArkit(Vec3f position, Vec4f quaternion_xyzw);

}  // namespace voxfuse
