#include "bench_plot.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <map>

namespace exa::cli {
namespace {

/// 5x7 bitmap glyphs for the characters the plots use; unknown characters draw as blanks.
const std::map<char, std::array<const char*, 7>>& glyphs() {
  static const std::map<char, std::array<const char*, 7>> g = {
      {'0', {" ### ", "#   #", "#  ##", "# # #", "##  #", "#   #", " ### "}},
      {'1', {"  #  ", " ##  ", "  #  ", "  #  ", "  #  ", "  #  ", " ### "}},
      {'2', {" ### ", "#   #", "    #", "   # ", "  #  ", " #   ", "#####"}},
      {'3', {"#####", "   # ", "  #  ", "   # ", "    #", "#   #", " ### "}},
      {'4', {"   # ", "  ## ", " # # ", "#  # ", "#####", "   # ", "   # "}},
      {'5', {"#####", "#    ", "#### ", "    #", "    #", "#   #", " ### "}},
      {'6', {"  ## ", " #   ", "#    ", "#### ", "#   #", "#   #", " ### "}},
      {'7', {"#####", "    #", "   # ", "  #  ", " #   ", " #   ", " #   "}},
      {'8', {" ### ", "#   #", "#   #", " ### ", "#   #", "#   #", " ### "}},
      {'9', {" ### ", "#   #", "#   #", " ####", "    #", "   # ", " ##  "}},
      {'.', {"     ", "     ", "     ", "     ", "     ", " ##  ", " ##  "}},
      {',', {"     ", "     ", "     ", "     ", " ##  ", "  #  ", " #   "}},
      {'-', {"     ", "     ", "     ", "#####", "     ", "     ", "     "}},
      {'=', {"     ", "     ", "#####", "     ", "#####", "     ", "     "}},
      {'(', {"   # ", "  #  ", " #   ", " #   ", " #   ", "  #  ", "   # "}},
      {')', {" #   ", "  #  ", "   # ", "   # ", "   # ", "  #  ", " #   "}},
      {':', {"     ", " ##  ", " ##  ", "     ", " ##  ", " ##  ", "     "}},
      {'/', {"     ", "    #", "   # ", "  #  ", " #   ", "#    ", "     "}},
      {'a', {"     ", "     ", " ### ", "    #", " ####", "#   #", " ####"}},
      {'b', {"#    ", "#    ", "# ## ", "##  #", "#   #", "#   #", "#### "}},
      {'c', {"     ", "     ", " ### ", "#    ", "#    ", "#   #", " ### "}},
      {'d', {"    #", "    #", " ## #", "#  ##", "#   #", "#   #", " ####"}},
      {'e', {"     ", "     ", " ### ", "#   #", "#####", "#    ", " ### "}},
      {'f', {"  ## ", " #  #", " #   ", "###  ", " #   ", " #   ", " #   "}},
      {'g', {"     ", " ####", "#   #", "#   #", " ####", "    #", " ### "}},
      {'h', {"#    ", "#    ", "# ## ", "##  #", "#   #", "#   #", "#   #"}},
      {'i', {"  #  ", "     ", " ##  ", "  #  ", "  #  ", "  #  ", " ### "}},
      {'j', {"   # ", "     ", "  ## ", "   # ", "   # ", "#  # ", " ##  "}},
      {'k', {"#    ", "#    ", "#  # ", "# #  ", "##   ", "# #  ", "#  # "}},
      {'l', {" ##  ", "  #  ", "  #  ", "  #  ", "  #  ", "  #  ", " ### "}},
      {'m', {"     ", "     ", "## # ", "# # #", "# # #", "#   #", "#   #"}},
      {'n', {"     ", "     ", "# ## ", "##  #", "#   #", "#   #", "#   #"}},
      {'o', {"     ", "     ", " ### ", "#   #", "#   #", "#   #", " ### "}},
      {'p', {"     ", "     ", "#### ", "#   #", "#### ", "#    ", "#    "}},
      {'q', {"     ", "     ", " ## #", "#  ##", " ####", "    #", "    #"}},
      {'r', {"     ", "     ", "# ## ", "##  #", "#    ", "#    ", "#    "}},
      {'s', {"     ", "     ", " ### ", "#    ", " ### ", "    #", "#### "}},
      {'t', {" #   ", " #   ", "###  ", " #   ", " #   ", " #  #", "  ## "}},
      {'u', {"     ", "     ", "#   #", "#   #", "#   #", "#  ##", " ## #"}},
      {'v', {"     ", "     ", "#   #", "#   #", "#   #", " # # ", "  #  "}},
      {'w', {"     ", "     ", "#   #", "#   #", "# # #", "# # #", " # # "}},
      {'x', {"     ", "     ", "#   #", " # # ", "  #  ", " # # ", "#   #"}},
      {'y', {"     ", "     ", "#   #", "#   #", " ####", "    #", " ### "}},
      {'z', {"     ", "     ", "#####", "   # ", "  #  ", " #   ", "#####"}},
      {'M', {"#   #", "## ##", "# # #", "# # #", "#   #", "#   #", "#   #"}},
      {'G', {" ### ", "#   #", "#    ", "# ###", "#   #", "#   #", " ####"}},
  };
  return g;
}

constexpr int kScale = 2;            ///< font pixels per glyph pixel
constexpr int kAdvance = 6 * kScale; ///< glyph width plus spacing
constexpr int kTextHeight = 7 * kScale;

struct Canvas {
  Image& image;
  void put(int x, int y, const vec4f& c) {
    if (x >= 0 && y >= 0 && x < image.width && y < image.height) image.at(x, y) = c;
  }
  void rect(int x0, int y0, int x1, int y1, const vec4f& c) {
    for (int y = y0; y <= y1; ++y)
      for (int x = x0; x <= x1; ++x)
        put(x, y, c);
  }
  int textWidth(const std::string& s) const { return int(s.size()) * kAdvance; }
  void text(int x, int y, const std::string& s, const vec4f& c) {
    for (char ch : s) {
      const auto it = glyphs().find(ch);
      if (it != glyphs().end())
        for (int r = 0; r < 7; ++r)
          for (int k = 0; k < 5; ++k)
            if (it->second[size_t(r)][k] == '#')
              rect(x + k * kScale, y + r * kScale, x + k * kScale + kScale - 1, y + r * kScale + kScale - 1, c);
      x += kAdvance;
    }
  }
  void disc(int cx, int cy, int radius, const vec4f& c) {
    for (int y = -radius; y <= radius; ++y)
      for (int x = -radius; x <= radius; ++x)
        if (x * x + y * y <= radius * radius) put(cx + x, cy + y, c);
  }
};

/// Round tick step giving about `target` intervals over [0, maxValue].
double tickStep(double maxValue, int target) {
  if (!(maxValue > 0)) return 1.0;
  const double raw = maxValue / target;
  const double mag = std::pow(10.0, std::floor(std::log10(raw)));
  for (double m : {1.0, 2.0, 2.5, 5.0, 10.0})
    if (m * mag >= raw) return m * mag;
  return 10.0 * mag;
}

std::string number(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%g", std::abs(v) < 1e-12 ? 0.0 : v);
  return buf;
}

void drawPanel(Canvas& cv, const ScatterPanel& p, int left, int width, int height) {
  const vec4f black{0.f, 0.f, 0.f, 1.f}, grey{0.8f, 0.8f, 0.8f, 1.f}, blue{0.05f, 0.2f, 0.75f, 1.f};
  const int plotX0 = left + 100, plotX1 = left + width - 30;
  const int plotY0 = 70, plotY1 = height - 80;
  double maxX = 0, maxY = 0;
  for (double v : p.x)
    maxX = std::max(maxX, v);
  for (double v : p.y)
    maxY = std::max(maxY, v);
  const double stepX = tickStep(maxX, 5), stepY = tickStep(maxY, 5);
  const double spanX = std::max(stepX, std::ceil(maxX / stepX - 1e-9) * stepX);
  const double spanY = std::max(stepY, std::ceil(maxY / stepY - 1e-9) * stepY);
  auto px = [&](double v) { return plotX0 + int(std::lround(v / spanX * (plotX1 - plotX0))); };
  auto py = [&](double v) { return plotY1 - int(std::lround(v / spanY * (plotY1 - plotY0))); };

  cv.text(left + (width - cv.textWidth(p.title)) / 2, 12, p.title, black);
  cv.text(plotX0 - 60, plotY0 - 28, p.yLabel, black);
  cv.text(plotX0 + (plotX1 - plotX0 - cv.textWidth(p.xLabel)) / 2, plotY1 + 48, p.xLabel, black);
  // Grid lines and ticks with their values.
  for (int i = 0; i * stepX <= spanX + 1e-9 * spanX; ++i) {
    const int x = px(i * stepX);
    cv.rect(x, plotY0, x, plotY1, grey);
    cv.rect(x, plotY1, x, plotY1 + 8, black);
    const std::string s = number(i * stepX);
    cv.text(x - cv.textWidth(s) / 2, plotY1 + 14, s, black);
  }
  for (int i = 0; i * stepY <= spanY + 1e-9 * spanY; ++i) {
    const int y = py(i * stepY);
    cv.rect(plotX0, y, plotX1, y, grey);
    cv.rect(plotX0 - 8, y, plotX0, y, black);
    const std::string s = number(i * stepY);
    cv.text(plotX0 - 14 - cv.textWidth(s), y - kTextHeight / 2, s, black);
  }
  // Axes frame.
  cv.rect(plotX0, plotY0, plotX1, plotY0 + 1, black);
  cv.rect(plotX0, plotY1 - 1, plotX1, plotY1, black);
  cv.rect(plotX0, plotY0, plotX0 + 1, plotY1, black);
  cv.rect(plotX1 - 1, plotY0, plotX1, plotY1, black);
  for (size_t i = 0; i < std::min(p.x.size(), p.y.size()); ++i)
    cv.disc(px(p.x[i]), py(p.y[i]), 4, blue);
}

} // namespace

Image drawScatterPanels(const std::vector<ScatterPanel>& panels, int panelWidth, int height) {
  Image image(std::max(1, panelWidth * int(panels.size())), height);
  std::fill(image.pixels.begin(), image.pixels.end(), vec4f{1.f, 1.f, 1.f, 1.f});
  Canvas cv{image};
  for (size_t i = 0; i < panels.size(); ++i)
    drawPanel(cv, panels[i], int(i) * panelWidth, panelWidth, height);
  return image;
}

} // namespace exa::cli
