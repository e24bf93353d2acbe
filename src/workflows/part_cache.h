// The parts of a step held under a memory budget, kept on disk once built: each part's model is
// written to a file in the temporary folder the first time it is read and built, and read from
// there (a mapped model file: no reading of the source, no build) when it is needed again. The
// files are unlinked as soon as they are written and live only as open descriptors, so that they
// vanish with the process however it ends.
#pragma once

#include "exabricks/amr/model.h"

#include <array>
#include <cstdint>
#include <functional>
#include <map>
#include <optional>
#include <string>
#include <vector>

namespace exa {

class PartCache {
public:
  /// A cache for `parts` parts, on when the temporary folder ($TMPDIR, else /tmp) has room for
  /// `bytes` twice over (the parts' models, estimated; 0: off) and EXABRICKS_PART_CACHE is not 0.
  PartCache(int parts, uint64_t bytes);
  ~PartCache();
  PartCache(const PartCache&) = delete;
  PartCache& operator=(const PartCache&) = delete;

  bool on() const { return !folder_.empty(); }
  /// Part p's model as written, or none when it has not been.
  std::optional<Model> read(int part) const;
  /// Keeps part p's model; a failure to write (a full disk) turns the cache off with a warning.
  void write(int part, const Model& model);
  /// Smooth shading's gradient fields of part p's field f, as written (none when they have not
  /// been), and keeping them.
  std::optional<std::array<std::vector<float>, 3>> readGradients(int part, int field) const;
  void writeGradients(int part, int field, const std::array<std::vector<float>, 3>& gradients);
  bool hasGradients(int part, int field) const { return gradientFds_.count({part, field}) > 0; }
  /// Parts read back from the cache so far.
  uint64_t hits() const { return hits_; }

private:
  std::string folder_;                             ///< private folder the files pass through (empty: off)
  std::vector<int> fds_;                           ///< per part, the unlinked file's descriptor, or -1
  std::map<std::pair<int, int>, int> gradientFds_; ///< per (part, field), likewise
  /// A new file of the folder, written by `write(path)`: its descriptor, the file unlinked; -1
  /// (and the cache off, with a warning) when it cannot be written.
  int keep(const std::string& name, const std::function<void(const std::string&)>& write);
  void turnOff(const std::string& why);
  mutable uint64_t hits_ = 0;
};

} // namespace exa
