// The array helpers every binding shares (NumpyArrays.h).

#include "NumpyArrays.h"

#include <cmath>

namespace voxfuse::python {

std::string shapeText(const py::array& a) {
    std::string s = "(";
    for (py::ssize_t i = 0; i < a.ndim(); ++i) s += (i ? ", " : "") + std::to_string(a.shape(i));
    return s + (a.ndim() == 1 ? ",)" : ")");
}

Mat4f arrayToMatrix(const py::handle& value, const char* what) {
    py::array_t<double, py::array::c_style | py::array::forcecast> a;
    try {
        a = py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(value);
    } catch (const py::error_already_set&) {
        a = {};
    }
    if (!a || a.ndim() != 2 || a.shape(0) != 4 || a.shape(1) != 4)
        throw py::value_error(std::string(what) + " must be a 4x4 matrix" +
                              (a ? ", not of shape " + shapeText(a) : std::string()));
    Mat4f T;
    const auto m = a.unchecked<2>();
    for (int r = 0; r < 4; ++r)
        for (int c = 0; c < 4; ++c) {
            if (!std::isfinite(m(r, c))) throw py::value_error(std::string(what) + " has a value that is not finite");
            T(r, c) = float(m(r, c));
        }
    if (T(3, 0) != 0.f || T(3, 1) != 0.f || T(3, 2) != 0.f || T(3, 3) != 1.f)
        throw py::value_error(std::string(what) + " must be a rigid transform (last row 0 0 0 1)");
    return T;
}

py::tuple timedPosesToArrays(const std::vector<TimedPose>& poses) {
    const std::size_t n = poses.size();
    py::array_t<double> t(std::vector<py::ssize_t>{py::ssize_t(n)});
    py::array_t<double> p({py::ssize_t(n), py::ssize_t(4), py::ssize_t(4)});
    auto ta = t.mutable_unchecked<1>();
    auto pa = p.mutable_unchecked<3>();
    for (std::size_t i = 0; i < n; ++i) {
        ta(py::ssize_t(i)) = poses[i].timestamp_s;
        for (int r = 0; r < 4; ++r)
            for (int c = 0; c < 4; ++c) pa(py::ssize_t(i), r, c) = double(poses[i].T_world_camera(r, c));
    }
    return py::make_tuple(t, p);
}

}  // namespace voxfuse::python
