// The scene vocabulary: every described setting survives the scene file, and names and ranges
// are refused with one message.
#include "exabricks/core/error.h"
#include "exabricks/render/scene.h"
#include "exabricks/render/scene_vocabulary.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <cmath>

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

} // namespace
} // namespace exa
