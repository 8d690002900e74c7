#include "KinectDepthModel.h"

#include <algorithm>
#include <cmath>

namespace voxfuse::synth {

KinectDepthModel::KinectDepthModel(const Params& params, std::uint32_t seed) : params_(params), rng_(seed) {}

float KinectDepthModel::measure(float z) { return measureWithNoise(z, noise_(rng_)); }

float KinectDepthModel::measureWithNoise(float z, float unitNoise) const {
    if (!(z > 0.0f)) return 0.0f;
    float d = depthToDisparity(z) + params_.disparitySigma * unitNoise;
    d = std::round(d / params_.disparityStep) * params_.disparityStep;
    if (d <= 0.0f) return 0.0f;
    const float measured = disparityToDepth(d);
    return (measured >= params_.minDepth && measured <= params_.maxDepth) ? measured : 0.0f;
}

bool KinectDepthModel::onFarSideOfEdge(const std::vector<float>& depth, int width, int height, int x, int y) const {
    const float z = depth[static_cast<std::size_t>(y) * width + x];
    const float nearLimit = z * (1.0f - params_.edgeJumpRatio);
    const int r = params_.edgeRadius;
    for (int ny = std::max(y - r, 0); ny <= std::min(y + r, height - 1); ++ny) {
        for (int nx = std::max(x - r, 0); nx <= std::min(x + r, width - 1); ++nx) {
            const float neighbour = depth[static_cast<std::size_t>(ny) * width + nx];
            if (neighbour > 0.0f && neighbour < nearLimit) return true;
        }
    }
    return false;
}

const std::vector<float>& KinectDepthModel::noiseField(int width, int height) {
    const std::size_t count = static_cast<std::size_t>(width) * height;
    field_.resize(count);
    for (float& value : field_) value = noise_(rng_);
    const int r = params_.noiseCorrelationRadius;
    if (r <= 0) return field_;
    // Separable box sums; dividing by sqrt(number of samples) keeps every
    // pixel exactly standard normal, borders included.
    rows_.resize(count);
    correlated_.resize(count);
    for (int y = 0; y < height; ++y)
        for (int x = 0; x < width; ++x) {
            float sum = 0.0f;
            for (int nx = std::max(x - r, 0); nx <= std::min(x + r, width - 1); ++nx)
                sum += field_[static_cast<std::size_t>(y) * width + nx];
            rows_[static_cast<std::size_t>(y) * width + x] = sum;
        }
    for (int y = 0; y < height; ++y) {
        const int countY = std::min(y + r, height - 1) - std::max(y - r, 0) + 1;
        for (int x = 0; x < width; ++x) {
            const int countX = std::min(x + r, width - 1) - std::max(x - r, 0) + 1;
            float sum = 0.0f;
            for (int ny = std::max(y - r, 0); ny <= std::min(y + r, height - 1); ++ny)
                sum += rows_[static_cast<std::size_t>(ny) * width + x];
            correlated_[static_cast<std::size_t>(y) * width + x] = sum / std::sqrt(static_cast<float>(countX * countY));
        }
    }
    return correlated_;
}

std::vector<float> KinectDepthModel::apply(const std::vector<float>& exactDepth, const std::vector<float>& cosIncidence,
                                           int width, int height) {
    std::vector<float> out;
    apply(exactDepth, cosIncidence, width, height, out);
    return out;
}

void KinectDepthModel::apply(const std::vector<float>& exactDepth, const std::vector<float>& cosIncidence, int width,
                             int height, std::vector<float>& out) {
    const float minCos = std::cos(params_.maxIncidenceDeg * 3.14159265f / 180.0f);
    const std::vector<float>& noise = noiseField(width, height);
    out.assign(exactDepth.size(), 0.0f);
    for (int y = 0; y < height; ++y) {
        for (int x = 0; x < width; ++x) {
            const std::size_t i = static_cast<std::size_t>(y) * width + x;
            const float z = exactDepth[i];
            // Draw the dropout first and always, so the random stream does not
            // depend on which pixels happen to be rejected below.
            const bool dropped = uniform_(rng_) < params_.dropoutProbability;
            if (!(z > 0.0f) || dropped || cosIncidence[i] < minCos) continue;
            if (onFarSideOfEdge(exactDepth, width, height, x, y)) continue;
            out[i] = measureWithNoise(z, noise[i]);
        }
    }
}

float KinectDepthModel::depthStepAt(float z) const {
    const float d = depthToDisparity(z);
    return disparityToDepth(d - 0.5f * params_.disparityStep) - disparityToDepth(d + 0.5f * params_.disparityStep);
}

std::uint16_t KinectDepthModel::depthToKinectRaw(float z) const {
    if (!(z > 0.0f)) return 0;
    const float raw = std::round(kKinectK1 - 8.0f * depthToDisparity(z));
    return (raw >= 1.0f && raw <= 65535.0f) ? static_cast<std::uint16_t>(raw) : 0;
}

float KinectDepthModel::kinectRawToDepth(std::uint16_t raw) const {
    if (raw == 0 || raw >= kKinectK1) return 0.0f;
    return 8.0f * params_.baseline * params_.fx / (kKinectK1 - static_cast<float>(raw));
}

}  // namespace voxfuse::synth
