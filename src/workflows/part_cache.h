// The parts of a step held under a memory budget, kept on disk once built: each part's model is
// written to a file in the temporary folder the first time it is read and built, and read from
// there (a mapped model file: no reading of the source, no build) when it is needed again. The
// files are unlinked as soon as they are written and live only as open descriptors, so that they
// vanish with the process however it ends.
#pragma once

#include "exabricks/amr/gradients.h"
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
  /// Smooth shading's gradient fields of part p's field f as last written, for a part of `cells`
  /// cells in `bricks` bricks (none when none were written); keeping them (in place of any
  /// written before); and whether `gradients` have bricks built that those written lack.
  std::optional<GradientFields> readGradients(int part, int field, size_t cells, size_t bricks) const;
  void writeGradients(int part, int field, const GradientFields& gradients);
  bool buildsMore(int part, int field, const GradientFields& gradients) const;
  /// Parts read back from the cache so far.
  uint64_t hits() const { return hits_; }
  /// Gradient fields read back so far.
  uint64_t gradientHits() const { return gradientHits_; }

private:
  std::string folder_;   ///< private folder the files pass through (empty: off)
  std::vector<int> fds_; ///< per part, the unlinked file's descriptor, or -1
  /// per (part, field), likewise, and the bricks not built in what it holds
  std::map<std::pair<int, int>, std::pair<int, size_t>> gradientFds_;
  /// A new file of the folder, written by `write(path)`: its descriptor, the file unlinked; -1
  /// (and the cache off, with a warning) when it cannot be written.
  int keep(const std::string& name, const std::function<void(const std::string&)>& write);
  void turnOff(const std::string& why);
  mutable uint64_t hits_ = 0, gradientHits_ = 0;
};

} // namespace exa
