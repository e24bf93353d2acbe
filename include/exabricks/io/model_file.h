// The exabricks model file: one versioned binary file holding bricks, regions and fields, so
// that large datasets are built once. Layout (little-endian):
//   header  : magic "EXABRMDL", uint32 version, uint32 header size (48), uint64 payload size,
//             uint64 checksum of the payload (FNV-1a over 64-bit words), 16 reserved bytes
//   payload : world transform (6 float64); bricks; fields (name, brick-ordered float32
//             values); regions; region brick ids; k-d tree nodes; root bounds; per field
//             value ranges; build times (3 float64). Every array is preceded by its uint64
//             length and (version 2) zeros up to the next multiple of 8 bytes in the file, so
//             that the values can be used in place from a mapped file. Version 1 files (no
//             padding) are still read; their values are copied.
#pragma once

#include "exabricks/amr/model.h"

#include <string>

namespace exa {

constexpr char kModelMagic[8] = {'E', 'X', 'A', 'B', 'R', 'M', 'D', 'L'};
constexpr uint32_t kModelVersion = 2;

/// True when the file starts with the model magic.
bool isModelFile(const std::string& path);

/// Writes the model atomically (temporary file, then rename).
void writeModel(const Model& model, const std::string& path);

/// Reads and verifies a model file; corrupt, truncated or foreign files are rejected with a
/// message naming the file and the problem. The file is mapped where the platform allows and
/// the field values are used in place (read-only, kept mapped while the model's values live);
/// bricks and regions are copied.
Model readModel(const std::string& path);

} // namespace exa
