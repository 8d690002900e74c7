#include "voxfuse/io/ArkitPose.h"

#include <cmath>

namespace voxfuse {

Mat4f poseFromArkit(Vec3f position, Vec4f q) {
    const double n = std::sqrt(double(q.x) * q.x + double(q.y) * q.y + double(q.z) * q.z + double(q.w) * q.w);
    const double x = q.x / n, y = q.y / n, z = q.z / n, w = q.w / n;
    // Rotation matrix of the unit quaternion: ARKit camera axes expressed in the world.
    const double R[3][3] = {{1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)},
                            {2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)},
                            {2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)}};
    // T_world_ours = T_world_arkit * diag(1, -1, -1): our y and z axes are ARKit's -y and -z.
    const double flip[3] = {1.0, -1.0, -1.0};
    Mat4f T = Mat4f::identity();
    for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 3; ++c) T(r, c) = float(R[r][c] * flip[c]);
    T(0, 3) = position.x;
    T(1, 3) = position.y;
    T(2, 3) = position.z;
    return T;
}

}  // namespace voxfuse
