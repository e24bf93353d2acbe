// The scene vocabulary: every described setting survives the scene file, and names and ranges
// are refused with one message.
#include "exabricks/core/error.h"
#include "exabricks/render/renderer.h"
#include "exabricks/render/scene.h"
#include "exabricks/render/scene_vocabulary.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <map>

namespace exa {
namespace {

using json = nlohmann::json;

/// A value of a described setting in its range and different from its default (the rule the
/// Python test follows too).
json otherValue(const json& setting) {
  const std::string type = setting["type"];
  const json& d = setting["default"];
  if (type == "boolean") return !d.get<bool>();
  if (type == "choice") {
    for (const json& c : setting["choices"])
      if (c != d) return c;
    ADD_FAILURE() << setting.dump() << " offers no other choice";
    return d;
  }
  if (type == "vector") {
    // Within every kind (finite, non-zero, >= 0 where the default is) and exact in float.
    if (d.is_null()) return json::array({0.25, 0.5, 0.75});
    return json::array({d[1].get<double>() + 0.5, d[2].get<double>() + 0.25, d[0].get<double>() + 0.125});
  }
  const double def = d.get<double>(), low = setting["min"].get<double>();
  if (type == "integer") {
    const double v = std::floor((low + def) / 2);
    return int64_t(v == def ? def + 1 : v);
  }
  const double v = (low + def) / 2;
  if (v != def) return v;
  return setting.contains("max") ? (def + setting["max"].get<double>()) / 2 : def + 1;
}

json atKey(const json& doc, const std::string& key) {
  const json* j = &doc;
  for (size_t start = 0;;) {
    const size_t dot = key.find('.', start);
    j = &j->at(key.substr(start, dot - start));
    if (dot == std::string::npos) return *j;
    start = dot + 1;
  }
}

void putKey(json& doc, const std::string& key, const json& value) {
  json* j = &doc;
  size_t start = 0;
  for (size_t dot; (dot = key.find('.', start)) != std::string::npos; start = dot + 1)
    j = &(*j)[key.substr(start, dot - start)];
  (*j)[key.substr(start)] = value;
}

TEST(SceneVocabulary, EveryDescribedSettingRoundTrips) {
  const json vocabulary = json::parse(sceneVocabularyJson());
  ASSERT_GE(vocabulary.size(), 26u);
  const json defaults = json::parse(writeSceneJson(SceneDocument()));
  json doc = json::object();
  for (const json& s : vocabulary) {
    const std::string key = s["key"];
    if (s["default"].is_null())
      EXPECT_THROW(atKey(defaults, key), json::exception) << key << ": unset, so not written";
    else
      EXPECT_EQ(atKey(defaults, key), s["default"]) << key;
    EXPECT_FALSE(s["help"].get<std::string>().empty()) << key;
    putKey(doc, key, otherValue(s));
  }
  doc["iso"] = {{"values", {0.5}}}; // with the volume off, something to draw
  const std::string text = writeSceneJson(readSceneJson(doc.dump(), "every.json"));
  const json written = json::parse(text);
  for (const json& s : vocabulary) {
    const std::string key = s["key"];
    const json want = otherValue(s), got = atKey(written, key);
    EXPECT_NE(got, s["default"]) << key;
    if (s["type"] == "number")
      EXPECT_FLOAT_EQ(float(got.get<double>()), float(want.get<double>())) << key;
    else
      EXPECT_EQ(got, want) << key;
  }
  EXPECT_EQ(writeSceneJson(readSceneJson(text, "again.json")), text);
}

TEST(SceneVocabulary, NamesAndRangesAreRefusedWithOneMessage) {
  EXPECT_EQ(parseName<Shading>("clamped", "shading"), Shading::Smooth);
  EXPECT_STREQ(nameOf(Shading::Smooth), "smooth");
  EXPECT_EQ(choicesOf<DebugView>(), "none, level, brick, region, steps");
  auto message = [](auto&& f) {
    try {
      f();
    } catch (const Error& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_EQ(message([] { parseName<TraversalSetting>("bvh", "--traversal"); }),
            "--traversal is 'bvh' (choose from: auto, kd, embree)");
  EXPECT_EQ(message([] { readSceneJson(R"({"integration": {"traversal": "bvh"}})", "s.json"); }),
            "s.json: \"integration.traversal\" is 'bvh' (choose from: auto, kd, embree)");
  EXPECT_EQ(message([] { readSceneJson(R"({"ambient_occlusion": {"rays": 2000}})", "s.json"); }),
            "s.json: \"ambient_occlusion.rays\" must be an integer in 0..1024, not 2000");
  EXPECT_EQ(message([] { readSceneJson(R"({"pathtrace": {"sky": [1, -1, 0]}})", "s.json"); }),
            "s.json: \"pathtrace.sky\" must be a finite radiance r,g,b >= 0, not [1, -1, 0]");
  EXPECT_EQ(message([] { readSceneJson(R"({"light": {"direction": [0, 0]}})", "s.json"); }),
            "s.json: \"light.direction\" must be a finite, non-zero direction x,y,z, not [0, 0]");
  Scene s;
  s.integration.terminationOpacity = 0.f;
  EXPECT_EQ(message([&] { s.validate(); }), "\"integration.termination_opacity\" must be in (0, 1], not 0");
  Frame f;
  f.rate = -1.f;
  EXPECT_EQ(message([&] { f.validate(); }), "\"frame.rate\" must be in (0, 1024], not -1");
  EXPECT_EQ(message([] { checkSceneSetting("light.ambient", -0.5); }),
            "\"light.ambient\" must be a finite number >= 0, not -0.5");
}

TEST(SceneVocabulary, UnknownKeysNameEveryKnownOne) {
  try {
    readSceneJson(R"({"integration": {"bogus": 1}})", "s.json");
    FAIL() << "an unknown key must be refused";
  } catch (const Error& e) {
    const std::string m = e.what();
    EXPECT_EQ(m.rfind("s.json: unknown key \"integration.bogus\" (known: ", 0), 0u) << m;
    for (const char* k : {"sampling", "traversal", "termination_opacity", "vectorized"})
      EXPECT_NE(m.find(k), std::string::npos) << m;
  }
}

/// Whether every key of `want` is in `got` with an equal value (numbers equal in single precision,
/// up to the sRGB round trip of colours); `where` names the first difference.
bool holds(const json& got, const json& want, const std::string& path, std::string& where) {
  if (want.is_object()) {
    if (!got.is_object()) return where = path, false;
    for (auto it = want.begin(); it != want.end(); ++it)
      if (!got.contains(it.key()) || !holds(got[it.key()], it.value(), path + "." + it.key(), where)) {
        if (where.empty()) where = path + "." + it.key();
        return false;
      }
    return true;
  }
  if (want.is_array()) {
    if (!got.is_array() || got.size() != want.size()) return where = path, false;
    for (size_t i = 0; i < want.size(); ++i)
      if (!holds(got[i], want[i], path + "[" + std::to_string(i) + "]", where)) return false;
    return true;
  }
  if (want.is_number() && got.is_number()) {
    const double a = got.get<double>(), b = want.get<double>();
    if (std::abs(a - b) <= 1e-6 * std::max(1.0, std::abs(b))) return true;
    return where = path + " (" + got.dump() + ")", false;
  }
  if (got == want) return true;
  return where = path + " (" + got.dump() + ")", false;
}

/// The objects a described key stands for in a document: "layers[].field" in every layer.
void collect(const json& doc, const std::string& key, std::vector<json>& out) {
  const size_t dot = key.find('.');
  std::string head = key.substr(0, dot);
  const bool items = head.size() > 2 && head.compare(head.size() - 2, 2, "[]") == 0;
  if (items) head.resize(head.size() - 2);
  if (!doc.is_object() || !doc.contains(head)) return;
  std::vector<json> here;
  if (items)
    for (const json& item : doc[head])
      here.push_back(item);
  else
    here.push_back(doc[head]);
  for (const json& h : here)
    if (dot == std::string::npos)
      out.push_back(h);
    else
      collect(h, key.substr(dot + 1), out);
}

TEST(SceneVocabulary, EveryStructuredKeyIsDescribedAndRoundTrips) {
  const json structure = json::parse(sceneStructureJson());
  const json example = json::parse(sceneExampleJson());
  std::map<std::string, std::vector<json>> objects; // values of the object types, by type
  for (const json& e : structure) {
    const std::string key = e["key"], type = e["type"];
    EXPECT_FALSE(e["help"].get<std::string>().empty()) << key;
    if (e.contains("object") || !e.value("document", true) || !e.value("written", true)) continue;
    if (!e.value("in_example", true)) { // (a file the example cannot name: it renders as written)
      EXPECT_EQ(key, "meshes[].file");
      continue;
    }
    // Every key is used by the example document, at a value other than its default.
    std::vector<json> values;
    collect(example, key, values);
    EXPECT_FALSE(values.empty()) << key << " is not in the example document";
    for (const json& v : values) {
      if (type != "object") {
        EXPECT_NE(v, e["default"]) << key;
      }
      if (type == "camera" || type == "transfer_function") objects[type].push_back(v);
    }
  }
  // The keys of the object types, within the objects the example holds.
  for (const json& e : structure)
    if (e.contains("object")) {
      const std::string type = e["object"], key = e["key"];
      const auto& values = objects[type];
      EXPECT_TRUE(std::any_of(values.begin(), values.end(), [&](const json& o) { return o.contains(key); }))
          << type << "." << key << " is not in the example document";
    }
  // Read and written, the document keeps every key.
  const std::string text = writeSceneJson(readSceneJson(example.dump(), "example.json"));
  std::string where;
  EXPECT_TRUE(holds(json::parse(text), example, "", where)) << where << "\n" << text;
  EXPECT_EQ(writeSceneJson(readSceneJson(text, "again.json")), text);
}

TEST(SceneVocabulary, StructuredKeysAreRefusedWithOneMessage) {
  auto message = [](const char* text) {
    try {
      readSceneJson(text, "s.json");
    } catch (const Error& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  const json example = json::parse(sceneExampleJson());
  json doc = {{"camera", example["camera"]}};
  doc["camera"]["orthographic"] = false;
  doc["camera"]["fov"] = 200;
  EXPECT_EQ(message(doc.dump().c_str()), "s.json: \"camera.fov\" must be in (0, 180), not 200");
  doc["camera"]["fov"] = 30;
  doc["camera"]["zoom"] = 2;
  EXPECT_EQ(message(doc.dump().c_str()),
            "s.json: unknown key \"camera.zoom\" (known: position, look_at, up, fov, orthographic, ortho_height)");
  EXPECT_EQ(message(R"({"layers": [{"field": "a", "colour": 1}]})"),
            "s.json: unknown key \"layers[0].colour\" (known: field, transfer_function)");
  EXPECT_EQ(message(R"({"layers": [{"transfer_function": {"colour": 1}}]})"),
            "s.json: \"layers[0].transfer_function\": unknown key \"colour\" (known: colormap, opacity, albedo, range, "
            "log, opacity_scale)");
  EXPECT_EQ(message(R"({"frame": {"frame_index": -1}})"),
            "s.json: \"frame.frame_index\" must be an integer >= 0, not -1");
  const std::string top = message(R"({"cameras": 1})");
  for (const char* k : {"camera", "camera_path", "layers", "iso", "meshes", "clip", "background", "light", "legends",
                        "frame", "integration", "pathtrace", "ambient_occlusion", "volume", "shading"})
    EXPECT_TRUE(top.find(std::string(" ") + k + ",") != std::string::npos ||
                top.find(std::string(" ") + k + ")") != std::string::npos)
        << k << ": " << top;
  // The device choice: one list for every front end.
  const json structure = json::parse(sceneStructureJson());
  const auto device =
      std::find_if(structure.begin(), structure.end(), [](const json& e) { return e["key"] == "device"; });
  ASSERT_NE(device, structure.end());
  EXPECT_EQ((*device)["choices"].get<std::vector<std::string>>(), deviceChoices());
  try {
    resolveDevice("gpu");
    ADD_FAILURE() << "an unknown device must be refused";
  } catch (const Error& e) {
    EXPECT_STREQ(e.what(), "device is 'gpu' (choose from: auto, cpu, cuda, portable)");
  }
}

} // namespace
} // namespace exa
