// Scene files on disk: the JSON of render/scene.h with the meshes it names read from their files.
#pragma once

#include "exabricks/render/scene.h"

#include <string>

namespace exa {

/// Reads a scene file and every mesh it names (relative to the working directory); errors name
/// the file, the key or mesh, and the problem.
SceneDocument readSceneFile(const std::string& path);

/// Reads the meshes of a scene that name a file but hold no data.
void loadSceneMeshes(Scene& scene, const std::string& source);

/// Writes a scene document atomically.
void writeSceneFile(const std::string& path, const SceneDocument& doc);

} // namespace exa
