#pragma once
// The status bar under the panels, as in InfiniTAM's UI: per-frame time, fps and the keys, drawn with a
// tiny built-in 5x7 bitmap font (digits, letters shown upper-case, and . , : / | - ( ) = + %) so the
// viewer needs no font library; and the submaps' overlay on the model panel.

#include <string>

#include "PanelLayout.h"
#include "SubmapOverlay.h"

namespace voxfuse::viewer {

// Pixels a line of `text` takes at `scale` (each font pixel drawn as scale x scale).
int textWidth(const std::string& text, int scale);
// Draws `text` with its top-left corner at (x, y) in the current colour. Expects a projection with one
// unit per pixel and the origin at the top-left.
void drawText(int x, int y, const std::string& text, int scale);
// Fills `bar` with a dark background and writes the two lines in it, at scale 2 when the keys line fits, else 1.
void drawStatusBar(const PanelRect& bar, const std::string& status_line, const std::string& keys_line);
// Odometry edges in amber, loop closures in magenta, submap origins as amber squares.
void drawSubmapOverlay(const SubmapOverlay& overlay);

}  // namespace voxfuse::viewer
