// The structured keys of scene files (camera, camera path, layers and transfer functions, iso,
// meshes, clipping, background) and the device choice: each once, with its type, range, default,
// an example and help. The scene reader takes its known keys and number ranges from here.
#include "exabricks/amr/scenes.h"
#include "exabricks/render/scene_vocabulary.h"
#include "exabricks/render/transfer_function.h"

#include "scene_settings.h"
#include "tf_json.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string_view>
#include <utility>

namespace exa {

namespace {

using json = nlohmann::json;
constexpr double kInf = std::numeric_limits<double>::infinity();

json entry(const char* key, const char* type, json def, json example, const char* help) {
  return {{"key", key}, {"type", type}, {"default", std::move(def)}, {"example", std::move(example)}, {"help", help}};
}

json ranged(json e, double low, double high, bool lowOpen, bool highOpen) {
  e["min"] = low;
  if (lowOpen) e["min_exclusive"] = true;
  if (std::isfinite(high)) e["max"] = high;
  if (highOpen) e["max_exclusive"] = true;
  return e;
}

json vector(const char* key, const char* kind, json def, json example, const char* help) {
  json e = entry(key, "vector", std::move(def), std::move(example), help);
  e["kind"] = kind;
  return e;
}

json required(json e) {
  e["required"] = true;
  return e;
}

/// The keys of an object type used at several places ("camera", "transfer_function").
json member(const char* object, json e) {
  e["object"] = object;
  return e;
}

json cameraExample(double x) {
  return {{"position", {x, 130.5, 120.25}}, {"look_at", {48.0, 43.75, 43.5}},
          {"up", {0.0, 1.0, 0.0}},          {"fov", 35.0},
          {"orthographic", true},           {"ortho_height", 90.5}};
}

std::vector<json> cameraKeys() {
  const char* c = "camera";
  return {
      member(c, required(vector("position", "point", nullptr, {205.5, 130.5, 120.25}, "Where the eye is (world)"))),
      member(c, vector("look_at", "point", {0.0, 0.0, 0.0}, {48.0, 43.75, 43.5},
                       "The point the view is centred on (world)")),
      member(c, vector("up", "direction", {0.0, 0.0, 1.0}, {0.0, 1.0, 0.0}, "The image's up direction (world)")),
      member(c, ranged(entry("fov", "number", 40.0, 35.0, "Vertical field of view in degrees (perspective)"), 0.0,
                       180.0, true, true)),
      member(c, entry("orthographic", "boolean", false, true, "An orthographic (parallel) projection")),
      member(c, ranged(entry("ortho_height", "number", 1.0, 90.5, "World height of an orthographic view"), 0.0, kInf,
                       true, false)),
  };
}

std::vector<json> transferFunctionKeys() {
  const char* t = "transfer_function";
  json colormap = entry("colormap", "colormap", "viridis", "inferno",
                        "A built-in colour map by name, or {\"points\": [[x, r, g, b], ...]} from x = 0 to 1 (sRGB)");
  colormap["choices"] = builtinColorMapNames();
  return {
      member(t, colormap),
      member(t, entry("opacity", "points", nullptr, {{0.0, 0.0}, {0.5, 0.125}, {1.0, 0.75}},
                      "Opacity points [[x, opacity], ...] over the normalised value x in [0, 1] (default: a ramp)")),
      member(t, entry("albedo", "points", nullptr, {{0.0, 0.25}, {1.0, 0.875}},
                      "Path tracing: albedo points [[x, albedo], ...] over the normalised value (default: the scene's "
                      "pathtrace.albedo)")),
      member(t, entry("range", "numbers", nullptr, {0.125, 1.25},
                      "The value range [low, high] the map spans (default: the field's range)")),
      member(t, entry("log", "boolean", false, true, "Map the logarithm of the value (the range must be positive)")),
      member(t, ranged(entry("opacity_scale", "number", "auto", 0.0625,
                             "Opacity per world unit at opacity 1, or \"auto\" (the dataset's default)"),
                       0.0, kInf, true, false)),
  };
}

json meshesExample() {
  return {{{"vertices", {{0.0, 0.0, 0.0}, {1.0, 0.0, 0.0}, {0.0, 1.0, 0.5}}},
           {"triangles", {{0, 1, 2}}},
           {"color", {0.5, 0.25, 0.125}}}};
}

json keyframesExample() {
  return {{{"time", 0.0},
           {"camera", cameraExample(205.5)},
           {"range", {0.25, 1.25}},
           {"opacity_scale", 0.5},
           {"iso_values", {0.5, 0.75}}},
          {{"time", 2.5},
           {"camera", cameraExample(180.5)},
           {"range", {0.125, 1.5}},
           {"opacity_scale", 0.25},
           {"iso_values", {0.25, 0.5}}}};
}

/// A mesh file: left out of the example document, which renders as it is written.
json meshFileKey() {
  json e = entry("meshes[].file", "string", nullptr, "triangle.ply", "A mesh file (OBJ, PLY or .tris)");
  e["in_example"] = false;
  return e;
}

std::vector<json> documentKeys() {
  const json tfExample = {{"colormap", "inferno"},
                          {"opacity", {{0.0, 0.0}, {0.5, 0.125}, {1.0, 0.75}}},
                          {"albedo", {{0.0, 0.25}, {1.0, 0.875}}},
                          {"range", {0.125, 1.25}},
                          {"log", true},
                          {"opacity_scale", 0.0625}};
  json frameIndex = ranged(
      entry("frame.frame_index", "integer", 0, 3, "The pass a frame renders (its random sequence); read, not written"),
      0.0, kInf, false, false);
  frameIndex["written"] = false;
  return {
      entry("input", "string", "", kEmbeddedInput,
            "The dataset the scene was made for (its path; \"<embedded>\": the embedded default dataset)"),
      entry("camera", "camera", nullptr, cameraExample(205.5),
            "The view; without it, the data is framed from the default direction"),
      vector("background", "color", {0.0, 0.0, 0.0}, {0.125, 0.25, 0.5}, "Background colour (sRGB, each in [0, 1])"),
      frameIndex,
      entry("layers", "list", nullptr, {{{"field", "scalar"}, {"transfer_function", tfExample}}, {{"field", "scalar"}}},
            "Volume layers, drawn together (extinction adds up); default: the first field with its default map"),
      entry("layers[].field", "string", "", "scalar", "The layer's field (\"\": the dataset's first)"),
      entry("layers[].transfer_function", "transfer_function", nullptr, tfExample,
            "The layer's transfer function (or a ParaView colour-map preset)"),
      entry("iso", "object", nullptr, nullptr, "Iso-surfaces"),
      entry("iso.field", "string", "", "scalar", "The field of the iso-surfaces (\"\": the first layer's)"),
      entry("iso.values", "numbers", json::array(), {0.5, 0.75}, "Iso-values (finite numbers)"),
      entry("iso.colors", "list", json::array(), {{1.0, 0.5, 0.25}, {0.25, 0.5, 1.0}},
            "A colour per iso-value (sRGB); none: coloured by color_field, else by the layer's map"),
      vector("iso.colors[]", "color", nullptr, {1.0, 0.5, 0.25}, "An iso-surface's colour (sRGB, each in [0, 1])"),
      entry("iso.color_field", "string", "", "scalar", "Colour the iso-surfaces by this field through color_map"),
      entry("iso.color_map", "transfer_function", transferFunctionToJson(IsoSurfaces().colorTf),
            {{"colormap", {{"points", {{0.0, 0.0, 0.0, 1.0}, {1.0, 1.0, 0.0, 0.0}}}}}, {"log", false}},
            "The map that colours iso-surfaces by color_field"),
      entry("meshes", "list", json::array(), meshesExample(), "Triangle meshes drawn with the volume"),
      meshFileKey(),
      vector("meshes[].color", "color", {0.8, 0.8, 0.8}, {0.25, 0.5, 0.75}, "The mesh's colour (sRGB)"),
      entry("meshes[].vertices", "list", nullptr, {{0.0, 0.0, 0.0}, {1.0, 0.0, 0.0}, {0.0, 1.0, 0.5}},
            "Vertices in place of a file"),
      vector("meshes[].vertices[]", "point", nullptr, {0.0, 1.0, 0.5}, "A vertex (world)"),
      entry("meshes[].triangles", "list", nullptr, {{0, 1, 2}}, "Triangles in place of a file"),
      vector("meshes[].triangles[]", "index", nullptr, {0, 1, 2}, "A triangle's three vertex indices"),
      entry("particles", "object", nullptr, nullptr, "The dataset's particles, drawn as spheres"),
      entry("particles.species", "string", "", "dark_matter", "Draw this species only (\"\": every species)"),
      entry("particles.radius_by", "string", "", "mass",
            "Scale each radius by the cube root of this attribute over its largest value (\"\": one radius)"),
      vector("particles.color", "color", {1.0, 0.7, 0.35}, {0.25, 0.5, 0.75},
             "The spheres' colour (sRGB), where not coloured by an attribute"),
      entry("particles.color_by", "string", "", "mass", "Colour the spheres by this attribute through color_map"),
      entry("particles.color_map", "transfer_function", transferFunctionToJson(ParticleStyle().colorTf),
            {{"colormap", "viridis"}, {"range", {0.5, 2.0}}, {"log", true}},
            "The map, range (none: the attribute's) and scale that colour particles by color_by"),
      entry("clip", "object", nullptr, nullptr, "Clipping"),
      entry("clip.planes", "list", json::array(), {{{"point", {48.0, 40.5, 40.0}}, {"normal", {1.0, 0.0, 0.0}}}},
            "Clip planes; each removes the half-space its normal points into"),
      required(vector("clip.planes[].point", "point", nullptr, {48.0, 40.5, 40.0}, "A point on the plane (world)")),
      required(vector("clip.planes[].normal", "direction", nullptr, {1.0, 0.0, 0.0}, "The plane's normal")),
      entry("clip.box", "numbers", nullptr, {8.0, 4.5, 0.0, 60.0, 70.25, 80.5},
            "Keep only this box: lower x, y, z, then upper x, y, z (world)"),
      entry("camera_path", "object", nullptr, nullptr, "A camera path for movies"),
      required(entry("camera_path.keyframes", "list", nullptr, keyframesExample(),
                     "Keyframes at strictly increasing times")),
      entry("camera_path.constant_speed", "boolean", false, true,
            "Frames spaced evenly along the camera's path instead of evenly in time"),
      required(entry("camera_path.keyframes[].time", "number", nullptr, 2.5, "The keyframe's time (seconds)")),
      required(entry("camera_path.keyframes[].camera", "camera", nullptr, cameraExample(180.5),
                     "The camera at the keyframe")),
      entry("camera_path.keyframes[].range", "numbers", nullptr, {0.25, 1.25},
            "The first layer's value range at the keyframe (given by every keyframe or none)"),
      ranged(entry("camera_path.keyframes[].opacity_scale", "number", nullptr, 0.5,
                   "The first layer's opacity scale at the keyframe"),
             0.0, kInf, true, false),
      entry("camera_path.keyframes[].iso_values", "numbers", nullptr, {0.5, 0.75}, "Iso-values at the keyframe"),
  };
}

json deviceKey() {
  json e = entry("device", "choice", "auto", "cpu",
                 "Where passes run: auto (the GPU where one can be used and the scene has nothing it lacks, else the "
                 "CPU), cpu, cuda (an NVIDIA GPU) or portable (the GPU's code on CPU threads, for comparisons)");
  e["choices"] = deviceChoices();
  e["document"] = false;
  return e;
}

const json& structure() {
  static const json table = [] {
    json all = json::array();
    for (const json& e : documentKeys())
      all.push_back(e);
    for (const json& e : cameraKeys())
      all.push_back(e);
    for (const json& e : transferFunctionKeys())
      all.push_back(e);
    all.push_back(deviceKey());
    return all;
  }();
  return table;
}

/// The parent of a key path ("" at the top): the part before its last '.'.
std::string parentOf(const std::string& key) {
  const size_t dot = key.rfind('.');
  return dot == std::string::npos ? std::string() : key.substr(0, dot);
}

std::string leafOf(const std::string& key) { return key.substr(key.rfind('.') + 1); }

/// The structured keys by their paths ("camera.fov" is the camera object's fov), built once so
/// that checks allocate nothing.
const std::vector<std::pair<std::string, const json*>>& structuredPaths() {
  static const std::vector<std::pair<std::string, const json*>> paths = [] {
    std::vector<std::pair<std::string, const json*>> out;
    for (const json& e : structure()) {
      const std::string k = e["key"];
      out.emplace_back(e.contains("object") ? e["object"].get<std::string>() + "." + k : k, &e);
    }
    return out;
  }();
  return paths;
}

const json* findStructured(std::string_view key) {
  for (const auto& [path, e] : structuredPaths())
    if (path == key) return e;
  return nullptr;
}

} // namespace

const std::vector<std::string>& deviceChoices() {
  static const std::vector<std::string> names = {"auto", "cpu", "cuda", "portable"};
  return names;
}

std::string sceneStructureJson() {
  json j = structure();
  removeFloatNoise(j);
  return j.dump();
}

std::string sceneExampleJson() {
  json doc = json::object();
  for (const json& e : structure()) {
    const std::string key = e["key"];
    if (e.contains("object") || !e.value("document", true) || !e.value("written", true) || e["type"] == "object" ||
        key.find("[]") != std::string::npos)
      continue;
    json* at = &doc;
    size_t start = 0;
    for (size_t dot; (dot = key.find('.', start)) != std::string::npos; start = dot + 1)
      at = &(*at)[key.substr(start, dot - start)];
    (*at)[key.substr(start)] = e["example"];
  }
  removeFloatNoise(doc);
  return doc.dump(2) + "\n";
}

std::vector<std::string> knownSceneKeys(const std::string& path) {
  std::vector<std::string> keys;
  for (const json& e : structure()) {
    if (e.value("document", true) == false) continue;
    const std::string k = e["key"];
    const bool item = k.size() >= 2 && k.compare(k.size() - 2, 2, "[]") == 0; // the items of a list
    if (e.contains("object") ? e["object"] == path : parentOf(k) == path && !item)
      keys.push_back(e.contains("object") ? k : leafOf(k));
  }
  auto add = [&](const std::string& section, const std::string& leaf) {
    if (section == path) keys.push_back(leaf);
    // A section of settings is a key of its parent.
    if (!section.empty() && parentOf(section) == path &&
        std::find(keys.begin(), keys.end(), leafOf(section)) == keys.end())
      keys.push_back(leafOf(section));
  };
  for (const Setting<Scene>& s : sceneSettings())
    add(s.section(), s.leaf());
  for (const Setting<Frame>& s : frameSettings())
    add(s.section(), s.leaf());
  return keys;
}

const json& structuredDefault(std::string_view key) {
  const json* e = findStructured(key);
  if (!e) fail("no scene key \"", key, "\"");
  return (*e)["default"];
}

std::string structuredKeyHelp(const std::string& key) {
  const json* e = findStructured(key);
  if (!e) fail("no scene key \"", key, "\"");
  return (*e)["help"];
}

bool checkStructuredNumber(std::string_view key, double value) {
  const json* e = findStructured(key);
  if (!e) return false;
  const auto low = e->find("min");
  if (low == e->end()) return false;
  const auto high = e->find("max"), lowOpen = e->find("min_exclusive"), highOpen = e->find("max_exclusive");
  const double lo = low->get<double>(), hi = high == e->end() ? kInf : high->get<double>();
  const bool openLow = lowOpen != e->end(), openHigh = highOpen != e->end();
  const bool integer = e->find("type")->get_ref<const std::string&>() == "integer";
  checkSettingValue(key, integer ? SettingType::Integer : SettingType::Number, lo, hi, openLow, openHigh, value);
  return true;
}

} // namespace exa
