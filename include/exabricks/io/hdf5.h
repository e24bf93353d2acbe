// HDF5 input in general: recognising an HDF5 file by its signature.
#pragma once

#include <string>

namespace exa {

/// True when the file carries the HDF5 signature (whatever its layout).
bool isHdf5File(const std::string& path);

} // namespace exa
