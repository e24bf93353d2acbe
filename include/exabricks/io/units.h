// Units of simulation fields where the format fixes them by convention: FLASH writes CGS
// quantities under fixed variable names, Enzo writes temperature in kelvin and other fields in
// its code units. Readers whose files record units themselves set Field::units directly.
#pragma once

#include "exabricks/amr/cells.h"
#include "exabricks/io/reader.h"

#include <string>

namespace exa {

/// The units a field of this name has in outputs of this kind ("" where unknown).
std::string conventionalUnits(InputKind kind, const std::string& field);

/// Sets the units of every field that has none from conventionalUnits.
void assignConventionalUnits(InputKind kind, CellSet& set);

} // namespace exa
