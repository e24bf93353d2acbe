#include "exabricks/io/vtk_amr.h"

#include "patches.h"
#include "vtk_xml.h"

#include "exabricks/core/error.h"
#include "exabricks/core/log.h"

#include "checked.h"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>

namespace exa {
namespace fs = std::filesystem;

namespace {

using namespace io::vtk;

struct Piece {
  std::string path;
  vec3l cells{0};
  std::map<std::string, std::vector<double>> arrays; ///< only when read
  std::vector<std::string> names;                    ///< scalar cell arrays in file order
};

/// Where the piece's XML ends and its appended data (if any) lies.
struct Appended {
  size_t xmlEnd = 0, at = std::string::npos, end = 0;
  bool base64 = false;
};

Appended findAppended(const std::string& path, const std::string& data) {
  Appended a{data.size(), std::string::npos, data.size(), false};
  const size_t app = data.find("<AppendedData");
  if (app == std::string::npos) return a;
  a.xmlEnd = app;
  const size_t close = data.find('>', app);
  const size_t underscore = close == std::string::npos ? close : data.find('_', close);
  if (underscore == std::string::npos) fail(path, ": AppendedData without its '_' marker (truncated file?)");
  const std::string tag = data.substr(app, close - app);
  // VTK's XML writers encode appended data in base64 unless told to write it raw.
  a.base64 = tag.find("encoding=\"base64\"") != std::string::npos;
  a.at = underscore + 1;
  if (a.base64) a.end = std::min(data.size(), data.find("</AppendedData>", a.at));
  return a;
}

/// The cells of a <Piece>'s Extent.
vec3l pieceCells(const std::string& path, const Tag& t) {
  const auto e = numbers(path, t.attr("Extent"), 6, "Piece Extent");
  int64_t ext[6];
  for (int k = 0; k < 6; ++k)
    ext[k] =
        io::checkedInteger(e[size_t(k)], -kLatticeLimit, kLatticeLimit, [&] { return strCat(path, ": Piece Extent"); });
  const vec3l cells(ext[1] - ext[0], ext[3] - ext[2], ext[5] - ext[4]);
  if (cells.x < 0 || cells.y < 0 || cells.z < 0) fail(path, ": Piece Extent is inverted");
  if (cells.x == 0 || cells.y == 0 || cells.z == 0)
    fail(path, ": Piece Extent is flat (2-D data); only 3-D AMR data can be read");
  return cells;
}

/// The bytes of a binary or appended <DataArray>, decoded and inflated.
std::string arrayBytes(const std::string& path, const std::string& what, const Tag& t, const std::string& data,
                       const Appended& appended, const Encoding& enc, uint64_t expected) {
  if (t.attr("format") == "binary") {
    Base64Source src(path, what, t.text);
    return readBlock(path, what, src, enc, expected);
  }
  if (appended.at == std::string::npos) fail(path, ": ", what, ": appended array but no <AppendedData>");
  const std::string off = t.attr("offset");
  char* endp = nullptr;
  const unsigned long long o = std::strtoull(off.c_str(), &endp, 10);
  if (off.empty() || *endp) fail(path, ": ", what, ": bad offset '", off, "'");
  if (appended.base64) {
    if (o > appended.end - appended.at) fail(path, ": ", what, ": offset ", o, " lies beyond the appended data");
    const std::string text = data.substr(appended.at + size_t(o), appended.end - appended.at - size_t(o));
    Base64Source src(path, what, text);
    return readBlock(path, what, src, enc, expected);
  }
  RawSource src(path, what, data, appended.at + size_t(o));
  return readBlock(path, what, src, enc, expected);
}

/// The values of a scalar cell <DataArray> of a piece of `cells`.
std::vector<double> arrayValues(const std::string& path, const std::string& name, const Tag& t, const vec3l& cells,
                                const std::string& data, const Appended& appended, const Encoding& enc) {
  const std::string what = "array '" + name + "'";
  const std::string type = t.attr("type");
  if (typeSize(type) == 0) fail(path, ": ", what, ": unsupported type '", type, "'");
  uint64_t count = 0;
  if (!io::cellCountWithin(cells.x, cells.y, cells.z, uint64_t(1) << 40, count))
    fail(path, ": Piece Extent of ", cells.x, "x", cells.y, "x", cells.z, " cells is too large");
  std::vector<double> values;
  const std::string format = t.attr("format");
  if (format == "ascii") {
    std::istringstream in(t.text);
    for (double d; in >> d;)
      values.push_back(d);
    if (!in.eof()) fail(path, ": ", what, ": malformed ascii value");
  } else if (format == "binary" || format == "appended") {
    const std::string bytes = arrayBytes(path, what, t, data, appended, enc, count * typeSize(type));
    const size_t ts = typeSize(type);
    io::reserveMore(values, bytes.size() / ts, [&] { return strCat(path, ": ", what); });
    for (size_t i = 0; i + ts <= bytes.size(); i += ts)
      values.push_back(toDouble(reinterpret_cast<const unsigned char*>(bytes.data() + i), type, enc.bigEndian));
  } else {
    fail(path, ": ", what, ": unknown format '", format, "'");
  }
  if (values.size() != count)
    fail(path, ": ", what, ": ", values.size(), " values for ", count, " cells (truncated or wrong extent?)");
  return values;
}

/// Reads a .vti piece: its extent and the wanted scalar cell arrays (none when `wanted` is null).
Piece readPiece(const std::string& path, const std::vector<std::string>* wanted) {
  Piece piece;
  piece.path = path;
  const std::string data = readFile(path, "piece");
  const Appended appended = findAppended(path, data);
  const std::vector<Tag> tags = scanTags(path, data, appended.xmlEnd);
  const auto vtkFile = std::find_if(tags.begin(), tags.end(), [](const Tag& t) { return t.name == "VTKFile"; });
  if (vtkFile == tags.end()) fail(path, ": not a VTK XML file (no <VTKFile>)");
  if (vtkFile->attr("type") != "ImageData")
    fail(path, ": piece of type '", vtkFile->attr("type"), "', expected ImageData");
  const Encoding enc = encodingOf(path, *vtkFile);
  bool inCells = false, sawPiece = false;
  for (const Tag& t : tags) {
    if (t.name == "Piece") {
      if (sawPiece) fail(path, ": more than one <Piece> (one is expected per AMR box)");
      sawPiece = true;
      piece.cells = pieceCells(path, t);
    } else if (t.name == "CellData") {
      inCells = true;
    } else if (t.name == "/CellData") {
      inCells = false;
    } else if (t.name == "DataArray" && inCells) {
      const std::string name = t.attr("Name");
      const std::string comps = t.attr("NumberOfComponents", "1");
      if (name.empty() || name == "vtkGhostType" || comps != "1") continue;
      piece.names.push_back(name);
      if (!wanted || std::find(wanted->begin(), wanted->end(), name) == wanted->end()) continue;
      piece.arrays[name] = arrayValues(path, name, t, piece.cells, data, appended, enc);
    }
  }
  if (!sawPiece) fail(path, ": no <Piece> (truncated file?)");
  return piece;
}

struct DataSetRef {
  int level = 0;
  size_t index = 0;
  vec3l lo, hi; ///< amr_box, inclusive cell indices of the level
  std::string file;
};

struct Hierarchy {
  vec3d origin{0.0};
  std::vector<vec3d> spacing; ///< per level
  std::vector<DataSetRef> sets;
};

Hierarchy readHierarchy(const std::string& path) {
  const std::string xml = readFile(path, "file");
  const std::vector<Tag> tags = scanTags(path, xml, xml.size());
  Hierarchy h;
  bool sawRoot = false, sawAmr = false;
  int level = -1;
  const fs::path dir = fs::path(path).parent_path();
  for (const Tag& t : tags) {
    if (t.name == "VTKFile") {
      if (t.attr("type") != "vtkOverlappingAMR")
        fail(path, ": VTKFile type '", t.attr("type"), "', expected vtkOverlappingAMR");
      sawRoot = true;
    } else if (t.name == "vtkOverlappingAMR") {
      sawAmr = true;
      const auto o = numbers(path, t.attr("origin", "0 0 0"), 3, "origin");
      h.origin = vec3d(o[0], o[1], o[2]);
      const std::string gd = t.attr("grid_description", "XYZ");
      if (gd != "XYZ") fail(path, ": grid_description '", gd, "': only 3-D (XYZ) AMR data can be read");
    } else if (t.name == "Block") {
      const auto l = numbers(path, t.attr("level"), 1, "Block level");
      if (!(l[0] >= 0 && l[0] <= 30) || l[0] != std::floor(l[0]))
        fail(path, ": Block level ", l[0], " is out of range");
      level = int(l[0]);
      const auto s = numbers(path, t.attr("spacing"), 3, strCat("Block ", level, " spacing"));
      if (!(s[0] > 0 && s[1] > 0 && s[2] > 0)) fail(path, ": Block ", level, ": spacing must be positive");
      if (h.spacing.size() <= size_t(level)) h.spacing.resize(size_t(level) + 1, vec3d(0.0));
      h.spacing[size_t(level)] = vec3d(s[0], s[1], s[2]);
    } else if (t.name == "DataSet") {
      if (level < 0) fail(path, ": <DataSet> outside a <Block>");
      DataSetRef d;
      d.level = level;
      const double index = numbers(path, t.attr("index", "0"), 1, "DataSet index")[0];
      if (!(index >= 0 && index < 1e12)) fail(path, ": level ", level, ": DataSet index ", index, " out of range");
      d.index = size_t(index);
      const auto b = numbers(path, t.attr("amr_box"), 6, strCat("level ", level, " DataSet ", d.index, " amr_box"));
      for (int a = 0; a < 3; ++a) {
        auto where = [&] { return strCat(path, ": level ", level, " DataSet ", d.index, ": amr_box"); };
        d.lo[a] = io::checkedInteger(b[size_t(2 * a)], -kLatticeLimit, kLatticeLimit, where);
        d.hi[a] = io::checkedInteger(b[size_t(2 * a + 1)], -kLatticeLimit, kLatticeLimit, where);
        if (d.hi[a] < d.lo[a]) fail(path, ": level ", level, " DataSet ", d.index, ": empty amr_box");
      }
      const std::string file = t.attr("file");
      if (file.empty()) continue; // a box without data on this rank
      d.file = (dir / file).string();
      h.sets.push_back(d);
    }
  }
  if (!sawRoot || !sawAmr) fail(path, ": not a vtkOverlappingAMR file (missing <VTKFile> or <vtkOverlappingAMR>)");
  if (h.sets.empty()) fail(path, ": no DataSet with a file");
  return h;
}

/// The finest level that has datasets.
int finestLevel(const Hierarchy& h) {
  int finest = 0;
  for (const DataSetRef& d : h.sets)
    finest = std::max(finest, d.level);
  return finest;
}

/// Every dataset's box on the finest level's lattice, its width from the levels' spacings.
std::vector<io::Patch> placeDataSets(const std::string& path, const Hierarchy& h) {
  const int finest = finestLevel(h);
  std::vector<io::Patch> patches;
  for (const DataSetRef& d : h.sets) {
    const vec3d s = h.spacing.size() > size_t(d.level) ? h.spacing[size_t(d.level)] : vec3d(0.0);
    if (!(s.x > 0)) fail(path, ": level ", d.level, " has datasets but no Block spacing");
    int64_t width = 0;
    for (int a = 0; a < 3; ++a) {
      const double r = s[a] / h.spacing[size_t(finest)][a];
      const double w = std::round(r);
      if (!(w >= 1 && w <= double(int64_t(1) << kMaxLevel)) || std::abs(r - w) > 1e-6 * w ||
          io::log2Exact(int64_t(w)) < 0)
        fail(path, ": level ", d.level, ": spacing is ", r, " times the finest level's, not a power of two");
      if (a > 0 && int64_t(w) != width) fail(path, ": level ", d.level, ": refined differently along the axes");
      width = int64_t(w);
    }
    patches.push_back({d.lo * width, d.hi - d.lo + vec3l(1), width});
  }
  return patches;
}

/// Every box is bounded by the bytes of its piece before per-cell memory is reserved for it:
/// a cell takes at least one byte, or 1/kMaxInflate of a byte compressed. A box whose piece is
/// missing can only be fully covered by finer boxes.
template <typename Name>
void checkPieceSizes(const Hierarchy& h, const std::vector<io::Patch>& patches, const Name& name) {
  std::vector<uint8_t> backed(patches.size(), 0);
  for (size_t i = 0; i < patches.size(); ++i) {
    io::checkPatchCells(patches[i].cells, name(i));
    std::error_code ec;
    const auto bytes = fs::file_size(h.sets[i].file, ec);
    if (ec) continue;
    backed[i] = 1;
    if (uint64_t(patches[i].cellCount()) / io::kMaxInflate > bytes)
      fail(h.sets[i].file, ": the piece of ", name(i), " (", patches[i].cells.x, "x", patches[i].cells.y, "x",
           patches[i].cells.z, " cells) holds only ", bytes, " bytes, too few for its cells");
  }
  io::checkUnbackedPatches(patches, backed, name);
}

/// The piece's arrays `names`, converted to float.
std::vector<std::vector<float>> pieceValues(const Piece& piece, const std::vector<std::string>& names) {
  std::vector<std::vector<float>> values;
  for (const std::string& n : names) {
    const auto it = piece.arrays.find(n);
    if (it == piece.arrays.end()) fail(piece.path, ": no cell array '", n, "'");
    std::vector<float> v;
    v.reserve(it->second.size());
    for (size_t c = 0; c < it->second.size(); ++c)
      v.push_back(io::toFloat32(it->second[c], [&] { return strCat(piece.path, ": array '", n, "' value ", c); }));
    values.push_back(std::move(v));
  }
  return values;
}

std::string firstBytes(const std::string& path, size_t n) {
  std::ifstream in(path, std::ios::binary);
  std::string s(n, '\0');
  in.read(s.data(), std::streamsize(n));
  s.resize(size_t(in.gcount()));
  return s;
}

} // namespace

bool isVtkAmrFile(const std::string& path) {
  std::error_code ec;
  if (fs::is_directory(path, ec)) return false;
  const std::string head = firstBytes(path, 2048);
  return head.find("<VTKFile") != std::string::npos && head.find("vtkOverlappingAMR") != std::string::npos;
}

std::vector<std::string> listVtkAmrFields(const std::string& path) {
  const Hierarchy h = readHierarchy(path);
  return readPiece(h.sets.front().file, nullptr).names;
}

std::vector<double> vtkAmrLevelCells(const std::string& path) {
  const Hierarchy h = readHierarchy(path);
  return io::levelCellsOfPatches(placeDataSets(path, h));
}

Census vtkAmrCensus(const std::string& path) {
  const Hierarchy h = readHierarchy(path);
  const std::vector<io::Patch> patches = placeDataSets(path, h);
  auto name = [&](size_t i) { return strCat(path, ": level ", h.sets[i].level, " DataSet ", h.sets[i].index); };
  checkPieceSizes(h, patches, name); // counted from the boxes, but only as far as the pieces hold them
  return io::censusOfPatches(patches, name);
}

PatchSource vtkAmrPatches(const std::string& path, const std::vector<std::string>& wanted, int coarsest) {
  struct State {
    Hierarchy h;
    std::vector<std::string> names;
  };
  auto st = std::make_shared<State>();
  st->h = readHierarchy(path);
  Hierarchy& h = st->h;
  const std::vector<std::string> available = readPiece(h.sets.front().file, nullptr).names;
  for (size_t k : io::pickFields(path, available, wanted))
    st->names.push_back(available[k]);

  PatchSource source;
  source.input = path;
  source.fieldNames = st->names;
  source.fieldUnits.assign(source.fieldNames.size(), "");
  source.patches = placeDataSets(path, h);
  const vec3d finestSpacing = h.spacing[size_t(finestLevel(h))]; // the lattice, whichever boxes are read
  // Boxes with cells narrower than 2^coarsest finest cells are left out: the coarser cells under
  // them are leaves, with their own stored values.
  const std::vector<size_t> kept = io::coarsePatches(source.patches, coarsest);
  io::keepOnly(h.sets, kept);
  io::keepOnly(source.patches, kept);
  source.name = [st, path](size_t i) {
    return strCat(path, ": level ", st->h.sets[i].level, " DataSet ", st->h.sets[i].index);
  };
  checkPieceSizes(h, source.patches, source.name);
  source.read = [st, name = source.name, patches = source.patches](size_t i, std::vector<std::vector<float>>& values) {
    const std::string& file = st->h.sets[i].file;
    std::error_code ec;
    if (!fs::exists(file, ec)) fail(file, ": missing piece named by ", name(i));
    const Piece piece = readPiece(file, &st->names);
    if (!(piece.cells == patches[i].cells))
      fail(piece.path, ": Piece Extent holds ", piece.cells.x, "x", piece.cells.y, "x", piece.cells.z,
           " cells, but the amr_box of ", name(i), " holds ", patches[i].cells.x, "x", patches[i].cells.y, "x",
           patches[i].cells.z);
    values = pieceValues(piece, st->names);
  };
  source.concurrentReads = true;
  source.world.origin = h.origin;
  source.world.scale = finestSpacing;
  return source;
}

CellSet readVtkAmr(const std::string& path, const std::vector<std::string>& wanted, int coarsest, const box3i& box) {
  return io::readPatchCells(vtkAmrPatches(path, wanted, coarsest), box);
}

} // namespace exa
