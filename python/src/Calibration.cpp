// voxfuse.Intrinsics and voxfuse.Calibration (InfiniTAM's calib.txt: both cameras, the RGB-to-depth
// transform, and how raw depth becomes metres).

#include <pybind11/stl.h>

#include <cmath>
#include <sstream>

#include "Bindings.h"
#include "NumpyArrays.h"
#include "voxfuse/core/Error.h"
#include "voxfuse/io/CalibIO.h"
#include "voxfuse/objects/RGBDCalib.h"

namespace voxfuse::python {

namespace {

std::string describe(const Intrinsics& k) {
    std::ostringstream s;
    s << "Intrinsics(width=" << k.width << ", height=" << k.height << ", fx=" << k.fx << ", fy=" << k.fy
      << ", cx=" << k.cx << ", cy=" << k.cy << ")";
    return s.str();
}

RGBDCalib pinhole(int width, int height, float fx, float fy, float cx, float cy, float depth_scale) {
    if (width <= 0 || height <= 0) throw ConfigError("the image size must be positive");
    if (!(fx > 0.f) || !(fy > 0.f)) throw ConfigError("focal lengths must be positive");
    if (!(depth_scale > 0.f) || !std::isfinite(depth_scale))
        throw ConfigError("depth_scale (metres per raw depth unit) must be positive");
    RGBDCalib c;
    c.depth = {width, height, fx, fy, cx, cy};
    c.rgb = c.depth;
    c.disparity = DisparityCalib::affine(depth_scale);
    for (const std::string& problem : {focalLengthProblem(c.depth), depthConversionProblem(c.disparity, fx)})
        if (!problem.empty()) throw ConfigError(problem);
    return c;
}

}  // namespace

float metresPerRawUnit(const RGBDCalib& calib) {
    if (calib.disparity.type != DisparityCalib::Type::Affine || calib.disparity.b != 0.f)
        throw ConfigError(
            "the calibration converts depth by Kinect disparity or with an offset; depth in metres needs a plain "
            "scale");
    return calib.disparity.a;
}

void bindCalibration(py::module_& m) {
    py::class_<Intrinsics>(m, "Intrinsics", "Pinhole intrinsics in pixels (pixel centres at integers).")
        .def(py::init([](int width, int height, float fx, float fy, float cx, float cy) {
                 return Intrinsics{width, height, fx, fy, cx, cy};
             }),
             py::arg("width"), py::arg("height"), py::arg("fx"), py::arg("fy"), py::arg("cx"), py::arg("cy"))
        .def_readwrite("width", &Intrinsics::width)
        .def_readwrite("height", &Intrinsics::height)
        .def_readwrite("fx", &Intrinsics::fx)
        .def_readwrite("fy", &Intrinsics::fy)
        .def_readwrite("cx", &Intrinsics::cx)
        .def_readwrite("cy", &Intrinsics::cy)
        .def_property_readonly(
            "K",
            [](const Intrinsics& k) {
                py::array_t<double> K({3, 3});
                auto a = K.mutable_unchecked<2>();
                for (int r = 0; r < 3; ++r)
                    for (int c = 0; c < 3; ++c) a(r, c) = 0.0;
                a(0, 0) = k.fx, a(1, 1) = k.fy, a(0, 2) = k.cx, a(1, 2) = k.cy, a(2, 2) = 1.0;
                return K;
            },
            "The 3x3 camera matrix.")
        .def("__repr__", &describe);

    py::class_<RGBDCalib>(
        m, "Calibration",
        "An RGB-D camera pair: depth and colour intrinsics, the colour-to-depth transform and the depth scale.\n\n"
        "Make one with Calibration.pinhole(...), read InfiniTAM's calib.txt with Calibration.from_file(path), or take\n"
        "a source's (Source.calib).")
        .def_static("pinhole", &pinhole, py::arg("width"), py::arg("height"), py::arg("fx"), py::arg("fy"),
                    py::arg("cx"), py::arg("cy"), py::arg("depth_scale") = 0.001f,
                    "One camera for depth and colour (registered depth): raw depth * depth_scale = metres (0.001 for\n"
                    "millimetres, 0.0002 for TUM's PNGs).")
        .def_static("from_file", &readCalib, py::arg("path"), "Reads InfiniTAM's calib.txt format.")
        .def(
            "save", [](const RGBDCalib& c, const std::string& path) { writeCalib(path, c); }, py::arg("path"),
            "Writes InfiniTAM's calib.txt format.")
        .def_readwrite("depth", &RGBDCalib::depth, "The depth camera's intrinsics (the frames' geometry).")
        .def_readwrite("rgb", &RGBDCalib::rgb, "The colour camera's intrinsics.")
        .def_property(
            "T_depth_rgb", [](const RGBDCalib& c) { return matrixToArray(c.T_depth_rgb); },
            [](RGBDCalib& c, const py::handle& T) { c.T_depth_rgb = arrayToMatrix(T, "T_depth_rgb"); },
            "4x4 transform from colour-camera to depth-camera coordinates.")
        .def_property_readonly(
            "depth_scale", [](const RGBDCalib& c) { return metresPerRawUnit(c); },
            "Metres per raw depth unit (ConfigError for a Kinect disparity calibration).")
        .def("__repr__", [](const RGBDCalib& c) {
            return "Calibration(depth=" + describe(c.depth) + ", rgb=" + describe(c.rgb) + ")";
        });
}

}  // namespace voxfuse::python
