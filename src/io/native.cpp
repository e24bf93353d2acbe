#include "exabricks/io/native.h"
#include "exabricks/io/particles.h"

#include "exabricks/core/error.h"

#include "checked.h"
#include "patches.h"

#include <algorithm>
#include <atomic>
#include <bit>
#include <cerrno>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <memory>
#include <sstream>

#include <fcntl.h>
#include <signal.h>
#include <unistd.h>

static_assert(std::endian::native == std::endian::little,
              "the native format is little-endian; big-endian hosts are not supported");

namespace exa {
namespace fs = std::filesystem;

namespace {

std::string stemOf(const std::string& cellsPath) {
  const std::string ext = ".cells";
  if (cellsPath.size() <= ext.size() || cellsPath.compare(cellsPath.size() - ext.size(), ext.size(), ext) != 0)
    fail(cellsPath, ": a native dataset is named by its NAME.cells path");
  return cellsPath.substr(0, cellsPath.size() - ext.size());
}

} // namespace

std::string nativeParticlesPath(const std::string& cellsPath) { return stemOf(cellsPath) + ".particles"; }

namespace {

std::string scalarsPath(const std::string& stem, const std::string& field) {
  return field == "scalar" ? stem + ".scalars" : stem + "." + field + ".scalars";
}

} // namespace

std::vector<std::string> listNativeFields(const std::string& cellsPath) {
  const std::string stem = stemOf(cellsPath);
  const fs::path stemPath(stem);
  const fs::path dir = stemPath.has_parent_path() ? stemPath.parent_path() : fs::path(".");
  const std::string base = stemPath.filename().string();
  std::vector<std::string> fields;
  std::error_code ec;
  for (const auto& entry : fs::directory_iterator(dir, ec)) {
    const std::string name = entry.path().filename().string();
    if (name.size() < base.size() + 8 || name.compare(0, base.size(), base) != 0) continue;
    if (name.compare(name.size() - 8, 8, ".scalars") != 0) continue;
    const std::string middle = name.substr(base.size(), name.size() - 8 - base.size());
    if (middle.empty())
      fields.push_back("scalar");
    else if (middle[0] == '.' && middle.size() > 1 && middle.find('.', 1) == std::string::npos)
      fields.push_back(middle.substr(1));
  }
  std::sort(fields.begin(), fields.end());
  return fields;
}

namespace {

/// Records per piece of a streamed read: 1 MiB of cells, small beside any budget.
constexpr uint64_t kPieceRecords = uint64_t(1) << 16;

/// The number of records of NAME.cells, refused where the file is empty or ends in a partial record.
uint64_t checkedCellCount(const std::string& cellsPath) {
  const uint64_t bytes = fileSize(cellsPath);
  if (bytes == 0) fail(cellsPath, ": no cells (empty file)");
  if (bytes % sizeof(Cell) != 0)
    fail(cellsPath, ": truncated record ", bytes / sizeof(Cell), ": file size ", bytes,
         " is not a multiple of the 16-byte cell record");
  return bytes / sizeof(Cell);
}

/// Reads NAME.cells in pieces of kPieceRecords records, each validated, and hands them to `use`
/// with the index of their first record.
template <typename Use> void streamCells(const std::string& cellsPath, Use&& use) {
  const uint64_t count = checkedCellCount(cellsPath);
  std::FILE* f = std::fopen(cellsPath.c_str(), "rb");
  if (!f) fail(cellsPath, ": cannot open: ", std::strerror(errno));
  std::unique_ptr<std::FILE, int (*)(std::FILE*)> closer(f, std::fclose);
  std::vector<Cell> chunk(size_t(std::min<uint64_t>(count, kPieceRecords)));
  for (uint64_t at = 0; at < count; at += chunk.size()) {
    const size_t n = size_t(std::min<uint64_t>(chunk.size(), count - at));
    if (std::fread(chunk.data(), sizeof(Cell), n, f) != n)
      fail(cellsPath, ": read error (file changed while reading?)");
    for (size_t i = 0; i < n; ++i) {
      const std::string problem = cellProblem(chunk[i]);
      if (!problem.empty()) fail(cellsPath, ": record ", at + i, ": ", problem);
    }
    use(chunk.data(), n, at);
  }
}

/// A field's value of record `record` from `path`, refused where it is not finite (unless kept:
/// its cell becomes a hole).
void checkFinite(float v, bool keepNonFinite, const std::string& path, uint64_t record, const std::string& name) {
  if (!keepNonFinite && !std::isfinite(v))
    fail(path, ": record ", record, ": value ", v, " of field '", name, "' is not finite");
}

/// The values of a piece's kept records (`kept`: ascending indices into the piece that starts
/// at record `at`), read from `f` (the .scalars file at `path`) from the first kept to the last
/// and appended to `out`.
void appendKeptValues(std::FILE* f, const std::string& path, const std::string& name, uint64_t at,
                      const std::vector<uint32_t>& kept, bool keepNonFinite, std::vector<float>& scratch,
                      std::vector<float>& out) {
  const uint64_t first = at + kept.front();
  const size_t n = size_t(kept.back() - kept.front()) + 1;
  scratch.resize(n);
  if (std::fseek(f, long(first * sizeof(float)), SEEK_SET) != 0) fail(path, ": seek failed");
  if (std::fread(scratch.data(), sizeof(float), n, f) != n) fail(path, ": read error (file changed while reading?)");
  for (uint32_t i : kept) {
    const float v = scratch[i - kept.front()];
    checkFinite(v, keepNonFinite, path, at + i, name);
    out.push_back(v);
  }
}

/// The fields to read: those asked for, else every NAME[.FIELD].scalars beside the cells.
std::vector<std::string> fieldNamesToRead(const std::string& cellsPath, const std::string& stem,
                                          const std::vector<std::string>& wanted) {
  std::vector<std::string> names = wanted;
  if (names.empty()) names = listNativeFields(cellsPath);
  if (names.empty()) fail(cellsPath, ": no field files (expected ", stem, ".scalars or ", stem, ".FIELD.scalars)");
  return names;
}

/// The values file of a field, checked to exist and to hold one float32 per cell.
std::string checkedScalarsPath(const std::string& cellsPath, const std::string& stem, const std::string& name,
                               uint64_t cellCount) {
  const std::string path = scalarsPath(stem, name);
  std::error_code ec;
  if (!fs::exists(path, ec)) {
    std::string known;
    for (const std::string& f : listNativeFields(cellsPath))
      known += (known.empty() ? "" : ", ") + f;
    fail(cellsPath, ": unknown field '", name, "' (no file ", path, "; fields: ", known, ")");
  }
  const uint64_t bytes = fileSize(path);
  if (bytes % sizeof(float) != 0)
    fail(path, ": truncated record ", bytes / sizeof(float), ": file size ", bytes, " is not a multiple of 4");
  if (bytes / sizeof(float) != cellCount)
    fail(path, ": size mismatch: ", bytes / sizeof(float), " values for ", cellCount, " cells in ", cellsPath);
  return path;
}

using OpenFile = std::unique_ptr<std::FILE, int (*)(std::FILE*)>;

/// The values files of `fields`, checked against `count` cells and opened: their paths in `paths`.
std::vector<OpenFile> openFieldFiles(const std::string& cellsPath, const std::string& stem,
                                     const std::vector<std::string>& fields, uint64_t count,
                                     std::vector<std::string>& paths) {
  std::vector<OpenFile> files;
  for (const std::string& name : fields) {
    paths.push_back(checkedScalarsPath(cellsPath, stem, name, count));
    std::FILE* f = std::fopen(paths.back().c_str(), "rb");
    if (!f) fail(paths.back(), ": cannot open: ", std::strerror(errno));
    files.emplace_back(f, std::fclose);
  }
  return files;
}

} // namespace

Census nativeCensus(const std::string& cellsPath) {
  stemOf(cellsPath);
  CellCensus census;
  streamCells(cellsPath, [&](const Cell* cells, size_t n, uint64_t) { census.add(cells, n); });
  return census.finish();
}

void streamNative(const std::string& cellsPath, const std::vector<std::string>& fields, bool keepNonFinite,
                  const std::function<void(const Cell*, const std::vector<const float*>&, size_t)>& use) {
  const std::string stem = stemOf(cellsPath);
  const uint64_t count = checkedCellCount(cellsPath);
  std::vector<std::string> paths;
  const std::vector<OpenFile> files = openFieldFiles(cellsPath, stem, fields, count, paths);
  std::vector<std::vector<float>> values(fields.size());
  std::vector<const float*> at(fields.size());
  streamCells(cellsPath, [&](const Cell* cells, size_t n, uint64_t first) {
    for (size_t f = 0; f < fields.size(); ++f) {
      values[f].resize(n);
      if (std::fread(values[f].data(), sizeof(float), n, files[f].get()) != n)
        fail(paths[f], ": read error (file changed while reading?)");
      for (size_t i = 0; i < n; ++i)
        checkFinite(values[f][i], keepNonFinite, paths[f], first + i, fields[f]);
      at[f] = values[f].data();
    }
    use(cells, at, n);
  });
}

std::vector<Cell> readNativeCells(const std::string& cellsPath) {
  std::vector<Cell> cells(size_t(checkedCellCount(cellsPath)));
  readInto(cellsPath, cells.data(), cells.size() * sizeof(Cell));
  validateCellRecords(cells, cellsPath);
  return cells;
}

std::vector<std::string> nativeFieldsToRead(const std::string& cellsPath, const std::vector<std::string>& wanted,
                                            uint64_t cellCount) {
  const std::string stem = stemOf(cellsPath);
  std::vector<std::string> names = fieldNamesToRead(cellsPath, stem, wanted);
  for (const std::string& name : names)
    checkedScalarsPath(cellsPath, stem, name, cellCount);
  return names;
}

std::vector<float> readNativeField(const std::string& cellsPath, const std::string& name, uint64_t cellCount,
                                   bool keepNonFinite) {
  const std::string path = checkedScalarsPath(cellsPath, stemOf(cellsPath), name, cellCount);
  Field field{name, std::vector<float>(size_t(cellCount))};
  readInto(path, field.values.data(), cellCount * sizeof(float));
  if (!keepNonFinite) validateFieldValues(field, cellCount, path);
  return std::move(field.values);
}

CellSet readNative(const std::string& cellsPath, const std::vector<std::string>& wanted, const box3i& box,
                   bool keepNonFinite, size_t expectedCells) {
  const std::string stem = stemOf(cellsPath);
  if (!box.empty()) {
    // Only the cells overlapping the box are kept, with their values, read piece by piece: memory
    // for those alone (reserved for `expectedCells` where the caller knows about how many).
    const uint64_t count = checkedCellCount(cellsPath);
    const std::vector<std::string> names = fieldNamesToRead(cellsPath, stem, wanted);
    std::vector<std::string> paths;
    const std::vector<OpenFile> files = openFieldFiles(cellsPath, stem, names, count, paths);
    CellSet set;
    for (const std::string& name : names) {
      set.fields.push_back(Field{name, {}});
      set.fields.back().values.reserve(expectedCells);
    }
    set.cells.reserve(expectedCells);
    std::vector<uint32_t> kept;
    std::vector<float> scratch;
    streamCells(cellsPath, [&](const Cell* cells, size_t n, uint64_t at) {
      kept.clear();
      for (size_t i = 0; i < n; ++i)
        if (cellOverlaps(cells[i], box)) {
          kept.push_back(uint32_t(i));
          set.cells.push_back(cells[i]);
        }
      if (kept.empty()) return;
      for (size_t f = 0; f < files.size(); ++f)
        appendKeptValues(files[f].get(), paths[f], set.fields[f].name, at, kept, keepNonFinite, scratch,
                         set.fields[f].values);
    });
    return set;
  }
  CellSet set;
  set.cells = readNativeCells(cellsPath);
  for (const std::string& name : nativeFieldsToRead(cellsPath, wanted, set.cells.size()))
    set.fields.push_back(Field{name, readNativeField(cellsPath, name, set.cells.size(), keepNonFinite)});
  return set;
}

NativeWriter::NativeWriter(const std::string& cellsPath, const std::vector<std::string>& fieldNames)
    : cellsPath_(cellsPath), fieldNames_(fieldNames) {
  const std::string stem = stemOf(cellsPath);
  if (fieldNames.empty()) fail(cellsPath, ": nothing to write: no fields");
  for (const std::string& name : fieldNames)
    if (name.empty() || name.find_first_of("./\\") != std::string::npos)
      fail(cellsPath, ": field name '", name, "' cannot be stored in a file name");
  // Every file to a temporary first; the dataset appears only when all are written.
  files_.begin(cellsPath);
  for (const std::string& name : fieldNames)
    files_.begin(scalarsPath(stem, name));
}

void NativeWriter::append(const CellSet& piece) {
  EXA_CHECK(piece.fields.size() == fieldNames_.size(), "one value array per field");
  files_.append(0, piece.cells.data(), piece.cells.size() * sizeof(Cell));
  for (size_t f = 0; f < piece.fields.size(); ++f) {
    EXA_CHECK(piece.fields[f].name == fieldNames_[f] && piece.fields[f].values.size() == piece.cells.size());
    files_.append(1 + f, piece.fields[f].values.data(), piece.fields[f].values.size() * sizeof(float));
  }
  cells_ += piece.cells.size();
}

void NativeWriter::addFile(const std::string& path, const std::vector<char>& bytes) {
  files_.write(path, bytes.data(), bytes.size());
  if (path == nativeParticlesPath(cellsPath_)) wroteParticles_ = true;
}

void NativeWriter::finish() {
  files_.commit();
  // The particles of an earlier dataset of this name are not this one's.
  std::error_code ec;
  if (!wroteParticles_) std::filesystem::remove(nativeParticlesPath(cellsPath_), ec);
}

void writeNative(const CellSet& set, const std::string& cellsPath) {
  std::vector<std::string> names;
  for (const Field& f : set.fields)
    names.push_back(f.name);
  NativeWriter writer(cellsPath, names);
  writer.append(set);
  writer.finish();
}

namespace {

/// One line of a .grids fixture: the box's corner, size and level, and one value or eight
/// corner values.
struct GridsLine {
  int64_t ints[7] = {};
  double v[8] = {};
  int nv = 0;
};

GridsLine parseGridsLine(const std::string& path, size_t lineNo, const std::vector<std::string>& tokens) {
  if (tokens.size() != 8 && tokens.size() != 15)
    fail(path, ": line ", lineNo, ": expected 'x y z nx ny nz level value' or eight corner", " values, got ",
         tokens.size(), " numbers");
  GridsLine g;
  for (int i = 0; i < 7; ++i) {
    char* end = nullptr;
    errno = 0;
    const long long v = std::strtoll(tokens[i].c_str(), &end, 10);
    if (*end != 0 || errno == ERANGE || v < INT32_MIN || v > INT32_MAX)
      fail(path, ": line ", lineNo, ": '", tokens[i], "' is not a 32-bit integer");
    g.ints[i] = v;
  }
  g.nv = int(tokens.size()) - 7;
  for (int i = 0; i < g.nv; ++i) {
    char* end = nullptr;
    g.v[i] = std::strtod(tokens[7 + i].c_str(), &end);
    if (*end != 0) fail(path, ": line ", lineNo, ": '", tokens[7 + i], "' is not a number");
    const bool kept = io::tKeepNonFinite && !std::isfinite(g.v[i]); // its cells become holes
    if (!kept && (!std::isfinite(g.v[i]) || std::fabs(g.v[i]) > 3.4e38))
      fail(path, ": line ", lineNo, ": value ", tokens[7 + i], " is not a finite float");
  }
  return g;
}

/// Checks the line's box (its cells, the lattice range, the fixture's cell limit) and makes room
/// for its cells, growing geometrically; running out of memory names the line.
void reserveBox(const std::string& path, size_t lineNo, const GridsLine& g, CellSet& set, Field& field) {
  const vec3l n(g.ints[3], g.ints[4], g.ints[5]);
  if (n.x < 1 || n.y < 1 || n.z < 1)
    fail(path, ": line ", lineNo, ": box size ", n.x, "x", n.y, "x", n.z, " must be positive");
  const int64_t level = g.ints[6];
  const Cell probe{vec3i(int32_t(g.ints[0]), int32_t(g.ints[1]), int32_t(g.ints[2])), int32_t(level)};
  if (const std::string p = cellProblem(probe); !p.empty()) fail(path, ": line ", lineNo, ": ", p);
  const int64_t w = int64_t(1) << level;
  for (int a = 0; a < 3; ++a)
    if (g.ints[a] + n[a] * w > kLatticeLimit)
      fail(path, ": line ", lineNo, ": box reaches outside the supported lattice range");
  // A fixture line expands to its cells: bound the total before reserving memory for them.
  if (double(n.x) * double(n.y) * double(n.z) + double(set.cells.size()) > double(kMaxGridsCells))
    fail(path, ": line ", lineNo, ": box of ", n.x, "x", n.y, "x", n.z, " cells: a .grids fixture describes at most ",
         kMaxGridsCells, " cells (store larger data as NAME.cells)");
  const uint64_t add = uint64_t(n.x * n.y * n.z), need = set.cells.size() + add;
  auto where = [&] { return strCat(path, ": line ", lineNo, ": box of ", n.x, "x", n.y, "x", n.z, " cells"); };
  if (need > set.cells.capacity()) {
    const uint64_t room = std::max<uint64_t>(need, std::min<uint64_t>(2 * set.cells.capacity(), kMaxGridsCells));
    const uint64_t grow = room - set.cells.size();
    io::reserveMore(set.cells, grow, where);
    io::reserveMore(field.values, grow, where);
  }
}

/// The line's cells and their values (trilinear between the corner values when it has eight).
void appendBox(const GridsLine& g, CellSet& set, Field& field) {
  const vec3l n(g.ints[3], g.ints[4], g.ints[5]);
  const int64_t level = g.ints[6];
  const int64_t w = int64_t(1) << level;
  for (int64_t k = 0; k < n.z; ++k)
    for (int64_t j = 0; j < n.y; ++j)
      for (int64_t i = 0; i < n.x; ++i) {
        set.cells.push_back(Cell{
            vec3i(int32_t(g.ints[0] + i * w), int32_t(g.ints[1] + j * w), int32_t(g.ints[2] + k * w)), int32_t(level)});
        double value = g.v[0];
        if (g.nv == 8) {
          const double u = (i + 0.5) / n.x, s = (j + 0.5) / n.y, t = (k + 0.5) / n.z;
          auto lerp = [](double a, double b, double f) { return a + (b - a) * f; };
          value = lerp(lerp(lerp(g.v[0], g.v[1], u), lerp(g.v[2], g.v[3], u), s),
                       lerp(lerp(g.v[4], g.v[5], u), lerp(g.v[6], g.v[7], u), s), t);
        }
        field.values.push_back(float(value));
      }
}

} // namespace

CellSet readGrids(const std::string& path) {
  std::ifstream in(path);
  if (!in) fail(path, ": cannot open: ", std::strerror(errno));
  CellSet set;
  Field field{"scalar", {}};
  std::string line;
  size_t lineNo = 0;
  while (std::getline(in, line)) {
    ++lineNo;
    const size_t hash = line.find('#');
    if (hash != std::string::npos) line.resize(hash);
    std::istringstream ls(line);
    std::vector<std::string> tokens;
    for (std::string t; ls >> t;)
      tokens.push_back(t);
    if (tokens.empty()) continue;
    const GridsLine g = parseGridsLine(path, lineNo, tokens);
    reserveBox(path, lineNo, g, set, field);
    appendBox(g, set, field);
  }
  if (set.cells.empty()) fail(path, ": no cells (empty input)");
  set.fields.push_back(std::move(field));
  return set;
}

} // namespace exa
