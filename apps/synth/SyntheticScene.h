// Analytic indoor scene with exact geometry, used to render synthetic RGB-D
// sequences whose ground truth (surfaces, poses) is known exactly.
//
// World frame: metres, z up, floor at z = 0. Camera frame: OpenCV/TUM
// convention (x right, y down, z forward).
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <cstdint>
#include <string>
#include <vector>

namespace voxfuse::synth {

struct Hit {
    float t = 0.0f;  // ray parameter: hit point = origin + t * dir (dir need not be unit)
    Eigen::Vector3f normal = Eigen::Vector3f::Zero();      // unit, facing the ray origin
    Eigen::Vector3f albedo_rgb = Eigen::Vector3f::Zero();  // linear RGB in [0, 1]
    int primitive = -1;                                    // index into SyntheticScene::primitives()
};

enum class TextureKind { Solid, Checker, Stripes, Noise, Wood, Poster };

// Procedural solid texture evaluated in the primitive's local frame, so the
// pattern is glued to the surface and stays consistent across views.
struct Texture {
    TextureKind kind = TextureKind::Solid;
    Eigen::Vector3f colorA{0.7f, 0.7f, 0.7f};
    Eigen::Vector3f colorB{0.3f, 0.3f, 0.3f};
    float scale = 0.1f;      // feature size in metres (tile, stripe, noise cell, ring, poster cell)
    std::uint32_t seed = 0;  // selects the noise / poster pattern

    Eigen::Vector3f albedo(const Eigen::Vector3f& p_local) const;
};
Texture makeTexture(TextureKind kind, const Eigen::Vector3f& a, const Eigen::Vector3f& b, float scale,
                    std::uint32_t seed = 0);

enum class PrimitiveKind { Rectangle, Box, Sphere, Cylinder };

// Semantic class of a primitive, as label images store it per pixel; 0 means
// unlabelled (also: no surface). The built-in scenes use these ids.
constexpr std::uint16_t kUnlabelled = 0;
namespace room_class {
constexpr std::uint16_t kFloor = 1;
constexpr std::uint16_t kWall = 2;
constexpr std::uint16_t kCeiling = 3;
constexpr std::uint16_t kTable = 4;  // top and legs
constexpr std::uint16_t kBall = 5;   // spheres
constexpr std::uint16_t kCylinder = 6;
constexpr std::uint16_t kBox = 7;     // boxes standing on the floor or the table
constexpr std::uint16_t kPoster = 8;  // the framed posters on the walls
}  // namespace room_class

struct SemanticClass {
    std::uint16_t id = kUnlabelled;
    std::string name;  // one word
};

// One surface, defined in its local frame and placed by world_from_local.
//   Rectangle: lies in local z = 0, half extents (size.x, size.y), may be
//              infinite (a plane); its normal is local +z.
//   Box:       half extents size.
//   Sphere:    radius size.x, centred at the local origin.
//   Cylinder:  capped, axis local z, radius size.x, half height size.y.
struct Primitive {
    PrimitiveKind kind = PrimitiveKind::Sphere;
    Eigen::Vector3f size = Eigen::Vector3f::Ones();
    Eigen::Vector3f translation = Eigen::Vector3f::Zero();
    Eigen::Quaternionf rotation = Eigen::Quaternionf::Identity();
    Texture texture;
    std::uint16_t classId = kUnlabelled;
};

struct PointLight {
    Eigen::Vector3f position = Eigen::Vector3f::Zero();
    float intensity = 1.0f;  // irradiance scale at 1 m
};

// Pinhole intrinsics; pixel (u, v) has its centre at integer coordinates.
struct PinholeCamera {
    int width = 640;
    int height = 480;
    float fx = 525.0f, fy = 525.0f, cx = 319.5f, cy = 239.5f;

    // Kinect v1 defaults (640x480, f = 525), scaled to another resolution.
    static PinholeCamera kinectV1(int width = 640, int height = 480);
    // Camera-frame ray through pixel (u, v), scaled so that its z is 1.
    Eigen::Vector3f ray(float u, float v) const { return {(u - cx) / fx, (v - cy) / fy, 1.0f}; }
};

// Exact per-pixel rendering of one view.
struct RenderedFrame {
    int width = 0, height = 0;
    std::vector<float> depth;          // z along the optical axis (m), 0 = no surface
    std::vector<float> cosIncidence;   // |cos| of the angle between viewing ray and normal
    std::vector<Eigen::Vector3f> rgb;  // display RGB in [0, 1] (gamma applied), noise-free
    std::vector<std::uint16_t> label;  // class of the primitive hit by the depth ray
                                       // (pixel centre), 0 = no surface; noise-free
};

class SyntheticScene {
public:
    int add(const Primitive& primitive);
    int addPlane(const Eigen::Vector3f& point, const Eigen::Vector3f& normal, const Texture& texture = {},
                 std::uint16_t classId = kUnlabelled);
    int addRectangle(const Eigen::Vector3f& center, const Eigen::Vector3f& normal, float halfWidth, float halfHeight,
                     const Texture& texture = {}, std::uint16_t classId = kUnlabelled);
    int addBox(const Eigen::Vector3f& center, const Eigen::Quaternionf& rotation, const Eigen::Vector3f& halfExtents,
               const Texture& texture = {}, std::uint16_t classId = kUnlabelled);
    int addSphere(const Eigen::Vector3f& center, float radius, const Texture& texture = {},
                  std::uint16_t classId = kUnlabelled);
    int addCylinder(const Eigen::Vector3f& center, const Eigen::Quaternionf& rotation, float radius, float halfHeight,
                    const Texture& texture = {}, std::uint16_t classId = kUnlabelled);
    void addLight(const PointLight& light) { lights_.push_back(light); }
    // Names a semantic class (id >= 1, name one word); replaces an earlier
    // name of the same id. Throws std::invalid_argument otherwise.
    void addClass(std::uint16_t id, const std::string& name);
    void setAmbient(float ambient) { ambient_ = ambient; }

    // Nearest hit with t > 1e-5 (in units of |dir|). Returns false on a miss.
    bool intersect(const Eigen::Vector3f& origin, const Eigen::Vector3f& dir, Hit& hit) const;
    bool intersect(const Eigen::Vector3f& origin, const Eigen::Vector3f& dir, Hit& hit, float tMin, float tMax) const;
    // True if any surface lies on the ray for t in (tMin, tMax).
    bool occluded(const Eigen::Vector3f& origin, const Eigen::Vector3f& dir, float tMin, float tMax) const;
    // Unsigned distance (m) from p_world to the nearest surface.
    float distanceToSurface(const Eigen::Vector3f& p_world) const;

    // Lambertian shading (ambient + point lights with shadows) of a hit point,
    // in linear RGB.
    Eigen::Vector3f shade(const Eigen::Vector3f& point, const Hit& hit) const;
    // Renders exact depth, incidence, class labels and colour; colour uses
    // colorSamples x colorSamples samples per pixel against aliasing.
    RenderedFrame render(const PinholeCamera& camera, const Eigen::Isometry3f& T_world_camera,
                         int colorSamples = 2) const;
    // The same into `frame`, whose buffers are reused: rendering a sequence this way allocates no
    // image memory per frame (megabyte temporaries freed every frame fragment the heap).
    void render(const PinholeCamera& camera, const Eigen::Isometry3f& T_world_camera, int colorSamples,
                RenderedFrame& frame) const;

    const std::vector<Primitive>& primitives() const { return primitives_; }
    const std::vector<PointLight>& lights() const { return lights_; }
    const std::vector<SemanticClass>& classes() const { return classes_; }  // sorted by id
    float ambient() const { return ambient_; }

    // The project's default data set: a 5 x 4 x 2.7 m room with a table,
    // boxes, spheres, a cylinder and posters.
    static SyntheticScene defaultRoom();
    // A corridor `length_m` long along +x from x = 0 (2.4 m wide, 2.6 m high), textured walls, posters
    // and boxes along it: a map that outgrows an active voxel array (swapping benchmarks).
    static SyntheticScene corridor(float length_m);
    static SyntheticScene singlePlane(const Eigen::Vector3f& point, const Eigen::Vector3f& normal);
    static SyntheticScene singleSphere(const Eigen::Vector3f& center, float radius);
    // A box (half extents 0.2, centred at (0, 0, 0.2)) on an infinite floor
    // z = 0, and a sphere of radius 0.15 at (0.6, 0, 0.15).
    static SyntheticScene boxAndSphere();

    // scene.txt: one primitive / light / class per line, world coordinates in
    // metres. Primitive lines without a class (older files) read as unlabelled.
    void write(const std::string& path) const;
    static SyntheticScene read(const std::string& path);  // throws std::runtime_error

private:
    struct Placement {  // cached transforms of one primitive
        Eigen::Matrix3f R_world_local;
        Eigen::Vector3f t_world_local;
        float bound_radius;  // a sphere about t_world_local holds the primitive (infinite for planes)
    };
    // False when the ray o + t d, t in [tMin, tMax], cannot meet the primitive: it misses the
    // bounding sphere. Skipping those leaves every hit as it was and saves most intersection tests.
    static bool mayHit(const Placement& pl, const Eigen::Vector3f& o, const Eigen::Vector3f& d, float tMin, float tMax);
    std::vector<Primitive> primitives_;
    std::vector<Placement> placements_;
    std::vector<PointLight> lights_;
    std::vector<SemanticClass> classes_;
    float ambient_ = 0.25f;
};

// Rotation whose local +z is `normal` and whose local x is horizontal
// (world z up) when possible; used to place rectangles and posters.
Eigen::Quaternionf rotationFromNormal(const Eigen::Vector3f& normal);

}  // namespace voxfuse::synth
