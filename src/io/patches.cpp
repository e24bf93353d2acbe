#include "patches.h"

#include "checked.h"

#include "exabricks/core/error.h"
#include "exabricks/core/log.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>

namespace exa::io {

void checkPatchCells(const vec3l& cells, const std::string& where) {
  uint64_t n = 0;
  if (cells.x < 1 || cells.y < 1 || cells.z < 1) fail(where, ": empty or inverted box");
  if (!cellCountWithin(cells.x, cells.y, cells.z, uint64_t(1) << 40, n))
    fail(where, ": box of ", cells.x, "x", cells.y, "x", cells.z, " cells is too large (at most 2^40 cells)");
}

void checkUnbackedPatches(const std::vector<Patch>& patches, const std::vector<uint8_t>& backed,
                          const std::function<std::string(size_t)>& name) {
  uint64_t withData = 0;
  for (size_t i = 0; i < patches.size(); ++i)
    if (backed[i]) withData += uint64_t(patches[i].cellCount());
  for (size_t i = 0; i < patches.size(); ++i)
    if (!backed[i] && uint64_t(patches[i].cellCount()) > withData)
      fail(name(i), ": has no data and ", patches[i].cellCount(), " cells, more than all boxes with data hold (",
           withData, "), so finer boxes cannot cover it");
}

int log2Exact(int64_t width) {
  if (width < 1 || (width & (width - 1)) != 0) return -1;
  int l = 0;
  while ((int64_t(1) << l) < width)
    ++l;
  return l;
}

Coverage::Coverage(std::vector<Patch> patches, std::function<std::string(size_t)> name)
    : patches_(std::move(patches)), name_(std::move(name)) {
  items_.resize(patches_.size());
  for (size_t i = 0; i < items_.size(); ++i)
    items_[i] = uint32_t(i);
  nodes_.push_back({});
  if (!items_.empty()) build(0, 0, uint32_t(items_.size()));
  for (const Patch& p : patches_)
    widths_.push_back(p.width);
  std::sort(widths_.begin(), widths_.end());
  widths_.erase(std::unique(widths_.begin(), widths_.end()), widths_.end());
}

void Coverage::build(uint32_t node, uint32_t begin, uint32_t end) {
  vec3l lo(INT64_MAX), hi(INT64_MIN), clo(INT64_MAX), chi(INT64_MIN);
  for (uint32_t i = begin; i < end; ++i) {
    const Patch& p = patches_[items_[i]];
    lo = min(lo, p.lower);
    hi = max(hi, p.upper());
    const vec3l c2 = p.lower + p.upper(); // twice the centre, to stay integer
    clo = min(clo, c2);
    chi = max(chi, c2);
  }
  nodes_[node].lo = lo;
  nodes_[node].hi = hi;
  if (end - begin <= 4 || clo == chi) {
    nodes_[node].first = begin;
    nodes_[node].count = end - begin;
    return;
  }
  const vec3l ext = chi - clo;
  const int axis = ext.x >= ext.y && ext.x >= ext.z ? 0 : (ext.y >= ext.z ? 1 : 2);
  const uint32_t mid = begin + (end - begin) / 2;
  std::nth_element(items_.begin() + begin, items_.begin() + mid, items_.begin() + end, [&](uint32_t a, uint32_t b) {
    return (patches_[a].lower + patches_[a].upper())[axis] < (patches_[b].lower + patches_[b].upper())[axis];
  });
  const uint32_t child = uint32_t(nodes_.size());
  nodes_.push_back({});
  nodes_.push_back({});
  nodes_[node].first = child;
  nodes_[node].count = 0;
  build(child, begin, mid);
  build(child + 1, mid, end);
}

void Coverage::forEachOverlapping(const vec3l& lo, const vec3l& hi, const std::function<void(size_t)>& visit) const {
  auto overlaps = [&](const vec3l& a, const vec3l& b) {
    return a.x < hi.x && a.y < hi.y && a.z < hi.z && lo.x < b.x && lo.y < b.y && lo.z < b.z;
  };
  std::vector<uint32_t> stack{0};
  while (!stack.empty()) {
    const Node& n = nodes_[stack.back()];
    stack.pop_back();
    if (!overlaps(n.lo, n.hi)) continue;
    if (n.count == 0) {
      stack.push_back(n.first);
      stack.push_back(n.first + 1);
      continue;
    }
    for (uint32_t k = n.first; k < n.first + n.count; ++k)
      if (overlaps(patches_[items_[k]].lower, patches_[items_[k]].upper())) visit(items_[k]);
  }
}

void Coverage::forEachCover(size_t i, const std::function<void(const vec3l&, const vec3l&)>& use) const {
  const Patch& p = patches_[i];
  // Only the next finer width decides: the formats nest each level inside the one above, so a
  // deeper patch lies under next-finer patches and may legitimately cut coarse cells.
  const auto next = std::lower_bound(widths_.begin(), widths_.end(), p.width);
  if (next == widths_.begin()) return;
  const int64_t coverWidth = *(next - 1);
  const vec3l plo = p.lower, phi = p.upper();
  forEachOverlapping(plo, phi, [&](size_t j) {
    const Patch& q = patches_[j];
    if (q.width != coverWidth) return;
    const vec3l lo = max(q.lower, plo), hi = min(q.upper(), phi);
    // The overlap must consist of whole cells of p: a finer patch never splits a cell.
    for (int a = 0; a < 3; ++a)
      if ((lo[a] - plo[a]) % p.width != 0 || (hi[a] - plo[a]) % p.width != 0)
        fail(name_(j), " covers only part of a cell of ", name_(i), " (finer patches must cover whole coarser cells)");
    use((lo - plo) / p.width, (hi - plo) / p.width);
  });
}

std::vector<uint8_t> Coverage::covered(size_t i) const {
  const Patch& p = patches_[i];
  std::vector<uint8_t> mask = allocate<uint8_t>(uint64_t(p.cellCount()), [&] { return name_(i); });
  forEachCover(i, [&](const vec3l& clo, const vec3l& chi) {
    for (int64_t z = clo.z; z < chi.z; ++z)
      for (int64_t y = clo.y; y < chi.y; ++y)
        std::fill_n(mask.begin() + ((z * p.cells.y + y) * p.cells.x + clo.x), chi.x - clo.x, uint8_t(1));
  });
  return mask;
}

Census censusOfPatches(const std::vector<Patch>& patches, const std::function<std::string(size_t)>& name) {
  const Coverage coverage(patches, name);
  std::vector<uint64_t> leaves(patches.size());
  tbb::parallel_for(tbb::blocked_range<size_t>(0, patches.size(), 256), [&](const tbb::blocked_range<size_t>& r) {
    for (size_t i = r.begin(); i < r.end(); ++i)
      leaves[i] = coverage.leafCount(i);
  });
  Census census;
  census.levelCells.assign(size_t(kMaxLevel) + 1, 0.0);
  for (size_t i = 0; i < patches.size(); ++i) {
    const int level = log2Exact(patches[i].width);
    census.coarsestLevel = std::max(census.coarsestLevel, level);
    if (leaves[i] == 0) continue;
    census.boxes.push_back({box3l(patches[i].lower, patches[i].upper()), double(leaves[i])});
    census.levelCells[size_t(std::clamp(level, 0, kMaxLevel))] += double(leaves[i]);
    // Where finer patches cover part of it, their cells (or finer ones) fill that part.
    census.cellBounds.extend(census.boxes.back().box);
  }
  return census;
}

std::vector<double> levelCellsOfPatches(const std::vector<Patch>& patches) {
  std::vector<double> cells(size_t(kMaxLevel) + 1, 0.0);
  for (const Patch& p : patches)
    cells[size_t(std::clamp(log2Exact(p.width), 0, kMaxLevel))] +=
        double(p.cells.x) * double(p.cells.y) * double(p.cells.z);
  return cells;
}

std::vector<size_t> coarsePatches(const std::vector<Patch>& patches, int finestLevel) {
  std::vector<size_t> kept;
  for (size_t i = 0; i < patches.size(); ++i)
    if (patches[i].width >= (int64_t(1) << finestLevel)) kept.push_back(i);
  return kept;
}

uint64_t Coverage::leafCount(size_t i) const {
  const Patch& p = patches_[i];
  // The covering boxes (in p's cells) and their bounding box: a mask over that box alone.
  std::vector<std::pair<vec3l, vec3l>> covers;
  vec3l blo(INT64_MAX), bhi(INT64_MIN);
  forEachCover(i, [&](const vec3l& clo, const vec3l& chi) {
    covers.push_back({clo, chi});
    blo = min(blo, clo);
    bhi = max(bhi, chi);
  });
  const uint64_t all = uint64_t(p.cellCount());
  if (covers.empty()) return all;
  if (covers.size() == 1) {
    const vec3l n = covers[0].second - covers[0].first;
    return all - uint64_t(n.x * n.y * n.z);
  }
  const vec3l n = bhi - blo;
  std::vector<uint8_t> mask = allocate<uint8_t>(uint64_t(n.x * n.y * n.z), [&] { return name_(i); });
  for (const auto& [clo, chi] : covers)
    for (int64_t z = clo.z; z < chi.z; ++z)
      for (int64_t y = clo.y; y < chi.y; ++y)
        std::fill_n(mask.begin() + (((z - blo.z) * n.y + (y - blo.y)) * n.x + (clo.x - blo.x)), chi.x - clo.x,
                    uint8_t(1));
  return all - uint64_t(std::count(mask.begin(), mask.end(), uint8_t(1)));
}

std::vector<std::pair<vec3l, vec3l>> Coverage::leafBoxes(size_t i) const {
  const Patch& p = patches_[i];
  std::vector<std::pair<vec3l, vec3l>> boxes{{vec3l(0), p.cells}}, next;
  forEachCover(i, [&](const vec3l& clo, const vec3l& chi) {
    next.clear();
    for (auto [lo, hi] : boxes) {
      if (!(clo.x < hi.x && clo.y < hi.y && clo.z < hi.z && lo.x < chi.x && lo.y < chi.y && lo.z < chi.z)) {
        next.push_back({lo, hi});
        continue;
      }
      // The slabs beside the cover, axis by axis; what is left lies inside the cover.
      for (int a = 0; a < 3; ++a) {
        if (lo[a] < clo[a]) {
          vec3l h = hi;
          h[a] = clo[a];
          next.push_back({lo, h});
          lo[a] = clo[a];
        }
        if (hi[a] > chi[a]) {
          vec3l l = lo;
          l[a] = chi[a];
          next.push_back({l, hi});
          hi[a] = chi[a];
        }
      }
    }
    boxes.swap(next);
  });
  return boxes;
}

std::optional<std::pair<size_t, size_t>> Coverage::firstOverlap() const {
  for (size_t i = 0; i < patches_.size(); ++i) {
    std::optional<size_t> other;
    forEachOverlapping(patches_[i].lower, patches_[i].upper(), [&](size_t j) {
      if (j != i && !other) other = j;
    });
    if (other) return std::pair<size_t, size_t>(std::min(i, *other), std::max(i, *other));
  }
  return std::nullopt;
}

CellSet readPatchCells(const PatchSource& source, const box3i& box) {
  CellSet set;
  for (size_t f = 0; f < source.fieldNames.size(); ++f)
    set.fields.push_back(Field{source.fieldNames[f], {}, f < source.fieldUnits.size() ? source.fieldUnits[f] : ""});
  set.world = source.world;
  set.simulation = source.simulation;
  const Coverage coverage(source.patches, source.name);
  Progress progress("reading " + source.input, source.patches.size());
  std::vector<std::vector<float>> values;
  for (size_t i = 0; i < source.patches.size(); ++i) {
    progress.advance(1);
    if (!patchInBox(source.patches[i], box) || source.heldElsewhere(i)) continue; // its data is not read
    const std::vector<uint8_t> covered = coverage.covered(i);
    if (std::find(covered.begin(), covered.end(), uint8_t(0)) == covered.end()) continue; // fully refined
    source.read(i, values);
    appendLeafCells(set, source.patches[i], covered, values, source.name(i));
  }
  progress.finish();
  logInfo(strCat("read ", set.cells.size(), " leaf cells from ", source.input));
  return set;
}

void badValue(double value, const std::string& where) {
  if (std::isnan(value)) fail(where, " is NaN");
  fail(where, " is ", value, ", outside the float32 range");
}

void appendLeafCells(CellSet& set, const Patch& patch, const std::vector<uint8_t>& covered,
                     const std::vector<std::vector<float>>& values, const std::string& where) {
  const int level = log2Exact(patch.width);
  if (level < 0 || level > kMaxLevel)
    fail(where, ": cell width ", patch.width, " is not a power of two up to 2^", kMaxLevel);
  const vec3l hi = patch.upper();
  for (int a = 0; a < 3; ++a)
    if (patch.lower[a] < -kLatticeLimit || hi[a] > kLatticeLimit)
      fail(where, ": lies outside the supported lattice range (±2^29 finest cells)");
  for (const auto& v : values)
    if (int64_t(v.size()) != patch.cellCount())
      fail(where, ": ", v.size(), " values for ", patch.cellCount(), " cells");
  size_t i = 0;
  for (int64_t z = 0; z < patch.cells.z; ++z)
    for (int64_t y = 0; y < patch.cells.y; ++y)
      for (int64_t x = 0; x < patch.cells.x; ++x, ++i) {
        if (covered[i]) continue;
        const vec3l c = patch.lower + vec3l(x, y, z) * patch.width;
        set.cells.push_back(Cell{vec3i(int32_t(c.x), int32_t(c.y), int32_t(c.z)), level});
        for (size_t f = 0; f < values.size(); ++f)
          set.fields[f].values.push_back(values[f][i]);
      }
}

std::vector<size_t> pickFields(const std::string& source, const std::vector<std::string>& available,
                               const std::vector<std::string>& wanted) {
  std::vector<size_t> out;
  if (wanted.empty()) {
    for (size_t i = 0; i < available.size(); ++i)
      out.push_back(i);
    return out;
  }
  for (const std::string& name : wanted) {
    const auto it = std::find(available.begin(), available.end(), name);
    if (it == available.end()) {
      std::string known;
      for (const std::string& n : available)
        known += (known.empty() ? "" : ", ") + n;
      fail(source, ": unknown field '", name, "' (fields: ", known, ")");
    }
    out.push_back(size_t(it - available.begin()));
  }
  return out;
}

PatchSource sourceOfFields(const std::string& path, const std::vector<std::string>& available,
                           const std::vector<size_t>& picked) {
  PatchSource source;
  source.input = path;
  for (size_t k : picked)
    source.fieldNames.push_back(available.at(k));
  source.fieldUnits.assign(source.fieldNames.size(), "");
  return source;
}

} // namespace exa::io
