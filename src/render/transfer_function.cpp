#include "exabricks/render/transfer_function.h"

#include "exabricks/core/color.h"
#include "exabricks/core/error.h"
#include "exabricks/core/text.h"
#include "exabricks/render/sample_math.h"
#include "exabricks/render/scene_vocabulary.h"

#include "tf_json.h"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <initializer_list>
#include <numbers>

namespace exa {
namespace {

vec3f linearFromHex(uint32_t hex) {
  return vec3f(srgbToLinear(float((hex >> 16) & 255u) / 255.f), srgbToLinear(float((hex >> 8) & 255u) / 255.f),
               srgbToLinear(float(hex & 255u) / 255.f));
}

/// A colour map from evenly spaced sRGB anchors (0xRRGGBB), stored in linear RGB.
ColorMap evenlySpaced(const std::string& name, std::initializer_list<uint32_t> hex) {
  ColorMap m;
  m.name = name;
  const size_t n = hex.size();
  size_t i = 0;
  for (uint32_t h : hex) {
    m.positions.push_back(float(double(i) / double(n - 1)));
    m.colors.push_back(linearFromHex(h));
    ++i;
  }
  return m;
}

// Moreland's diverging colour map (K. Moreland, "Diverging Color Maps for Scientific
// Visualization", ISVC 2009): the two end colours are interpolated in Msh space, the polar form
// of CIELAB (M = |Lab|, s = angle from the L axis, h = hue angle), through an unsaturated
// white of magnitude max(M1, M2, 88) in the middle. Unsaturated colours take the hue of the
// saturated end, spun so that the path keeps turning smoothly.

struct Msh {
  double m = 0, s = 0, h = 0;
};

constexpr double kWhiteX = 0.95047, kWhiteY = 1.0, kWhiteZ = 1.08883; // D65
constexpr double kLabEpsilon = 216.0 / 24389.0, kLabKappa = 24389.0 / 27.0;

double labF(double t) { return t > kLabEpsilon ? std::cbrt(t) : (kLabKappa * t + 16.0) / 116.0; }
double labFInverse(double f) {
  const double t = f * f * f;
  return t > kLabEpsilon ? t : (116.0 * f - 16.0) / kLabKappa;
}

Msh linearToMsh(const vec3d& c) {
  const double x = 0.4124564 * c.x + 0.3575761 * c.y + 0.1804375 * c.z;
  const double y = 0.2126729 * c.x + 0.7151522 * c.y + 0.0721750 * c.z;
  const double z = 0.0193339 * c.x + 0.1191920 * c.y + 0.9503041 * c.z;
  const double fx = labF(x / kWhiteX), fy = labF(y / kWhiteY), fz = labF(z / kWhiteZ);
  const double l = 116.0 * fy - 16.0, a = 500.0 * (fx - fy), b = 200.0 * (fy - fz);
  const double m = std::sqrt(l * l + a * a + b * b);
  return {m, m > 0.0 ? std::acos(l / m) : 0.0, std::atan2(b, a)};
}

vec3d mshToLinear(const Msh& p) {
  const double l = p.m * std::cos(p.s);
  const double a = p.m * std::sin(p.s) * std::cos(p.h);
  const double b = p.m * std::sin(p.s) * std::sin(p.h);
  const double fy = (l + 16.0) / 116.0, fx = fy + a / 500.0, fz = fy - b / 200.0;
  const double x = kWhiteX * labFInverse(fx), y = kWhiteY * labFInverse(fy);
  const double z = kWhiteZ * labFInverse(fz);
  return {3.2404542 * x - 1.5371385 * y - 0.4985314 * z, -0.9692660 * x + 1.8760108 * y + 0.0415560 * z,
          0.0556434 * x - 0.2040259 * y + 1.0572252 * z};
}

/// Hue for an unsaturated colour of magnitude `m` next to the saturated colour `sat`.
double spunHue(const Msh& sat, double m) {
  if (sat.m >= m) return sat.h;
  const double spin = sat.s * std::sqrt(m * m - sat.m * sat.m) / (sat.m * std::sin(sat.s));
  return sat.h > -std::numbers::pi / 3.0 ? sat.h + spin : sat.h - spin;
}

vec3d divergingColor(Msh a, Msh b, double t) {
  double hueGap = std::abs(a.h - b.h);
  if (hueGap > std::numbers::pi) hueGap = 2.0 * std::numbers::pi - hueGap;
  if (a.s > 0.05 && b.s > 0.05 && hueGap > std::numbers::pi / 3.0) {
    const Msh white{std::max({a.m, b.m, 88.0}), 0.0, 0.0};
    if (t < 0.5) {
      b = white;
      t = 2.0 * t;
    } else {
      a = white;
      t = 2.0 * t - 1.0;
    }
  }
  if (a.s < 0.05 && b.s > 0.05)
    a.h = spunHue(b, a.m);
  else if (b.s < 0.05 && a.s > 0.05)
    b.h = spunHue(a, b.m);
  return mshToLinear({(1 - t) * a.m + t * b.m, (1 - t) * a.s + t * b.s, (1 - t) * a.h + t * b.h});
}

/// Moreland's map sampled at `n` evenly spaced anchors. Linear-RGB interpolation between them
/// bends away from the Msh curve most where a channel is near zero (green at the red end); with
/// 65 anchors that stays under half an 8-bit step.
ColorMap diverging(const std::string& name, uint32_t lowHex, uint32_t highHex, int n) {
  const Msh a = linearToMsh(vec3d(linearFromHex(lowHex))), b = linearToMsh(vec3d(linearFromHex(highHex)));
  ColorMap m;
  m.name = name;
  for (int i = 0; i < n; ++i) {
    const double t = double(i) / double(n - 1);
    const vec3d c = divergingColor(a, b, t);
    m.positions.push_back(float(t));
    // Ends are the published colours exactly; elsewhere Lab can leave the gamut by a hair.
    m.colors.push_back(i == 0       ? linearFromHex(lowHex)
                       : i == n - 1 ? linearFromHex(highHex)
                                    : vec3f(float(std::clamp(c.x, 0.0, 1.0)), float(std::clamp(c.y, 0.0, 1.0)),
                                            float(std::clamp(c.z, 0.0, 1.0))));
  }
  return m;
}

/// Piecewise-linear opacity at t, constant beyond the end points. At a step (two points with the
/// same x) the right-hand point wins, as in ColorMap::at. The result is clamped to its segment's
/// end values so that rounding can never exceed what maxOpacity reports.
float opacityAt(const std::vector<OpacityPoint>& points, float t) {
  if (points.empty()) return std::clamp(t, 0.f, 1.f);
  const auto it =
      std::upper_bound(points.begin(), points.end(), t, [](float v, const OpacityPoint& p) { return v < p.x; });
  if (it == points.begin()) return points.front().alpha;
  if (it == points.end()) return points.back().alpha;
  const OpacityPoint& a = *(it - 1);
  const OpacityPoint& b = *it;
  const float f = (t - a.x) / (b.x - a.x); // b.x > t >= a.x
  const float v = a.alpha + (b.alpha - a.alpha) * f;
  return std::clamp(v, std::min(a.alpha, b.alpha), std::max(a.alpha, b.alpha));
}

} // namespace

vec3f ColorMap::at(float t) const {
  const size_t n = std::min(positions.size(), colors.size());
  t = std::isnan(t) ? 0.f : std::clamp(t, 0.f, 1.f);
  // No colour map at all: a grey ramp rather than black, so that something is visible.
  if (n == 0) return vec3f(t);
  const auto end = positions.begin() + std::ptrdiff_t(n);
  const size_t i = size_t(std::upper_bound(positions.begin(), end, t) - positions.begin());
  if (i == 0) return colors[0];
  if (i == n) return colors[n - 1];
  const float f = (t - positions[i - 1]) / (positions[i] - positions[i - 1]);
  return colors[i - 1] + (colors[i] - colors[i - 1]) * f;
}

const std::vector<std::string>& builtinColorMapNames() {
  static const std::vector<std::string> names = {"viridis", "plasma", "inferno", "magma", "cool-to-warm", "grayscale"};
  return names;
}

ColorMap builtinColorMap(const std::string& name) {
  // The perceptual maps of van der Walt and Smith (matplotlib, public domain) by sixteen of
  // their published key colours, entries 0, 17, ..., 255 of the 256-entry tables (so at i/15).
  // Linear interpolation between them stays within a few 8-bit steps of the full tables (the
  // most in channels near zero, where the sRGB curve is steepest).
  if (name == "viridis")
    return evenlySpaced(name, {0x440154, 0x481a6c, 0x472f7d, 0x414487, 0x39568c, 0x31688e, 0x2a788e, 0x23888e, 0x1f988b,
                               0x22a884, 0x35b779, 0x54c568, 0x7ad151, 0xa5db36, 0xd2e21b, 0xfde725});
  if (name == "plasma")
    return evenlySpaced(name, {0x0d0887, 0x330597, 0x5002a2, 0x6a00a8, 0x8405a7, 0x9c179e, 0xb12a90, 0xc33d80, 0xd35171,
                               0xe16462, 0xed7953, 0xf68f44, 0xfca636, 0xfec029, 0xf9dc24, 0xf0f921});
  if (name == "inferno")
    return evenlySpaced(name, {0x000004, 0x0c0826, 0x240c4f, 0x420a68, 0x5d126e, 0x781c6d, 0x932667, 0xae305c, 0xc73e4c,
                               0xdd513a, 0xed6925, 0xf8850f, 0xfca50a, 0xfac62d, 0xf2e661, 0xfcffa4});
  if (name == "magma")
    return evenlySpaced(name, {0x000004, 0x0b0924, 0x20114b, 0x3b0f70, 0x57157e, 0x721f81, 0x8c2981, 0xa8327d, 0xc43c75,
                               0xde4968, 0xf1605d, 0xfa7f5e, 0xfe9f6d, 0xfebf84, 0xfddea0, 0xfcfdbf});
  if (name == "cool-to-warm") return diverging(name, 0x3b4cc0, 0xb40426, 65);
  if (name == "grayscale") return evenlySpaced(name, {0x000000, 0xffffff});
  std::string known;
  for (const std::string& n : builtinColorMapNames())
    known += (known.empty() ? "" : ", ") + n;
  fail("unknown colour map '", name, "' (built in: ", known, ")");
}

float TransferFunction::normalize(float value) const { return normalizeValue(valueRange, logScale, value); }

vec4f TransferFunction::lookup(float value) const { return atNormalized(normalize(value)); }

vec4f TransferFunction::atNormalized(float t) const {
  const vec3f c = colorMap.at(t);
  const float a = std::clamp(opacityAt(opacity, t) * opacityScale, 0.f, 1.f);
  return {c.x, c.y, c.z, std::isnan(a) ? 0.f : a};
}

float TransferFunction::maxOpacity(const range1f& r) const {
  if (r.empty()) return 0.f;
  // normalize is monotonic, so the values in [lower, upper] map onto [n0, n1]; over that
  // interval the piecewise-linear opacity peaks at an end or at a control point. Where several
  // points share one x (a step), the last one is the value there, so it counts when x lies in
  // [n0, n1]; the first one is only approached from below, so it counts when n0 < x <= n1; any
  // between them is never taken.
  const float n0 = normalize(r.lower), n1 = normalize(r.upper);
  float m = std::max(opacityAt(opacity, n0), opacityAt(opacity, n1));
  for (size_t i = 0; i < opacity.size(); ++i) {
    const float x = opacity[i].x;
    const bool first = i == 0 || opacity[i - 1].x < x;
    const bool last = i + 1 == opacity.size() || opacity[i + 1].x > x;
    if ((last && x >= n0 && x <= n1) || (first && x > n0 && x <= n1)) m = std::max(m, opacity[i].alpha);
  }
  const float a = std::clamp(m * opacityScale, 0.f, 1.f);
  return std::isnan(a) ? 0.f : a;
}

namespace {

using json = nlohmann::json;

/// nlohmann's messages start with "[json.exception.KIND.ID] "; the rest is what users need.
std::string jsonMessage(const std::exception& e) {
  std::string m = e.what();
  if (!m.empty() && m[0] == '[') {
    const size_t close = m.find("] ");
    if (close != std::string::npos) m.erase(0, close + 2);
  }
  return m;
}

/// A finite number that fits a float.
double number(const json& v, const std::string& path, const std::string& what) {
  if (!v.is_number()) fail(path, ": ", what, " must be a number, not ", v.dump());
  const double d = v.get<double>();
  if (const std::string why = beyondSinglePrecision(d); !why.empty()) fail(path, ": ", what, ": ", why);
  if (!std::isfinite(d)) fail(path, ": ", what, " = ", v.dump(), " is not a finite number");
  return d;
}

double unitNumber(const json& v, const std::string& path, const std::string& what) {
  const double d = number(v, path, what);
  if (d < 0.0 || d > 1.0) fail(path, ": ", what, " = ", d, " is outside [0, 1]");
  return d;
}

vec3f srgbTriple(const json& r, const json& g, const json& b, const std::string& path, const std::string& what) {
  return vec3f(srgbToLinear(float(unitNumber(r, path, what + " red"))),
               srgbToLinear(float(unitNumber(g, path, what + " green"))),
               srgbToLinear(float(unitNumber(b, path, what + " blue"))));
}

/// Restricts a piecewise-linear opacity with any x to [0, 1], keeping its values there.
std::vector<OpacityPoint> clipToUnit(const std::vector<OpacityPoint>& points) {
  std::vector<OpacityPoint> out{{0.f, opacityAt(points, 0.f)}};
  for (const OpacityPoint& p : points)
    if (p.x > 0.f && p.x < 1.f) out.push_back(p);
  // A step exactly at 1 keeps its left-hand value, which the segment before it approaches.
  for (const OpacityPoint& p : points)
    if (p.x == 1.f) {
      out.push_back(p);
      break;
    }
  out.push_back({1.f, opacityAt(points, 1.f)});
  return out;
}

TransferFunction fromParaView(const json& preset, const std::string& path) {
  const auto rgbIt = preset.find("RGBPoints");
  if (rgbIt == preset.end())
    fail(path, ": ParaView preset has no \"RGBPoints\" (indexed-colour presets are not supported)");
  const json& rgb = *rgbIt;
  if (!rgb.is_array()) fail(path, ": \"RGBPoints\" must be an array of x, r, g, b numbers");
  if (rgb.size() % 4 != 0)
    fail(path, ": \"RGBPoints\" holds ", rgb.size(), " numbers, not a multiple of 4 (x, r, g, b)");
  if (rgb.size() < 8) fail(path, ": \"RGBPoints\" needs at least two points");
  const size_t n = rgb.size() / 4;
  std::vector<double> xs(n);
  for (size_t i = 0; i < n; ++i) {
    xs[i] = number(rgb[4 * i], path, strCat("RGBPoints x of point ", i));
    if (i > 0 && xs[i] < xs[i - 1])
      fail(path, ": RGBPoints x values must not decrease (point ", i, ": ", xs[i], " after ", xs[i - 1], ")");
  }
  const double lo = xs.front(), hi = xs.back();
  if (!(hi > lo)) fail(path, ": RGBPoints span no value range (first and last x are ", lo, ")");

  TransferFunction tf;
  tf.valueRange = range1f{float(lo), float(hi)};
  const auto nameIt = preset.find("Name");
  tf.colorMap.name = nameIt != preset.end() && nameIt->is_string() ? nameIt->get<std::string>() : std::string("preset");
  for (size_t i = 0; i < n; ++i) {
    tf.colorMap.positions.push_back(float((xs[i] - lo) / (hi - lo)));
    tf.colorMap.colors.push_back(
        srgbTriple(rgb[4 * i + 1], rgb[4 * i + 2], rgb[4 * i + 3], path, strCat("RGBPoints point ", i)));
  }

  const auto ptsIt = preset.find("Points");
  if (ptsIt != preset.end() && !(ptsIt->is_array() && ptsIt->empty())) {
    const json& pts = *ptsIt;
    if (!pts.is_array() || pts.size() % 4 != 0)
      fail(path, ": \"Points\" must hold x, opacity, midpoint, sharpness per point");
    // The midpoint and sharpness of ParaView's opacity segments are ignored: segments are linear.
    std::vector<OpacityPoint> raw;
    double previous = -HUGE_VAL;
    for (size_t i = 0; i < pts.size(); i += 4) {
      const double x = number(pts[i], path, strCat("Points x of point ", i / 4));
      if (x < previous)
        fail(path, ": Points x values must not decrease (point ", i / 4, ": ", x, " after ", previous, ")");
      previous = x;
      const double a = unitNumber(pts[i + 1], path, strCat("Points opacity of point ", i / 4));
      raw.push_back({float((x - lo) / (hi - lo)), float(a)});
    }
    tf.opacity = clipToUnit(raw);
  }
  return tf;
}

ColorMap customColorMap(const json& cm, const std::string& path) {
  for (auto it = cm.begin(); it != cm.end(); ++it)
    if (it.key() != "points") fail(path, ": unknown key \"", it.key(), "\" in \"colormap\" (known: points)");
  const auto pts = cm.find("points");
  if (pts == cm.end() || !pts->is_array() || pts->size() < 2)
    fail(path, ": \"colormap\" {\"points\": [[x, r, g, b], ...]} needs at least two points");
  ColorMap m;
  m.name = "custom";
  for (size_t i = 0; i < pts->size(); ++i) {
    const json& p = (*pts)[i];
    if (!p.is_array() || p.size() != 4) fail(path, ": colormap point ", i, " is ", p.dump(), ", expected [x, r, g, b]");
    const double x = unitNumber(p[0], path, strCat("colormap x of point ", i));
    if (!m.positions.empty() && x < m.positions.back())
      fail(path, ": colormap x values must not decrease (point ", i, ": ", x, " after ", m.positions.back(), ")");
    m.positions.push_back(float(x));
    m.colors.push_back(srgbTriple(p[1], p[2], p[3], path, strCat("colormap point ", i)));
  }
  if (m.positions.front() != 0.f || m.positions.back() != 1.f)
    fail(path, ": colormap points must start at x = 0 and end at x = 1");
  return m;
}

/// Points [[x, y], ...] of a piecewise-linear curve over [0, 1] with values in [0, 1] (the
/// opacity, the albedo), x not decreasing; `value` names a point's y in messages.
std::vector<OpacityPoint> unitCurve(const json& points, const std::string& path, const char* key, const char* y,
                                    const char* value) {
  if (!points.is_array() || points.empty()) fail(path, ": \"", key, "\" must be [[x, ", y, "], ...]");
  std::vector<OpacityPoint> out;
  for (size_t i = 0; i < points.size(); ++i) {
    const json& p = points[i];
    if (!p.is_array() || p.size() != 2)
      fail(path, ": ", key, " point ", i, " is ", p.dump(), ", expected [x, ", y, "]");
    const double x = unitNumber(p[0], path, strCat(key, " x of point ", i));
    if (!out.empty() && x < out.back().x)
      fail(path, ": ", key, " x values must not decrease (point ", i, ": ", x, " after ", out.back().x, ")");
    out.push_back({float(x), float(unitNumber(p[1], path, strCat(value, " of point ", i)))});
  }
  return out;
}

TransferFunction fromExabricks(const json& j, const std::string& path) {
  const std::vector<std::string> known = knownSceneKeys("transfer_function");
  for (auto it = j.begin(); it != j.end(); ++it)
    if (std::find(known.begin(), known.end(), it.key()) == known.end()) {
      std::string list;
      for (const std::string& k : known)
        list += (list.empty() ? "" : ", ") + k;
      fail(path, ": unknown key \"", it.key(), "\" (known: ", list, ")");
    }

  TransferFunction tf;
  tf.colorMap = builtinColorMap("viridis");
  tf.opacityScale = 0.f; // without "opacity_scale": the dataset's default, as for built-in maps
  if (const auto cm = j.find("colormap"); cm != j.end()) {
    if (cm->is_string()) {
      try {
        tf.colorMap = builtinColorMap(cm->get<std::string>());
      } catch (const Error& e) {
        fail(path, ": ", e.what());
      }
    } else if (cm->is_object()) {
      tf.colorMap = customColorMap(*cm, path);
    } else {
      fail(path, ": \"colormap\" must be a built-in name or {\"points\": [[x, r, g, b], ...]}");
    }
  }
  if (const auto op = j.find("opacity"); op != j.end())
    tf.opacity = unitCurve(*op, path, "opacity", "alpha", "opacity alpha");
  if (const auto al = j.find("albedo"); al != j.end()) tf.albedo = unitCurve(*al, path, "albedo", "albedo", "albedo");
  if (const auto lg = j.find("log"); lg != j.end()) {
    if (!lg->is_boolean()) fail(path, ": \"log\" must be true or false");
    tf.logScale = lg->get<bool>();
  }
  if (const auto r = j.find("range"); r != j.end()) {
    if (!r->is_array() || r->size() != 2) fail(path, ": \"range\" must be [low, high]");
    const double lo = number((*r)[0], path, "range low"), hi = number((*r)[1], path, "range high");
    if (!(lo < hi)) fail(path, ": range low (", lo, ") must be below range high (", hi, ")");
    if (tf.logScale && !(lo > 0.0)) fail(path, ": a logarithmic range must be positive, got [", lo, ", ", hi, "]");
    tf.valueRange = range1f{float(lo), float(hi)};
  }
  if (const auto s = j.find("opacity_scale"); s != j.end() && s->is_string()) {
    if (s->get<std::string>() != "auto")
      fail(path, ": opacity_scale must be a number >= 0 or \"auto\", not ", s->dump());
    tf.opacityScale = 0.f; // the dataset's default scale
  } else if (s != j.end()) {
    const double scale = number(*s, path, "opacity_scale");
    if (!(scale > 0.0)) fail(path, ": opacity_scale must be positive (or \"auto\"), got ", scale);
    tf.opacityScale = float(scale);
  }
  return tf;
}

/// ParaView presets are recognised by their capitalised keys; anything else is the native form.
bool isParaViewPreset(const json& j) {
  for (const char* key :
       {"RGBPoints", "Points", "ColorSpace", "Name", "NanColor", "IndexedColors", "Annotations", "Creator"})
    if (j.contains(key)) return true;
  return false;
}

} // namespace

TransferFunction transferFunctionFromJson(const json& j, const std::string& source) {
  try {
    if (j.is_array()) {
      // ParaView writes a list of presets; the first one is used.
      if (j.empty() || !j[0].is_object()) fail(source, ": expected an array of ParaView colour-map preset objects");
      return fromParaView(j[0], source);
    }
    if (!j.is_object())
      fail(source, ": expected a JSON object (exabricks transfer function or ParaView preset) or an "
                   "array of ParaView presets");
    return isParaViewPreset(j) ? fromParaView(j, source) : fromExabricks(j, source);
  } catch (const json::exception& e) {
    fail(source, ": ", jsonMessage(e));
  }
}

json transferFunctionToJson(const TransferFunction& tf) {
  json j = json::object();
  bool builtin = false;
  for (const std::string& name : builtinColorMapNames())
    if (name == tf.colorMap.name && builtinColorMap(name) == tf.colorMap) builtin = true;
  if (builtin) {
    j["colormap"] = tf.colorMap.name;
  } else {
    json points = json::array();
    for (size_t i = 0; i < tf.colorMap.positions.size() && i < tf.colorMap.colors.size(); ++i) {
      const vec3f c = linearToSrgb(tf.colorMap.colors[i]);
      points.push_back({tf.colorMap.positions[i], c.x, c.y, c.z});
    }
    j["colormap"] = {{"points", points}};
  }
  if (!tf.opacity.empty()) {
    json op = json::array();
    for (const OpacityPoint& p : tf.opacity)
      op.push_back({p.x, p.alpha});
    j["opacity"] = op;
  }
  if (!tf.albedo.empty()) {
    json al = json::array();
    for (const OpacityPoint& p : tf.albedo)
      al.push_back({p.x, p.alpha});
    j["albedo"] = al;
  }
  if (!tf.valueRange.empty()) j["range"] = {tf.valueRange.lower, tf.valueRange.upper};
  j["log"] = tf.logScale;
  if (tf.opacityScale == 0.f)
    j["opacity_scale"] = "auto";
  else
    j["opacity_scale"] = tf.opacityScale;
  return j;
}

TransferFunction defaultTransferFunction(const std::string& colorMap) {
  TransferFunction tf;
  tf.colorMap = builtinColorMap(colorMap);
  tf.opacityScale = 0.f;
  return tf;
}

std::vector<vec4f> tabulateTransferFunction(const TransferFunction& tf) {
  std::vector<vec4f> table(kTfTableSize);
  for (int i = 0; i < kTfTableSize; ++i) {
    const vec4f c = tf.atNormalized(float(i) / float(kTfTableSize - 1));
    table[size_t(i)] = {c.x, c.y, c.z, std::log2(1.f - std::min(c.w, 0.999999f))};
  }
  return table;
}

std::vector<float> tabulateAlbedo(const TransferFunction& tf) {
  if (tf.albedo.empty()) return {};
  std::vector<float> table(kTfTableSize);
  for (int i = 0; i < kTfTableSize; ++i)
    table[size_t(i)] = opacityAt(tf.albedo, float(i) / float(kTfTableSize - 1));
  return table;
}

TransferFunction parseTransferFunction(const std::string& jsonText, const std::string& source, bool* isPreset) {
  json j;
  try {
    j = json::parse(jsonText);
  } catch (const json::exception& e) {
    fail(source, ": invalid JSON: ", jsonMessage(e));
  }
  if (isPreset) *isPreset = j.is_array() || (j.is_object() && isParaViewPreset(j));
  return transferFunctionFromJson(j, source);
}

void removeFloatNoise(json& j) {
  if (j.is_number_float()) {
    j = withoutFloatNoise(j.get<double>());
  } else if (j.is_structured()) {
    for (json& child : j)
      removeFloatNoise(child);
  }
}

std::string transferFunctionJson(const TransferFunction& tf) {
  json j = transferFunctionToJson(tf);
  removeFloatNoise(j);
  return j.dump(2);
}

} // namespace exa
