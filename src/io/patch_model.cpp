#include "exabricks/io/patch_source.h"

#include "exabricks/core/error.h"
#include "exabricks/core/log.h"

#include "checked.h"
#include "patches.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cstring>
#include <optional>

namespace exa {

bool PatchKeep::along(int axis, int64_t lower, int64_t width) const {
  switch (rule) {
  case Rule::All:
    return true;
  case Rule::Overlapping:
    return lower + width > box.lower[axis] && lower < box.upper[axis];
  case Rule::Reaching: // the support (centre ± width) in doubled units, as supportReaches
    return 2 * lower - width < 2 * box.upper[axis] && 2 * (lower + width) + width > 2 * box.lower[axis];
  }
  return true;
}

namespace {

/// A brick cut from a patch, in the patch's cells (exclusive upper).
struct Piece {
  vec3l lower, upper;
};

/// The kept cells of one leaf box of patch p: along each axis the kept indices are contiguous
/// (every rule's test is monotone along an axis).
bool cropToKept(const io::Patch& p, const PatchKeep& keep, vec3l& lo, vec3l& hi) {
  for (int a = 0; a < 3; ++a) {
    while (lo[a] < hi[a] && !keep.along(a, p.lower[a] + lo[a] * p.width, p.width))
      ++lo[a];
    while (hi[a] > lo[a] && !keep.along(a, p.lower[a] + (hi[a] - 1) * p.width, p.width))
      --hi[a];
    if (lo[a] >= hi[a]) return false;
  }
  return true;
}

/// Cuts a box into bricks of at most maxWidth cells per axis, of nearly equal sizes.
void cutIntoBricks(const vec3l& lo, const vec3l& hi, int64_t maxWidth, std::vector<Piece>& out) {
  vec3l parts;
  for (int a = 0; a < 3; ++a)
    parts[a] = (hi[a] - lo[a] + maxWidth - 1) / maxWidth;
  auto cut = [&](int a, int64_t k) { return lo[a] + (hi[a] - lo[a]) * k / parts[a]; };
  for (int64_t z = 0; z < parts.z; ++z)
    for (int64_t y = 0; y < parts.y; ++y)
      for (int64_t x = 0; x < parts.x; ++x)
        out.push_back({vec3l(cut(0, x), cut(1, y), cut(2, z)), vec3l(cut(0, x + 1), cut(1, y + 1), cut(2, z + 1))});
}

/// The coverage of the patches that may hold kept cells or cover them: those that meet the
/// kept cells' reach (the keep box widened by two of the widest cells), with each patch's index
/// in it (or -1).
struct KeptCoverage {
  std::vector<int64_t> local;
  std::optional<io::Coverage> coverage;

  KeptCoverage(const PatchSource& source, const PatchKeep& keep) {
    const std::vector<io::Patch>& patches = source.patches;
    std::vector<size_t> near;
    if (keep.rule == PatchKeep::Rule::All) {
      for (size_t i = 0; i < patches.size(); ++i)
        near.push_back(i);
    } else {
      int64_t widest = 1;
      for (const io::Patch& p : patches)
        widest = std::max(widest, p.width);
      const vec3l lo = keep.box.lower - vec3l(2 * widest), hi = keep.box.upper + vec3l(2 * widest);
      for (size_t i = 0; i < patches.size(); ++i) {
        const vec3l plo = patches[i].lower, phi = patches[i].upper();
        if (plo.x < hi.x && plo.y < hi.y && plo.z < hi.z && lo.x < phi.x && lo.y < phi.y && lo.z < phi.z)
          near.push_back(i);
      }
    }
    local.assign(patches.size(), -1);
    std::vector<io::Patch> kept;
    kept.reserve(near.size());
    for (size_t k = 0; k < near.size(); ++k)
      local[near[k]] = int64_t(k), kept.push_back(patches[near[k]]);
    coverage.emplace(std::move(kept), [&source, near](size_t k) { return source.name(near[k]); });
  }
};

/// Each patch's bricks: its leaf boxes, cropped to the kept cells, cut to the brick width.
std::vector<std::vector<Piece>> cutPatches(const PatchSource& source, const KeptCoverage& kept, const PatchKeep& keep,
                                           int64_t maxWidth) {
  const std::vector<io::Patch>& patches = source.patches;
  std::vector<std::vector<Piece>> pieces(patches.size());
  tbb::parallel_for(size_t(0), patches.size(), [&](size_t i) {
    const io::Patch& p = patches[i];
    vec3l all(0), allUp = p.cells;
    if (source.heldElsewhere(i) || !cropToKept(p, keep, all, allUp)) return;              // none of its cells is kept
    if (kept.local[i] < 0) fail(source.name(i), ": holds kept cells beyond their reach"); // cannot happen
    for (auto [lo, hi] : kept.coverage->leafBoxes(size_t(kept.local[i])))
      if (cropToKept(p, keep, lo, hi)) cutIntoBricks(lo, hi, maxWidth, pieces[i]);
    if (pieces[i].empty()) return;
    const int level = io::log2Exact(p.width);
    if (level < 0 || level > kMaxLevel)
      fail(source.name(i), ": cell width ", p.width, " is not a power of two up to 2^", kMaxLevel);
    for (int a = 0; a < 3; ++a)
      if (p.lower[a] < -kLatticeLimit || p.upper()[a] > kLatticeLimit)
        fail(source.name(i), ": lies outside the supported lattice range (±2^29 finest cells)");
  });
  return pieces;
}

/// No two leaves may overlap: boxes of one level that overlap, or a level that the next coarser
/// does not hold, would give a point two cells.
void checkDisjoint(const PatchSource& source, const std::vector<Brick>& bricks, const std::vector<size_t>& patchOf) {
  std::vector<io::Patch> boxes;
  boxes.reserve(bricks.size());
  for (const Brick& b : bricks)
    boxes.push_back({vec3l(b.lower), vec3l(b.size), int64_t(b.cellWidth())});
  const io::Coverage leaves(std::move(boxes), [&](size_t k) { return source.name(patchOf[k]); });
  if (const auto pair = leaves.firstOverlap()) {
    const size_t a = patchOf[pair->first], b = patchOf[pair->second];
    if (a == b) fail(source.name(a), ": overlaps itself");
    fail(source.name(a), " and ", source.name(b),
         " hold cells that overlap (boxes of one level must not overlap, and each level must lie within the",
         " next coarser)");
  }
}

/// Reads patch i once and copies its kept cells into the slots of its bricks.
void placeValues(const PatchSource& source, size_t i, const std::vector<Piece>& pieces, const Brick* bricks,
                 std::vector<std::vector<float>>& values) {
  const io::Patch& p = source.patches[i];
  std::vector<std::vector<float>> read;
  source.read(i, read);
  if (read.size() != values.size())
    fail(source.name(i), ": ", read.size(), " fields read, ", values.size(), " asked for");
  for (const auto& v : read)
    if (int64_t(v.size()) != p.cellCount())
      fail(source.name(i), ": ", v.size(), " values for ", p.cellCount(), " cells");
  for (size_t k = 0; k < pieces.size(); ++k) {
    const Piece& piece = pieces[k];
    const Brick& b = bricks[k];
    const size_t row = size_t(b.size.x);
    for (size_t f = 0; f < values.size(); ++f) {
      float* dst = values[f].data() + b.valueOffset;
      for (int64_t z = piece.lower.z; z < piece.upper.z; ++z)
        for (int64_t y = piece.lower.y; y < piece.upper.y; ++y, dst += row)
          std::memcpy(dst, read[f].data() + ((z * p.cells.y + y) * p.cells.x + piece.lower.x), row * sizeof(float));
    }
  }
}

} // namespace

Model buildModelOfPatches(const PatchSource& source, const PatchKeep& keep, const BuildOptions& options) {
  Timer timer;
  const std::vector<io::Patch>& patches = source.patches;
  const KeptCoverage kept(source, keep);
  const std::vector<std::vector<Piece>> pieces =
      cutPatches(source, kept, keep, std::clamp(options.bricks.maxBrickWidth, 1, kMaxBrickWidth));

  Model model;
  model.world = source.world;
  model.simulation = source.simulation;
  model.fieldNames = source.fieldNames;
  model.fieldUnits = source.fieldUnits;
  model.fieldUnits.resize(model.fieldNames.size());
  std::vector<size_t> firstBrick(patches.size() + 1, 0), patchOf; // per patch; per brick
  uint64_t cells = 0;
  for (size_t i = 0; i < patches.size(); ++i) {
    firstBrick[i] = model.bricks.size();
    for (const Piece& piece : pieces[i]) {
      const vec3l n = piece.upper - piece.lower, lower = patches[i].lower + piece.lower * patches[i].width;
      Brick b;
      b.lower = vec3i(int32_t(lower.x), int32_t(lower.y), int32_t(lower.z));
      b.level = io::log2Exact(patches[i].width);
      b.size = vec3i(int32_t(n.x), int32_t(n.y), int32_t(n.z));
      b.valueOffset = uint32_t(cells);
      cells += uint64_t(n.x * n.y * n.z);
      if (cells >= uint64_t(UINT32_MAX))
        fail(source.input, ": too many cells: more than ", cells - 1, " (limit 2^32-1)");
      model.bricks.push_back(b);
      patchOf.push_back(i);
    }
  }
  firstBrick[patches.size()] = model.bricks.size();
  if (model.bricks.empty()) return model;
  checkDisjoint(source, model.bricks, patchOf);

  // Each patch's values, read once, into its bricks' slots.
  std::vector<std::vector<float>> values(model.fieldNames.size());
  for (auto& v : values)
    v = io::allocate<float>(cells, [&] { return strCat(source.input, ": the values of ", cells, " cells"); });
  Progress progress("reading " + source.input, patches.size());
  auto place = [&](size_t i) {
    if (!pieces[i].empty()) placeValues(source, i, pieces[i], model.bricks.data() + firstBrick[i], values);
    progress.advance(1);
  };
  if (source.concurrentReads)
    tbb::parallel_for(size_t(0), patches.size(), place, tbb::simple_partitioner());
  else
    for (size_t i = 0; i < patches.size(); ++i)
      place(i);
  for (auto& v : values)
    model.fieldValues.push_back(std::move(v));
  model.stats.brickSeconds = timer.seconds();
  progress.finish();
  buildRegionsOf(model, options.regions);
  logInfo(strCat("built ", model.bricks.size(), " bricks of ", cells, " cells from ", patches.size(), " boxes and ",
                 model.regions.regions.size(), " regions in ", timer.seconds(), " s"));
  return model;
}

} // namespace exa

namespace exa {

int64_t alignedMerge(const std::vector<io::Patch>& patches, int64_t most) {
  int64_t factor = most;
  for (const io::Patch& p : patches)
    for (int a = 0; a < 3; ++a)
      while (factor > 1 && (p.cells[a] % factor != 0 || p.lower[a] % (p.width * factor) != 0))
        factor /= 2;
  return std::max<int64_t>(factor, 1);
}

PatchSource mergedPatches(const PatchSource& source, int64_t factor) {
  if (factor < 1 || (factor & (factor - 1)) != 0 || alignedMerge(source.patches, factor) != factor)
    fail(source.input, ": cells cannot be merged by ", factor);
  PatchSource merged = source;
  for (io::Patch& p : merged.patches) {
    p.cells = p.cells / factor;
    p.width *= factor;
  }
  merged.read = [read = source.read, name = source.name, patches = source.patches,
                 factor](size_t i, std::vector<std::vector<float>>& values) {
    std::vector<std::vector<float>> fine;
    read(i, fine);
    const vec3l n = patches[i].cells, m = n / factor;
    const double share = 1.0 / double(factor * factor * factor);
    values.assign(fine.size(), std::vector<float>(size_t(m.x * m.y * m.z)));
    for (size_t f = 0; f < fine.size(); ++f) {
      if (int64_t(fine[f].size()) != n.x * n.y * n.z)
        fail(name(i), ": ", fine[f].size(), " values for ", n.x * n.y * n.z, " cells");
      std::vector<double> sums(size_t(m.x * m.y * m.z), 0.0);
      for (int64_t z = 0; z < n.z; ++z)
        for (int64_t y = 0; y < n.y; ++y) {
          const float* row = fine[f].data() + (z * n.y + y) * n.x;
          double* out = sums.data() + ((z / factor) * m.y + y / factor) * m.x;
          for (int64_t x = 0; x < n.x; ++x)
            out[x / factor] += row[x];
        }
      for (size_t k = 0; k < sums.size(); ++k)
        values[f][k] = float(sums[k] * share);
    }
  };
  return merged;
}

} // namespace exa
