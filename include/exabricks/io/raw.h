// Raw dense volumes (headerless x-fastest arrays of uint8, uint16, float32 or float64, little-
// endian) turned into multi-level AMR cells: 2x2x2 blocks whose values spread no more than a
// threshold are merged, level by level, up to a maximum level. Dimensions and type come from
// options or from a name such as NAME_512x512x256_uint8.raw.
#pragma once

#include "exabricks/amr/cells.h"

#include <string>
#include <vector>

namespace exa {

struct RawOptions {
  vec3l dims{0};          ///< voxels per axis (0: take them from the file name)
  std::string type;       ///< uint8, uint16, float32 or float64 (empty: from the file name)
  double threshold = 0.0; ///< largest value spread (max - min) of a merged cell
  int maxLevel = 4;       ///< coarsest merged cells are 2^maxLevel voxels wide
};

/// True when the path ends in ".raw".
bool isRawVolume(const std::string& path);

/// Fills dims and type from a NAME_NXxNYxNZ_TYPE.raw file name; false when it does not match.
bool parseRawName(const std::string& path, RawOptions& out);

/// Reads a raw volume and merges it into cells (field "scalar"). Options given explicitly win
/// over the file name; errors name the file and the problem.
CellSet readRaw(const std::string& path, const RawOptions& options);

/// Merges a dense x-fastest volume into cells: a cell of level l is kept when all its voxels
/// lie within `threshold` of each other (max - min) and its parent is not kept; its value is
/// the voxels' mean. Blocks that would reach past the volume stay finer.
CellSet mergeDenseVolume(const std::vector<float>& voxels, vec3l dims, double threshold, int maxLevel);

} // namespace exa
