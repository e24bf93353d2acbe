// Scatter plots drawn straight into an Image (for the orbit study of `exabricks bench`): framed
// panels with tick marks and numbers in a small built-in bitmap font.
#pragma once

#include "exabricks/documents/image.h"

#include <string>
#include <vector>

namespace exa::cli {

struct ScatterPanel {
  std::string title;
  std::string xLabel, yLabel;
  std::vector<double> x, y;
};

/// Draws the panels side by side, each `panelWidth` x `height` pixels, on white.
Image drawScatterPanels(const std::vector<ScatterPanel>& panels, int panelWidth, int height);

} // namespace exa::cli
