#include "exabricks/io/native.h"

#include "exabricks/core/error.h"

#include "checked.h"

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

std::string scalarsPath(const std::string& stem, const std::string& field) {
  return field == "scalar" ? stem + ".scalars" : stem + "." + field + ".scalars";
}

} // namespace

uint64_t fileSize(const std::string& path) {
  std::error_code ec;
  if (fs::is_directory(path, ec)) fail(path, ": is a directory, not a file");
  const auto size = fs::file_size(path, ec);
  if (ec) fail(path, ": cannot open: ", ec.message());
  return size;
}

void readInto(const std::string& path, void* data, uint64_t size) {
  std::FILE* f = std::fopen(path.c_str(), "rb");
  if (!f) fail(path, ": cannot open: ", std::strerror(errno));
  const size_t n = std::fread(data, 1, size, f);
  std::fclose(f);
  if (n != size) fail(path, ": read error (file changed while reading?)");
}

std::vector<char> readFile(const std::string& path) {
  std::vector<char> data(fileSize(path));
  readInto(path, data.data(), data.size());
  return data;
}

namespace {

/// Temporary files not yet published, for removePendingTemporaries() (which a signal handler
/// may call): fixed slots, each claimed and released with an atomic flag.
constexpr int kPendingSlots = 64;
struct PendingSlot {
  std::atomic<bool> used{false};
  char path[4096];
};
PendingSlot gPending[kPendingSlots];

int claimPending(const std::string& path) {
  if (path.size() >= sizeof(PendingSlot::path)) return -1;
  for (int i = 0; i < kPendingSlots; ++i) {
    bool expected = false;
    if (!gPending[i].used.compare_exchange_strong(expected, true)) continue;
    std::memcpy(gPending[i].path, path.c_str(), path.size() + 1);
    return i;
  }
  return -1;
}

void releasePending(int slot) {
  if (slot >= 0) gPending[slot].used.store(false);
}

/// Commits renaming their files into place right now, and an interrupt that arrived meanwhile
/// (deferInterrupt), raised again when the last of them ends.
std::atomic<int> gPublishing{0};
std::atomic<int> gDeferredSignal{0};

/// Marks a commit's renames; the interrupt deferred during them is raised again at the end.
struct Publishing {
  Publishing() { gPublishing.fetch_add(1); }
  ~Publishing() {
    if (gPublishing.fetch_sub(1) == 1)
      if (const int signal = gDeferredSignal.exchange(0)) std::raise(signal);
  }
  Publishing(const Publishing&) = delete;
  Publishing& operator=(const Publishing&) = delete;
};

/// Where a write to `path` goes: symlinks are followed, so the link stays and its target changes.
std::string resolveTarget(const std::string& path) {
  std::error_code ec;
  fs::path p(path);
  for (int hops = 0; hops < 40 && fs::is_symlink(fs::symlink_status(p, ec)); ++hops) {
    const fs::path target = fs::read_symlink(p, ec);
    if (ec) break;
    p = target.is_absolute() ? target : p.parent_path() / target;
  }
  return p.string();
}

/// Flushes and closes a file being written; false (errno set) when any of it failed.
bool closeWritten(std::FILE* f, bool sync) {
  // A file renamed into place is on disk first: a crash leaves the old file or the new one.
  const bool flushed = std::fflush(f) == 0 && (!sync || ::fsync(::fileno(f)) == 0);
  const int err = errno;
  const bool closed = std::fclose(f) == 0;
  if (!closed && flushed) return false;
  errno = err;
  return flushed;
}

/// Flushes a directory's entries (a rename into it) to disk; best effort.
void syncDirectory(const std::string& target) {
  const fs::path parent = fs::path(target).parent_path();
  const int fd = ::open(parent.empty() ? "." : parent.c_str(), O_RDONLY | O_DIRECTORY);
  if (fd < 0) return;
  ::fsync(fd);
  ::close(fd);
}

} // namespace

std::string temporaryPath(const std::string& target, size_t index) {
  return target + ".tmp" + std::to_string(::getpid()) + "." + std::to_string(index);
}

void removeStaleTemporaries(const std::string& target) {
  const fs::path t(target);
  const fs::path dir = t.has_parent_path() ? t.parent_path() : fs::path(".");
  const std::string prefix = t.filename().string() + ".tmp";
  std::error_code ec;
  for (fs::directory_iterator it(dir, ec), end; !ec && it != end; it.increment(ec)) {
    const std::string name = it->path().filename().string();
    if (name.size() <= prefix.size() || name.compare(0, prefix.size(), prefix) != 0) continue;
    // NAME.tmpPID.INDEX (or NAME.tmpPID): only when process PID no longer runs.
    const std::string rest = name.substr(prefix.size());
    const size_t dot = rest.find('.');
    const std::string pid = rest.substr(0, dot), index = dot == std::string::npos ? "1" : rest.substr(dot + 1);
    auto digits = [](const std::string& x) {
      return !x.empty() && x.size() < 10 && x.find_first_not_of("0123456789") == std::string::npos;
    };
    if (!digits(pid) || !digits(index)) continue;
    const long id = std::stol(pid);
    if (id <= 0 || id == long(::getpid()) || ::kill(pid_t(id), 0) == 0 || errno != ESRCH) continue;
    std::error_code rec;
    fs::remove(it->path(), rec);
  }
}

PendingTemporary::PendingTemporary(const std::string& path) : slot_(claimPending(path)) {}
PendingTemporary::~PendingTemporary() { releasePending(slot_); }

bool deferInterrupt(int signal) {
  // The signal is recorded before the count is read: a commit that ends after this read raises
  // it, and one that ended before leaves the count at zero, so the caller goes on.
  gDeferredSignal.store(signal);
  return gPublishing.load() > 0;
}

void removePendingTemporaries() {
  for (PendingSlot& s : gPending)
    if (s.used.load()) ::unlink(s.path);
}

size_t AtomicFiles::begin(const std::string& path) {
  Pending p;
  p.path = path;
  p.target = resolveTarget(path);
  std::error_code ec;
  const fs::file_status st = fs::status(p.target, ec);
  if (!ec && fs::exists(st) && !fs::is_regular_file(st)) {
    // A device, a FIFO or another special file: written through, never replaced.
    if (fs::is_directory(st)) fail(path, ": cannot write: is a directory");
    p.stream = std::fopen(p.target.c_str(), "wb");
    if (!p.stream) fail(path, ": cannot write: ", std::strerror(errno));
    pending_.push_back(p);
    return pending_.size() - 1;
  }
  removeStaleTemporaries(p.target);
  p.temporary = temporaryPath(p.target, pending_.size());
  p.slot = claimPending(p.temporary);
  p.stream = std::fopen(p.temporary.c_str(), "wb");
  if (!p.stream) {
    const std::string why = std::strerror(errno);
    releasePending(p.slot);
    discard();
    fail(path, ": cannot write: ", why);
  }
  pending_.push_back(p);
  return pending_.size() - 1;
}

void AtomicFiles::append(size_t file, const void* data, size_t size) {
  Pending& p = pending_.at(file);
  EXA_CHECK(p.stream != nullptr, "appending to a finished file");
  if (size > 0 && std::fwrite(data, 1, size, p.stream) != size) {
    const std::string why = std::strerror(errno ? errno : EIO), path = p.path;
    discard();
    fail(path, ": write failed: ", why);
  }
}

void AtomicFiles::write(const std::string& path, const void* data, size_t size) { append(begin(path), data, size); }

void AtomicFiles::commit() {
  // Everything is on disk before anything is renamed into place.
  for (Pending& p : pending_) {
    errno = 0;
    const bool ok = closeWritten(p.stream, !p.temporary.empty());
    p.stream = nullptr;
    if (!ok) {
      const std::string why = std::strerror(errno ? errno : EIO), path = p.path;
      discard();
      fail(path, ": write failed: ", why);
    }
  }
  // An interrupt during the renames waits for them, so that all files appear or none.
  const Publishing publishing;
  for (size_t i = 0; i < pending_.size(); ++i) {
    Pending& p = pending_[i];
    if (p.temporary.empty()) continue; // written through
    if (std::rename(p.temporary.c_str(), p.target.c_str()) != 0) {
      const std::string why = std::strerror(errno);
      pending_.erase(pending_.begin(), pending_.begin() + long(i)); // those are published
      discard();
      fail(p.path, ": cannot rename the temporary file into place: ", why);
    }
    releasePending(p.slot);
    syncDirectory(p.target);
  }
  pending_.clear();
}

void AtomicFiles::discard() {
  for (const Pending& p : pending_) {
    if (p.stream) std::fclose(p.stream);
    if (p.temporary.empty()) continue;
    std::remove(p.temporary.c_str());
    releasePending(p.slot);
  }
  pending_.clear();
}

AtomicFiles::~AtomicFiles() { discard(); }

void writeFileAtomic(const std::string& path, const void* data, size_t size) {
  AtomicFiles files;
  files.write(path, data, size);
  files.commit();
}

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

/// Reads NAME.cells in pieces of a million records, each validated, and hands them to `use`
/// with the index of their first record.
template <typename Use> void streamCells(const std::string& cellsPath, Use&& use) {
  const uint64_t bytes = fileSize(cellsPath);
  if (bytes == 0) fail(cellsPath, ": no cells (empty file)");
  if (bytes % sizeof(Cell) != 0)
    fail(cellsPath, ": truncated record ", bytes / sizeof(Cell), ": file size ", bytes,
         " is not a multiple of the 16-byte cell record");
  std::FILE* f = std::fopen(cellsPath.c_str(), "rb");
  if (!f) fail(cellsPath, ": cannot open: ", std::strerror(errno));
  std::unique_ptr<std::FILE, int (*)(std::FILE*)> closer(f, std::fclose);
  const uint64_t count = bytes / sizeof(Cell);
  std::vector<Cell> chunk(size_t(std::min<uint64_t>(count, uint64_t(1) << 20)));
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

/// The values of the records `keep` (ascending) of a .scalars file of `count` values.
std::vector<float> readSelectedValues(const std::string& path, const std::string& name, uint64_t count,
                                      const std::vector<uint64_t>& keep) {
  std::FILE* f = std::fopen(path.c_str(), "rb");
  if (!f) fail(path, ": cannot open: ", std::strerror(errno));
  std::unique_ptr<std::FILE, int (*)(std::FILE*)> closer(f, std::fclose);
  std::vector<float> out;
  out.reserve(keep.size());
  std::vector<float> chunk(size_t(std::min<uint64_t>(count, uint64_t(1) << 20)));
  size_t next = 0;
  for (uint64_t at = 0; at < count && next < keep.size(); at += chunk.size()) {
    const size_t n = size_t(std::min<uint64_t>(chunk.size(), count - at));
    if (keep[next] >= at + n) { // nothing wanted in this piece
      if (std::fseek(f, long(n * sizeof(float)), SEEK_CUR) != 0) fail(path, ": seek failed");
      continue;
    }
    if (std::fread(chunk.data(), sizeof(float), n, f) != n) fail(path, ": read error (file changed while reading?)");
    for (; next < keep.size() && keep[next] < at + n; ++next) {
      const float v = chunk[size_t(keep[next] - at)];
      if (!std::isfinite(v)) fail(path, ": record ", keep[next], ": value ", v, " of field '", name, "' is not finite");
      out.push_back(v);
    }
  }
  return out;
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

} // namespace

Census nativeCensus(const std::string& cellsPath) {
  stemOf(cellsPath);
  CellCensus census;
  streamCells(cellsPath, [&](const Cell* cells, size_t n, uint64_t) { census.add(cells, n); });
  return census.finish();
}

CellSet readNative(const std::string& cellsPath, const std::vector<std::string>& wanted, const box3i& box) {
  const std::string stem = stemOf(cellsPath);
  if (!box.empty()) {
    // Only the cells overlapping the box are kept, read in pieces: memory for those alone.
    CellSet set;
    std::vector<uint64_t> keep;
    uint64_t count = 0;
    streamCells(cellsPath, [&](const Cell* cells, size_t n, uint64_t at) {
      for (size_t i = 0; i < n; ++i) {
        if (!cellOverlaps(cells[i], box)) continue;
        keep.push_back(at + i);
        set.cells.push_back(cells[i]);
      }
      count = at + n;
    });
    for (const std::string& name : fieldNamesToRead(cellsPath, stem, wanted)) {
      const std::string path = checkedScalarsPath(cellsPath, stem, name, count);
      set.fields.push_back(Field{name, readSelectedValues(path, name, count, keep)});
    }
    return set;
  }
  CellSet set;
  {
    const uint64_t bytes = fileSize(cellsPath);
    if (bytes == 0) fail(cellsPath, ": no cells (empty file)");
    if (bytes % sizeof(Cell) != 0)
      fail(cellsPath, ": truncated record ", bytes / sizeof(Cell), ": file size ", bytes,
           " is not a multiple of the 16-byte cell record");
    set.cells.resize(bytes / sizeof(Cell));
    readInto(cellsPath, set.cells.data(), bytes);
  }
  validateCellRecords(set.cells, cellsPath);

  for (const std::string& name : fieldNamesToRead(cellsPath, stem, wanted)) {
    const std::string path = checkedScalarsPath(cellsPath, stem, name, set.cells.size());
    const uint64_t bytes = set.cells.size() * sizeof(float);
    Field field{name, std::vector<float>(set.cells.size())};
    readInto(path, field.values.data(), bytes);
    validateFieldValues(field, set.cells.size(), path);
    set.fields.push_back(std::move(field));
  }
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

void NativeWriter::finish() { files_.commit(); }

void writeNative(const CellSet& set, const std::string& cellsPath) {
  std::vector<std::string> names;
  for (const Field& f : set.fields)
    names.push_back(f.name);
  NativeWriter writer(cellsPath, names);
  writer.append(set);
  writer.finish();
}

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
    if (tokens.size() != 8 && tokens.size() != 15)
      fail(path, ": line ", lineNo, ": expected 'x y z nx ny nz level value' or eight corner", " values, got ",
           tokens.size(), " numbers");
    int64_t ints[7];
    for (int i = 0; i < 7; ++i) {
      char* end = nullptr;
      errno = 0;
      const long long v = std::strtoll(tokens[i].c_str(), &end, 10);
      if (*end != 0 || errno == ERANGE || v < INT32_MIN || v > INT32_MAX)
        fail(path, ": line ", lineNo, ": '", tokens[i], "' is not a 32-bit integer");
      ints[i] = v;
    }
    double v[8];
    const int nv = int(tokens.size()) - 7;
    for (int i = 0; i < nv; ++i) {
      char* end = nullptr;
      v[i] = std::strtod(tokens[7 + i].c_str(), &end);
      if (*end != 0) fail(path, ": line ", lineNo, ": '", tokens[7 + i], "' is not a number");
      if (!std::isfinite(v[i]) || std::fabs(v[i]) > 3.4e38)
        fail(path, ": line ", lineNo, ": value ", tokens[7 + i], " is not a finite float");
    }
    const vec3l n(ints[3], ints[4], ints[5]);
    if (n.x < 1 || n.y < 1 || n.z < 1)
      fail(path, ": line ", lineNo, ": box size ", n.x, "x", n.y, "x", n.z, " must be positive");
    const int64_t level = ints[6];
    const Cell probe{vec3i(int32_t(ints[0]), int32_t(ints[1]), int32_t(ints[2])), int32_t(level)};
    if (const std::string p = cellProblem(probe); !p.empty()) fail(path, ": line ", lineNo, ": ", p);
    const int64_t w = int64_t(1) << level;
    for (int a = 0; a < 3; ++a)
      if (ints[a] + n[a] * w > kLatticeLimit)
        fail(path, ": line ", lineNo, ": box reaches outside the supported lattice range");
    // A fixture line expands to its cells: bound the total before reserving memory for them.
    if (double(n.x) * double(n.y) * double(n.z) + double(set.cells.size()) > double(kMaxGridsCells))
      fail(path, ": line ", lineNo, ": box of ", n.x, "x", n.y, "x", n.z, " cells: a .grids fixture describes at most ",
           kMaxGridsCells, " cells (store larger data as NAME.cells)");
    {
      // Room for the line's cells, growing geometrically; running out of memory names the line.
      const uint64_t add = uint64_t(n.x * n.y * n.z), need = set.cells.size() + add;
      auto where = [&] { return strCat(path, ": line ", lineNo, ": box of ", n.x, "x", n.y, "x", n.z, " cells"); };
      if (need > set.cells.capacity()) {
        const uint64_t room = std::max<uint64_t>(need, std::min<uint64_t>(2 * set.cells.capacity(), kMaxGridsCells));
        const uint64_t grow = room - set.cells.size();
        io::reserveMore(set.cells, grow, where);
        io::reserveMore(field.values, grow, where);
      }
    }
    for (int64_t k = 0; k < n.z; ++k)
      for (int64_t j = 0; j < n.y; ++j)
        for (int64_t i = 0; i < n.x; ++i) {
          set.cells.push_back(Cell{vec3i(int32_t(ints[0] + i * w), int32_t(ints[1] + j * w), int32_t(ints[2] + k * w)),
                                   int32_t(level)});
          double value = v[0];
          if (nv == 8) {
            const double u = (i + 0.5) / n.x, s = (j + 0.5) / n.y, t = (k + 0.5) / n.z;
            auto lerp = [](double a, double b, double f) { return a + (b - a) * f; };
            value = lerp(lerp(lerp(v[0], v[1], u), lerp(v[2], v[3], u), s),
                         lerp(lerp(v[4], v[5], u), lerp(v[6], v[7], u), s), t);
          }
          field.values.push_back(float(value));
        }
  }
  if (set.cells.empty()) fail(path, ": no cells (empty input)");
  set.fields.push_back(std::move(field));
  return set;
}

} // namespace exa
