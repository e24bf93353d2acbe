// Opens whatever the user names: a model file (known by its magic bytes), any input a registered
// reader recognises (io/reader.h), or the embedded default dataset when no input is given.
#pragma once

#include "exabricks/amr/model.h"
#include "exabricks/io/reader.h"

#include <optional>
#include <string>
#include <vector>

namespace exa {

struct LoadOptions {
  std::vector<std::string> fields; ///< fields to load (all when empty)
  BuildOptions build;
  RawOptions raw; ///< dimensions, type and merging of raw volumes
  box3i box;      ///< finest-lattice box: only cells that overlap it (empty: all)
};

/// Determines the kind of input; throws with the path when it is not recognised.
InputKind detectInput(const std::string& path);

/// Reads raw cells (not for model files).
CellSet loadCells(const std::string& path, const LoadOptions& options = {});

/// Reads a model file, or reads cells and builds the model. Errors name the input.
Model loadModel(const std::string& path, const LoadOptions& options = {});

/// A field's value range from the input's metadata alone, where its format records one (AMReX
/// plotfiles: the per-box minima and maxima); none otherwise.
std::optional<range1f> fieldRangeFromMetadata(const std::string& path, const std::string& field);

/// Names of the fields an input holds, without building anything.
std::vector<std::string> listFields(const std::string& path);

} // namespace exa
