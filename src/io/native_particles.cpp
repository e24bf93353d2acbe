// NAME.particles: the particles of a native dataset, beside its NAME.cells. Little-endian:
//   "EXAPTCL1"                       8 bytes
//   u32 species count                at most kMaxSpecies
//   f64 lower x, y, z, upper x, y, z the domain (world coordinates)
//   per species: u8 name length, name, u64 particle count, u8 attribute count,
//                per attribute: u8 kind (0 real, 1 integer), u8 name length, name
//   per species, in order: x, y, z per particle (f64), then each attribute's values (f64)
// Names are 1 to 128 printable characters; the file holds exactly the bytes its header declares.
#include "exabricks/io/particles.h"

#include "particle_checks.h"

#include "exabricks/core/error.h"
#include "exabricks/core/files.h"

#include <bit>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>

namespace exa {

static_assert(std::endian::native == std::endian::little,
              "the native format is little-endian; big-endian hosts are not supported");

namespace {

constexpr char kMagic[8] = {'E', 'X', 'A', 'P', 'T', 'C', 'L', '1'};
constexpr uint32_t kMaxSpecies = 64;
constexpr uint8_t kMaxAttributes = 64;
constexpr size_t kMaxName = 128;

struct Header {
  vec3d lower, upper;
  std::vector<ParticleSpeciesInfo> species;
  std::vector<std::vector<bool>> integer; ///< per species, per attribute
  uint64_t dataOffset = 0;
};

/// Reads the header from `in`, checking each record against the file's size.
class HeaderReader {
public:
  HeaderReader(const std::string& path, std::ifstream& in, uint64_t size) : path_(path), in_(in), size_(size) {}

  void bytes(void* out, uint64_t n, const std::string& what) {
    if (n > size_ - offset_) fail(path_, ": ", what, " at byte ", offset_, ": the file ends (", size_, " bytes)");
    in_.read(static_cast<char*>(out), std::streamsize(n));
    if (!in_) fail(path_, ": cannot read ", what, " at byte ", offset_);
    offset_ += n;
  }
  template <typename T> T value(const std::string& what) {
    T v;
    bytes(&v, sizeof v, what);
    return v;
  }
  std::string name(const std::string& what) {
    const uint8_t length = value<uint8_t>(what + "'s length");
    if (length == 0 || length > kMaxName)
      fail(path_, ": ", what, " has length ", int(length), " (1 to ", kMaxName, ")");
    std::string s(length, '\0');
    bytes(s.data(), length, what);
    for (char c : s)
      if (c < 0x21 || c > 0x7e || c == '/')
        fail(path_, ": ", what, " holds a character that is not printable (or '/')");
    return s;
  }
  uint64_t offset() const { return offset_; }

private:
  const std::string& path_;
  std::ifstream& in_;
  uint64_t size_, offset_ = 0;
};

Header readHeader(const std::string& path, std::ifstream& in) {
  const uint64_t size = fileSize(path);
  in.open(path, std::ios::binary);
  if (!in) fail(path, ": cannot open");
  HeaderReader r(path, in, size);
  char magic[8];
  r.bytes(magic, 8, "the magic bytes");
  if (std::memcmp(magic, kMagic, 8) != 0) fail(path, ": not an exabricks particle file (no EXAPTCL1 at its start)");
  const uint32_t count = r.value<uint32_t>("the species count");
  if (count > kMaxSpecies) fail(path, ": ", count, " species declared (at most ", kMaxSpecies, ")");
  Header h;
  for (int a = 0; a < 3; ++a)
    h.lower[a] = r.value<double>("the domain's lower corner");
  for (int a = 0; a < 3; ++a)
    h.upper[a] = r.value<double>("the domain's upper corner");
  for (int a = 0; a < 3; ++a)
    if (!(std::isfinite(h.lower[a]) && std::isfinite(h.upper[a]) && h.lower[a] <= h.upper[a]))
      fail(path, ": the domain is not a box of finite corners");
  uint64_t dataBytes = 0;
  for (uint32_t s = 0; s < count; ++s) {
    const std::string record = strCat("species ", s);
    ParticleSpeciesInfo info;
    info.name = r.name(record + "'s name");
    for (const ParticleSpeciesInfo& other : h.species)
      if (other.name == info.name) fail(path, ": ", record, ": the species name '", info.name, "' repeats");
    info.count = r.value<uint64_t>(record + "'s particle count");
    info.precision = "double";
    const uint8_t attributes = r.value<uint8_t>(record + "'s attribute count");
    if (attributes > kMaxAttributes)
      fail(path, ": ", record, ": ", int(attributes), " attributes (at most ", int(kMaxAttributes), ")");
    std::vector<bool> integer;
    for (uint8_t a = 0; a < attributes; ++a) {
      const uint8_t kind = r.value<uint8_t>(strCat(record, ", attribute ", int(a), "'s kind"));
      if (kind > 1) fail(path, ": ", record, ", attribute ", int(a), ": kind ", int(kind), " (0 real, 1 integer)");
      info.attributes.push_back(r.name(strCat(record, ", attribute ", int(a), "'s name")));
      for (size_t b = 0; b + 1 < info.attributes.size(); ++b)
        if (info.attributes[b] == info.attributes.back())
          fail(path, ": ", record, ": the attribute name '", info.attributes.back(), "' repeats");
      integer.push_back(kind == 1);
    }
    // Every count is checked against the file's size before anything is allocated by it.
    const uint64_t perParticle = 8 * (3 + uint64_t(attributes));
    if (info.count > size / perParticle || info.count * perParticle > size - dataBytes)
      fail(path, ": ", record, " ('", info.name, "'): ", info.count, " particles of ", perParticle,
           " bytes each do not fit in the file (", size, " bytes)");
    dataBytes += info.count * perParticle;
    h.species.push_back(std::move(info));
    h.integer.push_back(std::move(integer));
  }
  h.dataOffset = r.offset();
  if (size - h.dataOffset != dataBytes)
    fail(path, ": the header declares ", dataBytes, " bytes of particle data after byte ", h.dataOffset,
         ", the file holds ", size - h.dataOffset);
  return h;
}

void readDoubles(const std::string& path, std::ifstream& in, std::vector<double>& out, size_t n) {
  out.resize(n);
  in.read(reinterpret_cast<char*>(out.data()), std::streamsize(n * sizeof(double)));
  if (!in) fail(path, ": cannot read the particle data");
}

void append(std::vector<char>& out, const void* data, size_t n) {
  const char* p = static_cast<const char*>(data);
  out.insert(out.end(), p, p + n);
}

template <typename T> void appendValue(std::vector<char>& out, T v) { append(out, &v, sizeof v); }

void appendName(std::vector<char>& out, const std::string& name, const std::string& what) {
  if (name.empty() || name.size() > kMaxName) fail("particles: ", what, " '", name, "' must be 1 to 128 characters");
  for (char c : name)
    if (c < 0x21 || c > 0x7e || c == '/')
      fail("particles: ", what, " '", name, "' holds a character that is not printable (or '/')");
  appendValue(out, uint8_t(name.size()));
  append(out, name.data(), name.size());
}

} // namespace

std::vector<ParticleSpeciesInfo> listNativeParticles(const std::string& cellsPath) {
  const std::string path = nativeParticlesPath(cellsPath);
  if (!std::filesystem::exists(path)) return {};
  std::ifstream in;
  return readHeader(path, in).species;
}

ParticleSet readNativeParticles(const std::string& cellsPath, const std::string& species) {
  const std::string path = nativeParticlesPath(cellsPath);
  ParticleSet set;
  if (!std::filesystem::exists(path)) {
    if (!species.empty()) fail(cellsPath, ": no particle species '", species, "' (it holds no particles)");
    return set;
  }
  std::ifstream in;
  Header h = readHeader(path, in);
  std::vector<std::string> names;
  for (const ParticleSpeciesInfo& s : h.species)
    names.push_back(s.name);
  const std::vector<size_t> wanted = io::pickSpecies(path, names, species);
  size_t next = 0;
  for (size_t s = 0; s < h.species.size(); ++s) {
    const ParticleSpeciesInfo& info = h.species[s];
    const bool keep = next < wanted.size() && wanted[next] == s;
    if (!keep) {
      in.seekg(std::streamoff(info.count * 8 * (3 + info.attributes.size())), std::ios::cur);
      continue;
    }
    ++next;
    ParticleSpecies out;
    out.name = info.name;
    out.precision = info.precision;
    readDoubles(path, in, out.position, size_t(info.count) * 3);
    for (size_t a = 0; a < info.attributes.size(); ++a) {
      ParticleAttribute attr;
      attr.name = info.attributes[a];
      attr.integer = h.integer[s][a];
      readDoubles(path, in, attr.values, size_t(info.count));
      if (attr.integer)
        for (size_t p = 0; p < attr.values.size(); ++p)
          if (!(std::isfinite(attr.values[p]) && attr.values[p] == std::trunc(attr.values[p])))
            fail(path, ": species '", info.name, "', integer attribute '", attr.name, "': particle ", p, " holds ",
                 attr.values[p], ", not a whole number");
      out.attributes.push_back(std::move(attr));
    }
    io::finishSpecies(out, h.lower, h.upper, path, set);
  }
  return set;
}

std::vector<char> nativeParticleBytes(const ParticleSet& set, const vec3d& lower, const vec3d& upper) {
  if (set.species.size() > kMaxSpecies) fail("particles: ", set.species.size(), " species (at most ", kMaxSpecies, ")");
  std::vector<char> out;
  append(out, kMagic, 8);
  appendValue(out, uint32_t(set.species.size()));
  for (int a = 0; a < 3; ++a)
    appendValue(out, lower[a]);
  for (int a = 0; a < 3; ++a)
    appendValue(out, upper[a]);
  for (size_t i = 0; i < set.species.size(); ++i) {
    const ParticleSpecies& s = set.species[i];
    for (size_t j = 0; j < i; ++j)
      if (set.species[j].name == s.name) fail("particles: the species name '", s.name, "' repeats");
    appendName(out, s.name, "the species name");
    appendValue(out, uint64_t(s.count()));
    if (s.attributes.size() > kMaxAttributes)
      fail("particles: species '", s.name, "' has ", s.attributes.size(), " attributes (at most 64)");
    appendValue(out, uint8_t(s.attributes.size()));
    for (const ParticleAttribute& a : s.attributes) {
      if (a.values.size() != s.count())
        fail("particles: species '", s.name, "', attribute '", a.name, "' holds ", a.values.size(), " values for ",
             s.count(), " particles");
      if (s.attribute(a.name) != &a)
        fail("particles: species '", s.name, "': the attribute name '", a.name, "' repeats");
      appendValue(out, uint8_t(a.integer ? 1 : 0));
      appendName(out, a.name, "the attribute name");
    }
  }
  for (const ParticleSpecies& s : set.species) {
    append(out, s.position.data(), s.position.size() * sizeof(double));
    for (const ParticleAttribute& a : s.attributes)
      append(out, a.values.data(), a.values.size() * sizeof(double));
  }
  return out;
}

void writeNativeParticles(const ParticleSet& set, const std::string& cellsPath, const vec3d& lower,
                          const vec3d& upper) {
  const std::vector<char> bytes = nativeParticleBytes(set, lower, upper);
  writeFileAtomic(nativeParticlesPath(cellsPath), bytes.data(), bytes.size());
}

} // namespace exa
