#include "SyntheticSource.h"

#include <algorithm>
#include <cmath>
#include <random>

#include "CameraPath.h"
#include "KinectDepthModel.h"
#include "SyntheticScene.h"
#include "voxfuse/core/EigenInterop.h"
#include "voxfuse/core/Error.h"

namespace voxfuse::app {
namespace {
constexpr float kDepthScale = 5000.f;  // raw depth = metres * 5000, as the bundled TUM-layout data
constexpr double kFirstTimestamp = 1000.0;
constexpr int kMaxFrames = 1000000;  // 9 hours at 30 Hz; the poses are made up front
constexpr float kCorridorLength = 20.f;
}  // namespace

struct SyntheticSource::Renderer {
    synth::SyntheticScene scene;
    synth::PinholeCamera camera;
    synth::KinectDepthModel depth_model;
    std::mt19937 color_rng;
    // Kept between frames, so that a sequence allocates no image memory per frame.
    synth::RenderedFrame rendered;
    std::vector<float> depth_m;
    FrameImageBuffers images;
    Renderer(Kind kind, int width, int height, unsigned seed)
        : scene(kind == Kind::Corridor ? synth::SyntheticScene::corridor(kCorridorLength)
                                       : synth::SyntheticScene::defaultRoom()),
          camera(synth::PinholeCamera::kinectV1(width, height)),
          depth_model(depthParams(camera), seed),
          color_rng(seed + 1) {}
    static synth::KinectDepthParams depthParams(const synth::PinholeCamera& camera) {
        synth::KinectDepthParams p;
        p.fx = camera.fx;
        return p;
    }
};

SyntheticSource::SyntheticSource(Kind kind, int frames, int width, int height, unsigned seed)
    : renderer_(std::make_unique<Renderer>(kind, width, height, seed)), kind_(kind), frames_(frames) {
    if (frames < 1 || width < 16 || height < 16)
        throw ConfigError("synthetic source: need at least one frame of 16x16 pixels or more");
    const synth::PinholeCamera& c = renderer_->camera;
    calib_.depth = calib_.rgb = Intrinsics{c.width, c.height, c.fx, c.fy, c.cx, c.cy};
    calib_.disparity = DisparityCalib::affine(1.f / kDepthScale);
    const synth::CameraPath room_path;
    const synth::CorridorWalk corridor_walk(kCorridorLength, frames);
    for (int i = 0; i < frames; ++i) {
        const Eigen::Isometry3f pose = kind == Kind::Corridor ? corridor_walk.pose(i) : room_path.pose(i);
        ground_truth_.push_back({kFirstTimestamp + i / synth::CameraPath::kFps, toMat4f(pose.matrix())});
    }
}

SyntheticSource::~SyntheticSource() = default;

bool SyntheticSource::isSyntheticName(const std::string& path) {
    for (const std::string name : {"synthetic", "synthetic-corridor"})
        if (path == name || path.rfind(name + ":", 0) == 0) return true;
    return false;
}

std::unique_ptr<SyntheticSource> SyntheticSource::open(const std::string& path) {
    if (!isSyntheticName(path)) throw ConfigError("not a synthetic source: '" + path + "'");
    const Kind kind = path.rfind("synthetic-corridor", 0) == 0 ? Kind::Corridor : Kind::Room;
    int frames = kind == Kind::Corridor ? 1200 : 100;
    const std::size_t colon = path.find(':');
    if (colon != std::string::npos) {
        std::size_t used = 0;
        try {
            frames = std::stoi(path.substr(colon + 1), &used);
        } catch (const std::exception&) {
            used = 0;
        }
        if (used == 0 || used != path.size() - colon - 1 || frames < 1 || frames > kMaxFrames)
            throw ConfigError("synthetic source: '" + path +
                              "' should be NAME:N with 1 <= N <= " + std::to_string(kMaxFrames) + " frames");
    }
    return std::make_unique<SyntheticSource>(kind, frames);
}

std::string SyntheticSource::description() const {
    return std::string(kind_ == Kind::Corridor ? "synthetic corridor walk" : "synthetic room") +
           " rendered in memory (" + std::to_string(frames_) + " frames, " + std::to_string(calib_.depth.width) + "x" +
           std::to_string(calib_.depth.height) + ")";
}

bool SyntheticSource::next(RGBDFrame& frame) {
    if (next_ >= frames_) return false;
    const int i = next_++;
    Renderer& r = *renderer_;
    Eigen::Isometry3f pose;
    pose.matrix() = toEigen(ground_truth_[std::size_t(i)].T_world_camera);
    r.scene.render(r.camera, pose, 1, r.rendered);
    r.depth_model.apply(r.rendered.depth, r.rendered.cosIncidence, r.rendered.width, r.rendered.height, r.depth_m);

    r.images.depth_raw.resize(Vec2i{r.rendered.width, r.rendered.height});
    r.images.rgb.resize(Vec2i{r.rendered.width, r.rendered.height});
    std::normal_distribution<float> noise(0.f, 1.5f);  // 8-bit colour sensor noise, as the bundled data
    for (std::size_t p = 0; p < r.depth_m.size(); ++p) {
        const float raw = std::round(r.depth_m[p] * kDepthScale);
        r.images.depth_raw.host()[p] = raw >= 1.f && raw <= 65535.f ? std::uint16_t(raw) : 0;
        auto channel = [&](float v) {
            return std::uint8_t(std::clamp(std::round(v * 255.f + noise(r.color_rng)), 0.f, 255.f));
        };
        const Eigen::Vector3f& c = r.rendered.rgb[p];
        const std::uint8_t red = channel(c.x()), green = channel(c.y()), blue = channel(c.z());
        r.images.rgb.host()[p] = Vec4u8{red, green, blue, 255};
    }
    r.images.handOver(frame, true);
    frame.index = i;
    frame.timestamp_s = ground_truth_[std::size_t(i)].timestamp_s;
    frame.rgb_timestamp_s = -1.0;
    frame.has_ground_truth = true;
    frame.T_world_camera_gt = ground_truth_[std::size_t(i)].T_world_camera;
    frame.depth_path = "synthetic frame " + std::to_string(i);
    frame.labels = Image<ClassId>();
    frame.labels_path.clear();
    return true;
}

}  // namespace voxfuse::app
