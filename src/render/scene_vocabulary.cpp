#include "exabricks/render/scene_vocabulary.h"

#include "exabricks/core/text.h"

#include "scene_settings.h"
#include "tf_json.h"

#include <charconv>
#include <cmath>
#include <limits>
#include <utility>

namespace exa {

TraversalSetting traversalSetting(const Integration& in) {
  if (in.autoTraversal) return TraversalSetting::Auto;
  return in.traversal == TraversalKind::Embree ? TraversalSetting::Embree : TraversalSetting::KdTree;
}

void setTraversal(Integration& in, TraversalSetting t) {
  in.autoTraversal = t == TraversalSetting::Auto;
  if (!in.autoTraversal) in.traversal = t == TraversalSetting::Embree ? TraversalKind::Embree : TraversalKind::KdTree;
}

std::span<const EnumName<Shading>> enumNames(Shading) {
  static const EnumName<Shading> names[] = {{"analytic", Shading::Analytic},
                                            {"central", Shading::Central},
                                            {"smooth", Shading::Smooth},
                                            {"none", Shading::None},
                                            {"clamped", Shading::Smooth, true}};
  return names;
}

std::span<const EnumName<DebugView>> enumNames(DebugView) {
  static const EnumName<DebugView> names[] = {{"none", DebugView::None},
                                              {"level", DebugView::Level},
                                              {"brick", DebugView::Brick},
                                              {"region", DebugView::Region},
                                              {"steps", DebugView::Steps}};
  return names;
}

std::span<const EnumName<Sampling>> enumNames(Sampling) {
  static const EnumName<Sampling> names[] = {{"adaptive", Sampling::Adaptive}, {"fixed", Sampling::Fixed}};
  return names;
}

std::span<const EnumName<Reconstruction>> enumNames(Reconstruction) {
  static const EnumName<Reconstruction> names[] = {{"regions", Reconstruction::Regions},
                                                   {"cells", Reconstruction::CellLocation}};
  return names;
}

std::span<const EnumName<Integrator>> enumNames(Integrator) {
  static const EnumName<Integrator> names[] = {{"march", Integrator::March}, {"pathtrace", Integrator::PathTrace}};
  return names;
}

std::span<const EnumName<TraversalSetting>> enumNames(TraversalSetting) {
  static const EnumName<TraversalSetting> names[] = {
      {"auto", TraversalSetting::Auto}, {"kd", TraversalSetting::KdTree}, {"embree", TraversalSetting::Embree}};
  return names;
}

std::span<const EnumName<TraversalKind>> enumNames(TraversalKind) {
  static const EnumName<TraversalKind> names[] = {{"kd", TraversalKind::KdTree}, {"embree", TraversalKind::Embree}};
  return names;
}

namespace {

using json = nlohmann::json;
constexpr double kInf = std::numeric_limits<double>::infinity();

template <typename E> std::vector<std::string> offered() {
  std::vector<std::string> out;
  for (const EnumName<E>& n : enumNames(E{}))
    if (!n.alias) out.push_back(n.name);
  return out;
}

template <typename Owner, typename Ref>
Setting<Owner> boolean(const char* key, const char* name, Ref ref, const char* help) {
  Setting<Owner> s{key, name, SettingType::Boolean};
  s.help = help;
  s.get = [ref](const Owner& o) { return json(ref(const_cast<Owner&>(o))); };
  s.set = [ref](Owner& o, const json& v, const std::string&) { ref(o) = v.get<bool>(); };
  return s;
}

/// An integer or a number in [low, high] (open ends where asked).
template <typename Owner, typename Ref>
Setting<Owner> number(const char* key, const char* name, Ref ref, double low, double high, const char* help,
                      bool lowOpen = false, bool highOpen = false) {
  using T = std::remove_reference_t<decltype(ref(std::declval<Owner&>()))>;
  Setting<Owner> s{key,     name,    std::is_integral_v<T> ? SettingType::Integer : SettingType::Number, low, high,
                   lowOpen, highOpen};
  s.help = help;
  s.get = [ref](const Owner& o) { return json(ref(const_cast<Owner&>(o))); };
  s.set = [ref](Owner& o, const json& v, const std::string&) {
    if constexpr (std::is_integral_v<T>)
      ref(o) = v.is_number_integer() ? v.get<T>() : T(v.get<double>());
    else
      ref(o) = T(v.get<double>());
  };
  return s;
}

/// A choice among an enumeration's names, read and written through get and put.
template <typename Owner, typename E, typename Get, typename Put>
Setting<Owner> choice(const char* key, const char* name, Get get, Put put, const char* help) {
  Setting<Owner> s{key, name, SettingType::Choice};
  s.choices = offered<E>();
  s.help = help;
  s.get = [get](const Owner& o) { return json(nameOf<E>(get(o))); };
  s.set = [put](Owner& o, const json& v, const std::string& what) { put(o, parseName<E>(v.get<std::string>(), what)); };
  return s;
}

template <typename Owner, typename E, typename Ref>
Setting<Owner> choice(const char* key, const char* name, Ref ref, const char* help) {
  return choice<Owner, E>(
      key, name, [ref](const Owner& o) { return ref(const_cast<Owner&>(o)); }, [ref](Owner& o, E e) { ref(o) = e; },
      help);
}

json vectorJson(const vec3f& v) { return json::array({v.x, v.y, v.z}); }
vec3f vectorOf(const json& v) { return vec3f(v[0].get<float>(), v[1].get<float>(), v[2].get<float>()); }

/// Three numbers: a direction or a radiance.
template <typename Owner, typename Ref>
Setting<Owner> vector(const char* key, const char* name, Ref ref, VectorKind kind, const char* help) {
  Setting<Owner> s{key, name, SettingType::Vector};
  s.vector = kind;
  s.help = help;
  s.get = [ref](const Owner& o) { return vectorJson(ref(const_cast<Owner&>(o))); };
  s.set = [ref](Owner& o, const json& v, const std::string&) { ref(o) = vectorOf(v); };
  return s;
}

/// Three numbers that may be unset (null).
template <typename Owner, typename Ref>
Setting<Owner> optionalVector(const char* key, const char* name, Ref ref, VectorKind kind, const char* help) {
  Setting<Owner> s{key, name, SettingType::Vector};
  s.vector = kind;
  s.optional = true;
  s.help = help;
  s.get = [ref](const Owner& o) {
    const std::optional<vec3f>& v = ref(const_cast<Owner&>(o));
    return v ? vectorJson(*v) : json();
  };
  s.set = [ref](Owner& o, const json& v, const std::string&) {
    if (v.is_null())
      ref(o).reset();
    else
      ref(o) = vectorOf(v);
  };
  return s;
}

/// The settings at the top level: what is drawn, legends, clipping of meshes.
std::vector<Setting<Scene>> topLevelSettings() {
  using S = Scene;
  return {
      boolean<S>(
          "volume", "volume", [](S& s) -> bool& { return s.volume; }, "Integrate the volume (false: surfaces only)"),
      choice<S, Shading>(
          "shading", "shading", [](S& s) -> Shading& { return s.shading; },
          "Normals of volume samples: smooth (a gradient field of per-cell central differences, "
          "reconstructed like the values), analytic (the exact gradient, which shows the cell "
          "lattice), central (differences at every sample) or none (unlit)"),
      choice<S, DebugView>(
          "debug", "debug", [](S& s) -> DebugView& { return s.debug; },
          "Debug view: none, or colour by level, brick, region or steps per ray"),
      boolean<S>(
          "alpha", "alpha", [](S& s) -> bool& { return s.keepAlpha; },
          "Images keep the alpha channel instead of the background"),
      boolean<S>(
          "legends.color_bar", "color_bar", [](S& s) -> bool& { return s.legends.colorBar; },
          "A colour bar of the first layer's field at the right edge (with the volume on and no debug view)"),
      boolean<S>(
          "legends.annotation", "annotation", [](S& s) -> bool& { return s.legends.annotation; },
          "Dataset name, field, simulation time and cycle at the top left, and the outline of the domain"),
      boolean<S>(
          "legends.level_legend", "level_legend", [](S& s) -> bool& { return s.legends.levelLegend; },
          "With the level debug view: the level colours and their cell widths at the bottom left"),
      boolean<S>(
          "clip.meshes", "clip_meshes", [](S& s) -> bool& { return s.clip.meshes; }, "Clip meshes and particles too"),
      boolean<S>(
          "particles.show", "particles", [](S& s) -> bool& { return s.particles.show; },
          "Draw the dataset's particles as spheres (particles.species: one species only)"),
      number<S>(
          "particles.radius", "particle_radius", [](S& s) -> float& { return s.particles.radius; }, 0.0, kInf,
          "The spheres' radius, world units (0: 1/800 of the data's diagonal; with particles.radius_by, the "
          "largest sphere's)"),
      number<S>(
          "particles.radius_pixels", "particle_radius_pixels", [](S& s) -> float& { return s.particles.radiusPixels; },
          0.0, 10000.0,
          "Above 0: the spheres' radius in pixels at the distance of the camera's look-at point, instead of "
          "particles.radius (with particles.radius_by, the largest sphere's)"),
  };
}

/// Local lighting and ambient occlusion.
std::vector<Setting<Scene>> lightSettings() {
  using S = Scene;
  return {
      boolean<S>(
          "light.headlight", "headlight", [](S& s) -> bool& { return s.light.headlight; },
          "Light from the eye (false: along light.direction)"),
      number<S>(
          "light.ambient", "ambient", [](S& s) -> float& { return s.light.terms.ambient; }, 0.0, kInf,
          "Ambient term of the lighting"),
      number<S>(
          "light.diffuse", "diffuse", [](S& s) -> float& { return s.light.terms.diffuse; }, 0.0, kInf,
          "Diffuse term of the lighting"),
      number<S>(
          "light.specular", "specular", [](S& s) -> float& { return s.light.terms.specular; }, 0.0, kInf,
          "Specular term of the lighting"),
      number<S>(
          "light.shininess", "shininess", [](S& s) -> float& { return s.light.terms.shininess; }, 0.0, kInf,
          "Specular exponent"),
      number<S>(
          "ambient_occlusion.rays", "ao_rays", [](S& s) -> int& { return s.ao.rays; }, 0, 1024,
          "Ambient occlusion rays per surface hit (0: off)"),
      number<S>(
          "ambient_occlusion.length", "ao_length", [](S& s) -> float& { return s.ao.length; }, 0.0, kInf,
          "Ambient occlusion ray length, world units (0: a tenth of the data's diagonal)"),
      boolean<S>(
          "ambient_occlusion.volume", "ao_volume", [](S& s) -> bool& { return s.ao.volume; },
          "The volume attenuates ambient occlusion rays"),
  };
}

/// How rays integrate the volume.
std::vector<Setting<Scene>> integrationSettings() {
  using S = Scene;
  return {
      choice<S, Sampling>(
          "integration.sampling", "sampling", [](S& s) -> Sampling& { return s.integration.sampling; },
          "Sample placement: adaptive (per region) or fixed (the finest width everywhere)"),
      choice<S, Reconstruction>(
          "integration.reconstruction", "reconstruction",
          [](S& s) -> Reconstruction& { return s.integration.reconstruction; },
          "regions (bricks listed by the sample's region) or cells (baseline: locate every "
          "cell)"),
      choice<S, TraversalSetting>(
          "integration.traversal", "traversal", [](const S& s) { return traversalSetting(s.integration); },
          [](S& s, TraversalSetting t) { setTraversal(s.integration, t); },
          "Region traversal: auto (Embree when few regions are visible), kd or embree"),
      number<S>(
          "integration.embree_below_visible_fraction", "embree_below_visible_fraction",
          [](S& s) -> float& { return s.integration.embreeBelowVisibleFraction; }, 0.0, 1.0,
          "With auto traversal: Embree below this fraction of visible regions"),
      boolean<S>(
          "integration.space_skipping", "space_skipping", [](S& s) -> bool& { return s.integration.spaceSkipping; },
          "Skip regions the transfer function hides"),
      boolean<S>(
          "integration.uniform_stride", "uniform_stride", [](S& s) -> bool& { return s.integration.uniformStride; },
          "Step four times as far in regions the transfer function shows uniformly"),
      boolean<S>(
          "integration.early_termination", "early_termination",
          [](S& s) -> bool& { return s.integration.earlyTermination; },
          "End rays once their opacity reaches termination_opacity"),
      number<S>(
          "integration.termination_opacity", "termination_opacity",
          [](S& s) -> float& { return s.integration.terminationOpacity; }, 0.0, 1.0,
          "Opacity at which early termination ends a ray", true),
      choice<S, Integrator>(
          "integration.integrator", "integrator", [](S& s) -> Integrator& { return s.integration.integrator; },
          "march (emission and absorption, local shading) or pathtrace (volume path tracing: shadows and "
          "multiple scattering from the environment and the sun; one sample per pixel and pass)"),
  };
}

/// The path tracer's numbers.
std::vector<Setting<Scene>> pathTracingSettings() {
  using S = Scene;
  return {
      number<S>(
          "pathtrace.albedo", "albedo", [](S& s) -> float& { return s.pathTracing.albedo; }, 0.0, 1.0,
          "Path tracing: the share of extinction that scatters (0: absorption and emission only)"),
      number<S>(
          "pathtrace.anisotropy", "anisotropy", [](S& s) -> float& { return s.pathTracing.anisotropy; }, -1.0, 1.0,
          "Path tracing: Henyey-Greenstein anisotropy g (0: isotropic, > 0: forward scattering)", true, true),
      number<S>(
          "pathtrace.bounces", "bounces", [](S& s) -> int& { return s.pathTracing.bounces; }, 0, 1024,
          "Path tracing: scattering events per path at most (Russian roulette ends dim paths earlier)"),
      number<S>(
          "pathtrace.emission", "emission", [](S& s) -> float& { return s.pathTracing.emission; }, 0.0, kInf,
          "Path tracing: light the absorbing part of the medium emits, times the transfer function's colour"),
      number<S>(
          "pathtrace.sun_intensity", "sun_intensity", [](S& s) -> float& { return s.pathTracing.sunIntensity; }, 0.0,
          kInf, "Path tracing: the sun's irradiance (0: no sun)"),
      number<S>(
          "pathtrace.sun_angle", "sun_angle", [](S& s) -> float& { return s.pathTracing.sunAngle; }, 0.0, 90.0,
          "Path tracing: the sun's angular diameter in degrees (0: a point; soft shadows grow with it)"),
  };
}

/// Directions and radiances (three numbers each).
std::vector<Setting<Scene>> vectorSettings() {
  using S = Scene;
  return {
      vector<S>(
          "light.direction", "light_direction", [](S& s) -> vec3f& { return s.light.direction; }, VectorKind::Direction,
          "The direction light travels (world), where the light is not the headlight"),
      vector<S>(
          "pathtrace.environment", "environment", [](S& s) -> vec3f& { return s.pathTracing.environment; },
          VectorKind::Radiance,
          "Path tracing: the environment's radiance (linear r,g,b): everywhere, or at the horizon with a sky "
          "or ground"),
      optionalVector<S>(
          "pathtrace.sky", "sky", [](S& s) -> std::optional<vec3f>& { return s.pathTracing.sky; }, VectorKind::Radiance,
          "Path tracing: the environment's radiance at the zenith (the camera's up), blending linearly in the "
          "sine of the elevation to the horizon's (unset: the horizon's)"),
      optionalVector<S>(
          "pathtrace.ground", "ground", [](S& s) -> std::optional<vec3f>& { return s.pathTracing.ground; },
          VectorKind::Radiance,
          "Path tracing: the environment's radiance straight down, blending to the horizon's (unset: the "
          "horizon's)"),
      vector<S>(
          "pathtrace.sun_direction", "sun_direction", [](S& s) -> vec3f& { return s.pathTracing.sunDirection; },
          VectorKind::Direction, "Path tracing: the direction sunlight travels (world)"),
  };
}

} // namespace

const std::vector<Setting<Scene>>& sceneSettings() {
  // In this order: it is the order of the scene JSON and of the settings listed.
  static const std::vector<Setting<Scene>> table = [] {
    using Part = std::vector<Setting<Scene>> (*)();
    std::vector<Setting<Scene>> all;
    for (Part part : {topLevelSettings, lightSettings, integrationSettings, pathTracingSettings, vectorSettings})
      for (Setting<Scene>& s : part())
        all.push_back(std::move(s));
    return all;
  }();
  return table;
}

const std::vector<Setting<Frame>>& frameSettings() {
  using F = Frame;
  static const std::vector<Setting<Frame>> table = {
      number<F>(
          "frame.width", "width", [](F& f) -> int& { return f.width; }, 1, 32768, "Image width in pixels"),
      number<F>(
          "frame.height", "height", [](F& f) -> int& { return f.height; }, 1, 32768, "Image height in pixels"),
      number<F>(
          "frame.samples_per_pixel", "spp", [](F& f) -> int& { return f.samplesPerPixel; }, 1, 65536,
          "Jittered samples per pixel, accumulated (with a noise target: the most a tile takes)"),
      number<F>(
          "frame.noise_target", "noise_target", [](F& f) -> float& { return f.noiseTarget; }, 0.0, 255.0,
          "Path tracing: stop each tile once its estimated noise is at most this many 1/255 steps of the 8-bit "
          "image (0: take samples_per_pixel everywhere)"),
      boolean<F>(
          "frame.denoise", "denoise", [](F& f) -> bool& { return f.denoise; },
          "Path tracing: denoise the picture, guided by the frame ray-marched (a noise target is then the "
          "denoised picture's)"),
      number<F>(
          "frame.rate", "rate", [](F& f) -> float& { return f.rate; }, 0.0, 1024.0,
          "Quality factor: step = region's finest width x 0.5 / rate", true),
      boolean<F>(
          "frame.jitter", "jitter", [](F& f) -> bool& { return f.jitter; }, "Random offsets of the sample positions"),
      number<F>(
          "frame.seed", "seed", [](F& f) -> uint64_t& { return f.seed; }, 0.0, 18446744073709549568.0,
          "Seed of the per-pixel jitter"),
  };
  return table;
}

namespace {

/// A number as a message shows it: integers without a fraction.
std::string shown(double v) {
  if (std::isnan(v)) return "nan";
  if (std::isinf(v)) return v > 0 ? "inf" : "-inf";
  if (v == std::floor(v) && std::abs(v) < 1e15) return std::to_string(int64_t(v));
  return nlohmann::json(v).dump();
}

} // namespace

void checkSettingValue(std::string_view key, SettingType type, double low, double high, bool lowOpen, bool highOpen,
                       double value) {
  const bool integer = type == SettingType::Integer;
  const bool ok = std::isfinite(value) && (lowOpen ? value > low : value >= low) &&
                  (highOpen ? value < high : value <= high) && (!integer || value == std::floor(value));
  if (ok) {
    if (integer) return;
    const std::string why = beyondSinglePrecision(value); // within its range, but no float holds it
    if (why.empty()) return;
    fail("\"", key, "\": ", why);
  }
  const std::string lo = shown(low), hi = shown(high), v = shown(value);
  if (integer && high > 1e15) fail("\"", key, "\" must be an integer >= ", lo, ", not ", v);
  if (integer) fail("\"", key, "\" must be an integer in ", lo, "..", hi, ", not ", v);
  if (std::isinf(high)) fail("\"", key, "\" must be a finite number ", lowOpen ? "> " : ">= ", lo, ", not ", v);
  fail("\"", key, "\" must be in ", lowOpen ? "(" : "[", lo, ", ", hi, highOpen ? ")" : "]", ", not ", v);
}

namespace {

/// A vector as a message shows it: numbers in their shortest single-precision form.
std::string shownVector(const json& v) {
  if (!v.is_array()) return v.dump();
  std::string out = "[";
  for (size_t i = 0; i < v.size(); ++i) {
    if (i) out += ", ";
    if (!v[i].is_number()) {
      out += v[i].dump();
      continue;
    }
    char buf[32];
    const auto end = std::to_chars(buf, buf + sizeof(buf), v[i].get<float>()).ptr;
    out.append(buf, end);
  }
  return out + "]";
}

} // namespace

void checkVectorValue(const std::string& key, VectorKind kind, const json& v) {
  for (size_t i = 0; v.is_array() && i < v.size(); ++i)
    if (v[i].is_number())
      if (const std::string why = beyondSinglePrecision(v[i].get<double>()); !why.empty()) fail("\"", key, "\": ", why);
  bool numbers = v.is_array() && v.size() == 3;
  for (size_t i = 0; numbers && i < 3; ++i)
    numbers = v[i].is_number() && std::isfinite(v[i].get<double>()) && std::isfinite(v[i].get<float>());
  if (kind == VectorKind::Direction) {
    if (!numbers || !(length(vec3d(v[0].get<double>(), v[1].get<double>(), v[2].get<double>())) > 0.0))
      fail("\"", key, "\" must be a finite, non-zero direction x,y,z, not ", shownVector(v));
  } else if (!numbers || !(v[0].get<double>() >= 0.0 && v[1].get<double>() >= 0.0 && v[2].get<double>() >= 0.0)) {
    fail("\"", key, "\" must be a finite radiance r,g,b >= 0, not ", shownVector(v));
  }
}

namespace {

template <typename Owner> void describe(const std::vector<Setting<Owner>>& table, json& out) {
  static const char* types[] = {"boolean", "integer", "number", "choice", "vector"};
  const Owner defaults{};
  for (const Setting<Owner>& s : table) {
    json e = {
        {"key", s.key}, {"name", s.name}, {"type", types[int(s.type)]}, {"default", s.get(defaults)}, {"help", s.help}};
    if (s.type == SettingType::Integer || s.type == SettingType::Number) {
      // (an integer's bounds as integers: a seed's reaches 2^64 - 2048)
      const bool integer = s.type == SettingType::Integer;
      e["min"] = integer ? json(int64_t(s.low)) : json(s.low);
      if (s.lowOpen) e["min_exclusive"] = true;
      if (std::isfinite(s.high))
        e["max"] = !integer ? json(s.high) : s.high >= 0x1p63 ? json(uint64_t(s.high)) : json(int64_t(s.high));
      if (s.highOpen) e["max_exclusive"] = true;
    }
    if (s.type == SettingType::Choice) e["choices"] = s.choices;
    if (s.type == SettingType::Vector) {
      e["kind"] = s.vector == VectorKind::Direction ? "direction" : "radiance";
      if (s.optional) e["optional"] = true;
    }
    out.push_back(e);
  }
}

} // namespace

namespace {

template <typename Owner>
const Setting<Owner>* findSetting(const std::vector<Setting<Owner>>& table, const std::string& key) {
  for (const Setting<Owner>& s : table)
    if (s.key == key) return &s;
  return nullptr;
}

} // namespace

std::string sceneSettingHelp(const std::string& key) {
  if (const auto* s = findSetting(sceneSettings(), key)) return s->help;
  if (const auto* s = findSetting(frameSettings(), key)) return s->help;
  return structuredKeyHelp(key);
}

void checkSceneSetting(const std::string& key, double value) {
  if (const auto* s = findSetting(sceneSettings(), key)) return checkSetting(*s, value);
  if (const auto* s = findSetting(frameSettings(), key)) return checkSetting(*s, value);
  if (!checkStructuredNumber(key, value)) fail("no numeric scene setting \"", key, "\"");
}

namespace {

/// A described setting's value from text as a command line gives it: true or false, a number,
/// a name, or x,y,z. Range and kind are checked (the messages name the key).
template <typename Owner> json valueOfText(const Setting<Owner>& s, const std::string& text) {
  auto number = [&](const std::string& part) {
    double v = 0.0;
    const char* end = part.data() + part.size();
    const auto r = std::from_chars(part.data(), end, v);
    if (part.empty() || r.ec == std::errc::invalid_argument || r.ptr != end)
      fail("\"", s.key, "\" must be a number, not '", text, "'");
    return v; // out of range: +-inf or 0, refused or kept by the range check
  };
  switch (s.type) {
  case SettingType::Boolean:
    if (text != "true" && text != "false" && text != "on" && text != "off")
      fail("\"", s.key, "\" must be true or false (on or off), not '", text, "'");
    return text == "true" || text == "on";
  case SettingType::Choice:
    return text;
  case SettingType::Vector: {
    json v = json::array();
    for (size_t start = 0;;) {
      const size_t comma = text.find(',', start);
      v.push_back(number(text.substr(start, comma - start)));
      if (comma == std::string::npos) break;
      start = comma + 1;
    }
    checkVectorValue(s.key, s.vector, v);
    return v;
  }
  default:
    break;
  }
  const double v = number(text);
  checkSetting(s, v);
  if (s.type == SettingType::Integer) {
    uint64_t u = 0; // exact beyond 2^53 (seeds)
    if (v >= 0.0 && std::from_chars(text.data(), text.data() + text.size(), u).ptr == text.data() + text.size())
      return json(u);
    return json(int64_t(v));
  }
  return json(v);
}

} // namespace

void setSceneSettingText(Scene& scene, Frame& frame, const std::string& key, const std::string& text,
                         const std::string& what) {
  if (const auto* s = findSetting(sceneSettings(), key)) return s->set(scene, valueOfText(*s, text), what);
  if (const auto* s = findSetting(frameSettings(), key)) return s->set(frame, valueOfText(*s, text), what);
  fail("no scene setting \"", key, "\"");
}

std::string sceneSettingDefaultText(const std::string& key) {
  auto number = [](const json& x) { // in the shortest form of its single-precision value
    if (x.is_number_integer()) return x.dump();
    char buf[32];
    return std::string(buf, std::to_chars(buf, buf + sizeof(buf), x.get<float>()).ptr);
  };
  auto text = [&](const json& d) {
    if (d.is_null()) return std::string();
    if (d.is_string()) return d.get<std::string>();
    if (!d.is_array()) return number(d);
    std::string out;
    for (const json& x : d)
      out += (out.empty() ? "" : ",") + number(x);
    return out;
  };
  if (const auto* s = findSetting(sceneSettings(), key)) {
    const json d = s->get(Scene());
    return d.is_boolean() ? (d.get<bool>() ? "true" : "false") : text(d);
  }
  if (const auto* s = findSetting(frameSettings(), key)) return text(s->get(Frame()));
  fail("no scene setting \"", key, "\"");
}

void checkSceneVector(const std::string& key, const vec3f& value) {
  const Setting<Scene>* s = findSetting(sceneSettings(), key);
  if (!s || s->type != SettingType::Vector) fail("no vector scene setting \"", key, "\"");
  checkVectorValue(key, s->vector, json::array({value.x, value.y, value.z}));
}

std::string sceneVocabularyJson() {
  json out = json::array();
  describe(frameSettings(), out);
  describe(sceneSettings(), out);
  removeFloatNoise(out);
  return out.dump();
}

} // namespace exa
