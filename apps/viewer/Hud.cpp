#include "Hud.h"

#include <cctype>

#define GL_SILENCE_DEPRECATION
#include <GLFW/glfw3.h>

namespace voxfuse::viewer {
namespace {

constexpr int kGlyphWidth = 5, kGlyphHeight = 7;
constexpr int kAdvance = kGlyphWidth + 1;  // one empty column between characters

struct Glyph {
    char c;
    unsigned char rows[kGlyphHeight];  // top row first; bit 4 is the leftmost column
};

// clang-format off
constexpr Glyph kFont[] = {
    {'0', {0b01110, 0b10001, 0b10011, 0b10101, 0b11001, 0b10001, 0b01110}},
    {'1', {0b00100, 0b01100, 0b00100, 0b00100, 0b00100, 0b00100, 0b01110}},
    {'2', {0b01110, 0b10001, 0b00001, 0b00010, 0b00100, 0b01000, 0b11111}},
    {'3', {0b11111, 0b00010, 0b00100, 0b00010, 0b00001, 0b10001, 0b01110}},
    {'4', {0b00010, 0b00110, 0b01010, 0b10010, 0b11111, 0b00010, 0b00010}},
    {'5', {0b11111, 0b10000, 0b11110, 0b00001, 0b00001, 0b10001, 0b01110}},
    {'6', {0b00110, 0b01000, 0b10000, 0b11110, 0b10001, 0b10001, 0b01110}},
    {'7', {0b11111, 0b00001, 0b00010, 0b00100, 0b01000, 0b01000, 0b01000}},
    {'8', {0b01110, 0b10001, 0b10001, 0b01110, 0b10001, 0b10001, 0b01110}},
    {'9', {0b01110, 0b10001, 0b10001, 0b01111, 0b00001, 0b00010, 0b01100}},
    {'A', {0b01110, 0b10001, 0b10001, 0b11111, 0b10001, 0b10001, 0b10001}},
    {'B', {0b11110, 0b10001, 0b10001, 0b11110, 0b10001, 0b10001, 0b11110}},
    {'C', {0b01110, 0b10001, 0b10000, 0b10000, 0b10000, 0b10001, 0b01110}},
    {'D', {0b11100, 0b10010, 0b10001, 0b10001, 0b10001, 0b10010, 0b11100}},
    {'E', {0b11111, 0b10000, 0b10000, 0b11110, 0b10000, 0b10000, 0b11111}},
    {'F', {0b11111, 0b10000, 0b10000, 0b11110, 0b10000, 0b10000, 0b10000}},
    {'G', {0b01110, 0b10001, 0b10000, 0b10111, 0b10001, 0b10001, 0b01111}},
    {'H', {0b10001, 0b10001, 0b10001, 0b11111, 0b10001, 0b10001, 0b10001}},
    {'I', {0b01110, 0b00100, 0b00100, 0b00100, 0b00100, 0b00100, 0b01110}},
    {'J', {0b00111, 0b00010, 0b00010, 0b00010, 0b00010, 0b10010, 0b01100}},
    {'K', {0b10001, 0b10010, 0b10100, 0b11000, 0b10100, 0b10010, 0b10001}},
    {'L', {0b10000, 0b10000, 0b10000, 0b10000, 0b10000, 0b10000, 0b11111}},
    {'M', {0b10001, 0b11011, 0b10101, 0b10101, 0b10001, 0b10001, 0b10001}},
    {'N', {0b10001, 0b10001, 0b11001, 0b10101, 0b10011, 0b10001, 0b10001}},
    {'O', {0b01110, 0b10001, 0b10001, 0b10001, 0b10001, 0b10001, 0b01110}},
    {'P', {0b11110, 0b10001, 0b10001, 0b11110, 0b10000, 0b10000, 0b10000}},
    {'Q', {0b01110, 0b10001, 0b10001, 0b10001, 0b10101, 0b10010, 0b01101}},
    {'R', {0b11110, 0b10001, 0b10001, 0b11110, 0b10100, 0b10010, 0b10001}},
    {'S', {0b01111, 0b10000, 0b10000, 0b01110, 0b00001, 0b00001, 0b11110}},
    {'T', {0b11111, 0b00100, 0b00100, 0b00100, 0b00100, 0b00100, 0b00100}},
    {'U', {0b10001, 0b10001, 0b10001, 0b10001, 0b10001, 0b10001, 0b01110}},
    {'V', {0b10001, 0b10001, 0b10001, 0b10001, 0b10001, 0b01010, 0b00100}},
    {'W', {0b10001, 0b10001, 0b10001, 0b10101, 0b10101, 0b10101, 0b01010}},
    {'X', {0b10001, 0b10001, 0b01010, 0b00100, 0b01010, 0b10001, 0b10001}},
    {'Y', {0b10001, 0b10001, 0b01010, 0b00100, 0b00100, 0b00100, 0b00100}},
    {'Z', {0b11111, 0b00001, 0b00010, 0b00100, 0b01000, 0b10000, 0b11111}},
    {'.', {0b00000, 0b00000, 0b00000, 0b00000, 0b00000, 0b01100, 0b01100}},
    {',', {0b00000, 0b00000, 0b00000, 0b00000, 0b01100, 0b00100, 0b01000}},
    {':', {0b00000, 0b01100, 0b01100, 0b00000, 0b01100, 0b01100, 0b00000}},
    {'/', {0b00000, 0b00001, 0b00010, 0b00100, 0b01000, 0b10000, 0b00000}},
    {'|', {0b00100, 0b00100, 0b00100, 0b00100, 0b00100, 0b00100, 0b00100}},
    {'-', {0b00000, 0b00000, 0b00000, 0b11111, 0b00000, 0b00000, 0b00000}},
    {'(', {0b00010, 0b00100, 0b01000, 0b01000, 0b01000, 0b00100, 0b00010}},
    {')', {0b01000, 0b00100, 0b00010, 0b00010, 0b00010, 0b00100, 0b01000}},
    {'=', {0b00000, 0b00000, 0b11111, 0b00000, 0b11111, 0b00000, 0b00000}},
    {'+', {0b00000, 0b00100, 0b00100, 0b11111, 0b00100, 0b00100, 0b00000}},
    {'%', {0b11000, 0b11001, 0b00010, 0b00100, 0b01000, 0b10011, 0b00011}},
};
// clang-format on

// The glyph for `c` (letters in either case), or null for a character the font lacks (drawn as a space).
const Glyph* findGlyph(char c) {
    const char upper = char(std::toupper(static_cast<unsigned char>(c)));
    for (const Glyph& g : kFont)
        if (g.c == upper) return &g;
    return nullptr;
}

}  // namespace

int textWidth(const std::string& text, int scale) { return int(text.size()) * kAdvance * scale; }

void drawText(int x, int y, const std::string& text, int scale) {
    glBegin(GL_QUADS);
    for (std::size_t i = 0; i < text.size(); ++i) {
        const Glyph* g = findGlyph(text[i]);
        if (!g) continue;
        const int left = x + int(i) * kAdvance * scale;
        for (int row = 0; row < kGlyphHeight; ++row)
            for (int col = 0; col < kGlyphWidth; ++col) {
                if (!(g->rows[row] & (1 << (kGlyphWidth - 1 - col)))) continue;
                const int px = left + col * scale, py = y + row * scale;
                glVertex2i(px, py);
                glVertex2i(px + scale, py);
                glVertex2i(px + scale, py + scale);
                glVertex2i(px, py + scale);
            }
    }
    glEnd();
}

void drawStatusBar(const PanelRect& bar, const std::string& status_line, const std::string& keys_line) {
    if (bar.height <= 0) return;
    glColor3f(0.05f, 0.05f, 0.05f);
    glBegin(GL_QUADS);
    glVertex2i(bar.x, bar.y);
    glVertex2i(bar.x + bar.width, bar.y);
    glVertex2i(bar.x + bar.width, bar.y + bar.height);
    glVertex2i(bar.x, bar.y + bar.height);
    glEnd();
    const int margin = 4;
    // The keys line sets the scale, so the text does not change size as the status line grows; a status
    // line too long for the window is cut off at its edge.
    const int scale =
        (textWidth(keys_line, 2) <= bar.width - 2 * margin && 2 * (2 * kGlyphHeight + margin) <= bar.height) ? 2 : 1;
    const int line_height = kGlyphHeight * scale + margin;
    const int top = bar.y + (bar.height - 2 * line_height + margin) / 2;
    glColor3f(1.f, 1.f, 1.f);
    drawText(bar.x + margin, top, status_line, scale);
    glColor3f(0.65f, 0.65f, 0.65f);
    drawText(bar.x + margin, top + line_height, keys_line, scale);
}

void drawSubmapOverlay(const SubmapOverlay& overlay) {
    glLineWidth(2.f);
    glBegin(GL_LINES);
    for (const OverlaySegment& s : overlay.segments) {
        if (s.loop)
            glColor3f(1.f, 0.2f, 0.8f);
        else
            glColor3f(1.f, 0.75f, 0.1f);
        glVertex2f(s.from.x, s.from.y);
        glVertex2f(s.to.x, s.to.y);
    }
    glEnd();
    glLineWidth(1.f);
    constexpr float kHalf = 4.f;  // an origin's square: 8 pixels across
    glColor3f(1.f, 0.75f, 0.1f);
    glBegin(GL_QUADS);
    for (const Vec2f& o : overlay.origins) {
        glVertex2f(o.x - kHalf, o.y - kHalf);
        glVertex2f(o.x + kHalf, o.y - kHalf);
        glVertex2f(o.x + kHalf, o.y + kHalf);
        glVertex2f(o.x - kHalf, o.y + kHalf);
    }
    glEnd();
}

}  // namespace voxfuse::viewer
