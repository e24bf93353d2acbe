#include "exabricks/io/flash.h"

#include "hdf5_file.h"
#include "patches.h"

#include "exabricks/core/error.h"
#include "exabricks/core/log.h"

#include <algorithm>
#include <cfloat>
#include <cmath>
#include <limits>

namespace exa {
namespace {

/// An integer from a (name, value) table such as "integer scalars", or -1 when absent.
int64_t tableInt(const h5::CompoundTable& t, const std::string& name) {
  const auto nameAt = std::find(t.members.begin(), t.members.end(), "name");
  const auto valueAt = std::find(t.members.begin(), t.members.end(), "value");
  if (nameAt == t.members.end() || valueAt == t.members.end()) return -1;
  const size_t m = t.members.size();
  const size_t vi = size_t(valueAt - t.members.begin());
  // One string per record: "name" is the table's only string member.
  for (size_t r = 0; r < t.records; ++r)
    if (r < t.strings.size() && t.strings[r] == name) {
      const double v = t.values[r * m + vi];
      return std::abs(v) < 1e9 ? int64_t(v) : -2;
    }
  return -1;
}

/// A number from a (name, value) table such as "real scalars", or NaN when absent.
double tableReal(const h5::CompoundTable& t, const std::string& name) {
  const auto nameAt = std::find(t.members.begin(), t.members.end(), "name");
  const auto valueAt = std::find(t.members.begin(), t.members.end(), "value");
  if (nameAt == t.members.end() || valueAt == t.members.end()) return std::numeric_limits<double>::quiet_NaN();
  const size_t m = t.members.size();
  const size_t vi = size_t(valueAt - t.members.begin());
  for (size_t r = 0; r < t.records; ++r)
    if (r < t.strings.size() && t.strings[r] == name) return t.values[r * m + vi];
  return std::numeric_limits<double>::quiet_NaN();
}

struct FlashHeader {
  std::vector<std::string> names; ///< variables with a dataset
  uint64_t blocks = 0;
  vec3l blockCells{0}; ///< nxb, nyb, nzb
};

FlashHeader readHeader(const h5::File& f) {
  FlashHeader h;
  const std::vector<uint64_t> bbox = f.dims("bounding box");
  if (bbox.size() != 3 || bbox[2] != 2) f.bad("bounding box", "expected dimensions [blocks, dims, 2]");
  h.blocks = bbox[0];
  if (f.isDataset("integer scalars")) {
    const h5::CompoundTable t = f.readCompound("integer scalars");
    const int64_t dim = tableInt(t, "dimensionality");
    if (dim != -1 && dim != 3)
      f.bad("integer scalars",
            strCat("dimensionality is ", dim, ": a ", dim, "-D file; only 3-D AMR data can be read"));
    h.blockCells = vec3l(tableInt(t, "nxb"), tableInt(t, "nyb"), tableInt(t, "nzb"));
  }
  if (bbox[1] != 3)
    f.bad("bounding box", strCat("holds ", bbox[1], " axes: a ", bbox[1], "-D file; only 3-D AMR data can be read"));
  const std::vector<std::string> unknowns = f.readStrings("unknown names");
  for (const std::string& n : unknowns) {
    std::string name = n;
    while (!name.empty() && name.front() == ' ')
      name.erase(name.begin());
    if (!name.empty() && f.isDataset(name)) h.names.push_back(name);
  }
  if (h.names.empty()) f.bad("unknown names", "no variable has a dataset in the file");
  // Block size from the variables when the scalars do not give it.
  const std::vector<uint64_t> vd = f.dims(h.names[0]);
  if (vd.size() != 4) f.bad(h.names[0], strCat("has ", vd.size(), " dimensions, expected [blocks, nzb, nyb, nxb]"));
  if (h.blockCells.x <= 0 || h.blockCells.y <= 0 || h.blockCells.z <= 0)
    h.blockCells = vec3l(int64_t(vd[3]), int64_t(vd[2]), int64_t(vd[1]));
  if (h.blockCells.z == 1) f.bad(h.names[0], "nzb is 1: a 2-D file; only 3-D AMR data can be read");
  for (int a = 0; a < 3; ++a)
    if (h.blockCells[a] < 1 || h.blockCells[a] > 4096) f.bad(h.names[0], "absurd block size");
  for (const std::string& name : h.names) {
    const std::vector<uint64_t> d = f.dims(name);
    if (d.size() != 4 || d[0] != h.blocks || int64_t(d[1]) != h.blockCells.z || int64_t(d[2]) != h.blockCells.y ||
        int64_t(d[3]) != h.blockCells.x)
      f.bad(name, strCat("dimensions do not match [", h.blocks, ", ", h.blockCells.z, ", ", h.blockCells.y, ", ",
                         h.blockCells.x, "] (blocks, nzb, nyb, nxb)"));
    // The cells of every block are bounded by the values stored before any is allocated.
    f.requireStorage(name);
  }
  return h;
}

/// The leaf blocks (node type 1), with the finest cell size and the domain's lower corner.
struct Leaves {
  std::vector<uint64_t> blocks;
  vec3d finest{INFINITY}, origin{INFINITY};
};

Leaves findLeaves(const h5::File& f, const FlashHeader& h, const std::vector<int64_t>& nodeType,
                  const std::vector<double>& bbox) {
  Leaves l;
  for (uint64_t b = 0; b < h.blocks; ++b) {
    if (nodeType[b] != 1) continue;
    l.blocks.push_back(b);
    for (int a = 0; a < 3; ++a) {
      const double lo = bbox[b * 6 + size_t(a) * 2], hi = bbox[b * 6 + size_t(a) * 2 + 1];
      if (!std::isfinite(lo) || !std::isfinite(hi) || !(hi > lo))
        f.bad("bounding box", strCat("block ", b, ": empty or non-finite extent on axis ", a));
      l.finest[a] = std::min(l.finest[a], (hi - lo) / double(h.blockCells[a]));
      l.origin[a] = std::min(l.origin[a], lo);
    }
  }
  if (l.blocks.empty()) f.bad("node type", "no leaf blocks (node type 1)");
  return l;
}

/// Places every leaf block on the finest lattice; reports any block that does not fit exactly.
/// `eps` is the precision of the stored coordinates.
std::vector<io::Patch> placeLeaves(const h5::File& f, const FlashHeader& h, const std::vector<double>& bbox,
                                   const Leaves& l, double eps) {
  std::vector<io::Patch> patches;
  for (uint64_t b : l.blocks) {
    io::Patch p;
    p.cells = h.blockCells;
    double ratio[3];
    for (int a = 0; a < 3; ++a) {
      const double lo = bbox[b * 6 + size_t(a) * 2], hi = bbox[b * 6 + size_t(a) * 2 + 1];
      ratio[a] = (hi - lo) / double(h.blockCells[a]) / l.finest[a];
      const double w = std::round(ratio[a]);
      if (!(w >= 1 && w <= double(int64_t(1) << kMaxLevel)) || std::abs(ratio[a] - w) > 1e-5 * w ||
          io::log2Exact(int64_t(w)) < 0)
        f.bad("bounding box", strCat("block ", b, ": cell size on axis ", a, " is ", ratio[a],
                                     " times the finest leaf cell size, not a power of two"));
      if (a > 0 && int64_t(w) != p.width)
        f.bad("bounding box", strCat("block ", b, ": refined differently along the axes (cell size ratios ", ratio[0],
                                     ", ", ratio[a], ")"));
      p.width = int64_t(w);
      const double c = (lo - l.origin[a]) / l.finest[a];
      const double ci = std::round(c);
      if (!(std::abs(c) <= double(kLatticeLimit)) || std::abs(c - ci) > 1e-6 + 16 * eps * (std::abs(c) + 1))
        f.bad("bounding box", strCat("block ", b, ": lower corner on axis ", a, " lies ", c,
                                     " finest cells from the domain corner, not on the finest lattice"));
      p.lower[a] = int64_t(ci);
      if (p.lower[a] % p.width != 0)
        f.bad("bounding box", strCat("block ", b, ": lower corner ", p.lower[a], " on axis ", a,
                                     " is not a multiple of its cell width ", p.width, " finest cells"));
    }
    patches.push_back(p);
  }
  return patches;
}

/// The simulation's time and step, where the scalars hold them.
SimulationState simulationOf(const h5::File& f) {
  SimulationState s;
  if (f.isDataset("real scalars")) {
    const double t = tableReal(f.readCompound("real scalars"), "time");
    if (std::isfinite(t)) s.time = t;
  }
  if (f.isDataset("integer scalars")) {
    const int64_t step = tableInt(f.readCompound("integer scalars"), "nstep");
    if (step >= 0) s.cycle = step;
  }
  return s;
}

/// The header, the leaf blocks and their places on the finest lattice.
struct FlashBlocks {
  FlashHeader header;
  Leaves leaves;
  std::vector<io::Patch> patches; ///< per leaf block
};

FlashBlocks readBlocks(const h5::File& f) {
  FlashBlocks b;
  b.header = readHeader(f);
  const std::vector<int64_t> nodeType = f.readInts("node type");
  if (nodeType.size() != b.header.blocks)
    f.bad("node type", strCat(nodeType.size(), " entries for ", b.header.blocks, " blocks"));
  const std::vector<double> bbox = f.readDoubles("bounding box");
  // Coordinates stored as float32 carry only about 7 digits.
  const double eps = f.isDouble("bounding box") ? DBL_EPSILON : double(FLT_EPSILON);
  b.leaves = findLeaves(f, b.header, nodeType, bbox);
  b.patches = placeLeaves(f, b.header, bbox, b.leaves, eps);
  return b;
}

/// Variable `name`'s value at cell i of block b, as float32 (a value float32 cannot hold is an
/// error naming the block, the variable and the cell).
float blockValue(const std::string& path, const FlashHeader& h, uint64_t b, const std::string& name, int64_t i,
                 double v) {
  return io::toFloat32(v, [&] {
    const int64_t x = i % h.blockCells.x, y = (i / h.blockCells.x) % h.blockCells.y,
                  z = i / (h.blockCells.x * h.blockCells.y);
    return strCat(path, ": block ", b, ": variable '", name, "' at cell (", x, ",", y, ",", z, ")");
  });
}

/// The cells of every leaf block, in block order and x fastest within a block.
void addCells(const std::string& path, const std::vector<io::Patch>& patches, CellSet& set) {
  for (const io::Patch& p : patches) {
    const int level = io::log2Exact(p.width);
    for (int64_t z = 0; z < p.cells.z; ++z)
      for (int64_t y = 0; y < p.cells.y; ++y)
        for (int64_t x = 0; x < p.cells.x; ++x) {
          const vec3l c = p.lower + vec3l(x, y, z) * p.width;
          if (c.x + p.width > kLatticeLimit || c.y + p.width > kLatticeLimit || c.z + p.width > kLatticeLimit)
            fail(path, ": leaf blocks span more than the supported lattice range (2^29 finest cells)");
          set.cells.push_back(Cell{vec3i(int32_t(c.x), int32_t(c.y), int32_t(c.z)), level});
        }
  }
}

/// The chosen variables' values on the leaf blocks, into set.fields. Variables are read a run
/// of blocks at a time: whole runs are cheap for HDF5, and the run length bounds the memory held.
void readVariables(const h5::File& f, const std::string& path, const FlashHeader& h, const std::vector<size_t>& vars,
                   const std::vector<uint64_t>& leaves, CellSet& set) {
  const int64_t perBlock = h.blockCells.x * h.blockCells.y * h.blockCells.z;
  const uint64_t run = std::max<uint64_t>(1, uint64_t(4 << 20) / uint64_t(perBlock));
  Progress progress("reading " + path, uint64_t(vars.size()) * h.blocks);
  for (size_t k = 0; k < vars.size(); ++k) {
    const std::string& name = h.names[vars[k]];
    std::vector<float>& out = set.fields[k].values;
    out.reserve(set.cells.size());
    size_t next = 0; // index into leaves
    for (uint64_t first = 0; first < h.blocks && next < leaves.size(); first += run) {
      const uint64_t count = std::min(run, h.blocks - first);
      if (leaves[next] >= first + count) {
        progress.advance(count);
        continue;
      }
      const std::vector<double> raw = f.readRows(name, first, count);
      for (; next < leaves.size() && leaves[next] < first + count; ++next) {
        const uint64_t b = leaves[next];
        const double* src = raw.data() + (b - first) * uint64_t(perBlock);
        for (int64_t i = 0; i < perBlock; ++i)
          out.push_back(blockValue(path, h, b, name, i, src[i]));
      }
      progress.advance(count);
    }
  }
  progress.finish();
}

} // namespace

bool isFlashFile(const std::string& path) {
  if (!h5::hasSignature(path)) return false;
  try {
    const h5::File f(path);
    return f.isDataset("node type") && f.isDataset("bounding box");
  } catch (const h5::DamagedFile&) {
    throw; // a damaged HDF5 file, whatever its layout: the check's message says what is wrong
  } catch (const Error&) {
    return false;
  }
}

std::vector<std::string> listFlashFields(const std::string& path) { return readHeader(h5::File(path)).names; }

CellSet readFlash(const std::string& path, const std::vector<std::string>& wanted) {
  const h5::File f(path);
  const FlashBlocks blocks = readBlocks(f);
  const FlashHeader& h = blocks.header;
  const Leaves& leaves = blocks.leaves;
  const std::vector<size_t> vars = io::pickFields(path, h.names, wanted);

  CellSet set;
  for (size_t v : vars)
    set.fields.push_back({h.names[v], {}});
  set.simulation = simulationOf(f);
  addCells(path, blocks.patches, set);
  readVariables(f, path, h, vars, leaves.blocks, set);
  set.world.origin = leaves.origin;
  set.world.scale = leaves.finest;
  logInfo(strCat("read ", set.cells.size(), " cells of ", leaves.blocks.size(), " leaf blocks from ", path));
  return set;
}

Census flashCensus(const std::string& path) {
  const h5::File f(path);
  const FlashBlocks b = readBlocks(f);
  return io::censusOfPatches(b.patches, [&](size_t i) { return strCat(path, ": block ", b.leaves.blocks[i]); });
}

PatchSource flashPatches(const std::string& path, const std::vector<std::string>& wanted, int finestLevel) {
  if (finestLevel > 0)
    fail(path, ": a FLASH file is read with all its levels (its parent blocks need not hold values)");
  // The variables of a run of consecutive blocks are read at once (whole runs are cheap for
  // HDF5) and kept until a block beyond them is asked for: a build reads its blocks in order.
  struct State {
    h5::File file;
    FlashBlocks blocks;
    std::vector<size_t> vars;
    uint64_t first = 0, count = 0;        ///< the blocks of the run read last
    std::vector<std::vector<double>> run; ///< per variable, their values
    explicit State(const std::string& p) : file(p) {}
  };
  auto st = std::make_shared<State>(path);
  st->blocks = readBlocks(st->file);
  const FlashHeader& h = st->blocks.header;
  st->vars = io::pickFields(path, h.names, wanted);

  PatchSource source = io::sourceOfFields(path, h.names, st->vars);
  source.patches = st->blocks.patches;
  source.name = [st, path](size_t i) { return strCat(path, ": block ", st->blocks.leaves.blocks[i]); };
  source.read = [st, path](size_t i, std::vector<std::vector<float>>& values) {
    const FlashHeader& hd = st->blocks.header;
    const uint64_t b = st->blocks.leaves.blocks[i];
    const int64_t perBlock = hd.blockCells.x * hd.blockCells.y * hd.blockCells.z;
    if (b < st->first || b >= st->first + st->count) {
      st->first = b;
      st->count = std::min(std::max<uint64_t>(1, uint64_t(1 << 18) / uint64_t(perBlock)), hd.blocks - b);
      st->run.clear();
      for (size_t v : st->vars)
        st->run.push_back(st->file.readRows(hd.names[v], st->first, st->count));
    }
    values.assign(st->vars.size(), {});
    for (size_t k = 0; k < st->vars.size(); ++k) {
      const double* src = st->run[k].data() + (b - st->first) * uint64_t(perBlock);
      values[k].resize(size_t(perBlock));
      for (int64_t c = 0; c < perBlock; ++c)
        values[k][size_t(c)] = blockValue(path, hd, b, hd.names[st->vars[k]], c, src[c]);
    }
  };
  source.simulation = simulationOf(st->file);
  source.world.origin = st->blocks.leaves.origin;
  source.world.scale = st->blocks.leaves.finest;
  return source;
}

} // namespace exa
