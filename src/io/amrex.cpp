#include "exabricks/io/amrex.h"

#include "exabricks/core/error.h"
#include "exabricks/core/kept.h"
#include "exabricks/core/log.h"

#include "checked.h"
#include "exabricks/core/byte_order.h"
#include "patches.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <memory>
#include <optional>
#include <sstream>
#include <string_view>

namespace exa {
namespace fs = std::filesystem;

namespace {

/// Whitespace-separated tokens of a text file, with the line of each for messages.
class TextReader {
public:
  explicit TextReader(const std::string& path) : path_(path) {
    std::ifstream in(path);
    if (!in) fail(path, ": cannot open: ", std::strerror(errno));
    std::ostringstream s;
    s << in.rdbuf();
    text_ = s.str();
  }
  const std::string& path() const { return path_; }
  std::string line() {
    if (pos_ >= text_.size()) fail(path_, ": line ", lineNo_ + 1, ": unexpected end of file");
    const size_t end = std::min(text_.find('\n', pos_), text_.size());
    std::string l = text_.substr(pos_, end - pos_);
    pos_ = end + 1;
    ++lineNo_;
    if (!l.empty() && l.back() == '\r') l.pop_back();
    return l;
  }
  /// Passes over a line without copying it.
  void skipLine() {
    if (pos_ >= text_.size()) fail(path_, ": line ", lineNo_ + 1, ": unexpected end of file");
    pos_ = std::min(text_.find('\n', pos_), text_.size()) + 1;
    ++lineNo_;
  }
  size_t lineNo() const { return lineNo_; }
  bool atEnd() const { return pos_ >= text_.size(); }
  [[noreturn]] void bad(const std::string& what) const { fail(path_, ": line ", lineNo_, ": ", what); }
  /// An integer within [lo, hi] from a number of the current line; `what` names it.
  int64_t integer(double v, int64_t lo, int64_t hi, const char* what) const {
    return io::checkedInteger(v, lo, hi, [&] { return strCat(path_, ": line ", lineNo_, ": ", what); });
  }

private:
  std::string path_, text_;
  size_t pos_ = 0, lineNo_ = 0;
};

/// The numbers of a line, separated by blanks, parentheses and commas, up to the first word that
/// is not one.
std::vector<double> numbers(TextReader& r, std::string_view line, size_t expected, const char* what) {
  std::vector<double> v;
  auto separator = [](char c) { return c == '(' || c == ')' || c == ',' || std::isspace((unsigned char)c); };
  for (size_t at = 0; at < line.size();) {
    if (separator(line[at])) {
      ++at;
      continue;
    }
    size_t end = at;
    while (end < line.size() && !separator(line[end]))
      ++end;
    const char* first = line.data() + at + (line[at] == '+' ? 1 : 0);
    double d = 0;
    const auto [ptr, ec] = std::from_chars(first, line.data() + end, d);
    if (ec != std::errc() || first == line.data() + end) break;
    v.push_back(d);
    if (ptr != line.data() + end) break; // a number glued to a word ends the numbers
    at = end;
  }
  if (expected && v.size() < expected) r.bad(strCat("expected ", expected, " numbers for ", what));
  return v;
}

/// An index-space box "((lo) (hi) (type))", inclusive bounds, each within the lattice range.
struct IndexBox {
  vec3l lo, hi;
};

/// Parses every "((a,b,c) (d,e,f) (g,h,i))" box on a line.
std::vector<IndexBox> parseBoxes(TextReader& r, const std::string& line) {
  std::vector<IndexBox> boxes;
  size_t pos = 0;
  while ((pos = line.find("((", pos)) != std::string::npos) {
    const size_t end = line.find("))", pos);
    if (end == std::string::npos) r.bad("unterminated box");
    const std::vector<double> v = numbers(r, std::string_view(line).substr(pos, end - pos + 2), 9, "a box");
    IndexBox b;
    for (int a = 0; a < 3; ++a) {
      b.lo[a] = r.integer(v[size_t(a)], -kLatticeLimit, kLatticeLimit, "a box corner");
      b.hi[a] = r.integer(v[size_t(a) + 3], -kLatticeLimit, kLatticeLimit, "a box corner");
    }
    if (b.hi.x < b.lo.x || b.hi.y < b.lo.y || b.hi.z < b.lo.z) r.bad("empty box");
    boxes.push_back(b);
    pos = end + 2;
  }
  return boxes;
}

struct LevelData {
  std::vector<IndexBox> boxes;        ///< valid regions (ghost cells stripped)
  std::vector<std::string> fileNames; ///< the level's data files
  std::vector<uint32_t> fileOf;       ///< data file of each box (into fileNames)
  std::vector<uint64_t> offsets;      ///< byte offset per box
  std::vector<range1f> ranges;        ///< per component, from the min/max tables (empty: none)
  int nghost = 0;
  const std::string& file(size_t box) const { return fileNames[fileOf[box]]; }
};

struct Plotfile {
  std::string dir;
  std::vector<std::string> names;
  int finestLevel = 0;
  vec3d probLo, probHi;
  std::vector<int> ratios; ///< per level step (finestLevel entries)
  std::vector<IndexBox> domains;
  std::vector<vec3d> dx;
  std::vector<std::string> levelPrefixes;
  double time = std::numeric_limits<double>::quiet_NaN();
  int64_t cycle = -1; ///< steps of the coarsest level
};

/// The version line (only HyperCLaw-V1.1 is read) and the variable names.
std::vector<std::string> readNames(TextReader& r) {
  const std::string version = r.line();
  if (version.rfind("HyperCLaw", 0) != 0) r.bad("not an AMReX plotfile header ('" + version + "')");
  {
    std::string v = version;
    while (!v.empty() && std::isspace((unsigned char)v.back()))
      v.pop_back();
    if (v != "HyperCLaw-V1.1") r.bad("plotfile version '" + v + "' is not supported (HyperCLaw-V1.1 is)");
  }
  const int nvars = int(r.integer(numbers(r, r.line(), 1, "the variable count")[0], 1, 100000, "the variable count"));
  std::vector<std::string> names;
  for (int i = 0; i < nvars; ++i) {
    std::string name = r.line();
    while (!name.empty() && std::isspace((unsigned char)name.back()))
      name.pop_back();
    if (name.empty()) r.bad("empty variable name");
    names.push_back(name);
  }
  return names;
}

/// The refinement ratio of each level to the next (powers of two, isotropic, multiplying to at
/// most 2^kMaxLevel).
void readRatios(TextReader& r, Plotfile& pf) {
  const auto ratios = numbers(r, r.line(), 0, "refinement ratios");
  if (int(ratios.size()) < pf.finestLevel) r.bad("fewer refinement ratios than levels");
  // Ratios may be written as one number per level or as IntVects; take one per level.
  const size_t stride = ratios.size() >= size_t(3 * pf.finestLevel) && pf.finestLevel > 0 && ratios.size() % 3 == 0 &&
                                ratios.size() != size_t(pf.finestLevel)
                            ? 3
                            : 1;
  for (int l = 0; l < pf.finestLevel; ++l) {
    const double rv = ratios[size_t(l) * stride];
    int64_t ri = 0;
    if (!io::integerIn(rv, 2, int64_t(1) << kMaxLevel, ri) || (ri & (ri - 1)) != 0)
      r.bad(strCat("refinement ratio ", rv, " between levels ", l, " and ", l + 1, " is not a power of two up to 2^",
                   kMaxLevel));
    if (stride == 3 && (ratios[size_t(l) * 3 + 1] != rv || ratios[size_t(l) * 3 + 2] != rv))
      r.bad("anisotropic refinement ratios are not supported");
    pf.ratios.push_back(int(ri));
  }
  int64_t width = 1;
  for (int ratio : pf.ratios)
    if ((width *= ratio) > (int64_t(1) << kMaxLevel))
      r.bad(strCat("the refinement ratios multiply to more than 2^", kMaxLevel));
}

/// The levels' lines at the end of the header: each level's grids (skipped) and the prefix of
/// its Cell_H file.
void readLevelPrefixes(TextReader& r, Plotfile& pf) {
  for (int l = 0; l <= pf.finestLevel; ++l) {
    const auto head = numbers(r, r.line(), 2, "the level line");
    if (head[0] != double(l)) r.bad(strCat("expected level ", l));
    const int64_t ngrids = r.integer(head[1], 0, 100000000, "the grid count");
    r.line(); // level step
    for (int64_t g = 0; g < ngrids * 3; ++g)
      r.skipLine();
    std::string prefix = r.line();
    while (!prefix.empty() && std::isspace((unsigned char)prefix.back()))
      prefix.pop_back();
    pf.levelPrefixes.push_back(prefix);
  }
}

Plotfile readHeader(const std::string& dir) {
  Plotfile pf;
  pf.dir = dir;
  TextReader r((fs::path(dir) / "Header").string());
  pf.names = readNames(r);
  const int dim = int(r.integer(numbers(r, r.line(), 1, "the dimension")[0], 1, 3, "the dimension"));
  if (dim != 3) r.bad(strCat("a ", dim, "-D plotfile; only 3-D AMR data can be read"));
  {
    const auto t = numbers(r, r.line(), 1, "the time");
    if (std::isfinite(t[0])) pf.time = t[0];
  }
  pf.finestLevel = int(r.integer(numbers(r, r.line(), 1, "the finest level")[0], 0, kMaxLevel, "the finest level"));
  const auto lo = numbers(r, r.line(), 3, "prob_lo");
  const auto hi = numbers(r, r.line(), 3, "prob_hi");
  pf.probLo = vec3d(lo[0], lo[1], lo[2]);
  pf.probHi = vec3d(hi[0], hi[1], hi[2]);
  readRatios(r, pf);
  pf.domains = parseBoxes(r, r.line());
  if (int(pf.domains.size()) < pf.finestLevel + 1) r.bad("fewer level domains than levels");
  {
    const auto steps = numbers(r, r.line(), 0, "the level steps");
    if (!steps.empty() && steps[0] >= 0 && steps[0] < 9.0e18 && steps[0] == std::floor(steps[0]))
      pf.cycle = int64_t(steps[0]);
  }
  for (int l = 0; l <= pf.finestLevel; ++l) {
    const auto d = numbers(r, r.line(), 3, "the cell size");
    pf.dx.push_back(vec3d(d[0], d[1], d[2]));
    if (!(d[0] > 0 && d[1] > 0 && d[2] > 0)) r.bad("cell sizes must be positive");
  }
  const double coord = numbers(r, r.line(), 1, "the coordinate system")[0];
  if (coord != 0) r.bad(strCat("coordinate system ", coord, " is not Cartesian"));
  r.line(); // boundary width
  readLevelPrefixes(r, pf);
  return pf;
}

/// Reads a level's Cell_H: its boxes, where their FABs are, and the per-FAB minima and maxima of
/// every component that follow the FAB list (one range per component; none when the file has no
/// such tables).
LevelData readCellHeader(const Plotfile& pf, int level) {
  const fs::path prefix = fs::path(pf.dir) / pf.levelPrefixes[size_t(level)];
  TextReader r(prefix.string() + "_H");
  LevelData ld;
  const double version = numbers(r, r.line(), 1, "the VisMF version")[0];
  if (version != 1)
    r.bad(strCat("VisMF version ", version, " is not supported (version 1 is: re-write the plotfile with ",
                 "AMReX's default 'VisMF::Header::Version_v1', or convert it)"));
  r.line(); // how
  const double ncomp = numbers(r, r.line(), 1, "the component count")[0];
  if (ncomp != double(pf.names.size())) r.bad(strCat(ncomp, " components, but the Header names ", pf.names.size()));
  ld.nghost = int(r.integer(numbers(r, r.line(), 1, "the ghost width")[0], 0, 64, "the ghost width"));
  const int64_t nboxes = r.integer(numbers(r, r.line(), 1, "the box count")[0], 0, 100000000, "the box count");
  for (int64_t b = 0; b < nboxes; ++b) {
    const std::vector<IndexBox> box = parseBoxes(r, r.line());
    if (box.size() != 1) r.bad("expected one box");
    ld.boxes.push_back(box[0]);
  }
  r.line(); // ")"
  const int64_t nfabs = r.integer(numbers(r, r.line(), 1, "the FAB count")[0], 0, 100000000, "the FAB count");
  if (nfabs != nboxes) r.bad(strCat(nfabs, " FabOnDisk entries for ", nboxes, " boxes"));
  std::map<std::string, uint32_t, std::less<>> fileIndex;
  for (int64_t b = 0; b < nfabs; ++b) {
    const std::string line = r.line();
    const std::string_view tag = "FabOnDisk:";
    std::string_view rest(line);
    if (rest.substr(0, tag.size()) != tag) r.bad("expected 'FabOnDisk: FILE OFFSET'");
    rest.remove_prefix(tag.size());
    auto word = [&rest] {
      while (!rest.empty() && std::isspace((unsigned char)rest.front()))
        rest.remove_prefix(1);
      size_t n = 0;
      while (n < rest.size() && !std::isspace((unsigned char)rest[n]))
        ++n;
      const std::string_view w = rest.substr(0, n);
      rest.remove_prefix(n);
      return w;
    };
    const std::string_view file = word(), number = word();
    uint64_t offset = 0;
    const auto [end, ec] = std::from_chars(number.data(), number.data() + number.size(), offset);
    if (file.empty() || number.empty() || ec != std::errc() || end != number.data() + number.size())
      r.bad("expected 'FabOnDisk: FILE OFFSET'");
    auto it = fileIndex.find(file);
    if (it == fileIndex.end()) {
      it = fileIndex.emplace(std::string(file), uint32_t(ld.fileNames.size())).first;
      ld.fileNames.push_back((prefix.parent_path() / std::string(file)).string());
    }
    ld.fileOf.push_back(it->second);
    ld.offsets.push_back(offset);
  }
  {
    // A table that is absent or malformed only means that the data must be read for the range.
    std::vector<range1f>* ranges = &ld.ranges;
    try {
      ranges->assign(size_t(ncomp), range1f());
      for (int pass = 0; pass < 2; ++pass) { // minima, then maxima
        std::string line;
        while (!r.atEnd() && line.empty())
          line = r.line();
        if (line.empty()) throw Error("no min/max table");
        const std::vector<double> counts = numbers(r, line, 2, "the FAB and component counts");
        if (counts[0] != double(nfabs) || counts[1] != ncomp) r.bad("the min/max table does not match the FABs");
        for (int64_t b = 0; b < nfabs; ++b) {
          const std::vector<double> v = numbers(r, r.line(), size_t(ncomp), "per-FAB extremes");
          for (size_t k = 0; k < ranges->size(); ++k)
            if (std::isfinite(v[k])) (*ranges)[k].extend(float(v[k]));
        }
      }
    } catch (const Error&) {
      ranges->clear();
    }
  }
  return ld;
}

/// A plotfile's metadata: its Header and every level's Cell_H.
struct PlotfileMeta {
  Plotfile pf;
  std::vector<LevelData> levels;
  std::vector<int64_t> width; ///< of a level's cells, in finest cells
  std::string stamp;          ///< of the Header and Cell_H files parsed (metaStamp)
};

/// What tells a file's versions apart: its contents up to 1 MiB (a file rewritten within the
/// file system's clock tick at the same size, as a fuzzer does, is still told apart), else the
/// time it was last written and its size; "" when it cannot be read.
std::string fileStamp(const fs::path& p) {
  std::error_code ec;
  const auto size = fs::file_size(p, ec);
  if (ec) return {};
  if (size <= (1u << 20)) {
    std::ifstream in(p, std::ios::binary);
    std::string bytes(size, '\0');
    if (!in.read(bytes.data(), std::streamsize(size))) return {};
    return strCat(std::hash<std::string>()(bytes), ":", size, ";");
  }
  const auto t = fs::last_write_time(p, ec);
  return ec ? std::string() : strCat(t.time_since_epoch().count(), ":", size, ";");
}

std::string metaStamp(const std::string& dir, const std::vector<std::string>& levelPrefixes) {
  std::string stamp = fileStamp(fs::path(dir) / "Header");
  for (const std::string& prefix : levelPrefixes)
    stamp += fileStamp((fs::path(dir) / prefix).string() + "_H");
  return stamp;
}

/// The plotfile's metadata, parsed once while its Header and Cell_H files are unchanged: the
/// census, the memory plan, the coarse levels and every part of a step ask for them, and a large
/// step's box lists take seconds to parse. The last two plotfiles are kept.
std::shared_ptr<const PlotfileMeta> plotfileMeta(const std::string& dir) {
  static KeptResults<PlotfileMeta> kept(2);
  if (auto meta = kept.find(dir, [&](const PlotfileMeta& m) { return m.stamp == metaStamp(dir, m.pf.levelPrefixes); }))
    return meta;
  PlotfileMeta meta;
  meta.pf = readHeader(dir);
  const Plotfile& pf = meta.pf;
  meta.stamp = metaStamp(dir, pf.levelPrefixes);
  meta.width.assign(size_t(pf.finestLevel) + 1, 1);
  for (int l = pf.finestLevel - 1; l >= 0; --l)
    meta.width[size_t(l)] = meta.width[size_t(l) + 1] * pf.ratios[size_t(l)];
  for (int l = 0; l <= pf.finestLevel; ++l)
    meta.levels.push_back(readCellHeader(pf, l));
  return kept.keep(dir, std::move(meta));
}

/// Reads one FAB: its header line, then the requested components as float.
void readFab(const std::string& file, uint64_t offset, const IndexBox& valid, int nghost,
             const std::vector<int>& components, std::vector<std::vector<float>>& out,
             const std::vector<std::string>& names) {
  std::ifstream in(file, std::ios::binary);
  if (!in) fail(file, ": cannot open: ", std::strerror(errno), " (missing file of the plotfile?)");
  std::error_code ec;
  const uint64_t fileBytes = fs::file_size(file, ec);
  if (ec) fail(file, ": cannot read: ", ec.message());
  if (offset >= fileBytes) fail(file, ": offset ", offset, ": past the end of the file (", fileBytes, " bytes)");
  in.seekg(std::streamoff(offset));
  std::string header;
  if (!in || !std::getline(in, header)) fail(file, ": offset ", offset, ": no FAB record (truncated file?)");
  if (header.rfind("FAB ", 0) != 0) fail(file, ": offset ", offset, ": expected a 'FAB' record");
  // FAB ((8, (64 11 52 0 1 12 0 1023)),(8, (8 7 6 5 4 3 2 1)))((lo) (hi) (type)) ncomp
  std::string cleaned = header.substr(4);
  for (char& c : cleaned)
    if (c == '(' || c == ')' || c == ',') c = ' ';
  std::istringstream hs(cleaned);
  std::vector<int64_t> v;
  for (int64_t x; hs >> x;)
    v.push_back(x);
  if (v.size() < 2 || v[0] < 1 || v[0] > 64 || v.size() < size_t(2 + v[0] + 1))
    fail(file, ": offset ", offset, ": corrupt FAB header");
  const int64_t bits = v[1];
  const size_t orderAt = size_t(1 + v[0]);
  const int64_t bytes = v[orderAt];
  if (!((bits == 64 && bytes == 8) || (bits == 32 && bytes == 4)))
    fail(file, ": offset ", offset, ": unsupported real format (", bits, " bits)");
  if (v.size() < orderAt + 1 + size_t(bytes) + 10) fail(file, ": offset ", offset, ": corrupt FAB header");
  // The byte order lists byte positions: (8 7 ... 1), the highest first, is little-endian.
  const bool swap = io::needsSwap(v[orderAt + 1] != bytes);
  const size_t boxAt = orderAt + 1 + size_t(bytes);
  const IndexBox stored{vec3l(v[boxAt], v[boxAt + 1], v[boxAt + 2]), vec3l(v[boxAt + 3], v[boxAt + 4], v[boxAt + 5])};
  const int64_t ncomp = v[boxAt + 9];
  const vec3l g(nghost);
  if (!(stored.lo == valid.lo - g) || !(stored.hi == valid.hi + g))
    fail(file, ": offset ", offset, ": FAB box does not match the level's box grown by ", nghost, " ghost cells");
  if (ncomp != int64_t(names.size()))
    fail(file, ": offset ", offset, ": FAB holds ", ncomp, " components, expected ", names.size());
  // The stored box equals the valid one (within the lattice range) grown by at most 64 cells.
  const vec3l n = stored.hi - stored.lo + vec3l(1);
  const int64_t count = n.x * n.y * n.z;
  const std::streamoff dataStart = in.tellg();
  if (dataStart < 0) fail(file, ": offset ", offset, ": no FAB data");
  const std::string where = strCat(file, ": offset ", offset, ": FAB of ", n.x, "x", n.y, "x", n.z, " cells");
  uint64_t values = 0;
  if (!io::productWithin(uint64_t(count), uint64_t(ncomp), UINT64_MAX / 8, values)) fail(where, ": too many values");
  io::requireBytes(values, uint64_t(bytes), fileBytes - uint64_t(dataStart), where);
  std::vector<char> raw = io::allocate<char>(uint64_t(count * bytes), [&] { return where; });
  for (size_t k = 0; k < components.size(); ++k) {
    const int c = components[k];
    in.seekg(dataStart + std::streamoff(int64_t(c) * count * bytes));
    if (!in.read(raw.data(), std::streamsize(raw.size())))
      fail(file, ": offset ", offset, ": truncated data of component '", names[size_t(c)], "'");
    std::vector<float>& dst = out[k];
    for (int64_t z = nghost; z < n.z - nghost; ++z)
      for (int64_t y = nghost; y < n.y - nghost; ++y)
        for (int64_t x = nghost; x < n.x - nghost; ++x) {
          const auto* p = reinterpret_cast<const unsigned char*>(raw.data() + ((z * n.y + y) * n.x + x) * bytes);
          const double value = bytes == 8 ? io::loadScalar<double>(p, swap) : double(io::loadScalar<float>(p, swap));
          dst.push_back(io::toFloat32(value, [&] {
            return strCat(file, ": offset ", offset, ": component '", names[size_t(c)], "' at index (",
                          valid.lo.x + x - nghost, ",", valid.lo.y + y - nghost, ",", valid.lo.z + z - nghost, ")");
          }));
        }
  }
}

/// Bounds every box by the bytes of its FAB file before anything is allocated per cell: a FAB
/// holds at least 4 bytes (float32) per cell and component, the FABs of one file do not share
/// bytes, and a file shorter than what its boxes need is refused naming the file, the level and
/// the box. Each file is measured once.
void checkFabBytes(const Plotfile& pf, const std::vector<const LevelData*>& levels) {
  struct FileUse {
    uint64_t size = 0, needed = 0;
  };
  std::map<std::string, FileUse> files;
  const uint64_t ncomp = pf.names.size();
  for (size_t l = 0; l < levels.size(); ++l) {
    const LevelData& ld = *levels[l];
    for (size_t b = 0; b < ld.boxes.size(); ++b) {
      const std::string& file = ld.file(b);
      auto it = files.find(file);
      if (it == files.end()) {
        std::error_code ec;
        const uint64_t size = fs::file_size(file, ec);
        if (ec)
          fail(file, ": cannot open the data of level ", l, " box ", b, ": ", ec.message(),
               " (missing file of the plotfile?)");
        it = files.emplace(file, FileUse{size, 0}).first;
      }
      FileUse& use = it->second;
      const vec3l n = ld.boxes[b].hi - ld.boxes[b].lo + vec3l(1 + 2 * ld.nghost);
      uint64_t cells = 0, values = 0, bytes = 0;
      const std::string where = strCat(file, ": offset ", ld.offsets[b], ": FAB of level ", l, " box ", b, " (", n.x,
                                       "x", n.y, "x", n.z, " cells, ", ncomp, " components)");
      if (!io::cellCountWithin(n.x, n.y, n.z, UINT64_MAX / 4, cells) ||
          !io::productWithin(cells, ncomp, UINT64_MAX / 4, values))
        fail(where, ": too many values");
      bytes = values * 4;
      if (ld.offsets[b] >= use.size || bytes > use.size - ld.offsets[b])
        fail(where, ": needs at least ", bytes, " bytes of data (float32), but ",
             ld.offsets[b] >= use.size ? 0 : use.size - ld.offsets[b], " bytes follow the offset in a file of ",
             use.size, " bytes (truncated file or corrupt box?)");
      use.needed += bytes;
      if (use.needed > use.size)
        fail(where, ": the boxes stored in this file need at least ", use.needed,
             " bytes of data (float32), but the file holds ", use.size, " (truncated file or corrupt boxes?)");
    }
  }
}

} // namespace

bool isAmrexPlotfile(const std::string& path) {
  std::error_code ec;
  if (!fs::is_directory(path, ec)) return false;
  std::ifstream in(fs::path(path) / "Header");
  std::string first;
  return in && std::getline(in, first) && first.rfind("HyperCLaw", 0) == 0;
}

// From the metadata kept for the process: a large step's Header alone lists every box (tens of
// megabytes), and whatever asks for the fields asks for the boxes next.
std::vector<std::string> listAmrexFields(const std::string& path) { return plotfileMeta(path)->pf.names; }

std::optional<range1f> amrexFieldRange(const std::string& path, const std::string& field) {
  const std::shared_ptr<const PlotfileMeta> meta = plotfileMeta(path);
  const std::vector<std::string>& names = meta->pf.names;
  const auto it = std::find(names.begin(), names.end(), field);
  if (it == names.end()) return std::nullopt;
  const size_t component = size_t(it - names.begin());
  range1f all;
  for (const LevelData& ld : meta->levels) {
    if (ld.ranges.size() <= component) return std::nullopt; // no table: the data must be read
    if (!ld.ranges[component].empty()) all.extend(ld.ranges[component]);
  }
  return all;
}

std::vector<double> amrexLevelCells(const std::string& path) {
  const std::shared_ptr<const PlotfileMeta> meta = plotfileMeta(path);
  std::vector<double> cells(size_t(kMaxLevel) + 1, 0.0);
  for (int l = 0; l <= meta->pf.finestLevel; ++l) {
    const int level = std::clamp(io::log2Exact(meta->width[size_t(l)]), 0, kMaxLevel);
    for (const IndexBox& b : meta->levels[size_t(l)].boxes) {
      const vec3l n = b.hi - b.lo + vec3l(1);
      cells[size_t(level)] += double(n.x) * double(n.y) * double(n.z);
    }
  }
  return cells;
}

PatchSource amrexPatches(const std::string& path, const std::vector<std::string>& wanted, int finestLevel) {
  struct State {
    std::shared_ptr<const PlotfileMeta> meta;
    std::vector<int> components;
    std::vector<std::pair<int, size_t>> origin; // level and box of each patch
  };
  auto st = std::make_shared<State>();
  st->meta = plotfileMeta(path);
  const Plotfile& pf = st->meta->pf;
  const std::vector<int64_t>& width = st->meta->width;
  PatchSource source;
  source.input = path;
  source.fieldNames = wanted.empty() ? pf.names : wanted;
  for (size_t c : io::pickFields(path, pf.names, source.fieldNames))
    st->components.push_back(int(c));
  source.fieldUnits.assign(source.fieldNames.size(), "");

  // Every box of every level read on the finest lattice; a cell is a leaf unless a box of the
  // next finer level covers it.
  for (int l = 0; l <= pf.finestLevel; ++l)
    for (size_t bi = 0; bi < st->meta->levels[size_t(l)].boxes.size(); ++bi) {
      if (width[size_t(l)] < (int64_t(1) << finestLevel)) break; // finer than asked: its cover stays a leaf
      const IndexBox& b = st->meta->levels[size_t(l)].boxes[bi];
      const int64_t w = width[size_t(l)];
      source.patches.push_back({b.lo * w, b.hi - b.lo + vec3l(1), w});
      st->origin.push_back({l, bi});
    }
  {
    // The data of the levels read must be there (coarse levels alone: not the finer ones').
    std::vector<const LevelData*> read;
    for (int l = 0; l <= pf.finestLevel; ++l)
      if (width[size_t(l)] >= (int64_t(1) << finestLevel)) read.push_back(&st->meta->levels[size_t(l)]);
    checkFabBytes(pf, read);
  }
  source.name = [st, path](size_t i) {
    return strCat(path, ": level ", st->origin[i].first, " box ", st->origin[i].second);
  };
  source.read = [st](size_t i, std::vector<std::vector<float>>& values) {
    const auto [l, bi] = st->origin[i];
    const LevelData& ld = st->meta->levels[size_t(l)];
    values.assign(st->components.size(), {});
    readFab(ld.file(bi), ld.offsets[bi], ld.boxes[bi], ld.nghost, st->components, values, st->meta->pf.names);
  };
  source.concurrentReads = true;
  // Finest index space onto the physical domain.
  const IndexBox& fineDomain = pf.domains[size_t(pf.finestLevel)];
  const vec3d dx = pf.dx[size_t(pf.finestLevel)];
  source.world.scale = dx;
  source.world.origin = pf.probLo - vec3d(fineDomain.lo) * dx;
  source.simulation.time = pf.time;
  source.simulation.cycle = pf.cycle;
  return source;
}

CellSet readAmrex(const std::string& path, const std::vector<std::string>& wanted, const box3i& box, int finestLevel) {
  return io::readPatchCells(amrexPatches(path, wanted, finestLevel), box);
}

AmrexDomain amrexDomain(const std::string& path) {
  const Plotfile pf = readHeader(path);
  return {pf.probLo, pf.probHi};
}

Census amrexCensus(const std::string& path) {
  // The boxes are counted from the headers, but only as far as the data files can hold them
  // (amrexPatches bounds every box by its FAB file).
  const PatchSource source = amrexPatches(path);
  return io::censusOfPatches(source.patches, source.name);
}

} // namespace exa
