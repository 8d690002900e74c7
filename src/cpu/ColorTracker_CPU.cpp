// CPU/OpenMP loops of colour tracking; per-pixel work is in shared/ColorTracker.h.

#include <vector>

#include "NormalEquationsReduction_CPU.h"
#include "voxfuse/engines/ColorTracker.h"

namespace voxfuse::cpu {
namespace {

class ColorTrackerKernels_CPU final : public ColorTrackerKernels {
public:
    void intensityFromRgb(const Image<Vec4u8>& rgb, Image<float>& intensity) override {
        intensity.resize(rgb.size());
        const Vec4u8* in = rgb.host();
        float* out = intensity.host();
        const long long n = (long long)rgb.pixelCount();
#pragma omp parallel for schedule(static)
        for (long long i = 0; i < n; ++i) out[i] = voxfuse::intensityFromRgb(in[i]);
    }

    void downsampleIntensity(const Image<float>& in, Image<float>& out) override {
        const Vec2i size{in.width() / 2, in.height() / 2};
        out.resize(size);
        const float* src = in.host();
        float* dst = out.host();
#pragma omp parallel for schedule(static)
        for (int y = 0; y < size.y; ++y)
            for (int x = 0; x < size.x; ++x) dst[x + y * size.x] = downsampleIntensityPixel(src, in.size(), x, y);
    }

    void sobelGradient(const Image<float>& intensity, Image<Vec2f>& gradient) override {
        gradient.resize(intensity.size());
        const float* src = intensity.host();
        Vec2f* dst = gradient.host();
        const Vec2i size = intensity.size();
#pragma omp parallel for schedule(static)
        for (int y = 0; y < size.y; ++y)
            for (int x = 0; x < size.x; ++x) dst[x + y * size.x] = sobelGradientPixel(src, size, x, y);
    }

    void colorModelPoints(const RenderState& model, int step, const Image<float>& intensity, const Intrinsics& rgb,
                          const Mat4f& T_rgb_world, Image<ColorPoint>& points) override {
        const Vec2i size{model.points_world.width() / step, model.points_world.height() / step};
        points.resize(size);
        const Vec4f* src = model.points_world.host();
        const int model_width = model.points_world.width();
        const float* image = intensity.host();
        ColorPoint* dst = points.host();
#pragma omp parallel for schedule(static)
        for (int y = 0; y < size.y; ++y)
            for (int x = 0; x < size.x; ++x)
                dst[x + y * size.x] = colorPointFromModel(src[x * step + y * step * model_width], image, intensity.size(), T_rgb_world, rgb);
    }

    NormalEquations<double> accumulate(const Image<ColorPoint>& points, const ColorFrameLevel& level, const ColorTermParams& params,
                                       RobustKernel kernel, float kernel_scale) override {
        const ColorPoint* pts = points.host();
        const float* intensity = level.intensity.host();
        const Vec2f* gradient = level.gradient.host();
        const Vec2i size = level.intensity.size();
        const int n = int(points.pixelCount());
        return accumulateNormalEquations(
            n, kernel, kernel_scale,
            [&](int i, float* J, float& r) { return photometricTerm(pts[i], intensity, gradient, size, params, J, r); }, partials_);
    }

private:
    std::vector<NormalEquations<double>> partials_;
};

}  // namespace

std::unique_ptr<ColorTrackerKernels> makeColorTrackerKernels() { return std::make_unique<ColorTrackerKernels_CPU>(); }

}  // namespace voxfuse::cpu
