#include "exabricks/io/vtk_amr.h"

#include "patches.h"

#include "exabricks/core/error.h"
#include "exabricks/core/log.h"

#include "checked.h"
#include "exabricks/core/byte_order.h"

#include <zlib.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>

namespace exa {
namespace fs = std::filesystem;

namespace {

std::string readFile(const std::string& path, const std::string& role) {
  std::ifstream in(path, std::ios::binary);
  if (!in) fail(path, ": cannot open ", role, ": ", std::strerror(errno));
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

/// One XML start tag (or self-closing tag) with its attributes and the text that follows it up
/// to the next tag. VTK's XML is simple enough that this is all the readers need.
struct Tag {
  std::string name; ///< "/Name" for an end tag
  std::map<std::string, std::string> attrs;
  std::string text;
  size_t offset = 0; ///< byte offset of '<' in the file
  std::string attr(const std::string& key, const std::string& fallback = "") const {
    const auto it = attrs.find(key);
    return it == attrs.end() ? fallback : it->second;
  }
};

/// Tags of `xml` up to `end` (the start of raw appended data, which is not XML).
std::vector<Tag> scanTags(const std::string& path, const std::string& xml, size_t end) {
  std::vector<Tag> tags;
  size_t pos = 0;
  while ((pos = xml.find('<', pos)) != std::string::npos && pos < end) {
    if (xml.compare(pos, 4, "<!--") == 0) {
      const size_t close = xml.find("-->", pos);
      if (close == std::string::npos) fail(path, ": byte ", pos, ": unterminated XML comment");
      pos = close + 3;
      continue;
    }
    const size_t close = xml.find('>', pos);
    if (close == std::string::npos || close > end)
      fail(path, ": byte ", pos, ": unterminated XML tag (truncated file?)");
    if (xml[pos + 1] == '?' || xml[pos + 1] == '!') {
      pos = close + 1;
      continue;
    }
    Tag t;
    t.offset = pos;
    size_t i = pos + 1;
    while (i < close && !std::isspace((unsigned char)xml[i]) && xml[i] != '/' && xml[i] != '>')
      ++i;
    if (xml[pos + 1] == '/') {
      while (i < close && !std::isspace((unsigned char)xml[i]) && xml[i] != '>')
        ++i;
    }
    t.name = xml.substr(pos + 1, i - pos - 1);
    while (i < close) {
      while (i < close && (std::isspace((unsigned char)xml[i]) || xml[i] == '/'))
        ++i;
      if (i >= close) break;
      const size_t eq = xml.find('=', i);
      if (eq == std::string::npos || eq > close) fail(path, ": byte ", i, ": malformed attribute in <", t.name, ">");
      std::string key = xml.substr(i, eq - i);
      while (!key.empty() && std::isspace((unsigned char)key.back()))
        key.pop_back();
      size_t q = eq + 1;
      while (q < close && std::isspace((unsigned char)xml[q]))
        ++q;
      if (q >= close || (xml[q] != '"' && xml[q] != '\''))
        fail(path, ": byte ", q, ": attribute '", key, "' of <", t.name, "> is not quoted");
      const size_t qe = xml.find(xml[q], q + 1);
      if (qe == std::string::npos || qe > close) fail(path, ": byte ", q, ": unterminated attribute '", key, "'");
      t.attrs[key] = xml.substr(q + 1, qe - q - 1);
      i = qe + 1;
    }
    const size_t next = std::min(xml.find('<', close + 1), end);
    t.text = xml.substr(close + 1, (next == std::string::npos ? end : next) - close - 1);
    tags.push_back(std::move(t));
    pos = close + 1;
  }
  return tags;
}

std::vector<double> numbers(const std::string& path, const std::string& text, size_t expected,
                            const std::string& what) {
  std::istringstream in(text);
  std::vector<double> v;
  for (double d; in >> d;)
    v.push_back(d);
  if (v.size() != expected || !in.eof()) fail(path, ": ", what, ": expected ", expected, " numbers, got '", text, "'");
  for (double d : v)
    if (!std::isfinite(d)) fail(path, ": ", what, ": not finite");
  return v;
}

/// Byte order, header width and compression of one VTKFile.
struct Encoding {
  bool bigEndian = false;
  size_t headerBytes = 4;
  bool zlib = false;
};

Encoding encodingOf(const std::string& path, const Tag& vtkFile) {
  Encoding e;
  const std::string order = vtkFile.attr("byte_order", "LittleEndian");
  if (order == "BigEndian")
    e.bigEndian = true;
  else if (order != "LittleEndian")
    fail(path, ": unknown byte_order '", order, "'");
  const std::string header = vtkFile.attr("header_type", "UInt32");
  if (header == "UInt64")
    e.headerBytes = 8;
  else if (header != "UInt32")
    fail(path, ": unsupported header_type '", header, "' (UInt32 and UInt64 are read)");
  const std::string compressor = vtkFile.attr("compressor");
  if (compressor == "vtkZLibDataCompressor")
    e.zlib = true;
  else if (!compressor.empty())
    fail(path, ": compressor '", compressor,
         "' is not supported (vtkZLibDataCompressor is; re-save without compression)");
  return e;
}

std::string decodeBase64(const std::string& path, const std::string& what, const std::string& text, size_t& consumed,
                         size_t wantBytes) {
  static int8_t table[256];
  static bool init = [] {
    std::fill(std::begin(table), std::end(table), int8_t(-1));
    const char* a = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    for (int i = 0; i < 64; ++i)
      table[(unsigned char)a[i]] = int8_t(i);
    return true;
  }();
  (void)init;
  // Decodes whole 4-character groups from `consumed` until `wantBytes` bytes are out (or the
  // text ends); whitespace is skipped.
  std::string out;
  uint32_t acc = 0;
  int n = 0, pad = 0;
  size_t i = consumed;
  for (; i < text.size() && out.size() < wantBytes; ++i) {
    const unsigned char c = (unsigned char)text[i];
    if (std::isspace(c)) continue;
    if (c == '=') {
      ++pad;
      acc <<= 6;
    } else {
      if (table[c] < 0 || pad) fail(path, ": ", what, ": invalid base64 data");
      acc = (acc << 6) | uint32_t(table[c]);
    }
    if (++n == 4) {
      out.push_back(char((acc >> 16) & 0xff));
      if (pad < 2) out.push_back(char((acc >> 8) & 0xff));
      if (pad < 1) out.push_back(char(acc & 0xff));
      n = 0;
      acc = 0;
      if (pad) {
        ++i;
        break;
      }
    }
  }
  if (n != 0) fail(path, ": ", what, ": truncated base64 data");
  consumed = i;
  return out;
}

/// A data block as VTK writes it: a header (byte count, or block table when compressed) and the
/// bytes. `src` is the raw bytes of an appended block or the decoded base64 stream.
class BlockSource {
public:
  virtual ~BlockSource() = default;
  /// The next `n` bytes (throws when there are fewer).
  virtual std::string take(size_t n) = 0;
  /// An upper bound of the bytes left: declared sizes are checked against it before anything
  /// is allocated for them.
  virtual uint64_t left() const = 0;
};

class RawSource : public BlockSource {
public:
  RawSource(const std::string& path, const std::string& what, const std::string& data, size_t at)
      : path_(path), what_(what), data_(data), at_(at) {}
  std::string take(size_t n) override {
    if (at_ > data_.size() || n > data_.size() - at_) fail(path_, ": ", what_, ": truncated appended data");
    std::string s = data_.substr(at_, n);
    at_ += n;
    return s;
  }
  uint64_t left() const override { return at_ > data_.size() ? 0 : data_.size() - at_; }

private:
  const std::string &path_, &what_, &data_;
  size_t at_;
};

class Base64Source : public BlockSource {
public:
  Base64Source(const std::string& path, const std::string& what, const std::string& text)
      : path_(path), what_(what), text_(text) {}
  std::string take(size_t n) override {
    // VTK encodes the header and the (compressed) data as separate base64 streams, but the
    // uncompressed form as one; keep decoded leftovers so both work.
    while (buffer_.size() < n) {
      const std::string more = decodeBase64(path_, what_, text_, consumed_, n - buffer_.size());
      if (more.empty()) fail(path_, ": ", what_, ": truncated binary data");
      buffer_ += more;
    }
    std::string s = buffer_.substr(0, n);
    buffer_.erase(0, n);
    return s;
  }
  uint64_t left() const override {
    return buffer_.size() + (consumed_ >= text_.size() ? 0 : (text_.size() - consumed_) / 4 * 3 + 3);
  }

private:
  const std::string &path_, &what_, &text_;
  size_t consumed_ = 0;
  std::string buffer_;
};

std::string readBlock(const std::string& path, const std::string& what, BlockSource& src, const Encoding& e,
                      uint64_t expectedBytes) {
  auto header = [&] {
    const std::string h = src.take(e.headerBytes);
    return io::loadUnsigned(reinterpret_cast<const unsigned char*>(h.data()), e.headerBytes, e.bigEndian);
  };
  if (!e.zlib) {
    const uint64_t n = header();
    if (n != expectedBytes) fail(path, ": ", what, ": block holds ", n, " bytes, expected ", expectedBytes);
    io::requireBytes(n, 1, src.left(), strCat(path, ": ", what));
    return src.take(size_t(n));
  }
  // The compression header: block count, nominal block size, size of the last block (0 when it
  // is a whole block), then the compressed size of each block. The nominal size may exceed a
  // small array (VTK writes 32768 for every array), so a single block may be shorter than it.
  const uint64_t blocks = header(), blockSize = header(), lastSize = header();
  const std::string where = strCat(path, ": ", what);
  if (blocks > 0 && blockSize == 0) fail(where, ": corrupt compression header (block size 0)");
  if (lastSize > blockSize)
    fail(where, ": corrupt compression header (last block of ", lastSize, " bytes, block size ", blockSize, ")");
  if (blocks > expectedBytes / std::max<uint64_t>(blockSize, 1) + 1)
    fail(where, ": corrupt compression header (", blocks, " blocks of ", blockSize, " bytes for ", expectedBytes,
         " bytes)");
  const uint64_t total = blocks == 0 ? 0 : (blocks - 1) * blockSize + (lastSize == 0 ? blockSize : lastSize);
  if (total != expectedBytes) fail(where, ": compressed data holds ", total, " bytes, expected ", expectedBytes);
  io::requireBytes(blocks, e.headerBytes, src.left(), where + ": compressed block sizes");
  std::vector<uint64_t> sizes = io::allocate<uint64_t>(blocks, [&] { return where; });
  uint64_t packedTotal = 0;
  for (uint64_t& s : sizes) {
    s = header();
    if (s > src.left() - std::min(src.left(), packedTotal)) // packedTotal stays within the bytes left
      io::requireBytes(packedTotal + std::min(s, UINT64_MAX - packedTotal), 1, src.left(),
                       where + ": compressed blocks");
    packedTotal += s;
  }
  // Inflating never grows a block by more than kMaxInflate: bound the declared size by the
  // bytes present before reserving it.
  uint64_t inflatable = 0;
  if (io::productWithin(packedTotal + 1, io::kMaxInflate, UINT64_MAX, inflatable) && total > inflatable)
    fail(where, ": declares ", total, " bytes, more than its ", packedTotal, " compressed bytes can hold");
  std::string out;
  io::reserveMore(out, total, [&] { return where; });
  for (uint64_t b = 0; b < blocks; ++b) {
    const std::string packed = src.take(size_t(sizes[size_t(b)]));
    uLongf size = uLongf(b + 1 == blocks && lastSize != 0 ? lastSize : blockSize);
    std::string plain(size_t(size), '\0');
    const uLongf want = size;
    if (uncompress(reinterpret_cast<Bytef*>(plain.data()), &size, reinterpret_cast<const Bytef*>(packed.data()),
                   uLong(packed.size())) != Z_OK ||
        size != want)
      fail(path, ": ", what, ": zlib block ", b, " does not decompress (corrupt data)");
    out += plain;
  }
  return out;
}

size_t typeSize(const std::string& type) {
  static const std::map<std::string, size_t> sizes{{"Int8", 1},    {"UInt8", 1},  {"Int16", 2}, {"UInt16", 2},
                                                   {"Int32", 4},   {"UInt32", 4}, {"Int64", 8}, {"UInt64", 8},
                                                   {"Float32", 4}, {"Float64", 8}};
  const auto it = sizes.find(type);
  return it == sizes.end() ? 0 : it->second;
}

double toDouble(const unsigned char* p, const std::string& type, bool bigEndian) {
  const size_t n = typeSize(type);
  const bool swap = io::needsSwap(bigEndian);
  if (type == "Float32") return io::loadScalar<float>(p, swap);
  if (type == "Float64") return io::loadScalar<double>(p, swap);
  const uint64_t u = io::loadUnsigned(p, n, bigEndian);
  if (type[0] == 'U') return double(u);
  const int64_t s = n == 8 ? int64_t(u) : int64_t(u << (64 - 8 * n)) >> (64 - 8 * n);
  return double(s);
}

struct Piece {
  std::string path;
  vec3l cells{0};
  std::map<std::string, std::vector<double>> arrays; ///< only when read
  std::vector<std::string> names;                    ///< scalar cell arrays in file order
};

/// Reads a .vti piece: its extent and the wanted scalar cell arrays (none when `wanted` is null).
Piece readPiece(const std::string& path, const std::vector<std::string>* wanted) {
  Piece piece;
  piece.path = path;
  const std::string data = readFile(path, "piece");
  size_t xmlEnd = data.size(), appendedAt = std::string::npos, appendedEnd = data.size();
  bool appendedBase64 = false;
  const size_t app = data.find("<AppendedData");
  if (app != std::string::npos) {
    xmlEnd = app;
    const size_t close = data.find('>', app);
    const size_t underscore = close == std::string::npos ? close : data.find('_', close);
    if (underscore == std::string::npos) fail(path, ": AppendedData without its '_' marker (truncated file?)");
    const std::string tag = data.substr(app, close - app);
    // VTK's XML writers encode appended data in base64 unless told to write it raw.
    appendedBase64 = tag.find("encoding=\"base64\"") != std::string::npos;
    appendedAt = underscore + 1;
    if (appendedBase64) appendedEnd = std::min(data.size(), data.find("</AppendedData>", appendedAt));
  }
  const std::vector<Tag> tags = scanTags(path, data, xmlEnd);
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
      const auto e = numbers(path, t.attr("Extent"), 6, "Piece Extent");
      int64_t ext[6];
      for (int k = 0; k < 6; ++k)
        ext[k] = io::checkedInteger(e[size_t(k)], -kLatticeLimit, kLatticeLimit,
                                    [&] { return strCat(path, ": Piece Extent"); });
      piece.cells = vec3l(ext[1] - ext[0], ext[3] - ext[2], ext[5] - ext[4]);
      if (piece.cells.x < 0 || piece.cells.y < 0 || piece.cells.z < 0) fail(path, ": Piece Extent is inverted");
      if (piece.cells.x == 0 || piece.cells.y == 0 || piece.cells.z == 0)
        fail(path, ": Piece Extent is flat (2-D data); only 3-D AMR data can be read");
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
      const std::string what = "array '" + name + "'";
      const std::string type = t.attr("type");
      if (typeSize(type) == 0) fail(path, ": ", what, ": unsupported type '", type, "'");
      uint64_t count = 0;
      if (!io::cellCountWithin(piece.cells.x, piece.cells.y, piece.cells.z, uint64_t(1) << 40, count))
        fail(path, ": Piece Extent of ", piece.cells.x, "x", piece.cells.y, "x", piece.cells.z, " cells is too large");
      std::vector<double> values;
      const std::string format = t.attr("format");
      if (format == "ascii") {
        std::istringstream in(t.text);
        for (double d; in >> d;)
          values.push_back(d);
        if (!in.eof()) fail(path, ": ", what, ": malformed ascii value");
      } else if (format == "binary" || format == "appended") {
        std::string bytes;
        const uint64_t expected = count * typeSize(type);
        if (format == "binary") {
          Base64Source src(path, what, t.text);
          bytes = readBlock(path, what, src, enc, expected);
        } else {
          if (appendedAt == std::string::npos) fail(path, ": ", what, ": appended array but no <AppendedData>");
          const std::string off = t.attr("offset");
          char* endp = nullptr;
          const unsigned long long o = std::strtoull(off.c_str(), &endp, 10);
          if (off.empty() || *endp) fail(path, ": ", what, ": bad offset '", off, "'");
          if (appendedBase64) {
            if (o > appendedEnd - appendedAt) fail(path, ": ", what, ": offset ", o, " lies beyond the appended data");
            const std::string text = data.substr(appendedAt + size_t(o), appendedEnd - appendedAt - size_t(o));
            Base64Source src(path, what, text);
            bytes = readBlock(path, what, src, enc, expected);
          } else {
            RawSource src(path, what, data, appendedAt + size_t(o));
            bytes = readBlock(path, what, src, enc, expected);
          }
        }
        const size_t ts = typeSize(type);
        io::reserveMore(values, bytes.size() / ts, [&] { return strCat(path, ": ", what); });
        for (size_t i = 0; i + ts <= bytes.size(); i += ts)
          values.push_back(toDouble(reinterpret_cast<const unsigned char*>(bytes.data() + i), type, enc.bigEndian));
      } else {
        fail(path, ": ", what, ": unknown format '", format, "'");
      }
      if (values.size() != count)
        fail(path, ": ", what, ": ", values.size(), " values for ", count, " cells (truncated or wrong extent?)");
      piece.arrays[name] = std::move(values);
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

CellSet readVtkAmr(const std::string& path, const std::vector<std::string>& wanted) {
  const Hierarchy h = readHierarchy(path);
  const std::vector<std::string> available = readPiece(h.sets.front().file, nullptr).names;
  const std::vector<size_t> picked = io::pickFields(path, available, wanted);
  std::vector<std::string> names;
  for (size_t k : picked)
    names.push_back(available[k]);

  int finestLevel = 0;
  for (const DataSetRef& d : h.sets)
    finestLevel = std::max(finestLevel, d.level);
  std::vector<io::Patch> patches;
  for (const DataSetRef& d : h.sets) {
    const vec3d s = h.spacing.size() > size_t(d.level) ? h.spacing[size_t(d.level)] : vec3d(0.0);
    if (!(s.x > 0)) fail(path, ": level ", d.level, " has datasets but no Block spacing");
    int64_t width = 0;
    for (int a = 0; a < 3; ++a) {
      const double r = s[a] / h.spacing[size_t(finestLevel)][a];
      const double w = std::round(r);
      if (!(w >= 1 && w <= double(int64_t(1) << kMaxLevel)) || std::abs(r - w) > 1e-6 * w ||
          io::log2Exact(int64_t(w)) < 0)
        fail(path, ": level ", d.level, ": spacing is ", r, " times the finest level's, not a power of two");
      if (a > 0 && int64_t(w) != width) fail(path, ": level ", d.level, ": refined differently along the axes");
      width = int64_t(w);
    }
    patches.push_back({d.lo * width, d.hi - d.lo + vec3l(1), width});
  }
  auto name = [&](size_t i) { return strCat(path, ": level ", h.sets[i].level, " DataSet ", h.sets[i].index); };
  // Every box is bounded by the bytes of its piece before per-cell memory is reserved for it:
  // a cell takes at least one byte, or 1/kMaxInflate of a byte compressed. A box whose piece is
  // missing can only be fully covered by finer boxes.
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
  const io::Coverage coverage(patches, name);

  CellSet set;
  for (const std::string& n : names)
    set.fields.push_back({n, {}});
  Progress progress("reading " + path, patches.size());
  for (size_t i = 0; i < patches.size(); ++i) {
    const std::vector<uint8_t> covered = coverage.covered(i);
    if (std::find(covered.begin(), covered.end(), uint8_t(0)) == covered.end()) {
      progress.advance(1);
      continue;
    }
    std::error_code ec;
    if (!fs::exists(h.sets[i].file, ec)) fail(h.sets[i].file, ": missing piece named by ", name(i));
    const Piece piece = readPiece(h.sets[i].file, &names);
    if (!(piece.cells == patches[i].cells))
      fail(piece.path, ": Piece Extent holds ", piece.cells.x, "x", piece.cells.y, "x", piece.cells.z,
           " cells, but the amr_box of ", name(i), " holds ", patches[i].cells.x, "x", patches[i].cells.y, "x",
           patches[i].cells.z);
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
    io::appendLeafCells(set, patches[i], covered, values, name(i));
    progress.advance(1);
  }
  progress.finish();
  set.world.origin = h.origin;
  set.world.scale = h.spacing[size_t(finestLevel)];
  logInfo(strCat("read ", set.cells.size(), " leaf cells of ", patches.size(), " boxes from ", path));
  return set;
}

} // namespace exa
