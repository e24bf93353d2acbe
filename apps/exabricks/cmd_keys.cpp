// exabricks keys: the scene file's keys as the library describes them (settings and structured
// keys, with type, range, default and help), as text, as JSON, or as an example scene file.
#include "commands.h"

#include "exabricks/render/scene_vocabulary.h"

#include <nlohmann/json.hpp>

#include <cmath>
#include <iostream>
#include <memory>
#include <string>

namespace exa::cli {

namespace {

using json = nlohmann::json;

struct KeysOptions {
  bool json = false;
  bool example = false;
};

/// A bound as people write it: 0, not 0.0.
std::string bound(const json& v) {
  if (v.is_number_integer()) return v.dump();
  const double d = v.get<double>();
  if (!(std::abs(d) < 0x1p62)) return v.dump();
  return d == double(int64_t(d)) ? std::to_string(int64_t(d)) : v.dump();
}

/// "[0, 1]", "(0, 180)", ">= 0", or "" where unbounded; choices as "a | b".
std::string rangeOf(const json& e) {
  if (e.contains("choices")) {
    std::string out;
    for (const json& c : e["choices"])
      out += (out.empty() ? "" : " | ") + c.get<std::string>();
    return out;
  }
  if (!e.contains("min")) return e.contains("kind") ? e["kind"].get<std::string>() : "";
  const bool lowOpen = e.value("min_exclusive", false), highOpen = e.value("max_exclusive", false);
  if (!e.contains("max")) return std::string(lowOpen ? "> " : ">= ") + bound(e["min"]);
  return std::string(lowOpen ? "(" : "[") + bound(e["min"]) + ", " + bound(e["max"]) + (highOpen ? ")" : "]");
}

void printText(const json& entries) {
  for (const json& e : entries) {
    std::string key = e["key"];
    if (e.contains("object")) key = "<" + e["object"].get<std::string>() + ">." + key;
    std::cout << key << "  (" << e["type"].get<std::string>();
    if (const std::string r = rangeOf(e); !r.empty()) std::cout << ": " << r;
    if (!e["default"].is_null()) std::cout << "; default " << e["default"].dump();
    if (e.value("required", false)) std::cout << "; required";
    std::cout << ")\n    " << e["help"].get<std::string>() << "\n";
  }
}

void run(const KeysOptions& o) {
  if (o.example) {
    std::cout << sceneExampleJson();
    return;
  }
  const json settings = json::parse(sceneVocabularyJson()), structure = json::parse(sceneStructureJson());
  if (o.json) {
    std::cout << json{{"settings", settings}, {"structure", structure}}.dump() << "\n";
    return;
  }
  printText(settings);
  printText(structure);
}

} // namespace

void addKeys(CLI::App& app) {
  auto o = std::make_shared<KeysOptions>();
  CLI::App* cmd = app.add_subcommand(
      "keys", "Print the keys of scene files (render --scene): type, range, default and help of each");
  cmd->add_flag("--json", o->json,
                "Print one JSON object: \"settings\" (the scalar and vector settings) and \"structure\" (camera, "
                "layers, transfer functions, iso, meshes, clipping, camera path, device)");
  cmd->add_flag("--example", o->example, "Print a scene file that uses every structured key (at an example value)");
  cmd->callback([o] { run(*o); });
}

} // namespace exa::cli
