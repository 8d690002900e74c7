// Checks a voxfuse_viewer screenshot: each of the three panels shows an image (its pixels vary), and
// the model panel shows surface (a good share of its pixels is neither the model's black background
// nor the window's grey). Usage: check_viewer_screenshot FILE.png; exit 0 when it passes, 1 when not.

#include <cstdio>
#include <cstdlib>
#include <exception>

#include "PanelLayout.h"
#include "voxfuse/io/ImageIO.h"

using namespace voxfuse;

namespace {

constexpr double kMinLumaVariance = 50.0;  // a flat panel is ~0; a real image is in the hundreds
constexpr double kMinModelSurfaceFraction = 0.25;

int luma(Vec4u8 p) { return (299 * p.x + 587 * p.y + 114 * p.z) / 1000; }

struct PanelStats {
    double variance = 0.0;
    double surface_fraction = 0.0;  // pixels that are neither black nor the window's grey
};

PanelStats measure(const Image<Vec4u8>& image, const viewer::PanelRect& r) {
    double sum = 0.0, sum_sq = 0.0;
    long count = 0, surface = 0;
    for (int y = r.y; y < r.y + r.height && y < image.height(); ++y)
        for (int x = r.x; x < r.x + r.width && x < image.width(); ++x) {
            const Vec4u8 p = image.at(x, y);
            const int l = luma(p);
            sum += l;
            sum_sq += double(l) * l;
            ++count;
            const bool black = p.x < 8 && p.y < 8 && p.z < 8;
            const bool window_grey = std::abs(p.x - 38) < 4 && std::abs(p.y - 38) < 4 && std::abs(p.z - 38) < 4;
            if (!black && !window_grey) ++surface;
        }
    PanelStats s;
    if (count == 0) return s;
    const double mean = sum / double(count);
    s.variance = sum_sq / double(count) - mean * mean;
    s.surface_fraction = double(surface) / double(count);
    return s;
}

}  // namespace

int main(int argc, char** argv) {
    if (argc != 2) {
        std::fprintf(stderr, "usage: %s SCREENSHOT.png\n", argv[0]);
        return 2;
    }
    try {
        const Image<Vec4u8> shot = readColorImage(argv[1]);
        const viewer::PanelLayout layout = viewer::layoutPanels(shot.width(), shot.height());
        struct Named {
            const char* name;
            viewer::PanelRect rect;
        };
        bool ok = true;
        for (const Named& panel : {Named{"model", layout.model}, Named{"live depth", layout.live_depth},
                                   Named{"live colour", layout.live_color}}) {
            const PanelStats s = measure(shot, panel.rect);
            const bool varied = s.variance > kMinLumaVariance;
            std::printf("%-12s %4dx%-4d at (%d,%d): luma variance %.1f%s, non-background %.0f%%\n", panel.name,
                        panel.rect.width, panel.rect.height, panel.rect.x, panel.rect.y, s.variance,
                        varied ? "" : " (BLANK)", 100.0 * s.surface_fraction);
            ok = ok && varied;
            if (panel.rect.x == layout.model.x && panel.rect.y == layout.model.y &&
                s.surface_fraction < kMinModelSurfaceFraction) {
                std::printf("model panel shows too little surface (%.0f%% < %.0f%%)\n", 100.0 * s.surface_fraction,
                            100.0 * kMinModelSurfaceFraction);
                ok = false;
            }
        }
        std::printf("%s: %s (%dx%d)\n", ok ? "PASS" : "FAIL", argv[1], shot.width(), shot.height());
        return ok ? 0 : 1;
    } catch (const std::exception& e) {
        std::fprintf(stderr, "cannot check %s: %s\n", argv[1], e.what());
        return 2;
    }
}
