#include "exabricks/documents/mesh.h"

#include "exabricks/core/error.h"
#include "exabricks/core/files.h"

#include "exabricks/core/byte_order.h"

#include <bit>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <limits>
#include <optional>
#include <ostream>
#include <string_view>
#include <utility>

namespace exa {

namespace {

constexpr int64_t kMaxVertices = std::numeric_limits<int32_t>::max();

bool isSpace(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\f' || c == '\v'; }
bool isSpaceOrNewline(char c) { return isSpace(c) || c == '\n'; }

bool finite(const vec3f& v) { return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z); }

/// Parses the whole of `token` as a number; a leading '+' is accepted.
template <typename T> std::optional<T> parseNumber(std::string_view token) {
  if (!token.empty() && token.front() == '+') token.remove_prefix(1);
  if (token.empty()) return std::nullopt;
  T value{};
  const auto [end, ec] = std::from_chars(token.data(), token.data() + token.size(), value);
  if (ec != std::errc() || end != token.data() + token.size()) return std::nullopt;
  return value;
}

/// Parses a float coordinate; out-of-range numbers become infinite so that they are reported as
/// non-finite rather than as malformed.
std::optional<float> parseCoordinate(std::string_view token) {
  const std::optional<double> d = parseNumber<double>(token);
  if (!d) {
    // from_chars reports overflow as an error; classify such numbers as infinite.
    std::string_view t = token;
    if (!t.empty() && (t.front() == '+' || t.front() == '-')) t.remove_prefix(1);
    if (!t.empty() && (std::isdigit(static_cast<unsigned char>(t.front())) || t.front() == '.'))
      if (t.find_first_not_of("0123456789.eE+-") == std::string_view::npos)
        return std::numeric_limits<float>::infinity();
    return std::nullopt;
  }
  if (std::isfinite(*d) && std::fabs(*d) > double(std::numeric_limits<float>::max()))
    return std::numeric_limits<float>::infinity();
  return float(*d);
}

/// Splits one line into whitespace-separated tokens.
class Tokens {
public:
  explicit Tokens(std::string_view line) : rest_(line) {}
  std::optional<std::string_view> next() {
    size_t i = 0;
    while (i < rest_.size() && isSpace(rest_[i]))
      ++i;
    if (i == rest_.size()) return std::nullopt;
    size_t j = i;
    while (j < rest_.size() && !isSpace(rest_[j]))
      ++j;
    const std::string_view token = rest_.substr(i, j - i);
    rest_.remove_prefix(j);
    return token;
  }

private:
  std::string_view rest_;
};

void appendFan(TriangleMesh& mesh, const std::vector<int32_t>& polygon) {
  for (size_t k = 1; k + 1 < polygon.size(); ++k)
    mesh.triangles.push_back(vec3i(polygon[0], polygon[k], polygon[k + 1]));
}

// ---------------------------------------------------------------------------------------------
// OBJ

/// Checks the optional "/t", "/t/n" or "//n" tail of a face corner.
bool validCornerTail(std::string_view tail) {
  if (tail.empty()) return true;
  if (tail.front() != '/') return false;
  tail.remove_prefix(1);
  const size_t slash = tail.find('/');
  const std::string_view t = tail.substr(0, slash);
  if (!t.empty() && !parseNumber<int64_t>(t)) return false;
  if (slash == std::string_view::npos) return true;
  const std::string_view n = tail.substr(slash + 1);
  return n.empty() || parseNumber<int64_t>(n).has_value();
}

TriangleMesh readObj(const std::string& path, const char* data, size_t size) {
  TriangleMesh mesh;
  std::vector<int32_t> polygon;
  // Faces that reference vertices defined further down: checked once every vertex is known.
  std::vector<std::pair<size_t, int64_t>> forward;
  const char* p = data;
  const char* const end = data + size;
  size_t lineNo = 0;
  while (p < end) {
    ++lineNo;
    const char* nl = static_cast<const char*>(std::memchr(p, '\n', size_t(end - p)));
    const char* lineEnd = nl ? nl : end;
    std::string_view line(p, size_t(lineEnd - p));
    p = nl ? nl + 1 : end;
    if (const size_t hash = line.find('#'); hash != std::string_view::npos) line = line.substr(0, hash);
    Tokens tokens(line);
    const std::optional<std::string_view> keyword = tokens.next();
    if (!keyword) continue;
    if (*keyword == "v") {
      vec3f v;
      for (int a = 0; a < 3; ++a) {
        const std::optional<std::string_view> t = tokens.next();
        if (!t) fail(path, ": line ", lineNo, ": malformed 'v' line: expected three coordinates, got ", a);
        const std::optional<float> c = parseCoordinate(*t);
        if (!c) fail(path, ": line ", lineNo, ": malformed 'v' line: '", *t, "' is not a number");
        v[a] = *c;
      }
      if (!finite(v)) fail(path, ": line ", lineNo, ": vertex coordinate is NaN or infinite");
      if (int64_t(mesh.vertices.size()) >= kMaxVertices)
        fail(path, ": line ", lineNo, ": too many vertices (more than ", kMaxVertices, ")");
      mesh.vertices.push_back(v);
    } else if (*keyword == "f") {
      polygon.clear();
      int64_t maxIndex = -1;
      const int64_t known = int64_t(mesh.vertices.size());
      while (const std::optional<std::string_view> t = tokens.next()) {
        const size_t slash = t->find('/');
        const std::string_view head = t->substr(0, slash);
        const std::optional<int64_t> index = parseNumber<int64_t>(head);
        if (!index || !validCornerTail(slash == std::string_view::npos ? std::string_view() : t->substr(slash)))
          fail(path, ": line ", lineNo, ": malformed 'f' line: '", *t, "' is not a vertex reference");
        int64_t resolved = 0;
        if (*index > 0)
          resolved = *index - 1;
        else if (*index < 0)
          resolved = known + *index;
        else
          fail(path, ": line ", lineNo, ": vertex index 0 is invalid (OBJ indices start at 1)");
        if (resolved < 0 || resolved >= kMaxVertices)
          fail(path, ": line ", lineNo, ": vertex index ", *index, " out of range (", known,
               " vertices defined so far)");
        maxIndex = std::max(maxIndex, resolved);
        polygon.push_back(int32_t(resolved));
      }
      if (polygon.size() < 3)
        fail(path, ": line ", lineNo, ": malformed 'f' line: a face needs at least 3 vertices, got ", polygon.size());
      if (maxIndex >= known) forward.emplace_back(lineNo, maxIndex);
      appendFan(mesh, polygon);
    }
    // Every other statement (vt, vn, vp, g, o, s, l, usemtl, mtllib, extensions) is ignored.
  }
  for (const auto& [line, index] : forward)
    if (index >= int64_t(mesh.vertices.size()))
      fail(path, ": line ", line, ": vertex index ", index + 1, " out of range (", mesh.vertices.size(),
           " vertices in the file)");
  return mesh;
}

// ---------------------------------------------------------------------------------------------
// PLY

enum class PlyType : uint8_t { Int8, UInt8, Int16, UInt16, Int32, UInt32, Float32, Float64 };

bool plyType(std::string_view name, PlyType& type) {
  static constexpr std::pair<std::string_view, PlyType> names[] = {
      {"char", PlyType::Int8},      {"int8", PlyType::Int8},       {"uchar", PlyType::UInt8},
      {"uint8", PlyType::UInt8},    {"short", PlyType::Int16},     {"int16", PlyType::Int16},
      {"ushort", PlyType::UInt16},  {"uint16", PlyType::UInt16},   {"int", PlyType::Int32},
      {"int32", PlyType::Int32},    {"uint", PlyType::UInt32},     {"uint32", PlyType::UInt32},
      {"float", PlyType::Float32},  {"float32", PlyType::Float32}, {"double", PlyType::Float64},
      {"float64", PlyType::Float64}};
  for (const auto& [n, t] : names)
    if (n == name) {
      type = t;
      return true;
    }
  return false;
}

size_t typeSize(PlyType t) {
  switch (t) {
  case PlyType::Int8:
  case PlyType::UInt8:
    return 1;
  case PlyType::Int16:
  case PlyType::UInt16:
    return 2;
  case PlyType::Int32:
  case PlyType::UInt32:
  case PlyType::Float32:
    return 4;
  case PlyType::Float64:
    return 8;
  }
  return 0;
}

bool isIntegerType(PlyType t) { return t != PlyType::Float32 && t != PlyType::Float64; }

enum class PlyFormat { Ascii, BinaryLittle, BinaryBig };

struct PlyProperty {
  std::string name;
  bool list = false;
  PlyType type = PlyType::Float32;    ///< value type, or item type of a list
  PlyType countType = PlyType::UInt8; ///< list count type
};

struct PlyElement {
  std::string name;
  uint64_t count = 0;
  std::vector<PlyProperty> properties;
};

struct PlyHeader {
  PlyFormat format = PlyFormat::Ascii;
  std::vector<PlyElement> elements;
  size_t dataOffset = 0;
  size_t dataLine = 0; ///< line number of the first data line (ascii)
};

PlyHeader readPlyHeader(const std::string& path, const char* data, size_t size) {
  PlyHeader header;
  bool haveFormat = false, done = false;
  size_t pos = 0, lineNo = 0;
  while (pos < size && !done) {
    ++lineNo;
    const char* nl = static_cast<const char*>(std::memchr(data + pos, '\n', size - pos));
    if (!nl) fail(path, ": line ", lineNo, ": PLY header has no 'end_header' line");
    const std::string_view line(data + pos, size_t(nl - (data + pos)));
    pos = size_t(nl - data) + 1;
    Tokens tokens(line);
    const std::optional<std::string_view> keyword = tokens.next();
    if (lineNo == 1) {
      if (!keyword || *keyword != "ply" || tokens.next()) fail(path, ": line 1: missing 'ply' magic line");
      continue;
    }
    if (!keyword) continue;
    if (*keyword == "comment" || *keyword == "obj_info") continue;
    if (*keyword == "format") {
      const std::optional<std::string_view> f = tokens.next();
      const std::optional<std::string_view> version = tokens.next();
      if (!f) fail(path, ": line ", lineNo, ": 'format' without a format name");
      if (*f == "ascii")
        header.format = PlyFormat::Ascii;
      else if (*f == "binary_little_endian")
        header.format = PlyFormat::BinaryLittle;
      else if (*f == "binary_big_endian")
        header.format = PlyFormat::BinaryBig;
      else
        fail(path, ": line ", lineNo, ": unknown PLY format '", *f, "'");
      if (!version || *version != "1.0")
        fail(path, ": line ", lineNo, ": unsupported PLY version '", version.value_or(""), "' (expected 1.0)");
      haveFormat = true;
    } else if (*keyword == "element") {
      const std::optional<std::string_view> name = tokens.next();
      const std::optional<std::string_view> count = tokens.next();
      if (!name || !count) fail(path, ": line ", lineNo, ": expected 'element NAME COUNT'");
      if (!count->empty() && count->front() == '-')
        fail(path, ": line ", lineNo, ": element '", *name, "' has a negative count ", *count);
      const std::optional<uint64_t> n = parseNumber<uint64_t>(*count);
      if (!n) fail(path, ": line ", lineNo, ": element '", *name, "' count '", *count, "' is not a count");
      header.elements.push_back(PlyElement{std::string(*name), *n, {}});
    } else if (*keyword == "property") {
      if (header.elements.empty()) fail(path, ": line ", lineNo, ": 'property' before any 'element'");
      PlyProperty prop;
      std::optional<std::string_view> t = tokens.next();
      if (t && *t == "list") {
        prop.list = true;
        const std::string_view ct = tokens.next().value_or("");
        const std::string_view it = tokens.next().value_or("");
        if (!plyType(ct, prop.countType) || !plyType(it, prop.type))
          fail(path, ": line ", lineNo, ": expected 'property list COUNTTYPE ITEMTYPE NAME' with",
               " known types, got '", ct, "' and '", it, "'");
        if (!isIntegerType(prop.countType))
          fail(path, ": line ", lineNo, ": list count type '", ct, "' is not an integer type");
      } else if (!plyType(t.value_or(""), prop.type)) {
        fail(path, ": line ", lineNo, ": unknown property type '", t.value_or(""), "'");
      }
      const std::optional<std::string_view> name = tokens.next();
      if (!name) fail(path, ": line ", lineNo, ": property without a name");
      prop.name = std::string(*name);
      header.elements.back().properties.push_back(std::move(prop));
    } else if (*keyword == "end_header") {
      done = true;
    } else {
      fail(path, ": line ", lineNo, ": unknown PLY header line '", *keyword, "'");
    }
  }
  if (!done) fail(path, ": PLY header has no 'end_header' line");
  if (!haveFormat) fail(path, ": PLY header has no 'format' line");
  header.dataOffset = pos;
  header.dataLine = lineNo + 1;
  return header;
}

/// What the reader does with one property of the vertex or face element.
enum class Role : uint8_t { Skip, X, Y, Z, Indices };

struct PlyLayout {
  const PlyElement* vertex = nullptr;
  const PlyElement* face = nullptr;
  std::vector<std::vector<Role>> roles; ///< per element, per property
};

PlyLayout planPly(const std::string& path, const PlyHeader& header) {
  PlyLayout layout;
  for (const PlyElement& e : header.elements) {
    std::vector<Role> roles(e.properties.size(), Role::Skip);
    if (e.name == "vertex" && !layout.vertex) {
      layout.vertex = &e;
      const char* axes[3] = {"x", "y", "z"};
      for (int a = 0; a < 3; ++a) {
        bool found = false;
        for (size_t j = 0; j < e.properties.size() && !found; ++j)
          if (e.properties[j].name == axes[a] && !e.properties[j].list) {
            roles[j] = Role(int(Role::X) + a);
            found = true;
          }
        if (!found) fail(path, ": PLY vertex element has no scalar '", axes[a], "' property");
      }
    } else if (e.name == "face" && !layout.face) {
      layout.face = &e;
      bool found = false;
      for (size_t j = 0; j < e.properties.size() && !found; ++j) {
        const PlyProperty& p = e.properties[j];
        if (p.list && (p.name == "vertex_indices" || p.name == "vertex_index")) {
          if (!isIntegerType(p.type)) fail(path, ": PLY face property '", p.name, "' has a non-integer index type");
          roles[j] = Role::Indices;
          found = true;
        }
      }
      if (!found) fail(path, ": PLY face element has no 'vertex_indices' list property");
    }
    layout.roles.push_back(std::move(roles));
  }
  if (!layout.vertex) fail(path, ": PLY header has no 'vertex' element");
  if (!layout.face || layout.face->count == 0) fail(path, ": no triangles (empty mesh: PLY header has no faces)");
  if (layout.vertex->count > uint64_t(kMaxVertices))
    fail(path, ": PLY vertex count ", layout.vertex->count, " exceeds the supported ", kMaxVertices);
  return layout;
}

/// Rejects counts that the remaining bytes cannot hold before anything is allocated. `minBytes`
/// gives the smallest encoding of one element.
void checkCounts(const std::string& path, const PlyHeader& header, size_t size) {
  const bool ascii = header.format == PlyFormat::Ascii;
  uint64_t remaining = size - header.dataOffset;
  // In ascii every value takes at least one character and one separator (the very last value
  // may lack its separator).
  if (ascii) remaining += 1;
  for (const PlyElement& e : header.elements) {
    uint64_t minBytes = 0;
    for (const PlyProperty& p : e.properties)
      minBytes += ascii ? 2 : typeSize(p.list ? p.countType : p.type);
    if (minBytes == 0) continue;
    if (e.count > remaining / minBytes)
      fail(path, ": PLY element '", e.name, "' count ", e.count, " exceeds what the file size allows (",
           size - header.dataOffset, " data bytes, at least ", minBytes, " per element)");
    remaining -= e.count * minBytes;
  }
}

double loadNumber(PlyType t, const unsigned char* p, bool swap) {
  switch (t) {
  case PlyType::Int8:
    return io::loadScalar<int8_t>(p, swap);
  case PlyType::UInt8:
    return io::loadScalar<uint8_t>(p, swap);
  case PlyType::Int16:
    return io::loadScalar<int16_t>(p, swap);
  case PlyType::UInt16:
    return io::loadScalar<uint16_t>(p, swap);
  case PlyType::Int32:
    return io::loadScalar<int32_t>(p, swap);
  case PlyType::UInt32:
    return io::loadScalar<uint32_t>(p, swap);
  case PlyType::Float32:
    return io::loadScalar<float>(p, swap);
  case PlyType::Float64:
    return io::loadScalar<double>(p, swap);
  }
  return 0;
}

int64_t loadInteger(PlyType t, const unsigned char* p, bool swap) {
  switch (t) {
  case PlyType::Int8:
    return io::loadScalar<int8_t>(p, swap);
  case PlyType::UInt8:
    return io::loadScalar<uint8_t>(p, swap);
  case PlyType::Int16:
    return io::loadScalar<int16_t>(p, swap);
  case PlyType::UInt16:
    return io::loadScalar<uint16_t>(p, swap);
  case PlyType::Int32:
    return io::loadScalar<int32_t>(p, swap);
  case PlyType::UInt32:
    return io::loadScalar<uint32_t>(p, swap);
  default:
    return -1; // float types are rejected for counts and indices in the header
  }
}

float toCoordinate(double d) {
  if (std::isfinite(d) && std::fabs(d) > double(std::numeric_limits<float>::max()))
    return std::numeric_limits<float>::infinity();
  return float(d);
}

/// Where a PLY record starts: a byte offset (binary) or a line number (ascii); formatted only
/// when an error is reported.
struct Where {
  const char* unit;
  size_t value;
};
std::ostream& operator<<(std::ostream& out, const Where& w) { return out << " (" << w.unit << " " << w.value << ")"; }

/// Reads the data section of a PLY file: one pass over all elements in file order.
class PlyReader {
public:
  PlyReader(const std::string& path, const char* data, size_t size, const PlyHeader& header, const PlyLayout& layout)
      : path_(path), data_(data), size_(size), header_(header), layout_(layout) {}

  TriangleMesh read() {
    // Counts were checked against the file size; reserve no more triangles than the data bytes
    // could hold if every face were a triangle.
    const bool ascii = header_.format == PlyFormat::Ascii;
    size_t faceBytes = ascii ? 6 : 0;
    for (const PlyProperty& p : layout_.face->properties)
      faceBytes += ascii ? 2 : typeSize(p.list ? p.countType : p.type);
    for (const PlyProperty& p : layout_.face->properties)
      if (p.list && (p.name == "vertex_indices" || p.name == "vertex_index")) {
        if (!ascii) faceBytes += 3 * typeSize(p.type);
        break;
      }
    mesh_.vertices.reserve(layout_.vertex->count);
    mesh_.triangles.reserve(std::min<uint64_t>(layout_.face->count, (size_ - header_.dataOffset) / faceBytes));
    numVertices_ = int64_t(layout_.vertex->count);
    if (header_.format == PlyFormat::Ascii)
      readAscii();
    else
      readBinary(io::needsSwap(header_.format == PlyFormat::BinaryBig));
    return std::move(mesh_);
  }

private:
  void addIndex(const PlyElement& e, uint64_t i, int64_t index, Where where) {
    if (index < 0 || index >= numVertices_)
      fail(path_, ": PLY element '", e.name, "' ", i, where, ": vertex index ", index, " out of range [0, ",
           numVertices_, ")");
    polygon_.push_back(int32_t(index));
  }
  void finishFace(const PlyElement& e, uint64_t i, Where where) {
    if (polygon_.size() < 3)
      fail(path_, ": PLY element '", e.name, "' ", i, where, ": a face needs at least 3 vertices, got ",
           polygon_.size());
    appendFan(mesh_, polygon_);
  }
  void finishVertex(const PlyElement& e, uint64_t i, const vec3f& v, Where where) {
    if (!finite(v)) fail(path_, ": PLY element '", e.name, "' ", i, where, ": vertex coordinate is NaN or infinite");
    mesh_.vertices.push_back(v);
  }

  Where byteAt(const unsigned char* p) const {
    return {"byte", size_t(p - reinterpret_cast<const unsigned char*>(data_))};
  }

  void readBinary(bool swap) {
    const auto* p = reinterpret_cast<const unsigned char*>(data_) + header_.dataOffset;
    const auto* const end = reinterpret_cast<const unsigned char*>(data_) + size_;
    for (size_t ei = 0; ei < header_.elements.size(); ++ei) {
      const PlyElement& e = header_.elements[ei];
      const std::vector<Role>& roles = layout_.roles[ei];
      if (e.properties.empty()) continue;
      const bool isVertex = &e == layout_.vertex, isFace = &e == layout_.face;
      for (uint64_t i = 0; i < e.count; ++i) {
        const unsigned char* const start = p;
        vec3f v;
        polygon_.clear();
        for (size_t j = 0; j < e.properties.size(); ++j) {
          const PlyProperty& prop = e.properties[j];
          if (!prop.list) {
            const size_t n = typeSize(prop.type);
            if (size_t(end - p) < n) truncated(e, i, start);
            if (roles[j] != Role::Skip) v[int(roles[j]) - int(Role::X)] = toCoordinate(loadNumber(prop.type, p, swap));
            p += n;
            continue;
          }
          const size_t cn = typeSize(prop.countType);
          if (size_t(end - p) < cn) truncated(e, i, start);
          const int64_t count = loadInteger(prop.countType, p, swap);
          if (count < 0)
            fail(path_, ": PLY element '", e.name, "' ", i, byteAt(start), ": negative list count ", count);
          p += cn;
          const size_t in = typeSize(prop.type);
          if (uint64_t(count) > uint64_t(end - p) / in) truncated(e, i, start);
          if (roles[j] == Role::Indices) {
            const Where where = byteAt(start);
            for (int64_t k = 0; k < count; ++k, p += in)
              addIndex(e, i, loadInteger(prop.type, p, swap), where);
          } else {
            p += size_t(count) * in;
          }
        }
        if (isVertex) finishVertex(e, i, v, byteAt(start));
        if (isFace) finishFace(e, i, byteAt(start));
      }
    }
  }

  [[noreturn]] void truncated(const PlyElement& e, uint64_t i, const unsigned char* start) const {
    fail(path_, ": PLY element '", e.name, "' ", i, byteAt(start), ": truncated data (file ends at byte ", size_, ")");
  }

  void readAscii() {
    const char* p = data_ + header_.dataOffset;
    const char* const end = data_ + size_;
    size_t line = header_.dataLine;
    auto next = [&]() -> std::string_view {
      while (p < end && isSpaceOrNewline(*p)) {
        if (*p == '\n') ++line;
        ++p;
      }
      const char* s = p;
      while (p < end && !isSpaceOrNewline(*p))
        ++p;
      return std::string_view(s, size_t(p - s));
    };
    for (size_t ei = 0; ei < header_.elements.size(); ++ei) {
      const PlyElement& e = header_.elements[ei];
      const std::vector<Role>& roles = layout_.roles[ei];
      if (e.properties.empty()) continue;
      const bool isVertex = &e == layout_.vertex, isFace = &e == layout_.face;
      for (uint64_t i = 0; i < e.count; ++i) {
        vec3f v;
        polygon_.clear();
        auto token = [&]() {
          const std::string_view t = next();
          if (t.empty())
            fail(path_, ": PLY element '", e.name, "' ", i, " (line ", line, "): truncated data (file ends early)");
          return t;
        };
        auto integer = [&](std::string_view t) {
          const std::optional<int64_t> n = parseNumber<int64_t>(t);
          if (!n) fail(path_, ": PLY element '", e.name, "' ", i, " (line ", line, "): '", t, "' is not an integer");
          return *n;
        };
        for (size_t j = 0; j < e.properties.size(); ++j) {
          const PlyProperty& prop = e.properties[j];
          if (!prop.list) {
            const std::string_view t = token();
            if (roles[j] != Role::Skip) {
              const std::optional<float> c = parseCoordinate(t);
              if (!c) fail(path_, ": PLY element '", e.name, "' ", i, " (line ", line, "): '", t, "' is not a number");
              v[int(roles[j]) - int(Role::X)] = *c;
            }
            continue;
          }
          const int64_t count = integer(token());
          if (count < 0)
            fail(path_, ": PLY element '", e.name, "' ", i, " (line ", line, "): negative list count ", count);
          // Each list item takes at least two bytes; reject counts the rest of the file cannot hold.
          if (uint64_t(count) > uint64_t(end - p) / 2 + 1)
            fail(path_, ": PLY element '", e.name, "' ", i, " (line ", line, "): truncated data (list count ", count,
                 " exceeds the rest of the file)");
          const Where where{"line", line};
          for (int64_t k = 0; k < count; ++k) {
            const std::string_view t = token();
            if (roles[j] == Role::Indices) addIndex(e, i, integer(t), where);
          }
        }
        if (isVertex) finishVertex(e, i, v, Where{"line", line});
        if (isFace) finishFace(e, i, Where{"line", line});
      }
    }
  }

  const std::string& path_;
  const char* data_;
  size_t size_;
  const PlyHeader& header_;
  const PlyLayout& layout_;
  TriangleMesh mesh_;
  std::vector<int32_t> polygon_;
  int64_t numVertices_ = 0;
};

TriangleMesh readPly(const std::string& path, const char* data, size_t size) {
  const PlyHeader header = readPlyHeader(path, data, size);
  const PlyLayout layout = planPly(path, header);
  checkCounts(path, header, size);
  return PlyReader(path, data, size, header, layout).read();
}

// ---------------------------------------------------------------------------------------------
// .tris

int32_t loadInt32LE(const char* p) {
  return io::loadScalar<int32_t>(reinterpret_cast<const unsigned char*>(p), io::needsSwap(false));
}
float loadFloatLE(const char* p) {
  return io::loadScalar<float>(reinterpret_cast<const unsigned char*>(p), io::needsSwap(false));
}

/// True when the counts chain through the whole file exactly (one mesh at least).
bool looksLikeTris(const char* data, size_t size) {
  size_t pos = 0;
  int meshes = 0;
  while (pos < size) {
    for (int part = 0; part < 2; ++part) { // vertices, then triangles: 12 bytes each
      if (size - pos < 4) return false;
      const int32_t n = loadInt32LE(data + pos);
      pos += 4;
      if (n < 0 || uint64_t(n) > (size - pos) / 12) return false;
      pos += size_t(n) * 12;
    }
    ++meshes;
  }
  return meshes > 0;
}

TriangleMesh readTris(const std::string& path, const char* data, size_t size) {
  TriangleMesh mesh;
  size_t pos = 0;
  for (size_t m = 0; pos < size; ++m) {
    auto count = [&](const char* what) -> size_t {
      if (size - pos < 4)
        fail(path, ": mesh ", m, " (byte ", pos, "): truncated data: no room for the ", what, " count");
      const int32_t n = loadInt32LE(data + pos);
      if (n < 0) fail(path, ": mesh ", m, " (byte ", pos, "): negative ", what, " count ", n);
      if (uint64_t(n) > (size - pos - 4) / 12)
        fail(path, ": mesh ", m, " (byte ", pos, "): ", what, " count ", n, " exceeds what the file size allows (",
             size - pos - 4, " bytes left)");
      pos += 4;
      return size_t(n);
    };
    const size_t numVerts = count("vertex");
    const int64_t base = int64_t(mesh.vertices.size());
    if (base + int64_t(numVerts) > kMaxVertices)
      fail(path, ": mesh ", m, " (byte ", pos - 4, "): too many vertices in total (more than ", kMaxVertices, ")");
    mesh.vertices.reserve(mesh.vertices.size() + numVerts);
    for (size_t i = 0; i < numVerts; ++i, pos += 12) {
      const vec3f v(loadFloatLE(data + pos), loadFloatLE(data + pos + 4), loadFloatLE(data + pos + 8));
      if (!finite(v)) fail(path, ": mesh ", m, " vertex ", i, " (byte ", pos, "): coordinate is NaN or infinite");
      mesh.vertices.push_back(v);
    }
    const size_t numTris = count("triangle");
    mesh.triangles.reserve(mesh.triangles.size() + numTris);
    for (size_t i = 0; i < numTris; ++i, pos += 12) {
      vec3i t;
      for (int a = 0; a < 3; ++a) {
        const int32_t index = loadInt32LE(data + pos + 4 * size_t(a));
        if (index < 0 || size_t(index) >= numVerts)
          fail(path, ": mesh ", m, " triangle ", i, " (byte ", pos, "): vertex index ", index, " out of range [0, ",
               numVerts, ")");
        t[a] = int32_t(base + index);
      }
      mesh.triangles.push_back(t);
    }
  }
  return mesh;
}

std::string lowerExtension(const std::string& path) {
  std::string ext = std::filesystem::path(path).extension().string();
  for (char& c : ext)
    c = char(std::tolower(static_cast<unsigned char>(c)));
  return ext;
}

bool hasPlyMagic(const char* data, size_t size) {
  return size >= 4 && std::memcmp(data, "ply", 3) == 0 && (data[3] == '\n' || data[3] == '\r');
}

} // namespace

TriangleMesh readMesh(const std::string& path) {
  const std::vector<char> bytes = readFile(path);
  const char* data = bytes.data();
  const size_t size = bytes.size();
  if (size == 0) fail(path, ": empty file (no triangles)");
  const std::string ext = lowerExtension(path);
  TriangleMesh mesh;
  if (hasPlyMagic(data, size))
    mesh = readPly(path, data, size);
  else if (ext == ".ply")
    fail(path, ": line 1: missing 'ply' magic line");
  else if (ext == ".obj")
    mesh = readObj(path, data, size);
  else if (ext == ".tris" || looksLikeTris(data, size))
    mesh = readTris(path, data, size);
  else
    fail(path, ": unknown mesh format (expected a PLY file, an .obj file or a .tris file)");
  if (mesh.triangles.empty()) fail(path, ": no triangles (empty mesh)");
  return mesh;
}

} // namespace exa
