#include "exabricks/io/particles.h"

#include "checked.h"
#include "particle_checks.h"

#include "exabricks/core/byte_order.h"
#include "exabricks/core/error.h"
#include "exabricks/io/amrex.h"

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>

namespace exa {
namespace fs = std::filesystem;

namespace {

/// Whitespace-separated tokens of a particle Header, each with its line.
class Tokens {
public:
  explicit Tokens(const std::string& path) : path_(path) {
    std::ifstream in(path);
    if (!in) fail(path, ": cannot open: ", std::strerror(errno));
    std::string l;
    for (size_t n = 1; std::getline(in, l); ++n) {
      std::istringstream s(l);
      for (std::string t; s >> t;)
        tokens_.push_back({t, n});
    }
  }
  const std::string& path() const { return path_; }
  std::string word(const char* what) {
    if (next_ >= tokens_.size())
      fail(path_, ": line ", tokens_.empty() ? 1 : tokens_.back().second, ": ends before ", what);
    return tokens_[next_++].first;
  }
  int64_t integer(int64_t lo, int64_t hi, const char* what) {
    const std::string w = word(what);
    char* end = nullptr;
    errno = 0;
    const long long v = std::strtoll(w.c_str(), &end, 10);
    if (w.empty() || *end != '\0' || errno == ERANGE || v < lo || v > hi)
      fail(path_, ": line ", tokens_[next_ - 1].second, ": ", what, " is '", w, "', not an integer in ", lo, "..", hi);
    return v;
  }
  size_t line() const { return next_ == 0 ? 1 : tokens_[next_ - 1].second; }

private:
  std::string path_;
  std::vector<std::pair<std::string, size_t>> tokens_;
  size_t next_ = 0;
};

struct GridEntry {
  int64_t file = 0, count = 0, offset = 0;
};

struct SpeciesHeader {
  std::string name, dir, header;
  bool single = false, packedIds = false;
  std::vector<std::string> reals, ints; ///< component names beyond positions, id and cpu
  int64_t total = 0;
  std::vector<std::vector<GridEntry>> levels;
};

constexpr int64_t kMaxComponents = 100000;
constexpr int64_t kMaxGrids = int64_t(1) << 30;

bool isParticleVersion(const std::string& v) { return v.rfind("Version_", 0) == 0; }

SpeciesHeader readSpeciesHeader(const fs::path& dir) {
  SpeciesHeader h;
  h.dir = dir.string();
  h.name = dir.filename().string();
  h.header = (dir / "Header").string();
  Tokens t(h.header);
  const std::string version = t.word("the version");
  if (version.rfind("Version_Two_Dot_Zero_", 0) == 0 || version.rfind("Version_Two_Dot_One_", 0) == 0 ||
      version.rfind("Version_One_Dot_One_", 0) == 0) {
    const std::string how = version.substr(version.rfind('_') + 1);
    if (how != "single" && how != "double")
      fail(h.header, ": line 1: version '", version, "' names neither single nor double precision");
    h.single = how == "single";
  } else if (version != "Version_One_Dot_Zero") {
    fail(h.header, ": line 1: unknown particle version '", version,
         "' (expected Version_Two_Dot_Zero_double, ..._single or Version_Two_Dot_One_*)");
  }
  h.packedIds = version.rfind("Version_Two_Dot_One_", 0) == 0;
  const int64_t dim = t.integer(1, 3, "the dimension");
  if (dim != 3) fail(h.header, ": line ", t.line(), ": ", dim, "-D particles; only 3-D data can be read");
  const int64_t nreal = t.integer(0, kMaxComponents, "the number of real components");
  for (int64_t i = 0; i < nreal; ++i)
    h.reals.push_back(t.word("a real component's name"));
  const int64_t nint = t.integer(0, kMaxComponents, "the number of integer components");
  for (int64_t i = 0; i < nint; ++i)
    h.ints.push_back(t.word("an integer component's name"));
  t.integer(0, 1, "the checkpoint flag");
  h.total = t.integer(0, int64_t(1) << 50, "the particle count");
  t.integer(INT64_MIN, INT64_MAX, "the next id");
  const int64_t finest = t.integer(0, 64, "the finest level");
  std::vector<int64_t> grids;
  for (int64_t l = 0; l <= finest; ++l)
    grids.push_back(t.integer(0, kMaxGrids, "a level's number of grids"));
  int64_t listed = 0;
  for (int64_t l = 0; l <= finest; ++l) {
    h.levels.emplace_back();
    for (int64_t g = 0; g < grids[size_t(l)]; ++g) {
      GridEntry e;
      e.file = t.integer(-1, 99999999, "a grid's data file number");
      e.count = t.integer(0, int64_t(1) << 50, "a grid's particle count");
      e.offset = t.integer(0, INT64_MAX, "a grid's byte offset");
      if (e.count > 0 && e.file < 0)
        fail(h.header, ": line ", t.line(), ": level ", l, " grid ", g, " holds ", e.count,
             " particles but names no data file");
      listed += e.count;
      if (listed > h.total)
        fail(h.header, ": line ", t.line(), ": the grid table lists more particles than the ", h.total, " declared");
      h.levels.back().push_back(e);
    }
  }
  if (listed != h.total) fail(h.header, ": declares ", h.total, " particles but its grid table lists ", listed);
  return h;
}

/// The particle species folders of a plotfile, sorted by name.
std::vector<fs::path> speciesFolders(const std::string& plotfile) {
  std::vector<fs::path> out;
  std::error_code ec;
  for (const fs::directory_entry& e : fs::directory_iterator(plotfile, ec)) {
    if (!e.is_directory(ec)) continue;
    std::ifstream in(e.path() / "Header");
    std::string first;
    if (in >> first && isParticleVersion(first)) out.push_back(e.path());
  }
  std::sort(out.begin(), out.end());
  return out;
}

std::vector<std::string> attributeNames(const SpeciesHeader& h) {
  std::vector<std::string> names{"id", "cpu"};
  names.insert(names.end(), h.ints.begin(), h.ints.end());
  names.insert(names.end(), h.reals.begin(), h.reals.end());
  return names;
}

/// Bytes of one particle in the data files: id, cpu and integer components, positions and real
/// components.
uint64_t bytesPerParticle(const SpeciesHeader& h) {
  return 4 * (2 + h.ints.size()) + (h.single ? 4 : 8) * (3 + h.reals.size());
}

/// A Version_Two_Dot_One particle's id from its packed 64-bit id and cpu (the valid flag in the
/// top bit, 39 bits of id and 24 of cpu below it).
void unpackId(uint64_t idcpu, double& id, double& cpu) {
  const double magnitude = double((idcpu >> 24) & ((uint64_t(1) << 39) - 1));
  id = (idcpu >> 63) ? magnitude : -magnitude;
  cpu = double(idcpu & 0xFFFFFF);
}

/// A grid's data file, checked to hold the grid's particles at its offset, and its size.
struct GridFile {
  std::string path, where;
  uint64_t size = 0;
};
GridFile checkGrid(const SpeciesHeader& h, size_t level, size_t grid, const GridEntry& e) {
  char name[32];
  std::snprintf(name, sizeof name, "DATA_%05lld", static_cast<long long>(e.file));
  GridFile f;
  f.path = (fs::path(h.dir) / ("Level_" + std::to_string(level)) / name).string();
  f.where = strCat(h.header, ": level ", level, " grid ", grid, " (", f.path, ")");
  std::error_code ec;
  f.size = fs::file_size(f.path, ec);
  if (ec) fail(f.where, ": cannot read the data file: ", ec.message());
  if (uint64_t(e.offset) > f.size) fail(f.where, ": offset ", e.offset, " lies beyond the file's ", f.size, " bytes");
  io::requireBytes(uint64_t(e.count), bytesPerParticle(h), f.size - uint64_t(e.offset), f.where);
  return f;
}

/// Appends one grid's particles (`e`) from its data file, checked by checkGrid.
void readGrid(const SpeciesHeader& h, const GridEntry& e, const GridFile& f, ParticleSpecies& s) {
  const uint64_t realBytes = h.single ? 4 : 8;
  const uint64_t intsPer = 2 + h.ints.size(), realsPer = 3 + h.reals.size();
  std::ifstream in(f.path, std::ios::binary);
  in.seekg(std::streamoff(e.offset));
  std::vector<unsigned char> bytes =
      io::allocate<unsigned char>(uint64_t(e.count) * bytesPerParticle(h), [&] { return f.where; });
  if (!in.read(reinterpret_cast<char*>(bytes.data()), std::streamsize(bytes.size())))
    fail(f.where, ": cannot read ", bytes.size(), " bytes at offset ", e.offset);
  const bool swap = io::needsSwap(false);
  const unsigned char* ints = bytes.data();
  const unsigned char* reals = ints + 4 * intsPer * uint64_t(e.count);
  for (int64_t p = 0; p < e.count; ++p) {
    const unsigned char* ip = ints + 4 * intsPer * uint64_t(p);
    double id = io::loadScalar<int32_t>(ip, swap), cpu = io::loadScalar<int32_t>(ip + 4, swap);
    if (h.packedIds)
      unpackId(uint64_t(io::loadScalar<uint32_t>(ip, swap)) | uint64_t(io::loadScalar<uint32_t>(ip + 4, swap)) << 32,
               id, cpu);
    s.attributes[0].values.push_back(id);
    s.attributes[1].values.push_back(cpu);
    for (size_t k = 0; k < h.ints.size(); ++k)
      s.attributes[2 + k].values.push_back(io::loadScalar<int32_t>(ip + 4 * (2 + k), swap));
    const unsigned char* rp = reals + realBytes * realsPer * uint64_t(p);
    auto real = [&](size_t k) {
      return h.single ? double(io::loadScalar<float>(rp + 4 * k, swap)) : io::loadScalar<double>(rp + 8 * k, swap);
    };
    for (size_t a = 0; a < 3; ++a)
      s.position.push_back(real(a));
    for (size_t k = 0; k < h.reals.size(); ++k)
      s.attributes[2 + h.ints.size() + k].values.push_back(real(3 + k));
  }
}

} // namespace

std::vector<ParticleSpeciesInfo> listAmrexParticles(const std::string& plotfile) {
  std::vector<ParticleSpeciesInfo> out;
  for (const fs::path& dir : speciesFolders(plotfile)) {
    const SpeciesHeader h = readSpeciesHeader(dir);
    out.push_back({h.name, uint64_t(h.total), attributeNames(h), h.single ? "single" : "double"});
  }
  return out;
}

ParticleSet readAmrexParticles(const std::string& plotfile, const std::string& species) {
  const std::vector<fs::path> folders = speciesFolders(plotfile);
  std::vector<std::string> names;
  for (const fs::path& f : folders)
    names.push_back(f.filename().string());
  const AmrexDomain domain = amrexDomain(plotfile);
  ParticleSet set;
  for (size_t i : io::pickSpecies(plotfile, names, species)) {
    const SpeciesHeader h = readSpeciesHeader(folders[i]);
    // Every grid's bytes are checked against its file before the species is allocated, and the
    // grids of one file together claim no more bytes than it holds (grids do not overlap).
    std::map<std::string, uint64_t> claimed;
    std::vector<std::pair<const GridEntry*, GridFile>> grids; ///< those with particles, in file order
    for (size_t l = 0; l < h.levels.size(); ++l)
      for (size_t g = 0; g < h.levels[l].size(); ++g) {
        const GridEntry& e = h.levels[l][g];
        if (e.count == 0) continue;
        GridFile f = checkGrid(h, l, g, e);
        uint64_t& bytes = claimed[f.path];
        bytes += uint64_t(e.count) * bytesPerParticle(h);
        if (bytes > f.size)
          fail(f.where, ": the grids of this file claim ", bytes, " bytes, more than its ", f.size, " (grids overlap)");
        grids.emplace_back(&e, std::move(f));
      }
    ParticleSpecies s;
    s.name = h.name;
    s.precision = h.single ? "single" : "double";
    for (const std::string& a : attributeNames(h))
      s.attributes.push_back({a, {}, false});
    for (size_t k = 0; k < 2 + h.ints.size(); ++k)
      s.attributes[k].integer = true;
    s.position.reserve(3 * size_t(h.total));
    for (ParticleAttribute& a : s.attributes)
      a.values.reserve(size_t(h.total));
    for (const auto& [e, f] : grids)
      readGrid(h, *e, f, s);
    io::finishSpecies(s, domain.lower, domain.upper, plotfile, set);
  }
  return set;
}

} // namespace exa
