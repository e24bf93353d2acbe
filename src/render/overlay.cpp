#include "exabricks/render/overlay.h"

#include "exabricks/core/error.h"
#include "exabricks/render/renderer.h"

#include <stb/stb_easy_font.h>

#include <cmath>
#include <cstdio>
#include <limits>

namespace exa {
namespace {

void fillRect(Image& image, int x0, int y0, int x1, int y1, const vec3f& c) {
  x0 = std::max(x0, 0), y0 = std::max(y0, 0);
  x1 = std::min(x1, image.width), y1 = std::min(y1, image.height);
  for (int y = y0; y < y1; ++y)
    for (int x = x0; x < x1; ++x)
      image.at(x, y) = {c.x, c.y, c.z, 1.f};
}

void drawLine(Image& image, double x0, double y0, double x1, double y1, const vec3f& c,
              const std::vector<PixelRect>& keepClear = {}) {
  const int steps = int(std::ceil(std::max(std::abs(x1 - x0), std::abs(y1 - y0)))) + 1;
  if (steps > 1 << 20) return;
  for (int i = 0; i <= steps; ++i) {
    const double t = double(i) / steps;
    const int x = int(std::floor(x0 + (x1 - x0) * t)), y = int(std::floor(y0 + (y1 - y0) * t));
    if (x < 0 || y < 0 || x >= image.width || y >= image.height) continue;
    bool clear = true;
    for (const PixelRect& r : keepClear)
      clear = clear && !r.contains(x, y);
    if (clear) image.at(x, y) = {c.x, c.y, c.z, 1.f};
  }
}

} // namespace

int overlayScale(const Image& image) { return 1 + std::max(0, (std::min(image.width, image.height) - 1) / 400); }

int textWidth(const std::string& text, int scale) {
  std::string copy = text;
  return stb_easy_font_width(copy.data()) * scale;
}

namespace {

/// The strokes of `text` at (x, y), in pixels.
std::vector<PixelRect> glyphStrokes(int x, int y, const std::string& text, int scale) {
  // stb's easy font: quads of four vertices (x, y, z, colour; 16 bytes each) per glyph stroke. It
  // stops quietly when its buffer is full, so the buffer grows until a pass leaves room for
  // another quad: then no stroke was dropped.
  constexpr size_t kQuadBytes = 4 * 16;
  std::string copy = text;
  std::vector<char> buffer(text.size() * 16 * kQuadBytes + kQuadBytes);
  int quads = 0;
  for (;;) {
    quads = stb_easy_font_print(0.f, 0.f, copy.data(), nullptr, buffer.data(), int(buffer.size()));
    if (size_t(quads + 1) * kQuadBytes <= buffer.size()) break;
    buffer.resize(buffer.size() * 2);
  }
  std::vector<PixelRect> strokes(size_t(std::max(quads, 0)));
  for (int q = 0; q < quads; ++q) {
    const float* v = reinterpret_cast<const float*>(buffer.data() + size_t(q) * kQuadBytes);
    const float qx0 = v[0], qy0 = v[1], qx1 = v[8], qy1 = v[9]; // vertices 0 and 2
    strokes[size_t(q)] = {x + int(qx0 * scale), y + int(qy0 * scale), x + int(qx1 * scale), y + int(qy1 * scale)};
  }
  return strokes;
}

int drawGlyphs(Image& image, int x, int y, const std::string& text, const vec3f& color, int scale,
               const vec3f* backing) {
  const std::vector<PixelRect> strokes = glyphStrokes(x, y, text, scale);
  // The backing first (every stroke grown by one font unit), then the strokes over it.
  if (backing)
    for (const PixelRect& r : strokes)
      fillRect(image, r.x0 - scale, r.y0 - scale, r.x1 + scale, r.y1 + scale, *backing);
  for (const PixelRect& r : strokes)
    fillRect(image, r.x0, r.y0, r.x1, r.y1, color);
  return textWidth(text, scale);
}

} // namespace

int drawText(Image& image, int x, int y, const std::string& text, const vec3f& color, int scale) {
  return drawGlyphs(image, x, y, text, color, scale, nullptr);
}

PixelRect textOverRect(int x, int y, const std::string& text, int scale) {
  PixelRect box{x, y, x, y};
  for (const PixelRect& r : glyphStrokes(x, y, text, scale))
    box = {std::min(box.x0, r.x0 - scale), std::min(box.y0, r.y0 - scale), std::max(box.x1, r.x1 + scale),
           std::max(box.y1, r.y1 + scale)};
  return box;
}

vec3f legendInk(const vec3f& bg) { return luminance(bg) > 0.3f ? vec3f(0.f) : vec3f(1.f); }

int drawTextOver(Image& image, int x, int y, const std::string& text, const vec3f& color, int scale) {
  const vec3f backing = legendInk(color);
  return drawGlyphs(image, x, y, text, color, scale, &backing);
}

namespace {

/// Multiples of `step` in [lo, hi] (at most 64).
std::vector<double> multiplesIn(double lo, double hi, double step) {
  std::vector<double> ticks;
  // (float ranges: an end a float rounding away from a multiple still has its tick)
  const int64_t k0 = int64_t(std::ceil(lo / step - 1e-4)), k1 = int64_t(std::floor(hi / step + 1e-4));
  for (int64_t k = k0; k <= k1 && ticks.size() < 64; ++k)
    ticks.push_back(double(k) * step);
  return ticks;
}

/// About `parts` + 1 ticks at 1-2-5 steps over [lo, hi].
std::vector<double> linearTicks(double lo, double hi, double parts = 5.0) {
  const double rough = (hi - lo) / parts;
  const double mag = std::pow(10.0, std::floor(std::log10(rough)));
  double step = mag;
  for (double m : {1.0, 2.0, 5.0, 10.0})
    if (m * mag >= rough * (1 - 1e-6)) {
      step = m * mag;
      break;
    }
  return multiplesIn(lo, hi, step);
}

} // namespace

std::vector<double> colorBarTicks(const range1f& range, bool logScale) {
  std::vector<double> ticks;
  if (range.empty() || !(range.upper >= range.lower)) return ticks;
  double lo = range.lower, hi = range.upper;
  if (!(hi > lo)) return {lo};
  if (logScale) {
    if (!(hi > 0.0)) return ticks;
    if (!(lo > 0.0)) lo = hi * 1e-6;
    // (float ranges: 1e-3f is 1.0000000475e-3, a decade within 1e-6 of an end counts)
    const int d0 = int(std::ceil(std::log10(lo) - 1e-6)), d1 = int(std::floor(std::log10(hi) + 1e-6));
    if (d1 - d0 + 1 >= 2) {
      const int every = std::max(1, (d1 - d0 + 1 + 5) / 6);
      for (int d = d0; d <= d1; d += every)
        ticks.push_back(std::pow(10.0, d));
      return ticks;
    }
    // Under two decades: 1, 2 and 5 times the powers of ten where that gives two ticks, else 1-2-5
    // steps over the range (two to five ticks).
    for (int d = d0 - 1; d <= d1; ++d)
      for (double m : {1.0, 2.0, 5.0}) {
        const double t = m * std::pow(10.0, d);
        if (t >= lo * (1 - 1e-6) && t <= hi * (1 + 1e-6)) ticks.push_back(t);
      }
    if (ticks.size() >= 2) return ticks;
    ticks = linearTicks(lo, hi, 3.0);
    return ticks.size() >= 2 ? ticks : std::vector<double>{lo, hi};
  }
  return linearTicks(lo, hi);
}

std::vector<std::string> colorBarLabels(const std::vector<double>& ticks, bool logScale) {
  // The fewest significant digits (but every digit of the integer part below a million) that keep
  // each label distinct and nearer its own tick than half the way to a neighbour.
  double largest = 0.0;
  for (double t : ticks)
    largest = std::max(largest, std::abs(t));
  const int integerDigits = largest >= 1.0 && largest < 1e6 ? int(std::floor(std::log10(largest))) + 1 : 1;
  auto position = [&](double v) { return logScale && v > 0.0 ? std::log10(v) : v; };
  std::vector<std::string> labels(ticks.size());
  // Linear bars of moderate values: one number of decimals for all, those of the step.
  double step = std::numeric_limits<double>::infinity();
  for (size_t i = 1; i < ticks.size(); ++i)
    step = std::min(step, ticks[i] - ticks[i - 1]);
  const bool fixed = !logScale && largest < 1e6 && (largest >= 1e-3 || largest == 0.0) && step > 0.0;
  const int first = fixed && std::isfinite(step) ? std::max(0, -int(std::floor(std::log10(step) + 1e-9))) : 0;
  for (int digits = fixed ? first : std::max(3, integerDigits); digits <= 17; ++digits) {
    bool ok = true;
    for (size_t i = 0; i < ticks.size() && ok; ++i) {
      char buf[40];
      if (fixed)
        std::snprintf(buf, sizeof buf, "%.*f", digits, ticks[i] == 0.0 ? 0.0 : ticks[i]);
      else
        std::snprintf(buf, sizeof buf, "%.*g", digits, ticks[i]);
      labels[i] = buf;
      double gap = std::numeric_limits<double>::infinity();
      if (i > 0) gap = std::min(gap, std::abs(position(ticks[i]) - position(ticks[i - 1])));
      if (i + 1 < ticks.size()) gap = std::min(gap, std::abs(position(ticks[i + 1]) - position(ticks[i])));
      const double shown = std::strtod(buf, nullptr);
      ok = (std::isinf(gap) || std::abs(position(shown) - position(ticks[i])) < gap / 2) &&
           (i == 0 || labels[i] != labels[i - 1]);
    }
    if (ok) return labels;
  }
  return labels;
}

ColorBarLayout colorBarLayout(const Image& image, const TransferFunction& tf, const std::string& title, int top) {
  if (tf.valueRange.empty()) fail("a colour bar needs the transfer function's value range");
  ColorBarLayout l;
  const int s = l.scale = overlayScale(image);
  l.ticks = colorBarTicks(tf.valueRange, tf.logScale);
  l.labels = colorBarLabels(l.ticks, tf.logScale);
  int labelW = 0;
  for (const std::string& label : l.labels)
    labelW = std::max(labelW, textWidth(label, s));
  const int barW = std::max(6, image.width / 40);
  l.x1 = image.width - labelW - 6 * s - 4, l.x0 = l.x1 - barW;
  // Centred, below `top` (what is drawn above it, its title included), inside the bottom margin.
  const int titleH = 14 * s;
  int barH = std::max(20, image.height * 3 / 5);
  l.y0 = std::max((image.height - barH) / 2, top + titleH + 2 * s);
  barH = std::max(8 * s, std::min(barH, image.height - 6 * s - l.y0));
  l.y1 = l.y0 + barH;
  l.head = tf.logScale ? title + " (log)" : title;
  l.headX = std::max(0, l.x1 - textWidth(l.head, s)), l.headY = l.y0 - titleH;
  // What is drawn: the bar in its frame, each tick with its label, the title (each glyph's backing
  // reaches one font unit beyond it).
  l.boxes.push_back({l.x0 - 1, l.y0 - 1, l.x1 + 1, l.y1 + 1});
  for (size_t i = 0; i < l.ticks.size(); ++i) {
    const int y = l.tickRow(tf, i);
    const PixelRect label = textOverRect(l.x1 + 5 * s, y - 4 * s, l.labels[i], s);
    l.boxes.push_back({l.x1, std::min(y, label.y0), label.x1, std::max(y + 1, label.y1)});
  }
  l.boxes.push_back(textOverRect(l.headX, l.headY, l.head, s));
  return l;
}

int ColorBarLayout::tickRow(const TransferFunction& tf, size_t i) const {
  return y1 - int(std::lround(double(tf.normalize(float(ticks.at(i)))) * (y1 - y0)));
}

void drawColorBar(Image& image, const TransferFunction& tf, const ColorBarLayout& l, const vec3f& textColor) {
  const int s = l.scale;
  for (int y = l.y0; y < l.y1; ++y) {
    const float t = 1.f - (float(y - l.y0) + 0.5f) / float(l.y1 - l.y0);
    fillRect(image, l.x0, y, l.x1, y + 1, tf.colorMap.at(t));
  }
  // Frame and ticks.
  drawLine(image, l.x0 - 1, l.y0 - 1, l.x1, l.y0 - 1, textColor);
  drawLine(image, l.x0 - 1, l.y1, l.x1, l.y1, textColor);
  drawLine(image, l.x0 - 1, l.y0 - 1, l.x0 - 1, l.y1, textColor);
  drawLine(image, l.x1, l.y0 - 1, l.x1, l.y1, textColor);
  for (size_t i = 0; i < l.ticks.size(); ++i) {
    const int y = l.tickRow(tf, i);
    drawLine(image, l.x1, y, l.x1 + 3 * s, y, textColor);
    drawTextOver(image, l.x1 + 5 * s, y - 4 * s, l.labels[i], textColor, s);
  }
  drawTextOver(image, l.headX, l.headY, l.head, textColor, s);
}

void drawColorBar(Image& image, const TransferFunction& tf, const std::string& title, const vec3f& textColor, int top) {
  drawColorBar(image, tf, colorBarLayout(image, tf, title, top), textColor);
}

std::string fitText(const std::string& text, int width, int scale) {
  if (textWidth(text, scale) <= width) return text;
  std::string cut = text;
  while (!cut.empty() && textWidth(cut + "...", scale) > width)
    cut.pop_back();
  return cut + "...";
}

int linesHeight(size_t lines, const Image& image) {
  const int s = overlayScale(image);
  return lines == 0 ? 0 : 6 * s + int(lines) * 12 * s;
}

void drawLines(Image& image, const std::vector<std::string>& lines, const vec3f& color) {
  const int s = overlayScale(image);
  for (size_t i = 0; i < lines.size(); ++i)
    drawTextOver(image, 6 * s, 6 * s + int(i) * 12 * s, fitText(lines[i], image.width - 12 * s, s), color, s);
}

void drawBoxOutline(Image& image, const Camera& camera, const box3d& box, const vec3f& color,
                    const std::vector<PixelRect>& keepClear) {
  if (box.empty()) return;
  const double aspect = double(image.width) / double(image.height);
  auto corner = [&](int i) {
    return vec3d(i & 1 ? box.upper.x : box.lower.x, i & 2 ? box.upper.y : box.lower.y,
                 i & 4 ? box.upper.z : box.lower.z);
  };
  for (int a = 0; a < 8; ++a)
    for (int bit : {1, 2, 4}) {
      if (a & bit) continue;
      double u0, v0, u1, v1;
      if (!camera.project(corner(a), aspect, u0, v0) || !camera.project(corner(a | bit), aspect, u1, v1)) continue;
      drawLine(image, u0 * image.width, v0 * image.height, u1 * image.width, v1 * image.height, color, keepClear);
    }
}

void drawLevelLegend(Image& image, const std::vector<int>& levels, const vec3f& textColor) {
  const int s = overlayScale(image);
  int y = image.height - 6 * s - int(levels.size()) * 12 * s;
  for (int level : levels) {
    fillRect(image, 6 * s, y, 14 * s, y + 8 * s, debugLevelColor(level));
    drawText(image, 18 * s, y, strCat("level ", level, ": cells ", int64_t(1) << level, " wide"), textColor, s);
    y += 12 * s;
  }
}

} // namespace exa
