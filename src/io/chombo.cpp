#include "exabricks/io/chombo.h"

#include "checked.h"
#include "hdf5_file.h"
#include "patches.h"

#include "exabricks/core/error.h"
#include "exabricks/core/log.h"

#include <algorithm>
#include <cmath>

namespace exa {
namespace {

struct ChomboLevel {
  std::string group;            ///< "/level_L"
  std::vector<io::Patch> boxes; ///< valid boxes in this level's index space (width 1)
  std::vector<int64_t> offsets; ///< start of each box's data, nboxes + 1 entries
  vec3l ghost{0};               ///< outputGhost: stored boxes are grown by it
  vec3d dx{0.0};
  int64_t ratio = 0; ///< to the next finer level (0 on the finest)
};

struct ChomboHeader {
  std::vector<std::string> names;
  std::vector<ChomboLevel> levels;
};

std::vector<std::string> componentNames(const h5::File& f) {
  const std::vector<double> n = f.attrNumbers("/", "num_components");
  if (n.size() != 1 || n[0] < 1 || n[0] > 100000 || n[0] != std::floor(n[0]))
    f.bad("/", "attribute 'num_components' is not a positive count");
  std::vector<std::string> names;
  for (int c = 0; c < int(n[0]); ++c) {
    const std::string attr = "component_" + std::to_string(c);
    std::string name = f.attrString("/", attr);
    if (name.empty()) f.bad("/", "attribute '" + attr + "' is empty");
    names.push_back(name);
  }
  return names;
}

/// The level's cell size and, below the finest level, its refinement ratio to the next.
void readSpacing(const h5::File& f, ChomboLevel& lv, int l, int numLevels) {
  const std::vector<double> dx = f.attrNumbers(lv.group, "dx");
  if (dx.size() == 1)
    lv.dx = vec3d(dx[0]);
  else if (dx.size() == 3)
    lv.dx = vec3d(dx[0], dx[1], dx[2]);
  else
    f.bad(lv.group, "attribute 'dx' has neither 1 nor 3 values");
  if (!(lv.dx.x > 0 && lv.dx.y > 0 && lv.dx.z > 0) || !std::isfinite(lv.dx.x + lv.dx.y + lv.dx.z))
    f.bad(lv.group, "attribute 'dx' must be positive");
  if (l + 1 < numLevels) {
    const std::vector<double> r = f.attrNumbers(lv.group, "ref_ratio");
    if (r.empty()) f.bad(lv.group, "attribute 'ref_ratio' is empty");
    for (double v : r)
      if (v != r[0]) f.bad(lv.group, "anisotropic refinement ratios are not supported");
    if (r[0] != std::floor(r[0]) || r[0] < 2 || r[0] > 1024 || io::log2Exact(int64_t(r[0])) < 0)
      f.bad(lv.group,
            strCat("refinement ratio ", r[0], " between levels ", l, " and ", l + 1, " is not a power of two"));
    lv.ratio = int64_t(r[0]);
  }
}

/// The ghost cells the stored boxes are grown by (outputGhost), where the level gives them.
void readGhost(const h5::File& f, ChomboLevel& lv) {
  const std::string dataAttrs = lv.group + "/data_attributes";
  if (!f.hasAttribute(dataAttrs, "outputGhost")) return;
  const std::vector<double> g = f.attrNumbers(dataAttrs, "outputGhost");
  if (g.size() != 3)
    f.bad(dataAttrs, strCat("attribute 'outputGhost' has ", g.size(), " values, expected 3 (a 3-D file)"));
  for (int a = 0; a < 3; ++a) {
    if (g[size_t(a)] < 0 || g[size_t(a)] > 64) f.bad(dataAttrs, "attribute 'outputGhost' is out of range");
    lv.ghost[a] = int64_t(g[size_t(a)]);
  }
}

/// The level's valid boxes from its "boxes" table.
void readBoxes(const h5::File& f, ChomboLevel& lv) {
  const h5::CompoundTable boxes = f.readCompound(lv.group + "/boxes");
  if (boxes.members.size() != 6)
    f.bad(lv.group + "/boxes", strCat("records have ", boxes.members.size(), " members; a 3-D box has 6 (a ",
                                      boxes.members.size() / 2, "-D file?)"));
  // Members by name when they carry Chombo's names, else in file order.
  static const char* kNames[6] = {"lo_i", "lo_j", "lo_k", "hi_i", "hi_j", "hi_k"};
  size_t order[6];
  for (size_t m = 0; m < 6; ++m) {
    const auto it = std::find(boxes.members.begin(), boxes.members.end(), kNames[m]);
    order[m] = it == boxes.members.end() ? m : size_t(it - boxes.members.begin());
  }
  for (size_t b = 0; b < boxes.records; ++b) {
    const double* v = boxes.values.data() + b * 6;
    vec3l lo, hi;
    for (int a = 0; a < 3; ++a) {
      if (!io::integerIn(v[order[a]], -kLatticeLimit, kLatticeLimit, lo[a]) ||
          !io::integerIn(v[order[a + 3]], -kLatticeLimit, kLatticeLimit, hi[a]))
        f.bad(lv.group + "/boxes",
              strCat("box ", b, " has corners that are not integers in the supported index range"));
    }
    if (hi.x < lo.x || hi.y < lo.y || hi.z < lo.z) f.bad(lv.group + "/boxes", strCat("box ", b, " is empty"));
    lv.boxes.push_back({lo, hi - lo + vec3l(1), 1});
  }
}

/// The offsets of the boxes' data, checked against the boxes and the data's length.
void readOffsets(const h5::File& f, ChomboLevel& lv, int64_t ncomp) {
  const std::string offsetsName = lv.group + "/data:offsets=0";
  lv.offsets = f.readInts(offsetsName);
  if (lv.offsets.size() != lv.boxes.size() + 1)
    f.bad(offsetsName, strCat(lv.offsets.size(), " offsets for ", lv.boxes.size(), " boxes (expected boxes + 1)"));
  for (size_t b = 0; b < lv.boxes.size(); ++b) {
    const vec3l n = lv.boxes[b].cells + lv.ghost * int64_t(2);
    const int64_t expected = ncomp * n.x * n.y * n.z;
    if (lv.offsets[b + 1] - lv.offsets[b] != expected)
      f.bad(offsetsName, strCat("box ", b, " has ", lv.offsets[b + 1] - lv.offsets[b], " values, expected ", expected,
                                " (", ncomp, " components of ", n.x, "x", n.y, "x", n.z, " cells with ghost cells)"));
  }
  const std::string dataName = lv.group + "/data:datatype=0";
  const std::vector<uint64_t> dims = f.dims(dataName);
  if (dims.size() != 1) f.bad(dataName, "expected a one-dimensional dataset");
  if (lv.offsets.front() != 0 || int64_t(dims[0]) != lv.offsets.back())
    f.bad(dataName,
          strCat("holds ", dims[0], " values, but the offsets describe ", lv.offsets.back() - lv.offsets.front()));
  // The boxes' cells are bounded by the values the file stores before anything is allocated
  // per cell (the coverage of each box included).
  f.requireStorage(dataName);
}

/// The cell sizes must follow the ratios; a mismatch means the header contradicts itself.
void checkSpacings(const h5::File& f, const ChomboHeader& h) {
  for (size_t l = 0; l + 1 < h.levels.size(); ++l) {
    const vec3d expect = h.levels[l].dx / double(h.levels[l].ratio);
    const vec3d got = h.levels[l + 1].dx;
    for (int a = 0; a < 3; ++a)
      if (std::abs(expect[a] - got[a]) > 1e-6 * expect[a])
        f.bad(h.levels[l + 1].group,
              strCat("dx ", got[a], " does not equal the coarser level's dx ", h.levels[l].dx[a],
                     " divided by its ref_ratio ", h.levels[l].ratio, " (inconsistent headers)"));
  }
}

ChomboHeader readHeader(const h5::File& f) {
  ChomboHeader h;
  if (f.hasAttribute("/Chombo_global", "SpaceDim")) {
    const std::vector<double> dim = f.attrNumbers("/Chombo_global", "SpaceDim");
    if (dim.size() != 1 || dim[0] != 3)
      f.bad("/Chombo_global", strCat("SpaceDim is ", dim.empty() ? 0.0 : dim[0], ": only 3-D AMR data can be read"));
  }
  h.names = componentNames(f);
  const std::vector<double> nl = f.attrNumbers("/", "num_levels");
  if (nl.size() != 1 || nl[0] < 1 || nl[0] > 30 || nl[0] != std::floor(nl[0]))
    f.bad("/", "attribute 'num_levels' is not a level count (1..30)");
  const int numLevels = int(nl[0]);
  for (int l = 0; l < numLevels; ++l) {
    ChomboLevel lv;
    lv.group = "/level_" + std::to_string(l);
    if (!f.exists(lv.group)) f.bad(lv.group, strCat("missing group (num_levels is ", numLevels, ")"));
    readSpacing(f, lv, l, numLevels);
    readGhost(f, lv);
    readBoxes(f, lv);
    readOffsets(f, lv, int64_t(h.names.size()));
    h.levels.push_back(std::move(lv));
  }
  checkSpacings(f, h);
  return h;
}

} // namespace

bool isChomboFile(const std::string& path) {
  if (!h5::hasSignature(path)) return false;
  try {
    const h5::File f(path);
    return f.exists("/level_0") && f.hasAttribute("/", "num_levels");
  } catch (const h5::DamagedFile&) {
    throw; // a damaged HDF5 file, whatever its layout: the check's message says what is wrong
  } catch (const Error&) {
    return false;
  }
}

std::vector<std::string> listChomboFields(const std::string& path) { return componentNames(h5::File(path)); }

namespace {

/// Width of each level's cells in finest cells.
std::vector<int64_t> levelWidths(const h5::File& f, const ChomboHeader& h) {
  const size_t nl = h.levels.size();
  std::vector<int64_t> width(nl, 1);
  for (size_t l = nl - 1; l-- > 0;) {
    width[l] = width[l + 1] * h.levels[l].ratio;
    if (width[l] > (int64_t(1) << kMaxLevel)) f.bad(h.levels[l].group, "refinement too deep for the lattice");
  }
  return width;
}

/// Every level's boxes on the finest lattice (`width`: levelWidths), and the (level, box) of each.
std::vector<io::Patch> placeBoxes(const ChomboHeader& h, const std::vector<int64_t>& width,
                                  std::vector<std::pair<size_t, size_t>>& owner) {
  std::vector<io::Patch> patches;
  owner.clear();
  for (size_t l = 0; l < h.levels.size(); ++l)
    for (size_t b = 0; b < h.levels[l].boxes.size(); ++b) {
      const io::Patch& stored = h.levels[l].boxes[b];
      patches.push_back({stored.lower * width[l], stored.cells, width[l]});
      owner.push_back({l, b});
    }
  return patches;
}

} // namespace

std::vector<double> chomboLevelCells(const std::string& path) {
  const h5::File f(path);
  const ChomboHeader h = readHeader(f);
  std::vector<std::pair<size_t, size_t>> owner;
  return io::levelCellsOfPatches(placeBoxes(h, levelWidths(f, h), owner));
}

Census chomboCensus(const std::string& path) {
  const h5::File f(path);
  const ChomboHeader h = readHeader(f);
  std::vector<std::pair<size_t, size_t>> owner; // (level, box) per patch
  const std::vector<io::Patch> patches = placeBoxes(h, levelWidths(f, h), owner);
  return io::censusOfPatches(
      patches, [&](size_t i) { return strCat(path, ": level ", owner[i].first, " box ", owner[i].second); });
}

PatchSource chomboPatches(const std::string& path, const std::vector<std::string>& wanted, int finestLevel) {
  struct State {
    h5::File file;
    ChomboHeader header;
    std::vector<size_t> comps;
    std::vector<std::pair<size_t, size_t>> owner; // (level, box) per patch
    explicit State(const std::string& path) : file(path) {}
  };
  auto st = std::make_shared<State>(path);
  st->header = readHeader(st->file);
  const ChomboHeader& h = st->header;
  const h5::File& f = st->file;
  st->comps = io::pickFields(path, h.names, wanted);

  PatchSource source = io::sourceOfFields(path, h.names, st->comps);
  // Levels finer than finestLevel are not read: the coarser cells under them are leaves (every
  // level's values are stored, those under finer boxes included).
  source.patches = placeBoxes(h, levelWidths(f, h), st->owner);
  const std::vector<size_t> kept = io::coarsePatches(source.patches, finestLevel);
  io::keepOnly(source.patches, kept);
  io::keepOnly(st->owner, kept);
  source.name = [st, path](size_t i) {
    return strCat(path, ": level ", st->owner[i].first, " box ", st->owner[i].second);
  };
  source.read = [st, name = source.name](size_t i, std::vector<std::vector<float>>& values) {
    const size_t l = st->owner[i].first, b = st->owner[i].second;
    const ChomboHeader& hd = st->header;
    const ChomboLevel& lv = hd.levels[l];
    const vec3l g = lv.ghost;
    const vec3l n = lv.boxes[b].cells + g * int64_t(2);
    const int64_t stored = n.x * n.y * n.z;
    const std::vector<double> raw = st->file.readRows(lv.group + "/data:datatype=0", uint64_t(lv.offsets[b]),
                                                      uint64_t(lv.offsets[b + 1] - lv.offsets[b]));
    values.assign(st->comps.size(), {});
    const vec3l cells = lv.boxes[b].cells;
    for (size_t k = 0; k < st->comps.size(); ++k) {
      values[k].reserve(size_t(cells.x * cells.y * cells.z));
      const double* src = raw.data() + int64_t(st->comps[k]) * stored;
      for (int64_t z = 0; z < cells.z; ++z)
        for (int64_t y = 0; y < cells.y; ++y)
          for (int64_t x = 0; x < cells.x; ++x) {
            const double v = src[((z + g.z) * n.y + (y + g.y)) * n.x + (x + g.x)];
            values[k].push_back(io::toFloat32(v, [&] {
              const vec3l at = lv.boxes[b].lower + vec3l(x, y, z);
              return strCat(name(i), ": component '", hd.names[st->comps[k]], "' at index (", at.x, ",", at.y, ",",
                            at.z, ")");
            }));
          }
    }
  };
  // The simulation's time and step, where the coarsest level's attributes hold them.
  if (f.hasAttribute("/level_0", "time")) {
    const std::vector<double> t = f.attrNumbers("/level_0", "time");
    if (t.size() == 1 && std::isfinite(t[0])) source.simulation.time = t[0];
  }
  for (const char* stepName : {"step", "iteration"})
    if (source.simulation.cycle < 0 && f.hasAttribute("/level_0", stepName)) {
      const std::vector<double> c = f.attrNumbers("/level_0", stepName);
      if (c.size() == 1 && c[0] >= 0 && c[0] < 9.0e18 && c[0] == std::floor(c[0]))
        source.simulation.cycle = int64_t(c[0]);
    }
  source.world.scale = h.levels.back().dx;
  source.world.origin = vec3d(0.0);
  return source;
}

CellSet readChombo(const std::string& path, const std::vector<std::string>& wanted, int finestLevel, const box3i& box) {
  return io::readPatchCells(chomboPatches(path, wanted, finestLevel), box);
}

} // namespace exa
