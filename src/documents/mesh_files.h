// What the mesh file readers share (documents/mesh.h reads OBJ and .tris in mesh.cpp, PLY in
// mesh_ply.cpp): token and number parsing, the vertex bound and polygon fans.
#pragma once

#include "exabricks/core/mesh.h"

#include <cctype>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <limits>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace exa::mesh_files {

constexpr int64_t kMaxVertices = std::numeric_limits<int32_t>::max();

inline bool isSpace(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\f' || c == '\v'; }
inline bool isSpaceOrNewline(char c) { return isSpace(c) || c == '\n'; }

inline bool finite(const vec3f& v) { return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z); }

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
inline std::optional<float> parseCoordinate(std::string_view token) {
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

inline void appendFan(TriangleMesh& mesh, const std::vector<int32_t>& polygon) {
  for (size_t k = 1; k + 1 < polygon.size(); ++k)
    mesh.triangles.push_back(vec3i(polygon[0], polygon[k], polygon[k + 1]));
}

/// Reads a PLY file's bytes (ASCII or binary, either byte order).
TriangleMesh readPly(const std::string& path, const char* data, size_t size);

} // namespace exa::mesh_files
