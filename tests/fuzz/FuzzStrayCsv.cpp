// The CSV files of a Stray Scanner capture: odometry.csv (ARKit poses) and camera_matrix.csv (K);
// the first byte picks the file.

#include <cmath>
#include <cstdlib>

#include "FuzzInput.h"
#include "io/StrayScannerFiles.h"
#include "voxfuse/core/Error.h"
#include "voxfuse/io/ArkitPose.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    using namespace voxfuse;
    if (size < 1) return 0;
    const bool odometry = data[0] & 1;
    const std::string path = fuzz::writeInput(data + 1, size - 1, odometry ? "odometry.csv" : "camera_matrix.csv");
    try {
        if (odometry) {
            for (const stray_scanner::OdometryRow& row : stray_scanner::readOdometry(path)) {
                const Mat4f T = poseFromArkit(row.position, row.quaternion_xyzw);
                for (float v : T.m)
                    if (!std::isfinite(v)) std::abort();  // a pose the engines cannot use got through
            }
        } else {
            stray_scanner::readCameraMatrix(path);
        }
    } catch (const Error&) {
    }
    return 0;
}
