#include "exabricks/documents/mesh.h"

#include "exabricks/core/error.h"
#include "exabricks/core/files.h"

#include "mesh_files.h"

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

using namespace mesh_files;

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
