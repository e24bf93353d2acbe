// The description of a built model as JSON: what `exabricks info --json` prints and what the
// Python module's Dataset.info() returns.
#pragma once

#include "exabricks/amr/model.h"

#include <string>

namespace exa {

/// Cells, bricks and regions (per level), bounds (lattice and world), the world transform,
/// fields with their ranges, memory per structure and build times; `loadSeconds` is the total
/// time to load and build, as the caller measured it.
std::string modelInfoJson(const Model& model, const std::string& input, double loadSeconds);

/// The entries every description of a dataset shares, whole or held in parts: input, cells,
/// bounds (the cells' lattice box and its world box), simulation, world, and fields (names and
/// units of `described`, one range per field). A JSON object.
std::string datasetInfoJson(const Model& described, const std::string& input, uint64_t cells, const box3i& lattice,
                            const std::vector<range1f>& fieldRanges);

} // namespace exa
