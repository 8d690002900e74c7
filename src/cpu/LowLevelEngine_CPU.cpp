// CPU/OpenMP loops of the low-level engine; per-pixel work is in shared/LowLevel.h.

#include "voxfuse/engines/LowLevelEngine.h"
#include "voxfuse/shared/LowLevel.h"

namespace voxfuse::cpu {
namespace {

class LowLevelEngine_CPU final : public LowLevelEngine {
public:
    void convertDepthToMetres(const Image<std::uint16_t>& raw, const DisparityCalib& calib, float fx_depth, float min_m,
                              float max_m, Image<float>& depth_m) override {
        depth_m.resize(raw.size());
        const std::uint16_t* in = raw.host();
        float* out = depth_m.host();
        const long long n = (long long)raw.pixelCount();
#pragma omp parallel for schedule(static)
        for (long long i = 0; i < n; ++i) {
            const float d = calib.toMetres(in[i], fx_depth);
            out[i] = (d >= min_m && d <= max_m) ? d : 0.f;
        }
    }

    void bilateralFilterDepth(const Image<float>& in, Image<float>& out, const BilateralFilterParams& p) override {
        out.resize(in.size());
        const Vec2i size = in.size();
        const float* src = in.host();
        float* dst = out.host();
#pragma omp parallel for schedule(static)
        for (int y = 0; y < size.y; ++y)
            for (int x = 0; x < size.x; ++x)
                dst[x + y * size.x] = bilateralFilterDepthPixel(src, size, x, y, p.radius_px, p.sigma_space_px, p.sigma_depth_m);
    }

    void downsampleDepth(const Image<float>& in, Image<float>& out, float max_diff_m) override {
        const Vec2i size{in.width() / 2, in.height() / 2};
        out.resize(size);
        const float* src = in.host();
        float* dst = out.host();
#pragma omp parallel for schedule(static)
        for (int y = 0; y < size.y; ++y)
            for (int x = 0; x < size.x; ++x) dst[x + y * size.x] = downsampleDepthPixel(src, in.size(), x, y, max_diff_m);
    }

    void computeVertexMap(const Image<float>& depth, const Intrinsics& intr, Image<Vec4f>& vertices) override {
        vertices.resize(depth.size());
        const float* src = depth.host();
        Vec4f* dst = vertices.host();
#pragma omp parallel for schedule(static)
        for (int y = 0; y < depth.height(); ++y)
            for (int x = 0; x < depth.width(); ++x) dst[x + y * depth.width()] = vertexFromDepthPixel(src, intr, x, y);
    }

    void computeNormalMap(const Image<Vec4f>& vertices, Image<Vec4f>& normals, float max_edge_m) override {
        normals.resize(vertices.size());
        const Vec4f* src = vertices.host();
        Vec4f* dst = normals.host();
#pragma omp parallel for schedule(static)
        for (int y = 0; y < vertices.height(); ++y)
            for (int x = 0; x < vertices.width(); ++x)
                dst[x + y * vertices.width()] = normalFromVertexPixel(src, vertices.size(), x, y, max_edge_m);
    }
};

}  // namespace

std::unique_ptr<LowLevelEngine> makeLowLevelEngine() { return std::make_unique<LowLevelEngine_CPU>(); }

}  // namespace voxfuse::cpu
