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

#include <memory>
#include <string>
#include <vector>

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

/// A model file's table without its values or regions, for a step read brick by brick: the
/// header, the world, the bricks and the fields checked against the file (sizes, each brick's
/// place among the values), the file kept open. The checksum, which covers every value, is
/// verified where the model is read whole (readModel).
struct ModelTable {
  WorldTransform world;
  std::vector<Brick> bricks;
  std::vector<std::string> fieldNames;
  std::vector<uint64_t> valuesAt;  ///< per field, the file offset of its first value
  std::shared_ptr<const int> file; ///< the open descriptor
  /// Brick b's values of `field` (b.cellCount() of them, x fastest) into `out`.
  void readValues(const std::string& path, size_t field, const Brick& b, float* out) const;
};
ModelTable readModelTable(const std::string& path);

} // namespace exa
