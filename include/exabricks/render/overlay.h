// Annotations drawn into a rendered image: a labelled colour bar, text lines, the outline of a
// box and a legend of the level colours. Opaque, in linear RGB, after rendering (the image's
// alpha becomes 1 where they draw); text is stb's easy font, scaled with the image. They draw
// over the picture and change no pixel outside their own strokes and glyph backings.
#pragma once

#include "exabricks/core/image.h"
#include "exabricks/render/camera.h"
#include "exabricks/render/transfer_function.h"

#include <string>
#include <vector>

namespace exa {

/// Pixels per font unit for an image of this size (1 up to 400 rows, then one more per 400).
int overlayScale(const Image& image);

/// The colour legends draw in over `background`: black over a light one, white over a dark one
/// (and the backing of text in `ink`: legendInk(ink)).
vec3f legendInk(const vec3f& background);

/// A rectangle of pixels, [x0, x1) x [y0, y1).
struct PixelRect {
  int x0 = 0, y0 = 0, x1 = 0, y1 = 0;
  bool contains(int x, int y) const { return x >= x0 && x < x1 && y >= y0 && y < y1; }
};

/// Draws `text` with its top-left corner at pixel (x, y); returns the width drawn.
int drawText(Image& image, int x, int y, const std::string& text, const vec3f& color, int scale);
/// drawText over a backing of the contrasting colour one font unit around each stroke (legible
/// over any picture, hiding no more of it than the glyphs' outlines).
int drawTextOver(Image& image, int x, int y, const std::string& text, const vec3f& color, int scale);
/// The pixels drawTextOver writes, as one rectangle.
PixelRect textOverRect(int x, int y, const std::string& text, int scale);
int textWidth(const std::string& text, int scale);

/// Ticks in data values for a colour bar over `range`: 1-2-5 steps (about five ticks), or for
/// logarithmic mapping the decades (every n-th when there are many), under two decades 1, 2 and 5
/// (or every digit) times the powers of ten, so that there are at least two ticks.
std::vector<double> colorBarTicks(const range1f& range, bool logScale);

/// The labels of the ticks with the digits they need: each distinct from its neighbours and
/// nearer its own tick than half the way to the next (in log10 for logarithmic bars).
std::vector<std::string> colorBarLabels(const std::vector<double>& ticks, bool logScale);

/// Where a colour bar goes: the bar's colours in [x0, x1) x [y0, y1), its ticks and labels, its
/// title (with " (log)" for logarithmic mapping) at (headX, headY), and `boxes`, which hold every
/// pixel the bar draws (frame, each tick with its label, the title).
struct ColorBarLayout {
  int x0 = 0, x1 = 0, y0 = 0, y1 = 0, scale = 1;
  std::vector<double> ticks;
  std::vector<std::string> labels;
  std::string head;
  int headX = 0, headY = 0;
  std::vector<PixelRect> boxes;
  int tickRow(const TransferFunction& tf, size_t i) const; ///< the row of tick i
};

/// A vertical colour bar at the right edge: the colour map over the transfer function's value
/// range (which must be set), ticks with their values, and `title` above it (the field name);
/// its title starts below row `top` (what is written above it).
ColorBarLayout colorBarLayout(const Image& image, const TransferFunction& tf, const std::string& title, int top = 0);
void drawColorBar(Image& image, const TransferFunction& tf, const ColorBarLayout& layout, const vec3f& textColor);
void drawColorBar(Image& image, const TransferFunction& tf, const std::string& title, const vec3f& textColor,
                  int top = 0);

/// `text`, cut and ended with "..." where it is wider than `width` pixels.
std::string fitText(const std::string& text, int width, int scale);

/// Rows that drawLines takes for this many lines (margins included).
int linesHeight(size_t lines, const Image& image);

/// Lines of text at the top-left corner, each cut to the image's width.
void drawLines(Image& image, const std::vector<std::string>& lines, const vec3f& color);

/// The edges of a world box as seen by the camera, leaving the pixels in `keepClear` alone (what
/// another legend draws there).
void drawBoxOutline(Image& image, const Camera& camera, const box3d& box, const vec3f& color,
                    const std::vector<PixelRect>& keepClear = {});

/// Swatches of the debug view's level colours with each level's cell width, at the bottom left.
void drawLevelLegend(Image& image, const std::vector<int>& levels, const vec3f& textColor);

} // namespace exa
