#include "SyntheticScene.h"

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <limits>
#include <sstream>
#include <stdexcept>

#include "voxfuse/core/CpuThreads.h"

namespace voxfuse::synth {
namespace {

constexpr float kInf = std::numeric_limits<float>::infinity();
constexpr float kPi = 3.14159265358979f;
// Rectangles accept hits this far beyond their edges, so that walls meeting at
// a corner leave no crack for rays to slip through.
constexpr float kEdgeTolerance = 1e-4f;

// ---------------------------------------------------------------- textures

std::uint32_t hashInts(int x, int y, int z, std::uint32_t seed) {
    std::uint32_t h = seed * 0x9E3779B1u + 0x7F4A7C15u;
    for (std::uint32_t v :
         {static_cast<std::uint32_t>(x), static_cast<std::uint32_t>(y), static_cast<std::uint32_t>(z)}) {
        h ^= v + 0x9E3779B9u + (h << 6) + (h >> 2);
        h ^= h >> 16;
        h *= 0x85EBCA6Bu;
        h ^= h >> 13;
        h *= 0xC2B2AE35u;
        h ^= h >> 16;
    }
    return h;
}

float hashToUnit(std::uint32_t h) { return static_cast<float>(h >> 8) * (1.0f / 16777216.0f); }

// Smooth value noise in [0, 1]: trilinear blend of random lattice values.
float valueNoise(const Eigen::Vector3f& p, std::uint32_t seed) {
    const Eigen::Vector3f cell = p.array().floor();
    const Eigen::Vector3f f = p - cell;
    const Eigen::Vector3f w = f.array() * f.array() * (3.0f - 2.0f * f.array());
    const int ix = static_cast<int>(cell.x()), iy = static_cast<int>(cell.y()), iz = static_cast<int>(cell.z());
    float result = 0.0f;
    for (int corner = 0; corner < 8; ++corner) {
        const int dx = corner & 1, dy = (corner >> 1) & 1, dz = (corner >> 2) & 1;
        const float weight = (dx ? w.x() : 1.0f - w.x()) * (dy ? w.y() : 1.0f - w.y()) * (dz ? w.z() : 1.0f - w.z());
        result += weight * hashToUnit(hashInts(ix + dx, iy + dy, iz + dz, seed));
    }
    return result;
}

// Three octaves of value noise, normalised to [0, 1].
float fractalNoise(const Eigen::Vector3f& p, std::uint32_t seed) {
    return (valueNoise(p, seed) * 0.5714f + valueNoise(2.0f * p, seed + 1) * 0.2857f +
            valueNoise(4.0f * p, seed + 2) * 0.1429f);
}

int floorInt(float v) { return static_cast<int>(std::floor(v)); }

const char* textureName(TextureKind kind) {
    switch (kind) {
        case TextureKind::Solid:
            return "solid";
        case TextureKind::Checker:
            return "checker";
        case TextureKind::Stripes:
            return "stripes";
        case TextureKind::Noise:
            return "noise";
        case TextureKind::Wood:
            return "wood";
        case TextureKind::Poster:
            return "poster";
    }
    return "solid";
}

TextureKind textureFromName(const std::string& name) {
    for (TextureKind kind : {TextureKind::Solid, TextureKind::Checker, TextureKind::Stripes, TextureKind::Noise,
                             TextureKind::Wood, TextureKind::Poster})
        if (name == textureName(kind)) return kind;
    throw std::runtime_error("scene: unknown texture '" + name + "'");
}

const char* primitiveName(PrimitiveKind kind) {
    switch (kind) {
        case PrimitiveKind::Rectangle:
            return "rectangle";
        case PrimitiveKind::Box:
            return "box";
        case PrimitiveKind::Sphere:
            return "sphere";
        case PrimitiveKind::Cylinder:
            return "cylinder";
    }
    return "sphere";
}

int sizeParameterCount(PrimitiveKind kind) {
    switch (kind) {
        case PrimitiveKind::Rectangle:
            return 2;
        case PrimitiveKind::Box:
            return 3;
        case PrimitiveKind::Sphere:
            return 1;
        case PrimitiveKind::Cylinder:
            return 2;
    }
    return 1;
}

// ------------------------------------------------- local-frame ray casting
// Each routine finds the nearest t in (tMin, tMax) and the outward normal.

bool intersectRectangle(const Eigen::Vector3f& size, const Eigen::Vector3f& o, const Eigen::Vector3f& d, float tMin,
                        float tMax, float& t, Eigen::Vector3f& n) {
    if (d.z() == 0.0f) return false;
    const float tHit = -o.z() / d.z();
    if (!(tHit > tMin && tHit < tMax)) return false;
    if (std::abs(o.x() + tHit * d.x()) > size.x() + kEdgeTolerance ||
        std::abs(o.y() + tHit * d.y()) > size.y() + kEdgeTolerance)
        return false;
    t = tHit;
    n = Eigen::Vector3f::UnitZ();
    return true;
}

bool intersectSphere(const Eigen::Vector3f& size, const Eigen::Vector3f& o, const Eigen::Vector3f& d, float tMin,
                     float tMax, float& t, Eigen::Vector3f& n) {
    const float r = size.x();
    const float a = d.squaredNorm(), b = o.dot(d), c = o.squaredNorm() - r * r;
    const float disc = b * b - a * c;
    if (disc < 0.0f || a == 0.0f) return false;
    // Numerically stable pair of roots.
    const float q = -(b + std::copysign(std::sqrt(disc), b));
    float t0 = q / a, t1 = (q != 0.0f) ? c / q : t0;
    if (t0 > t1) std::swap(t0, t1);
    const float tHit = (t0 > tMin) ? t0 : t1;
    if (!(tHit > tMin && tHit < tMax)) return false;
    t = tHit;
    n = (o + tHit * d) / r;
    return true;
}

bool intersectBox(const Eigen::Vector3f& size, const Eigen::Vector3f& o, const Eigen::Vector3f& d, float tMin,
                  float tMax, float& t, Eigen::Vector3f& n) {
    float tNear = -kInf, tFar = kInf;
    int nearAxis = -1, farAxis = -1;
    for (int i = 0; i < 3; ++i) {
        if (d[i] == 0.0f) {
            if (std::abs(o[i]) > size[i]) return false;
            continue;
        }
        float t0 = (-size[i] - o[i]) / d[i], t1 = (size[i] - o[i]) / d[i];
        if (t0 > t1) std::swap(t0, t1);
        if (t0 > tNear) {
            tNear = t0;
            nearAxis = i;
        }
        if (t1 < tFar) {
            tFar = t1;
            farAxis = i;
        }
    }
    if (tNear > tFar) return false;
    if (tNear > tMin && tNear < tMax && nearAxis >= 0) {  // entering from outside
        t = tNear;
        n = Eigen::Vector3f::Zero();
        n[nearAxis] = d[nearAxis] > 0.0f ? -1.0f : 1.0f;
        return true;
    }
    if (tFar > tMin && tFar < tMax && farAxis >= 0) {  // leaving from inside
        t = tFar;
        n = Eigen::Vector3f::Zero();
        n[farAxis] = d[farAxis] > 0.0f ? 1.0f : -1.0f;
        return true;
    }
    return false;
}

bool intersectCylinder(const Eigen::Vector3f& size, const Eigen::Vector3f& o, const Eigen::Vector3f& d, float tMin,
                       float tMax, float& t, Eigen::Vector3f& n) {
    const float r = size.x(), halfHeight = size.y();
    bool found = false;
    float best = tMax;
    // Curved side.
    const float a = d.x() * d.x() + d.y() * d.y();
    if (a > 0.0f) {
        const float b = o.x() * d.x() + o.y() * d.y();
        const float c = o.x() * o.x() + o.y() * o.y() - r * r;
        const float disc = b * b - a * c;
        if (disc >= 0.0f) {
            const float sq = std::sqrt(disc);
            for (float tc : {(-b - sq) / a, (-b + sq) / a}) {
                if (tc > tMin && tc < best && std::abs(o.z() + tc * d.z()) <= halfHeight) {
                    best = tc;
                    const Eigen::Vector3f p = o + tc * d;
                    n = Eigen::Vector3f(p.x(), p.y(), 0.0f) / r;
                    found = true;
                }
            }
        }
    }
    // Caps.
    if (d.z() != 0.0f) {
        for (float capZ : {-halfHeight, halfHeight}) {
            const float tc = (capZ - o.z()) / d.z();
            if (tc > tMin && tc < best) {
                const Eigen::Vector3f p = o + tc * d;
                if (p.x() * p.x() + p.y() * p.y() <= r * r) {
                    best = tc;
                    n = Eigen::Vector3f(0.0f, 0.0f, capZ > 0.0f ? 1.0f : -1.0f);
                    found = true;
                }
            }
        }
    }
    if (found) t = best;
    return found;
}

bool intersectLocal(const Primitive& prim, const Eigen::Vector3f& o, const Eigen::Vector3f& d, float tMin, float tMax,
                    float& t, Eigen::Vector3f& n) {
    switch (prim.kind) {
        case PrimitiveKind::Rectangle:
            return intersectRectangle(prim.size, o, d, tMin, tMax, t, n);
        case PrimitiveKind::Box:
            return intersectBox(prim.size, o, d, tMin, tMax, t, n);
        case PrimitiveKind::Sphere:
            return intersectSphere(prim.size, o, d, tMin, tMax, t, n);
        case PrimitiveKind::Cylinder:
            return intersectCylinder(prim.size, o, d, tMin, tMax, t, n);
    }
    return false;
}

// Unsigned distance from a local point to the primitive's surface.
float distanceLocal(const Primitive& prim, const Eigen::Vector3f& p) {
    const Eigen::Vector3f& s = prim.size;
    switch (prim.kind) {
        case PrimitiveKind::Rectangle: {
            const float dx = std::max(std::abs(p.x()) - s.x(), 0.0f);
            const float dy = std::max(std::abs(p.y()) - s.y(), 0.0f);
            return std::sqrt(dx * dx + dy * dy + p.z() * p.z());
        }
        case PrimitiveKind::Box: {
            const Eigen::Vector3f q = p.cwiseAbs() - s;
            const float outside = q.cwiseMax(0.0f).norm();
            const float inside = std::min(q.maxCoeff(), 0.0f);
            return std::abs(outside + inside);
        }
        case PrimitiveKind::Sphere:
            return std::abs(p.norm() - s.x());
        case PrimitiveKind::Cylinder: {
            const float radial = std::hypot(p.x(), p.y()) - s.x();
            const float axial = std::abs(p.z()) - s.y();
            const float outside = std::hypot(std::max(radial, 0.0f), std::max(axial, 0.0f));
            const float inside = std::min(std::max(radial, axial), 0.0f);
            return std::abs(outside + inside);
        }
    }
    return kInf;
}

// Shortest text that reads back as the same float ("0.3", not "0.300000012").
std::string formatFloat(float value) {
    if (value == 0.0f) return "0";  // also turns -0 into 0
    char buffer[32];
    const auto result = std::to_chars(buffer, buffer + sizeof(buffer), value);
    return std::string(buffer, result.ptr);
}

std::string formatVector(const Eigen::Vector3f& v) {
    return formatFloat(v.x()) + " " + formatFloat(v.y()) + " " + formatFloat(v.z());
}

Eigen::Vector3f gammaEncode(const Eigen::Vector3f& linear) {
    Eigen::Vector3f out;
    for (int c = 0; c < 3; ++c) out[c] = std::pow(std::clamp(linear[c], 0.0f, 1.0f), 1.0f / 2.2f);
    return out;
}

Eigen::Quaternionf yaw(float degrees) {
    return Eigen::Quaternionf(Eigen::AngleAxisf(degrees * kPi / 180.0f, Eigen::Vector3f::UnitZ()));
}

}  // namespace

Texture makeTexture(TextureKind kind, const Eigen::Vector3f& a, const Eigen::Vector3f& b, float scale,
                    std::uint32_t seed) {
    Texture tex;
    tex.kind = kind;
    tex.colorA = a;
    tex.colorB = b;
    tex.scale = scale;
    tex.seed = seed;
    return tex;
}

// -------------------------------------------------------------------- Texture

Eigen::Vector3f Texture::albedo(const Eigen::Vector3f& p) const {
    const Eigen::Vector3f q = p / scale;
    switch (kind) {
        case TextureKind::Solid:
            return colorA;
        case TextureKind::Checker:
            return ((floorInt(q.x()) + floorInt(q.y()) + floorInt(q.z())) & 1) ? colorB : colorA;
        case TextureKind::Stripes:
            return (floorInt(q.x()) & 1) ? colorB : colorA;
        case TextureKind::Noise: {
            const float n = fractalNoise(q, seed);
            return colorA + (colorB - colorA) * std::clamp(1.6f * (n - 0.5f) + 0.5f, 0.0f, 1.0f);
        }
        case TextureKind::Wood: {
            // Growth rings around an axis parallel to local y, off to one side,
            // distorted by noise: reads as planks along y.
            const float ring = std::hypot(q.x() + 7.3f, q.z() + 3.1f) +
                               1.5f * fractalNoise(Eigen::Vector3f(q.x(), 0.15f * q.y(), q.z()), seed);
            const float band = 0.5f + 0.5f * std::sin(2.0f * kPi * ring);
            return colorA + (colorB - colorA) * (band * band);
        }
        case TextureKind::Poster: {
            // Random blocks in four colours: high-contrast corners and edges.
            const std::uint32_t h = hashInts(floorInt(q.x()), floorInt(q.y()), 0, seed);
            switch (h & 3u) {
                case 0:
                    return colorA;
                case 1:
                    return colorB;
                case 2:
                    return Eigen::Vector3f(0.05f, 0.05f, 0.05f);
                default:
                    return Eigen::Vector3f(0.92f, 0.92f, 0.9f);
            }
        }
    }
    return colorA;
}

// --------------------------------------------------------------- PinholeCamera

PinholeCamera PinholeCamera::kinectV1(int width, int height) {
    PinholeCamera cam;
    const float sx = width / 640.0f, sy = height / 480.0f;
    cam.width = width;
    cam.height = height;
    cam.fx = 525.0f * sx;
    cam.fy = 525.0f * sy;
    cam.cx = (319.5f + 0.5f) * sx - 0.5f;  // scale about the image corner, not pixel 0
    cam.cy = (239.5f + 0.5f) * sy - 0.5f;
    return cam;
}

Eigen::Quaternionf rotationFromNormal(const Eigen::Vector3f& normal) {
    const Eigen::Vector3f z = normal.normalized();
    const Eigen::Vector3f reference = std::abs(z.z()) > 0.99f ? Eigen::Vector3f::UnitY() : Eigen::Vector3f::UnitZ();
    const Eigen::Vector3f x = reference.cross(z).normalized();
    Eigen::Matrix3f R;
    R.col(0) = x;
    R.col(1) = z.cross(x);
    R.col(2) = z;
    return Eigen::Quaternionf(R).normalized();
}

// ------------------------------------------------------------- SyntheticScene

int SyntheticScene::add(const Primitive& primitive) {
    Primitive prim = primitive;
    // Normalise only when needed, so a scene read back from scene.txt is
    // bit-identical to the one that was written.
    if (std::abs(prim.rotation.squaredNorm() - 1.0f) > 1e-6f) prim.rotation.normalize();
    primitives_.push_back(prim);
    const Eigen::Vector3f& s = prim.size;
    float bound = kInf;
    switch (prim.kind) {
        case PrimitiveKind::Rectangle:
            bound = std::hypot(s.x(), s.y());
            break;
        case PrimitiveKind::Box:
            bound = s.norm();
            break;
        case PrimitiveKind::Sphere:
            bound = s.x();
            break;
        case PrimitiveKind::Cylinder:
            bound = std::hypot(s.x(), s.y());
            break;
    }
    // A margin for rounding: a sphere a little too large only costs a test.
    placements_.push_back(
        {prim.rotation.toRotationMatrix(), prim.translation, std::isfinite(bound) ? bound * 1.001f + 1e-4f : kInf});
    return static_cast<int>(primitives_.size()) - 1;
}

bool SyntheticScene::mayHit(const Placement& pl, const Eigen::Vector3f& o, const Eigen::Vector3f& d, float tMin,
                            float tMax) {
    if (!std::isfinite(pl.bound_radius)) return true;
    const Eigen::Vector3f oc = pl.t_world_local - o;
    const float dd = d.squaredNorm();
    if (!(dd > 0.0f)) return true;
    const float tClosest = oc.dot(d) / dd;
    const float miss2 = (oc - tClosest * d).squaredNorm();
    const float r2 = pl.bound_radius * pl.bound_radius;
    if (miss2 > r2) return false;
    const float halfChord = std::sqrt((r2 - miss2) / dd);  // in units of t
    return tClosest + halfChord >= tMin && tClosest - halfChord <= tMax;
}

int SyntheticScene::addPlane(const Eigen::Vector3f& point, const Eigen::Vector3f& normal, const Texture& texture,
                             std::uint16_t classId) {
    return addRectangle(point, normal, kInf, kInf, texture, classId);
}

int SyntheticScene::addRectangle(const Eigen::Vector3f& center, const Eigen::Vector3f& normal, float halfWidth,
                                 float halfHeight, const Texture& texture, std::uint16_t classId) {
    Primitive prim;
    prim.kind = PrimitiveKind::Rectangle;
    prim.size = Eigen::Vector3f(halfWidth, halfHeight, 0.0f);
    prim.translation = center;
    prim.rotation = rotationFromNormal(normal);
    prim.texture = texture;
    prim.classId = classId;
    return add(prim);
}

int SyntheticScene::addBox(const Eigen::Vector3f& center, const Eigen::Quaternionf& rotation,
                           const Eigen::Vector3f& halfExtents, const Texture& texture, std::uint16_t classId) {
    Primitive prim;
    prim.kind = PrimitiveKind::Box;
    prim.size = halfExtents;
    prim.translation = center;
    prim.rotation = rotation;
    prim.texture = texture;
    prim.classId = classId;
    return add(prim);
}

int SyntheticScene::addSphere(const Eigen::Vector3f& center, float radius, const Texture& texture,
                              std::uint16_t classId) {
    Primitive prim;
    prim.kind = PrimitiveKind::Sphere;
    prim.size = Eigen::Vector3f(radius, 0.0f, 0.0f);
    prim.translation = center;
    prim.texture = texture;
    prim.classId = classId;
    return add(prim);
}

int SyntheticScene::addCylinder(const Eigen::Vector3f& center, const Eigen::Quaternionf& rotation, float radius,
                                float halfHeight, const Texture& texture, std::uint16_t classId) {
    Primitive prim;
    prim.kind = PrimitiveKind::Cylinder;
    prim.size = Eigen::Vector3f(radius, halfHeight, 0.0f);
    prim.translation = center;
    prim.rotation = rotation;
    prim.texture = texture;
    prim.classId = classId;
    return add(prim);
}

void SyntheticScene::addClass(std::uint16_t id, const std::string& name) {
    if (id == kUnlabelled) throw std::invalid_argument("scene: class id 0 means unlabelled");
    if (name.empty() || std::any_of(name.begin(), name.end(), [](unsigned char c) { return std::isspace(c) != 0; }))
        throw std::invalid_argument("scene: class name '" + name + "' is not one word");
    const auto at = std::lower_bound(classes_.begin(), classes_.end(), id,
                                     [](const SemanticClass& c, std::uint16_t v) { return c.id < v; });
    if (at != classes_.end() && at->id == id)
        at->name = name;
    else
        classes_.insert(at, SemanticClass{id, name});
}

bool SyntheticScene::intersect(const Eigen::Vector3f& origin, const Eigen::Vector3f& dir, Hit& hit) const {
    return intersect(origin, dir, hit, 1e-5f, kInf);
}

bool SyntheticScene::intersect(const Eigen::Vector3f& origin, const Eigen::Vector3f& dir, Hit& hit, float tMin,
                               float tMax) const {
    int best = -1;
    float bestT = tMax;
    Eigen::Vector3f bestNormalLocal = Eigen::Vector3f::Zero();
    for (std::size_t i = 0; i < primitives_.size(); ++i) {
        const Placement& pl = placements_[i];
        if (!mayHit(pl, origin, dir, tMin, bestT)) continue;
        const Eigen::Vector3f o = pl.R_world_local.transpose() * (origin - pl.t_world_local);
        const Eigen::Vector3f d = pl.R_world_local.transpose() * dir;
        float t;
        Eigen::Vector3f n;
        if (intersectLocal(primitives_[i], o, d, tMin, bestT, t, n)) {
            best = static_cast<int>(i);
            bestT = t;
            bestNormalLocal = n;
        }
    }
    if (best < 0) return false;
    const Placement& pl = placements_[best];
    const Eigen::Vector3f pLocal = pl.R_world_local.transpose() * (origin + bestT * dir - pl.t_world_local);
    hit.t = bestT;
    hit.primitive = best;
    // Sample the texture just inside the surface so that solid patterns whose
    // cell borders coincide with a face do not flicker.
    hit.albedo_rgb = primitives_[best].texture.albedo(pLocal - 1e-4f * bestNormalLocal);
    hit.normal = (pl.R_world_local * bestNormalLocal).normalized();
    if (hit.normal.dot(dir) > 0.0f) hit.normal = -hit.normal;
    return true;
}

bool SyntheticScene::occluded(const Eigen::Vector3f& origin, const Eigen::Vector3f& dir, float tMin, float tMax) const {
    for (std::size_t i = 0; i < primitives_.size(); ++i) {
        const Placement& pl = placements_[i];
        if (!mayHit(pl, origin, dir, tMin, tMax)) continue;
        const Eigen::Vector3f o = pl.R_world_local.transpose() * (origin - pl.t_world_local);
        const Eigen::Vector3f d = pl.R_world_local.transpose() * dir;
        float t;
        Eigen::Vector3f n;
        if (intersectLocal(primitives_[i], o, d, tMin, tMax, t, n)) return true;
    }
    return false;
}

float SyntheticScene::distanceToSurface(const Eigen::Vector3f& p_world) const {
    float best = kInf;
    for (std::size_t i = 0; i < primitives_.size(); ++i) {
        const Placement& pl = placements_[i];
        const Eigen::Vector3f p = pl.R_world_local.transpose() * (p_world - pl.t_world_local);
        best = std::min(best, distanceLocal(primitives_[i], p));
    }
    return best;
}

Eigen::Vector3f SyntheticScene::shade(const Eigen::Vector3f& point, const Hit& hit) const {
    float irradiance = ambient_;
    const Eigen::Vector3f start = point + 1e-4f * hit.normal;
    for (const PointLight& light : lights_) {
        const Eigen::Vector3f toLight = light.position - start;
        const float distance = toLight.norm();
        const float cosine = hit.normal.dot(toLight) / distance;
        if (cosine <= 0.0f || occluded(start, toLight, 1e-5f, 1.0f - 1e-5f)) continue;
        irradiance += light.intensity * cosine / std::max(distance * distance, 0.25f);
    }
    return hit.albedo_rgb * irradiance;
}

RenderedFrame SyntheticScene::render(const PinholeCamera& camera, const Eigen::Isometry3f& T_world_camera,
                                     int colorSamples) const {
    RenderedFrame frame;
    render(camera, T_world_camera, colorSamples, frame);
    return frame;
}

void SyntheticScene::render(const PinholeCamera& camera, const Eigen::Isometry3f& T_world_camera, int colorSamples,
                            RenderedFrame& frame) const {
    frame.width = camera.width;
    frame.height = camera.height;
    const std::size_t count = static_cast<std::size_t>(camera.width) * camera.height;
    frame.depth.assign(count, 0.0f);
    frame.cosIncidence.assign(count, 0.0f);
    frame.rgb.assign(count, Eigen::Vector3f::Zero());
    frame.label.assign(count, kUnlabelled);
    const Eigen::Matrix3f R = T_world_camera.linear();
    const Eigen::Vector3f origin = T_world_camera.translation();
    const int n = std::max(colorSamples, 1);

    // A row per task, on the library's CPU threads (not a second set of threads beside them).
    forEachCpuTask(camera.height, [&](int v) {
        for (int u = 0; u < camera.width; ++u) {
            const std::size_t idx = static_cast<std::size_t>(v) * camera.width + u;
            // Camera ray with z = 1, so the hit parameter is the depth itself.
            const Eigen::Vector3f dir = R * camera.ray(static_cast<float>(u), static_cast<float>(v));
            Hit hit;
            const bool found = intersect(origin, dir, hit);
            if (found) {
                frame.depth[idx] = hit.t;
                frame.cosIncidence[idx] = std::abs(hit.normal.dot(dir)) / dir.norm();
                frame.label[idx] = primitives_[hit.primitive].classId;
            }
            Eigen::Vector3f color = Eigen::Vector3f::Zero();
            if (n == 1) {
                // The one colour sample is the depth ray itself (du = dv = 0): its hit is the one above.
                if (found) color = shade(origin + hit.t * dir, hit);
            } else {
                for (int sy = 0; sy < n; ++sy) {
                    for (int sx = 0; sx < n; ++sx) {
                        const float du = (sx + 0.5f) / n - 0.5f, dv = (sy + 0.5f) / n - 0.5f;
                        const Eigen::Vector3f sampleDir = R * camera.ray(u + du, v + dv);
                        Hit sample;
                        if (intersect(origin, sampleDir, sample)) color += shade(origin + sample.t * sampleDir, sample);
                    }
                }
            }
            frame.rgb[idx] = gammaEncode(color / static_cast<float>(n * n));
        }
    });
}

// ------------------------------------------------------------------ factories

SyntheticScene SyntheticScene::defaultRoom() {
    using V = Eigen::Vector3f;
    namespace rc = room_class;
    SyntheticScene scene;
    const float hx = 2.5f, hy = 2.0f, height = 2.7f;
    scene.addClass(rc::kFloor, "floor");
    scene.addClass(rc::kWall, "wall");
    scene.addClass(rc::kCeiling, "ceiling");
    scene.addClass(rc::kTable, "table");
    scene.addClass(rc::kBall, "ball");
    scene.addClass(rc::kCylinder, "cylinder");
    scene.addClass(rc::kBox, "box");
    scene.addClass(rc::kPoster, "poster");

    // Room shell, all normals pointing inwards.
    scene.addRectangle(V(0, 0, 0), V(0, 0, 1), hx, hy,
                       makeTexture(TextureKind::Checker, V(0.78f, 0.72f, 0.62f), V(0.45f, 0.38f, 0.30f), 0.5f),
                       rc::kFloor);
    scene.addRectangle(V(0, 0, height), V(0, 0, -1), hx, hy,
                       makeTexture(TextureKind::Noise, V(0.92f, 0.92f, 0.90f), V(0.75f, 0.75f, 0.72f), 0.4f, 11),
                       rc::kCeiling);
    scene.addRectangle(V(hx, 0, height / 2), V(-1, 0, 0), hy, height / 2,
                       makeTexture(TextureKind::Noise, V(0.85f, 0.80f, 0.68f), V(0.60f, 0.55f, 0.45f), 0.25f, 12),
                       rc::kWall);
    scene.addRectangle(V(-hx, 0, height / 2), V(1, 0, 0), hy, height / 2,
                       makeTexture(TextureKind::Noise, V(0.70f, 0.80f, 0.85f), V(0.45f, 0.55f, 0.62f), 0.25f, 13),
                       rc::kWall);
    scene.addRectangle(V(0, hy, height / 2), V(0, -1, 0), hx, height / 2,
                       makeTexture(TextureKind::Stripes, V(0.80f, 0.84f, 0.74f), V(0.62f, 0.70f, 0.56f), 0.15f),
                       rc::kWall);
    scene.addRectangle(V(0, -hy, height / 2), V(0, 1, 0), hx, height / 2,
                       makeTexture(TextureKind::Noise, V(0.88f, 0.75f, 0.75f), V(0.62f, 0.48f, 0.50f), 0.25f, 14),
                       rc::kWall);

    // Posters: 2 cm deep frames on every wall, so any view has strong texture.
    const Texture posterBase = makeTexture(TextureKind::Poster, V(0.85f, 0.15f, 0.10f), V(0.10f, 0.30f, 0.80f), 0.1f);
    struct PosterSpec {
        V center;
        V normal;
        float halfW, halfH;
        std::uint32_t seed;
    };
    const PosterSpec posters[] = {
        {V(hx - 0.01f, 0.3f, 1.2f), V(-1, 0, 0), 0.6f, 0.4f, 21},
        {V(-hx + 0.01f, -0.4f, 1.2f), V(1, 0, 0), 0.5f, 0.4f, 22},
        {V(-0.6f, hy - 0.01f, 1.25f), V(0, -1, 0), 0.55f, 0.35f, 23},
        {V(0.7f, -hy + 0.01f, 1.2f), V(0, 1, 0), 0.6f, 0.45f, 24},
    };
    for (const PosterSpec& p : posters) {
        Texture tex = posterBase;
        tex.seed = p.seed;
        scene.addBox(p.center, rotationFromNormal(p.normal), V(p.halfW, p.halfH, 0.01f), tex, rc::kPoster);
    }

    // Table: wooden top on four legs.
    const V tableCenter(0.15f, 0.1f, 0.73f);
    const V tableHalf(0.55f, 0.35f, 0.02f);
    scene.addBox(tableCenter, yaw(0), tableHalf,
                 makeTexture(TextureKind::Wood, V(0.62f, 0.42f, 0.22f), V(0.38f, 0.22f, 0.10f), 0.04f, 31), rc::kTable);
    for (float sx : {-1.0f, 1.0f})
        for (float sy : {-1.0f, 1.0f})
            scene.addBox(V(tableCenter.x() + sx * (tableHalf.x() - 0.06f),
                           tableCenter.y() + sy * (tableHalf.y() - 0.06f), 0.355f),
                         yaw(0), V(0.025f, 0.025f, 0.355f),
                         makeTexture(TextureKind::Solid, V(0.25f, 0.18f, 0.12f), V::Zero(), 1.0f), rc::kTable);
    const float tableTop = tableCenter.z() + tableHalf.z();

    // Objects on the table.
    scene.addBox(V(-0.05f, 0.2f, tableTop + 0.1f), yaw(30), V(0.1f, 0.1f, 0.1f),
                 makeTexture(TextureKind::Checker, V(0.90f, 0.20f, 0.15f), V(0.95f, 0.95f, 0.90f), 0.05f), rc::kBox);
    scene.addSphere(V(0.45f, 0.25f, tableTop + 0.11f), 0.11f,
                    makeTexture(TextureKind::Noise, V(0.15f, 0.30f, 0.85f), V(0.70f, 0.85f, 1.00f), 0.05f, 41),
                    rc::kBall);
    scene.addBox(V(0.35f, -0.1f, tableTop + 0.03f), yaw(-15), V(0.12f, 0.08f, 0.03f),
                 makeTexture(TextureKind::Stripes, V(0.95f, 0.80f, 0.10f), V(0.20f, 0.20f, 0.25f), 0.02f), rc::kBox);

    // Objects on the floor.
    scene.addBox(V(-0.75f, -0.55f, 0.2f), yaw(25), V(0.25f, 0.2f, 0.2f),
                 makeTexture(TextureKind::Stripes, V(0.20f, 0.60f, 0.30f), V(0.90f, 0.90f, 0.80f), 0.06f), rc::kBox);
    scene.addSphere(V(0.8f, -0.6f, 0.18f), 0.18f,
                    makeTexture(TextureKind::Checker, V(0.95f, 0.55f, 0.10f), V(0.15f, 0.15f, 0.20f), 0.07f),
                    rc::kBall);
    scene.addCylinder(V(-0.6f, 0.7f, 0.35f), yaw(0), 0.12f, 0.35f,
                      makeTexture(TextureKind::Wood, V(0.75f, 0.55f, 0.35f), V(0.45f, 0.28f, 0.15f), 0.03f, 51),
                      rc::kCylinder);

    scene.addLight({V(0.8f, 0.5f, 2.5f), 2.5f});
    scene.addLight({V(-1.2f, -0.8f, 2.5f), 1.8f});
    scene.setAmbient(0.3f);
    return scene;
}

SyntheticScene SyntheticScene::corridor(float length_m) {
    using V = Eigen::Vector3f;
    namespace rc = room_class;
    SyntheticScene scene;
    const float hy = 1.2f, height = 2.6f, hx = 0.5f * length_m;
    scene.addClass(rc::kFloor, "floor");
    scene.addClass(rc::kWall, "wall");
    scene.addClass(rc::kCeiling, "ceiling");
    scene.addClass(rc::kBox, "box");
    scene.addClass(rc::kPoster, "poster");
    scene.addClass(rc::kCylinder, "cylinder");
    const V centre(hx, 0, 0);
    scene.addRectangle(centre, V(0, 0, 1), hx, hy,
                       makeTexture(TextureKind::Checker, V(0.78f, 0.72f, 0.62f), V(0.45f, 0.38f, 0.30f), 0.4f),
                       rc::kFloor);
    scene.addRectangle(centre + V(0, 0, height), V(0, 0, -1), hx, hy,
                       makeTexture(TextureKind::Noise, V(0.92f, 0.92f, 0.90f), V(0.75f, 0.75f, 0.72f), 0.4f, 61),
                       rc::kCeiling);
    scene.addRectangle(centre + V(0, hy, height / 2), V(0, -1, 0), hx, height / 2,
                       makeTexture(TextureKind::Noise, V(0.85f, 0.80f, 0.68f), V(0.60f, 0.55f, 0.45f), 0.25f, 62),
                       rc::kWall);
    scene.addRectangle(centre + V(0, -hy, height / 2), V(0, 1, 0), hx, height / 2,
                       makeTexture(TextureKind::Stripes, V(0.80f, 0.84f, 0.74f), V(0.62f, 0.70f, 0.56f), 0.15f),
                       rc::kWall);
    scene.addRectangle(V(0, 0, height / 2), V(1, 0, 0), hy, height / 2,
                       makeTexture(TextureKind::Noise, V(0.70f, 0.80f, 0.85f), V(0.45f, 0.55f, 0.62f), 0.25f, 63),
                       rc::kWall);
    scene.addRectangle(V(length_m, 0, height / 2), V(-1, 0, 0), hy, height / 2,
                       makeTexture(TextureKind::Noise, V(0.88f, 0.75f, 0.75f), V(0.62f, 0.48f, 0.50f), 0.25f, 64),
                       rc::kWall);
    // Every 1.5 m a poster on one wall and an object on the floor by the other, so that every view
    // has texture and shape to track.
    const Texture poster = makeTexture(TextureKind::Poster, V(0.85f, 0.15f, 0.10f), V(0.10f, 0.30f, 0.80f), 0.1f);
    int k = 0;
    for (float x = 0.8f; x < length_m - 0.5f; x += 1.5f, ++k) {
        const float side = (k % 2) ? 1.f : -1.f;
        Texture tex = poster;
        tex.seed = std::uint32_t(70 + k);
        scene.addBox(V(x, side * (hy - 0.01f), 1.3f + 0.2f * float(k % 3) - 0.2f), rotationFromNormal(V(0, -side, 0)),
                     V(0.45f, 0.35f, 0.01f), tex, rc::kPoster);
        if (k % 3 == 2)
            scene.addCylinder(V(x + 0.4f, -side * (hy - 0.3f), 0.4f), yaw(0), 0.15f, 0.4f,
                              makeTexture(TextureKind::Wood, V(0.75f, 0.55f, 0.35f), V(0.45f, 0.28f, 0.15f), 0.03f,
                                          std::uint32_t(90 + k)),
                              rc::kCylinder);
        else
            scene.addBox(V(x + 0.4f, -side * (hy - 0.35f), 0.25f), yaw(float(20 * k)), V(0.25f, 0.2f, 0.25f),
                         makeTexture(TextureKind::Checker, V(0.90f, 0.20f + 0.1f * float(k % 4), 0.15f),
                                     V(0.95f, 0.95f, 0.90f), 0.06f),
                         rc::kBox);
    }
    // Pilasters on both walls, between the posters. Walls, floor and ceiling are parallel to the
    // corridor's axis, so depth constrains motion along it only through the objects, and a view turned
    // towards one wall may see none of them: depth tracking then slides along the corridor (as it does
    // in real ones). With a pilaster every 1.5 m on each side, every view has surfaces facing the axis.
    const Texture plaster = makeTexture(TextureKind::Noise, V(0.82f, 0.80f, 0.76f), V(0.66f, 0.64f, 0.60f), 0.2f, 65);
    for (float x = 1.55f; x < length_m - 0.3f; x += 1.5f)
        for (const float side : {-1.f, 1.f})
            scene.addBox(V(x, side * (hy - 0.04f), height / 2), Eigen::Quaternionf::Identity(),
                         V(0.12f, 0.04f, height / 2), plaster, rc::kWall);
    for (float x = 2.f; x < length_m; x += 4.f) scene.addLight({V(x, 0.f, height - 0.1f), 2.0f});
    scene.setAmbient(0.35f);
    return scene;
}

SyntheticScene SyntheticScene::singlePlane(const Eigen::Vector3f& point, const Eigen::Vector3f& normal) {
    SyntheticScene scene;
    scene.addClass(room_class::kFloor, "floor");  // whatever its orientation
    scene.addPlane(
        point, normal,
        makeTexture(TextureKind::Checker, Eigen::Vector3f(0.8f, 0.8f, 0.8f), Eigen::Vector3f(0.2f, 0.2f, 0.2f), 0.1f),
        room_class::kFloor);
    scene.addLight({point + 2.0f * normal.normalized(), 2.0f});
    return scene;
}

SyntheticScene SyntheticScene::singleSphere(const Eigen::Vector3f& center, float radius) {
    SyntheticScene scene;
    scene.addClass(room_class::kBall, "ball");
    scene.addSphere(center, radius,
                    makeTexture(TextureKind::Checker, Eigen::Vector3f(0.9f, 0.3f, 0.2f),
                                Eigen::Vector3f(0.9f, 0.9f, 0.9f), radius / 3.0f),
                    room_class::kBall);
    scene.addLight({center + Eigen::Vector3f(1.0f, -1.0f, 2.0f), 2.0f});
    return scene;
}

SyntheticScene SyntheticScene::boxAndSphere() {
    using V = Eigen::Vector3f;
    namespace rc = room_class;
    SyntheticScene scene;
    scene.addClass(rc::kFloor, "floor");
    scene.addClass(rc::kBall, "ball");
    scene.addClass(rc::kBox, "box");
    scene.addPlane(V::Zero(), V::UnitZ(),
                   makeTexture(TextureKind::Checker, V(0.8f, 0.75f, 0.7f), V(0.4f, 0.35f, 0.3f), 0.25f), rc::kFloor);
    scene.addBox(V(0, 0, 0.2f), Eigen::Quaternionf::Identity(), V(0.2f, 0.2f, 0.2f),
                 makeTexture(TextureKind::Stripes, V(0.2f, 0.6f, 0.3f), V(0.9f, 0.9f, 0.8f), 0.05f), rc::kBox);
    scene.addSphere(V(0.6f, 0, 0.15f), 0.15f,
                    makeTexture(TextureKind::Noise, V(0.15f, 0.3f, 0.85f), V(0.7f, 0.85f, 1.0f), 0.05f, 7), rc::kBall);
    scene.addLight({V(0.5f, -0.5f, 2.0f), 2.5f});
    return scene;
}

// ------------------------------------------------------------------------- IO

void SyntheticScene::write(const std::string& path) const {
    std::ofstream out(path);
    if (!out) throw std::runtime_error("scene: cannot write " + path);
    out << "# VoxFuse synthetic scene (voxfuse_synth). Units: metres.\n"
           "# World frame: z up, floor at z = 0. Cameras use the OpenCV/TUM convention\n"
           "# (x right, y down, z forward); poses elsewhere are camera-to-world.\n"
           "# ambient <a>\n"
           "# light <x y z> <intensity at 1 m>\n"
           "# class <id> <name>   (semantic class: id >= 1, as label images store it; 0 = unlabelled)\n"
           "# <type> <size...> pose <tx ty tz qx qy qz qw> texture <kind> <rA gA bA> <rB gB bB> <scale> <seed> class "
           "<id>\n"
           "#   rectangle <half_x half_y>   (local z = 0, normal local +z; inf = infinite plane)\n"
           "#   box <half_x half_y half_z>\n"
           "#   sphere <radius>\n"
           "#   cylinder <radius half_height>  (capped, axis local z)\n"
           "#   pose = world_from_local; texture kinds: solid checker stripes noise wood poster\n";
    out << "ambient " << formatFloat(ambient_) << "\n";
    for (const PointLight& light : lights_)
        out << "light " << formatVector(light.position) << " " << formatFloat(light.intensity) << "\n";
    for (const SemanticClass& c : classes_) out << "class " << c.id << " " << c.name << "\n";
    for (const Primitive& p : primitives_) {
        out << primitiveName(p.kind);
        for (int i = 0; i < sizeParameterCount(p.kind); ++i) out << " " << formatFloat(p.size[i]);
        out << " pose " << formatVector(p.translation) << " " << formatFloat(p.rotation.x()) << " "
            << formatFloat(p.rotation.y()) << " " << formatFloat(p.rotation.z()) << " " << formatFloat(p.rotation.w());
        const Texture& t = p.texture;
        out << " texture " << textureName(t.kind) << " " << formatVector(t.colorA) << " " << formatVector(t.colorB)
            << " " << formatFloat(t.scale) << " " << t.seed << " class " << p.classId << "\n";
    }
    if (!out) throw std::runtime_error("scene: error writing " + path);
}

SyntheticScene SyntheticScene::read(const std::string& path) {
    std::ifstream in(path);
    if (!in) throw std::runtime_error("scene: cannot read " + path);
    SyntheticScene scene;
    std::string line;
    int lineNumber = 0;
    while (std::getline(in, line)) {
        ++lineNumber;
        std::istringstream tokens(line);
        std::vector<std::string> words;
        for (std::string w; tokens >> w;) words.push_back(w);
        if (words.empty() || words[0][0] == '#') continue;

        std::size_t next = 1;
        const auto fail = [&](const std::string& why) {
            return std::runtime_error("scene: " + path + ":" + std::to_string(lineNumber) + ": " + why);
        };
        const auto word = [&]() -> const std::string& {
            if (next >= words.size()) throw fail("line too short");
            return words[next++];
        };
        const auto number = [&]() {
            const std::string& w = word();
            char* end = nullptr;
            const float value = std::strtof(w.c_str(), &end);  // accepts "inf"
            if (end == w.c_str() || *end != '\0') throw fail("bad number '" + w + "'");
            return value;
        };
        const auto vec3 = [&]() {
            const float x = number(), y = number(), z = number();
            return Eigen::Vector3f(x, y, z);
        };
        const auto expect = [&](const char* keyword) {
            if (word() != keyword) throw fail(std::string("expected '") + keyword + "'");
        };
        const auto classId = [&]() {
            const std::string& w = word();
            char* end = nullptr;
            const unsigned long value = std::strtoul(w.c_str(), &end, 10);
            if (end == w.c_str() || *end != '\0' || !std::isdigit(static_cast<unsigned char>(w[0])) || value > 0xFFFFul)
                throw fail("bad class id '" + w + "'");
            return static_cast<std::uint16_t>(value);
        };

        const std::string& type = words[0];
        if (type == "ambient") {
            scene.setAmbient(number());
        } else if (type == "light") {
            PointLight light;
            light.position = vec3();
            light.intensity = number();
            scene.addLight(light);
        } else if (type == "class") {
            const std::uint16_t id = classId();
            const std::string& name = word();
            if (id == kUnlabelled) throw fail("class id 0 means unlabelled");
            scene.addClass(id, name);
        } else {
            Primitive prim;
            if (type == "rectangle")
                prim.kind = PrimitiveKind::Rectangle;
            else if (type == "box")
                prim.kind = PrimitiveKind::Box;
            else if (type == "sphere")
                prim.kind = PrimitiveKind::Sphere;
            else if (type == "cylinder")
                prim.kind = PrimitiveKind::Cylinder;
            else
                throw fail("unknown entry '" + type + "'");
            prim.size = Eigen::Vector3f::Zero();
            for (int i = 0; i < sizeParameterCount(prim.kind); ++i) prim.size[i] = number();
            expect("pose");
            prim.translation = vec3();
            const float qx = number(), qy = number(), qz = number(), qw = number();
            prim.rotation = Eigen::Quaternionf(qw, qx, qy, qz);
            expect("texture");
            prim.texture.kind = textureFromName(word());
            prim.texture.colorA = vec3();
            prim.texture.colorB = vec3();
            prim.texture.scale = number();
            prim.texture.seed = static_cast<std::uint32_t>(std::stoul(word()));
            if (next < words.size()) {  // older files end after the texture
                expect("class");
                prim.classId = classId();
            }
            if (next < words.size()) throw fail("unexpected '" + words[next] + "'");
            scene.add(prim);
        }
    }
    return scene;
}

}  // namespace voxfuse::synth
