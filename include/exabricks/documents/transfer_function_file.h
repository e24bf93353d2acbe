// Transfer function files: ParaView colour-map presets and exabricks JSON
// (render/transfer_function.h parses the text).
#pragma once

#include "exabricks/render/transfer_function.h"

#include <string>

namespace exa {

/// Reads a transfer function file (parseTransferFunction's forms); errors name the file and the
/// problem.
TransferFunction readTransferFunction(const std::string& path, bool* isPreset = nullptr);

} // namespace exa
