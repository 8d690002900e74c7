#include "voxfuse/io/CalibPlausibility.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "TextParsing.h"

namespace voxfuse {
namespace {

constexpr double kMaxRawDepth = 65535.0;  // depth images hold 16-bit samples

// The depth of raw sample `raw`, as the conversion computes it, without the clamp at zero.
double depthOfRaw(const DisparityCalib& d, float fx_depth, double raw) {
    if (d.type == DisparityCalib::Type::Kinect) return 8.0 * double(d.b) * double(fx_depth) / (double(d.a) - raw);
    return double(d.a) * raw + double(d.b);
}

// The depth step between neighbouring samples at 1 m (metres per raw unit there).
double stepAtOneMetre(const DisparityCalib& d, float fx_depth) {
    if (d.type == DisparityCalib::Type::Kinect) return 1.0 / (8.0 * double(d.b) * double(fx_depth));
    return double(d.a);
}

// Three significant digits: enough to recognise a value in a message.
std::string number(double v) {
    char buffer[32];
    std::snprintf(buffer, sizeof buffer, "%.3g", v);
    return buffer;
}
std::string mm(double metres) { return number(1000.0 * metres) + " mm"; }

// Brown-Conrady on normalised coordinates (x, y): the distorted point.
void distort(const LensDistortion& k, double x, double y, double& xd, double& yd) {
    const double r2 = x * x + y * y;
    const double radial = 1.0 + r2 * (k.k1 + r2 * (k.k2 + r2 * k.k3));
    xd = x * radial + 2.0 * k.p1 * x * y + k.p2 * (r2 + 2.0 * x * x);
    yd = y * radial + k.p1 * (r2 + 2.0 * y * y) + 2.0 * k.p2 * x * y;
}

// The largest displacement of an image corner, as a fraction of its distance from the principal point.
double cornerDisplacement(const LensDistortion& k, const Intrinsics& c) {
    double worst = 0.0;
    for (int i = 0; i < 4; ++i) {
        const double x = ((i & 1) ? c.width - 0.5 - c.cx : -0.5 - c.cx) / c.fx;
        const double y = ((i & 2) ? c.height - 0.5 - c.cy : -0.5 - c.cy) / c.fy;
        double xd, yd;
        distort(k, x, y, xd, yd);
        const double r = std::hypot(x, y);
        if (r > 0.0) worst = std::max(worst, std::hypot(xd - x, yd - y) / r);
    }
    return worst;
}

// The normalised radius of the image corner furthest from the principal point.
double cornerRadius(const Intrinsics& c) {
    const double dx = std::max(c.cx + 0.5, c.width - 0.5 - c.cx) / c.fx;
    const double dy = std::max(c.cy + 0.5, c.height - 0.5 - c.cy) / c.fy;
    return std::hypot(dx, dy);
}

// The normalised radius of the nearest image edge.
double edgeRadius(const Intrinsics& c) {
    return std::min(std::min(c.cx + 0.5, c.width - 0.5 - c.cx) / c.fx,
                    std::min(c.cy + 0.5, c.height - 0.5 - c.cy) / c.fy);
}

// Where the distorted radius r (1 + k1 r^2 + k2 r^4 + k3 r^6) stops growing, out to r_max, or -1 when it
// grows all the way (a factor that reaches zero has shrunk the radius to zero first). Steps of r_max / 512
// follow any real lens's smooth profile.
double foldRadius(const LensDistortion& k, double r_max) {
    double last_rd = 0.0;
    constexpr int kSteps = 512;
    for (int i = 1; i <= kSteps; ++i) {
        const double r = r_max * double(i) / kSteps, r2 = r * r;
        const double rd = r * (1.0 + r2 * (k.k1 + r2 * (k.k2 + r2 * k.k3)));
        if (!(rd > last_rd)) return r;
        last_rd = rd;
    }
    return -1.0;
}

}  // namespace

std::string focalLengthProblem(const Intrinsics& k) {
    // A side of s pixels seen at focal length f spans 2 atan(s / 2f): 170 degrees at f = 0.0437 s,
    // 1 degree at f = 57.3 s.
    const auto implausible = [](float f, int side) {
        return !(f >= 0.0437f * float(side) && f <= 57.3f * float(side));
    };
    if (!implausible(k.fx, k.width) && !implausible(k.fy, k.height)) return "";
    return "focal lengths (" + text::formatFloat(k.fx) + ", " + text::formatFloat(k.fy) +
           " pixels) give no field of view between 1 and " + "170 degrees across the " + std::to_string(k.width) + "x" +
           std::to_string(k.height) + " image (a typo, or units other than pixels?)";
}

std::string depthConversionProblem(const DisparityCalib& d, float fx_depth) {
    const bool kinect = d.type == DisparityCalib::Type::Kinect;
    if (kinect && !(d.b >= 0.005f && d.b <= 1.f))
        return "Kinect baseline k2 " + text::formatFloat(d.b) +
               " m is no depth camera's (5 mm to 1 m; the Kinect's is 7.5 cm)";
    if (!kinect && !(std::abs(d.b) < 1.f))
        return "depth offset " + text::formatFloat(d.b) +
               " m is no depth camera's (under a metre; cameras need a few centimetres at most)";
    // The depths the samples 1 .. 65535 reach (the Kinect form only below k1, where depth is positive).
    const double last = kinect ? std::min(kMaxRawDepth, std::ceil(double(d.a)) - 1.0) : kMaxRawDepth;
    if (last < 1.0)
        return "Kinect disparity offset k1 " + text::formatFloat(d.a) + " leaves no sample a positive depth";
    const double near_m = std::min(depthOfRaw(d, fx_depth, 1.0), depthOfRaw(d, fx_depth, last));
    const double far_m = std::max(depthOfRaw(d, fx_depth, 1.0), depthOfRaw(d, fx_depth, last));
    if (far_m < 0.05 || near_m > 50.0)
        return "the depth samples reach " + number(near_m) + " to " + number(far_m) +
               " m, no depth camera's range (5 cm to 50 m): is the scale in the wrong unit (metres per raw unit: "
               "0.001 for millimetres, 0.0002 for TUM's 1/5000)?";
    const double step = stepAtOneMetre(d, fx_depth);
    if (step > 0.1)
        return "neighbouring depth samples lie " + mm(step) +
               " apart at 1 m, coarser than any depth camera (at most a few mm): is the scale in the wrong unit?";
    return "";
}

std::string distortionProblem(const LensDistortion& k, const Intrinsics& c) {
    if (!k.any()) return "";
    const double fold = foldRadius(k, cornerRadius(c));
    if (fold >= 0.0 && fold < edgeRadius(c))
        return "radial distortion (k1 k2 k3) folds the image over itself " + number(100.0 * fold / edgeRadius(c)) +
               "% of the way to the nearest image edge (the distorted radius stops growing): no lens does that (a "
               "sign, or another model's coefficients?)";
    const double moved = cornerDisplacement(k, c);
    if (!(moved <= 1.0))
        return "distortion moves an image corner by " + number(100.0 * moved) +
               "% of its distance from the principal point: no lens of a depth camera does that";
    return "";
}

std::size_t depthSamplesWithoutDepth(const Image<std::uint16_t>& depth_raw, const DisparityCalib& d, float fx_depth) {
    // An affine conversion without a negative offset gives every sample a depth: nothing to look at.
    if (d.type == DisparityCalib::Type::Affine && d.b >= 0.f) return 0;
    std::size_t count = 0;
    const std::uint16_t* raw = depth_raw.host();
    for (std::size_t i = 0; i < depth_raw.pixelCount(); ++i)
        count += raw[i] != 0 && d.toMetres(raw[i], fx_depth) == 0.f;
    return count;
}

std::vector<std::string> calibrationWarnings(const RGBDCalib& calib) {
    std::vector<std::string> warnings;
    const DisparityCalib& d = calib.disparity;
    const double step = stepAtOneMetre(d, calib.depth.fx);
    if (step < 0.00005 || step > 0.005)
        warnings.push_back("neighbouring depth samples lie " + mm(step) +
                           " apart at 1 m; depth cameras store 0.1 to 1 mm per unit (is the scale right?)");
    if (d.type == DisparityCalib::Type::Affine && std::abs(d.b) > 0.1f)
        warnings.push_back("depth offset " + text::formatFloat(d.b) + " m is large (cameras need a few cm at most)");
    if (d.type == DisparityCalib::Type::Kinect && !(d.b >= 0.03f && d.b <= 0.3f))
        warnings.push_back("Kinect baseline k2 " + text::formatFloat(d.b) +
                           " m is unusual (3 to 30 cm; the Kinect's is 7.5 cm)");
    const struct {
        const char* name;
        const LensDistortion& k;
        const Intrinsics& camera;
    } lenses[] = {{"distortion_rgb", calib.rgb_distortion, calib.rgb},
                  {"distortion_depth", calib.depth_distortion, calib.depth}};
    for (const auto& lens : lenses) {
        if (!lens.k.any() || !lens.camera.valid()) continue;
        // OpenCV's fits, made from the middle of the image, can fold past its edges: the corners are then unusable.
        const double fold = foldRadius(lens.k, cornerRadius(lens.camera));
        if (fold >= 0.0)
            warnings.push_back(std::string(lens.name) +
                               " folds the image over itself between its edges and its corners (a fit that holds "
                               "only in the middle of the image?); the pixels beyond it are unreliable");
        const double moved = cornerDisplacement(lens.k, lens.camera);
        if (moved > 0.25)
            warnings.push_back(std::string(lens.name) + " moves an image corner by " + number(100.0 * moved) +
                               "% of its radius, more than the lenses of depth cameras do (a fisheye model's?)");
    }
    const Mat4f& T = calib.T_depth_rgb;
    const double baseline =
        std::sqrt(double(T(0, 3)) * T(0, 3) + double(T(1, 3)) * T(1, 3) + double(T(2, 3)) * T(2, 3));
    if (baseline > 0.3)
        warnings.push_back("the colour and depth cameras are " + number(baseline) +
                           " m apart (RGB-D cameras: a few cm; are the extrinsics in millimetres?)");
    return warnings;
}

}  // namespace voxfuse
