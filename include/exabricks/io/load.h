// Opens whatever the user names: a model file (known by its magic bytes), a native NAME.cells
// dataset, a .grids fixture, an AMReX plotfile directory, or the embedded default dataset when
// no input is given.
#pragma once

#include "exabricks/amr/model.h"
#include "exabricks/io/raw.h"

#include <string>
#include <vector>

namespace exa {

struct LoadOptions {
  std::vector<std::string> fields; ///< fields to load (all when empty)
  BuildOptions build;
  RawOptions raw; ///< dimensions, type and merging of raw volumes
};

enum class InputKind { Default, Model, Native, Grids, Amrex, Chombo, Flash, Enzo, VtkAmr, Raw };

/// Determines the kind of input; throws with the path when it is not recognised.
InputKind detectInput(const std::string& path);

/// Reads raw cells (not for model files).
CellSet loadCells(const std::string& path, const LoadOptions& options = {});

/// Reads a model file, or reads cells and builds the model. Errors name the input.
Model loadModel(const std::string& path, const LoadOptions& options = {});

/// Names of the fields an input holds, without building anything.
std::vector<std::string> listFields(const std::string& path);

} // namespace exa
