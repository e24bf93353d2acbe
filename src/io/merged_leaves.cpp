// A first picture of an input whose coarse levels cannot be read alone: every leaf cell merged
// into cubes of one width, read piece by piece (see load.h, loadMergedLeaves).
#include "patch_load.h"

#include "exabricks/core/error.h"
#include "exabricks/core/log.h"
#include "exabricks/io/load.h"
#include "exabricks/io/native.h"

#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <mutex>
#include <unordered_map>

namespace exa {

namespace {

/// Volume-weighted sums of leaf values per cube `width` finest cells wide, keyed sparsely (cells
/// may lie far apart: nothing is allocated by bounding volume).
class CubeSums {
public:
  CubeSums(int level, size_t fields)
      : level_(level), width_(int64_t(1) << level), sums_(fields), ranges_(fields), local_(fields) {}

  /// The cells of a box of same-width cells (x fastest): lower corner and width in finest
  /// units, cells per axis, one value array per field. Widths above the cubes' are not merged
  /// here (loadMergedLeaves chooses cubes at least as wide as every cell).
  void addBox(const vec3l& lower, const vec3l& cells, int64_t width, const std::vector<const float*>& values) {
    vec3l first, last; // cubes the box reaches
    for (int a = 0; a < 3; ++a) {
      first[a] = floorDiv(lower[a], width_);
      last[a] = floorDiv(lower[a] + cells[a] * width - 1, width_);
    }
    // Cell index range of the box within cube c along axis a.
    auto span = [&](int a, int64_t c, int64_t& begin, int64_t& end) {
      begin = std::max<int64_t>(0, (c * width_ - lower[a] + width - 1) / width);
      end = std::min<int64_t>(cells[a], (c * width_ + width_ - lower[a] + width - 1) / width);
    }; // a negative numerator's quotient rounds towards zero, to 0 or below: begin is 0 then
    const double volume = double(width) * double(width) * double(width);
    for (int64_t cz = first.z; cz <= last.z; ++cz)
      for (int64_t cy = first.y; cy <= last.y; ++cy)
        for (int64_t cx = first.x; cx <= last.x; ++cx) {
          int64_t b[3], e[3];
          span(0, cx, b[0], e[0]), span(1, cy, b[1], e[1]), span(2, cz, b[2], e[2]);
          if (e[0] <= b[0] || e[1] <= b[1] || e[2] <= b[2]) continue;
          const uint32_t slot = slotOf({cx, cy, cz});
          std::fill(local_.begin(), local_.end(), 0.0);
          double n = 0;
          for (int64_t z = b[2]; z < e[2]; ++z)
            for (int64_t y = b[1]; y < e[1]; ++y)
              for (int64_t x = b[0]; x < e[0]; ++x)
                n += addValues(values, size_t((z * cells.y + y) * cells.x + x), 1.0);
          for (size_t f = 0; f < sums_.size(); ++f)
            sums_[f][slot] += local_[f] * volume;
          weights_[slot] += n * volume;
        }
  }

  /// One cell (its value `values[f][0]` per field), as addBox adds a box of one; consecutive
  /// cells mostly share a cube, found once for them.
  void addCell(const Cell& c, const std::vector<const float*>& values) {
    const vec3l key(floorDiv(c.lower.x, width_), floorDiv(c.lower.y, width_), floorDiv(c.lower.z, width_));
    if (weights_.empty() || !(key == lastKey_)) lastSlot_ = slotOf(key), lastKey_ = key;
    const double volume = std::pow(8.0, double(c.level));
    std::fill(local_.begin(), local_.end(), 0.0);
    if (!addValues(values, 0, volume)) return;
    for (size_t f = 0; f < sums_.size(); ++f)
      sums_[f][lastSlot_] += local_[f];
    weights_[lastSlot_] += volume;
  }

  /// Adds another's sums (of cells it holds and this does not).
  void add(const CubeSums& other) {
    for (const auto& [key, slot] : other.index_) {
      const uint32_t to = slotOf(key);
      weights_[to] += other.weights_[slot];
      for (size_t f = 0; f < sums_.size(); ++f)
        sums_[f][to] += other.sums_[f][slot];
    }
    for (size_t f = 0; f < ranges_.size(); ++f)
      if (!other.ranges_[f].empty()) {
        ranges_[f].extend(other.ranges_[f].lower);
        ranges_[f].extend(other.ranges_[f].upper);
      }
  }

  const std::vector<range1f>& ranges() const { return ranges_; }

  /// The cubes as cells, each holding the mean of its cells (cubes no finite value reached are
  /// left out).
  void cellsInto(CellSet& set) const {
    set.cells.reserve(weights_.size());
    for (Field& f : set.fields)
      f.values.reserve(weights_.size());
    for (const auto& [key, slot] : index_) {
      if (!(weights_[slot] > 0)) continue;
      set.cells.push_back(
          Cell{vec3i(int32_t(key.x * width_), int32_t(key.y * width_), int32_t(key.z * width_)), int32_t(level_)});
      for (size_t f = 0; f < sums_.size(); ++f)
        set.fields[f].values.push_back(float(sums_[f][slot] / weights_[slot]));
    }
  }

private:
  struct KeyHash {
    size_t operator()(const vec3l& k) const {
      uint64_t h = uint64_t(k.x) * 0x9E3779B97F4A7C15ull;
      h ^= uint64_t(k.y) * 0xC2B2AE3D27D4EB4Full + (h >> 29);
      h ^= uint64_t(k.z) * 0x165667B19E3779F9ull + (h >> 31);
      return size_t(h ^ (h >> 32));
    }
  };
  /// Adds cell i's values, times `weight`, to local_ and the ranges; false (nothing added) where
  /// one is not finite (a hole, which the parts' reads name).
  bool addValues(const std::vector<const float*>& values, size_t i, double weight) {
    for (const float* v : values)
      if (!std::isfinite(v[i])) return false;
    for (size_t f = 0; f < values.size(); ++f) {
      local_[f] += double(values[f][i]) * weight;
      ranges_[f].extend(values[f][i]);
    }
    return true;
  }
  uint32_t slotOf(const vec3l& key) {
    const auto [it, added] = index_.try_emplace(key, uint32_t(weights_.size()));
    if (added) {
      weights_.push_back(0);
      for (std::vector<double>& s : sums_)
        s.push_back(0);
    }
    return it->second;
  }
  int level_;
  int64_t width_;
  vec3l lastKey_;
  uint32_t lastSlot_ = 0;
  std::unordered_map<vec3l, uint32_t, KeyHash> index_;
  std::vector<double> weights_;
  std::vector<std::vector<double>> sums_;
  std::vector<range1f> ranges_;
  std::vector<double> local_; ///< one cube's sums of a box or cell, per field
};

/// The cells' volume in finest cells.
double volumeOf(const Census& census) {
  double volume = 0;
  for (size_t l = 0; l < census.levelCells.size(); ++l)
    volume += census.levelCells[l] * std::pow(8.0, double(l));
  return volume;
}

/// The narrowest cubes, at least as wide as every cell, whose count the cells' volume keeps
/// within `maxCells` (the cubes at the edges of the cells' boxes add a few).
int cubeLevel(const Census& census, double maxCells) {
  const double volume = volumeOf(census);
  int level = census.coarsestLevel;
  while (level < kMaxLevel && volume / std::pow(8.0, double(level)) > maxCells)
    ++level;
  return level;
}

/// NAME.cells read 65,536 records at a time, its cells summed into cubes 2^level wide: the
/// cubes as cells, and the cells' value ranges.
CellSet mergedNative(const std::string& path, const LoadOptions& options, int level, std::vector<range1f>& ranges) {
  const uint64_t count = fileSize(path) / sizeof(Cell);
  const std::vector<std::string> names = nativeFieldsToRead(path, options.fields, count);
  CubeSums sums(level, names.size());
  Progress progress("merging every cell for a first picture", count);
  const bool holes = options.nonFinite == NonFinite::Holes;
  streamNative(path, names, holes, [&](const Cell* cells, const std::vector<const float*>& values, size_t n) {
    progress.advance(n);
    std::vector<const float*> at(values.size());
    for (size_t i = 0; i < n; ++i) {
      for (size_t f = 0; f < values.size(); ++f)
        at[f] = values[f] + i;
      sums.addCell(cells[i], at);
    }
  });
  CellSet set;
  for (const std::string& name : names)
    set.fields.push_back(Field{name, {}, ""});
  sums.cellsInto(set);
  ranges = sums.ranges();
  return set;
}

/// The same for an input of leaf patches (a model's bricks, FLASH's leaf blocks), read patch by
/// patch: on every core, each into sums of its own joined at the end, where the source's reads
/// may run at once.
CellSet mergedLeafPatches(const PatchSource& source, int level, std::vector<range1f>& ranges) {
  const size_t fields = source.fieldNames.size();
  Progress progress("merging every cell for a first picture", source.patches.size());
  // A patch that cannot be read is left out and said once: the part that holds it says so
  // again when it is drawn, and the view goes on.
  std::mutex failed;
  std::string firstFailure;
  std::atomic<size_t> failures{0};
  auto merge = [&](size_t begin, size_t end, CubeSums& sums) {
    std::vector<std::vector<float>> values;
    std::vector<const float*> at(fields);
    for (size_t i = begin; i < end; ++i) {
      const io::Patch& p = source.patches[i];
      try {
        source.read(i, values);
      } catch (const Error& e) {
        if (failures++ == 0) {
          const std::lock_guard<std::mutex> lock(failed);
          firstFailure = e.what();
        }
        continue;
      }
      for (size_t f = 0; f < fields; ++f)
        at[f] = values[f].data();
      sums.addBox(p.lower, p.cells, p.width, at);
      progress.advance(1);
    }
  };
  CubeSums sums(level, fields);
  if (!source.concurrentReads) {
    merge(0, source.patches.size(), sums);
  } else {
    tbb::enumerable_thread_specific<CubeSums> each([&] { return CubeSums(level, fields); });
    tbb::parallel_for(tbb::blocked_range<size_t>(0, source.patches.size(), 16),
                      [&](const tbb::blocked_range<size_t>& r) { merge(r.begin(), r.end(), each.local()); });
    for (const CubeSums& part : each)
      sums.add(part);
  }
  if (failures > 0 && failures == source.patches.size()) throw Error(firstFailure);
  if (failures > 0)
    logWarning(strCat(failures.load(), " of ", source.patches.size(),
                      " patches could not be read and are left out of the merged picture; the first: ", firstFailure));
  CellSet set;
  for (size_t f = 0; f < fields; ++f)
    set.fields.push_back(Field{source.fieldNames[f], {}, source.fieldUnits[f]});
  set.world = source.world;
  set.simulation = source.simulation;
  sums.cellsInto(set);
  ranges = sums.ranges();
  return set;
}

} // namespace

double mergedLeavesCubes(const std::string& path, const LoadOptions& options, double maxCells) {
  const Census census = loadCensus(path, options);
  return volumeOf(census) / std::pow(8.0, double(cubeLevel(census, maxCells)));
}

namespace {
/// mergesLeaves of an input of this kind.
bool mergesLeavesOf(const std::string& path, InputKind kind) {
  if (kind == InputKind::Model || kind == InputKind::Flash || kind == InputKind::Native) return true;
  // A patch-based input of one level: its patches are its leaves, and it has no coarser level.
  const FormatReader* reader = io::patchReader(kind, path, {});
  if (!reader || !reader->levelCells) return false;
  const std::vector<double> cells = reader->levelCells(path);
  return std::count_if(cells.begin(), cells.end(), [](double n) { return n > 0; }) == 1;
}
} // namespace

bool mergesLeaves(const std::string& path) { return !path.empty() && mergesLeavesOf(path, detectInput(path)); }

std::optional<MergedLeaves> loadMergedLeaves(const std::string& path, const LoadOptions& options, double maxCells) {
  if (path.empty() || options.finestLevel > 0) return std::nullopt;
  const InputKind kind = detectInput(path);
  if (!mergesLeavesOf(path, kind)) return std::nullopt;
  const Census census = loadCensus(path, options);
  MergedLeaves m;
  m.cells = census.cells();
  if (m.cells <= maxCells) return std::nullopt;
  m.level = cubeLevel(census, maxCells);
  for (m.finestLevel = 0;
       m.finestLevel + 1 < int(census.levelCells.size()) && !(census.levelCells[size_t(m.finestLevel)] > 0);)
    ++m.finestLevel;
  for (int a = 0; a < 3; ++a) {
    m.cellBounds.lower[a] = int32_t(census.cellBounds.lower[a]);
    m.cellBounds.upper[a] = int32_t(census.cellBounds.upper[a]);
  }
  Timer timer;
  CellSet set;
  if (kind == InputKind::Native) {
    set = mergedNative(path, options, m.level, m.ranges);
  } else {
    const FormatReader* reader =
        kind == InputKind::Model ? &io::modelPartsReader() : io::patchReader(kind, path, options);
    if (!reader) return std::nullopt; // FLASH read with holes: cell by cell
    set = mergedLeafPatches(io::patchesOf(path, *reader, options.fields, 0), m.level, m.ranges);
  }
  if (set.cells.empty()) return std::nullopt;
  validateCellRecords(set.cells, strCat(path, " merged into cubes"));
  const size_t cubes = set.cells.size();
  m.model = buildModel(std::move(set), options.build);
  logInfo(strCat(std::llround(m.cells), " cells merged into ", cubes, " cubes ", int64_t(1) << m.level,
                 " finest cells wide in ", timer.seconds(), " s"));
  return m;
}

} // namespace exa
