#pragma once
// Random-fern codes of whole frames, for finding a frame's look-alikes among keyframes (the
// relocaliser's keyframe database). The idea is Glocker et al.'s ("Real-time RGB-D camera
// relocalization via randomized ferns for keyframe encoding", TVCG 2015): the frame is shrunk to a
// small image, and each fern is a few binary tests "is this pixel's value above this threshold";
// the fern's code is the word those bits make. Two frames are as dissimilar as the fraction of
// ferns whose codes differ. Views a few centimetres and degrees apart share most codes; unrelated
// views share few.

#include <cstdint>
#include <memory>
#include <vector>

#include "voxfuse/core/Image.h"
#include "voxfuse/engines/LowLevelEngine.h"

namespace voxfuse {

struct FernSettings {
    int fern_count = 500;
    int tests_per_fern = 4;    // bits per fern (1..8): each fern's code is one of 2^tests words
    int image_width = 80;      // the frame is averaged down to this width (the height keeps the aspect: 80x60 for
                               // 640x480); a narrower frame is tested at its own size
    float min_depth_m = 0.2f;  // depth thresholds are drawn in this range
    float max_depth_m = 3.0f;
    bool use_intensity = true;  // with colour, each test reads depth or intensity at random; without, depth only
    std::uint32_t seed = 1;     // the tests are drawn from this seed: the same settings give the same codes
};

// One byte per fern: the fern's test outcomes as bits.
using FernCode = std::vector<std::uint8_t>;

// Fraction of ferns whose codes differ (0 = the same code, 1 = nothing in common). Codes of
// different lengths are wholly dissimilar.
float fernDissimilarity(const FernCode& a, const FernCode& b);

class FernEncoder {
public:
    // For frames of `frame_size` pixels. `with_intensity` chooses the channels once: a database holds
    // codes of one kind (settings.use_intensity off or no colour: depth only). The frames are averaged
    // down on `device` (the low-level engine's averageDepthCells), where the pipeline keeps them.
    FernEncoder(const FernSettings& settings, Vec2i frame_size, bool with_intensity, Device device = Device::CPU);
    ~FernEncoder();

    // The code of a frame: depth in metres (0 = no measurement) and its colour (may be empty; then
    // intensity tests read 0). A colour image of another size is sampled at the same relative position.
    FernCode encode(const Image<float>& depth_m, const Image<Vec4u8>& rgb);

    Vec2i codeImageSize() const { return small_size_; }
    bool withIntensity() const { return with_intensity_; }

    // The small images encode() tests, exposed for tests: depth averaged over the valid pixels of
    // each cell and smoothed (0 where a neighbourhood has none), intensity normalised to zero mean
    // and unit deviation over the image (so that exposure changes move few bits).
    void shrink(const Image<float>& depth_m, const Image<Vec4u8>& rgb, std::vector<float>& depth_small,
                std::vector<float>& intensity_small);

private:
    struct Test {
        int pixel;        // in the small image
        bool intensity;   // which channel
        float threshold;  // metres, or deviations from the mean intensity
    };
    FernSettings settings_;
    Vec2i frame_size_;
    Vec2i small_size_;
    bool with_intensity_;
    std::vector<Test> tests_;  // tests_per_fern per fern, fern after fern
    std::unique_ptr<LowLevelEngine> low_level_;
    Image<Vec2f> cells_;  // {mean, pixels} per cell of the code image
};

}  // namespace voxfuse
