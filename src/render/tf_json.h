// Transfer functions as nlohmann::json, for the scene file (private to the library).
#pragma once

#include "exabricks/render/transfer_function.h"

#include <nlohmann/json.hpp>

namespace exa {

/// An exabricks transfer-function object or a ParaView preset (object or array); errors name
/// `source`.
TransferFunction transferFunctionFromJson(const nlohmann::json& j, const std::string& source);
nlohmann::json transferFunctionToJson(const TransferFunction& tf);

/// Every number of `j` that holds a single-precision value written in its shortest form
/// (withoutFloatNoise), for documents people read: scene files, transfer functions, the keys.
void removeFloatNoise(nlohmann::json& j);

} // namespace exa
