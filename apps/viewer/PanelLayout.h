#pragma once
// Where the three panels sit in the window, as in InfiniTAM's UI: the model large on the left (two
// thirds of the width), live depth above live colour in the right third, and a status bar (times,
// keys) along the bottom. Header-only so that the screenshot test checks exactly the regions the
// viewer draws.

namespace voxfuse::viewer {

struct PanelRect {
    int x = 0, y = 0, width = 0, height = 0;  // pixels, origin at the top-left of the window

    bool contains(double px, double py) const { return px >= x && py >= y && px < x + width && py < y + height; }
};

struct PanelLayout {
    PanelRect model;
    PanelRect live_depth;
    PanelRect live_color;
    PanelRect status_bar;
};

constexpr int kStatusBarHeight = 40;  // two lines of the built-in font at scale 2

// The largest rectangle of aspect image_width:image_height centred in `cell` (images are never stretched).
inline PanelRect fitAspect(const PanelRect& cell, int image_width, int image_height) {
    if (image_width <= 0 || image_height <= 0) return cell;
    PanelRect r = cell;
    if (long(cell.width) * image_height > long(cell.height) * image_width) {
        r.width = int(long(cell.height) * image_width / image_height);
        r.x = cell.x + (cell.width - r.width) / 2;
    } else {
        r.height = int(long(cell.width) * image_height / image_width);
        r.y = cell.y + (cell.height - r.height) / 2;
    }
    return r;
}

// Cells for a window of width x height; each panel shows its image fitted into its cell.
inline PanelLayout layoutPanels(int width, int height) {
    const int bar_height = height >= 4 * kStatusBarHeight ? kStatusBarHeight : 0;  // tiny windows: panels only
    const int panels_height = height - bar_height;
    const int model_width = width * 2 / 3;
    const int small_width = width - model_width;
    PanelLayout layout;
    layout.model = {0, 0, model_width, panels_height};
    layout.live_depth = {model_width, 0, small_width, panels_height / 2};
    layout.live_color = {model_width, panels_height / 2, small_width, panels_height - panels_height / 2};
    layout.status_bar = {0, panels_height, width, bar_height};
    return layout;
}

}  // namespace voxfuse::viewer
