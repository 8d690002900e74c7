// Turns exact depth into Kinect-v1-like depth: noise and quantisation act on
// disparity (so depth error grows with z^2), and the sensor loses pixels at
// grazing angles, on the far side of depth edges, out of range and at random.
#pragma once

#include <cstdint>
#include <random>
#include <vector>

namespace voxfuse::synth {

struct KinectDepthParams {
    float fx = 525.0f;        // focal length of the depth camera (px)
    float baseline = 0.075f;  // projector-camera baseline (m)
    // Gaussian disparity noise (px); with the 1/8 px quantisation the depth
    // noise is ~1.6 mm at 1 m and ~6.3 mm at 2 m (sigma_z = sigma_d * z^2 / (fx * b)).
    float disparitySigma = 0.05f;
    // The Kinect matches blocks of pixels, so its disparity noise is correlated
    // over a few pixels: apply() uses a box-filtered Gaussian field of this
    // radius (0 = independent per pixel), rescaled to keep disparitySigma per
    // pixel. Correlated noise is also what keeps the PNG depth files small.
    int noiseCorrelationRadius = 2;
    float disparityStep = 0.125f;  // disparity quantisation (px), 1/8 as on the Kinect
    float minDepth = 0.4f;         // valid range (m)
    float maxDepth = 4.5f;
    float maxIncidenceDeg = 78.0f;      // larger ray/normal angles return no depth
    float edgeJumpRatio = 0.04f;        // depth jump (fraction of depth) that makes an edge
    int edgeRadius = 1;                 // far-side pixels within this radius of a jump are lost
    float dropoutProbability = 0.005f;  // random missing pixels
};

class KinectDepthModel {
public:
    using Params = KinectDepthParams;

    // Raw Kinect disparity encoding as InfiniTAM reads it:
    //   depth = 8 * k2 * fx / (k1 - raw), with k2 = baseline; raw 0 = no measurement.
    static constexpr float kKinectK1 = 1090.0f;

    explicit KinectDepthModel(const Params& params = Params(), std::uint32_t seed = 42);

    // exactDepth and cosIncidence are width x height, row-major; 0 depth = no
    // surface. Returns the sensor depth (m), 0 where the sensor gives nothing.
    // Draws from the model's generator: call in a fixed order for repeatable output.
    std::vector<float> apply(const std::vector<float>& exactDepth, const std::vector<float>& cosIncidence, int width,
                             int height);
    // The same into `out`, reusing its memory and the model's scratch: a sequence made this way
    // allocates nothing per frame.
    void apply(const std::vector<float>& exactDepth, const std::vector<float>& cosIncidence, int width, int height,
               std::vector<float>& out);

    // One noisy, quantised measurement of a surface at depth z seen head-on
    // (no holes except out of range), with independent noise.
    float measure(float z);
    // The same for a given standard-normal noise value.
    float measureWithNoise(float z, float unitNoise) const;

    float depthToDisparity(float z) const { return params_.fx * params_.baseline / z; }
    float disparityToDepth(float d) const { return params_.fx * params_.baseline / d; }
    // Depth change of one disparity quantisation step at depth z.
    float depthStepAt(float z) const;

    // Raw 16-bit Kinect value for depth z (0 if not representable or z <= 0).
    std::uint16_t depthToKinectRaw(float z) const;
    float kinectRawToDepth(std::uint16_t raw) const;

    const Params& params() const { return params_; }

private:
    // Standard-normal noise per pixel, correlated over noiseCorrelationRadius (in the scratch below).
    const std::vector<float>& noiseField(int width, int height);
    bool onFarSideOfEdge(const std::vector<float>& depth, int width, int height, int x, int y) const;

    Params params_;
    std::mt19937 rng_;
    std::normal_distribution<float> noise_{0.0f, 1.0f};
    std::uniform_real_distribution<float> uniform_{0.0f, 1.0f};
    std::vector<float> field_, rows_, correlated_;  // noiseField's scratch, kept between frames
};

}  // namespace voxfuse::synth
