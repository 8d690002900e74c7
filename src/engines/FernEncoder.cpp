// Frames as random-fern codes: shrink, smooth, test.

#include "voxfuse/engines/FernEncoder.h"

#include <algorithm>
#include <cmath>
#include <random>
#include <utility>

#include "voxfuse/core/Error.h"

namespace voxfuse {
namespace {

// Uniform in [0, 1) from the generator's raw output: std's distributions may differ between standard
// libraries, and the tests must be the same everywhere for a seed.
float uniform01(std::mt19937& rng) { return float(rng() >> 8) * (1.f / 16777216.f); }

// 3x3 binomial smoothing of cell means ({mean, pixels} per cell), weighted by how many pixels each
// has (none: no weight): a shift of a cell or two between two views of the same place then changes
// few test outcomes.
void smooth(const Vec2f* cells, Vec2i size, std::vector<float>& out) {
    static constexpr float kKernel[3] = {1.f, 2.f, 1.f};
    out.assign(std::size_t(size.x) * std::size_t(size.y), 0.f);
    for (int y = 0; y < size.y; ++y)
        for (int x = 0; x < size.x; ++x) {
            float sum = 0.f, sum_w = 0.f;
            for (int dy = -1; dy <= 1; ++dy)
                for (int dx = -1; dx <= 1; ++dx) {
                    const int xx = x + dx, yy = y + dy;
                    if (xx < 0 || yy < 0 || xx >= size.x || yy >= size.y) continue;
                    const std::size_t j = std::size_t(xx + yy * size.x);
                    const float w = kKernel[dx + 1] * kKernel[dy + 1] * cells[j].y;
                    sum += w * cells[j].x;
                    sum_w += w;
                }
            out[std::size_t(x + y * size.x)] = sum_w > 0.f ? sum / sum_w : 0.f;
        }
}

}  // namespace

float fernDissimilarity(const FernCode& a, const FernCode& b) {
    if (a.size() != b.size() || a.empty()) return 1.f;
    std::size_t differ = 0;
    for (std::size_t i = 0; i < a.size(); ++i) differ += a[i] != b[i];
    return float(differ) / float(a.size());
}

FernEncoder::FernEncoder(const FernSettings& settings, Vec2i frame_size, bool with_intensity, Device device)
    : settings_(settings),
      frame_size_(frame_size),
      with_intensity_(with_intensity && settings.use_intensity),
      low_level_(makeLowLevelEngine(device)) {
    if (settings.fern_count < 1 || settings.tests_per_fern < 1 || settings.tests_per_fern > 8)
        throw ConfigError("ferns: need at least one fern of 1 to 8 tests");
    if (settings.image_width < 4 || !(settings.max_depth_m > settings.min_depth_m))
        throw ConfigError("ferns: need a code image at least 4 pixels wide and max depth > min depth");
    if (frame_size.x < 1 || frame_size.y < 1) throw ConfigError("ferns: the frame has no pixels");
    // A frame narrower than the code image is tested at its own size.
    const int width = std::min(settings.image_width, frame_size.x);
    small_size_ = {
        width, std::clamp(int(std::lround(float(frame_size.y) * float(width) / float(frame_size.x))), 1, frame_size.y)};

    std::mt19937 rng(settings.seed);
    const int pixels = small_size_.x * small_size_.y;
    tests_.resize(std::size_t(settings.fern_count) * std::size_t(settings.tests_per_fern));
    for (Test& t : tests_) {
        t.pixel = std::min(pixels - 1, int(uniform01(rng) * float(pixels)));
        t.intensity = with_intensity_ && uniform01(rng) < 0.5f;
        const float u = uniform01(rng);
        t.threshold =
            t.intensity ? 2.f * u - 1.f : settings.min_depth_m + u * (settings.max_depth_m - settings.min_depth_m);
    }
}

FernEncoder::~FernEncoder() = default;

void FernEncoder::shrink(const Image<float>& depth_m, const Image<Vec4u8>& rgb, std::vector<float>& depth_small,
                         std::vector<float>& intensity_small) {
    if (depth_m.size() != frame_size_)
        throw ConfigError("ferns: the depth image is not of the size the encoder was made for");
    const std::size_t cells = std::size_t(small_size_.x) * std::size_t(small_size_.y);
    // The averages are taken where the images are (on the GPU only they come down), the rest here.
    low_level_->averageDepthCells(depth_m, small_size_, cells_);
    cells_.memory().updateHost();
    smooth(std::as_const(cells_).host(), small_size_, depth_small);

    intensity_small.assign(cells, 0.f);
    if (!with_intensity_ || rgb.empty()) return;
    low_level_->averageIntensityCells(rgb, small_size_, cells_);
    cells_.memory().updateHost();
    smooth(std::as_const(cells_).host(), small_size_, intensity_small);
    double sum = 0.0, square = 0.0;
    for (const float v : intensity_small) sum += v;
    const double average = sum / double(cells);
    for (const float v : intensity_small) square += (v - average) * (v - average);
    const double deviation = std::max(1.0, std::sqrt(square / double(cells)));  // a flat image stays flat
    for (float& v : intensity_small) v = float((v - average) / deviation);
}

FernCode FernEncoder::encode(const Image<float>& depth_m, const Image<Vec4u8>& rgb) {
    std::vector<float> depth_small, intensity_small;
    shrink(depth_m, rgb, depth_small, intensity_small);
    FernCode code(std::size_t(settings_.fern_count), 0);
    const Test* test = tests_.data();
    for (std::uint8_t& word : code)
        for (int b = 0; b < settings_.tests_per_fern; ++b, ++test) {
            const float value = (test->intensity ? intensity_small : depth_small)[std::size_t(test->pixel)];
            word = std::uint8_t(word | (value > test->threshold ? 1u << b : 0u));
        }
    return code;
}

}  // namespace voxfuse
