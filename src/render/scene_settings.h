// The table of scene and frame settings behind render/scene_vocabulary.h (private to the
// library): each scalar and three-component setting once, with its key, type, range, help and
// access to its member.
#pragma once

#include "exabricks/render/scene.h"

#include <nlohmann/json.hpp>

#include <functional>
#include <string>
#include <string_view>
#include <vector>

namespace exa {

enum class SettingType { Boolean, Integer, Number, Choice, Vector };
/// What a three-component setting holds: a direction (finite, non-zero) or a radiance (finite
/// linear r,g,b >= 0).
enum class VectorKind { Direction, Radiance };

template <typename Owner> struct Setting {
  std::string key;  ///< path in the scene file: "section.leaf", or "leaf" at the top level
  std::string name; ///< flat name (the Python Scene's attribute)
  SettingType type = SettingType::Boolean;
  double low = 0.0, high = 0.0; ///< integer and number: allowed range (may be infinite)
  bool lowOpen = false, highOpen = false;
  std::vector<std::string> choices;          ///< choice: the names offered
  VectorKind vector = VectorKind::Direction; ///< vector: what its components are
  bool optional = false;                     ///< vector: may be unset (null; then not written)
  std::string help;
  std::function<nlohmann::json(const Owner&)> get;
  /// Sets a value of the right JSON type; choices name `what` when the name is unknown.
  std::function<void(Owner&, const nlohmann::json&, const std::string& what)> set;

  std::string section() const {
    const size_t dot = key.rfind('.');
    return dot == std::string::npos ? std::string() : key.substr(0, dot);
  }
  std::string leaf() const { return key.substr(key.rfind('.') + 1); }
};

const std::vector<Setting<Scene>>& sceneSettings();
/// The default the description gives a structured key ("camera.up"); null where it has none.
const nlohmann::json& structuredDefault(std::string_view key);
const std::vector<Setting<Frame>>& frameSettings();

/// Throws exa::Error when a number is outside a setting's range (or not an integer where one is
/// needed): "KEY" must be in RANGE, not VALUE.
void checkSettingValue(std::string_view key, SettingType type, double low, double high, bool lowOpen, bool highOpen,
                       double value);
template <typename Owner> void checkSetting(const Setting<Owner>& s, double value) {
  checkSettingValue(s.key, s.type, s.low, s.high, s.lowOpen, s.highOpen, value);
}
/// Throws exa::Error unless `v` is a vector of its kind (a JSON array of three numbers):
/// "KEY" must be finite and non-zero / a finite radiance r,g,b >= 0.
void checkVectorValue(const std::string& key, VectorKind kind, const nlohmann::json& v);
/// Checks every numeric and vector setting of `owner` against its range or kind.
template <typename Owner> void checkSettings(const std::vector<Setting<Owner>>& table, const Owner& owner) {
  for (const Setting<Owner>& s : table)
    if (s.type == SettingType::Integer || s.type == SettingType::Number) {
      checkSetting(s, s.get(owner).template get<double>());
    } else if (s.type == SettingType::Vector) {
      const nlohmann::json v = s.get(owner);
      if (!v.is_null()) checkVectorValue(s.key, s.vector, v);
    }
}

} // namespace exa
