#pragma once
// Hand-over between the library's containers and NumPy. Outputs are not copied: the container moves
// to the heap and the array keeps it alive through a capsule (its `base`). Inputs are checked for
// dtype and shape, with errors that name the argument; a wrong dtype is a TypeError, never a cast.

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "voxfuse/core/Image.h"
#include "voxfuse/core/Math.h"
#include "voxfuse/io/TrajectoryIO.h"

namespace voxfuse::python {

namespace py = pybind11;

// An array over `data`, which lives as long as `owner` does; the array holds a reference to `owner`.
template <class TScalar, class TOwner>
py::array viewOf(const std::shared_ptr<TOwner>& owner, const TScalar* data, std::vector<py::ssize_t> shape,
                 std::vector<py::ssize_t> strides_bytes) {
    auto* keep = new std::shared_ptr<TOwner>(owner);
    py::capsule base(keep, [](void* p) { delete static_cast<std::shared_ptr<TOwner>*>(p); });
    static const TScalar no_data{};
    return py::array_t<TScalar>(std::move(shape), std::move(strides_bytes), data ? data : &no_data, base);
}

// (N, kComponents) rows over a vector of small structs (Vec3f -> float32 (N, 3)); (N,) for one component.
template <class TScalar, int kComponents, class TElement, class TOwner>
py::array rowsOf(const std::shared_ptr<TOwner>& owner, const std::vector<TElement>& v) {
    static_assert(sizeof(TElement) == kComponents * sizeof(TScalar), "elements must be packed scalars");
    const auto* data = reinterpret_cast<const TScalar*>(v.data());
    const auto n = py::ssize_t(v.size());
    if (kComponents == 1) return viewOf<TScalar>(owner, data, {n}, {py::ssize_t(sizeof(TScalar))});
    return viewOf<TScalar>(owner, data, {n, kComponents},
                           {py::ssize_t(sizeof(TElement)), py::ssize_t(sizeof(TScalar))});
}

// An image as (H, W) or, for pixels of several channels, (H, W, channels) without a copy. `channels`
// may be fewer than the pixel holds (RGBA seen as RGB: a stride of 4 bytes per pixel).
template <class TScalar, class TPixel>
py::array imageToArray(Image<TPixel>&& image, int channels) {
    auto owner = std::make_shared<Image<TPixel>>(std::move(image));
    const auto h = py::ssize_t(owner->height()), w = py::ssize_t(owner->width());
    const auto* data = reinterpret_cast<const TScalar*>(owner->host());
    const auto px = py::ssize_t(sizeof(TPixel)), s = py::ssize_t(sizeof(TScalar));
    if (channels == 1) return viewOf<TScalar>(owner, data, {h, w}, {w * px, px});
    return viewOf<TScalar>(owner, data, {h, w, channels}, {w * px, px, s});
}

inline py::array_t<double> matrixToArray(const Mat4f& T) {
    py::array_t<double> a({4, 4});
    auto m = a.mutable_unchecked<2>();
    for (int r = 0; r < 4; ++r)
        for (int c = 0; c < 4; ++c) m(r, c) = double(T(r, c));
    return a;
}

// A 4x4 rigid transform from any real array; ValueError naming `what` otherwise.
Mat4f arrayToMatrix(const py::handle& value, const char* what);

// `value` as a C-contiguous array of T (copied only when its strides need it). TypeError naming `what`
// when it is not an array of exactly that dtype.
template <class T>
py::array_t<T, py::array::c_style> requireDtype(const py::handle& value, const char* what, const char* dtype_name) {
    if (!py::isinstance<py::array>(value))
        throw py::type_error(std::string(what) + " must be a numpy array of " + dtype_name + ", not " +
                             std::string(py::str(py::type::of(value).attr("__name__"))));
    py::array a = py::reinterpret_borrow<py::array>(value);
    if (!py::isinstance<py::array_t<T>>(a))
        throw py::type_error(std::string(what) + " must be " + dtype_name + ", not " + std::string(py::str(a.dtype())));
    return py::array_t<T, py::array::c_style>::ensure(a);
}

// "(480, 640)": an array's shape for error messages.
std::string shapeText(const py::array& a);

// (timestamps (N,), camera-to-world poses (N, 4, 4)) from the library's timed poses.
py::tuple timedPosesToArrays(const std::vector<TimedPose>& poses);

}  // namespace voxfuse::python
