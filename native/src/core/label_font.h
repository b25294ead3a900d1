// A tiny 5x7 bitmap font for the debug views' panel labels (only the letters they use), and the
// stamping of a label into a mask: white glyph pixels with a 1-pixel black outline.
#pragma once

#include <cstdint>
#include <cstring>
#include <vector>

namespace lt {

constexpr int kGlyphWidth = 5, kGlyphHeight = 7;
enum LabelPixel : uint8_t { kLabelNone = 0, kLabelWhite = 1, kLabelBlack = 2 };

// Rows top to bottom; bit 4 is the leftmost column. Unknown characters draw as a space.
inline const uint8_t* label_glyph(char c) {
  static const uint8_t kSpace[7] = {0, 0, 0, 0, 0, 0, 0};
  static const struct {
    char c;
    uint8_t rows[7];
  } kGlyphs[] = {
      {'A', {0x0E, 0x11, 0x11, 0x1F, 0x11, 0x11, 0x11}}, {'C', {0x0E, 0x11, 0x10, 0x10, 0x10, 0x11, 0x0E}},
      {'D', {0x1E, 0x11, 0x11, 0x11, 0x11, 0x11, 0x1E}}, {'E', {0x1F, 0x10, 0x10, 0x1E, 0x10, 0x10, 0x1F}},
      {'H', {0x11, 0x11, 0x11, 0x1F, 0x11, 0x11, 0x11}}, {'I', {0x0E, 0x04, 0x04, 0x04, 0x04, 0x04, 0x0E}},
      {'L', {0x10, 0x10, 0x10, 0x10, 0x10, 0x10, 0x1F}}, {'M', {0x11, 0x1B, 0x15, 0x15, 0x11, 0x11, 0x11}},
      {'O', {0x0E, 0x11, 0x11, 0x11, 0x11, 0x11, 0x0E}}, {'R', {0x1E, 0x11, 0x11, 0x1E, 0x14, 0x12, 0x11}},
      {'T', {0x1F, 0x04, 0x04, 0x04, 0x04, 0x04, 0x04}},
  };
  for (const auto& g : kGlyphs)
    if (g.c == c) return g.rows;
  return kSpace;
}

// Size of a label's box, outline included: glyphs one (scaled) column apart.
inline int label_width(const char* text, int scale) {
  const int n = int(std::strlen(text));
  return n ? (n * (kGlyphWidth + 1) - 1) * scale + 2 : 0;
}
inline int label_height(int scale) { return kGlyphHeight * scale + 2; }

// Stamps `text` with its box's top-left at (x, y_top) into a w x h mask whose rows go bottom to
// top (y_top is the box's highest row). Pixels outside the mask are clipped.
inline void stamp_label(std::vector<uint8_t>& mask, int w, int h, int x, int y_top, const char* text, int scale) {
  const int bw = label_width(text, scale), bh = label_height(scale);
  // Glyph coverage of the box (row 0 at the top), then the outline around it.
  std::vector<uint8_t> on(size_t(bw) * bh, 0);
  for (int i = 0; text[i]; ++i) {
    const uint8_t* rows = label_glyph(text[i]);
    for (int gy = 0; gy < kGlyphHeight * scale; ++gy)
      for (int gx = 0; gx < kGlyphWidth * scale; ++gx)
        if ((rows[gy / scale] >> (kGlyphWidth - 1 - gx / scale)) & 1)
          on[size_t(1 + gy) * bw + 1 + i * (kGlyphWidth + 1) * scale + gx] = 1;
  }
  for (int by = 0; by < bh; ++by)
    for (int bx = 0; bx < bw; ++bx) {
      uint8_t v = on[size_t(by) * bw + bx] ? kLabelWhite : kLabelNone;
      for (int dy = -1; dy <= 1 && !v; ++dy)
        for (int dx = -1; dx <= 1 && !v; ++dx) {
          const int nx = bx + dx, ny = by + dy;
          if (nx >= 0 && ny >= 0 && nx < bw && ny < bh && on[size_t(ny) * bw + nx]) v = kLabelBlack;
        }
      const int px = x + bx, py = y_top - by;
      if (v && px >= 0 && py >= 0 && px < w && py < h) mask[size_t(py) * w + px] = v;
    }
}

}  // namespace lt
