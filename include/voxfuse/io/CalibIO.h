#pragma once
// InfiniTAM's calib.txt: RGB camera (size, focal lengths, principal point), depth camera (same),
// the 3x4 RGB-to-depth extrinsics, then the disparity calibration as "kinect k1 k2", "affine a b" or
// the bare two numbers "k1 k2" (Kinect form). Blank lines between blocks are optional; whole-line '#'
// comments are allowed. Optional trailing lines "distortion_rgb k1 k2 p1 p2 k3" and
// "distortion_depth k1 k2 p1 p2 k3" give lens distortion (OpenCV's model); files without them are
// undistorted cameras, as before.

#include <string>

#include "voxfuse/io/CalibPlausibility.h"  // what is checked, and why
#include "voxfuse/objects/RGBDCalib.h"

namespace voxfuse {

// Throws IoError if the file cannot be opened, ParseError naming file and line for a malformed or
// missing line (wrong count of numbers, non-numbers, non-positive sizes/focal lengths, unknown
// disparity keyword, trailing garbage).
RGBDCalib readCalib(const std::string& path);
void writeCalib(const std::string& path, const RGBDCalib& calib);

// Well-known calibrations (the same values as the files in calib/).
RGBDCalib kinectV1DefaultCalib();  // 640x480, f 525, c (319.5, 239.5), millimetre depth
RGBDCalib tumCalib(int freiburg);  // 1, 2 or 3; depth PNG scale 5000 (affine 0.0002)

}  // namespace voxfuse
