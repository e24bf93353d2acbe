// The words of scene files: the names of every enumeration (as scene files, command-line flags,
// Python and the viewer spell them) and the description of every scalar setting (key, type,
// default, allowed range, choices and help), which the JSON reader and writer, validation and the
// front ends read.
#pragma once

#include "exabricks/core/error.h"
#include "exabricks/render/scene.h"

#include <span>
#include <string>
#include <string_view>
#include <vector>

namespace exa {

/// The traversal setting as scene files spell it: auto (Integration::autoTraversal) or one kind.
enum class TraversalSetting { Auto, KdTree, Embree };
TraversalSetting traversalSetting(const Integration& in);
/// Sets autoTraversal, and the traversal kind unless auto.
void setTraversal(Integration& in, TraversalSetting t);

/// One name of an enumeration value. A value's first name is the one written; aliases (earlier
/// names) are read as well but not offered.
template <typename E> struct EnumName {
  const char* name;
  E value;
  bool alias = false;
};

std::span<const EnumName<Shading>> enumNames(Shading);
std::span<const EnumName<DebugView>> enumNames(DebugView);
std::span<const EnumName<Sampling>> enumNames(Sampling);
std::span<const EnumName<Reconstruction>> enumNames(Reconstruction);
std::span<const EnumName<Integrator>> enumNames(Integrator);
std::span<const EnumName<TraversalSetting>> enumNames(TraversalSetting);
/// The traversal a renderer uses (statistics name it so): kd or embree.
std::span<const EnumName<TraversalKind>> enumNames(TraversalKind);

/// The name a value is written with.
template <typename E> const char* nameOf(E value) {
  for (const EnumName<E>& n : enumNames(E{}))
    if (n.value == value && !n.alias) return n.name;
  fail("no name for enumeration value ", int(value));
}

/// The names offered for a choice, separated by ", " (aliases left out).
template <typename E> std::string choicesOf() {
  std::string out;
  for (const EnumName<E>& n : enumNames(E{}))
    if (!n.alias) out += (out.empty() ? "" : ", ") + std::string(n.name);
  return out;
}

/// The value a name (or alias) stands for; an unknown name throws exa::Error
/// "WHAT is 'NAME' (choose from: ...)".
template <typename E> E parseName(const std::string& name, const std::string& what) {
  for (const EnumName<E>& n : enumNames(E{}))
    if (name == n.name) return n.value;
  fail(what, " is '", name, "' (choose from: ", choicesOf<E>(), ")");
}

/// The description of every scalar setting of a scene file, as a JSON array of objects: "key"
/// (the path in the file, such as "integration.termination_opacity"), "name" (its flat name, the
/// Python Scene's attribute), "type" (boolean, integer, number or choice), "default", "min" and
/// "max" where bounded (with "min_exclusive" / "max_exclusive" when open), "choices" and "help".
std::string sceneVocabularyJson();
/// The one-line help of a described setting or structured key (key as in sceneVocabularyJson,
/// or a structured key's path, "camera.fov" and "transfer_function.range" for the objects' keys).
std::string sceneSettingHelp(const std::string& key);
/// Throws exa::Error when `value` is outside the range of a described numeric setting or
/// structured number.
void checkSceneSetting(const std::string& key, double value);
/// Sets a described setting of `scene` or `frame` from text as a command line gives it ("true",
/// "0.5", "smooth", "1,0,0"), checked against its type and range; an unknown name names `what`.
/// Throws exa::Error naming the key.
void setSceneSettingText(Scene& scene, Frame& frame, const std::string& key, const std::string& text,
                         const std::string& what);
/// A described setting's default as setSceneSettingText reads it ("" where unset).
std::string sceneSettingDefaultText(const std::string& key);
/// Throws exa::Error when `value` is not of the kind of a described vector setting (a finite,
/// non-zero direction or a finite radiance >= 0).
void checkSceneVector(const std::string& key, const vec3f& value);

/// The description of the structured keys of a scene file and of the device choice, as a JSON
/// array of objects: "key" (a path, "[]" standing for every item of a list; the keys of an object
/// used at several places carry "object": "camera" or "transfer_function" and their own name),
/// "type" (string, boolean, number, integer, numbers, points, vector, list, object, camera,
/// transfer_function, colormap or choice), "kind" (vectors: point, direction, color or index),
/// "min" and "max" where bounded (with "min_exclusive" / "max_exclusive"), "choices", "default"
/// (null: none, or taken from the data), "example" (a valid value other than the default),
/// "required", "written": false (read, not written) and "document": false (not a scene-file
/// key: an option of the front ends), and "help".
std::string sceneStructureJson();
/// A scene file holding every written structured key at its example value (lists and objects
/// whole, their items' keys within them) but a mesh file, over the embedded dataset: it renders
/// as it is written.
std::string sceneExampleJson();
/// The keys known directly under `path` of a scene file ("" at the top, "layers[]" for a layer,
/// "camera" or "transfer_function" for those objects): the structured keys and the settings.
std::vector<std::string> knownSceneKeys(const std::string& path);
/// The help of a structured key ("camera.fov", "clip.box", "device", ...).
std::string structuredKeyHelp(const std::string& key);
/// Throws exa::Error when `value` is outside the range of a described structured number (such as
/// "camera.fov"); false when the key has no range.
bool checkStructuredNumber(std::string_view key, double value);
/// The devices a renderer can be asked for: auto, cpu, cuda, portable (see selectDevice).
const std::vector<std::string>& deviceChoices();

} // namespace exa
