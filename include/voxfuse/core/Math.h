#pragma once
// Plain-old-data vectors and matrices for device-agnostic code.
//
// Why not Eigen here: Eigen 3.4 does compile under nvcc 13, but it floods every kernel with
// warning #20012, its fixed-size vectorisable types impose 16-byte alignment on anything stored in
// device buffers, and it slows nvcc down. These types are trivially copyable (memcpy to/from the GPU
// is safe), and host code converts to Eigen (core/EigenInterop.h) for solves and SE(3) algebra.

#include <cmath>
#include <cstdint>
#include <cstring>

#include "voxfuse/core/Platform.h"

namespace voxfuse {

template <typename T>
struct Vec2 {
    T x, y;
    VF_HOST_DEVICE T& operator[](int i) { return (&x)[i]; }
    VF_HOST_DEVICE const T& operator[](int i) const { return (&x)[i]; }
};

template <typename T>
struct Vec3 {
    T x, y, z;
    VF_HOST_DEVICE T& operator[](int i) { return (&x)[i]; }
    VF_HOST_DEVICE const T& operator[](int i) const { return (&x)[i]; }
};

template <typename T>
struct Vec4 {
    T x, y, z, w;
    VF_HOST_DEVICE T& operator[](int i) { return (&x)[i]; }
    VF_HOST_DEVICE const T& operator[](int i) const { return (&x)[i]; }
    VF_HOST_DEVICE Vec3<T> xyz() const { return {x, y, z}; }
};

using Vec2i = Vec2<int>;
using Vec2f = Vec2<float>;
using Vec3i = Vec3<int>;
using Vec3f = Vec3<float>;
using Vec3u8 = Vec3<std::uint8_t>;
using Vec4f = Vec4<float>;
using Vec4u8 = Vec4<std::uint8_t>;

// ---- Vec3 arithmetic ----
template <typename T>
VF_HOST_DEVICE inline Vec3<T> operator+(Vec3<T> a, Vec3<T> b) {
    return {a.x + b.x, a.y + b.y, a.z + b.z};
}
template <typename T>
VF_HOST_DEVICE inline Vec3<T> operator-(Vec3<T> a, Vec3<T> b) {
    return {a.x - b.x, a.y - b.y, a.z - b.z};
}
template <typename T>
VF_HOST_DEVICE inline Vec3<T> operator-(Vec3<T> a) {
    return {-a.x, -a.y, -a.z};
}
template <typename T>
VF_HOST_DEVICE inline Vec3<T> operator*(Vec3<T> a, T s) {
    return {a.x * s, a.y * s, a.z * s};
}
template <typename T>
VF_HOST_DEVICE inline Vec3<T> operator*(T s, Vec3<T> a) {
    return {a.x * s, a.y * s, a.z * s};
}
template <typename T>
VF_HOST_DEVICE inline Vec3<T> operator/(Vec3<T> a, T s) {
    return {a.x / s, a.y / s, a.z / s};
}
template <typename T>
VF_HOST_DEVICE inline Vec3<T>& operator+=(Vec3<T>& a, Vec3<T> b) {
    a.x += b.x;
    a.y += b.y;
    a.z += b.z;
    return a;
}
template <typename T>
VF_HOST_DEVICE inline Vec3<T>& operator-=(Vec3<T>& a, Vec3<T> b) {
    a.x -= b.x;
    a.y -= b.y;
    a.z -= b.z;
    return a;
}
template <typename T>
VF_HOST_DEVICE inline bool operator==(Vec3<T> a, Vec3<T> b) {
    return a.x == b.x && a.y == b.y && a.z == b.z;
}
template <typename T>
VF_HOST_DEVICE inline bool operator!=(Vec3<T> a, Vec3<T> b) {
    return !(a == b);
}
template <typename T>
VF_HOST_DEVICE inline T dot(Vec3<T> a, Vec3<T> b) {
    return a.x * b.x + a.y * b.y + a.z * b.z;
}
template <typename T>
VF_HOST_DEVICE inline Vec3<T> cross(Vec3<T> a, Vec3<T> b) {
    return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
VF_HOST_DEVICE inline float length(Vec3f a) { return sqrtf(dot(a, a)); }
VF_HOST_DEVICE inline Vec3f normalize(Vec3f a) {
    const float n = length(a);
    return n > 0.f ? a / n : Vec3f{0.f, 0.f, 0.f};
}
VF_HOST_DEVICE inline Vec3f toFloat(Vec3i a) { return {float(a.x), float(a.y), float(a.z)}; }
VF_HOST_DEVICE inline Vec3i floorToInt(Vec3f a) { return {int(floorf(a.x)), int(floorf(a.y)), int(floorf(a.z))}; }

// ---- Vec2 arithmetic ----
template <typename T>
VF_HOST_DEVICE inline Vec2<T> operator+(Vec2<T> a, Vec2<T> b) {
    return {a.x + b.x, a.y + b.y};
}
template <typename T>
VF_HOST_DEVICE inline Vec2<T> operator-(Vec2<T> a, Vec2<T> b) {
    return {a.x - b.x, a.y - b.y};
}
template <typename T>
VF_HOST_DEVICE inline Vec2<T> operator*(Vec2<T> a, T s) {
    return {a.x * s, a.y * s};
}
template <typename T>
VF_HOST_DEVICE inline bool operator==(Vec2<T> a, Vec2<T> b) {
    return a.x == b.x && a.y == b.y;
}
template <typename T>
VF_HOST_DEVICE inline bool operator!=(Vec2<T> a, Vec2<T> b) {
    return !(a == b);
}

// ---- 3x3 and rigid 4x4 matrices, row-major ----
struct Mat3f {
    float m[9];  // m[row * 3 + col]
    VF_HOST_DEVICE float& operator()(int r, int c) { return m[r * 3 + c]; }
    VF_HOST_DEVICE float operator()(int r, int c) const { return m[r * 3 + c]; }
    VF_HOST_DEVICE static Mat3f identity() { return {{1, 0, 0, 0, 1, 0, 0, 0, 1}}; }
};
VF_HOST_DEVICE inline Vec3f operator*(const Mat3f& a, Vec3f v) {
    return {a.m[0] * v.x + a.m[1] * v.y + a.m[2] * v.z, a.m[3] * v.x + a.m[4] * v.y + a.m[5] * v.z,
            a.m[6] * v.x + a.m[7] * v.y + a.m[8] * v.z};
}

// A 4x4 homogeneous transform. Named by its frames where it is used: T_world_camera maps camera
// coordinates to world coordinates.
struct Mat4f {
    float m[16];  // m[row * 4 + col]
    VF_HOST_DEVICE float& operator()(int r, int c) { return m[r * 4 + c]; }
    VF_HOST_DEVICE float operator()(int r, int c) const { return m[r * 4 + c]; }
    VF_HOST_DEVICE static Mat4f identity() { return {{1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1}}; }
    VF_HOST_DEVICE Vec3f translation() const { return {m[3], m[7], m[11]}; }
    VF_HOST_DEVICE Mat3f rotation() const { return {{m[0], m[1], m[2], m[4], m[5], m[6], m[8], m[9], m[10]}}; }
};

// Applies rotation and translation (the point is taken as homogeneous with w = 1).
VF_HOST_DEVICE inline Vec3f transformPoint(const Mat4f& T, Vec3f p) {
    return {T.m[0] * p.x + T.m[1] * p.y + T.m[2] * p.z + T.m[3], T.m[4] * p.x + T.m[5] * p.y + T.m[6] * p.z + T.m[7],
            T.m[8] * p.x + T.m[9] * p.y + T.m[10] * p.z + T.m[11]};
}
// Applies the rotation only (for directions and normals of rigid transforms).
VF_HOST_DEVICE inline Vec3f transformDirection(const Mat4f& T, Vec3f d) {
    return {T.m[0] * d.x + T.m[1] * d.y + T.m[2] * d.z, T.m[4] * d.x + T.m[5] * d.y + T.m[6] * d.z,
            T.m[8] * d.x + T.m[9] * d.y + T.m[10] * d.z};
}
VF_HOST_DEVICE inline Mat4f operator*(const Mat4f& a, const Mat4f& b) {
    Mat4f r{};
    for (int i = 0; i < 4; ++i)
        for (int j = 0; j < 4; ++j) {
            float s = 0.f;
            for (int k = 0; k < 4; ++k) s += a.m[i * 4 + k] * b.m[k * 4 + j];
            r.m[i * 4 + j] = s;
        }
    return r;
}
// Inverse of a rigid transform [R t; 0 1] -> [R^T -R^T t; 0 1].
VF_HOST_DEVICE inline Mat4f rigidInverse(const Mat4f& T) {
    Mat4f r = Mat4f::identity();
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) r.m[i * 4 + j] = T.m[j * 4 + i];
    for (int i = 0; i < 3; ++i)
        r.m[i * 4 + 3] = -(r.m[i * 4 + 0] * T.m[3] + r.m[i * 4 + 1] * T.m[7] + r.m[i * 4 + 2] * T.m[11]);
    return r;
}

template <typename T>
VF_HOST_DEVICE inline T clampValue(T v, T lo, T hi) {
    return v < lo ? lo : (v > hi ? hi : v);
}

// The float whose bits are `bits`.
VF_HOST_DEVICE inline float floatFromBits(std::uint32_t bits) {
#if defined(__CUDA_ARCH__)
    return __uint_as_float(bits);
#else
    float f;
    std::memcpy(&f, &bits, sizeof f);
    return f;
#endif
}

// e^-x for x >= 0, relative error below 3e-7 max(1, x); 0 from x = 87 on and for NaN. Inline
// arithmetic where expf() is a library call on the host: the weights of per-pixel filters need many of
// them, and both devices get the same bits from it.
VF_HOST_DEVICE inline float expOfNegative(float x) {
    // Branch-free, so that loops over pixels vectorise: out-of-range arguments compute on 0.
    const bool in_range = x < 87.f;  // false for NaN
    float y = x > 0.f ? x : 0.f;
    y = in_range ? y * 1.44269504f : 0.f;  // e^-x = 2^-y
    // floor(y) by adding and taking away 2^23 (y + 2^23 rounds y to an integer, y < 126) and stepping
    // down where that rounded up: the same value as int(y), but GCC vectorises this where it would
    // turn float(int(y)) into a truncation and leave the loop scalar (SSE4.1 and AVX2 builds).
    float fl = (y + 8388608.f) - 8388608.f;
    fl = fl > y ? fl - 1.f : fl;
    const int n = int(fl);
    const float f = y - fl;  // 2^-y = 2^-n 2^-f, f in [0, 1)
    // 2^-f, a degree-5 least-squares fit on [0, 1] (relative error 8e-8).
    const float p =
        0.99999994f +
        f * (-0.69314218f + f * (0.24017160f + f * (-0.055278152f + f * (0.0091868825f + f * -0.00093811715f))));
    const float e = p * floatFromBits(std::uint32_t(127 - n) << 23);  // n <= 125: 2^-n is a normal float
    return in_range ? e : 0.f;
}

}  // namespace voxfuse
