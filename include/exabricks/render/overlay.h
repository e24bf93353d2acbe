// Annotations drawn into a rendered image: a labelled colour bar, text lines, the outline of a
// box and a legend of the level colours. Opaque, in linear RGB, after rendering (the image's
// alpha becomes 1 where they draw); text is stb's easy font, scaled with the image.
#pragma once

#include "exabricks/core/image.h"
#include "exabricks/render/camera.h"
#include "exabricks/render/transfer_function.h"

#include <string>
#include <vector>

namespace exa {

/// Pixels per font unit for an image of this size (1 up to 400 rows, then one more per 400).
int overlayScale(const Image& image);

/// Draws `text` with its top-left corner at pixel (x, y); returns the width drawn.
int drawText(Image& image, int x, int y, const std::string& text, const vec3f& color, int scale);
int textWidth(const std::string& text, int scale);

/// Ticks in data values for a colour bar over `range`: 1-2-5 steps (about five ticks), or for
/// logarithmic mapping the decades (every n-th when there are many), under two decades 1, 2 and 5
/// (or every digit) times the powers of ten, so that there are at least two ticks.
std::vector<double> colorBarTicks(const range1f& range, bool logScale);

/// The labels of the ticks with the digits they need: each distinct from its neighbours and
/// nearer its own tick than half the way to the next (in log10 for logarithmic bars).
std::vector<std::string> colorBarLabels(const std::vector<double>& ticks, bool logScale);

/// A vertical colour bar at the right edge: the colour map over the transfer function's value
/// range (which must be set), ticks with their values, and `title` above it (the field name);
/// its title starts below row `top` (what is written above it), and its panel is cleared first
/// so that lines drawn before it do not cross it.
void drawColorBar(Image& image, const TransferFunction& tf, const std::string& title, const vec3f& textColor,
                  int top = 0);

/// `text`, cut and ended with "..." where it is wider than `width` pixels.
std::string fitText(const std::string& text, int width, int scale);

/// Rows that drawLines takes for this many lines (margins included).
int linesHeight(size_t lines, const Image& image);

/// Lines of text at the top-left corner, each cut to the image's width.
void drawLines(Image& image, const std::vector<std::string>& lines, const vec3f& color);

/// The edges of a world box as seen by the camera.
void drawBoxOutline(Image& image, const Camera& camera, const box3d& box, const vec3f& color);

/// Swatches of the debug view's level colours with each level's cell width, at the bottom left.
void drawLevelLegend(Image& image, const std::vector<int>& levels, const vec3f& textColor);

} // namespace exa
