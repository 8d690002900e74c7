#pragma once
// Internal: the two CSV files of a Stray Scanner capture. Both are comma-separated; every malformed
// line is a ParseError naming file and line.

#include <string>
#include <vector>

#include "voxfuse/core/Math.h"

namespace voxfuse {
namespace stray_scanner {

// camera_matrix.csv: the 3x3 K of the colour camera at the video's full resolution, one row per line.
struct CameraMatrix {
    double fx, fy, cx, cy;
};
CameraMatrix readCameraMatrix(const std::string& path);

// odometry.csv: ARKit camera-to-world poses, one row per frame, with a header naming the columns
// ("timestamp, frame, x, y, z, qx, qy, qz, qw"; columns are found by name, so their order and extra
// columns do not matter). Without a "frame" column, row i belongs to frame i. A file without a header
// must have exactly those nine columns in that order.
struct OdometryRow {
    double timestamp_s;
    int frame;
    Vec3f position;         // metres, ARKit world
    Vec4f quaternion_xyzw;  // normalised
};
std::vector<OdometryRow> readOdometry(const std::string& path);

}  // namespace stray_scanner
}  // namespace voxfuse
