#pragma once
// Whether a calibration's values can be a real depth camera's. A value of no real camera (a focal length
// of 1e-20, millimetres given as metres, a lens model that folds the image over itself) is refused: a
// run with it tracks nothing and "succeeds" with an empty map. A value a real camera can have, but
// rarely does, passes with a warning that names it. Each function returns "" when there is nothing to say.

#include <string>
#include <vector>

#include "voxfuse/core/Image.h"
#include "voxfuse/objects/RGBDCalib.h"

namespace voxfuse {

// Refused: focal lengths that give no field of view of 1 to 170 degrees across the image side (fx 0.044
// to 57 times the width).
std::string focalLengthProblem(const Intrinsics& camera);

// Refused: a depth conversion whose 16-bit samples reach no depth between 5 cm and 50 m (every depth
// camera measures inside that span; a scale in the wrong unit misses it by orders of magnitude), or
// whose step between neighbouring samples at 1 m is over 10 cm; an affine offset of a metre or more;
// a Kinect baseline (k2) outside 5 mm to 1 m. `fx_depth`: the depth camera's (the Kinect form uses it).
std::string depthConversionProblem(const DisparityCalib& disparity, float fx_depth);

// Refused: a lens model that is no lens over the image: the distorted radius stops growing with the
// radius (the image folds over itself) inside the nearest image edge, or a corner moves by more than
// its own distance from the principal point.
std::string distortionProblem(const LensDistortion& distortion, const Intrinsics& camera);

// The raw samples of `depth_raw` that are not 0 (no measurement) but that the conversion maps to no depth:
// the Kinect form's at or beyond k1, an affine one's below a negative offset. Such a sample cannot come
// from the camera the calibration describes.
std::size_t depthSamplesWithoutDepth(const Image<std::uint16_t>& depth_raw, const DisparityCalib& disparity,
                                     float fx_depth);

// Warned: values a real camera can have but that are more often a mistake: a depth step outside 0.05
// to 5 mm at 1 m (cameras store 0.1 to 1 mm per unit), an affine offset over 10 cm, a Kinect baseline
// outside 3 to 30 cm, distortion that folds the image between its edges and corners or moves a corner
// by more than a quarter of its radius, colour and depth cameras more than 30 cm apart. One line per
// value, naming it.
std::vector<std::string> calibrationWarnings(const RGBDCalib& calib);

}  // namespace voxfuse
