// The parts of an Enzo output that both its cell and its particle readers use: the parameter
// file's keys, the hierarchy's grids and the data files they name.
#pragma once

#include "hdf5_file.h"

#include "exabricks/amr/cells.h"
#include "exabricks/core/error.h"

#include <filesystem>
#include <map>
#include <memory>
#include <string>
#include <vector>

namespace exa::io::enzo {

struct Parameters {
  int rank = 3;
  int64_t refineBy = 2;
  vec3d left{0.0}, right{1.0};
  SimulationState simulation;
};

struct Grid {
  int64_t id = 0;
  size_t line = 0;
  int rank = 0;
  vec3l dimension{0}, start{0}, end{0};
  vec3d left{0.0}, right{0.0};
  std::string file; ///< data file beside the hierarchy
  int64_t fields = -1;
  int64_t particles = 0;
  std::string particleFile; ///< data file of the particles, beside the hierarchy
  unsigned seen = 0;
  vec3l active() const { return end - start + vec3l(1); }
};

struct Output {
  std::string parameterPath, hierarchyPath;
  Parameters params;
  std::vector<Grid> grids;
};

/// Reads the parameter file and the hierarchy (`path` names either) and checks every grid.
Output readOutput(const std::string& path);

/// The data files, opened once each.
class DataFiles {
public:
  const h5::File& get(const std::string& path) {
    auto it = files_.find(path);
    if (it == files_.end()) {
      std::error_code ec;
      if (!std::filesystem::exists(path, ec)) fail(path, ": missing data file of the Enzo output");
      it = files_.emplace(path, std::make_unique<h5::File>(path)).first;
    }
    return *it->second;
  }

private:
  std::map<std::string, std::unique_ptr<h5::File>> files_;
};

/// A grid's group name ("/Grid00000001").
std::string groupOf(int64_t id);
/// The grid's group in its data file, which must hold it (`h` names the hierarchy).
std::string gridGroup(const h5::File& f, const Grid& g, const std::string& h);

} // namespace exa::io::enzo
