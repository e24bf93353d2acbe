#include "exabricks/io/model_file.h"

#include "exabricks/core/error.h"
#include "exabricks/core/files.h"

#include <fcntl.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <memory>
#include <type_traits>

namespace exa {
namespace {

/// FNV-1a over little-endian 64-bit words (the tail is zero-padded), fed incrementally.
class Checksum {
public:
  void update(const void* data, size_t size) {
    const auto* p = static_cast<const unsigned char*>(data);
    while (size > 0 && pending_ > 0) {
      addByte(*p++);
      --size;
    }
    while (size >= 8) {
      uint64_t word;
      std::memcpy(&word, p, 8);
      mix(word);
      p += 8;
      size -= 8;
    }
    while (size-- > 0)
      addByte(*p++);
  }
  uint64_t value() const {
    uint64_t h = hash_;
    if (pending_ > 0) h = (h ^ partial_) * kPrime;
    return h;
  }

private:
  static constexpr uint64_t kPrime = 0x100000001b3ull;
  void mix(uint64_t w) { hash_ = (hash_ ^ w) * kPrime; }
  void addByte(unsigned char b) {
    partial_ |= uint64_t(b) << (8 * pending_);
    if (++pending_ == 8) {
      mix(partial_);
      partial_ = 0;
      pending_ = 0;
    }
  }
  uint64_t hash_ = 0xcbf29ce484222325ull;
  uint64_t partial_ = 0;
  int pending_ = 0;
};

struct Header {
  char magic[8];
  uint32_t version;
  uint32_t headerBytes;
  uint64_t payloadBytes;
  uint64_t checksum;
  uint64_t reserved[2];
};
static_assert(sizeof(Header) == 48);

/// Zero bytes that bring a file offset to a multiple of 8.
size_t padding(uint64_t offset) { return size_t((8 - offset % 8) % 8); }

class Writer {
public:
  Writer(const std::string& path, std::FILE* f) : path_(path), f_(f) {}
  void raw(const void* data, size_t size) {
    if (size == 0) return;
    if (std::fwrite(data, 1, size, f_) != size) fail(path_, ": write failed (disk full?)");
    sum_.update(data, size);
    bytes_ += size;
  }
  template <typename T> void value(const T& v) { raw(&v, sizeof(T)); }
  /// Any contiguous array (a std::vector, a ValueArray): its length, zeros up to the next
  /// multiple of 8 bytes in the file (so that a mapped file can be used in place), its data.
  template <typename A> void array(const A& v) {
    using T = std::remove_cv_t<std::remove_pointer_t<decltype(v.data())>>;
    value(uint64_t(v.size()));
    static const char zeros[8] = {};
    raw(zeros, padding(sizeof(Header) + bytes_));
    raw(v.data(), v.size() * sizeof(T));
  }
  uint64_t bytes() const { return bytes_; }
  uint64_t checksum() const { return sum_.value(); }

private:
  const std::string& path_;
  std::FILE* f_;
  Checksum sum_;
  uint64_t bytes_ = 0;
};

/// Reads the payload from the file's bytes in memory (mapped or read), verifying sizes and the
/// checksum as it goes.
class Reader {
public:
  /// `mapped`: the bytes are a mapping of the file, whose pages are released from this process
  /// once read (a later access reads them back from the page cache).
  Reader(const std::string& path, const char* payload, uint64_t payloadBytes, uint32_t version,
         std::shared_ptr<const void> keep, bool mapped)
      : path_(path), start_(payload - sizeof(Header)), at_(payload), left_(payloadBytes), version_(version),
        keep_(std::move(keep)), mapped_(mapped) {}
  void raw(void* data, size_t size, const char* what) {
    const char* from = take(size, what);
    if (size > 0) std::memcpy(data, from, size); // an empty array's data() may be null
  }
  template <typename T> T value(const char* what) {
    T v;
    raw(&v, sizeof(T), what);
    return v;
  }
  template <typename T> std::vector<T> array(const char* what) {
    const uint64_t n = arrayLength<T>(what);
    std::vector<T> v(n);
    raw(v.data(), n * sizeof(T), what);
    return v;
  }
  /// Field values: in place when the file's layout aligns them (version 2), else copied.
  ValueArray values(const char* what) {
    const uint64_t n = arrayLength<float>(what);
    const char* data = take(n * sizeof(float), what);
    if (reinterpret_cast<uintptr_t>(data) % alignof(float) == 0)
      return ValueArray(keep_, reinterpret_cast<const float*>(data), n);
    std::vector<float> v(n);
    if (n > 0) std::memcpy(v.data(), data, n * sizeof(float));
    return ValueArray(std::move(v));
  }
  uint64_t left() const { return left_; }
  uint64_t checksum() const { return sum_.value(); }
  /// Releases every page read so far (mapped files): the checksum touched them all, and the
  /// copies made of bricks and regions must not count twice.
  void releaseRead(uint64_t atLeast = 0) {
    if (!mapped_) return;
    const uint64_t page = uint64_t(::sysconf(_SC_PAGESIZE));
    const uint64_t end = uint64_t(at_ - start_) / page * page;
    if (end <= released_ + atLeast) return;
    ::madvise(const_cast<char*>(start_ + released_), size_t(end - released_), MADV_DONTNEED);
    released_ = end;
  }

private:
  const char* take(uint64_t size, const char* what) {
    if (size > left_) fail(path_, ": corrupt model file: ", what, " runs past the end of the data");
    const char* p = at_;
    // The checksum in pieces, each released once summed: reading a model never holds more of the
    // file than one piece beyond what it copies.
    constexpr uint64_t kPiece = uint64_t(32) << 20;
    for (uint64_t done = 0; done < size; done += kPiece) {
      const uint64_t n = std::min(kPiece, size - done);
      sum_.update(p + done, size_t(n));
      at_ = p + done + n;
      releaseRead(kPiece);
    }
    at_ = p + size;
    left_ -= size;
    return p;
  }
  template <typename T> uint64_t arrayLength(const char* what) {
    const uint64_t n = value<uint64_t>(what);
    if (version_ >= 2) { // zeros up to a multiple of 8 bytes in the file
      const size_t pad = padding(uint64_t(at_ - start_));
      const char* zeros = take(pad, what);
      for (size_t i = 0; i < pad; ++i)
        if (zeros[i] != 0) fail(path_, ": corrupt model file: padding before ", what, " is not zero");
    }
    if (n > left_ / sizeof(T))
      fail(path_, ": corrupt model file: ", what, " claims ", n, " entries, more than the file holds");
    return n;
  }
  const std::string& path_;
  const char* start_; ///< the file's first byte (the payload follows the header)
  const char* at_;
  uint64_t left_;
  uint32_t version_;
  std::shared_ptr<const void> keep_;
  bool mapped_;
  uint64_t released_ = 0; ///< bytes from the file's start whose pages were released
  Checksum sum_;
};

/// An open file descriptor, closed when it goes.
struct Descriptor {
  int fd = -1;
  ~Descriptor() {
    if (fd >= 0) ::close(fd);
  }
};

/// Reads `size` bytes at `offset` of the open file.
void readAt(const std::string& path, int fd, void* data, uint64_t size, uint64_t offset) {
  auto* out = static_cast<char*>(data);
  while (size > 0) {
    const ssize_t n = ::pread(fd, out, size_t(std::min<uint64_t>(size, uint64_t(1) << 30)), off_t(offset));
    if (n <= 0) fail(path, ": read error (file changed while reading?)");
    out += n, offset += uint64_t(n), size -= uint64_t(n);
  }
}

/// The whole open file read-only in memory: mapped where the platform allows, else read.
std::shared_ptr<const void> mapFile(const std::string& path, int fd, uint64_t size, bool& mapped) {
  mapped = false;
  if (size == 0) return nullptr;
  void* p = ::mmap(nullptr, size_t(size), PROT_READ, MAP_PRIVATE, fd, 0);
  if (p != MAP_FAILED) {
    ::madvise(p, size_t(size), MADV_SEQUENTIAL); // read once through by the checksum
    mapped = true;
    return std::shared_ptr<const void>(p, [size](const void* q) { ::munmap(const_cast<void*>(q), size_t(size)); });
  }
  auto bytes = std::make_shared<std::vector<char>>(size_t(size));
  readAt(path, fd, bytes->data(), size, 0);
  return std::shared_ptr<const void>(bytes, bytes->data());
}

/// The header of an open model file of `total` bytes, checked against the file.
Header checkedHeader(const std::string& path, int fd, uint64_t total) {
  if (total < sizeof(Header)) fail(path, ": truncated model file (no header)");
  Header h{};
  readAt(path, fd, &h, sizeof h, 0);
  if (std::memcmp(h.magic, kModelMagic, 8) != 0) fail(path, ": not an exabricks model file");
  if (h.version != kModelVersion && h.version != 1)
    fail(path, ": model file version ", h.version, " is not supported (this build reads versions 1 and ", kModelVersion,
         "); rebuild it with 'exabricks build'");
  if (h.headerBytes != sizeof(Header)) fail(path, ": corrupt model file header");
  if (h.reserved[0] != 0 || h.reserved[1] != 0)
    fail(path, ": corrupt model file header: its reserved bytes (32..47) are not zero");
  if (total - sizeof(Header) != h.payloadBytes)
    fail(path, ": truncated or padded model file: header says ", h.payloadBytes, " payload bytes, file holds ",
         total - sizeof(Header));
  return h;
}

struct FileCloser {
  std::FILE* f;
  ~FileCloser() {
    if (f) std::fclose(f);
  }
};

/// Every field holds as many values, and every brick's cells lie within them.
void checkBricks(const std::vector<Brick>& bricks, const std::vector<uint64_t>& valueCounts, const std::string& path) {
  auto bad = [&](auto&&... what) { fail(path, ": corrupt model file: ", what...); };
  const uint64_t values = valueCounts.empty() ? 0 : valueCounts[0];
  for (uint64_t n : valueCounts)
    if (n != values) bad("fields have different value counts");
  for (size_t i = 0; i < bricks.size(); ++i) {
    const Brick& b = bricks[i];
    if (b.level < 0 || b.level > kMaxLevel || b.size.x < 1 || b.size.y < 1 || b.size.z < 1 ||
        b.size.x > kMaxBrickWidth || b.size.y > kMaxBrickWidth || b.size.z > kMaxBrickWidth ||
        uint64_t(b.valueOffset) + uint64_t(b.size.x) * b.size.y * b.size.z > values)
      bad("brick ", i, " is invalid");
    // Its cells are cells (cellProblem): aligned to their width, within the lattice range.
    const int64_t w = int64_t(1) << b.level;
    for (int a = 0; a < 3; ++a)
      if (b.lower[a] % w != 0 || b.lower[a] < -kLatticeLimit || b.lower[a] + b.size[a] * w > kLatticeLimit)
        bad("brick ", i, " lies outside the supported lattice range [-2^29, 2^29] or off its cells' lattice");
  }
}

/// Index checks that keep a crafted file (with a valid checksum) from making samplers read
/// out of bounds or loop.
void checkConsistency(const Model& m, const std::string& path) {
  auto bad = [&](auto&&... what) { fail(path, ": corrupt model file: ", what...); };
  std::vector<uint64_t> counts;
  for (const auto& f : m.fieldValues)
    counts.push_back(f.size());
  checkBricks(m.bricks, counts, path);
  for (uint32_t id : m.regions.brickIds)
    if (id >= m.bricks.size()) bad("region brick id ", id, " out of range");
  for (size_t i = 0; i < m.regions.regions.size(); ++i) {
    const Region& r = m.regions.regions[i];
    if (uint64_t(r.brickBegin) + r.brickCount > m.regions.brickIds.size())
      bad("region ", i, " lists bricks out of range");
  }
  const auto& nodes = m.regions.nodes;
  for (size_t i = 0; i < nodes.size(); ++i) {
    const RegionKdNode& n = nodes[i];
    if (n.axis == kLeafAxis) {
      if (n.index != kNoRegion && n.index >= m.regions.regions.size())
        bad("k-d node ", i, " names region ", n.index, " out of range");
    } else if (n.axis > 2 || n.index <= i || uint64_t(n.index) + 1 >= nodes.size()) {
      bad("k-d node ", i, " is invalid");
    }
  }
  if (nodes.empty() != m.regions.regions.empty()) bad("regions without a k-d tree");
  // Each leaf's cell is its region's box: the traversal takes a region's ray interval from the
  // split planes. Children follow their parent (checked above) and no node has two parents.
  if (!nodes.empty()) {
    std::vector<uint8_t> reached(nodes.size(), 0);
    std::vector<std::pair<uint32_t, box3f>> stack{{0u, m.regions.bounds}};
    while (!stack.empty()) {
      const auto [i, cell] = stack.back();
      stack.pop_back();
      if (reached[i]++) bad("k-d node ", i, " has two parents");
      const RegionKdNode& n = nodes[i];
      if (n.axis == kLeafAxis) {
        if (n.index != kNoRegion && !(m.regions.regions[n.index].bounds() == cell))
          bad("region ", n.index, " does not fill its k-d cell");
        continue;
      }
      if (!(n.pos >= cell.lower[int(n.axis)] && n.pos <= cell.upper[int(n.axis)]))
        bad("k-d node ", i, " splits outside its cell");
      box3f lower = cell, upper = cell;
      lower.upper[int(n.axis)] = n.pos;
      upper.lower[int(n.axis)] = n.pos;
      stack.push_back({n.index, lower});
      stack.push_back({n.index + 1, upper});
    }
  }
  if (m.regions.valueRanges.size() != m.fieldValues.size()) bad("missing value ranges");
  for (const auto& r : m.regions.valueRanges)
    if (r.size() != m.regions.regions.size()) bad("value ranges do not match the regions");
}

} // namespace

bool isModelFile(const std::string& path) {
  std::FILE* f = std::fopen(path.c_str(), "rb");
  if (!f) return false;
  char magic[8] = {};
  const bool ok = std::fread(magic, 1, 8, f) == 8 && std::memcmp(magic, kModelMagic, 8) == 0;
  std::fclose(f);
  return ok;
}

void writeModel(const Model& m, const std::string& path) {
  removeStaleTemporaries(path);
  const std::string tmp = temporaryPath(path, 0);
  const PendingTemporary pending(tmp); // removed by an interrupt before the rename
  std::FILE* f = std::fopen(tmp.c_str(), "wb");
  if (!f) fail(path, ": cannot write: ", std::strerror(errno));
  try {
    FileCloser closer{f};
    Header h{};
    std::memcpy(h.magic, kModelMagic, 8);
    h.version = kModelVersion;
    h.headerBytes = sizeof(Header);
    if (std::fwrite(&h, sizeof h, 1, f) != 1) fail(path, ": write failed");
    Writer w(path, f);
    w.value(m.world);
    w.array(m.bricks);
    w.value(uint64_t(m.fieldNames.size()));
    for (size_t i = 0; i < m.fieldNames.size(); ++i) {
      w.value(uint64_t(m.fieldNames[i].size()));
      w.raw(m.fieldNames[i].data(), m.fieldNames[i].size());
      w.array(m.fieldValues[i]);
    }
    w.array(m.regions.regions);
    w.array(m.regions.brickIds);
    w.array(m.regions.nodes);
    w.value(m.regions.bounds);
    for (const auto& r : m.regions.valueRanges)
      w.array(r);
    for (double seconds : {m.stats.brickSeconds, m.stats.regionSeconds, m.stats.rangeSeconds})
      w.value(seconds);
    h.payloadBytes = w.bytes();
    h.checksum = w.checksum();
    if (std::fseek(f, 0, SEEK_SET) != 0 || std::fwrite(&h, sizeof h, 1, f) != 1) fail(path, ": write failed");
    // On disk before the rename: a crash leaves the old file or the new one.
    if (std::fflush(f) != 0 || ::fsync(::fileno(f)) != 0) fail(path, ": write failed: ", std::strerror(errno));
    closer.f = nullptr;
    if (std::fclose(f) != 0) fail(path, ": write failed (disk full?)");
  } catch (...) {
    std::remove(tmp.c_str());
    throw;
  }
  if (std::rename(tmp.c_str(), path.c_str()) != 0) {
    const std::string why = std::strerror(errno);
    std::remove(tmp.c_str());
    fail(path, ": cannot rename temporary file into place: ", why);
  }
}

Model readModel(const std::string& path) {
  // One descriptor for the header, the checks and every mapping: all of one file.
  Descriptor file;
  file.fd = ::open(path.c_str(), O_RDONLY);
  if (file.fd < 0) fail(path, ": cannot open: ", std::strerror(errno));
  struct stat st {};
  if (::fstat(file.fd, &st) != 0 || !S_ISREG(st.st_mode)) fail(path, ": not a regular file");
  const uint64_t total = uint64_t(st.st_size);
  const Header h = checkedHeader(path, file.fd, total);

  // The field values stay in the mapped file (version 2 aligns them); the rest is copied.
  bool mapped = false;
  std::shared_ptr<const void> bytes = mapFile(path, file.fd, total, mapped);
  const char* base = static_cast<const char*>(bytes.get());
  Reader r(path, base + sizeof(Header), h.payloadBytes, h.version, bytes, mapped);
  Model m;
  m.world = r.value<WorldTransform>("world transform");
  m.bricks = r.array<Brick>("bricks");
  const uint64_t fields = r.value<uint64_t>("field count");
  if (fields > 4096) fail(path, ": corrupt model file: ", fields, " fields");
  for (uint64_t i = 0; i < fields; ++i) {
    const uint64_t len = r.value<uint64_t>("field name");
    if (len > 4096) fail(path, ": corrupt model file: field name of ", len, " bytes");
    std::string name(len, '\0');
    r.raw(name.data(), len, "field name");
    m.fieldNames.push_back(name);
    m.fieldValues.push_back(r.values("field values"));
  }
  m.regions.regions = r.array<Region>("regions");
  m.regions.brickIds = r.array<uint32_t>("region brick ids");
  m.regions.nodes = r.array<RegionKdNode>("k-d tree");
  m.regions.bounds = r.value<box3f>("bounds");
  for (uint64_t i = 0; i < fields; ++i)
    m.regions.valueRanges.push_back(r.array<range1f>("value ranges"));
  m.stats.brickSeconds = r.value<double>("build times");
  m.stats.regionSeconds = r.value<double>("build times");
  m.stats.rangeSeconds = r.value<double>("build times");
  if (r.left() != 0) fail(path, ": corrupt model file: ", r.left(), " unexpected trailing bytes");
  if (r.checksum() != h.checksum) fail(path, ": corrupt model file: checksum mismatch");
  r.releaseRead();
  checkConsistency(m, path);
  if (mapped) {
    // The values move to a fresh mapping of the same file: the verification touched every page
    // of the first, which goes with it, and the new one holds only what the renderer reads.
    bool again = false;
    const std::shared_ptr<const void> fresh = mapFile(path, file.fd, total, again);
    if (again) {
      const char* freshBase = static_cast<const char*>(fresh.get());
      for (ValueArray& v : m.fieldValues) {
        const char* at = reinterpret_cast<const char*>(v.data());
        if (at >= base && at < base + total)
          v = ValueArray(fresh, reinterpret_cast<const float*>(freshBase + (at - base)), v.size());
      }
    }
  }
  return m;
}

ModelTable readModelTable(const std::string& path) {
  ModelTable t;
  auto fd = std::make_shared<Descriptor>();
  fd->fd = ::open(path.c_str(), O_RDONLY);
  if (fd->fd < 0) fail(path, ": cannot open: ", std::strerror(errno));
  struct stat st {};
  if (::fstat(fd->fd, &st) != 0 || !S_ISREG(st.st_mode)) fail(path, ": not a regular file");
  const uint64_t total = uint64_t(st.st_size);
  const Header h = checkedHeader(path, fd->fd, total);
  // The payload's records in order, read up to the regions; the values are skipped.
  uint64_t at = sizeof(Header);
  auto take = [&](void* data, uint64_t size, const char* what) {
    if (size > total - at) fail(path, ": corrupt model file: ", what, " runs past the end of the data");
    if (size > 0) readAt(path, fd->fd, data, size, at);
    at += size;
  };
  auto arrayLength = [&](uint64_t entryBytes, const char* what) {
    uint64_t n = 0;
    take(&n, sizeof n, what);
    if (h.version >= 2) {
      char zeros[8] = {};
      const size_t pad = padding(at);
      take(zeros, pad, what);
      for (size_t i = 0; i < pad; ++i)
        if (zeros[i] != 0) fail(path, ": corrupt model file: padding before ", what, " is not zero");
    }
    if (n > (total - at) / entryBytes)
      fail(path, ": corrupt model file: ", what, " claims ", n, " entries, more than the file holds");
    return n;
  };
  take(&t.world, sizeof t.world, "world transform");
  t.bricks.resize(size_t(arrayLength(sizeof(Brick), "bricks")));
  take(t.bricks.data(), t.bricks.size() * sizeof(Brick), "bricks");
  uint64_t fields = 0;
  take(&fields, sizeof fields, "field count");
  if (fields > 4096) fail(path, ": corrupt model file: ", fields, " fields");
  std::vector<uint64_t> counts;
  for (uint64_t i = 0; i < fields; ++i) {
    uint64_t len = 0;
    take(&len, sizeof len, "field name");
    if (len > 4096) fail(path, ": corrupt model file: field name of ", len, " bytes");
    std::string name(len, '\0');
    take(name.data(), len, "field name");
    t.fieldNames.push_back(name);
    counts.push_back(arrayLength(sizeof(float), "field values"));
    t.valuesAt.push_back(at);
    at += counts.back() * sizeof(float);
  }
  checkBricks(t.bricks, counts, path);
  t.file = std::shared_ptr<const int>(fd, &fd->fd);
  return t;
}

void ModelTable::readValues(const std::string& path, size_t field, const Brick& b, float* out) const {
  readAt(path, *file, out, uint64_t(b.cellCount()) * sizeof(float),
         valuesAt.at(field) + uint64_t(b.valueOffset) * sizeof(float));
}

} // namespace exa
