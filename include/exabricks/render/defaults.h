// A first picture that shows the data: transfer-function defaults chosen from the field's values
// and a view of the part of the data the transfer function shows. Used by the command line and
// the Python module alike; every choice comes with a note that says what was chosen and why.
#pragma once

#include "exabricks/render/renderer.h"

#include <functional>
#include <string>
#include <vector>

namespace exa {

/// A path-traced frame given neither a sample count nor a noise target: passes to this noise (in
/// 1/255 steps of the 8-bit image), at most kDefaultPathTracedPasses per pixel.
constexpr float kDefaultNoiseTarget = 2.f;
constexpr int kDefaultPathTracedPasses = 1024;

/// A model that holds one part of a dataset (with its halo): the defaults count only the cells
/// whose centres lie in `owned` (lattice), and `sumOverParts` adds the histograms of every part
/// element by element (an all-reduce), so that every part chooses what the whole data would.
struct PartialData {
  box3l owned;
  box3i bounds; ///< lattice bounds of the whole data's cells

  std::function<void(std::vector<double>&)> sumOverParts;
  /// A dataset held in parts one at a time (larger than memory): calls visit(part's model, the
  /// lattice box it owns) for every part, and the defaults count each part's owned cells instead
  /// of the model's.
  std::function<void(const std::function<void(const Model&, const box3l&)>&)> eachPart;
};

struct DefaultChoices {
  TransferFunction tf;
  std::vector<std::string> notes; ///< one line per choice, for stderr, a log or a page
  std::vector<std::string> hints; ///< per note: the command-line options that change it ("" for none)

  void note(std::string text, std::string hint);
  /// The notes with their command-line hints, as the command line prints them.
  std::vector<std::string> commandLineNotes() const;
};

/// Adapts `tf` (whose value range may be empty: the field's) to field `field`:
/// - with `autoLog`, logarithmic mapping when every value is positive, they span more than
///   three decades and a linear map would crowd half the volume into its lowest percent;
/// - with `autoOpacity`, an opacity transparent over the background: the value that fills the
///   most volume (a volume-weighted histogram of the normalised value) and its neighbourhood,
///   and at least the half of the volume on its side (the volume-weighted median): the value
///   range becomes the rest, so that colours and a linear opacity ramp span what lies beyond
///   the background (towards high values unless a dominant background, a fifth of the volume or
///   more, sits in the upper third, then towards low values).
/// Awkward fields first (with `autoOpacity` and no range given): a constant field (to a few
/// float steps) draws nothing and says so; with `autoColorMap`, a field of both signs (each at
/// least a tenth of the other) gets a diverging colour map over a range centred on zero, opaque
/// towards both ends; exact zeros beside positive values over more than three decades map
/// logarithmically over the positive values, zeros at the bottom.
DefaultChoices adaptTransferFunction(const Model& model, const DatasetInfo& dataset, int field,
                                     const TransferFunction& tf, bool autoLog, bool autoOpacity,
                                     const PartialData* part = nullptr, bool autoColorMap = true);

/// A transfer function adapted to one step of a series (`adapted`, chosen from the step's value
/// range `step`), widened to the values `series` of every step: an end that the adaptation left
/// at the step's own end moves to the series' end; the transparent (background) end stays where
/// the step's background ends, so that every step keeps its background transparent; the opaque
/// end moves out by as much as the series reaches beyond the step (by the same factor under
/// logarithmic mapping). A range centred on zero stays centred.
TransferFunction widenedForSeries(const TransferFunction& adapted, const range1f& step, const range1f& series);

/// What in a scene can never show anything, said before rendering: nothing to draw at all (no
/// volume, iso-surface or mesh), iso-values outside their field's range, a value range that
/// excludes all of a layer's data, logarithmic mapping of a field without positive values,
/// path-tracing settings with the ray marcher, and path tracing with zero bounces and no emission.
std::vector<std::string> sceneWarnings(const Scene& scene, const Model& model, const DatasetInfo& dataset);

/// Whether every pixel of an image is transparent (the render shows only the background).
bool imageIsEmpty(const Image& image);

/// The scene as far as what it shows goes, without its shading: a renderer set up only to frame
/// a view (visibleExtent, visibleBounds) then computes no gradients. What is visible does not
/// depend on the shading.
Scene framingScene(Scene scene);

/// What a first view of the scene frames (Renderer::visibleBounds), from a renderer set up for
/// it alone.
box3d visibleBoundsOf(const Model& model, const DatasetInfo& dataset, const Scene& scene);

} // namespace exa
