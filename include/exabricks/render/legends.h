// The legends a scene asks for (Scene::legends), drawn into a rendered image: the colour bar of
// the first layer, the annotation (dataset name, field, simulation time and cycle, and the outline
// of the data's domain) and the legend of the level colours of the level debug view. One drawing
// for the command line, movies, the viewer and Python.
#pragma once

#include "exabricks/core/image.h"
#include "exabricks/render/overlay.h"
#include "exabricks/render/renderer.h"
#include "exabricks/render/scene.h"

#include <string>
#include <vector>

namespace exa {

struct Model;

/// What the legends say that the model does not know, and what a process holding one part of the
/// data (data-parallel rendering) knows of the whole.
struct LegendText {
  std::string dataset;     ///< the first line of the annotation (legendDatasetLabel)
  std::vector<int> levels; ///< the level legend's levels; empty: the model's
  box3i cellBounds;        ///< the outlined domain (lattice); empty: the model's
};

/// The dataset's name as legends show it: the last component of its path ("run/plt00100/" is
/// "plt00100"), or the default dataset's description for an empty path.
std::string legendDatasetLabel(const std::string& input);

/// Draws the legends `scene.legends` asks for into `image` (in `frame`'s camera): the colour bar
/// with the volume on and no debug view, the level legend with the level debug view, the
/// annotation always. Draws nothing when none is asked for. They draw over the picture: the
/// colour bar changes no pixel outside the boxes it returns (empty without a colour bar).
std::vector<PixelRect> drawLegends(const Scene& scene, const Frame& frame, const Model& model,
                                   const DatasetInfo& dataset, const LegendText& text, Image& image);

} // namespace exa
