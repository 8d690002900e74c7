// Frames as random-fern codes: shrink, smooth, test.

#include "voxfuse/engines/FernEncoder.h"

#include <algorithm>
#include <cmath>
#include <random>

#include "voxfuse/core/Error.h"

namespace voxfuse {
namespace {

// Uniform in [0, 1) from the generator's raw output: std's distributions may differ between standard
// libraries, and the tests must be the same everywhere for a seed.
float uniform01(std::mt19937& rng) { return float(rng() >> 8) * (1.f / 16777216.f); }

// 3x3 binomial smoothing over the cells that have a value (weight > 0): a shift of a cell or two
// between two views of the same place then changes few test outcomes.
void smooth(const std::vector<float>& in, const std::vector<float>& weight, Vec2i size, std::vector<float>& out) {
    static constexpr float kKernel[3] = {1.f, 2.f, 1.f};
    out.assign(in.size(), 0.f);
    for (int y = 0; y < size.y; ++y)
        for (int x = 0; x < size.x; ++x) {
            float sum = 0.f, sum_w = 0.f;
            for (int dy = -1; dy <= 1; ++dy)
                for (int dx = -1; dx <= 1; ++dx) {
                    const int xx = x + dx, yy = y + dy;
                    if (xx < 0 || yy < 0 || xx >= size.x || yy >= size.y) continue;
                    const std::size_t j = std::size_t(xx + yy * size.x);
                    const float w = kKernel[dx + 1] * kKernel[dy + 1] * weight[j];
                    sum += w * in[j];
                    sum_w += w;
                }
            out[std::size_t(x + y * size.x)] = sum_w > 0.f ? sum / sum_w : 0.f;
        }
}

// The first of `frame` pixels along an axis whose cell (pixel * cells / frame) is `cell`.
int firstPixelOfCell(int cell, int cells, int frame) { return int((static_cast<long long>(cell) * frame + cells - 1) / cells); }

// Averages of value(pixel) over the valid(pixel) pixels of each cell, cell (cx, cy) holding the frame's
// pixels [cx * W / w, (cx + 1) * W / w) x [cy * H / h, (cy + 1) * H / h), and how many there were (0:
// mean 0). A cell row is one thread's: its columns are summed down its rows first (independent sums,
// which vectorise), then across each cell; the result does not depend on the thread count.
template <class Pixel, class Valid, class Value>
void cellAverages(Vec2i frame, Vec2i small, const Pixel* pixels, Valid valid, Value value, std::vector<float>& mean,
                  std::vector<float>& count) {
    mean.assign(std::size_t(small.x) * std::size_t(small.y), 0.f);
    count.assign(mean.size(), 0.f);
#pragma omp parallel
    {
        std::vector<float> column_sum(std::size_t(frame.x)), column_count(std::size_t(frame.x));
#pragma omp for schedule(static)
        for (int cy = 0; cy < small.y; ++cy) {
            std::fill(column_sum.begin(), column_sum.end(), 0.f);
            std::fill(column_count.begin(), column_count.end(), 0.f);
            for (int y = firstPixelOfCell(cy, small.y, frame.y); y < firstPixelOfCell(cy + 1, small.y, frame.y); ++y) {
                const Pixel* row = pixels + std::size_t(y) * std::size_t(frame.x);
                for (int x = 0; x < frame.x; ++x) {
                    const bool ok = valid(row[x]);
                    column_sum[std::size_t(x)] += ok ? value(row[x]) : 0.f;
                    column_count[std::size_t(x)] += ok ? 1.f : 0.f;
                }
            }
            for (int cx = 0; cx < small.x; ++cx) {
                float sum = 0.f, n = 0.f;
                for (int x = firstPixelOfCell(cx, small.x, frame.x); x < firstPixelOfCell(cx + 1, small.x, frame.x); ++x) {
                    sum += column_sum[std::size_t(x)];
                    n += column_count[std::size_t(x)];
                }
                const std::size_t c = std::size_t(cx) + std::size_t(cy) * std::size_t(small.x);
                mean[c] = n > 0.f ? sum / n : 0.f;
                count[c] = n;
            }
        }
    }
}

}  // namespace

float fernDissimilarity(const FernCode& a, const FernCode& b) {
    if (a.size() != b.size() || a.empty()) return 1.f;
    std::size_t differ = 0;
    for (std::size_t i = 0; i < a.size(); ++i) differ += a[i] != b[i];
    return float(differ) / float(a.size());
}

FernEncoder::FernEncoder(const FernSettings& settings, Vec2i frame_size, bool with_intensity)
    : settings_(settings), frame_size_(frame_size), with_intensity_(with_intensity && settings.use_intensity) {
    if (settings.fern_count < 1 || settings.tests_per_fern < 1 || settings.tests_per_fern > 8)
        throw ConfigError("ferns: need at least one fern of 1 to 8 tests");
    if (settings.image_width < 4 || !(settings.max_depth_m > settings.min_depth_m))
        throw ConfigError("ferns: need a code image at least 4 pixels wide and max depth > min depth");
    if (frame_size.x < 1 || frame_size.y < 1) throw ConfigError("ferns: the frame has no pixels");
    // A frame narrower than the code image is tested at its own size.
    const int width = std::min(settings.image_width, frame_size.x);
    small_size_ = {width, std::clamp(int(std::lround(float(frame_size.y) * float(width) / float(frame_size.x))), 1, frame_size.y)};

    std::mt19937 rng(settings.seed);
    const int pixels = small_size_.x * small_size_.y;
    tests_.resize(std::size_t(settings.fern_count) * std::size_t(settings.tests_per_fern));
    for (Test& t : tests_) {
        t.pixel = std::min(pixels - 1, int(uniform01(rng) * float(pixels)));
        t.intensity = with_intensity_ && uniform01(rng) < 0.5f;
        const float u = uniform01(rng);
        t.threshold = t.intensity ? 2.f * u - 1.f : settings.min_depth_m + u * (settings.max_depth_m - settings.min_depth_m);
    }
}

void FernEncoder::shrink(const Image<float>& depth_m, const Image<Vec4u8>& rgb, std::vector<float>& depth_small,
                         std::vector<float>& intensity_small) const {
    if (depth_m.size() != frame_size_) throw ConfigError("ferns: the depth image is not of the size the encoder was made for");
    const std::size_t cells = std::size_t(small_size_.x) * std::size_t(small_size_.y);
    std::vector<float> mean, count;
    cellAverages(frame_size_, small_size_, depth_m.host(), [](float d) { return d > 0.f; }, [](float d) { return d; }, mean, count);
    smooth(mean, count, small_size_, depth_small);

    intensity_small.assign(cells, 0.f);
    if (!with_intensity_ || rgb.empty()) return;
    cellAverages(rgb.size(), small_size_, rgb.host(), [](Vec4u8) { return true; },
                 [](Vec4u8 c) { return float(c.x) + float(c.y) + float(c.z); }, mean, count);
    smooth(mean, count, small_size_, intensity_small);
    double sum = 0.0, square = 0.0;
    for (const float v : intensity_small) sum += v;
    const double average = sum / double(cells);
    for (const float v : intensity_small) square += (v - average) * (v - average);
    const double deviation = std::max(1.0, std::sqrt(square / double(cells)));  // a flat image stays flat
    for (float& v : intensity_small) v = float((v - average) / deviation);
}

FernCode FernEncoder::encode(const Image<float>& depth_m, const Image<Vec4u8>& rgb) const {
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
