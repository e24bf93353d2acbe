#include "exabricks/io/enzo.h"

#include "checked.h"
#include "enzo_output.h"
#include "hdf5_file.h"
#include "patches.h"

#include "exabricks/core/error.h"
#include "exabricks/core/log.h"

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <memory>
#include <sstream>

namespace exa {
namespace fs = std::filesystem;
using io::enzo::DataFiles;
using io::enzo::Grid;
using io::enzo::gridGroup;
using io::enzo::groupOf;
using io::enzo::Output;
using io::enzo::Parameters;
using io::enzo::readOutput;

namespace {

bool endsWith(const std::string& s, const std::string& suffix) {
  return s.size() >= suffix.size() && s.compare(s.size() - suffix.size(), suffix.size(), suffix) == 0;
}

std::string trim(const std::string& s) {
  const size_t b = s.find_first_not_of(" \t\r");
  if (b == std::string::npos) return "";
  return s.substr(b, s.find_last_not_of(" \t\r") - b + 1);
}

/// "Key = value" lines of a text file, with the line number of each key's last occurrence.
struct KeyLine {
  std::string key, value;
  size_t line;
};

std::vector<KeyLine> readKeyLines(const std::string& path) {
  std::ifstream in(path);
  if (!in) fail(path, ": cannot open: ", std::strerror(errno));
  std::vector<KeyLine> out;
  std::string l;
  for (size_t n = 1; std::getline(in, l); ++n) {
    const size_t eq = l.find('=');
    if (eq == std::string::npos || l.find("Pointer:") != std::string::npos) continue;
    const std::string key = trim(l.substr(0, eq));
    if (key.empty() || key[0] == '#') continue;
    out.push_back({key, trim(l.substr(eq + 1)), n});
  }
  return out;
}

std::vector<double> numbersOf(const std::string& path, const KeyLine& k, size_t expected);

/// One integer value of a key (checked before conversion).
int64_t integerOf(const std::string& path, const KeyLine& k) {
  const std::vector<double> v = numbersOf(path, k, 1);
  int64_t out = 0;
  if (v.size() != 1 || !io::integerIn(v[0], -int64_t(1e15), int64_t(1e15), out))
    fail(path, ": line ", k.line, ": ", k.key, " must be one integer, got '", k.value, "'");
  return out;
}

std::vector<double> numbersOf(const std::string& path, const KeyLine& k, size_t expected) {
  std::istringstream in(k.value);
  std::vector<double> v;
  for (double d; in >> d;)
    v.push_back(d);
  if (v.size() < expected || !in.eof())
    fail(path, ": line ", k.line, ": expected ", expected, " numbers for ", k.key, ", got '", k.value, "'");
  for (double d : v)
    if (!std::isfinite(d)) fail(path, ": line ", k.line, ": ", k.key, " is not finite");
  return v;
}

Parameters readParameters(const std::string& path) {
  Parameters p;
  for (const KeyLine& k : readKeyLines(path)) {
    if (k.key == "TopGridRank") {
      p.rank = int(std::clamp<int64_t>(integerOf(path, k), -1, 1000));
      if (p.rank != 3)
        fail(path, ": line ", k.line, ": TopGridRank is ", p.rank, ": a ", p.rank,
             "-D output; only 3-D AMR data can be read");
    } else if (k.key == "RefineBy") {
      const double r = numbersOf(path, k, 1)[0];
      int64_t ri = 0;
      if (!io::integerIn(r, 2, 1024, ri) || io::log2Exact(ri) < 0)
        fail(path, ": line ", k.line, ": RefineBy ", r, " is not a power of two up to 1024");
      p.refineBy = ri;
    } else if (k.key == "DomainLeftEdge") {
      const auto v = numbersOf(path, k, 3);
      p.left = vec3d(v[0], v[1], v[2]);
    } else if (k.key == "DomainRightEdge") {
      const auto v = numbersOf(path, k, 3);
      p.right = vec3d(v[0], v[1], v[2]);
    } else if (k.key == "InitialTime") {
      const double t = numbersOf(path, k, 1)[0];
      if (std::isfinite(t)) p.simulation.time = t;
      p.simulation.timeUnits = "code units"; // Enzo's time unit is the run's own (TimeUnits, cosmology)
    } else if (k.key == "CosmologyCurrentRedshift") {
      const double z = numbersOf(path, k, 1)[0];
      if (std::isfinite(z) && z > -1.0) p.simulation.redshift = z;
    } else if (k.key == "InitialCycleNumber") {
      int64_t c = 0;
      if (io::integerIn(numbersOf(path, k, 1)[0], 0, INT64_MAX, c)) p.simulation.cycle = c;
    }
  }
  return p;
}

/// The hierarchy keys a grid must (or, for fields, may) give, as bits of Grid::seen.
enum : unsigned { kRank = 1, kDim = 2, kStart = 4, kEnd = 8, kLeft = 16, kRight = 32, kFile = 64 };

/// Applies one hierarchy line `k` to its grid `g`; `dir` holds the data files.
void readGridKey(const std::string& h, const fs::path& dir, const KeyLine& k, Grid& g) {
  auto v3 = [&](unsigned bit) {
    const auto v = numbersOf(h, k, 3);
    g.seen |= bit;
    return v;
  };
  auto l3 = [&](unsigned bit) {
    const auto v = v3(bit);
    vec3l out;
    for (int a = 0; a < 3; ++a)
      if (!io::integerIn(v[size_t(a)], -int64_t(1e9), int64_t(1e9), out[a]))
        fail(h, ": line ", k.line, ": ", k.key, " must be integers within +-10^9");
    return out;
  };
  if (k.key == "GridRank") {
    g.rank = int(std::clamp<int64_t>(integerOf(h, k), -1, 1000));
    g.seen |= kRank;
    if (g.rank != 3) fail(h, ": grid ", g.id, ": GridRank is ", g.rank, ": only 3-D AMR data can be read");
  } else if (k.key == "GridDimension") {
    g.dimension = l3(kDim);
  } else if (k.key == "GridStartIndex") {
    g.start = l3(kStart);
  } else if (k.key == "GridEndIndex") {
    g.end = l3(kEnd);
  } else if (k.key == "GridLeftEdge") {
    const auto v = v3(kLeft);
    g.left = vec3d(v[0], v[1], v[2]);
  } else if (k.key == "GridRightEdge") {
    const auto v = v3(kRight);
    g.right = vec3d(v[0], v[1], v[2]);
  } else if (k.key == "BaryonFileName") {
    // Written with the path of the machine that ran the simulation: keep the basename.
    g.file = (dir / fs::path(k.value).filename()).string();
    g.seen |= kFile;
  } else if (k.key == "NumberOfBaryonFields") {
    g.fields = integerOf(h, k);
  } else if (k.key == "NumberOfParticles") {
    g.particles = integerOf(h, k);
    if (g.particles < 0 || g.particles > (int64_t(1) << 50))
      fail(h, ": line ", k.line, ": NumberOfParticles ", g.particles, " is out of range");
  } else if (k.key == "ParticleFileName") {
    g.particleFile = (dir / fs::path(k.value).filename()).string();
  }
}

/// The grids of the hierarchy file `h`, in file order.
std::vector<Grid> readGrids(const std::string& h) {
  const fs::path dir = fs::path(h).parent_path();
  std::vector<Grid> grids;
  for (const KeyLine& k : readKeyLines(h)) {
    if (k.key == "Grid") {
      const int64_t id = integerOf(h, k);
      if (id < 0 || id > 99999999) fail(h, ": line ", k.line, ": grid number ", id, " out of range");
      grids.push_back({});
      grids.back().id = id;
      grids.back().line = k.line;
      continue;
    }
    if (grids.empty()) continue;
    readGridKey(h, dir, k, grids.back());
  }
  if (grids.empty()) fail(h, ": no 'Grid = N' entries (not an Enzo hierarchy, or an empty one)");
  return grids;
}

/// Every grid must give its shape and edges, and its active zones must fit its dimensions.
void checkGrids(const std::string& h, const std::vector<Grid>& grids) {
  static const std::pair<unsigned, const char*> kNeeded[] = {{kRank, "GridRank"},        {kDim, "GridDimension"},
                                                             {kStart, "GridStartIndex"}, {kEnd, "GridEndIndex"},
                                                             {kLeft, "GridLeftEdge"},    {kRight, "GridRightEdge"}};
  for (const Grid& g : grids) {
    for (const auto& [bit, name] : kNeeded)
      if (!(g.seen & bit)) fail(h, ": grid ", g.id, " (line ", g.line, "): missing ", name, " (truncated hierarchy?)");
    if (g.fields != 0 && !(g.seen & kFile)) fail(h, ": grid ", g.id, " (line ", g.line, "): missing BaryonFileName");
    if (g.particles > 0 && g.particleFile.empty() && !(g.seen & kFile))
      fail(h, ": grid ", g.id, " (line ", g.line, "): ", g.particles, " particles but no ParticleFileName");
    for (int a = 0; a < 3; ++a) {
      if (g.start[a] < 0 || g.end[a] < g.start[a] || g.end[a] >= g.dimension[a])
        fail(h, ": grid ", g.id, ": active zones ", g.start[a], "..", g.end[a], " on axis ", a,
             " do not fit GridDimension ", g.dimension[a]);
      if (!(g.right[a] > g.left[a])) fail(h, ": grid ", g.id, ": GridRightEdge is not above GridLeftEdge on axis ", a);
    }
    io::checkPatchCells(g.dimension, strCat(h, ": grid ", g.id, ": GridDimension"));
  }
}

} // namespace

Output io::enzo::readOutput(const std::string& path) {
  Output o;
  if (endsWith(path, ".hierarchy")) {
    o.hierarchyPath = path;
    o.parameterPath = path.substr(0, path.size() - 10);
  } else {
    o.parameterPath = path;
    o.hierarchyPath = path + ".hierarchy";
  }
  std::error_code ec;
  if (!fs::exists(o.parameterPath, ec)) fail(o.parameterPath, ": missing parameter file of the Enzo output");
  if (!fs::exists(o.hierarchyPath, ec)) fail(o.hierarchyPath, ": missing hierarchy file of the Enzo output");
  o.params = readParameters(o.parameterPath);
  o.grids = readGrids(o.hierarchyPath);
  checkGrids(o.hierarchyPath, o.grids);
  return o;
}

namespace {

/// Checks a field dataset's shape (z, y, x) against its grid: false when it holds the active
/// zones only, true when it holds the whole grid with ghost zones.
bool storedShape(const h5::File& f, const std::string& name, const Grid& g) {
  const std::vector<uint64_t> d = f.dims(name);
  const vec3l n = g.active();
  if (d.size() == 3 && d[0] == uint64_t(n.z) && d[1] == uint64_t(n.y) && d[2] == uint64_t(n.x)) return false;
  if (d.size() == 3 && d[0] == uint64_t(g.dimension.z) && d[1] == uint64_t(g.dimension.y) &&
      d[2] == uint64_t(g.dimension.x))
    return true;
  std::string shape;
  for (uint64_t x : d) {
    if (!shape.empty()) shape += 'x';
    shape += std::to_string(x);
  }
  f.bad(name, strCat("grid ", g.id, ": shape ", shape, " is neither the active zones ", n.z, "x", n.y, "x", n.x,
                     " nor GridDimension ", g.dimension.z, "x", g.dimension.y, "x", g.dimension.x, " (z, y, x)"));
}

} // namespace

std::string io::enzo::groupOf(int64_t id) {
  char name[32];
  std::snprintf(name, sizeof name, "/Grid%08lld", static_cast<long long>(id));
  return name;
}

namespace {

/// Field names of the first grid that has fields: its 3-D datasets.
std::vector<std::string> fieldNames(const Output& o, DataFiles& files) {
  for (const Grid& g : o.grids) {
    if (g.fields == 0) continue;
    const h5::File& f = files.get(g.file);
    const std::string group = groupOf(g.id);
    if (!f.exists(group)) f.bad(group, strCat("missing group of grid ", g.id));
    std::vector<std::string> names;
    for (const std::string& m : f.members(group))
      if (f.isDataset(group + "/" + m) && f.dims(group + "/" + m).size() == 3) names.push_back(m);
    if (names.empty()) f.bad(group, "holds no 3-D field datasets");
    return names;
  }
  fail(o.hierarchyPath, ": no grid has fields");
}

/// The finest cell size over all grids: it fixes the lattice.
vec3d finestCellSize(const Output& o) {
  vec3d finest(INFINITY);
  for (const Grid& g : o.grids)
    for (int a = 0; a < 3; ++a)
      finest[a] = std::min(finest[a], (g.right[a] - g.left[a]) / double(g.active()[a]));
  return finest;
}

/// Every grid's active zones on the finest lattice; every grid must sit on it exactly.
std::vector<io::Patch> placeGrids(const Output& o, const vec3d& finest) {
  const std::string& h = o.hierarchyPath;
  std::vector<io::Patch> patches;
  for (const Grid& g : o.grids) {
    io::Patch p;
    p.cells = g.active();
    for (int a = 0; a < 3; ++a) {
      const double ratio = (g.right[a] - g.left[a]) / double(p.cells[a]) / finest[a];
      const double w = std::round(ratio);
      if (!(w >= 1 && w <= double(int64_t(1) << kMaxLevel)) || std::abs(ratio - w) > 1e-6 * w ||
          io::log2Exact(int64_t(w)) < 0)
        fail(h, ": grid ", g.id, ": cell size on axis ", a, " is ", ratio, " times the finest, not a power of two");
      if (a > 0 && int64_t(w) != p.width) fail(h, ": grid ", g.id, ": refined differently along the axes");
      p.width = int64_t(w);
      const double c = (g.left[a] - o.params.left[a]) / finest[a];
      const double ci = std::round(c);
      if (!(std::abs(c) <= double(kLatticeLimit)) || std::abs(c - ci) > 1e-5 + 1e-12 * std::abs(c))
        fail(h, ": grid ", g.id, ": GridLeftEdge on axis ", a, " lies ", c,
             " finest cells from DomainLeftEdge, not on the lattice");
      p.lower[a] = int64_t(ci);
      if (p.lower[a] % p.width != 0)
        fail(h, ": grid ", g.id, ": corner ", p.lower[a], " on axis ", a, " is not a multiple of its cell width ",
             p.width);
    }
    patches.push_back(p);
  }
  return patches;
}

/// The grid's group in its data file, which must hold it (`h` names the hierarchy).
} // namespace

std::string io::enzo::gridGroup(const h5::File& f, const Grid& g, const std::string& h) {
  const std::string group = groupOf(g.id);
  if (!f.exists(group)) f.bad(group, strCat("missing group of grid ", g.id, " (named by ", h, ")"));
  return group;
}

namespace {

/// The picked fields' values on the grid's active zones, converted to float.
std::vector<std::vector<float>> gridValues(const h5::File& f, const std::string& group, const Grid& g,
                                           const std::vector<std::string>& available,
                                           const std::vector<size_t>& picked) {
  const vec3l n = g.active();
  std::vector<std::vector<float>> values(picked.size());
  for (size_t k = 0; k < picked.size(); ++k) {
    const std::string name = group + "/" + available[picked[k]];
    const bool whole = storedShape(f, name, g);
    const vec3l stored = whole ? g.dimension : n, offset = whole ? g.start : vec3l(0);
    const std::vector<double> raw = f.readDoubles(name);
    values[k].reserve(size_t(n.x * n.y * n.z));
    for (int64_t z = 0; z < n.z; ++z)
      for (int64_t y = 0; y < n.y; ++y)
        for (int64_t x = 0; x < n.x; ++x) {
          const double v = raw[size_t(((z + offset.z) * stored.y + (y + offset.y)) * stored.x + (x + offset.x))];
          values[k].push_back(io::toFloat32(
              v, [&] { return strCat(f.path(), ": ", name, ": grid ", g.id, " cell (", x, ",", y, ",", z, ")"); }));
        }
  }
  return values;
}

/// Every dataset of the fields `picked` in the grids `grid` (indices into o.grids, placed as
/// `patches`): its shape checked, and its storage against the file, before per-cell memory is
/// reserved for its grid; a grid without fields must be covered by finer ones.
void checkGridData(const Output& o, DataFiles& files, const std::vector<std::string>& available,
                   const std::vector<size_t>& picked, const std::vector<size_t>& grid,
                   const std::vector<io::Patch>& patches, const std::function<std::string(size_t)>& gridName) {
  std::vector<uint8_t> backed(grid.size(), 0);
  for (size_t i = 0; i < grid.size(); ++i) {
    const Grid& g = o.grids[grid[i]];
    if (g.fields == 0) continue;
    const h5::File& f = files.get(g.file);
    const std::string group = gridGroup(f, g, o.hierarchyPath);
    for (size_t k : picked) {
      storedShape(f, group + "/" + available[k], g);
      f.requireStorage(group + "/" + available[k]);
    }
    backed[i] = 1;
  }
  io::checkUnbackedPatches(patches, backed, gridName);
}

} // namespace

bool isEnzoOutput(const std::string& path) {
  std::error_code ec;
  if (fs::is_directory(path, ec)) return false;
  const std::string h = endsWith(path, ".hierarchy") ? path : path + ".hierarchy";
  std::ifstream in(h);
  if (!in) return false;
  char buf[4096] = {};
  in.read(buf, sizeof buf - 1);
  const std::string head(buf, size_t(in.gcount()));
  return head.find("GridRank") != std::string::npos || head.find("Grid = ") != std::string::npos;
}

std::vector<std::string> listEnzoFields(const std::string& path) {
  const Output o = readOutput(path);
  DataFiles files;
  return fieldNames(o, files);
}

std::vector<double> enzoLevelCells(const std::string& path) {
  const Output o = readOutput(path);
  return io::levelCellsOfPatches(placeGrids(o, finestCellSize(o)));
}

Census enzoCensus(const std::string& path) {
  const Output o = readOutput(path);
  const std::vector<io::Patch> patches = placeGrids(o, finestCellSize(o));
  auto gridName = [&](size_t i) { return strCat(o.hierarchyPath, ": grid ", o.grids[i].id); };
  // The grids are counted from the hierarchy, but only as far as the data files hold them (the
  // first field's datasets).
  DataFiles files;
  const std::vector<std::string> available = fieldNames(o, files);
  std::vector<size_t> all(o.grids.size());
  for (size_t i = 0; i < all.size(); ++i)
    all[i] = i;
  checkGridData(o, files, available, available.empty() ? std::vector<size_t>{} : std::vector<size_t>{0}, all, patches,
                gridName);
  return io::censusOfPatches(patches, gridName);
}

PatchSource enzoPatches(const std::string& path, const std::vector<std::string>& wanted, int finestLevel) {
  struct State {
    Output o;
    DataFiles files;
    std::vector<std::string> available;
    std::vector<size_t> picked;
    std::vector<size_t> grid; // the grids read, per patch
  };
  auto st = std::make_shared<State>();
  st->o = readOutput(path);
  const Output& o = st->o;
  st->available = fieldNames(o, st->files);
  st->picked = io::pickFields(path, st->available, wanted);

  PatchSource source = io::sourceOfFields(path, st->available, st->picked);
  // The lattice is the whole step's (its finest grids' cells), whichever levels are read; grids
  // finer than finestLevel are left out, and the coarser cells under them are leaves (Enzo stores
  // every grid's values, those under its children included).
  const vec3d finest = finestCellSize(o);
  source.patches = placeGrids(o, finest);
  st->grid = io::coarsePatches(source.patches, finestLevel);
  io::keepOnly(source.patches, st->grid);
  source.name = [st](size_t i) { return strCat(st->o.hierarchyPath, ": grid ", st->o.grids[st->grid[i]].id); };
  checkGridData(o, st->files, st->available, st->picked, st->grid, source.patches, source.name);
  source.read = [st, name = source.name](size_t i, std::vector<std::vector<float>>& values) {
    const Grid& g = st->o.grids[st->grid[i]];
    if (g.fields == 0) fail(name(i), ": has leaf cells but no fields");
    const h5::File& f = st->files.get(g.file);
    values = gridValues(f, gridGroup(f, g, st->o.hierarchyPath), g, st->available, st->picked);
  };
  source.world.origin = o.params.left;
  source.world.scale = finest;
  source.simulation = o.params.simulation;
  return source;
}

CellSet readEnzo(const std::string& path, const std::vector<std::string>& wanted, int finestLevel, const box3i& box) {
  return io::readPatchCells(enzoPatches(path, wanted, finestLevel), box);
}

} // namespace exa
