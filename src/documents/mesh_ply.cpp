#include "mesh_files.h"

#include "exabricks/core/byte_order.h"
#include "exabricks/core/error.h"

#include <bit>
#include <cstring>
#include <utility>

namespace exa::mesh_files {
namespace {

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

} // namespace

TriangleMesh readPly(const std::string& path, const char* data, size_t size) {
  const PlyHeader header = readPlyHeader(path, data, size);
  const PlyLayout layout = planPly(path, header);
  checkCounts(path, header, size);
  return PlyReader(path, data, size, header, layout).read();
}

} // namespace exa::mesh_files
