// Builds a small scene through the installed library and checks that a fused wall is found again.
#include <cstdio>

#include "voxfuse/engines/MainEngine.h"

int main() {
    using namespace voxfuse;
    MainEngineSettings s;
    s.dense_offset = {-32, -32, 0};
    s.dense_size = {64, 64, 128};
    s.scene.voxel_size_m = 0.01f;
    s.scene.mu_m = 0.04f;
    RGBDCalib calib;
    calib.depth = calib.rgb = Intrinsics{64, 48, 52.5f, 52.5f, 31.5f, 23.5f};
    calib.disparity = DisparityCalib::affine(0.001f);
    auto engine = MainEngine::create(s, calib);
    RGBDFrame frame;
    frame.depth_raw.resize({64, 48});
    for (std::size_t i = 0; i < frame.depth_raw.pixelCount(); ++i) frame.depth_raw.host()[i] = 800;  // a wall at 0.8 m
    const Mat4f pose = Mat4f::identity();
    engine->processFrame(frame, &pose);
    Image<float> depth;
    raycastDepth(engine->renderState(), depth);
    const float d = depth.at(32, 24);
    std::printf("consumer: raycast depth at the centre %.4f m\n", d);
    return (d > 0.79f && d < 0.81f) ? 0 : 1;
}
