// Shared by the readers of overlapping-level AMR formats (Chombo, Enzo, VTK overlapping AMR):
// patches (boxes of same-width cells) placed on the finest lattice, which of their cells are
// covered by finer patches, and the leaf cells and float32 values they contribute.
#pragma once

#include "exabricks/amr/cells.h"
#include "exabricks/amr/partition.h"
#include "exabricks/io/patch_source.h"

#include <cmath>
#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <vector>

namespace exa::io {

/// Fails unless every axis of `cells` is positive and the patch holds at most 2^40 cells, so
/// that cellCount() and every index into the patch stay in range.
void checkPatchCells(const vec3l& cells, const std::string& where);

/// A patch without data of its own (`backed[i]` false) is valid only when finer patches cover
/// it, and those hold at least as many cells: one holding more cells than all patches with data
/// together fails, before any per-cell memory is reserved for it.
void checkUnbackedPatches(const std::vector<Patch>& patches, const std::vector<uint8_t>& backed,
                          const std::function<std::string(size_t)>& name);

/// log2 of a width that is a power of two, or -1.
int log2Exact(int64_t width);

/// Finds, for each patch, the cells covered by patches of smaller width. A bounding-volume
/// hierarchy over the patches keeps the search proportional to the overlaps.
class Coverage {
public:
  /// `name(i)` describes patch i in messages ("level 2 box 7", "grid 12").
  Coverage(std::vector<Patch> patches, std::function<std::string(size_t)> name);
  /// One flag per cell of patch i (x fastest): 1 where a patch of the next finer width present
  /// covers the cell. Such a patch covering only part of a cell is an error naming both.
  std::vector<uint8_t> covered(size_t i) const;
  /// Cells of patch i that no patch of the next finer width covers, without a mask over the
  /// whole patch (only over the bounding box of its covered parts).
  uint64_t leafCount(size_t i) const;
  /// The boxes of patch i's cells that no patch of the next finer width covers, in its cells
  /// (exclusive upper): the patch less the covered parts, cut into disjoint boxes.
  std::vector<std::pair<vec3l, vec3l>> leafBoxes(size_t i) const;
  /// Two patches that overlap, whatever their widths (none among the leaves of a valid input),
  /// or none.
  std::optional<std::pair<size_t, size_t>> firstOverlap() const;

private:
  struct Node {
    vec3l lo, hi;          ///< bounds of the subtree's patches, exclusive upper
    uint32_t first, count; ///< leaf: item range; inner: count == 0, children at first, first+1
  };
  void build(uint32_t node, uint32_t begin, uint32_t end);
  /// Calls `use(lo, hi)` with each part of patch i that a patch of the next finer width covers,
  /// in p's cells (exclusive upper).
  void forEachCover(size_t i, const std::function<void(const vec3l&, const vec3l&)>& use) const;
  /// Calls visit(j) for every patch j that overlaps the lattice box [lo, hi).
  void forEachOverlapping(const vec3l& lo, const vec3l& hi, const std::function<void(size_t)>& visit) const;
  std::vector<Patch> patches_;
  std::vector<uint32_t> items_;
  std::vector<Node> nodes_;
  std::vector<int64_t> widths_; ///< distinct widths, ascending
  std::function<std::string(size_t)> name_;
};

/// Where the leaf cells of `patches` lie, from the boxes alone: per patch, its cells less those
/// that patches of the next finer width cover (patches without leaves left out); the coarsest
/// level is the widest patch's.
Census censusOfPatches(const std::vector<Patch>& patches, const std::function<std::string(size_t)>& name);

/// Cells in the patches of each width (index: exabricks level, log2 of the width), from the boxes
/// alone.
std::vector<double> levelCellsOfPatches(const std::vector<Patch>& patches);

/// The patches a read of the coarse levels alone keeps (LoadOptions::finestLevel): those whose
/// cells are 2^finestLevel finest cells wide or wider, as indices in order.
std::vector<size_t> coarsePatches(const std::vector<Patch>& patches, int finestLevel);

/// Keeps the entries `kept` (ascending indices) of v, in order.
template <typename T> void keepOnly(std::vector<T>& v, const std::vector<size_t>& kept) {
  for (size_t k = 0; k < kept.size(); ++k)
    v[k] = v[kept[k]];
  v.resize(kept.size());
}

/// Whether a read through `box` (finest lattice; empty: everything) needs patch p: its cells
/// overlap the box.
inline bool patchInBox(const Patch& p, const box3i& box) {
  if (box.empty()) return true;
  const vec3l lo = p.lower, hi = p.upper();
  return hi.x > box.lower.x && hi.y > box.lower.y && hi.z > box.lower.z && lo.x < box.upper.x && lo.y < box.upper.y &&
         lo.z < box.upper.z;
}

/// Throws the error for a value that is not a finite float32; `where` names file, record, field.
[[noreturn]] void badValue(double value, const std::string& where);

/// Whether the reads on this thread keep NaN and infinite values (LoadOptions::nonFinite: the
/// loader then makes their cells holes); set for a read by KeepNonFinite.
inline thread_local bool tKeepNonFinite = false;

/// Keeps NaN and infinite values in the reads of this thread while it lives (when `keep`).
class KeepNonFinite {
public:
  explicit KeepNonFinite(bool keep) : before_(tKeepNonFinite) { tKeepNonFinite = keep; }
  ~KeepNonFinite() { tKeepNonFinite = before_; }
  KeepNonFinite(const KeepNonFinite&) = delete;
  KeepNonFinite& operator=(const KeepNonFinite&) = delete;

private:
  bool before_;
};

/// Converts a value to float32; NaN, infinities and values outside the float32 range throw
/// with `where()` (file, record and field) in the message, except NaN and infinities under
/// KeepNonFinite, which stay what they are. Inline: it runs once per value.
template <typename Where> inline float toFloat32(double value, Where&& where) {
  if (std::abs(value) <= 3.4028234663852886e38) return float(value); // false for NaN and inf
  if (tKeepNonFinite && (std::isnan(value) || std::isinf(value))) return float(value);
  badValue(value, where());
}

/// Appends the uncovered cells of `patch` to `set`; `values[f]` holds the patch's values of
/// field f (x fastest, one per cell). Checks the lattice range.
void appendLeafCells(CellSet& set, const Patch& patch, const std::vector<uint8_t>& covered,
                     const std::vector<std::vector<float>>& values, const std::string& where);

/// The leaf cells of the source's patches that overlap `box` (empty: every patch), read patch
/// by patch: the cells of a read without structure (FormatReader::read).
CellSet readPatchCells(const PatchSource& source, const box3i& box);

/// Indices into `available` of the wanted fields (all when `wanted` is empty); an unknown name
/// throws "SOURCE: unknown field 'x' (fields: ...)".
std::vector<size_t> pickFields(const std::string& source, const std::vector<std::string>& available,
                               const std::vector<std::string>& wanted);

/// A patch source of `path` with the fields `available[picked]`, in that order, their units not
/// known yet: what the readers fill in with their patches.
PatchSource sourceOfFields(const std::string& path, const std::vector<std::string>& available,
                           const std::vector<size_t>& picked);

} // namespace exa::io
