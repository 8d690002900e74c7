#pragma once
// The low-level engine's stages, written once for both device layers: a template on the device type,
// instantiated by src/cpu/LowLevelEngine_CPU.cpp and cuda/LowLevelEngine_CUDA.cu. One pixel of the
// output per element (shared/LowLevel.h).

#include <cmath>
#include <memory>
#include <string>

#include "core/DeviceScratch.h"
#include "cpu/LowLevelShapes_CPU.h"
#include "engines/DeviceImages.h"
#include "voxfuse/engines/LowLevelEngine.h"
#include "voxfuse/shared/LowLevel.h"

namespace voxfuse {

// An image sized for output on `where` (its other copy, if any, becomes stale when written).
template <class T>
T* outputOn(Device where, Image<T>& image, Vec2i size) {
    image.resize(size, where == Device::CPU || image.memory().onHost(), where == Device::CUDA);
    return image.memory().data(where);
}

// The per-pass constants of the bilateral filter; ConfigError for a window it cannot hold.
inline BilateralWeights bilateralWeightsFor(const BilateralFilterParams& p) {
    if (p.radius_px < 0 || p.radius_px > kMaxBilateralRadius || !(p.sigma_space_px > 0.f) || !(p.sigma_depth_m > 0.f))
        throw ConfigError("bilateral filter: the radius must be 0.." + std::to_string(kMaxBilateralRadius) +
                          " pixels and both sigmas positive (got radius " + std::to_string(p.radius_px) + ", sigmas " +
                          std::to_string(p.sigma_space_px) + " px and " + std::to_string(p.sigma_depth_m) + " m)");
    BilateralWeights w{};
    w.radius_px = p.radius_px;
    for (int k = 0; k <= kMaxBilateralRadius; ++k)
        w.spatial[k] = std::exp(-float(k * k) / (2.f * p.sigma_space_px * p.sigma_space_px));
    w.inv_2_sigma_depth_sq = 1.f / (2.f * p.sigma_depth_m * p.sigma_depth_m);
    return w;
}

template <class TDevice>
class LowLevelEngineOn final : public LowLevelEngine {
    static constexpr Device kDevice = TDevice::kind;

public:
    void convertDepthToMetres(const Image<std::uint16_t>& raw, const DisparityCalib& calib, float fx_depth, float min_m,
                              float max_m, float gap_tolerance, Image<float>& depth_m) override {
        const std::uint16_t* in = imageOn(kDevice, raw, raw_staging_);
        float* out = outputOn(kDevice, depth_m, raw.size());
        TDevice::parallelFor(int(raw.pixelCount()),
                             ConvertDepthPixels{in, raw.size(), calib, fx_depth, min_m, max_m, gap_tolerance, out});
    }

    void bilateralFilterDepth(const Image<float>& in, Image<float>& out, const BilateralFilterParams& p) override {
        const float* src = imageOn(kDevice, in, float_staging_);
        float* dst = outputOn(kDevice, out, in.size());
        if constexpr (TDevice::kOneThreadPerItem) {
            TDevice::parallelFor(int(in.pixelCount()),
                                 BilateralFilterPixels{src, in.size(), bilateralWeightsFor(p), dst});
        } else {
            const BilateralFilterStrips strips{src, in.size(), bilateralWeightsFor(p), dst};
            TDevice::parallelFor(strips.elementCount(), strips);
        }
    }

    void downsampleDepth(const Image<float>& in, Image<float>& out, float max_diff_m) override {
        const Vec2i size{in.width() / 2, in.height() / 2};
        const float* src = imageOn(kDevice, in, float_staging_);
        float* dst = outputOn(kDevice, out, size);
        TDevice::parallelFor(size.x * size.y, DownsampleDepthPixels{src, in.size(), size.x, max_diff_m, dst});
    }

    void computeVertexMap(const Image<float>& depth, const Intrinsics& intr, Image<Vec4f>& vertices) override {
        const float* src = imageOn(kDevice, depth, float_staging_);
        Vec4f* dst = outputOn(kDevice, vertices, depth.size());
        TDevice::parallelFor(int(depth.pixelCount()), VertexPixels{src, intr, dst});
    }

    void computeNormalMap(const Image<Vec4f>& vertices, Image<Vec4f>& normals, float max_edge_m) override {
        const Vec4f* src = imageOn(kDevice, vertices, point_staging_);
        Vec4f* dst = outputOn(kDevice, normals, vertices.size());
        TDevice::parallelFor(int(vertices.pixelCount()), NormalPixels{src, vertices.size(), max_edge_m, dst});
    }

    void computeGridPointsAndNormals(const Image<float>& depth, const Intrinsics& intr, float max_edge_m,
                                     int pixel_step, Image<Vec4f>& vertices, Image<Vec4f>& normals) override {
        if (pixel_step < 1)
            throw Error("computeGridPointsAndNormals: the pixel step must be at least 1, got " +
                        std::to_string(pixel_step));
        if (depth.size() != intr.size())
            throw Error("computeGridPointsAndNormals: the depth image is not the intrinsics' size");
        // Every pixel: the vertex map first, each point unprojected once rather than by each neighbour.
        if (pixel_step == 1) {
            computeVertexMap(depth, intr, vertices);
            computeNormalMap(vertices, normals, max_edge_m);
            return;
        }
        const float* src = imageOn(kDevice, depth, float_staging_);
        const Vec2i extent = gridExtent(depth.size(), pixel_step);
        Vec4f* points = outputOn(kDevice, vertices, extent);
        Vec4f* dst = outputOn(kDevice, normals, extent);
        TDevice::parallelFor(gridSize(depth.size(), pixel_step),
                             GridPointNormalPixels{DepthImagePoints{src, intr}, depth.size(), max_edge_m,
                                                   pixelGridOf(depth.size(), pixel_step), points, dst});
    }

    void copyDepth(const Image<float>& in, Image<float>& out) override {
        const float* src = imageOn(kDevice, in, float_staging_);
        float* dst = outputOn(kDevice, out, in.size());
        TDevice::parallelFor(int(in.pixelCount()), CopyPixels<float>{src, dst});
    }

    void dropDepthBeyond(Image<float>& depth, float max_depth_m) override {
        if (depth.empty()) return;
        depth.memory().update(kDevice);
        TDevice::parallelFor(int(depth.pixelCount()), DropDepthBeyond{depth.memory().data(kDevice), max_depth_m});
    }

    int countValidDepth(const Image<float>& depth, int pixel_step) override {
        const PixelGrid grid = pixelGridOf(depth.size(), pixel_step);
        return TDevice::countIf(gridSize(depth.size(), pixel_step),
                                DepthIsValid{imageOn(kDevice, depth, float_staging_), grid}, scratch_);
    }
    int countValidPoints(const Image<Vec4f>& points) override {
        return TDevice::countIf(int(points.pixelCount()), PointIsValid{imageOn(kDevice, points, point_staging_)},
                                scratch_);
    }
    void averageDepthCells(const Image<float>& depth_m, Vec2i cells, Image<Vec2f>& mean_and_count) override {
        requireCellGrid(cells);
        averageCells(DepthSample{imageOn(kDevice, depth_m, float_staging_)}, depth_m.size(), cells,
                     outputOn(kDevice, mean_and_count, cells));
    }
    void averageIntensityCells(const Image<Vec4u8>& rgb, Vec2i cells, Image<Vec2f>& mean_and_count) override {
        requireCellGrid(cells);
        averageCells(IntensitySample{imageOn(kDevice, rgb, rgb_staging_)}, rgb.size(), cells,
                     outputOn(kDevice, mean_and_count, cells));
    }
    Device device() const override { return kDevice; }

private:
    template <class Sample>
    static void averageCells(const Sample& sample, Vec2i frame, Vec2i cells, Vec2f* out) {
        if constexpr (TDevice::kOneThreadPerItem)
            TDevice::parallelFor(cells.x * cells.y, CellAverages<Sample>{sample, frame, cells, out});
        else
            TDevice::parallelFor(cells.y, CellRowAverages<Sample>{sample, frame, cells, out});
    }
    // Cells may hold no pixel (a grid finer than the image): theirs is {0, 0}.
    static void requireCellGrid(Vec2i cells) {
        if (cells.x < 1 || cells.y < 1)
            throw Error("cell averages: a grid of " + std::to_string(cells.x) + "x" + std::to_string(cells.y) +
                        " cells has no cell");
    }

    DeviceScratch scratch_{kDevice};
    MemoryBlock<Vec4u8> rgb_staging_;
    MemoryBlock<std::uint16_t> raw_staging_;
    MemoryBlock<float> float_staging_;
    MemoryBlock<Vec4f> point_staging_;
};

}  // namespace voxfuse
