#include "exabricks/render/transfer_function.h"

#include "exabricks/core/error.h"
#include "exabricks/io/image.h"

#include <nlohmann/json.hpp>

#include <cerrno>
#include <cmath>
#include <cstring>
#include <fstream>

namespace exa {
namespace {

/// Colour map from evenly spaced sRGB anchors (0xRRGGBB), stored in linear RGB.
ColorMap fromHex(const std::string& name, std::initializer_list<uint32_t> hex) {
  ColorMap m;
  m.name = name;
  const size_t n = hex.size();
  size_t i = 0;
  for (uint32_t h : hex) {
    m.positions.push_back(float(i++) / float(n - 1));
    m.colors.push_back(vec3f(srgbToLinear(float((h >> 16) & 255) / 255.f), srgbToLinear(float((h >> 8) & 255) / 255.f),
                             srgbToLinear(float(h & 255) / 255.f)));
  }
  return m;
}

float opacityAt(const std::vector<OpacityPoint>& points, float t) {
  if (points.empty()) return t;
  if (t <= points.front().x) return points.front().alpha;
  if (t >= points.back().x) return points.back().alpha;
  for (size_t i = 1; i < points.size(); ++i)
    if (t <= points[i].x) {
      const OpacityPoint& a = points[i - 1];
      const OpacityPoint& b = points[i];
      const float f = b.x > a.x ? (t - a.x) / (b.x - a.x) : 1.f;
      return a.alpha + (b.alpha - a.alpha) * f;
    }
  return points.back().alpha;
}

} // namespace

vec3f ColorMap::at(float t) const {
  if (positions.empty()) return vec3f(t);
  t = std::clamp(t, 0.f, 1.f);
  if (t <= positions.front()) return colors.front();
  if (t >= positions.back()) return colors.back();
  for (size_t i = 1; i < positions.size(); ++i)
    if (t <= positions[i]) {
      const float span = positions[i] - positions[i - 1];
      const float f = span > 0.f ? (t - positions[i - 1]) / span : 1.f;
      return colors[i - 1] + (colors[i] - colors[i - 1]) * f;
    }
  return colors.back();
}

const std::vector<std::string>& builtinColorMapNames() {
  static const std::vector<std::string> names = {"viridis", "plasma", "inferno", "magma", "cool-to-warm", "grayscale"};
  return names;
}

ColorMap builtinColorMap(const std::string& name) {
  // Published anchor colours of each map, evenly spaced.
  if (name == "viridis")
    return fromHex(name, {0x440154, 0x482878, 0x3E4A89, 0x31688E, 0x26828E, 0x1F9E89, 0x35B779, 0x6DCD59,
                          0xB4DE2C, 0xFDE725});
  if (name == "plasma")
    return fromHex(name, {0x0D0887, 0x47039F, 0x7301A8, 0x9C179E, 0xBD3786, 0xD8576B, 0xED7953, 0xFA9E3B,
                          0xFDC926, 0xF0F921});
  if (name == "inferno")
    return fromHex(name, {0x000004, 0x1B0C42, 0x4B0C6B, 0x781C6D, 0xA52C60, 0xCF4446, 0xED6925, 0xFB9A06,
                          0xF7D03C, 0xFCFFA4});
  if (name == "magma")
    return fromHex(name, {0x000004, 0x180F3E, 0x451077, 0x721F81, 0x9F2F7F, 0xCD4071, 0xF1605D, 0xFD9567,
                          0xFEC98D, 0xFCFDBF});
  if (name == "cool-to-warm")
    return fromHex(name, {0x3B4CC0, 0x6282EA, 0x8DB0FE, 0xB8D0F9, 0xDDDDDD, 0xF5C4AD, 0xF49A7B, 0xDE604D,
                          0xB40426});
  if (name == "grayscale") {
    ColorMap m;
    m.name = name;
    m.positions = {0.f, 1.f};
    m.colors = {vec3f(0.f), vec3f(1.f)};
    return m;
  }
  std::string known;
  for (const std::string& n : builtinColorMapNames()) known += (known.empty() ? "" : ", ") + n;
  fail("unknown colour map '", name, "' (built in: ", known, ")");
}

float TransferFunction::normalize(float value) const {
  if (valueRange.empty() || !std::isfinite(value)) return 0.5f;
  double lo = valueRange.lower, hi = valueRange.upper, v = value;
  if (logScale) {
    if (hi <= 0) return 0.f;
    if (lo <= 0) lo = hi * 1e-6;
    if (v <= 0) return 0.f;
    lo = std::log10(lo);
    hi = std::log10(hi);
    v = std::log10(v);
  }
  if (!(hi > lo)) return 0.5f;
  return float(std::clamp((v - lo) / (hi - lo), 0.0, 1.0));
}

vec4f TransferFunction::lookup(float value) const {
  const float t = normalize(value);
  const vec3f c = colorMap.at(t);
  const float a = std::clamp(opacityAt(opacity, t) * opacityScale, 0.f, 1.f);
  return {c.x, c.y, c.z, a};
}

float TransferFunction::maxOpacity(const range1f& r) const {
  if (r.empty()) return 0.f;
  const float n0 = normalize(r.lower), n1 = normalize(r.upper);
  float m = std::max(opacityAt(opacity, n0), opacityAt(opacity, n1));
  for (const OpacityPoint& p : opacity)
    if (p.x > n0 && p.x < n1) m = std::max(m, p.alpha);
  return std::clamp(m * opacityScale, 0.f, 1.f);
}

namespace {

using json = nlohmann::json;

float number(const json& v, const std::string& path, const std::string& what) {
  if (!v.is_number()) fail(path, ": ", what, " must be a number");
  const double d = v.get<double>();
  if (!std::isfinite(d)) fail(path, ": ", what, " is not finite");
  return float(d);
}

float unit(const json& v, const std::string& path, const std::string& what) {
  const float f = number(v, path, what);
  if (f < 0.f || f > 1.f) fail(path, ": ", what, " = ", f, " is outside [0, 1]");
  return f;
}

TransferFunction fromParaView(const json& preset, const std::string& path) {
  TransferFunction tf;
  const json& rgb = preset["RGBPoints"];
  if (!rgb.is_array() || rgb.size() < 8 || rgb.size() % 4 != 0)
    fail(path, ": \"RGBPoints\" must hold x, r, g, b for at least two points");
  std::vector<float> xs;
  for (size_t i = 0; i < rgb.size(); i += 4) {
    xs.push_back(number(rgb[i], path, "RGBPoints x"));
    if (xs.size() > 1 && !(xs.back() >= xs[xs.size() - 2])) fail(path, ": RGBPoints x values must not decrease");
  }
  const float lo = xs.front(), hi = xs.back();
  if (!(hi > lo)) fail(path, ": RGBPoints span no value range");
  tf.valueRange = range1f{lo, hi};
  tf.colorMap.name = preset.value("Name", "preset");
  for (size_t i = 0; i < rgb.size(); i += 4) {
    tf.colorMap.positions.push_back((xs[i / 4] - lo) / (hi - lo));
    tf.colorMap.colors.push_back(vec3f(srgbToLinear(unit(rgb[i + 1], path, "RGBPoints red")),
                                       srgbToLinear(unit(rgb[i + 2], path, "RGBPoints green")),
                                       srgbToLinear(unit(rgb[i + 3], path, "RGBPoints blue"))));
  }
  if (preset.contains("Points")) {
    const json& pts = preset["Points"];
    if (!pts.is_array() || pts.size() < 4 || pts.size() % 4 != 0)
      fail(path, ": \"Points\" must hold x, opacity, midpoint, sharpness per point");
    for (size_t i = 0; i < pts.size(); i += 4) {
      const float x = (number(pts[i], path, "Points x") - lo) / (hi - lo);
      const float a = unit(pts[i + 1], path, "Points opacity");
      if (!tf.opacity.empty() && !(x >= tf.opacity.back().x)) fail(path, ": Points x values must not decrease");
      tf.opacity.push_back({std::clamp(x, 0.f, 1.f), a});
    }
  }
  return tf;
}

TransferFunction fromExabricks(const json& j, const std::string& path) {
  TransferFunction tf;
  for (auto it = j.begin(); it != j.end(); ++it)
    if (it.key() != "colormap" && it.key() != "opacity" && it.key() != "range" && it.key() != "log" &&
        it.key() != "opacity_scale")
      fail(path, ": unknown key \"", it.key(), "\" (known: colormap, opacity, range, log, opacity_scale)");
  const json cm = j.value("colormap", json("viridis"));
  if (cm.is_string()) {
    try {
      tf.colorMap = builtinColorMap(cm.get<std::string>());
    } catch (const Error& e) {
      fail(path, ": ", e.what());
    }
  } else if (cm.is_object() && cm.contains("points") && cm["points"].is_array() && cm["points"].size() >= 2) {
    tf.colorMap.name = "custom";
    for (const json& p : cm["points"]) {
      if (!p.is_array() || p.size() != 4) fail(path, ": colormap points are [x, r, g, b]");
      const float x = unit(p[0], path, "colormap x");
      if (!tf.colorMap.positions.empty() && !(x >= tf.colorMap.positions.back()))
        fail(path, ": colormap x values must not decrease");
      tf.colorMap.positions.push_back(x);
      tf.colorMap.colors.push_back(vec3f(srgbToLinear(unit(p[1], path, "red")), srgbToLinear(unit(p[2], path, "green")),
                                         srgbToLinear(unit(p[3], path, "blue"))));
    }
  } else {
    fail(path, ": \"colormap\" must be a built-in name or {\"points\": [[x, r, g, b], ...]}");
  }
  if (j.contains("opacity")) {
    if (!j["opacity"].is_array() || j["opacity"].empty()) fail(path, ": \"opacity\" must be [[x, alpha], ...]");
    for (const json& p : j["opacity"]) {
      if (!p.is_array() || p.size() != 2) fail(path, ": opacity points are [x, alpha]");
      const float x = unit(p[0], path, "opacity x");
      if (!tf.opacity.empty() && !(x >= tf.opacity.back().x)) fail(path, ": opacity x values must not decrease");
      tf.opacity.push_back({x, unit(p[1], path, "opacity alpha")});
    }
  }
  if (j.contains("range")) {
    const json& r = j["range"];
    if (!r.is_array() || r.size() != 2) fail(path, ": \"range\" must be [low, high]");
    tf.valueRange = range1f{number(r[0], path, "range low"), number(r[1], path, "range high")};
    if (!(tf.valueRange.upper > tf.valueRange.lower)) fail(path, ": range low must be below range high");
  }
  if (j.contains("log")) {
    if (!j["log"].is_boolean()) fail(path, ": \"log\" must be true or false");
    tf.logScale = j["log"].get<bool>();
  }
  if (j.contains("opacity_scale")) {
    tf.opacityScale = number(j["opacity_scale"], path, "opacity_scale");
    if (tf.opacityScale < 0.f) fail(path, ": opacity_scale must not be negative");
  }
  return tf;
}

} // namespace

TransferFunction readTransferFunction(const std::string& path) {
  std::ifstream in(path);
  if (!in) fail(path, ": cannot open: ", std::strerror(errno));
  json j;
  try {
    in >> j;
  } catch (const json::exception& e) {
    fail(path, ": invalid JSON: ", e.what());
  }
  if (j.is_array()) {
    if (j.empty() || !j[0].is_object()) fail(path, ": expected a ParaView preset (an array of objects)");
    j = j[0];
  }
  if (!j.is_object()) fail(path, ": expected a JSON object or an array of ParaView presets");
  if (j.contains("RGBPoints")) return fromParaView(j, path);
  return fromExabricks(j, path);
}

} // namespace exa
