#include "exabricks/render/legends.h"

#include "exabricks/amr/model.h"
#include "exabricks/amr/scenes.h"
#include "exabricks/core/error.h"
#include "exabricks/render/overlay.h"

#include <filesystem>
#include <optional>

namespace exa {

std::string legendDatasetLabel(const std::string& input) {
  if (input.empty()) return kDefaultDatasetName;
  std::filesystem::path p = std::filesystem::path(input).lexically_normal();
  if (p.filename().empty()) p = p.parent_path(); // a folder written with a trailing slash
  const std::string name = p.filename().string();
  return name.empty() || name == "." || name == ".." ? input : name;
}

namespace {

/// The annotation's lines for an image `width` pixels wide: the dataset, the field, then the
/// simulation's redshift, time and cycle, as many to a line as fit.
std::vector<std::string> annotationLines(const Model& model, const std::string& field, const LegendText& text,
                                         int width, int scale) {
  std::vector<std::string> lines{text.dataset, "field " + field};
  const SimulationState& sim = model.simulation;
  std::vector<std::string> parts;
  if (sim.hasRedshift()) parts.push_back(strCat("redshift ", sim.redshift));
  if (sim.hasTime())
    parts.push_back(strCat("time ", sim.time, sim.timeUnits.empty() ? "" : " (" + sim.timeUnits + ")"));
  if (sim.hasCycle()) parts.push_back(strCat("cycle ", sim.cycle));
  std::string line;
  for (const std::string& p : parts) {
    const std::string longer = line.empty() ? p : line + ", " + p;
    if (!line.empty() && textWidth(longer, scale) > width) {
      lines.push_back(line);
      line = p;
    } else {
      line = longer;
    }
  }
  if (!line.empty()) lines.push_back(line);
  return lines;
}

} // namespace

std::vector<PixelRect> drawLegends(const Scene& scene, const Frame& frame, const Model& model,
                                   const DatasetInfo& dataset, const LegendText& text, Image& image) {
  const Legends& want = scene.legends;
  if (!want.colorBar && !want.annotation && !want.levelLegend) return {};
  const vec3f ink = legendInk(scene.background);
  const int field = model.requireField(scene.layers.at(0).field);
  const std::string name = model.fieldNames[size_t(field)];
  if (want.levelLegend && scene.debug == DebugView::Level) {
    std::vector<int> levels = text.levels;
    if (levels.empty())
      for (const ModelSummary::Level& l : summarize(model).levels)
        levels.push_back(l.level);
    drawLevelLegend(image, levels, ink);
  }
  // The colour bar and the annotation's lines draw over the picture; the domain's outline keeps
  // off the colour bar's boxes.
  const std::vector<std::string> lines =
      want.annotation ? annotationLines(model, name, text, image.width - 12 * overlayScale(image), overlayScale(image))
                      : std::vector<std::string>();
  std::optional<ColorBarLayout> bar;
  TransferFunction tf = scene.layers.at(0).tf;
  if (want.colorBar && scene.debug == DebugView::None && scene.volume) {
    if (tf.valueRange.empty()) tf.valueRange = dataset.valueRanges.at(size_t(field));
    const std::string units = model.unitsOf(field);
    bar = colorBarLayout(image, tf, units.empty() ? name : name + " [" + units + "]", linesHeight(lines.size(), image));
  }
  if (want.annotation) {
    const box3i cb = text.cellBounds.empty() ? model.cellBounds() : text.cellBounds;
    drawBoxOutline(image, frame.camera, model.world.toWorld(cb), ink * 0.6f,
                   bar ? bar->boxes : std::vector<PixelRect>());
  }
  if (bar) drawColorBar(image, tf, *bar, ink);
  if (want.annotation) drawLines(image, lines, ink);
  return bar ? bar->boxes : std::vector<PixelRect>();
}

} // namespace exa
