#include "exabricks/documents/scene_file.h"

#include "exabricks/core/error.h"
#include "exabricks/core/files.h"
#include "exabricks/documents/mesh.h"

#include <cerrno>
#include <cstring>
#include <fstream>
#include <sstream>

namespace exa {

void loadSceneMeshes(Scene& scene, const std::string& source) {
  for (size_t i = 0; i < scene.meshes.size(); ++i) {
    SceneMesh& m = scene.meshes[i];
    if (m.mesh) continue;
    if (m.source.empty()) fail(source, ": mesh ", i, " names no file");
    m.mesh = std::make_shared<TriangleMesh>(readMesh(m.source));
  }
  try {
    scene.validate();
  } catch (const Error& e) {
    fail(source, ": ", e.what());
  }
}

SceneDocument readSceneFile(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) fail(path, ": cannot open: ", std::strerror(errno));
  std::ostringstream text;
  text << in.rdbuf();
  SceneDocument doc = readSceneJson(text.str(), path);
  loadSceneMeshes(doc.scene, path);
  return doc;
}

void writeSceneFile(const std::string& path, const SceneDocument& doc) {
  const std::string text = writeSceneJson(doc);
  writeFileAtomic(path, text.data(), text.size());
}

} // namespace exa
