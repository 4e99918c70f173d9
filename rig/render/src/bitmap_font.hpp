#pragma once
// A small bitmap font (5×7 glyphs, capitals, digits, punctuation) for the structure labels drawn
// in the surgeon's view and the instructor's overlay: no font library, the same pixels everywhere,
// so tests can reason about where text lands.
#include <array>
#include <cstdint>
#include <string_view>

#include "vitreo/render/frame_scene.hpp"

namespace vitreo::render::font {

inline constexpr int kGlyphWidth = 5;
inline constexpr int kGlyphHeight = 7;
inline constexpr int kAdvance = 6;     // glyph + one column of spacing
inline constexpr int kAtlasCell = 8;   // atlas cell (glyph + a texel of border)
inline constexpr int kAtlasFirst = 32;
inline constexpr int kAtlasChars = 95; // ' ' .. '~'

// Whether glyph `c` has ink at (col, row), row 0 at the top.
bool ink(char c, int col, int row);
// Width in pixels of `text` drawn at `scale` (no trailing spacing).
int text_width(std::string_view text, int scale);
// Draws `text` into `img` with its top-left at (x, y), `scale` pixels per glyph texel, optionally
// over a dark drop shadow. Clipped to the image.
void draw_text(Image& img, int x, int y, std::string_view text, const std::array<std::uint8_t, 3>& colour, int scale,
               bool shadow = true);
// The glyphs as a texture atlas for drawing text on the GPU (kAtlasChars cells in one row).
Image atlas();

}  // namespace vitreo::render::font
