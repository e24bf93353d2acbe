// What the parts of exabricks._core share: datasets and meshes as the module hands them to Python,
// and the renderer and series bindings (renderer.cpp, series.cpp) registered by the module.
#pragma once

#include "exabricks/amr/model.h"
#include "exabricks/core/image.h"
#include "exabricks/core/mesh.h"
#include "exabricks/render/renderer.h"
#include "exabricks/workflows/streamed.h"

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <memory>
#include <string>

namespace exa::pymod {

/// A built model, shared by every renderer made from it (they keep it alive).
struct Dataset {
  std::shared_ptr<const Model> model; ///< a step held in parts: its coarse levels (`coarse`), else its skeleton
  DatasetInfo info;                   ///< computed once, shared by its renderers, defaults and warnings
  std::string name;
  double loadSeconds = 0;
  /// A step larger than its memory budget, held in parts (null: `model` holds it whole). Its
  /// parts are read as renders and samples need them; one thread at a time uses it.
  std::shared_ptr<StreamedStep> streamed;
  bool coarse = false;       ///< held in parts, `model` holds its coarse levels: drafts come from them
  bool leavesMerged = false; ///< with `coarse`: `model` holds every cell merged into cubes instead
  /// The whole step's cell bounds (lattice).
  box3i cellBounds() const { return streamed ? streamed->survey().cellBounds : model->cellBounds(); }
  /// The input read (empty: the embedded dataset, or a dataset made from arrays).
  std::string path;
  /// The particles beside the cells: every species of the input, read when a scene first shows
  /// them, or given from Python (from_yt). Null: none.
  std::shared_ptr<const ParticleSet> particles;
  bool particlesKnown = false; ///< read or given
};

/// A triangle mesh made once from numpy arrays or read from a file (`source`, which scene files
/// record): scenes that keep it are not rebuilt.
struct Mesh {
  std::shared_ptr<const TriangleMesh> mesh;
  std::string source;
};

/// An image as an (H, W, 4) float32 array of linear, premultiplied RGBA.
pybind11::array_t<float> imageArray(const Image& image);

/// Registers exabricks._core.Renderer (renderer.cpp).
void bindRenderer(pybind11::module_& m);

/// Registers exabricks._core.Series.
void bindSeries(pybind11::module_& m);

} // namespace exa::pymod
